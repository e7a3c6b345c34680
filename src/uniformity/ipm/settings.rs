//! The interior-point method's tuning as plain data, for every problem the
//! driver runs (the ratio LP of `lp.rs`/`plan.rs`, the exact finish's
//! quadratic program): the stopping tests and limits of the Mehrotra
//! iteration, its step rule, the regularisation and refinement of the
//! problems' Newton systems, the FGMRES completion of the plan LP, the
//! finish's start, and the one check of their ranges
//! ([`IpmSettings::validate`]).

use super::IpmError;

/// How the ratio LP's starting point is scaled (issue 38, measured on three
/// net families: `tests/ipm_families.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Start {
    /// Mehrotra's heuristic in the LP's own variables `x = q − lb`: least norm
    /// with `Θ = I`, one shift for every `x_k`.
    Unscaled,
    /// The same in tensions above their floors (`ℓ_k x_k`, `z_k/ℓ_k`): least
    /// norm with `Θ = diag(1/ℓ²)`, one shift for every tension. Invariant
    /// under the nets' spread of cable lengths (the iteration itself is
    /// invariant under that diagonal scaling; only the start was not).
    TensionScaled,
}

/// The fraction `τ` of the step to the boundary that an iteration takes:
/// the step is `min(1, τ α)`, `α` the largest step that keeps the pairs
/// non-negative, capped at `1/τ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum StepLength {
    /// `τ = clamp(1 − min(μ, 0.1), 0.9, 0.99995)`, `α` capped at 1: short
    /// steps far from the optimum, nearly full ones close to it (the ratio
    /// LP's).
    Adaptive,
    /// A fixed `τ` in `(0, 1)`, `α` capped at `1/τ` so that a full step is
    /// taken where the boundary is beyond it.
    Fixed(f64),
}

