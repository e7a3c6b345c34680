//! The error budget (issue 35): thermal cases and manufacturing tolerances
//! assembled on the flexible truss, nonlinear and linearised, on small-hex.

mod common;

use ringmesh::budget::{
    self, thermal_perturbation, BudgetDesign, BudgetRow, BudgetSettings, BudgetTable, Measured,
    PerturbedAssembly, PointKind, ToleranceModel,
};
use ringmesh::design::{self, DesignRun, DesignSettings};
use ringmesh::effects::ThermalExpansion;
use ringmesh::scene::{Thermal, ThermalCase, Tolerances};
use ringmesh::shard::Shard;
use ringmesh::verify::{Perturbation, Verification};
use ringmesh::Scene;

/// small-hex designed for its exact truss.
fn designed() -> (Scene, DesignRun) {
    let scene = common::scene("small-hex");
    let run = design::run(&scene, &DesignSettings::default(), &mut |_, _| {}).expect("designs");
    (scene, run)
}

fn core<'a>(scene: &'a Scene, run: &'a DesignRun) -> PerturbedAssembly<'a> {
    PerturbedAssembly::new(
        scene,
        &run.mesh,
        &run.network,
        &run.report.net,
        run.assembled.clone(),
    )
    .expect("the design assembles")
}

fn case(name: &str) -> ThermalCase {
    ThermalCase {
        name: name.into(),
        uniform_k: 0.0,
        gradient_k_per_m: 0.0,
        gradient_direction: [1.0, 0.0],
        front_k: 0.0,
        rear_k: 0.0,
    }
}

fn effect(scene: &Scene, cables: f64, tubes: f64, cases: Vec<ThermalCase>) -> ThermalExpansion {
    let mut scene = scene.clone();
    scene.effects.thermal = Some(Thermal {
        cable_expansion_per_k: cables,
        tie_expansion_per_k: None,
        tube_expansion_per_k: tubes,
        cases,
    });
    ThermalExpansion::of(&scene).expect("asked for")
}

