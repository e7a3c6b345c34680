//! The gradient solver's settings, plain data with defaults and one
//! `validate()`: the objective's weights, L-BFGS's budget and tests
//! ([`Gradient`]), and the exact finish's trust region ([`FinishSettings`]).
//! The solve itself is `mod.rs`'s; every other file of the solver reads
//! these, and this file reads none of them.

use serde::{Deserialize, Serialize};

use crate::uniformity::UniformityError;

/// Adjoint-gradient L-BFGS on the free geometry (see the module documentation).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Gradient {
    /// Weight `w` of the ratio surrogate `ln(Tmax/Tmin)` against the surface
    /// term `(RMS/ε)²`: larger buys a lower `Tmax/Tmin` with a larger surface
    /// error (the design-front knob).
    pub weight: f64,
    /// Surface tolerance `ε`, m: the unit of the surface error and of the
    /// layout drift.
    pub surface_tolerance_m: f64,
    /// Weight of the layout drift against the surface error (0: free layout).
    pub layout_weight: f64,
    /// Sharpness `β` of the soft max/min of `ln T`: larger follows `Tmax/Tmin`
    /// more closely and makes the objective stiffer.
    pub sharpness: f64,
    /// Sharpness of the first L-BFGS run; it grows ×3 per restart up to
    /// `sharpness` (continuation: smooth first, sharp at the end).
    pub initial_sharpness: f64,
    /// Weight `κ` of the pretension-level term `(ln(T̄₀/t₀)/10⁻³)²`.
    pub level_weight: f64,
    /// Weight `ν` of the bound barrier (its unit: 1 % beyond a bound).
    pub barrier_weight: f64,
    /// Number of correction pairs L-BFGS keeps.
    pub memory: usize,
    /// Most L-BFGS iterations in all.
    pub max_iterations: usize,
    /// Most iterations of one L-BFGS run; then the preconditioner is
    /// re-linearised around the current point, the sharpness raised, and L-BFGS
    /// restarted.
    pub restart_iterations: usize,
    /// Converged (at the final sharpness) when the stationarity
    /// `‖dJ/dθ‖∞ / J` falls to this: scale-free, and independent of the start.
    pub gradient_tolerance: f64,
    /// Stop (at the final sharpness) when a whole L-BFGS run lowers `J` by no
    /// more than `cost_tolerance · |J|`: `Converged` if the stationarity
    /// holds, `Stalled` if it does not.
    pub cost_tolerance: f64,
    /// Precondition L-BFGS (see the module documentation); `false` runs it on `θ`.
    pub precondition: bool,
    /// Start from the uniform-tension guess projected onto equilibrium at the
    /// design geometry; `false` starts from the network's `q`.
    pub project_start: bool,
    /// Start from the fixed-geometry optimum (`lp`'s design) where `lp`
    /// applies (one set, no loads), before any other start.
    pub optimum_start: bool,
    /// After L-BFGS, sequential quadratic programs on the exact objective,
    /// `ln(Tmax/Tmin)` in place of its soft form, to its stationarity (see
    /// the `finish` module): the true minimiser for the weight, in a few programs
    /// whatever the size, each far dearer than an L-BFGS iteration. From a
    /// start near the optimum (`lp`'s, a neighbour's) or with
    /// `max_iterations = 0` the programs start there, without L-BFGS. On by
    /// default; off, the solver `gradient-smooth` ([`Gradient::smooth`]).
    pub exact_finish: bool,
    /// The exact finish's trust region and stopping test.
    pub finish: FinishSettings,
}

impl Default for Gradient {
    fn default() -> Self {
        Gradient {
            weight: 1.0,
            surface_tolerance_m: 1e-3,
            layout_weight: 1.0,
            sharpness: 1000.0,
            initial_sharpness: 10.0,
            level_weight: 1.0,
            barrier_weight: 1.0,
            memory: 20,
            max_iterations: 5000,
            restart_iterations: 300,
            gradient_tolerance: 1e-3,
            cost_tolerance: 1e-12,
            precondition: true,
            project_start: true,
            optimum_start: true,
            exact_finish: true,
            finish: FinishSettings::default(),
        }
    }
}

