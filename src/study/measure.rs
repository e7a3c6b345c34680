//! Running the study: each point designed and timed, judged as built on the
//! reference truss and made a row; the points of a shard run one at a time
//! or in parallel.

use std::time::Instant;

use rayon::prelude::*;

use super::{points, RunSettings, StudyError, StudyPoint, StudyRow, StudySettings};
use crate::design::{LoopSettings, LoopSummary, SceneNets};
use crate::scene::Scene;
use crate::shard::Shard;
use crate::status::Termination;
use crate::surface::facet_rms;
use crate::verify::{verify, AssemblyTruss};

/// A design as built on the reference truss.
struct Judged {
    built_ratio: f64,
    rms_mm: f64,
    max_deviation_mm: f64,
    facet_rms_mm: f64,
    tension_change_pct: f64,
    cut_lengths_m: Vec<f64>,
}

/// One point run and judged.
struct Measurement {
    time_s: f64,
    /// The outer loop's summary and its design's `Tmax/Tmin`, when the loop
    /// ended.
    designed: Option<(LoopSummary, f64)>,
    judged: Option<Judged>,
    error: Option<String>,
}

/// Runs the design of `run` on `scene` and judges it on a truss of
/// `judge_elements` elements per rod. Never fails: a failure is recorded.
fn measure(
    scene: &Scene,
    run: &RunSettings,
    max_iterations: usize,
    judge_elements: usize,
) -> Measurement {
    // The point's net, its tensions resolved for it as for any scene (a
    // membrane stress follows the spacing).
    let mut scene = match scene.clone().with_rings(run.rings) {
        Ok(s) => s,
        Err(e) => {
            return Measurement {
                time_s: 0.0,
                designed: None,
                judged: None,
                error: Some(e.to_string()),
            }
        }
    };
    scene.truss.elements_per_rod = run.elements_per_rod;
    scene.effects.truss = run.truss;
    let settings = LoopSettings {
        tolerance_m: run.tolerance_m,
        max_iterations,
        ..LoopSettings::default()
    };
    let clock = Instant::now();
    let designed = SceneNets::new(&scene).and_then(|nets| {
        let solver = run.solver.build(None);
        let outcome = nets.design_loop(solver.as_ref(), run.truss, &settings, &mut |_| {})?;
        Ok((nets, outcome))
    });
    let time_s = clock.elapsed().as_secs_f64();
    let (nets, outcome) = match designed {
        Ok(d) => d,
        Err(e) => {
            return Measurement {
                time_s,
                designed: None,
                judged: None,
                error: Some(e.to_string()),
            }
        }
    };
    let designed = (LoopSummary::of(&outcome), outcome.design.ratio);
    let mut judge = scene.clone();
    judge.truss.elements_per_rod = judge_elements;
    let network = outcome.problem.network();
    let design = &outcome.design;
    let judged = verify(
        &judge,
        &nets.mesh,
        &nets.effects,
        network,
        design,
        AssemblyTruss::Flexible,
        None,
    )
    // A point that cannot be judged is a row with its reason, not an error.
    .map_err(|e| e.to_string())
    .and_then(|v| {
        let facets = facet_rms(
            &nets.mesh.paraboloid,
            &v.nodes_xyz_m[..nets.mesh.n_front_nodes],
            &nets.mesh.front_triangles,
        )
        .map_err(|e| e.to_string())?;
        let built_ratio = outcome
            .problem
            .sets()
            .iter()
            .map(|set| set.ratio(&v.tensions_n))
            .fold(0.0, f64::max);
        let cut_lengths_m = design
            .lengths_m
            .iter()
            .zip(&design.tensions_n)
            .map(|(&l, &t)| scene.cables.cut_length_m(l, t))
            .collect();
        Ok(Judged {
            built_ratio,
            rms_mm: v.rms_mm,
            max_deviation_mm: v.max_deviation_mm,
            facet_rms_mm: 1e3 * facets.axial_m,
            tension_change_pct: v.max_tension_change_pct,
            cut_lengths_m,
        })
    });
    let (judged, error) = match judged {
        Ok(j) => (Some(j), None),
        Err(e) => (
            None,
            Some(format!("verification on the reference truss: {e}")),
        ),
    };
    Measurement {
        time_s,
        designed: Some(designed),
        judged,
        error,
    }
}

