//! `lp` beside clarabel and `gradient` on the same plan LPs, in one run
//! (issue 38): for each net family of `tests/common/nets.rs` (`hex`,
//! `sector`, `jitter`) and size (~10³ and ~10⁴ free net nodes by default),
//! in this one process,
//!
//! * ringmesh's `lp` (its route and the plan interior point's iterations),
//! * clarabel on the same plan LP (`tests/common/plan_lp.rs`), QDLDL and
//!   faer backends,
//! * ringmesh's `gradient` with the settings `ringmesh uniformity --solver
//!   gradient` uses (from `lp`'s optimum, so its time includes an `lp`;
//!   its route column counts the exact finish's programs and their
//!   interior-point iterations),
//!
//! each timed as the best wall time of `RINGMESH_SIDE_REPEATS` solves
//! (default 3; one solve on nets of more than 50 000 nodes, and no repeat
//! after a solve longer than 30 s). Prints a table and writes a CSV
//! (`family, free_nodes, cables, solver, backend, route, iterations, status,
//! ratio, ratio_rel_diff, agree, time_s, solves, time_over_lp,
//! clarabel_best_over_lp, gradient_over_lp, load_1min`), rewritten after
//! every net so that a run stopped early keeps its rows. `ratio_rel_diff` is
//! `|ratio − lp's ratio| / lp's ratio`; `agree` is `yes` within 1e-6, `NO`
//! beyond it (and the run's exit status is then 1), `n/a` for `gradient`,
//! whose geometry is free. `*_over_lp` are wall-time ratios against `lp`'s
//! row (`clarabel_best`: the faster backend); `load_1min` is the 1-minute
//! load average (`/proc/loadavg`) when the family's row was started.
//!
//! Not a criterion bench: at 10⁵ nodes one solve takes minutes. Environment:
//!
//! * `RINGMESH_SIDE_FREE` — comma-separated free-node counts (default
//!   `1000,10000`; add `100000` for ~10⁵, rows `nets::rings_for`);
//! * `RINGMESH_SIDE_FAMILIES` — comma-separated families (default all);
//! * `RINGMESH_SIDE_REPEATS` — solves per timing (default 3);
//! * `RINGMESH_SIDE_GRADIENT` — `1` runs `gradient` at every size, `0` at
//!   none (default: up to ~10³ free nodes; on the jittered net at 10⁴ it
//!   took 871 s, at 10⁵ over half an hour a net);
//! * `RINGMESH_SIDE_NETS` — comma-separated network files (interchange
//!   JSON, e.g. `ringmesh mesh`'s `network.json` of a shipped scene), each
//!   solved as `ringmesh uniformity` poses it (its `front` group the set;
//!   `gradient` only with `RINGMESH_SIDE_GRADIENT=1`), after the families
//!   named in `RINGMESH_SIDE_FAMILIES` (none by default when files are
//!   given); the family column is the file's path without `.json`;
//! * `RINGMESH_SIDE_CSV` — the CSV's path (default
//!   `target/side-by-side.csv`; a first argument not starting with `-`
//!   overrides both).
//!
//! ```text
//! cargo bench --bench side_by_side
//! RINGMESH_SIDE_FREE=100000 cargo bench --bench side_by_side
//! ringmesh mesh problems/super-100m.toml -o target/super-100m-mesh
//! RINGMESH_SIDE_NETS=target/super-100m-mesh/network.json cargo bench --bench side_by_side
//! ```
//!
//! `scripts/bench/side-by-side.sh` runs it into `results/bench/side-by-side.csv`.

#[path = "../tests/common/hexnet.rs"]
mod hexnet;
#[path = "../tests/common/nets.rs"]
mod nets;
#[path = "../tests/common/plan_lp.rs"]
mod plan_lp;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use ringmesh::network::Network;
use ringmesh::report::json_name;
use ringmesh::run::uniformity_problem;
use ringmesh::uniformity::{Gradient, Lp, UniformityProblem, UniformitySolver};

/// Relative ratio difference to `lp`'s beyond which a row is marked `NO`.
const RATIO_TOLERANCE: f64 = 1e-6;
/// Nets above this many nodes are solved once.
const REPEATED_MAX_NODES: usize = 50_000;
/// A solve longer than this, s, is not repeated.
const REPEATED_MAX_S: f64 = 30.0;
/// Free net nodes up to which `gradient` runs by default.
const GRADIENT_DEFAULT_MAX_FREE: usize = 2_000;

