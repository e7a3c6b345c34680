//! The paper's benchmark (§3.4, Tables 1–2): a cantilever of length 10 rolled
//! up by a tip moment, against the closed form `θ = ML/EI`:
//! tip axial displacement `L − L sin θ/θ`, vertical `L(1 − cos θ)/θ`.

use nalgebra::Vector3;
use serde::Serialize;

use crate::mechanics::{
    ElementKind, MechanicsError, ModelBuilder, RodSpec, Section, StaticSettings, StaticSolver,
};

/// Length of the cantilever (paper §3.4).
pub const LENGTH_M: f64 = 10.0;
/// Bending stiffness EI, N·m² (the classical roll-up benchmark's; only `ML/EI` matters).
pub const BENDING_NM2: f64 = 100.0;
/// The loads of the table, as `ML/(πEI)`: the paper's 0.2…1.0 and on to the full circle.
pub const M_RATIOS: [f64; 7] = [0.2, 0.4, 0.6, 0.8, 1.0, 1.5, 2.0];

/// The paper's result (Tables 1–2, 10 elements) where it gives one: `(m_ratio, axial, vertical)`.
pub const PAPER: [(f64, f64, f64); 1] = [(1.0, 9.96377, 6.54480)];

/// The section: EA = GA = 10⁴ N, GJ = EI = 100 N·m².
pub fn section() -> Section {
    Section {
        axial_n: 1e4,
        shear_n: [1e4, 1e4],
        torsion_nm2: BENDING_NM2,
        bending_nm2: [BENDING_NM2, BENDING_NM2],
    }
}

/// The closed-form tip displacement `(axial, vertical)` at `ML/(πEI) = m_ratio`.
pub fn analytic(m_ratio: f64) -> (f64, f64) {
    let theta = m_ratio * std::f64::consts::PI;
    if theta == 0.0 {
        return (0.0, 0.0);
    }
    (
        LENGTH_M - LENGTH_M * theta.sin() / theta,
        LENGTH_M * (1.0 - theta.cos()) / theta,
    )
}

/// One row of the table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CantileverRow {
    /// `ML/(πEI)`.
    pub m_ratio: f64,
    /// Computed tip axial displacement, m.
    pub axial_m: f64,
    /// Computed tip vertical displacement, m.
    pub vertical_m: f64,
    /// Closed form, m.
    pub analytic_axial_m: f64,
    /// Closed form, m.
    pub analytic_vertical_m: f64,
    /// Distance of the tip from the closed form over the closed form's tip displacement.
    pub relative_error: f64,
    /// Equilibrium reached at the full moment.
    pub converged: bool,
    /// Newton iterations, all steps.
    pub newton_iterations: usize,
    /// Converged load steps.
    pub load_steps: usize,
    /// Wall time, s.
    pub time_s: f64,
}

/// The cantilever of `elements` elements of `kind`, clamped at the origin,
/// axis along x, tip moment `M` about z (bending in the x–y plane).
pub fn model(
    elements: usize,
    kind: ElementKind,
    moment_nm: f64,
) -> Result<StaticSolver, MechanicsError> {
    let mut b = ModelBuilder::new();
    let rod = b.add_rod(
        Vector3::zeros(),
        Vector3::new(LENGTH_M, 0.0, 0.0),
        Vector3::y(),
        &RodSpec {
            section: section(),
            elements,
            kind,
        },
    );
    b.fix(rod.start(), [true; 6]);
    b.add_load(
        rod.end(),
        Vector3::zeros(),
        Vector3::new(0.0, 0.0, moment_nm),
    );
    StaticSolver::new(b.build()?)
}

/// Solve one load of the table.
pub fn row(
    elements: usize,
    kind: ElementKind,
    m_ratio: f64,
    settings: &StaticSettings,
) -> Result<CantileverRow, MechanicsError> {
    let moment = m_ratio * std::f64::consts::PI * BENDING_NM2 / LENGTH_M;
    let solver = model(elements, kind, moment)?;
    let solution = solver.solve(settings)?;
    let tip = solution
        .state
        .frames
        .last()
        .expect("a rod has nodes")
        .position_m;
    let (axial_m, vertical_m) = (LENGTH_M - tip.x, tip.y);
    let (ax, ve) = analytic(m_ratio);
    let relative_error =
        ((axial_m - ax).powi(2) + (vertical_m - ve).powi(2)).sqrt() / (ax * ax + ve * ve).sqrt();
    Ok(CantileverRow {
        m_ratio,
        axial_m,
        vertical_m,
        analytic_axial_m: ax,
        analytic_vertical_m: ve,
        relative_error,
        converged: solution.converged(),
        newton_iterations: solution.newton_iterations,
        load_steps: solution.steps.len(),
        time_s: solution.time_s,
    })
}

/// The whole table (every load of [`M_RATIOS`]).
pub fn table(elements: usize, kind: ElementKind) -> Result<Vec<CantileverRow>, MechanicsError> {
    let settings = StaticSettings::default();
    M_RATIOS
        .iter()
        .map(|&m| row(elements, kind, m, &settings))
        .collect()
}