/// Tolerances, limits, step rule and linear algebra of the interior-point
/// method; [`Default`] holds the values of the full (3-D) ratio LP, with
/// [`IpmSettings::plan`] and [`IpmSettings::finish`] the other problems'.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct IpmSettings {
    /// Relative primal residual at which the method has converged. The
    /// ratio LP projects its point onto equilibrium afterwards (its
    /// `polish`), which restores it to rounding: near the optimum `Θ = X
    /// Z⁻¹` spans some twenty orders of magnitude and the normal equations
    /// no longer resolve the primal residual, while the gap and the dual
    /// residual still converge.
    pub primal_tolerance: f64,
    /// Relative dual residual at which the method has converged.
    pub dual_tolerance: f64,
    /// Relative duality gap at which the method has converged (each problem
    /// states what the gap is relative to).
    pub gap_tolerance: f64,
    /// Primal and dual residuals of a best iterate accepted at reduced
    /// accuracy when the method stalls (clarabel's `AlmostSolved`); for the
    /// ratio LP at most its primal tolerance, which the projection needs.
    pub reduced_tolerance: f64,
    /// The gap of such an iterate.
    pub reduced_gap_tolerance: f64,
    /// Iterations without a better iterate after which the method counts as
    /// stalled.
    pub stall_iterations: usize,
    /// Iteration limit.
    pub max_iterations: usize,
    /// The least centring `σ` of the corrector (Mehrotra's `σ = (μ_aff/μ)³`
    /// is raised to it): a predictor that reaches far lowers `μ` by no more
    /// than about this in one step, which keeps the iterate centred enough
    /// for the next.
    pub min_centring: f64,
    /// The fraction of the step to the boundary taken.
    pub step_length: StepLength,
    /// Separate step lengths for the primal and the dual variables (the
    /// LP's); one common step otherwise (a quadratic program's dual residual
    /// depends on the primal step).
    pub separate_steps: bool,
    /// Gondzio's centrality correctors per iteration (at most; each is one
    /// more Newton solve with the iteration's factor, kept while it lengthens
    /// the step by 1 %). None by default: on the three net families of issue
    /// 38 at 9 913 free nodes, 1/2/3 correctors took hex 24 → 20/20/18,
    /// sector 16 → 15/14/13 and jitter 64 → 56/49/47 iterations, but the time
    /// fell on none of them (hex 1.18–1.27 s → 1.20–1.24 s, sector 0.58–0.64
    /// → 0.63–0.67 s, jitter 2.6–3.0 → 2.9–3.2 s, one run, load ≈ 2.7): near
    /// the optimum each correction's FGMRES completion needs most of its
    /// [`Self::krylov_steps`] solves, like the corrector's, and the solves
    /// are most of an iteration's time.
    pub centrality_correctors: usize,
    /// The ratio LP's starting point.
    pub start: Start,
    /// Relative primal residual of the ratio LP after its final projection.
    pub polished: f64,
    /// Pivots of the scaled Newton matrix below this are treated as zero …
    pub pivot_epsilon: f64,
    /// … and replaced by this (with the pivot's expected sign, for the
    /// quasi-definite matrix of the finish). Above 1 it drops the direction
    /// (dependent rows of the 3-D LP's `A`).
    pub pivot_delta: f64,
    /// Static shift of the diagonal of the scaled Newton matrix (a unit
    /// diagonal; the plan LP's node blocks scaled to the identity) before it
    /// is factored. Cable nets are mechanisms (`A` has dependent rows: the
    /// infinitesimal mechanisms a prestress stiffens), so the LP's `M` is
    /// singular; the shift makes the factor well defined, and iterative
    /// refinement against the exact matrix removes its effect on the range,
    /// where every right-hand side lives.
    pub regularization: f64,
    /// Largest shift tried when a factorisation fails (the ratio LP) …
    pub max_regularization: f64,
    /// … the shift growing by this factor per failed attempt.
    pub regularization_growth: f64,
    /// Least diagonal of the finish's cable unknowns in its factored system
    /// (a primal regularisation, refined away).
    pub primal_floor: f64,
    /// Refinement steps per solve with the factor (at most) …
    pub refinement_steps: usize,
    /// … of the predictor, which only sets the centring (the finish) …
    pub predictor_refinement_steps: usize,
    /// … and their relative residual target.
    pub refinement_tolerance: f64,
    /// FGMRES steps per Newton direction of the plan LP (at most) …
    pub krylov_steps: usize,
    /// … of its predictor, whose direction only sets the centring and the
    /// corrector's second-order term (the corrector is completed in full) …
    pub predictor_krylov_steps: usize,
    /// … and their target for the rows the factor solves inexactly, relative
    /// to their right-hand side (a centrality correction, whose rows are
    /// zero, stops at the corrector's residual instead: `ratio.rs`).
    pub krylov_tolerance: f64,
    /// … and their stagnation test: FGMRES stops when two steps have not
    /// lowered the residual below this fraction of what it was before them.
    /// Where the factor has lost many directions (the plan LP of a deformed
    /// boundary: the sagged boundary's stiff cables leave modes below
    /// rounding), its residual falls ~0.9 a step, and the steps past the
    /// third cost a solve each for a direction that ends no better: on
    /// super-100m's design loop its four warm LPs took 24–28 interior-point
    /// iterations with every step taken and 8–13 with this test, and
    /// `design` took 38.3–40.3 s against 24.0–26.4 s (the same binary, two
    /// rounds interleaved). Those LPs then end with a primal residual of
    /// 1.0–1.3e-7 of the largest tension instead of 3.8–4.8e-8, and their
    /// projected ratio 9e-6 above the iterate's lower bound instead of
    /// 3e-6 (neither within 1e-6: the residual sits in modes the factor
    /// cannot resolve). On the three net families at 10³ and 10⁴ free nodes
    /// (cold LPs, where FGMRES converges) the iterations did not change and
    /// the optima moved by at most 1.2e-7 (the jittered net at 10⁴, from
    /// 1.1e-7 below clarabel's to 1.2e-8 above).
    pub krylov_stagnation: f64,
    /// The finish's least first slack of a row (the rows are in units of
    /// `ln T` and of relative `δq`): 0.1 took 10 iterations a program where
    /// 1 took 13.
    pub first_slack: f64,
    /// The finish's least first multiplier of a warm start. The sets' rows
    /// keep their activity from one step to the next: on the tied nets a
    /// warm program takes 5–7 iterations against 7–11 cold; below 1e-4 it
    /// can stall.
    pub warm_floor: f64,
    /// A finish program that lowers the model by `Δ` is solved once its gap
    /// is below this times `Δ` (and its residuals converged): its step is
    /// then known to a thousandth of its decrease, which is all the finish
    /// reads from it; only a program that predicts (almost) no decrease —
    /// the certificate — is solved to [`Self::gap_tolerance`].
    pub coarse_gap: f64,
    /// The relative gap at which the driver keeps its iterate as the start
    /// of a neighbouring problem (`Outcome::kept`): the last iterate with
    /// the gap at least this. `None` keeps none.
    pub keep_at_gap: Option<f64>,
}

