//! Tension-uniformity solvers (paper eq. 5, DESIGN §4): one problem, one
//! [`UniformitySolver`] trait, one file per strategy, all returning a [`Design`].
//!
//! | solver | formulation | knob |
//! |---|---|---|
//! | [`Lp`] | one LP `min s`, `1 ≤ T_k ≤ s`, `A q = 0`, rescaled (homogeneous, one set) | — |
//! | [`Bisection`] | ratio bisection of LP feasibility, or SOCP with `‖A q − p‖ ≤ ε` | ε |
//! | [`Gradient`] | free geometry, adjoint gradient, L-BFGS, then sequential QPs on the exact ratio (`gradient-smooth`: L-BFGS alone) | weight of the ratio term |
//! | [`LeastSquares`] | `min ‖L q − T̄‖²` s.t. `A q = p`, or Tikhonov `λ` | λ |

mod bisection;
mod block_pattern;
mod conic;
mod design;
mod front;
mod gradient;
mod ipm;
mod least_squares;
mod lp;
mod ordering;
mod plan;
mod problem;
mod selection;

/// How a solver stopped: the crate's shared vocabulary ([`crate::status`]).
pub use crate::status::Termination;
pub use bisection::Bisection;
pub use design::{Design, Route, SlackNodes, TensionSpread};
pub use front::{
    design_front, design_front_chains, front_chains, front_jobs, knob_values, FrontPoint, KnobRange,
};
pub use gradient::{FinishSettings, Gradient, History};
pub use ipm::WarmStart;
pub use least_squares::LeastSquares;
pub use lp::Lp;
pub use problem::{SurfaceTarget, UniformityProblem, UniformitySet};
pub use selection::most_uniform;

use crate::fdm::FdmError;

/// A uniformity problem or solve that cannot go on.
#[derive(Debug, thiserror::Error)]
pub enum UniformityError {
    /// An input of the problem is ill-posed (an empty set, a bad bound, a
    /// zero-length cable, a count that does not match, …).
    #[error("invalid uniformity problem: {item}: {reason}")]
    Invalid {
        /// The input: ``uniformity set `front` ``, `cable 3 (nodes [3, 1])`,
        /// `positions`, `node 7`, …
        item: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A solver setting is out of its range.
    #[error("invalid `{solver}` setting: {name} = {value} must be {range}")]
    Setting {
        /// The solver.
        solver: &'static str,
        /// The setting (its field name).
        name: &'static str,
        /// Its value.
        value: f64,
        /// The range it must be in.
        range: &'static str,
    },
    /// The solver cannot treat this kind of problem (e.g. `lp` with loads).
    #[error("the `{solver}` solver cannot solve this problem: {reason}")]
    Unsupported {
        /// The solver.
        solver: &'static str,
        /// Why, and which solver can.
        reason: String,
    },
    /// Positive equilibria exist, but none with a ratio below the solver's
    /// search limit.
    #[error(
        "no design with a ratio below {max_ratio} exists (positive equilibria exist, but only \
         more uneven ones)"
    )]
    RatioLimit {
        /// The largest ratio the solver tries.
        max_ratio: f64,
    },
    /// A solver proved the problem infeasible where the caller needs a design
    /// ([`Design::feasible`]): solvers themselves return such a design with
    /// [`Termination::Infeasible`], not this error.
    #[error("the `{solver}` solver found no feasible design: {}", .warnings.join("; "))]
    Infeasible {
        /// The solver.
        solver: String,
        /// The nodes whose cables can only be slack, when the prescribed
        /// geometry is the cause.
        slack_nodes: Option<SlackNodes>,
        /// The design's warnings, the reason among them.
        warnings: Vec<String>,
    },
    /// A solver setting given by name that the solver does not have, or
    /// whose value is not of its type.
    #[error("invalid `{solver}` setting `{name}`: {reason}")]
    SettingValue {
        /// The solver.
        solver: &'static str,
        /// The setting as given.
        name: String,
        /// What is wrong with it (the settings it has, for an unknown one).
        reason: String,
    },
    /// The inner solver failed numerically (its status, verbatim).
    #[error("the `{solver}` solver failed: {status}")]
    SolverFailed {
        /// The solver.
        solver: &'static str,
        /// The inner solver's status.
        status: String,
    },
    /// A design whose numbers are not finite.
    #[error(
        "the `{solver}` design's {what} is {value}: force densities up to {max_q:e} N/m \
         overflow double precision on this geometry"
    )]
    NonFinite {
        /// The solver.
        solver: String,
        /// The quantity.
        what: &'static str,
        /// Its value.
        value: f64,
        /// The largest force density.
        max_q: f64,
    },
    /// A forward solve failed.
    #[error(transparent)]
    Fdm(#[from] FdmError),
}

