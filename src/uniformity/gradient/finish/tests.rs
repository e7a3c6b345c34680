//! The structured interior point against clarabel on the step programs of
//! the shipped scenes: one program, two independent solvers.

use super::*;
use crate::uniformity::gradient::fixtures::pattern;
use crate::uniformity::{Gradient, Lp, UniformityProblem, UniformitySolver};

fn problem(name: &str) -> UniformityProblem {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(name);
    let scene = crate::Scene::read(&path).expect("scene");
    crate::design::scene_problem(&scene).expect("problem").1
}

/// At `lp`'s optimum shifted by up to ±3 % per cable, with a tight and a
/// wide trust radius, and with and without the level term: both solvers'
/// points, made feasible, have one value to clarabel's tolerance, the
/// interior point's never above clarabel's, and it meets the box and the
/// linearised equilibrium.
#[test]
fn the_interior_point_and_clarabel_agree_on_the_step_programs() {
    for name in ["problems/small-hex.toml", "problems/paper-26m.toml"] {
        let problem = problem(name);
        let lp = Lp.solve(&problem).expect("lp");
        let shift = pattern(lp.q.len(), 3);
        let q: Vec<f64> =
            lp.q.iter()
                .zip(&shift)
                .map(|(q, s)| q * (1.0 + 0.03 * s))
                .collect();
        for level_weight in [0.0, Gradient::default().level_weight] {
            let settings = Gradient {
                level_weight,
                ..Gradient::default()
            };
            let objective = Objective::new(&settings, &problem);
            for radius in [0.01, 0.5] {
                let (model, eq) =
                    step_model(&objective, &q, radius, &FinishSettings::default()).expect("model");
                let feasible = |z: &[f64]| model.feasible_point(z, |rhs| eq.solve_d(rhs));
                let ours = feasible(
                    &ipm::solve(&model, None, false, &IpmSettings::finish())
                        .expect("interior point")
                        .z,
                );
                let theirs = feasible(&model.solve_with_clarabel().expect("clarabel"));
                let (a, b) = (model.value(&ours), model.value(&theirs));
                let case = format!("{name}, κ {level_weight}, radius {radius}");
                // clarabel stops at a gap of 1e-8 (its points lie up to
                // 3e-8 above here); the interior point at 1e-10, and is
                // never the higher of the two.
                let unit = b.abs().max(1.0);
                assert!(
                    a - b <= 1e-10 * unit && b - a <= 5e-8 * unit,
                    "{case}: {a} against clarabel's {b}"
                );
                assert!(
                    a < model.value(&feasible(&vec![0.0; model.n()])),
                    "{case}: no decrease"
                );
                for (p, cable) in ours.iter().zip(&model.cables) {
                    assert!((cable.lo..=cable.hi).contains(p), "{case}");
                }
                let mut residual = vec![0.0; 3 * model.n_free];
                model.equilibrium_mul(&ours, &mut residual);
                let scale = ours[..model.m()]
                    .iter()
                    .fold(0.0_f64, |a, p| a.max(p.abs()));
                assert!(
                    residual.iter().all(|r| r.abs() <= 1e-10 * scale),
                    "{case}: linearised equilibrium"
                );
            }
        }
    }
}

/// The finish's budget is its settings': from `lp`'s optimum shifted by ±3 %
/// per cable on small-hex, one program cannot reach the certificate and
/// says so; the default budget does.
#[test]
fn the_finish_stops_at_its_step_budget_and_converges_within_the_default() {
    let problem = problem("problems/small-hex.toml");
    let lp = Lp.solve(&problem).expect("lp");
    let shift = pattern(lp.q.len(), 3);
    let q: Vec<f64> =
        lp.q.iter()
            .zip(&shift)
            .map(|(q, s)| q * (1.0 + 0.03 * s))
            .collect();
    let gradient = Gradient::default();
    let objective = Objective::new(&gradient, &problem);
    let one = FinishSettings {
        max_steps: 1,
        ..FinishSettings::default()
    };
    let short = finish(&objective, &q, &one, &IpmSettings::finish()).expect("finish");
    assert_eq!(short.termination, Termination::MaxIterations);
    assert_eq!(short.steps, 1);
    assert!(
        short
            .warnings
            .iter()
            .any(|w| w.contains("did not converge in 1 steps")),
        "{:?}",
        short.warnings
    );
    let full = finish(
        &objective,
        &q,
        &FinishSettings::default(),
        &IpmSettings::finish(),
    )
    .expect("finish");
    assert_eq!(
        full.termination,
        Termination::Converged,
        "{:?}",
        full.warnings
    );
    assert!(full.steps > 1 && full.objective < short.objective);
}