impl Default for IpmSettings {
    fn default() -> Self {
        IpmSettings {
            primal_tolerance: 1e-6,
            dual_tolerance: 1e-9,
            gap_tolerance: 1e-9,
            reduced_tolerance: 1e-6,
            reduced_gap_tolerance: 1e-6,
            stall_iterations: 8,
            max_iterations: 100,
            min_centring: 0.0,
            step_length: StepLength::Adaptive,
            separate_steps: true,
            centrality_correctors: 0,
            start: Start::Unscaled,
            polished: 1e-12,
            pivot_epsilon: 1e-13,
            pivot_delta: 1e64,
            regularization: 1e-14,
            max_regularization: 1e-6,
            regularization_growth: 100.0,
            primal_floor: 1e-8,
            refinement_steps: 20,
            predictor_refinement_steps: 20,
            refinement_tolerance: 1e-12,
            krylov_steps: 8,
            predictor_krylov_steps: 8,
            krylov_tolerance: 1e-13,
            krylov_stagnation: 0.5,
            first_slack: 0.1,
            warm_floor: 1e-4,
            coarse_gap: 1e-3,
            keep_at_gap: None,
        }
    }
}

impl IpmSettings {
    /// The settings of the plan problem of a tied net (`D = 2`, see
    /// `uniformity/plan.rs`): a static shift of 1e-13 of the unit diagonal and
    /// no dropped pivots. The plan equilibrium matrix of a triangulated net has
    /// independent rows, so a tiny pivot is never a mechanism: it is a
    /// direction that the optimum's degenerate face leaves to the border `a`
    /// (the cables at `Tmax` moving with `s`). Dropping it (a pivot replaced by
    /// [`Self::pivot_delta`], right for the mechanisms of the 3-D problem)
    /// loses exactly the direction `ds` depends on: measured on independent
    /// hexagonal nets, the reduction's residual reached 10¹⁰…10⁹¹ of its
    /// right-hand side near the optimum, FGMRES could not recover, and the
    /// method stalled (2·10³ nodes), failed to factor (2·10⁴) or gave up
    /// (2·10⁵). With the shift the border's elimination stays consistent and
    /// the method converges on all of them (shift 1e-10 already leaves too
    /// many directions damped at 2·10⁵ nodes for FGMRES to restore). The
    /// shift was 1e-12: at 99 913 free nodes the primal residual then stalled
    /// at 2.6e-8 of the largest tension on the hexagonal net (FGMRES at its
    /// step limit) and the projection onto equilibrium put the ratio 5.1e-6
    /// above clarabel's; with 1e-13, 6.9e-9 and, with `Program::polish`'s
    /// choice of projection, 5.2e-7 (the jittered net 3.7e-6, still outside
    /// 1e-6), in 28.2–28.7 s against 30.5 s. A shift of 1e-14 stalled at 3.0e-9, but
    /// the 120-bay ring of `tests/super_large.rs` then assembled with a
    /// largest tension change of 0.054 % against 0.0014 % (1e-12) and
    /// 0.00074 % (1e-13).
    ///
    /// Its start is [`Start::TensionScaled`]: on the three net families of
    /// issue 38 it saved 1–13 of 21–77 iterations in five of six nets at
    /// 10³/10⁴ free nodes (one more on the regular sector grid at 10⁴).
    ///
    /// Its iteration limit is 200: the jittered sector grid of issue 38
    /// (`tests/common/nets.rs`) takes 33, 43, 65 iterations at 10³, 2.4·10³,
    /// 10⁴ free nodes and 137 at 10⁵ (converged; the gap still fell by about
    /// 0.8 per iteration at the default limit of 100, 2·10⁻⁶ there, so the
    /// run ended in `MaxIterations` and the route fell back to clarabel,
    /// which needs minutes at that size).
    ///
    /// It keeps its last iterate with a relative gap of at least 1e-5 for
    /// the next outer iteration's LP, whose boundary differs by micrometres.
    /// Measured on super-60m's design loop (LPs of 42 840 cables), the
    /// uniformity stage and the final ratio: cold 6.95 s (the three later
    /// LPs 25, 25 and 26 iterations), 15.8668529; kept at 1e-4 5.26 s (13,
    /// 12 and 11), 15.8668970; at 1e-5 4.41 s (the last LP 10), 15.8668471;
    /// at 1e-6 4.01 s, 15.8669741 — the closer to the optimal face the start,
    /// the less the next LP follows its own central path. (The *first*
    /// iterate below 1e-4 is already the optimum on small-hex, gap 3e-9:
    /// the outer loop to a 1e-7 m tolerance then took 13 iterations with
    /// Anderson mixing and 11 with the paper's relaxation, against 4 and 6
    /// cold and with this rule.)
    ///
    /// Its predictor is the reduction's direction as it is, without FGMRES
    /// ([`Self::predictor_krylov_steps`] 0): near the optimum FGMRES took 9
    /// of an iteration's 19 solves to complete a direction that only sets
    /// `σ` and the second-order term. Measured on the three families (best
    /// of 3–5, two rounds interleaved, load ≈ 1.3): at 9 913 free nodes hex
    /// 1.35–1.60 → 1.28–1.45 s (24 → 30 iterations), sector 0.72–0.75 →
    /// 0.64–0.66 s (16 → 17), jitter 3.18–3.37 → 2.59–2.76 s (64 → 68); at
    /// 2 431 hex 0.14 s either way (17 → 21), sector 0.09 → 0.075 s, jitter
    /// 0.31 → 0.25 s; every optimum within 6e-7 of clarabel's.
    ///
    /// Its least centring is 0.03: on the hexagonal net at 9 913 free nodes
    /// one predictor reached 0.96 of the way with `σ = 7·10⁻⁵`, `μ` fell 50×
    /// in one iteration, and the next 6–8 iterations took steps of 0.02–0.6
    /// at a gap of 1e-3 to recentre. With both changes (two rounds
    /// interleaved, best of 3, the machine quieter):
    /// hex 1.19–1.20 → 0.87–0.90 s (24 → 25 iterations), sector 0.58–0.59 →
    /// 0.54–0.57 s (16 → 18), jitter 2.73–2.80 → 2.24–2.27 s (64 → 68); at
    /// 1 021 free nodes hex and sector unchanged (0.06 and 0.05 s), jitter
    /// 0.13 → 0.11 s. A floor of 0.01 or 0.1 was slower on hex (1.07, 1.00 s)
    /// and sector (0.61, 0.77 s).
    pub(crate) fn plan() -> Self {
        IpmSettings {
            regularization: 1e-13,
            pivot_epsilon: 1e-30,
            predictor_krylov_steps: 0,
            min_centring: 0.03,
            start: Start::TensionScaled,
            max_iterations: 200,
            keep_at_gap: Some(1e-5),
            ..IpmSettings::default()
        }
    }