/// The row of `point`, judged against the reference.
fn row(
    point: &StudyPoint,
    m: &Measurement,
    reference: &Judged,
    reference_rings: usize,
) -> StudyRow {
    let nan = f64::NAN;
    let j = m.judged.as_ref();
    let get = |f: fn(&Judged) -> f64| j.map_or(nan, f);
    let cut_length_error_mm = match j {
        Some(j)
            if point.settings.rings == reference_rings
                && j.cut_lengths_m.len() == reference.cut_lengths_m.len() =>
        {
            1e3 * j
                .cut_lengths_m
                .iter()
                .zip(&reference.cut_lengths_m)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        }
        _ => nan,
    };
    StudyRow {
        knob: point.knob,
        value: point.value.clone(),
        settings: point.settings,
        time_s: m.time_s,
        summary: m.designed.map(|(summary, _)| summary),
        ratio: m.designed.map_or(nan, |(_, ratio)| ratio),
        built_ratio: get(|j| j.built_ratio),
        ratio_error: (get(|j| j.built_ratio) - reference.built_ratio).abs() / reference.built_ratio,
        rms_mm: get(|j| j.rms_mm),
        max_deviation_mm: get(|j| j.max_deviation_mm),
        facet_rms_mm: get(|j| j.facet_rms_mm),
        tension_change_pct: get(|j| j.tension_change_pct),
        cut_length_error_mm,
        error: m.error.clone(),
    }
}

/// Runs the points of `shard` (the reference always, to judge them), `jobs`
/// at a time (1: one after the other, so each point's wall time is measured
/// alone), calling `on_point` as each finishes. Returns `(point index, row)`
/// in sweep order.
///
/// # Errors
/// Invalid settings, worker threads that cannot start, or a reference that
/// fails or does not converge.
pub fn run_study(
    scene: &Scene,
    settings: &StudySettings,
    shard: Shard,
    jobs: usize,
    on_point: &(dyn Fn(&StudyRow) + Sync),
) -> Result<Vec<(usize, StudyRow)>, StudyError> {
    settings.validate()?;
    let list = points(scene, settings);
    let reference_point = &list[0];
    let judge_elements = reference_point.settings.elements_per_rod;
    let max_iterations = settings.max_iterations;
    let measured = measure(
        scene,
        &reference_point.settings,
        max_iterations,
        judge_elements,
    );
    let failed = |message: String| StudyError::Reference {
        settings: reference_point.settings.to_string(),
        message,
    };
    if let Some((s, _)) = measured.designed {
        if s.termination != Termination::Converged {
            return Err(failed(format!(
                "its outer loop stopped {:?} after {} iterations (residual {:.3e} m): a \
                 yardstick must be converged",
                s.termination, s.outer_iterations, s.boundary_residual_m
            )));
        }
    }
    let Some(reference) = measured.judged.as_ref() else {
        return Err(failed(measured.error.clone().unwrap_or_default()));
    };
    let reference_rings = reference_point.settings.rings;
    let reference_row = row(reference_point, &measured, reference, reference_rings);
    on_point(&reference_row);
    let others: Vec<usize> = shard
        .points(list.len())
        .into_iter()
        .filter(|&k| k != 0)
        .collect();
    let work = |&k: &usize| {
        let point = &list[k];
        let m = measure(scene, &point.settings, max_iterations, judge_elements);
        let r = row(point, &m, reference, reference_rings);
        on_point(&r);
        (k, r)
    };
    let mut rows: Vec<(usize, StudyRow)> = if jobs <= 1 {
        others.iter().map(work).collect()
    } else {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(jobs)
            .build()
            .map_err(|e| StudyError::Threads {
                jobs,
                message: e.to_string(),
            })?;
        pool.install(|| others.par_iter().map(work).collect())
    };
    if shard.includes(0) {
        rows.insert(0, (0, reference_row));
    }
    Ok(rows)
}
