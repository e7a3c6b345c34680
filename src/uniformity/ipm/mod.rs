//! A structure-exploiting primal–dual interior-point method (Mehrotra
//! predictor–corrector) for the ratio LP of one uniformity set (DESIGN §4):
//!
//! ```text
//! min s   s.t.  A q = 0,  q_k ≥ 1/ℓ_k (k ∈ S),  q_k ≥ f/ℓ_k (k ∉ S),
//!               ℓ_k q_k − s + w_k = 0, w_k ≥ 0 (k ∈ S)
//! ```
//!
//! `A` is the equilibrium matrix of the cables in `D` coordinates per free node
//! (`D = 3` for the full problem, `D = 2` for the plan problem of a reflector,
//! see `plan.rs`). In the shifted variables `x = q − lb ≥ 0` (`ℓ_k lb_k = 1` on
//! the set) the constraints read `A x = b := −A lb` and `w = s·e − E x − 1 ≥ 0`,
//! with `E` the set's rows of `diag(ℓ)` (one nonzero per row). With multipliers
//! `y` (for `A x = b`), `λ ≥ 0` (for `w ≥ 0`) and `z ≥ 0` (for `x ≥ 0`), dual
//! feasibility is `z = Eᵀλ − Aᵀy`, `eᵀλ = 1`.
//!
//! Each Newton system is reduced by eliminating `dz`, `dw` and then `dλ` (whose
//! block `G = EΘEᵀ + Ω` is diagonal because every set row of `E` holds a single
//! cable) to the bordered system
//!
//! ```text
//! [ A Θ̃ Aᵀ   a ] [dy]   [r1]       Θ̃_k = θ_k ω_j / (ℓ_k² θ_k + ω_j)  (k = S_j),
//! [ aᵀ      −γ ] [ds] = [r2]       Θ̃_k = θ_k otherwise,
//! ```
//!
//! `Θ = X Z⁻¹`, `Ω = W Λ⁻¹`, `a = A α` with `α_k = θ_k ℓ_k / G_j`, `γ = Σ 1/G_j`.
//! The normal matrix `M = A Θ̃ Aᵀ` has the pattern of `D = C_fᵀ Q C_f` with dense
//! D×D blocks: its pattern, fill-reducing ordering (AMD or nested dissection on
//! the node graph, whichever fills less, expanded blockwise) and symbolic
//! Cholesky factorisation are built once; every iteration refills the values,
//! scales `M` (the plan problem's node blocks to the identity, the 3-D
//! problem's diagonal to unity) and refactors numerically; the solves with
//! the supernodal factor run in `supernodal.rs`'s kernel. Dependent rows of `A`
//! (mechanisms of the net) show up as (near-)zero pivots, which faer's dynamic
//! regularisation replaces by a huge pivot, i.e. the direction is dropped. The
//! border is eliminated with the same factor (`t = M̂⁻¹ a` once per
//! iteration). This reduction, with the factor `M̂` in place of `M`, is only a
//! preconditioner: each Newton direction is
//! completed by FGMRES on the rows of the *unreduced* system it does not solve
//! exactly (`A dx = r_p`, the `w` rows, `eᵀdλ = r_s`), whose residuals are
//! formed from moderate quantities. Refining the reduced system instead
//! measures residuals of `A Θ Aᵀ dy` with `Θ` spanning ~10^±20 near the optimum
//! and loses the primal residual there (the run stalled at 3·10⁴ nodes).
//!
//! One interior point runs every program of the crate that needs one: the
//! driver (`driver.rs`) is generic over the problem's Newton system
//! ([`NewtonSystem`], `system.rs`) as clarabel's solver is over its
//! `KKTSolver`. It owns the Mehrotra predictor–corrector, the step to the
//! boundary, the centrality correctors, the stopping tests and the status;
//! the problem owns its variables, start, residuals and linear algebra. The
//! ratio LP above is one problem (`ratio.rs`, with its data in `data.rs`,
//! the normal system and its factorisation in `normal.rs`, its solves in
//! `supernodal.rs`, the Newton direction with its FGMRES completion in
//! `direction.rs`); the exact
//! finish's quadratic program is the other (`gradient/finish/ipm.rs`). One
//! settings struct ([`IpmSettings`], `settings.rs`) serves both, what the LP
//! returns is `status.rs`'s, and why it could not start is `error.rs`'s
//! (below the others).

mod data;
mod direction;
mod driver;
mod error;
mod normal;
mod ratio;
mod settings;
mod status;
mod supernodal;
mod system;

pub(crate) use data::RatioLp;
pub(crate) use driver::run;
pub(crate) use error::IpmError;
pub(crate) use ratio::solve;
pub(crate) use settings::IpmSettings;
pub use status::WarmStart;
pub(crate) use system::{Measures, NewtonSystem, Point, Rhs};

#[cfg(test)]
pub(crate) mod tests;