    /// The settings of the exact finish's quadratic program
    /// (`gradient/finish/ipm.rs`): residuals to 1e-8 (clarabel's default),
    /// the gap to 1e-10 of `max(1, |f|)` — the finish compares the model's
    /// optimum with `J` to `10⁻⁹ J` — or [`Self::coarse_gap`] of the decrease;
    /// a program that stalls is accepted with residuals to 1e-6 (the finish
    /// reads the point only after re-solving its equilibrium). One common
    /// step, 0.99 of the way to the boundary; an LDLᵀ of the quasi-definite
    /// reduced system with a static shift of 1e-12 of its unit diagonal and
    /// pivots below 1e-13 replaced by ±1e-8, refined to a backward error of
    /// 1e-10 (0 steps for the predictor).
    ///
    /// The shift was 1e-10. Near a program's optimum refinement could then
    /// no longer resolve the linearised equilibrium (its residual stalled at
    /// 1.3e-8 on the hexagonal nets, 2–5e-8 on realistic-26m), the programs
    /// ran to their stall test, and the finish certified points whose `J`
    /// lay 2e-8 `J` above the ones it reaches now. Measured on the three net
    /// families of issue 38 (`tests/ipm_families.rs`, `finish_table`), at
    /// 1e-10 → 1e-12: hex 1 021 free nodes 63 → 21 interior-point iterations
    /// (0.9 → 0.4 s), 2 431: 49 → 21, 9 913: 49 → 28 and 5 → 3 programs
    /// (18.4 → 10.9 s); jitter 2 431: 385 → 261 (21 → 13 s); sector
    /// unchanged; `J` lower on every net. The design loop of realistic-26m
    /// with `gradient` took 3.8 → 1.05 s to the same ratio. 1e-13 gave the
    /// same counts.
    pub(crate) fn finish() -> Self {
        IpmSettings {
            primal_tolerance: 1e-8,
            dual_tolerance: 1e-8,
            gap_tolerance: 1e-10,
            reduced_tolerance: 1e-6,
            reduced_gap_tolerance: 1e-10,
            stall_iterations: 10,
            max_iterations: 80,
            step_length: StepLength::Fixed(0.99),
            separate_steps: false,
            pivot_delta: 1e-8,
            regularization: 1e-12,
            refinement_steps: 30,
            predictor_refinement_steps: 0,
            refinement_tolerance: 1e-10,
            ..IpmSettings::default()
        }
    }