impl UniformityError {
    /// An ill-posed input: `item` names it, `reason` says what is wrong.
    pub(crate) fn invalid(item: impl Into<String>, reason: impl Into<String>) -> Self {
        UniformityError::Invalid {
            item: item.into(),
            reason: reason.into(),
        }
    }

    /// True when the cause is the caller's input.
    pub fn is_bad_input(&self) -> bool {
        match self {
            UniformityError::Invalid { .. }
            | UniformityError::Setting { .. }
            | UniformityError::SettingValue { .. }
            | UniformityError::Unsupported { .. }
            | UniformityError::RatioLimit { .. }
            | UniformityError::Infeasible { .. } => true,
            UniformityError::SolverFailed { .. } | UniformityError::NonFinite { .. } => false,
            UniformityError::Fdm(e) => e.is_bad_input(),
        }
    }
}

/// A strategy that turns a [`UniformityProblem`] into a [`Design`].
pub trait UniformitySolver: Send + Sync {
    /// The name used on the command line and in reports.
    fn name(&self) -> &'static str;
    /// The knob's name and the range the design front sweeps for `problem`
    /// (see [`knob_values`]), or `None` for a solver without a knob (one
    /// point).
    fn knob_range(&self, _problem: &UniformityProblem) -> Option<KnobRange> {
        None
    }
    /// Solves the problem. A well-posed problem without a feasible `q` is a
    /// design with [`Termination::Infeasible`] (the reason in its warnings),
    /// not an error; an error is invalid input or a failure.
    fn solve(&self, problem: &UniformityProblem) -> Result<Design, UniformityError>;
    /// Solves from `start`, the design of a neighbouring problem (the
    /// previous outer iteration's boundary, the neighbouring knob of a front):
    /// an iterative solver begins there, so that its answer moves smoothly
    /// with the problem; the others solve afresh.
    fn solve_from(
        &self,
        problem: &UniformityProblem,
        _start: &Design,
    ) -> Result<Design, UniformityError> {
        self.solve(problem)
    }
    /// True when the design is a unique, continuous function of the problem;
    /// false for min-ratio programs, whose optimum is a face (see
    /// [`most_uniform`] for a unique point of it).
    fn unique_design(&self) -> bool {
        true
    }
}

/// The solvers, by name (the command line's choice). What each does is
/// [`SolverKind::description`]: the one text `--help` shows and
/// `docs/solvers.md` quotes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SolverKind {
    /// Ratio bisection over conic feasibility programs (clarabel).
    Bisection,
    /// One LP: the single-set homogeneous baseline.
    Lp,
    /// Free geometry, finished by quadratic programs on the exact ratio.
    Gradient,
    /// Free geometry by L-BFGS on a smoothed ratio alone.
    GradientSmooth,
    /// Constrained or Tikhonov least squares (faer).
    LeastSquares,
}

impl clap::ValueEnum for SolverKind {
    fn value_variants<'a>() -> &'a [Self] {
        &SolverKind::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.description()))
    }
}

impl SolverKind {
    /// Every solver, in the order `--help` lists them.
    pub const ALL: [SolverKind; 5] = [
        SolverKind::Bisection,
        SolverKind::Lp,
        SolverKind::Gradient,
        SolverKind::GradientSmooth,
        SolverKind::LeastSquares,
    ];