impl Gradient {
    /// The smoothed solve alone (the solver `gradient-smooth`): L-BFGS on the
    /// soft max/min, without the exact finish.
    pub fn smooth() -> Self {
        Gradient {
            exact_finish: false,
            ..Gradient::default()
        }
    }

    /// Checks the settings, the finish's among them.
    ///
    /// # Errors
    /// [`UniformityError::Setting`] naming the first field out of its range
    /// (`finish.…` for the finish's).
    pub fn validate(&self) -> Result<(), UniformityError> {
        let bad = |name: &'static str, value: f64, range: &'static str| {
            Err(UniformityError::Setting {
                solver: "gradient",
                name,
                value,
                range,
            })
        };
        let non_negative = [
            ("weight", self.weight),
            ("layout_weight", self.layout_weight),
            ("barrier_weight", self.barrier_weight),
            ("gradient_tolerance", self.gradient_tolerance),
            ("cost_tolerance", self.cost_tolerance),
        ];
        for (what, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return bad(what, v, "finite and ≥ 0");
            }
        }
        for (what, v) in [
            ("surface_tolerance_m", self.surface_tolerance_m),
            ("sharpness", self.sharpness),
            ("initial_sharpness", self.initial_sharpness),
            ("level_weight", self.level_weight),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(what, v, "finite and > 0");
            }
        }
        if self.memory == 0 {
            return bad("memory", 0.0, "≥ 1");
        }
        if self.restart_iterations == 0 {
            return bad("restart_iterations", 0.0, "≥ 1");
        }
        self.finish.validate()
    }
}

/// The exact finish's trust region and stopping test (see the `finish`
/// module's documentation): plain data, the defaults those the benches'
/// nets were measured with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FinishSettings {
    /// The finish has converged when the model's predicted decrease is at
    /// most this times `J_exact`.
    pub tolerance: f64,
    /// Most steps of the finish: a quadratic program each, two where a step
    /// is corrected ([`Self::second_order_correction`]).
    pub max_steps: usize,
    /// The first trust radius, relative change of `q`.
    pub first_radius: f64,
    /// The largest trust radius (at 0.5, `q` stays above half its value at
    /// a step). At 0.9 the 428-node net took 19 programs from the
    /// uniform-tension guess (against 11).
    pub max_radius: f64,
    /// A cable outside the sets may fall by this many times the trust
    /// radius a step, to at most `max_fall`: the optimum slackens some (the
    /// ties of the tied nets), the model follows them well (they carry no
    /// ratio term), and halving them at most a step took the 38 876-node net
    /// 15 programs, the last nine spent so; with a reach of 4, 6.
    pub outside_reach: f64,
    /// The largest fall of a cable outside the sets in one step, relative.
    pub max_fall: f64,
    /// Below this radius a rejected step ends the finish.
    pub min_radius: f64,
    /// A step whose decrease falls short of three quarters of the predicted
    /// one is solved again with its set rows shifted by what the
    /// linearisation of `ln T_k` missed at the trial (a second-order
    /// correction; the better of the two trials is judged). Without it the
    /// finish crawled on the jittered sector grid of issue 38
    /// (`tests/common/nets.rs`): the model's `ln(Tmax/Tmin)` was 1e-3 off at
    /// a radius of 0.05 (the tensions' nonlinearity in `q`), steps were
    /// refused until the radius sat near 1e-2, and 50 programs ended in
    /// `MaxIterations` at 463, 1 021 and 2 431 free nodes (3.0, 12.0,
    /// 45.2 s); with it 7 + 5, 7 + 6 and 8 + 7 programs (steps +
    /// corrections) converge (0.8, 3.6, 15.8 s), to a `J` lower by 3e-6 …
    /// 3e-5 relative (`tests/ipm_families.rs`, `finish_table`). The
    /// hexagonal and sector nets, whose steps the model predicts well, are
    /// unchanged.
    pub second_order_correction: bool,
}

