//! The best-fit paraboloid: the six parameters (apex translations, two axis
//! tilts, focal length) that minimise the RMS half-path-length error of a
//! surface, by Gauss–Newton on the exact, nonlinear deviation; and the node
//! and facet RMS about it.

use super::placed::PlacedParaboloid;
use super::rms::{check_paraboloid, rms_about, SurfaceRms};
use super::samples::Samples;
use super::SurfaceError;
use crate::geometry::Paraboloid;
use serde::Serialize;

use crate::status::Termination;

/// Gauss–Newton iterations before the fit is declared not converged (a fit
/// from the design paraboloid converges in a handful: the deviations are
/// small against the focal length).
const MAX_ITERATIONS: usize = 50;
/// Step halvings tried before a step that raises the RMS is given up.
const MAX_HALVINGS: usize = 40;
/// A step that moves the surface by less than this fraction of the RMS
/// half-path-length error (RMS of `J·step`) ends the fit: at a minimum the RMS
/// then changes by a relative `STEP_TOLERANCE²/2` at most.
const STEP_TOLERANCE: f64 = 1e-6;
/// An accepted step that lowers the mean square by less than this fraction
/// ends the fit: the step is rounding (the shift and tilt of a shallow dish
/// are nearly the same motion, so its normal matrix is ill-conditioned).
const STALL_TOLERANCE: f64 = 1e-12;
/// Rounding floor of a deviation, in units of ε × the largest coordinate.
const ROUNDING_FLOOR: f64 = 64.0;
/// Smallest pivot of the unit-diagonal normal matrix kept as independent.
const PIVOT_TOLERANCE: f64 = 1e-13;

/// A surface about its best-fit paraboloid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BestFit {
    /// The fitted paraboloid: apex, axis tilts, focal length.
    pub paraboloid: PlacedParaboloid,
    /// RMS of the three deviations about it (same points and weights as the
    /// raw RMS), m.
    pub rms: SurfaceRms,
    /// Gauss–Newton iterations taken (0 when the surface is the design
    /// paraboloid to rounding).
    pub iterations: usize,
    /// How the fit ended: converged, or stopped (its iteration budget spent,
    /// or no step lowering the RMS) at the best paraboloid it had found —
    /// every accepted step lowers the RMS, so `rms` is then an upper bound
    /// of the best fit's, still at most the raw RMS.
    pub termination: Termination,
}

/// **Best-fit node RMS**: [`super::node_rms`] about the paraboloid that fits
/// the nodes best.
///
/// The fit minimises the nodes' mean square half-path-length error (Ruze's
/// ε: the paraboloid a feed would be aligned to) over the six parameters of
/// [`PlacedParaboloid`], from the design paraboloid, by Gauss–Newton on the
/// exact deviation in the fitted paraboloid's own frame; so a surface that is
/// an exactly moved, tilted or refocused paraboloid fits to rounding. The
/// axial and normal RMS reported are about the same fitted paraboloid.
///
/// # Errors
/// The input errors of [`super::node_rms`]; nodes that do not determine the
/// six parameters ([`SurfaceError::FitDegenerate`]: fewer than six, all on a
/// circle about the axis, …); a fit that does not converge.
pub fn best_fit_nodes(
    paraboloid: &Paraboloid,
    nodes_m: &[[f64; 3]],
) -> Result<BestFit, SurfaceError> {
    check_paraboloid(paraboloid)?;
    fit(paraboloid, &Samples::nodes(nodes_m)?)
}

/// **Best-fit facet RMS**: [`super::facet_rms`] about the paraboloid that fits
/// the faceted surface best (plan-area weighted, integrated over the facets;
/// the fit as in [`best_fit_nodes`]). The facets' plan areas are the design
/// frame's: the weights stay those of the raw facet RMS. (Weighting by the
/// fitted paraboloid's aperture plane instead would change them by the tilt
/// times the facets' slope: for a tilt of milliradians, the RMS by ≈ 1e-7
/// relative.)
///
/// # Errors
/// The input errors of [`super::facet_rms`]; a degenerate or non-converging
/// fit as in [`best_fit_nodes`].
pub fn best_fit_facets(
    paraboloid: &Paraboloid,
    nodes_m: &[[f64; 3]],
    triangles: &[[usize; 3]],
) -> Result<BestFit, SurfaceError> {
    check_paraboloid(paraboloid)?;
    fit(paraboloid, &Samples::facets(nodes_m, triangles)?)
}