    /// The name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Bisection => "bisection",
            SolverKind::Lp => "lp",
            SolverKind::Gradient => "gradient",
            SolverKind::GradientSmooth => "gradient-smooth",
            SolverKind::LeastSquares => "least-squares",
        }
    }

    /// The solver's accuracy knob as a reader names it, with its unit
    /// (`"ε, N"`: bisection's equilibrium tolerance; `"w"`: gradient's
    /// dimensionless weight; `"λ"`: least squares' Tikhonov weight); `None`
    /// for `lp`, which has none.
    pub fn knob_label(self) -> Option<&'static str> {
        match self {
            SolverKind::Bisection => Some("equilibrium tolerance ε (N)"),
            SolverKind::Lp => None,
            SolverKind::Gradient | SolverKind::GradientSmooth => Some("weight w"),
            SolverKind::LeastSquares => Some("Tikhonov weight λ"),
        }
    }

    /// A knob value as printed, `value` the number as written (`ε = 0.7 N`,
    /// `w = 100`, `λ = 1e-6`).
    pub fn knob_text(self, v: &str) -> String {
        match self {
            SolverKind::Bisection => format!("ε = {v} N"),
            SolverKind::Lp => format!("knob {v}"),
            SolverKind::Gradient | SolverKind::GradientSmooth => format!("w = {v}"),
            SolverKind::LeastSquares => format!("λ = {v}"),
        }
    }

    /// What the solver does, in one paragraph: the text of `--help` and of
    /// `docs/solvers.md` (a test checks the document quotes it verbatim).
    pub fn description(self) -> &'static str {
        match self {
            SolverKind::Bisection => {
                "Fixed geometry. Bisection on the ratio Tmax/Tmin: each trial ratio is one \
                 elastic feasibility program (an LP, or an SOCP when the equilibrium \
                 tolerance epsilon_n > 0) solved by clarabel. Handles several uniformity \
                 groups, nodal loads (gravity) and the bound [q]; the default where lp does \
                 not apply. Knob: epsilon_n (N), the equilibrium residual allowed."
            }
            SolverKind::Lp => {
                "Fixed geometry. One LP, min Tmax/Tmin, for one uniformity group without \
                 nodal loads, rescaled to the target mean tension. A tied net's plan problem \
                 is solved by the crate's own structured interior point (src/uniformity/ipm/); \
                 should it stop short, or on any other network, clarabel solves it. The \
                 default where it applies. No knob."
            }
            SolverKind::Gradient => {
                "Free geometry: minimises (RMS/1 mm)² + w·ln(Tmax/Tmin) (plus layout, level \
                 and bound terms) by its adjoint gradient. From lp's optimum (where lp \
                 applies) or a neighbouring design it goes straight to sequential quadratic \
                 programs on the exact ratio, each solved by an interior point on the net's \
                 structure; from a far start argmin's L-BFGS on a smoothed ratio first \
                 brings it near. Knob: the weight w (dimensionless)."
            }
            SolverKind::GradientSmooth => {
                "Free geometry: gradient without its finish, argmin's L-BFGS on a smoothed \
                 (log-sum-exp) ratio alone, from the same starts; its minimiser sits slightly \
                 off the exact objective's. Knob: the weight w (dimensionless)."
            }
            SolverKind::LeastSquares => {
                "Fixed geometry. The tensions closest to their targets, min ‖Lq − T̄‖², in \
                 exact equilibrium or traded against it (Tikhonov, min ‖Aq − p‖² + \
                 λ‖Lq − T̄‖²): one sparse KKT system (faer). Does not enforce 0 < q ≤ [q]: \
                 a design that breaks them is an error naming the cables. Knob: lambda \
                 (dimensionless)."
            }
        }
    }

    /// The default solver of a problem with `sets` uniformity sets, loaded
    /// (`loaded`: nodal loads such as the cables' weight) or not: [`Lp`] —
    /// one LP, a unique design, the fastest route — where it applies (one set,
    /// no loads), [`Bisection`] where it does not. Every command that takes
    /// `--solver` defaults to this rule.
    pub fn default_for(sets: usize, loaded: bool) -> SolverKind {
        if sets == 1 && !loaded {
            SolverKind::Lp
        } else {
            SolverKind::Bisection
        }
    }

    /// True for a solver that starts from a neighbouring problem's design
    /// ([`UniformitySolver::solve_from`]); the others solve every problem
    /// afresh.
    pub fn warm_starts(self) -> bool {
        matches!(self, SolverKind::Gradient | SolverKind::GradientSmooth)
    }

    /// The solver with `settings` over its defaults: each a field of its
    /// settings by name (`{"epsilon_n": 0.5}` for `bisection`, `finish` a
    /// table of the gradient finish's), validated as the solve would.
    ///
    /// # Errors
    /// [`UniformityError::SettingValue`] naming a setting the solver does not
    /// have or a value not of its type; [`UniformityError::Setting`] naming
    /// one out of its range.
    pub fn configure(
        self,
        settings: &serde_json::Map<String, serde_json::Value>,
    ) -> Result<Box<dyn UniformitySolver>, UniformityError> {
        let name = self.build(None).name();
        Ok(match self {
            SolverKind::Lp => match settings.keys().next() {
                Some(key) => {
                    return Err(UniformityError::SettingValue {
                        solver: name,
                        name: key.clone(),
                        reason: "the `lp` solver has no settings".into(),
                    })
                }
                None => Box::new(Lp),
            },
            SolverKind::Bisection => {
                let b: Bisection = overlay(name, Bisection::default(), settings)?;
                b.validate()?;
                Box::new(b)
            }
            SolverKind::Gradient | SolverKind::GradientSmooth => {
                let defaults = Gradient {
                    exact_finish: self == SolverKind::Gradient,
                    ..Gradient::default()
                };
                let g: Gradient = overlay(name, defaults, settings)?;
                g.validate()?;
                Box::new(g)
            }
            SolverKind::LeastSquares => {
                let l: LeastSquares = overlay(name, LeastSquares::default(), settings)?;
                l.validate()?;
                Box::new(l)
            }
        })
    }

    /// The solver with its default settings, or with its accuracy knob set.
    pub fn build(self, knob: Option<f64>) -> Box<dyn UniformitySolver> {
        match self {
            SolverKind::Bisection => Box::new(Bisection {
                epsilon_n: knob.unwrap_or(0.0),
                ..Bisection::default()
            }),
            SolverKind::Lp => Box::new(Lp),
            SolverKind::Gradient | SolverKind::GradientSmooth => {
                let defaults = Gradient {
                    exact_finish: self == SolverKind::Gradient,
                    ..Gradient::default()
                };
                Box::new(Gradient {
                    weight: knob.unwrap_or(defaults.weight),
                    ..defaults
                })
            }
            SolverKind::LeastSquares => Box::new(LeastSquares {
                lambda: knob,
                ..LeastSquares::default()
            }),
        }
    }
}