    /// Checks every setting's range: the tolerances, the pivot threshold,
    /// the shifts, FGMRES's stagnation fraction and the gap of a kept
    /// iterate in `(0, 1)`, the reduced
    /// tolerances at least the ones they relax, the shift bound at least the
    /// first shift, a growth above 1, a positive replacement pivot, a least
    /// centring in `[0, 1)`, a fixed step fraction in `(0, 1)`, a positive
    /// first slack and warm floor, and at least one stall iteration.
    ///
    /// # Errors
    /// [`IpmError::Setting`] naming the first field out of its range.
    pub(crate) fn validate(&self) -> Result<(), IpmError> {
        let bad = |name: &'static str, value: f64, range: &'static str| {
            Err(IpmError::Setting { name, value, range })
        };
        let fractions = [
            ("primal_tolerance", self.primal_tolerance),
            ("dual_tolerance", self.dual_tolerance),
            ("gap_tolerance", self.gap_tolerance),
            ("reduced_tolerance", self.reduced_tolerance),
            ("reduced_gap_tolerance", self.reduced_gap_tolerance),
            ("polished", self.polished),
            ("pivot_epsilon", self.pivot_epsilon),
            ("regularization", self.regularization),
            ("max_regularization", self.max_regularization),
            ("primal_floor", self.primal_floor),
            ("refinement_tolerance", self.refinement_tolerance),
            ("krylov_tolerance", self.krylov_tolerance),
            ("krylov_stagnation", self.krylov_stagnation),
            ("coarse_gap", self.coarse_gap),
            ("keep_at_gap", self.keep_at_gap.unwrap_or(0.5)),
        ];
        for (name, value) in fractions {
            if !(value > 0.0 && value < 1.0) {
                return bad(name, value, "in (0, 1)");
            }
        }
        if self.reduced_tolerance < self.primal_tolerance.max(self.dual_tolerance) {
            return bad(
                "reduced_tolerance",
                self.reduced_tolerance,
                "≥ primal_tolerance and dual_tolerance",
            );
        }
        if self.reduced_gap_tolerance < self.gap_tolerance {
            return bad(
                "reduced_gap_tolerance",
                self.reduced_gap_tolerance,
                "≥ gap_tolerance",
            );
        }
        if self.max_regularization < self.regularization {
            return bad(
                "max_regularization",
                self.max_regularization,
                "≥ regularization",
            );
        }
        if !(self.regularization_growth.is_finite() && self.regularization_growth > 1.0) {
            return bad(
                "regularization_growth",
                self.regularization_growth,
                "finite and > 1",
            );
        }
        for (name, value) in [
            ("pivot_delta", self.pivot_delta),
            ("first_slack", self.first_slack),
            ("warm_floor", self.warm_floor),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return bad(name, value, "finite and > 0");
            }
        }
        if !(0.0..1.0).contains(&self.min_centring) {
            return bad("min_centring", self.min_centring, "in [0, 1)");
        }
        if let StepLength::Fixed(fraction) = self.step_length {
            if !(fraction > 0.0 && fraction < 1.0) {
                return bad("step_length", fraction, "in (0, 1)");
            }
        }
        if self.stall_iterations == 0 {
            return bad("stall_iterations", 0.0, "≥ 1");
        }
        Ok(())
    }
}