/// The parameters as a vector: apex x, y, z, rotation about x, about y, F.
fn to_vector(p: &PlacedParaboloid) -> [f64; 6] {
    [
        p.apex_m[0],
        p.apex_m[1],
        p.apex_m[2],
        p.rotation_about_x_rad,
        p.rotation_about_y_rad,
        p.focal_length_m,
    ]
}

fn from_vector(x: &[f64; 6]) -> PlacedParaboloid {
    PlacedParaboloid {
        apex_m: [x[0], x[1], x[2]],
        rotation_about_x_rad: x[3],
        rotation_about_y_rad: x[4],
        focal_length_m: x[5],
    }
}

/// Mean square half-path-length error of `samples` about `x`.
fn mean_square(x: &[f64; 6], samples: &Samples) -> f64 {
    let deviation = from_vector(x).deviations();
    let (mut sum, mut weight) = (0.0, 0.0);
    samples.for_each(|p, w| {
        let e = deviation(p).half_path_m;
        sum += w * e * e;
        weight += w;
    });
    sum / weight
}

/// The rotation of parameters `x` and the sines and cosines of its two
/// angles: formed once per Gauss–Newton iteration, not per point.
#[derive(Clone, Copy)]
struct Tilt {
    r: [[f64; 3]; 3],
    sx: f64,
    cx: f64,
    sy: f64,
    cy: f64,
}

impl Tilt {
    fn of(x: &[f64; 6]) -> Tilt {
        let (sx, cx) = x[3].sin_cos();
        let (sy, cy) = x[4].sin_cos();
        Tilt {
            r: from_vector(x).rotation(),
            sx,
            cx,
            sy,
            cy,
        }
    }
}

/// The half-path-length error of point `p_m` about `x` (with its `tilt`)
/// and its gradient in the six parameters.
///
/// With `q = Rᵀ(p − a)`, `s = q_x² + q_y²`, `δ = q_z − s/(4F)` and
/// `w = 4F²/(4F² + s)`, the error is `g = w δ`:
/// `∇_q g = w (−q_x/(2F), −q_y/(2F), 1) − δ w²/(4F²) (2q_x, 2q_y, 0)`,
/// `∂g/∂F = w s/(4F²) + δ w² 2s/(4F³)`, `∂g/∂a = −R ∇_q g`, and
/// `∂g/∂θ = ∇_q g · ∂q/∂θ` through `Rᵀ = R_yᵀ R_xᵀ`.
fn residual_and_gradient(x: &[f64; 6], tilt: &Tilt, p_m: [f64; 3]) -> (f64, [f64; 6]) {
    let Tilt { r, sx, cx, sy, cy } = *tilt;
    let d: [f64; 3] = std::array::from_fn(|k| p_m[k] - x[k]);
    let q: [f64; 3] = std::array::from_fn(|i| r[0][i] * d[0] + r[1][i] * d[1] + r[2][i] * d[2]);
    let f = x[5];
    let s = q[0] * q[0] + q[1] * q[1];
    let delta = q[2] - s / (4.0 * f);
    let w = 4.0 * f * f / (4.0 * f * f + s);
    let g = w * delta;
    let dw_ds = -w * w / (4.0 * f * f);
    let grad_q = [
        -w * q[0] / (2.0 * f) + delta * dw_ds * 2.0 * q[0],
        -w * q[1] / (2.0 * f) + delta * dw_ds * 2.0 * q[1],
        w,
    ];
    let dg_df = w * s / (4.0 * f * f) + delta * w * w * 2.0 * s / (4.0 * f * f * f);
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    // ∂q/∂θx = R_yᵀ (∂R_x/∂θx)ᵀ d, (∂R_x/∂θx)ᵀ = [0 0 0; 0 −sx cx; 0 −cx −sx].
    let u = [0.0, -sx * d[1] + cx * d[2], -cx * d[1] - sx * d[2]];
    let dq_dx = [cy * u[0] - sy * u[2], u[1], sy * u[0] + cy * u[2]];
    // ∂q/∂θy = (∂R_y/∂θy)ᵀ R_xᵀ d, (∂R_y/∂θy)ᵀ = [−sy 0 −cy; 0 0 0; cy 0 −sy].
    let v = [d[0], cx * d[1] + sx * d[2], -sx * d[1] + cx * d[2]];
    let dq_dy = [-sy * v[0] - cy * v[2], 0.0, cy * v[0] - sy * v[2]];
    let r_grad: [f64; 3] = std::array::from_fn(|i| dot(r[i], grad_q));
    (
        g,
        [
            -r_grad[0],
            -r_grad[1],
            -r_grad[2],
            dot(grad_q, dq_dx),
            dot(grad_q, dq_dy),
            dg_df,
        ],
    )
}