/// `base` with the fields `settings` names replaced, each checked in turn so
/// that an error names its setting.
fn overlay<T: serde::Serialize + serde::de::DeserializeOwned>(
    solver: &'static str,
    base: T,
    settings: &serde_json::Map<String, serde_json::Value>,
) -> Result<T, UniformityError> {
    let mut value = serde_json::to_value(base).expect("solver settings serialise");
    let fields = value
        .as_object_mut()
        .expect("solver settings are a table of fields");
    for (key, v) in settings {
        if !fields.contains_key(key) {
            let known: Vec<&str> = fields.keys().map(String::as_str).collect();
            return Err(UniformityError::SettingValue {
                solver,
                name: key.clone(),
                reason: format!("no such setting (it has {})", known.join(", ")),
            });
        }
        fields.insert(key.clone(), v.clone());
        if let Err(e) = serde_json::from_value::<T>(serde_json::Value::Object(fields.clone())) {
            return Err(UniformityError::SettingValue {
                solver,
                name: key.clone(),
                reason: e.to_string(),
            });
        }
    }
    Ok(serde_json::from_value(value).expect("checked field by field"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    fn settings(json: &str) -> serde_json::Map<String, serde_json::Value> {
        serde_json::from_str(json).unwrap()
    }

    fn setting_error(kind: SolverKind, json: &str) -> UniformityError {
        match kind.configure(&settings(json)) {
            Err(e) => e,
            Ok(s) => panic!("{} accepted {json}", s.name()),
        }
    }

    #[test]
    fn configure_without_settings_is_build_with_defaults() {
        for kind in SolverKind::value_variants() {
            let configured = kind.configure(&serde_json::Map::new()).unwrap();
            assert_eq!(configured.name(), kind.build(None).name());
        }
    }

    #[test]
    fn configure_names_an_unknown_setting_and_lists_the_known_ones() {
        match setting_error(SolverKind::Bisection, r#"{"epsilon": 0.1}"#) {
            UniformityError::SettingValue {
                solver,
                name,
                reason,
            } => {
                assert_eq!((solver, name.as_str()), ("bisection", "epsilon"));
                assert!(reason.contains("epsilon_n"), "{reason}");
            }
            e => panic!("{e}"),
        }
        assert!(matches!(
            setting_error(SolverKind::Lp, r#"{"weight": 1.0}"#),
            UniformityError::SettingValue { name, .. } if name == "weight"
        ));
    }

    #[test]
    fn configure_names_a_value_of_the_wrong_type() {
        match setting_error(SolverKind::Gradient, r#"{"weight": 2.0, "memory": 2.5}"#) {
            UniformityError::SettingValue { name, .. } => assert_eq!(name, "memory"),
            e => panic!("{e}"),
        }
    }

    #[test]
    fn configure_validates_ranges_as_the_solve_would() {
        for (kind, json, field) in [
            (SolverKind::Bisection, r#"{"epsilon_n": -1.0}"#, "epsilon_n"),
            (
                SolverKind::Bisection,
                r#"{"max_iterations": 0}"#,
                "max_iterations",
            ),
            (
                SolverKind::LeastSquares,
                r#"{"tolerance": 2.0}"#,
                "tolerance",
            ),
            (
                SolverKind::GradientSmooth,
                r#"{"sharpness": 0.0}"#,
                "sharpness",
            ),
        ] {
            match setting_error(kind, json) {
                UniformityError::Setting { name, .. } => assert_eq!(name, field, "{json}"),
                e => panic!("{json}: {e}"),
            }
        }
    }

    #[test]
    fn configure_keeps_gradient_smooth_without_its_finish() {
        // gradient-smooth is gradient with exact_finish off; a setting given
        // by name changes that field alone.
        let g: Gradient = overlay(
            "gradient",
            Gradient::smooth(),
            &settings(r#"{"weight": 3.0, "finish": {"max_steps": 7}}"#),
        )
        .unwrap();
        assert!(!g.exact_finish);
        assert_eq!(g.weight, 3.0);
        assert_eq!(g.finish.max_steps, 7);
        assert_eq!(g.finish.tolerance, FinishSettings::default().tolerance);
    }
}