/// One solver's row of the table.
#[derive(Debug, Clone)]
struct Row {
    solver: &'static str,
    backend: &'static str,
    route: String,
    iterations: String,
    status: String,
    ratio: f64,
    time_s: f64,
    solves: usize,
}

impl Row {
    /// The row of a solve of `solver` that failed with `error`.
    fn failed(
        solver: &'static str,
        error: &dyn std::fmt::Display,
        time_s: f64,
        solves: usize,
    ) -> Self {
        Row {
            solver,
            backend: "",
            route: String::new(),
            iterations: String::new(),
            status: format!("error: {error}"),
            ratio: f64::NAN,
            time_s,
            solves,
        }
    }
}

/// One net: its family (or file), size and the rows of its solvers.
#[derive(Debug)]
struct NetRows {
    family: String,
    free: usize,
    cables: usize,
    load: f64,
    rows: Vec<Row>,
}

/// The settings of the run, from the environment.
#[derive(Debug)]
struct Settings {
    free: Vec<usize>,
    families: Vec<nets::Family>,
    /// Network files (interchange JSON) solved after the families, their
    /// `front` group the set.
    files: Vec<PathBuf>,
    repeats: usize,
    gradient: Option<bool>,
    csv: PathBuf,
}

impl Settings {
    fn from_env() -> Self {
        let var = |name: &str| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
        let free = var("RINGMESH_SIDE_FREE").map_or(vec![1_000, 10_000], |v| {
            v.split(',')
                .map(|s| {
                    s.trim()
                        .parse::<usize>()
                        .unwrap_or_else(|_| panic!("RINGMESH_SIDE_FREE: `{s}` is not a count"))
                })
                .collect()
        });
        let files = var("RINGMESH_SIDE_NETS").map_or_else(Vec::new, |v| {
            v.split(',').map(|s| PathBuf::from(s.trim())).collect()
        });
        // Network files alone unless families are named too.
        let all = if files.is_empty() {
            nets::Family::ALL.to_vec()
        } else {
            Vec::new()
        };
        let families = var("RINGMESH_SIDE_FAMILIES").map_or(all, |v| {
            v.split(',')
                .map(|s| {
                    *nets::Family::ALL
                        .iter()
                        .find(|f| f.name() == s.trim())
                        .unwrap_or_else(|| {
                            panic!("RINGMESH_SIDE_FAMILIES: no family `{s}` (hex, sector, jitter)")
                        })
                })
                .collect()
        });
        let repeats = var("RINGMESH_SIDE_REPEATS").map_or(3, |v| {
            v.trim()
                .parse::<usize>()
                .ok()
                .filter(|&n| n >= 1)
                .unwrap_or_else(|| panic!("RINGMESH_SIDE_REPEATS: `{v}` is not a count ≥ 1"))
        });
        let gradient = var("RINGMESH_SIDE_GRADIENT").map(|v| match v.trim() {
            "1" => true,
            "0" => false,
            other => panic!("RINGMESH_SIDE_GRADIENT: `{other}` is not 0 or 1"),
        });
        let argument = std::env::args().skip(1).find(|a| !a.starts_with('-'));
        let csv = argument.or_else(|| var("RINGMESH_SIDE_CSV")).map_or_else(
            || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/side-by-side.csv"),
            PathBuf::from,
        );
        Settings {
            free,
            families,
            files,
            repeats,
            gradient,
            csv,
        }
    }
}

/// The 1-minute load average, NaN where `/proc/loadavg` is not.
fn load_1min() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(f64::NAN)
}

/// The best wall time of up to `repeats` runs of `solve` and the last run's
/// outcome; no further run after one longer than [`REPEATED_MAX_S`].
fn best_of<T>(repeats: usize, mut solve: impl FnMut() -> T) -> (T, f64, usize) {
    let mut best = f64::INFINITY;
    let mut solves = 0;
    loop {
        let start = Instant::now();
        let outcome = solve();
        let t = start.elapsed().as_secs_f64();
        best = best.min(t);
        solves += 1;
        if solves >= repeats || t > REPEATED_MAX_S {
            return (outcome, best, solves);
        }
    }
}