/// Solves the 6 × 6 symmetric system `n s = b` scaled to a unit diagonal, by
/// Cholesky; `None` when a pivot falls below [`PIVOT_TOLERANCE`] (parameters
/// the points do not determine).
fn solve_normal(n: &[[f64; 6]; 6], b: &[f64; 6]) -> Option<[f64; 6]> {
    let scale: [f64; 6] = std::array::from_fn(|i| {
        if n[i][i] > 0.0 {
            1.0 / n[i][i].sqrt()
        } else {
            0.0
        }
    });
    let mut l = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..=i {
            let v = n[i][j] * scale[i] * scale[j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                // NaN fails too.
                if v.is_nan() || v <= PIVOT_TOLERANCE {
                    return None;
                }
                l[i][i] = v.sqrt();
            } else {
                l[i][j] = v / l[j][j];
            }
        }
    }
    let mut y = [0.0; 6];
    for i in 0..6 {
        y[i] = (b[i] * scale[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
    }
    let mut s = [0.0; 6];
    for i in (0..6).rev() {
        s[i] = (y[i] - (i + 1..6).map(|k| l[k][i] * s[k]).sum::<f64>()) / l[i][i];
    }
    Some(std::array::from_fn(|i| s[i] * scale[i]))
}

/// Gauss–Newton from the design paraboloid, with step halving.
fn fit(paraboloid: &Paraboloid, samples: &Samples) -> Result<BestFit, SurfaceError> {
    let floor = ROUNDING_FLOOR * f64::EPSILON * samples.scale_m().max(paraboloid.focal_length_m);
    let mut x = to_vector(&PlacedParaboloid::design(paraboloid));
    let mut objective = mean_square(&x, samples);
    let ended = |x: &[f64; 6], iterations, termination| {
        let placed = from_vector(x);
        Ok(BestFit {
            paraboloid: placed,
            rms: rms_about(&placed, samples),
            iterations,
            termination,
        })
    };
    let done = |x: &[f64; 6], iterations| ended(x, iterations, Termination::Converged);
    for iteration in 1..=MAX_ITERATIONS {
        if objective.sqrt() <= floor {
            return done(&x, iteration - 1);
        }
        // Normal equations of the weighted least squares, per unit weight.
        let (mut lower, mut b, mut weight) = ([[0.0; 6]; 6], [0.0; 6], 0.0);
        let tilt = Tilt::of(&x);
        samples.for_each(|p, w| {
            let (g, grad) = residual_and_gradient(&x, &tilt, p);
            weight += w;
            for i in 0..6 {
                b[i] -= w * g * grad[i];
                for j in 0..=i {
                    lower[i][j] += w * grad[i] * grad[j];
                }
            }
        });
        b.iter_mut().for_each(|v| *v /= weight);
        let n: [[f64; 6]; 6] =
            std::array::from_fn(|i| std::array::from_fn(|j| lower[i.max(j)][i.min(j)] / weight));
        let step = solve_normal(&n, &b).ok_or(SurfaceError::FitDegenerate {
            n_samples: samples.len(),
        })?;
        // Mean square of J·step: how far the step moves the surface.
        let moved: f64 = (0..6)
            .map(|i| step[i] * (0..6).map(|j| n[i][j] * step[j]).sum::<f64>())
            .sum();
        let small = moved.max(0.0).sqrt() <= STEP_TOLERANCE * objective.sqrt() + floor;
        let before = objective;
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..MAX_HALVINGS {
            let trial: [f64; 6] = std::array::from_fn(|i| x[i] + t * step[i]);
            let trial_objective = mean_square(&trial, samples);
            if trial[5] > 0.0 && trial_objective <= objective {
                x = trial;
                objective = trial_objective;
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        if small {
            return done(&x, iteration);
        }
        if !accepted {
            // No step lowers the RMS: converged if the step was lost in the
            // rounding of the objective, stuck otherwise.
            if moved <= 1e-8 * objective + floor * floor {
                return done(&x, iteration);
            }
            return ended(&x, iteration, Termination::Stalled);
        }
        if before - objective <= STALL_TOLERANCE * before {
            return done(&x, iteration);
        }
    }
    ended(&x, MAX_ITERATIONS, Termination::MaxIterations)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn some_points() -> Vec<[f64; 3]> {
        // A plan grid over a 10 m disc, off the surface by a few millimetres.
        let p = Paraboloid {
            focal_length_m: 6.0,
        };
        let mut points = Vec::new();
        for i in -5..=5 {
            for j in -5..=5 {
                let (x, y) = (i as f64, j as f64 * 0.9);
                if x * x + y * y <= 25.0 {
                    let wobble = 3e-3 * (0.7 * x + 1.3 * y * y).sin();
                    points.push([x, y, p.z(x, y) + wobble]);
                }
            }
        }
        points
    }

    #[test]
    fn gradient_of_the_half_path_error_matches_central_differences() {
        let x = [0.02, -0.01, 0.03, 0.004, -0.006, 6.1];
        let h = 1e-6;
        for p in some_points().into_iter().step_by(7) {
            let (_, grad) = residual_and_gradient(&x, &Tilt::of(&x), p);
            for k in 0..6 {
                let (mut up, mut down) = (x, x);
                up[k] += h;
                down[k] -= h;
                let fd = (residual_and_gradient(&up, &Tilt::of(&up), p).0
                    - residual_and_gradient(&down, &Tilt::of(&down), p).0)
                    / (2.0 * h);
                // Central differences: O(h²) truncation, O(ε|g|/h) rounding.
                assert!(
                    (fd - grad[k]).abs() <= 1e-8 * (1.0 + grad[k].abs()),
                    "point {p:?}, parameter {k}: {} analytic, {fd} differences",
                    grad[k]
                );
            }
        }
    }

    #[test]
    fn best_fit_is_a_minimum_of_the_half_path_error() {
        let p = Paraboloid {
            focal_length_m: 6.0,
        };
        let points = some_points();
        let samples = Samples::nodes(&points).unwrap();
        let fit = best_fit_nodes(&p, &points).unwrap();
        let x = to_vector(&fit.paraboloid);
        let best = mean_square(&x, &samples);
        assert!((best.sqrt() - fit.rms.half_path_m).abs() <= 1e-15);
        assert!(fit.rms.half_path_m < node_raw(&p, &points));
        // Every parameter nudged either way raises it (stationary and convex
        // there), by about the second-order amount.
        for k in 0..6 {
            let h = if k == 5 { 1e-4 } else { 1e-5 };
            for sign in [-1.0, 1.0] {
                let mut y = x;
                y[k] += sign * h;
                assert!(mean_square(&y, &samples) > best, "parameter {k}, {sign}");
            }
        }
    }

    fn node_raw(p: &Paraboloid, points: &[[f64; 3]]) -> f64 {
        super::super::node_rms(p, points).unwrap().half_path_m
    }

    #[test]
    fn points_on_one_circle_do_not_determine_a_paraboloid() {
        // On a circle about the axis, an apex lift and a focal length change
        // move every point alike.
        let p = Paraboloid {
            focal_length_m: 3.0,
        };
        let ring: Vec<[f64; 3]> = (0..12)
            .map(|k| {
                let (s, c) = (k as f64 * std::f64::consts::FRAC_PI_6).sin_cos();
                [2.0 * c, 2.0 * s, 1.0 / 3.0 + 1e-3]
            })
            .collect();
        assert!(matches!(
            best_fit_nodes(&p, &ring),
            Err(SurfaceError::FitDegenerate { n_samples: 12 })
        ));
        assert!(matches!(
            best_fit_nodes(&p, &ring[..5]),
            Err(SurfaceError::FitDegenerate { .. })
        ));
    }
}
