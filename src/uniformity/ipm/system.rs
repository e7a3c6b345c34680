//! What the interior-point driver (`driver.rs`) asks of a problem: its
//! iterate in the driver's form ([`Point`]), the size of its residuals
//! ([`Measures`]), and its Newton system ([`NewtonSystem`]: start,
//! residuals, factorisation, directions) — the way clarabel's solver runs
//! one iteration over its `KKTSolver`. The ratio LP (`lp.rs`) and the exact
//! finish's quadratic program (`gradient/finish/ipm.rs`) implement it.

/// A point of the iteration, or a direction in its space: the
/// complementary pairs `v ≥ 0`, `u ≥ 0` (the driver drives `v ∘ u` to
/// zero) and the free variables, split by the step length they take.
#[derive(Debug, Clone, Default)]
pub(crate) struct Point {
    /// The primal variables `v` of the pairs.
    pub primal: Vec<f64>,
    /// Their multipliers `u`, one per primal variable.
    pub dual: Vec<f64>,
    /// Free variables taking the primal step.
    pub free_primal: Vec<f64>,
    /// Free variables taking the dual step.
    pub free_dual: Vec<f64>,
}

impl Point {
    /// Whether every entry is finite.
    pub(crate) fn is_finite(&self) -> bool {
        [&self.primal, &self.dual, &self.free_primal, &self.free_dual]
            .iter()
            .all(|v| v.iter().all(|x| x.is_finite()))
    }

    /// `self += alpha·other`, entry by entry.
    pub(crate) fn add_scaled(&mut self, alpha: f64, other: &Point) {
        let add = |a: &mut [f64], b: &[f64]| a.iter_mut().zip(b).for_each(|(a, b)| *a += alpha * b);
        add(&mut self.primal, &other.primal);
        add(&mut self.dual, &other.dual);
        add(&mut self.free_primal, &other.free_primal);
        add(&mut self.free_dual, &other.free_dual);
    }
}

/// The residuals of a point relative to the problem's own scales, compared
/// with the settings' tolerances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Measures {
    /// Relative primal residual.
    pub primal: f64,
    /// Relative dual residual.
    pub dual: f64,
    /// Relative duality gap.
    pub gap: f64,
}

impl Measures {
    /// Not yet measured.
    pub(crate) const NAN: Measures = Measures {
        primal: f64::NAN,
        dual: f64::NAN,
        gap: f64::NAN,
    };

    /// Whether all three are finite.
    pub(crate) fn is_finite(&self) -> bool {
        self.primal.is_finite() && self.dual.is_finite() && self.gap.is_finite()
    }
}

/// Which right-hand side a Newton direction solves for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Rhs {
    /// The affine (predictor) direction: the iterate's residuals, which
    /// only sets the centring (a problem may solve it less accurately).
    Predictor,
    /// The corrector: the iterate's residuals.
    Corrector,
    /// A centrality correction: zero residual rows.
    Centrality,
}

/// A problem's Newton system: the driver owns the iteration (predictor,
/// corrector, step to the boundary, centrality, stopping tests, status);
/// the problem owns its variables, residuals and linear algebra.
pub(crate) trait NewtonSystem {
    /// Why the system could not be factored or solved.
    type Error;

    /// Ends of the blocks of pairs (the last is the number of pairs): sums
    /// over the pairs are formed block by block.
    fn pair_blocks(&self) -> Vec<usize>;

    /// The starting point, strictly interior in its pairs.
    fn start(&mut self) -> Result<Point, Self::Error>;

    /// The residuals of `point`, kept for the directions that follow, and
    /// their relative sizes.
    fn residuals(&mut self, point: &Point) -> Measures;

    /// Factors the Newton system at `point`.
    fn factor(&mut self, point: &Point) -> Result<(), Self::Error>;

    /// The Newton direction at `point` with the complementarity rows
    /// `U dv + V du = complementarity` and the other rows' right-hand sides
    /// chosen by `rhs`, with the last factor.
    fn direction(
        &mut self,
        point: &Point,
        complementarity: &[f64],
        rhs: Rhs,
    ) -> Result<Point, Self::Error>;
}
