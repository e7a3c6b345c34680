//! The `ringmesh` command line: parses arguments, calls [`ringmesh::run`], prints.
//! Exit codes: 0 success, 1 failure, 2 bad input (nothing is written then), 3
//! a `frame` run that ended before the full load (its results are written).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use ringmesh::algebra::norm3;
use ringmesh::design::RelaxationKind;
use ringmesh::mechanics::{ElementKind, StaticTermination};
use ringmesh::report::{json_name, readable};
use ringmesh::run::{CantileverTable, FrameOutput, Progress};
use ringmesh::scene::TrussModel;
use ringmesh::shard::Shard;
use ringmesh::study::Knob;
use ringmesh::uniformity::SolverKind;

/// Prints a line to stdout; a closed pipe (`ringmesh … | head`) is not an error.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// Pretension design of the cable mesh of ring-truss deployable reflectors.
#[derive(Parser)]
#[command(name = "ringmesh", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Most memory a run may take, e.g. `8G`, `512M` (default: the memory
    /// the machine has available). A run whose estimated need is larger is
    /// refused before it computes, naming the input that sets its size.
    #[arg(long, global = true, value_parser = parse_bytes)]
    max_memory: Option<u64>,
}

/// `8G`, `512M`, `64K` or a number of bytes.
fn parse_bytes(text: &str) -> Result<u64, String> {
    let text = text.trim();
    let (number, unit) = match text.char_indices().find(|(_, c)| c.is_ascii_alphabetic()) {
        Some((i, _)) => (&text[..i], text[i..].to_ascii_uppercase()),
        None => (text, String::new()),
    };
    let scale: u64 = match unit.trim_end_matches("IB").trim_end_matches('B') {
        "" => 1,
        "K" => 1 << 10,
        "M" => 1 << 20,
        "G" => 1 << 30,
        "T" => 1 << 40,
        _ => return Err(format!("unknown unit in {text:?}: use K, M, G or T")),
    };
    let value: f64 = number
        .trim()
        .parse()
        .map_err(|_| format!("{text:?} is not a size such as 8G or 512M"))?;
    if !(value.is_finite() && value > 0.0) {
        return Err(format!("{text:?} must be a positive size"));
    }
    Ok((value * scale as f64).min(u64::MAX as f64) as u64)
}