impl Default for FinishSettings {
    fn default() -> Self {
        FinishSettings {
            tolerance: 1e-9,
            max_steps: 50,
            first_radius: 0.05,
            max_radius: 0.5,
            outside_reach: 4.0,
            max_fall: 0.9,
            min_radius: 1e-9,
            second_order_correction: true,
        }
    }
}

impl FinishSettings {
    /// Checks the values.
    ///
    /// # Errors
    /// [`UniformityError::Setting`] naming the first field (`finish.…`) out
    /// of its range: a negative or non-finite tolerance, no step, radii
    /// outside `0 < min_radius ≤ first_radius ≤ max_radius < 1`, a reach that
    /// is not positive, a fall outside `(0, 1)`.
    pub fn validate(&self) -> Result<(), UniformityError> {
        let bad = |name: &'static str, value: f64, range: &'static str| {
            Err(UniformityError::Setting {
                solver: "gradient",
                name,
                value,
                range,
            })
        };
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return bad("finish.tolerance", self.tolerance, "finite and ≥ 0");
        }
        if self.max_steps == 0 {
            return bad("finish.max_steps", 0.0, "≥ 1");
        }
        if !(self.max_radius > 0.0 && self.max_radius < 1.0) {
            return bad("finish.max_radius", self.max_radius, "in (0, 1)");
        }
        if !(self.first_radius > 0.0 && self.first_radius <= self.max_radius) {
            return bad(
                "finish.first_radius",
                self.first_radius,
                "in (0, finish.max_radius]",
            );
        }
        if !(self.min_radius > 0.0 && self.min_radius <= self.first_radius) {
            return bad(
                "finish.min_radius",
                self.min_radius,
                "in (0, finish.first_radius]",
            );
        }
        if !(self.outside_reach.is_finite() && self.outside_reach > 0.0) {
            return bad("finish.outside_reach", self.outside_reach, "finite and > 0");
        }
        if !(self.max_fall > 0.0 && self.max_fall < 1.0) {
            return bad("finish.max_fall", self.max_fall, "in (0, 1)");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each out-of-range finish setting is refused by its dotted name, and
    /// through the solver's own check.
    #[test]
    fn finish_settings_out_of_range_are_named() {
        assert!(Gradient::default().validate().is_ok());
        let cases = [
            (
                FinishSettings {
                    tolerance: f64::NAN,
                    ..FinishSettings::default()
                },
                "finish.tolerance",
            ),
            (
                FinishSettings {
                    max_steps: 0,
                    ..FinishSettings::default()
                },
                "finish.max_steps",
            ),
            (
                FinishSettings {
                    max_radius: 1.0,
                    ..FinishSettings::default()
                },
                "finish.max_radius",
            ),
            (
                FinishSettings {
                    first_radius: 0.6,
                    ..FinishSettings::default()
                },
                "finish.first_radius",
            ),
            (
                FinishSettings {
                    min_radius: 0.0,
                    ..FinishSettings::default()
                },
                "finish.min_radius",
            ),
            (
                FinishSettings {
                    outside_reach: -1.0,
                    ..FinishSettings::default()
                },
                "finish.outside_reach",
            ),
            (
                FinishSettings {
                    max_fall: 1.0,
                    ..FinishSettings::default()
                },
                "finish.max_fall",
            ),
        ];
        for (finish, field) in cases {
            let gradient = Gradient {
                finish,
                ..Gradient::default()
            };
            match gradient.validate() {
                Err(UniformityError::Setting { name, .. }) => assert_eq!(name, field),
                other => panic!("{field}: {other:?}"),
            }
        }
    }
}
