//! The command line's surface: the `ringmesh` arguments and subcommands
//! (clap), with their help text; `main.rs` dispatches on them.

use std::path::PathBuf;

use clap::{Parser, Subcommand};
use ringmesh::design::RelaxationKind;
use ringmesh::mechanics::ElementKind;
use ringmesh::report::RmsAxis;
use ringmesh::scene::TrussModel;
use ringmesh::shard::Shard;
use ringmesh::study::Knob;
use ringmesh::uniformity::SolverKind;

/// Pretension design of the cable mesh of ring-truss deployable reflectors.
#[derive(Parser)]
#[command(name = "ringmesh", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// Most memory a run may take, e.g. `8G`, `512M` (default: the memory
    /// the machine has available). A run whose estimated need is larger is
    /// refused before it computes, naming the input that sets its size.
    #[arg(long, global = true, value_parser = parse_bytes)]
    pub max_memory: Option<u64>,
}

/// `8G`, `512M`, `64K` or a number of bytes.
fn parse_bytes(text: &str) -> Result<u64, String> {
    let text = text.trim();
    // The unit is the trailing letters, so that a number may have an
    // exponent (`1.5e3M`).
    let number = text.trim_end_matches(|c: char| c.is_ascii_alphabetic());
    let unit = text[number.len()..].to_ascii_uppercase();
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
pub enum Command {
    /// Write a commented starting scene: every key with its unit and meaning
    /// (optional ones commented out with their defaults); it designs as it is.
    /// Never writes over an existing file. The keys in full: docs/scene.md.
    ///
    /// Example: ringmesh init problems/my-dish.toml
    Init {
        /// The scene file to write [default: runs/my-dish.toml]; its stem
        /// names the scene.
        path: Option<PathBuf>,
    },
    /// Build the front net, rear net and ties of a scene.
    ///
    /// Prints a summary (free/fixed nodes, cables per group, shortest and longest
    /// cable) and writes network.json (interchange format, design positions,
    /// uniform initial q per group) and mesh.vtu (for ParaView).
    ///
    /// Example: ringmesh mesh problems/paper-26m.toml
    Mesh {
        /// The scene file (TOML; keys in docs/scene.md, a start from `ringmesh init`).
        scene: PathBuf,
        /// Output folder [default: runs/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Forward force density solve of an interchange-format network.
    ///
    /// Writes nodes (equilibrium xyz), lengths, forces, reactions (per fixed node,
    /// in the order of `fixed`) and max_residual.
    ///
    /// -o names a file or a folder by one rule: an existing folder, or a path
    /// ending in /, is a folder; otherwise a path ending in .json is the file;
    /// any other extension is refused; a path without one is a folder
    /// (created). A folder is never replaced: fdm.json is written into it,
    /// beside what it holds. The folder is checked writable before computing.
    ///
    /// Example: ringmesh fdm runs/paper-26m/network.json -o equilibrium.json
    Fdm {
        /// The network file (JSON: nodes, edges, fixed, q, loads?, groups?).
        network: PathBuf,
        /// Output JSON file, or a folder (receives fdm.json).
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
    /// surface-error.png and model.vtu; one line per outer iteration on stderr,
    /// then one per stage after the loop (a bar when stderr is a terminal).
    ///
    /// Example: ringmesh design problems/realistic-26m.toml --relaxation anderson,paper
    Design {
        /// The scene file (TOML; keys in docs/scene.md, a start from `ringmesh init`).
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
        /// Output folder [default: runs/<scene name>].
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
    /// outer iterations, RMS as built), sizing.png/.svg (margin against mass,
    /// the chosen section marked) and <scene>-sized.toml (the input file with
    /// its tube lines changed, comments kept); one line per section on stderr,
    /// and per outer iteration and stage of its design (a spinner on a terminal).
    ///
    /// Example: ringmesh size problems/paper-26m.toml --margin 2 --sections problems/carbon-tubes.csv
    Size {
        /// The scene file (TOML; keys in docs/scene.md, a start from `ringmesh init`).
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
        /// Output folder [default: runs/<scene name>].
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
        /// The scene file (TOML; keys in docs/scene.md, a start from `ringmesh init`).
        scene: PathBuf,
        /// The apertures, m, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "26,40,60,80,100")]
        apertures: Vec<f64>,
        /// The limit margin each truss is sized for (1 … 4).
        #[arg(long, default_value_t = 2.0)]
        margin: f64,
        /// Output folder [default: runs/<scene name>/apertures].
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
        /// The scene file (TOML; keys in docs/scene.md, a start from `ringmesh init`).
        scene: PathBuf,
        /// The uniformity solver [default: lp for one uniformity set without
        /// loads, bisection otherwise].
        #[arg(long, value_enum)]
        solver: Option<SolverKind>,
        /// Output folder [default: runs/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Tension uniformity on a network file whose node positions are the prescribed
    /// geometry (free = not fixed).
    ///
    /// The other cables only need 0 < q. Writes q, tensions, ratio, max_residual,
    /// solver, termination, iterations, time_s.
    ///
    /// -o names a file or a folder by one rule: an existing folder, or a path
    /// ending in /, is a folder; otherwise a path ending in .json is the file;
    /// any other extension is refused; a path without one is a folder
    /// (created). A folder is never replaced: uniformity.json is written into it,
    /// beside what it holds. The folder is checked writable before computing.
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
        /// Output JSON file, or a folder (receives uniformity.json).
        #[arg(short, long)]
        output: PathBuf,
    },
    /// The design front: ratio against actual surface RMS, sweeping each solver's
    /// accuracy knob (ε for bisection, weight for gradient, λ for least squares).
    ///
    /// Writes front.csv (solver,knob,ratio,rms_mm,time_s), front.png and front.svg,
    /// and front-time.png/.svg: every solver's wall time against its surface RMS.
    ///
    /// Example: ringmesh front problems/small-hex.toml --solvers bisection,least-squares --points 8
    Front {
        /// The scene file (TOML; keys in docs/scene.md, a start from `ringmesh init`).
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
        /// The surface RMS the plot is drawn against: `design`, each point's
        /// forward solve's; `total`, √(facets² + design²) with the facet RMS
        /// of the net's design surface (a shard draws nothing; `merge` draws
        /// against design).
        #[arg(long, value_enum, default_value = "design")]
        rms: RmsAxis,
        /// Run only shard I of N (from 0: point k runs when k mod N = I) and
        /// write front.shard-I-of-N.csv; join the shards with `ringmesh merge`.
        #[arg(long, value_name = "I/N")]
        shard: Option<Shard>,
        /// Output folder [default: runs/<scene name>].
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
        /// The scene file (TOML; keys in docs/scene.md, a start from `ringmesh init`).
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
        /// The surface RMS the plot is drawn against: `design`, the RMS as
        /// built; `total`, √(facets² + design²) with the facet RMS of each
        /// net's design surface (a shard draws nothing; `merge` draws
        /// against design).
        #[arg(long, value_enum, default_value = "design")]
        rms: RmsAxis,
        /// Run only shard I of N (from 0: point k runs when k mod N = I; every
        /// shard also runs the reference) and write
        /// accuracy-vs-time.shard-I-of-N.csv; join with `ringmesh merge`.
        #[arg(long, value_name = "I/N")]
        shard: Option<Shard>,
        /// Output folder [default: runs/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// The error budget of a dish as built on the flexible truss: facets,
    /// design, each thermal case, manufacturing tolerances, their
    /// root-sum-square and the gain loss at the scene's frequency.
    ///
    /// The scene's `[effects.thermal]` (expansion coefficients, named load
    /// cases) and `[tolerances]` (standard deviations of cut lengths, rod
    /// lengths, EA, hinge positions) say what to budget. Each case and each
    /// Monte Carlo sample is assembled from the design's equilibrium by
    /// Newton and, on the same draws, through its tangent (linearised).
    /// Writes budget.csv, budget.json, budget-samples.csv (every point),
    /// budget.png and budget.svg; with --shard, budget-samples.shard-I-of-N.csv
    /// for `ringmesh merge`.
    ///
    /// Example: ringmesh budget problems/small-hex.toml --samples 100 --seed 1
    Budget {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Monte Carlo samples [default: the scene's `[tolerances] samples`, else 100].
        #[arg(long)]
        samples: Option<usize>,
        /// Seed of the samples [default: the scene's `[tolerances] seed`, else 1].
        #[arg(long)]
        seed: Option<u64>,
        /// The budget of the conventional design (made for the undeformed
        /// truss, the outer loop's iteration 0) built on the same flexible
        /// truss, instead of the flexible-truss design's: which error the
        /// flexible design removes, and what is left.
        #[arg(long)]
        conventional: bool,
        /// Run only shard I of N (from 0: point k runs when k mod N = I) and
        /// write budget-samples.shard-I-of-N.csv; join the shards with
        /// `ringmesh merge`.
        #[arg(long, value_name = "I/N")]
        shard: Option<Shard>,
        /// Output folder [default: runs/<scene name>, with --conventional
        /// runs/<scene name>/conventional].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Join the shards of `front`, `study` or `budget` runs into one table and plot.
    ///
    /// Takes shard files or folders holding *.shard-I-of-N.csv; each command's
    /// shards must be all of 0..N of one sweep of one scene with the same
    /// settings, else nothing is written. Writes front.csv/.png/.svg,
    /// accuracy-vs-time.csv/.png/.svg or the budget's files.
    ///
    /// Example: ringmesh merge runs/realistic-26m
    Merge {
        /// Shard files, or folders holding them.
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Output folder [default: runs/<scene name>].
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
    /// -o names a file or a folder by one rule: an existing folder, or a path
    /// ending in /, is a folder; otherwise a path ending in .json is the file;
    /// any other extension is refused; a path without one is a folder
    /// (created). A folder receives frame.json and frame-path.csv/.png/.svg as
    /// one set, swapped in whole, keeping the other files it holds. A file
    /// D/x.json is written with x-path.csv/.png/.svg beside it, each renamed
    /// into D, which is never swapped. Checked writable before computing.
    ///
    /// Example: ringmesh frame problems/frames/cantilever-moment.toml
    Frame {
        /// The frame file (TOML).
        file: PathBuf,
        /// Output JSON file, or folder [default: the folder runs/<file
        /// stem>/]; the path's <stem>-path.csv/.png/.svg are written beside it.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// The ring truss's response to the pull of the scene's net (forward FDM
    /// with its initial q) or to loads from a file: attachment displacements.
    ///
    /// Loads file: {"loads_n": [[fx, fy, fz], ...]}, top hinges then bottom
    /// hinges, N. Writes truss-<model>.json to runs/<scene>/.
    ///
    /// -o names a file or a folder by one rule: an existing folder, or a path
    /// ending in /, is a folder; otherwise a path ending in .json is the file;
    /// any other extension is refused; a path without one is a folder
    /// (created). A folder is never replaced: truss-<model>.json is written into it,
    /// beside what it holds. The folder is checked writable before computing.
    ///
    /// Example: ringmesh truss problems/paper-26m.toml --model linear
    Truss {
        /// The scene file (TOML; keys in docs/scene.md, a start from `ringmesh init`).
        scene: PathBuf,
        /// Truss model [default: the scene's effects.truss].
        #[arg(long, value_enum)]
        model: Option<TrussModel>,
        /// Attachment loads (JSON) instead of the net's pull.
        #[arg(long)]
        loads: Option<PathBuf>,
        /// Output JSON file, or a folder (receives truss-<model>.json)
        /// [default: runs/<scene name>/].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// The paper's cantilever rolled up by a tip moment (Tables 1–2): analytic,
    /// paper and ours side by side, ML/(πEI) = 0.2 … 2.0 (the full circle).
    ///
    /// -o names a file or a folder by one rule: an existing folder, or a path
    /// ending in /, is a folder; otherwise a path ending in .json is the file;
    /// any other extension is refused; a path without one is a folder
    /// (created). A folder is never replaced: cantilever.json is written into it,
    /// beside what it holds. The folder is checked writable before computing.
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
        /// Also write the table to this folder, as cantilever.json, or to
        /// this .json file.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
}