/// A ringmesh solver's row: the design's route, iterations, termination and
/// ratio, or the error as the status.
fn ringmesh_row(
    solver: &'static str,
    repeats: usize,
    run: &dyn UniformitySolver,
    p: &UniformityProblem,
) -> Row {
    let (outcome, time_s, solves) = best_of(repeats, || run.solve(p));
    match outcome {
        Ok(d) => Row {
            solver,
            backend: "",
            route: d.route.map_or(String::new(), |r| r.to_string()),
            iterations: d.iterations.to_string(),
            status: json_name(&d.termination),
            ratio: d.ratio,
            time_s,
            solves,
        },
        Err(e) => Row::failed(solver, &e, time_s, solves),
    }
}

/// `gradient`'s row, with the settings of `ringmesh uniformity --solver
/// gradient` (`SolverKind::Gradient`'s defaults); its route column says the
/// exact finish's programs (steps and second-order corrections), their
/// interior-point iterations and the warnings (each printed).
fn gradient_row(repeats: usize, p: &UniformityProblem) -> Row {
    let gradient = Gradient {
        exact_finish: true,
        ..Gradient::default()
    };
    let (outcome, time_s, solves) = best_of(repeats, || gradient.solve_with_history(p));
    match outcome {
        Ok((d, history)) => {
            for w in &d.warnings {
                eprintln!("    warning: {w}");
            }
            Row {
                solver: "gradient",
                backend: "",
                route: format!(
                    "exact finish: {} programs + {} corrections, {} interior-point iterations, \
                     {} warnings",
                    history.finish_steps,
                    history.finish_corrections,
                    history.finish_interior_iterations,
                    d.warnings.len()
                ),
                iterations: d.iterations.to_string(),
                status: json_name(&d.termination),
                ratio: d.ratio,
                time_s,
                solves,
            }
        }
        Err(e) => Row::failed("gradient", &e, time_s, solves),
    }
}

/// Every solver on the net of `family` with about `free_target` free nodes.
fn measure_family(family: nets::Family, free_target: usize, settings: &Settings) -> NetRows {
    let p = family.problem(nets::rings_for(free_target));
    let gradient = settings
        .gradient
        .unwrap_or(free_target <= GRADIENT_DEFAULT_MAX_FREE);
    measure(family.name().to_string(), &p, gradient, settings)
}

/// Every solver on the network of `path` (`ringmesh uniformity`'s problem
/// of it: its `front` group the set), `gradient` where asked for.
fn measure_file(path: &Path, settings: &Settings) -> NetRows {
    let network = Network::read_json(path)
        .unwrap_or_else(|e| panic!("RINGMESH_SIDE_NETS: {}: {e}", path.display()));
    let p = uniformity_problem(network, None, None, f64::INFINITY)
        .unwrap_or_else(|e| panic!("RINGMESH_SIDE_NETS: {}: {e}", path.display()));
    let name = path.with_extension("").display().to_string();
    measure(name, &p, settings.gradient.unwrap_or(false), settings)
}

/// Every solver on the problem `p` of the net named `family`.
fn measure(family: String, p: &UniformityProblem, gradient: bool, settings: &Settings) -> NetRows {
    let free = p.structure().free_nodes().len();
    let cables = p.sets()[0].edges.len();
    let repeats = if p.network().n_nodes() > REPEATED_MAX_NODES {
        1
    } else {
        settings.repeats
    };
    let load = load_1min();
    eprintln!(
        "{family} / {free} free nodes ({} nodes, load {load:.2}):",
        p.network().n_nodes()
    );
    let mut rows = Vec::new();
    let lp = ringmesh_row("lp", repeats, &Lp, p);
    eprintln!("  lp {:.3} s", lp.time_s);
    rows.push(lp);
    for backend in ["qdldl", "faer"] {
        let (o, time_s, solves) = best_of(repeats, || plan_lp::solve_plan(p, backend));
        eprintln!("  clarabel {backend} {time_s:.3} s");
        rows.push(Row {
            solver: "clarabel",
            backend,
            route: "plan LP".into(),
            iterations: o.iterations.to_string(),
            status: o.status,
            ratio: o.ratio,
            time_s,
            solves,
        });
    }
    if gradient {
        let row = gradient_row(repeats, p);
        eprintln!("  gradient {:.3} s ({})", row.time_s, row.route);
        rows.push(row);
    }
    NetRows {
        family,
        free,
        cables,
        load,
        rows,
    }
}

/// The time of the row of `solver` (the fastest of its backends), NaN when
/// it did not run.
fn best_time(net: &NetRows, solver: &str) -> f64 {
    net.rows
        .iter()
        .filter(|r| r.solver == solver)
        .map(|r| r.time_s)
        .fold(f64::NAN, f64::min)
}