fn thermal(
    core: &PerturbedAssembly<'_>,
    run: &DesignRun,
    e: &ThermalExpansion,
    c: &ThermalCase,
) -> Perturbation {
    let _ = core;
    thermal_perturbation(e, c, &run.mesh, &run.network, &run.report.net.nodes_xyz_m)
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn uniform_temperature_with_one_coefficient_scales_the_dish() {
    let (scene, run) = designed();
    let core = core(&scene, &run);
    let (alpha, dt) = (1e-5, 50.0);
    let s = 1.0 + alpha * dt;
    let mut c = case("uniform");
    c.uniform_k = dt;
    let e = effect(&scene, alpha, alpha, vec![c.clone()]);
    let p = thermal(&core, &run, &e, &c);
    let tangent = core.linearise().expect("factored");
    let built: Verification = core.nonlinear(&tangent, &p).expect("assembles");
    let nominal = &core.nominal.verification;
    assert!(built.slack_cables.is_empty());
    // The whole net (and its attachments) is the design as built scaled by
    // s: every node's distance to four anchors that pin a solid (two top
    // hinges, a bottom hinge, the centre) scales by s.
    let fixed = &run.network.fixed;
    let n = scene.truss.bays;
    let anchors = [fixed[0], fixed[2], fixed[n + 1], 0];
    let mut worst = 0.0f64;
    for i in 0..run.network.n_nodes() {
        for &a in &anchors {
            let d0 = distance(nominal.nodes_xyz_m[i], nominal.nodes_xyz_m[a]);
            let d = distance(built.nodes_xyz_m[i], built.nodes_xyz_m[a]);
            worst = worst.max((d - s * d0).abs() / (s * d0).max(1.0));
        }
    }
    assert!(worst < 1e-9, "not a scaled dish: relative misfit {worst:e}");
    // Tensions scale with the cables' section, s².
    for (t, t0) in built.tensions_n.iter().zip(&nominal.tensions_n) {
        assert!(
            (t - s * s * t0).abs() <= 1e-9 * t0,
            "tension {t} against {t0} × s²"
        );
    }
    // Refocusing removes it: best-fit RMS ≈ 0, focal length F s.
    let m = core.change(&built).expect("measured");
    let f = scene.reflector.focal_length_m;
    assert!(m.best_fit_mm < 1e-6, "best-fit RMS {} mm", m.best_fit_mm);
    assert!(
        m.raw_mm > 1e-2,
        "the raw change {} mm is not seen",
        m.raw_mm
    );
    assert!(
        (m.focal_length_m - f * s).abs() < 1e-9 * f,
        "fitted focal length {} against {}",
        m.focal_length_m,
        f * s
    );
}

/// Best-fit RMS of case `c` scaled by `h`, nonlinear and linearised.
fn at(
    core: &PerturbedAssembly<'_>,
    run: &DesignRun,
    e: &ThermalExpansion,
    c: &ThermalCase,
    h: f64,
) -> (Measured, Measured) {
    let mut c = c.clone();
    c.uniform_k *= h;
    let p = thermal(core, run, e, &c);
    let tangent = core.linearise().expect("factored");
    let nl = core
        .change(&core.nonlinear(&tangent, &p).expect("assembles"))
        .expect("measured");
    let lin = core
        .change(&core.linear(&tangent, &p).expect("solves"))
        .expect("measured");
    (nl, lin)
}

#[test]
fn unequal_coefficients_distort_linearly_and_the_linearised_slope_is_the_nonlinear_one() {
    let (scene, run) = designed();
    let core = core(&scene, &run);
    // Aramid-like cables against carbon tubes.
    let mut c = case("uniform");
    c.uniform_k = 1.0;
    let e = effect(&scene, -4e-6, 1e-6, vec![c.clone()]);
    let h = 0.5;
    let (nl1, lin1) = at(&core, &run, &e, &c, h);
    let (nl2, _) = at(&core, &run, &e, &c, 2.0 * h);
    assert!(
        nl1.best_fit_mm > 1e-5,
        "no distortion: {} mm",
        nl1.best_fit_mm
    );
    // Linear growth: RMS(2h) ≈ 2 RMS(h).
    let ratio = nl2.best_fit_mm / nl1.best_fit_mm;
    assert!((ratio - 2.0).abs() < 2e-2, "RMS(2h)/RMS(h) = {ratio}");
    // The slope at 0 by Richardson's finite difference of the nonlinear
    // assembly (RMS = c h + d h²: c = (4 RMS(h) − RMS(2h))/(2h)) against
    // the linearised estimate's.
    let slope = (4.0 * nl1.best_fit_mm - nl2.best_fit_mm) / (2.0 * h);
    let linear = lin1.best_fit_mm / h;
    assert!(
        (slope - linear).abs() < 1e-3 * linear,
        "finite-difference slope {slope:e} mm/K, linearised {linear:e} mm/K"
    );
}

fn tolerances(sigma_m: f64, ea: f64) -> Tolerances {
    Tolerances {
        cable_length_sigma_m: sigma_m,
        tie_length_sigma_m: sigma_m,
        rod_length_sigma_m: sigma_m,
        cable_stiffness_sigma: ea,
        hinge_position_sigma_m: sigma_m,
        samples: None,
        seed: None,
    }
}

/// The tolerance model `t` of the design `run` of `scene`.
fn tolerance_model(scene: &Scene, run: &DesignRun, t: &Tolerances) -> ToleranceModel {
    ToleranceModel::new(t, &run.mesh, &run.network, &run.report.net, &scene.cables)
}

/// Rows of `n` samples of `t` (seed 7), nonlinear and linearised.
fn samples(
    core: &PerturbedAssembly<'_>,
    scene: &Scene,
    run: &DesignRun,
    t: &Tolerances,
    n: usize,
) -> Vec<BudgetRow> {
    let model = tolerance_model(scene, run, t);
    let tangent = core.linearise().expect("factored");
    (0..n)
        .map(|k| {
            let p = model.sample(7, k);
            BudgetRow {
                kind: PointKind::Sample,
                name: format!("sample {k}"),
                nonlinear: core
                    .nonlinear(&tangent, &p)
                    .and_then(|v| core.change(&v))
                    .map_err(|e| e.to_string()),
                linear: Some(
                    core.linear(&tangent, &p)
                        .and_then(|v| core.change(&v))
                        .map_err(|e| e.to_string()),
                ),
            }
        })
        .collect()
}

#[test]
fn tolerances_at_zero_sigma_return_the_design_as_built() {
    let (scene, run) = designed();
    let core = core(&scene, &run);
    let model = tolerance_model(&scene, &run, &tolerances(0.0, 0.0));
    let tangent = core.linearise().expect("factored");
    let built = core
        .nonlinear(&tangent, &model.sample(3, 0))
        .expect("assembles");
    assert_eq!(built.rms_mm, core.nominal.verification.rms_mm);
    assert_eq!(
        built.rms_mm, run.report.verification.rms_mm,
        "the design's RMS as built"
    );
    let m = core.change(&built).expect("measured");
    assert!(
        m.raw_mm < 1e-9,
        "the change {} mm is not roundoff",
        m.raw_mm
    );
    assert!(m.slack_cables.is_empty());
}

/// The Monte Carlo's mean-square RMS and the linearised one's agree within
/// the sampling error at small σ (40 samples of 0.1 µm, on the same draws)
/// and part at large σ (20 µm: cables near slack), where the table shows
/// both.
#[test]
fn monte_carlo_and_linearised_agree_at_small_sigma_and_part_at_large() {
    let (scene, run) = designed();
    let core = core(&scene, &run);
    let n = 40;
    let gap = |sigma: f64| {
        let rows = samples(&core, &scene, &run, &tolerances(sigma, 20.0 * sigma), n);
        let table = BudgetTable::of(&rows, None);
        assert_eq!(
            table.samples, n,
            "σ = {sigma}: failed: {:?}",
            table.failed_samples
        );
        let t = table
            .terms
            .iter()
            .find(|t| t.term == "tolerances (rms)")
            .expect("a tolerance term");
        // The sampling error of a mean square over n samples: the
        // standard deviation of the squares over √n.
        let squares: Vec<f64> = rows
            .iter()
            .filter_map(|r| r.nonlinear.as_ref().ok().map(|m| m.best_fit_mm.powi(2)))
            .collect();
        let mean = squares.iter().sum::<f64>() / n as f64;
        let sd = (squares.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
        let se = sd / (n as f64).sqrt();
        let (ms, lin) = (
            t.best_fit_mm.powi(2),
            t.linear_best_fit_mm.expect("linearised").powi(2),
        );
        (ms, lin, se)
    };
    let (ms, lin, se) = gap(1e-7);
    assert!(ms > 0.0);
    assert!(
        (ms - lin).abs() < se,
        "small σ: mean square {ms:e} against {lin:e}, sampling error {se:e}"
    );
    assert!(
        (ms - lin).abs() < 1e-3 * ms,
        "small σ: the paired draws differ by {:e}",
        (ms - lin).abs() / ms
    );
    let (ms_large, lin_large, _) = gap(2e-5);
    let small = (ms - lin).abs() / ms;
    let large = (ms_large - lin_large).abs() / ms_large;
    eprintln!("relative gap of mean squares: σ = 0.1 µm {small:e}, σ = 20 µm {large:e}");
    assert!(
        large > 10.0 * small,
        "no gap at large σ: {large:e} against {small:e}"
    );
}

#[test]
fn chord_iterations_on_the_designs_tangent_find_newtons_equilibrium() {
    // The budget's nonlinear points are solved by chord iterations with
    // the design's factored tangent where they converge fast, by Newton
    // otherwise: both are the perturbed assembly's equilibrium, so where
    // the chord path converges it must agree with Newton's to the
    // solver's tolerance, nonlinearity included (σ large enough that the
    // linearised response is measurably off).
    let (scene, run) = designed();
    let core = core(&scene, &run);
    let tangent = core.linearise().expect("factored");
    let model = tolerance_model(&scene, &run, &tolerances(1e-5, 0.2));
    let mut chords = 0;
    for k in 0..6 {
        let p = model.sample(11, k);
        let newton = core.newton(&p).expect("Newton assembles");
        let linear = core.linear(&tangent, &p).expect("solves");
        let Some(chord) = core
            .chord(&tangent, &p)
            .expect("a perturbation of the right size")
        else {
            continue;
        };
        chords += 1;
        assert!(
            chord.newton_iterations >= 2,
            "one solve is the linear response"
        );
        let worst = |v: &Verification| {
            v.nodes_xyz_m
                .iter()
                .zip(&newton.nodes_xyz_m)
                .map(|(a, b)| distance(*a, *b))
                .fold(0.0, f64::max)
        };
        let shift = core
            .nominal
            .verification
            .nodes_xyz_m
            .iter()
            .zip(&newton.nodes_xyz_m)
            .map(|(a, b)| distance(*a, *b))
            .fold(0.0, f64::max);
        let (chord_gap, linear_gap) = (worst(&chord), worst(&linear));
        // Both stop at forces 1e-12 of the cables' and increments 1e-12 of
        // the frame's size: equal to that, with room for conditioning.
        let tolerance = 1e-10 * scene.reflector.aperture_diameter_m;
        assert!(
            chord_gap < tolerance,
            "sample {k}: chord and Newton differ by {chord_gap:e} m (shift {shift:e} m)"
        );
        assert!(
            linear_gap > 100.0 * chord_gap,
            "sample {k}: the linear response ({linear_gap:e} m off) is as close as the chord \
             iterations ({chord_gap:e} m): nothing nonlinear was solved"
        );
        // A tension is EA times a strain: the positions' tolerance, over a
        // cable's metre, times EA/T ≈ 1e4–1e5 here.
        for (t, n) in chord.tensions_n.iter().zip(&newton.tensions_n) {
            assert!(
                (t - n).abs() <= 1e-6 * n.abs().max(1.0),
                "tension {t} N against {n} N"
            );
        }
        assert_eq!(chord.slack_cables, newton.slack_cables, "sample {k}");
    }
    assert!(
        chords >= 4,
        "the chord iterations converged on {chords} of 6 samples"
    );
}

#[test]
fn the_conventional_designs_budget_starts_from_its_assembly_on_the_flexible_truss() {
    // `budget --conventional` builds the loop's iteration 0 — the design
    // for the undeformed truss — on the same flexible truss: its design
    // term is the conventional verification the design run reports, far
    // above the flexible design's, and its tolerance samples perturb that
    // assembly.
    let mut scene = common::scene("small-hex");
    let mut t = tolerances(1e-7, 0.0);
    t.samples = Some(3);
    scene.tolerances = Some(t);
    let design_term = |design: BudgetDesign| {
        let settings = BudgetSettings {
            design,
            ..BudgetSettings::of(&scene, None, None)
        };
        let run = budget::run(
            &scene,
            &DesignSettings::default(),
            &settings,
            Shard::WHOLE,
            &|_| {},
        )
        .expect("a budget");
        let row = |kind: PointKind| {
            run.rows
                .iter()
                .find(|(_, r)| r.kind == kind)
                .map(|(_, r)| r.nonlinear.clone().expect("measured"))
                .expect("a row")
        };
        let samples = run
            .rows
            .iter()
            .filter(|(_, r)| r.kind == PointKind::Sample && r.nonlinear.is_ok())
            .count();
        assert_eq!(samples, 3, "{design:?}: every sample assembles");
        row(PointKind::Design)
    };
    let (_, reference) = designed();
    let conventional = reference
        .report
        .conventional
        .as_ref()
        .expect("a flexible truss has a conventional design");
    let c = design_term(BudgetDesign::Conventional);
    assert!(
        (c.raw_mm - conventional.rms_mm).abs() <= 1e-9 * conventional.rms_mm,
        "conventional design term {} mm against its verification's {} mm",
        c.raw_mm,
        conventional.rms_mm
    );
    let f = design_term(BudgetDesign::Flexible);
    assert!(
        f.raw_mm < 1e-3 * c.raw_mm,
        "the flexible design ({} mm) does not remove the conventional one's error ({} mm)",
        f.raw_mm,
        c.raw_mm
    );
}

/// small-hex with thermal cases (one of which slackens cables: aramid-like
/// cables 100 K colder shrink by 5e-4 more than the tubes, beyond their
/// 7e-5 prestrain), tolerances and a frequency, written into `dir`.
fn budget_scene(dir: &std::path::Path, extra: &str) -> std::path::PathBuf {
    let text = std::fs::read_to_string(common::problem("small-hex.toml")).unwrap();
    let text = text.replace("name = \"small-hex\"", "name = \"small-hex-budget\"")
        + r#"
[surface]
frequency_ghz = 8.0

[tolerances]
cable_length_sigma_m = 5e-6
tie_length_sigma_m = 5e-6
rod_length_sigma_m = 2e-5
cable_stiffness_sigma = 0.02
hinge_position_sigma_m = 2e-5
samples = 7
seed = 3

[effects.thermal]
cable_expansion_per_k = -4e-6
tube_expansion_per_k = 1e-6

[[effects.thermal.cases]]
name = "cold soak"
uniform_k = -100.0

[[effects.thermal.cases]]
name = "sun on front"
front_k = 30.0
rear_k = -30.0
"# + extra;
    let path = dir.join("small-hex-budget.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn succeed(args: &[&str]) -> String {
    let run = common::ringmesh(args);
    assert!(
        run.status.success(),
        "ringmesh {args:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    String::from_utf8_lossy(&run.stdout).into_owned()
}

#[test]
fn sharded_and_merged_budget_equals_the_unsharded_one_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = budget_scene(tmp.path(), "");
    let scene = scene.to_str().unwrap();
    let (whole, shards, merged) = (
        tmp.path().join("whole"),
        tmp.path().join("shards"),
        tmp.path().join("merged"),
    );
    let printed = succeed(&["budget", scene, "-o", whole.to_str().unwrap()]);
    for i in 0..3 {
        let shard = format!("{i}/3");
        succeed(&[
            "budget",
            scene,
            "--shard",
            &shard,
            "-o",
            shards.to_str().unwrap(),
        ]);
    }
    succeed(&[
        "merge",
        shards.to_str().unwrap(),
        "-o",
        merged.to_str().unwrap(),
    ]);
    for file in ["budget.csv", "budget.json", "budget-samples.csv"] {
        let a = std::fs::read(whole.join(file)).unwrap();
        let b = std::fs::read(merged.join(file)).unwrap();
        assert!(
            a == b,
            "{file} differs between the unsharded and the merged run"
        );
    }
    // 2 + 2 cases + 7 samples points, every sample measured.
    let samples = std::fs::read_to_string(whole.join("budget-samples.csv")).unwrap();
    assert_eq!(samples.lines().count(), 1 + 11);
    // The cold soak slackens cables: the table, the JSON and the printout
    // name them, and the row counts them.
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(whole.join("budget.json")).unwrap()).unwrap();
    let slack = &json["table"]["thermal_slack_cables"];
    let cold = slack
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c[0] == "cold soak")
        .expect("the cold soak listed");
    let cables = cold[1].as_array().unwrap();
    assert!(!cables.is_empty(), "the cold soak slackens no cable");
    assert!(
        printed.contains(&format!(
            "thermal case cold soak: {} cables slack: ",
            cables.len()
        )),
        "{printed}"
    );
    let row = samples
        .lines()
        .find(|l| l.starts_with("thermal,cold soak,"))
        .unwrap();
    let cells: Vec<&str> = row.split(',').collect();
    assert_eq!(cells[7], cables.len().to_string());
    assert_eq!(cells[8].split(' ').count(), cables.len());
}

#[test]
fn a_bad_tolerance_is_refused_naming_its_key() {
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(budget_scene(tmp.path(), "")).unwrap();
    let bad = tmp.path().join("bad.toml");
    std::fs::write(
        &bad,
        text.replace(
            "cable_stiffness_sigma = 0.02",
            "cable_stiffness_sigma = 0.5",
        ),
    )
    .unwrap();
    let run = common::ringmesh(&[
        "budget",
        bad.to_str().unwrap(),
        "-o",
        tmp.path().join("out").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("tolerances.cable_stiffness_sigma"),
        "{stderr}"
    );
    assert!(!tmp.path().join("out").join("budget.csv").exists());
}

/// Thermal cases and tolerances cost a design nothing: the design of a
/// scene that has them builds no thermal effect and is the design of the
/// scene without them.
#[test]
fn a_design_ignores_the_budget_sections() {
    use ringmesh::effects::{self, EffectKind};
    let tmp = tempfile::tempdir().unwrap();
    let with = Scene::read(&budget_scene(tmp.path(), "")).expect("valid");
    let (plain, plain_run) = designed();
    assert!(plain.effects.thermal.is_none() && plain.tolerances.is_none());
    effects::reset_log();
    let run = design::run(&with, &DesignSettings::default(), &mut |_, _| {}).expect("designs");
    assert_eq!(
        effects::constructed().get(&EffectKind::ThermalExpansion),
        None
    );
    assert_eq!(run.report.net.tensions_n, plain_run.report.net.tensions_n);
    assert_eq!(
        run.report.verification.rms_mm,
        plain_run.report.verification.rms_mm
    );
}

#[test]
fn chord_iterations_through_slackening_cables_find_newtons_equilibrium() {
    // At σ = 0.3 mm the samples slacken cables: the chord iterations then
    // refactor a matrix in which slack cables keep 1 % of their stiffness
    // (`SLACK_ITERATION_RATIO`), not the tangent, until the slack cables
    // settle (`SETTLED_SLACK_CHANGE`). Its residual is exact, so
    // the equilibrium must still be Newton's from the load ramp: the same
    // positions to the solvers' tolerance and the same slack cables.
    let (scene, run) = designed();
    let core = core(&scene, &run);
    let tangent = core.linearise().expect("factored");
    let model = tolerance_model(&scene, &run, &tolerances(3e-4, 0.0));
    let mut slackened = 0;
    for k in 0..4 {
        let p = model.sample(11, k);
        let newton = core.newton(&p).expect("Newton assembles");
        let chord = core
            .chord(&tangent, &p)
            .expect("a perturbation of the right size")
            .unwrap_or_else(|| panic!("sample {k}: the chord iterations did not converge"));
        let gap = chord
            .nodes_xyz_m
            .iter()
            .zip(&newton.nodes_xyz_m)
            .map(|(a, b)| distance(*a, *b))
            .fold(0.0, f64::max);
        assert!(
            gap < 1e-10 * scene.reflector.aperture_diameter_m,
            "sample {k}: chord and Newton differ by {gap:e} m"
        );
        assert_eq!(chord.slack_cables, newton.slack_cables, "sample {k}");
        slackened += usize::from(!newton.slack_cables.is_empty());
    }
    assert!(slackened >= 3, "{slackened} of 4 samples slackened a cable");
}