#[derive(Subcommand)]
enum Command {
    /// Build the front net, rear net and ties of a scene.
    ///
    /// Prints a summary (free/fixed nodes, cables per group, shortest and longest
    /// cable) and writes network.json (interchange format, design positions,
    /// uniform initial q per group) and mesh.vtu (for ParaView).
    ///
    /// Example: ringmesh mesh problems/paper-26m.toml -o results/paper-26m
    Mesh {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output folder [default: results/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Forward force density solve of an interchange-format network.
    ///
    /// Writes nodes (equilibrium xyz), lengths, forces, reactions (per fixed node,
    /// in the order of `fixed`) and max_residual.
    ///
    /// Example: ringmesh fdm results/paper-26m/network.json -o equilibrium.json
    Fdm {
        /// The network file (JSON: nodes, edges, fixed, q, loads?, groups?).
        network: PathBuf,
        /// Output JSON file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// The main job: design the net for the truss as it deforms, prove it by
    /// assembly, compare with the conventional (rigid-truss) design.
    ///
    /// The outer loop designs the net for a boundary, applies its pull to the
    /// truss and repeats until the boundary the net is designed for is the one
    /// the truss takes (‖G(C) − C‖∞ ≤ --tol). The design is then cut to length
    /// and assembled on the undeformed flexible truss. Writes design.json,
    /// cables.csv (with cut lengths), convergence.csv, convergence.png/.svg,
    /// surface-error.png and model.vtu; one line per outer iteration on stderr.
    ///
    /// Example: ringmesh design problems/realistic-26m.toml --relaxation anderson,paper
    Design {
        /// The scene file (TOML).
        scene: PathBuf,
        /// The uniformity solver [default: lp for one uniformity set without
        /// loads, bisection otherwise].
        #[arg(long, value_enum)]
        solver: Option<SolverKind>,
        /// The truss model [default: the scene's [effects] truss].
        #[arg(long, value_enum)]
        truss: Option<TrussModel>,
        /// Relaxation policies, comma-separated: the first makes the design, the
        /// others are run for the convergence comparison.
        #[arg(long, value_enum, value_delimiter = ',', default_value = "anderson")]
        relaxation: Vec<RelaxationKind>,
        /// Stop when the boundary moves by at most this, m.
        #[arg(long, default_value_t = 1e-6)]
        tol: f64,
        /// Most outer iterations.
        #[arg(long, default_value_t = 50)]
        max_iterations: usize,
        /// Output folder [default: results/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Size the ring truss: the lightest tube section whose design (the whole
    /// outer loop on the exact truss, as `design`) has a limit margin of at
    /// least --margin.
    ///
    /// With --sections, the catalogue's sections (CSV: outer_diameter_m,
    /// inner_diameter_m[,youngs_modulus_pa,density_kg_per_m3]; see
    /// problems/carbon-tubes.csv) are searched by bisection, lightest first;
    /// without, the outer diameter at the scene's d/D and material. Every rod
    /// gets the section. Writes sizing.csv (every section tried: mass, margin,
    /// outer iterations, RMS as built) and <scene>-sized.toml; one line per
    /// section on stderr.
    ///
    /// Example: ringmesh size problems/paper-26m.toml --margin 2 --sections problems/carbon-tubes.csv
    Size {
        /// The scene file (TOML).
        scene: PathBuf,
        /// The limit margin to reach: the multiple of the design's pull the
        /// truss must carry stably (1 … 4).
        #[arg(long, default_value_t = 2.0)]
        margin: f64,
        /// A catalogue of tube sections (CSV) [default: any outer diameter].
        #[arg(long)]
        sections: Option<PathBuf>,
        /// The uniformity solver [default: lp for one uniformity set without
        /// loads, bisection otherwise].
        #[arg(long, value_enum)]
        solver: Option<SolverKind>,
        /// Output folder [default: results/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// The aperture study: how much the flexible-truss design matters as the
    /// dish grows.
    ///
    /// For each aperture the scene is scaled (F/D, facet size and membrane
    /// stress kept, bays kept, every truss length grown with the aperture),
    /// its tube sized for --margin as `size` does (outer diameter at the
    /// scene's d/D), and the conventional (rigid-truss), linear-truss and
    /// exact-truss designs are each assembled on the exact truss. Writes
    /// apertures.csv/.json/.png/.svg and each aperture's sized scene
    /// (<scene>-at-<D>m.toml); one line per aperture on stderr.
    ///
    /// Example: ringmesh apertures problems/paper-26m.toml --apertures 26,40,60,80,100
    Apertures {
        /// The scene file (TOML).
        scene: PathBuf,
        /// The apertures, m, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "26,40,60,80,100")]
        apertures: Vec<f64>,
        /// The limit margin each truss is sized for (1 … 4).
        #[arg(long, default_value_t = 2.0)]
        margin: f64,
        /// Output folder [default: results/<scene name>/apertures].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// One tension-uniformity design for the scene's theoretical (rigid) boundary.
    ///
    /// Writes design.json (q, tensions, positions, ratio per set and group, surface
    /// RMS, termination, time) and cables.csv (id,group,i,j,q,tension_n,length_m,
    /// cut_length_m); prints ratio, RMS and time.
    ///
    /// Example: ringmesh optimize problems/small-hex.toml --solver bisection
    Optimize {
        /// The scene file (TOML).
        scene: PathBuf,
        /// The uniformity solver [default: lp for one uniformity set without
        /// loads, bisection otherwise].
        #[arg(long, value_enum)]
        solver: Option<SolverKind>,
        /// Output folder [default: results/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Tension uniformity on a network file whose node positions are the prescribed
    /// geometry (free = not fixed).
    ///
    /// The other cables only need 0 < q. Writes q, tensions, ratio, max_residual,
    /// solver, termination, iterations, time_s.
    ///
    /// Example: ringmesh uniformity net.json --solver lp --groups front,boundary -o out.json
    Uniformity {
        /// The network file (interchange JSON).
        network: PathBuf,
        /// The uniformity solver [default: lp for one uniformity set without
        /// loads, bisection otherwise].
        #[arg(long, value_enum)]
        solver: Option<SolverKind>,
        /// Groups whose union is made uniform [default: front, or all cables when
        /// the file has no groups].
        #[arg(long, value_delimiter = ',')]
        groups: Option<Vec<String>>,
        /// Target mean tension of those cables, N [default: that of the file's q].
        #[arg(long)]
        mean_tension: Option<f64>,
        /// Upper bound [q] on every force density, N/m [default: none].
        #[arg(long)]
        max_force_density: Option<f64>,
        /// Output JSON file.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// The design front: ratio against actual surface RMS, sweeping each solver's
    /// accuracy knob (ε for bisection, weight for gradient, λ for least squares).
    ///
    /// Writes front.csv (solver,knob,ratio,rms_mm,time_s), front.png and front.svg.
    ///
    /// Example: ringmesh front problems/small-hex.toml --solvers bisection,least-squares --points 8
    Front {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Solvers to sweep.
        #[arg(
            long,
            value_enum,
            value_delimiter = ',',
            default_value = "bisection,gradient,least-squares"
        )]
        solvers: Vec<SolverKind>,
        /// Knob values per solver.
        #[arg(long, default_value_t = 8)]
        points: usize,
        /// Run only shard I of N (from 0: point k runs when k mod N = I) and
        /// write front.shard-I-of-N.csv; join the shards with `ringmesh merge`.
        #[arg(long, value_name = "I/N")]
        shard: Option<Shard>,
        /// Output folder [default: results/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// What accuracy costs in time: the design's wall time against its accuracy
    /// as built, one knob at a time from the scene's settings.
    ///
    /// Knobs: outer-loop tolerance, elements per truss rod, front-net rings,
    /// truss model, uniformity solver. Every design is cut to length and
    /// assembled on the reference truss (exact, the most elements) and judged
    /// against the reference run (finest settings, the scene's net): surface
    /// RMS (mm), ratio error, tension change, cut-length error, facet RMS.
    /// Writes accuracy-vs-time.csv, .png and .svg (log-log, Pareto-optimal
    /// points ringed); a failed point is a row with its error.
    ///
    /// Example: ringmesh study problems/realistic-26m.toml
    Study {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Knobs to sweep, comma-separated.
        #[arg(
            long,
            value_enum,
            value_delimiter = ',',
            default_value = "tolerance,elements,rings,truss,solver"
        )]
        knobs: Vec<Knob>,
        /// Outer-loop tolerances, m [default: 1e-2,1e-3,1e-4,1e-5,1e-6,1e-7].
        #[arg(long, value_delimiter = ',')]
        tolerances: Option<Vec<f64>>,
        /// Elements per truss rod [default: 1,2,4,8,16].
        #[arg(long, value_delimiter = ',')]
        elements: Option<Vec<usize>>,
        /// Front-net rings [default: r/2, r, 3r/2, 2r about the scene's r].
        #[arg(long, value_delimiter = ',')]
        rings: Option<Vec<usize>>,
        /// Truss models [default: rigid,linear,exact].
        #[arg(long, value_enum, value_delimiter = ',')]
        trusses: Option<Vec<TrussModel>>,
        /// Uniformity solvers [default: lp,bisection,least-squares,gradient].
        #[arg(long, value_enum, value_delimiter = ',')]
        solvers: Option<Vec<SolverKind>>,
        /// Most outer iterations of a run [default: 50].
        #[arg(long)]
        max_iterations: Option<usize>,
        /// Points run at once (1: one after the other, so each is timed alone).
        #[arg(long, default_value_t = 1, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=1024))]
        jobs: usize,
        /// Run only shard I of N (from 0: point k runs when k mod N = I; every
        /// shard also runs the reference) and write
        /// accuracy-vs-time.shard-I-of-N.csv; join with `ringmesh merge`.
        #[arg(long, value_name = "I/N")]
        shard: Option<Shard>,
        /// Output folder [default: results/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Join the shards of `front` or `study` runs into one table and plot.
    ///
    /// Takes shard files or folders holding *.shard-I-of-N.csv; each command's
    /// shards must be all of 0..N of one sweep of one scene with the same
    /// settings, else nothing is written. Writes front.csv/.png/.svg or
    /// accuracy-vs-time.csv/.png/.svg.
    ///
    /// Example: ringmesh merge results/realistic-26m
    Merge {
        /// Shard files, or folders holding them.
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Output folder [default: results/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Large-deformation statics of any frame of rods, rigid bodies and joints.
    ///
    /// Writes every node's position, displacement and rotation vector, the
    /// support reactions and the solver's statistics (termination, load steps,
    /// Newton iterations, residual history, time) as JSON; prints a summary.
    /// The file format is documented in src/frame/mod.rs.
    ///
    /// Example: ringmesh frame problems/frames/cantilever-moment.toml
    Frame {
        /// The frame file (TOML).
        file: PathBuf,
        /// Output JSON file [default: results/<file stem>/frame.json]; the
        /// path's frame-path.csv/.png/.svg are written beside it.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// The ring truss's response to the pull of the scene's net (forward FDM
    /// with its initial q) or to loads from a file: attachment displacements.
    ///
    /// Loads file: {"loads_n": [[fx, fy, fz], ...]}, top hinges then bottom
    /// hinges, N. Writes truss-<model>.json to results/<scene>/.
    ///
    /// Example: ringmesh truss problems/paper-26m.toml --model linear
    Truss {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Truss model [default: the scene's effects.truss].
        #[arg(long, value_enum)]
        model: Option<TrussModel>,
        /// Attachment loads (JSON) instead of the net's pull.
        #[arg(long)]
        loads: Option<PathBuf>,
        /// Output JSON file [default: results/<scene name>/truss-<model>.json].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// The paper's cantilever rolled up by a tip moment (Tables 1–2): analytic,
    /// paper and ours side by side, ML/(πEI) = 0.2 … 2.0 (the full circle).
    ///
    /// Example: ringmesh cantilever --elements 10 --element crisfield-jelenic
    Cantilever {
        /// Elements along the cantilever.
        #[arg(long, default_value_t = 10, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=100_000))]
        elements: usize,
        /// The beam element.
        #[arg(long, value_enum, default_value = "se3")]
        element: ElementKind,
        /// Print the table as JSON instead.
        #[arg(long)]
        json: bool,
        /// Also write the table to this folder, as cantilever.json.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
struct Bar(ProgressBar);

impl Progress for Bar {
    fn start(&self, total: usize) {
        self.0.set_length(total as u64);
    }
    fn step(&self, message: &str) {
        self.0.set_message(message.to_string());
        self.0.inc(1);
        // Not on a terminal (a batch job's log): one line per step instead.
        if self.0.is_hidden() {
            eprintln!(
                "{}/{} {:.1} s {message}",
                self.0.position(),
                self.0.length().unwrap_or(0),
                self.0.elapsed().as_secs_f64()
            );
        }
    }
}

/// A progress bar on stderr; when stderr is not a terminal, one line per
/// finished step instead.
fn bar() -> Bar {
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} {elapsed} {msg}")
            .expect("valid template"),
    );
    Bar(bar)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    ringmesh::resources::set_memory_limit(cli.max_memory);
    // SIGINT, SIGTERM, SIGHUP: no staging folder or temporary file is left.
    let _ = ctrlc::set_handler(|| ringmesh::report::abandon_all_and_exit(130));
    // A run that wrote its results but ended before its target (exit 3).
    let mut ended_early: Option<String> = None;
    let result = match &cli.command {
        Command::Mesh { scene, output } => ringmesh::run::mesh(scene, output.as_deref()).map(|m| {
            say!("scene: {}", m.scene);
            say!("{}", m.summary.to_string().trim_end());
            say_written(&m.written);
        }),
        Command::Fdm { network, output } => ringmesh::run::fdm(network, output).map(|o| {
            say!("max residual: {:.3e} N", o.max_residual);
            say!("wrote {}", output.display());
        }),
        Command::Design {
            scene,
            solver,
            truss,
            relaxation,
            tol,
            max_iterations,
            output,
        } => {
            let options = ringmesh::design::DesignSettings {
                solver: *solver,
                truss: *truss,
                relaxations: relaxation.clone(),
                tolerance_m: *tol,
                max_iterations: *max_iterations,
                ..Default::default()
            };
            ringmesh::run::design(scene, &options, output.as_deref(), &mut |relaxation, r| {
                eprintln!(
                    "{:>8} {:>3}  boundary change {:.3e} m  ratio {:.6}  truss Newton {}  {:.2} s",
                    relaxation.name(),
                    r.iteration,
                    r.boundary_change_max_m,
                    r.ratio,
                    r.oracle_newton_iterations,
                    r.elapsed_s
                );
            })
            .map(|outcome| {
                let r = &outcome.report;
                say!(
                    "{}: {} after {} outer iterations of {}, boundary residual {:.3e} m, ratio {:.6}",
                    r.relaxation.name(),
                    json_name(&r.termination),
                    r.outer_iterations,
                    r.solver,
                    r.boundary_residual_m,
                    r.ratio
                );
                let v = &r.verification;
                say!(
                    "assembled{}: RMS {} mm (max {} mm), tension change {} %, boundary {} mm, {} slack cables",
                    cables_note(v),
                    readable(v.rms_mm, 4),
                    readable(v.max_deviation_mm, 4),
                    readable(v.max_tension_change_pct, 4),
                    readable(v.boundary_deviation_mm, 4),
                    v.slack_cables.len()
                );
                if let Some(c) = &r.conventional {
                    say!(
                        "conventional (rigid-truss) design assembled{}: RMS {} mm (max {} mm), tension change {} %, {} slack cables",
                        cables_note(c),
                        readable(c.rms_mm, 4),
                        readable(c.max_deviation_mm, 4),
                        readable(c.max_tension_change_pct, 4),
                        c.slack_cables.len()
                    );
                }
                if let Some(m) = &r.limit_margin {
                    say!("truss under the design's pull: {m}");
                }
                let t = &r.timings;
                say!(
                    "time: {:.2} s — mesh {:.2}, loop {:.2} (uniformity {:.2}, truss {:.2}), \
                     comparison loops {:.2}, margin {:.2}, verification {:.2}, conventional {:.2}, \
                     writing {:.2}",
                    t.total_s,
                    t.mesh_s,
                    t.design_loop_s(),
                    t.uniformity_s.iter().sum::<f64>(),
                    t.truss_s.iter().sum::<f64>(),
                    t.comparison_loops_s,
                    t.margin_s,
                    t.verification_s,
                    t.conventional_s,
                    t.writing_s
                );
                for w in &r.net.warnings {
                    say!("warning: {w}");
                }
                say_written(&outcome.written);
            })
        }
        Command::Apertures {
            scene,
            apertures,
            margin,
            output,
        } => {
            let settings = ringmesh::study::ApertureSettings {
                apertures_m: apertures.clone(),
                margin: *margin,
                design: Default::default(),
            };
            ringmesh::run::apertures(scene, &settings, output.as_deref(), &mut |r| {
                eprintln!("{}", aperture_line(r))
            })
            .map(|outcome| {
                for r in &outcome.results {
                    say!("{}", aperture_line(r));
                }
                say_written(&outcome.written);
            })
        }
        Command::Size {
            scene,
            margin,
            sections,
            solver,
            output,
        } => {
            let settings = ringmesh::design::DesignSettings {
                solver: *solver,
                ..Default::default()
            };
            ringmesh::run::size(
                scene,
                *margin,
                sections.as_deref(),
                &settings,
                output.as_deref(),
                &mut |t| eprintln!("{}", section_line(t)),
            )
            .map(|outcome| {
                let s = &outcome.sizing;
                let chosen = &s.trials[s.chosen];
                say!(
                    "lightest section with a margin ≥ {} of {} tried: {}",
                    s.margin,
                    s.trials.len(),
                    section_line(chosen)
                );
                say_written(&outcome.written);
            })
        }
        Command::Optimize {
            scene,
            solver,
            output,
        } => ringmesh::run::optimize(scene, *solver, output.as_deref()).map(|(d, written)| {
            for set in &d.sets {
                say!(
                    "ratio over {}: {:.6} ({} cables)",
                    set.name,
                    set.ratio,
                    set.cables
                );
            }
            say!(
                "surface RMS: {} mm (max {} mm)",
                readable(1e3 * d.surface_rms_m, 4),
                readable(1e3 * d.surface_max_m, 4)
            );
            say!(
                "termination: {} after {} iterations of {}, {:.3} s",
                json_name(&d.termination),
                d.iterations,
                d.solver,
                d.time_s
            );
            if let Some(route) = d.route {
                say!("route: {route}");
            }
            for w in &d.warnings {
                say!("warning: {w}");
            }
            say_written(&written);
        }),
        Command::Uniformity {
            network,
            solver,
            groups,
            mean_tension,
            max_force_density,
            output,
        } => ringmesh::run::uniformity(
            network,
            *solver,
            groups.as_deref(),
            *mean_tension,
            max_force_density.unwrap_or(f64::INFINITY),
            output,
        )
        .map(|o| {
            say!("ratio: {:.6}", o.ratio);
            say!("max residual: {:.3e} N", o.max_residual);
            say!(
                "termination: {} after {} iterations of {}, {:.3} s",
                json_name(&o.termination),
                o.iterations,
                o.solver,
                o.time_s
            );
            if let Some(route) = o.route {
                say!("route: {route}");
            }
            for w in &o.warnings {
                say!("warning: {w}");
            }
            say!("wrote {}", output.display());
        }),
        Command::Front {
            scene,
            solvers,
            points,
            shard,
            output,
        } => {
            let progress = bar();
            let result = ringmesh::run::front(
                scene,
                solvers,
                *points,
                output.as_deref(),
                *shard,
                &progress,
            );
            progress.0.finish_and_clear();
            result.map(|(points, written)| {
                for p in &points {
                    match &p.outcome {
                        Ok(t) => say!(
                            "{} knob {:.3e}: ratio {:.6}, RMS {:.3e} mm, {:.3} s ({})",
                            ringmesh::study::value_name(&p.solver),
                            p.knob,
                            p.ratio,
                            p.rms_mm,
                            p.time_s,
                            json_name(t)
                        ),
                        Err(e) => say!(
                            "{} knob {:.3e}: failed: {e}",
                            ringmesh::study::value_name(&p.solver),
                            p.knob
                        ),
                    }
                }
                say_written(&written);
            })
        }
        Command::Study {
            scene,
            knobs,
            tolerances,
            elements,
            rings,
            trusses,
            solvers,
            max_iterations,
            jobs,
            shard,
            output,
        } => {
            let options = ringmesh::run::StudyOptions {
                knobs: knobs.clone(),
                tolerances_m: tolerances.clone(),
                elements_per_rod: elements.clone(),
                rings: rings.clone(),
                truss_models: trusses.clone(),
                solvers: solvers.clone(),
                max_iterations: *max_iterations,
                jobs: *jobs,
            };
            let progress = bar();
            let result = ringmesh::run::study(scene, &options, output.as_deref(), *shard, &progress);
            progress.0.finish_and_clear();
            result.map(|outcome| {
                say!(
                    "{}: {} of {} points (time: design wall time; accuracy: as built on the reference truss)",
                    outcome.scene,
                    outcome.rows.len(),
                    outcome.points
                );
                say!(
                    "{:>5} {:>10} {:>13} {:>9} {:>10} {:>11} {:>11} {:>13} {:>13}",
                    "point", "knob", "value", "time s", "RMS mm", "ratio err", "tension %", "cut len mm", "facet RMS mm"
                );
                for (k, r) in &outcome.rows {
                    let value = if r.value.is_empty() { "-" } else { &r.value };
                    let g = |v: f64| if v.is_finite() { format!("{v:.3e}") } else { "-".into() };
                    match &r.error {
                        Some(e) => say!("{k:>5} {:>10} {value:>13} {:>9.3}  failed: {e}", r.knob.name(), r.time_s),
                        None => say!(
                            "{k:>5} {:>10} {value:>13} {:>9.3} {:>10} {:>11} {:>11} {:>13} {:>13}",
                            r.knob.name(),
                            r.time_s,
                            g(r.rms_mm),
                            g(r.ratio_error),
                            g(r.tension_change_pct),
                            g(r.cut_length_error_mm),
                            g(r.facet_rms_mm)
                        ),
                    }
                }
                say_written(&outcome.written);
            })
        }
        Command::Merge { paths, output } => {
            ringmesh::run::merge(paths, output.as_deref()).map(|outcomes| {
                for m in outcomes {
                    say!(
                        "{} of {}: {} shards, {} rows",
                        m.command,
                        m.scene,
                        m.shards,
                        m.rows
                    );
                    say_written(&m.written);
                }
            })
        }
        Command::Frame { file, output } => {
            ringmesh::run::frame(file, output.as_deref()).map(|(o, paths)| {
                say!("{}", frame_summary(&o));
                say_written(&paths);
                ended_early = o.ended_early();
            })
        }
        Command::Truss {
            scene,
            model,
            loads,
            output,
        } => ringmesh::run::truss(scene, *model, loads.as_deref(), output.as_deref()).map(
            |(r, path)| {
                say!(
                    "{} truss under loads from {}: max displacement {:.6e} m, {} Newton iterations, {} load steps, {:.3} s",
                    r.model, r.loads_from, r.max_displacement_m, r.newton_iterations, r.load_steps, r.time_s
                );
                for a in &r.attachments {
                    let d = a.displacement_m;
                    say!("  {:<10} u = [{:+.4e}, {:+.4e}, {:+.4e}] m", a.hinge, d[0], d[1], d[2]);
                }
                say!("wrote {}", path.display());
            },
        ),
        Command::Cantilever {
            elements,
            element,
            json,
            output,
        } => ringmesh::run::cantilever(*elements, *element, output.as_deref()).map(|table| {
            if *json {
                say!(
                    "{}",
                    serde_json::to_string_pretty(&table).expect("a table serialises")
                );
            } else {
                print_cantilever(&table);
            }
        }),
    };
    match result {
        Ok(()) => match ended_early {
            None => ExitCode::SUCCESS,
            Some(reason) => {
                eprintln!("ended before the full load: {reason}");
                ExitCode::from(3)
            }
        },
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(if error.is_bad_input() { 2 } else { 1 })
        }
    }
}

/// One `wrote PATH` line per file written.
fn say_written(paths: &[PathBuf]) {
    for path in paths {
        say!("wrote {}", path.display());
    }
}

/// One aperture of the aperture study, on one line.
fn aperture_line(r: &ringmesh::study::ApertureResult) -> String {
    let models: Vec<String> = r
        .models
        .iter()
        .map(|m| {
            format!(
                "{} {} mm / {} %",
                ringmesh::study::value_name(&m.model),
                readable(m.rms_mm, 3),
                readable(m.tension_change_pct, 3)
            )
        })
        .collect();
    format!(
        "{} m: {} rings, {:.1}/{:.1} mm tube ({:.0} kg, margin {:.3}), hinges move {:.1} mm; \
         RMS / tension change as built: {} ({:.0} s sizing)",
        r.aperture_m,
        r.rings,
        1e3 * r.section.outer_diameter_m,
        1e3 * r.section.inner_diameter_m,
        r.truss_mass_kg,
        r.margin,
        r.hinge_motion_mm,
        models.join(", "),
        r.sizing_time_s
    )
}

/// One section a sizing tried, on one line.
fn section_line(t: &ringmesh::sizing::SectionTrial) -> String {
    let c = &t.section;
    let outcome = match (&t.failure, t.rms_mm) {
        (Some(f), _) => format!("no design: {f}"),
        (None, Some(rms)) => format!(
            "{} outer iterations, RMS as built {} mm",
            t.outer_iterations,
            readable(rms, 3)
        ),
        (None, None) => String::new(),
    };
    format!(
        "{:.1}/{:.1} mm tube: {:.0} kg, margin {:.3}{}, {}; {outcome} ({:.1} s)",
        1e3 * c.outer_diameter_m,
        1e3 * c.inner_diameter_m,
        t.mass_kg,
        t.margin,
        if t.bound == Some(ringmesh::mechanics::LimitBound::SearchEnd) {
            " (searched to its end)"
        } else {
            ""
        },
        if t.carries {
            "carries"
        } else {
            "does not carry"
        },
        t.time_s
    )
}

/// One paragraph: size, how the solve ended, and its largest results.
fn frame_summary(o: &FrameOutput) -> String {
    let c = &o.counts;
    let ending = match o.termination {
        StaticTermination::Converged => {
            format!("reached its target at load factor {:.6}", o.load_factor)
        }
        StaticTermination::Stalled { load_factor } => {
            format!("STALLED: the load step fell below the minimum at load factor {load_factor:.6}")
        }
        StaticTermination::LimitPoint { limit_load_factor } => {
            format!("passed a LIMIT POINT at load factor {limit_load_factor:.6}")
        }
        StaticTermination::MaxSteps { load_factor } => {
            format!("ran out of steps (MAX STEPS) at load factor {load_factor:.6}")
        }
        StaticTermination::Overflow { load_factor } => {
            format!("OVERFLOWED beyond load factor {load_factor:.6}")
        }
    };
    let reaction = o
        .reactions
        .iter()
        .map(|r| norm3(r.force_n))
        .fold(0.0, f64::max);
    let moment = o
        .reactions
        .iter()
        .map(|r| norm3(r.moment_nm))
        .fold(0.0, f64::max);
    let at = match o.nodes.get(o.max_displacement_node) {
        Some(largest) => match (&largest.rod, largest.rod_node, &largest.body) {
            (Some(rod), Some(i), _) => format!("rod {rod} node {i}"),
            (_, _, Some(body)) => format!("body {body}"),
            _ => format!("node {}", largest.id),
        },
        None => "no node".to_string(),
    };
    format!(
        "{}: {} nodes ({} rods, {} elements, {} bodies, {} joints); {} in {} load steps, \
         {} Newton iterations, {} rejected steps, {:.3} ms; largest displacement {:.6e} m \
         at {at}; largest reaction {:.6e} N, {:.6e} N·m.",
        o.file,
        c.nodes,
        c.rods,
        c.elements,
        c.bodies,
        c.joints,
        ending,
        o.load_steps,
        o.newton_iterations,
        o.rejected_steps,
        1e3 * o.time_s,
        o.max_displacement_m,
        reaction,
        moment
    ) + &o
        .critical_points
        .iter()
        .map(|c| {
            format!(
                "\n  {} at load factor {:.9}{}",
                json_name(&c.kind).replace('_', " "),
                c.load_factor,
                if c.switched_branch {
                    " (followed its branch)"
                } else {
                    ""
                }
            )
        })
        .collect::<String>()
}

/// The cantilever table, one load per line.
fn print_cantilever(t: &CantileverTable) {
    say!(
        "cantilever L = 10, EI = 100 under a tip moment: {} {} elements (paper §3.4, Tables 1-2)",
        t.elements,
        t.element
    );
    say!(
        "{:>9} | {:>9} {:>9} | {:>9} {:>9} | {:>9} {:>9} | {:>9} | {:>6} {:>5} {:>9}",
        "ML/(πEI)",
        "analytic",
        "",
        "paper",
        "",
        "ours",
        "",
        "rel. err",
        "Newton",
        "steps",
        "time ms"
    );
    say!(
        "{:>9} | {:>9} {:>9} | {:>9} {:>9} | {:>9} {:>9} | {:>9} | {:>6} {:>5} {:>9}",
        "",
        "axial",
        "vertical",
        "axial",
        "vertical",
        "axial",
        "vertical",
        "",
        "",
        "",
        ""
    );
    for r in &t.rows {
        let paper = |v: Option<f64>| v.map_or_else(|| "—".to_string(), |v| format!("{v:.5}"));
        let row = &r.row;
        say!(
            "{:>9.1} | {:>9.5} {:>9.5} | {:>9} {:>9} | {:>9.5} {:>9.5} | {:>9.2e} | {:>6} {:>5} {:>9.3}{}",
            row.m_ratio,
            row.analytic_axial_m,
            row.analytic_vertical_m,
            paper(r.paper_axial_m),
            paper(r.paper_vertical_m),
            row.axial_m,
            row.vertical_m,
            row.relative_error,
            row.newton_iterations,
            row.load_steps,
            1e3 * row.time_s,
            if row.converged { "" } else { "  NOT CONVERGED" }
        );
    }
}

/// How the assembly's cables were modelled, when not as built (`[effects]
/// cable_elasticity = false`).
fn cables_note(v: &ringmesh::verify::Verification) -> &'static str {
    match v.cable_model {
        ringmesh::verify::CableModel::Elastic => "",
        ringmesh::verify::CableModel::Inextensible => " with inextensible cables",
    }
}