/// `a / b` with 4 significant digits, empty when either is NaN.
fn ratio_text(a: f64, b: f64) -> String {
    let r = a / b;
    if r.is_finite() {
        format!("{r:.4}")
    } else {
        String::new()
    }
}

/// `text` as a CSV field: quoted when it holds a comma or a quote.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// The CSV and the printed table of `nets_rows`, and how many rows disagree
/// with `lp`'s ratio.
fn tables(nets_rows: &[NetRows]) -> (String, String, usize) {
    let mut csv = String::from(
        "family,free_nodes,cables,solver,backend,route,iterations,status,ratio,\
         ratio_rel_diff,agree,time_s,solves,time_over_lp,clarabel_best_over_lp,\
         gradient_over_lp,load_1min\n",
    );
    let mut table = String::from(
        "| family | free nodes | solver | backend | iterations | status | Tmax/Tmin | \
         agree | time | × lp |\n|---|---:|---|---|---:|---|---:|---|---:|---:|\n",
    );
    let mut disagreements = 0;
    for net in nets_rows {
        let lp_ratio = net.rows[0].ratio;
        let lp_time = net.rows[0].time_s;
        let clarabel = ratio_text(best_time(net, "clarabel"), lp_time);
        let gradient = ratio_text(best_time(net, "gradient"), lp_time);
        for r in &net.rows {
            let diff = (r.ratio - lp_ratio).abs() / lp_ratio;
            let agree = match r.solver {
                "lp" => "ref",
                "gradient" => "n/a",
                _ if diff <= RATIO_TOLERANCE => "yes",
                _ => {
                    disagreements += 1;
                    "NO"
                }
            };
            let status = r.status.replace('\n', " ");
            writeln!(
                csv,
                "{},{},{},{},{},{},{},{},{:.10},{:.3e},{},{:.6},{},{},{},{},{:.2}",
                net.family,
                net.free,
                net.cables,
                r.solver,
                r.backend,
                csv_field(&r.route),
                r.iterations,
                csv_field(&status),
                r.ratio,
                diff,
                agree,
                r.time_s,
                r.solves,
                ratio_text(r.time_s, lp_time),
                clarabel,
                gradient,
                net.load
            )
            .expect("writing to a String");
            writeln!(
                table,
                "| {} | {} | {} | {} | {} | {} | {:.8} | {} | {:.3} s | {} |",
                net.family,
                net.free,
                r.solver,
                r.backend,
                r.iterations,
                status,
                r.ratio,
                agree,
                r.time_s,
                ratio_text(r.time_s, lp_time)
            )
            .expect("writing to a String");
        }
    }
    (csv, table, disagreements)
}

/// Writes `csv` to `path`, its folder made first.
fn write_csv(path: &Path, csv: &str) {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).expect("the CSV's folder can be made");
    }
    std::fs::write(path, csv).expect("the CSV can be written");
}

fn main() {
    let settings = Settings::from_env();
    let mut nets_rows = Vec::new();
    for &free in &settings.free {
        for &family in &settings.families {
            nets_rows.push(measure_family(family, free, &settings));
            // After every net, so that a run stopped early keeps its rows.
            write_csv(&settings.csv, &tables(&nets_rows).0);
        }
    }
    for path in &settings.files {
        nets_rows.push(measure_file(path, &settings));
        write_csv(&settings.csv, &tables(&nets_rows).0);
    }
    let (csv, table, disagreements) = tables(&nets_rows);
    println!("{table}");
    println!("| family | free nodes | load | clarabel best / lp | gradient / lp |");
    println!("|---|---:|---:|---:|---:|");
    for net in &nets_rows {
        let lp_time = net.rows[0].time_s;
        println!(
            "| {} | {} | {:.2} | {} | {} |",
            net.family,
            net.free,
            net.load,
            ratio_text(best_time(net, "clarabel"), lp_time),
            ratio_text(best_time(net, "gradient"), lp_time)
        );
    }
    write_csv(&settings.csv, &csv);
    println!("\nwritten {}", settings.csv.display());
    if disagreements > 0 {
        eprintln!(
            "{disagreements} row(s) whose ratio differs from lp's by more than {RATIO_TOLERANCE:e} (agree = NO)"
        );
        std::process::exit(1);
    }
}
