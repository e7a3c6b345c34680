//! The `ringmesh` command line: parses arguments ([`cli`]), calls
//! [`ringmesh::run`], prints the command's summary ([`Summary`]).
//! Exit codes: 0 success, 1 failure, 2 bad input (nothing is written then), 3
//! a run that ended before its target — a `frame` path short of its full
//! load, a `design` loop stopped before its tolerance — (its results are
//! written), 130 interrupted (SIGINT, SIGTERM, SIGHUP).

mod cli;
mod progress;

use std::process::ExitCode;

use clap::Parser;
use ringmesh::budget::BudgetDesign;
use ringmesh::run::{self, Summary};

use cli::{Cli, Command};
use progress::{bar, DesignProgress, SizeProgress};

fn main() -> ExitCode {
    ringmesh::resources::retain_freed_memory();
    let cli = Cli::parse();
    ringmesh::resources::set_memory_limit(cli.max_memory);
    // SIGINT, SIGTERM, SIGHUP: no staging folder or temporary file is left.
    let _ = ctrlc::set_handler(|| ringmesh::report::abandon_all_and_exit(130));
    // A file-size limit (`ulimit -f`) then fails the write that crosses it
    // (EFBIG), reported and cleaned up like a full disk, instead of killing
    // the run by SIGXFSZ with its staging folder left.
    // SAFETY: setting a signal's disposition to "ignore" before any thread
    // that writes is started; no handler runs.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    match dispatch(&cli.command) {
        Ok(summary) => {
            print(&summary);
            match summary.ended_early {
                None => ExitCode::SUCCESS,
                Some(reason) => {
                    eprintln!("{reason}");
                    ExitCode::from(3)
                }
            }
        }
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(if error.is_bad_input() { 2 } else { 1 })
        }
    }
}

/// Prints a summary to stdout; a closed pipe (`ringmesh … | head`) is not an
/// error.
fn print(summary: &Summary) {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    for line in &summary.lines {
        let _ = writeln!(stdout, "{line}");
    }
}

/// Runs a command: its arguments handed to its [`ringmesh::run`] function,
/// its progress shown on stderr; returns what it prints.
fn dispatch(command: &Command) -> Result<Summary, ringmesh::Error> {
    Ok(match command {
        Command::Init { path } => run::init(path.as_deref())?.summary(),
        Command::Mesh { scene, output } => run::mesh(scene, output.as_deref())?.summary(),
        Command::Fdm { network, output } => run::fdm(network, output)?.summary(),
        Command::Design {
            scene,
            solver,
            truss,
            relaxation,
            tol,
            max_iterations,
            output,
        } => {
            let settings = ringmesh::design::DesignSettings {
                solver: *solver,
                truss: *truss,
                relaxations: relaxation.clone(),
                tolerance_m: *tol,
                max_iterations: *max_iterations,
                ..Default::default()
            };
            let mut progress = DesignProgress::new();
            let result = run::design_observed(scene, &settings, output.as_deref(), &mut progress);
            progress.bar.finish_and_clear();
            result?.summary()
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
            run::apertures(scene, &settings, output.as_deref(), &mut |r| {
                eprintln!("{}", run::aperture_line(r))
            })?
            .summary()
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
            let mut progress = SizeProgress::new();
            let result = run::size(
                scene,
                *margin,
                sections.as_deref(),
                &settings,
                output.as_deref(),
                &mut progress,
            );
            progress.bar.finish_and_clear();
            result?.summary()
        }
        Command::Optimize {
            scene,
            solver,
            output,
        } => run::optimize(scene, *solver, output.as_deref())?.summary(),
        Command::Uniformity {
            network,
            solver,
            groups,
            mean_tension,
            max_force_density,
            output,
        } => run::uniformity(
            network,
            *solver,
            groups.as_deref(),
            *mean_tension,
            max_force_density.unwrap_or(f64::INFINITY),
            output,
        )?
        .summary(),
        Command::Front {
            scene,
            solvers,
            points,
            rms,
            shard,
            output,
        } => {
            let progress = bar();
            let result = run::front(
                scene,
                solvers,
                *points,
                *rms,
                output.as_deref(),
                *shard,
                &progress,
            );
            progress.0.finish_and_clear();
            result?.summary()
        }
        Command::Budget {
            scene,
            samples,
            seed,
            conventional,
            shard,
            output,
        } => {
            let progress = bar();
            let design = match conventional {
                true => BudgetDesign::Conventional,
                false => BudgetDesign::Flexible,
            };
            let result = run::budget(
                scene,
                (*samples, *seed),
                design,
                output.as_deref(),
                *shard,
                &progress,
            );
            progress.0.finish_and_clear();
            result?.summary()
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
            rms,
            shard,
            output,
        } => {
            let options = run::StudyOptions {
                knobs: knobs.clone(),
                tolerances_m: tolerances.clone(),
                elements_per_rod: elements.clone(),
                rings: rings.clone(),
                truss_models: trusses.clone(),
                solvers: solvers.clone(),
                max_iterations: *max_iterations,
                jobs: *jobs,
                rms: *rms,
            };
            let progress = bar();
            let result = run::study(scene, &options, output.as_deref(), *shard, &progress);
            progress.0.finish_and_clear();
            result?.summary()
        }
        Command::Merge { paths, output } => run::merge(paths, output.as_deref())?.summary(),
        Command::Frame { file, output } => run::frame(file, output.as_deref())?.summary(),
        Command::Truss {
            scene,
            model,
            loads,
            output,
        } => run::truss(scene, *model, loads.as_deref(), output.as_deref())?.summary(),
        Command::Cantilever {
            elements,
            element,
            json,
            output,
        } => run::cantilever(*elements, *element, output.as_deref())?.summary(*json),
    })
}
