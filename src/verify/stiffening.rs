//! The continuation of an assembly from elastic to inextensible cables
//! ([`crate::effects::CableModel::Inextensible`], whose module says why):
//! the stiff assembly solved at once fails, so the elastic equilibrium is
//! continued in stages of ×10 stiffness, each from the last equilibrium.

use super::VerifyError;
use crate::effects::INEXTENSIBLE_STIFFENING;
use crate::mechanics::{ModelBuilder, StaticSettings, StaticSolution, StaticSolver};

/// Stiffening of each stage of the continuation from the elastic cables to
/// the inextensible ones.
const STAGE_STIFFENING: f64 = 10.0;

/// Continue `solution`, the elastic assembly's equilibrium (cables of axial
/// stiffness `ea_n` in `solver`'s model, in the order of `targets`), to
/// inextensible cables: the cables are stiffened ×[`STAGE_STIFFENING`] per
/// stage up to [`INEXTENSIBLE_STIFFENING`] × `ea_n`. Each stage starts from
/// the last equilibrium with every taut cable's unstressed length set so
/// that the stiffer cable carries the same tension (`ℓ/(1 + T/EA_k)`, a
/// slack one keeps its length), and ramps it to the stage's cut length
/// `ℓ_design/(1 + T_design/EA_k)` (`targets`: `[ℓ_design, T_design]` per
/// cable). Solving the stiff assembly at once fails: its Newton iterates
/// flip cables between taut and slack, a misfit of the design's boundary
/// tolerance (1e-6 m) being worth hundreds of newtons in a penalised cable.
///
/// `bare` is the assembly's truss and net points, without cables. Returns
/// the last stage's solver and solution and the Newton iterations and load
/// steps of all stages (the elastic one's included).
///
/// # Errors
/// An invalid stage model (named), or a stage without equilibrium.
pub(crate) fn stiffen(
    bare: &ModelBuilder,
    targets: &[[f64; 2]],
    ea_n: f64,
    mut solver: StaticSolver,
    mut solution: StaticSolution,
    settings: &StaticSettings,
) -> Result<(StaticSolver, StaticSolution, usize, usize), VerifyError> {
    let mut newton_iterations = solution.newton_iterations;
    let mut load_steps = solution.steps.len();
    let mut stiffening = 1.0;
    while stiffening < INEXTENSIBLE_STIFFENING * (1.0 - 1e-12) {
        stiffening = (stiffening * STAGE_STIFFENING).min(INEXTENSIBLE_STIFFENING);
        let ea = stiffening * ea_n;
        let frames = &solution.state.frames;
        let mut b = bare.clone();
        for (cable, &[length_m, tension_n]) in solver.model().cables().iter().zip(targets) {
            let [a, c] = cable.nodes();
            let now = cable.state(&frames[a].position_m, &frames[c].position_m, 1.0);
            let start = if now.slack || now.tension_n <= 0.0 {
                cable.rest_length_m(1.0)
            } else {
                now.length_m / (1.0 + now.tension_n / ea)
            };
            b.add_cable(a, c, ea, [start, length_m / (1.0 + tension_n / ea)]);
        }
        let next = StaticSolver::new(b.build()?)?;
        let mut start = solution.state.clone();
        start.rescale_multipliers(solver.constraint_scale() / next.constraint_scale());
        let s = next.solve_from(start, 0.0, settings)?;
        newton_iterations += s.newton_iterations;
        load_steps += s.steps.len();
        if !s.converged() {
            return Err(VerifyError::NoInextensibleEquilibrium {
                stiffening,
                termination: s.termination,
                load_factor: s.load_factor,
            });
        }
        (solver, solution) = (next, s);
    }
    Ok((solver, solution, newton_iterations, load_steps))
}
