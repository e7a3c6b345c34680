//! The Newton direction of one iteration: the per-iteration scaling (`Θ̃`,
//! the border `a`, `t = M̂⁻¹ a`), the elimination of `dz`, `dw` and `dλ`
//! down to the bordered normal system, and the FGMRES completion on the rows
//! of the unreduced system the regularised factor solves only inexactly.

use super::data::Program;
use super::error::NormalError;
use super::normal::NormalMatrix;
use super::system::Point;
use crate::algebra::{dot, norm2};
use crate::fdm::NONE;

/// The per-iteration scaling of the reduced system.
pub(super) struct Scaling {
    theta: Vec<f64>,
    /// `1/G_j`.
    g_inv: Vec<f64>,
    /// `Θ̃`.
    theta_tilde: Vec<f64>,
    /// `α`, nonzero on the set.
    alpha: Vec<f64>,
    /// `a = A α`.
    a: Vec<f64>,
    /// `t = M̂⁻¹ a`.
    t: Vec<f64>,
    /// `aᵀ t + γ`.
    schur: f64,
}

/// Right-hand sides of the Newton system.
pub(super) struct Rhs<'a> {
    /// `b − A x`.
    pub(super) rp: &'a [f64],
    /// `−(s e − E x − 1 − w)`.
    pub(super) rw: &'a [f64],
    /// `Eᵀλ − Aᵀy − z`.
    pub(super) rd: &'a [f64],
    /// `1 − eᵀλ`.
    pub(super) rs: f64,
    /// Complementarity: `Z dx + X dz = r_xz`.
    pub(super) rxz: &'a [f64],
    /// `Λ dw + W dλ = r_wλ`.
    pub(super) rwl: &'a [f64],
}

impl Program {
    /// The scaling of the reduced system for `Θ = theta`, `Ω = omega`, with
    /// the normal matrix factored for it.
    pub(super) fn scaling<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        theta: Vec<f64>,
        omega: &[f64],
    ) -> Result<Scaling, NormalError> {
        let p = self.set.len();
        let mut g_inv = vec![0.0; p];
        let mut theta_tilde = theta.clone();
        let mut alpha = vec![0.0; self.m];
        let mut gamma = 0.0;
        for (j, &k) in self.set.iter().enumerate() {
            let l = self.lengths[k];
            let g = l * l * theta[k] + omega[j];
            g_inv[j] = 1.0 / g;
            theta_tilde[k] = theta[k] * omega[j] / g;
            alpha[k] = theta[k] * l / g;
            gamma += 1.0 / g;
        }
        let mut a = vec![0.0; normal.n_rows];
        normal.a_mul(&alpha, &mut a);
        normal.factorize(&theta_tilde)?;
        let mut t = a.clone();
        normal.precondition(&mut t);
        let schur = dot(&a, &t) + gamma;
        Ok(Scaling {
            theta,
            g_inv,
            theta_tilde,
            alpha,
            a,
            t,
            schur,
        })
    }

    /// Solves the bordered system `[M̂ a; aᵀ −γ] [dy; ds] = [r1; r2]` with the
    /// factor `M̂` of `M` by eliminating the border: `dy = M̂⁻¹ r1 − t ds`,
    /// `ds = (aᵀ M̂⁻¹ r1 − r2)/(aᵀ t + γ)`. Linear in the right-hand side: the
    /// preconditioner of [`Program::direction`].
    fn solve_bordered<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        sc: &Scaling,
        r1: &[f64],
        r2: f64,
    ) -> (Vec<f64>, f64) {
        let mut u = r1.to_vec();
        normal.precondition(&mut u);
        let ds = (dot(&sc.a, &u) - r2) / sc.schur;
        let dy = u.iter().zip(&sc.t).map(|(ui, ti)| ui - ti * ds).collect();
        (dy, ds)
    }

    /// Solves the reduced Newton system for a given `θ`-scaling, with
    /// `g = X⁻¹ r_xz − r_d` and `h = r_w + Λ⁻¹ r_wλ` already formed:
    /// returns `(dx, dλ, dy, ds)` with `dx = Θ(Aᵀdy − Eᵀdλ + g)`.
    pub(super) fn solve_reduced<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        sc: &Scaling,
        g: &[f64],
        h: &[f64],
        rp: &[f64],
        rs: f64,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>, f64) {
        // r1 = r_p + A(−Θ̃ g + α h),  r2 = r_s − Σ_j (h_j + ℓ θ g)_j / G_j.
        let mut v: Vec<f64> = g
            .iter()
            .zip(&sc.theta_tilde)
            .map(|(gk, t)| -t * gk)
            .collect();
        let mut r2 = rs;
        for (j, &k) in self.set.iter().enumerate() {
            v[k] += sc.alpha[k] * h[j];
            r2 -= (h[j] + self.lengths[k] * sc.theta[k] * g[k]) * sc.g_inv[j];
        }
        let mut r1 = vec![0.0; normal.n_rows];
        normal.a_mul(&v, &mut r1);
        for (r, p) in r1.iter_mut().zip(rp) {
            *r += p;
        }
        let (dy, ds) = self.solve_bordered(normal, sc, &r1, r2);
        let mut atdy = vec![0.0; self.m];
        normal.at_mul(&dy, &mut atdy);
        let mut dlam = vec![0.0; self.set.len()];
        for (j, &k) in self.set.iter().enumerate() {
            let lt = self.lengths[k] * sc.theta[k];
            dlam[j] = (h[j] + lt * (g[k] + atdy[k]) - ds) * sc.g_inv[j];
        }
        // Room for `dw` after `dx` (the driver's `primal`): no reallocation.
        let mut dx = Vec::with_capacity(self.m + self.set.len());
        dx.extend((0..self.m).map(|k| {
            let et = match self.in_set[k] {
                NONE => 0.0,
                j => self.lengths[k] * dlam[j],
            };
            sc.theta[k] * (atdy[k] - et + g[k])
        }));
        (dx, dlam, dy, ds)
    }

    /// One Newton direction for the current iterate, in the driver's form
    /// (`dx, dw | dz, dλ | ds | dy`): the reduction
    /// ([`Program::direction_once`]) as a right preconditioner of FGMRES on
    /// the rows it solves only up to the factor's regularisation. FGMRES
    /// takes at most `steps` steps and stops at
    /// [`IpmSettings::krylov_tolerance`] of those rows' right-hand side or at
    /// `floor`, whichever is larger (an absolute 2-norm), or when it
    /// stagnates ([`IpmSettings::krylov_stagnation`]); returns the
    /// direction and the 2-norm of its residual in those rows (0 where the
    /// reduction is taken as it is: `steps` 0, or the 3-D problem).
    ///
    /// [`IpmSettings::krylov_tolerance`]: super::settings::IpmSettings::krylov_tolerance
    /// [`IpmSettings::krylov_stagnation`]: super::settings::IpmSettings::krylov_stagnation
    #[allow(clippy::too_many_arguments)]
    pub(super) fn direction<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        sc: &Scaling,
        x: &[f64],
        z: &[f64],
        w: &[f64],
        lam: &[f64],
        rhs: &Rhs,
        floor: f64,
        steps: usize,
    ) -> (Point, f64) {
        let (m, p, n) = (self.m, self.set.len(), normal.n_rows);
        let mut d = self.direction_once(normal, sc, x, z, w, lam, rhs);
        // Measured limitation: on the full 3-D problem, whose `A` has dependent
        // rows (mechanisms), FGMRES makes the small test scenes stall at
        // reduced accuracy; there the reduction alone converges. The plan
        // problem (D = 2, a triangulated plan net) is where FGMRES is needed.
        if D == 3 || steps == 0 {
            return (d, 0.0);
        }
        // Rows the reduction solves only up to the factor's regularisation:
        // A dx = r_p, dw + E dx − ds e = −r_w, eᵀdλ = r_s. The other rows hold
        // to rounding for any right-hand side, so FGMRES runs on these.
        let len = n + p + 1;
        let mut f = vec![0.0; len];
        f[..n].copy_from_slice(rhs.rp);
        for j in 0..p {
            f[n + j] = -rhs.rw[j];
        }
        f[n + p] = rhs.rs;
        let f_norm = norm2(&f);
        let mut kd = vec![0.0; len];
        self.krylov_rows(normal, &d, &mut kd);
        let mut r: Vec<f64> = f.iter().zip(&kd).map(|(a, b)| a - b).collect();
        let beta = norm2(&r);
        let tolerance = (self.settings.krylov_tolerance * f_norm).max(floor);
        if beta.is_nan() || beta <= tolerance {
            return (d, beta);
        }
        let zero_m = vec![0.0; m];
        let zero_p = vec![0.0; p];
        r.iter_mut().for_each(|v| *v /= beta);
        let mut basis = vec![r];
        let mut zs: Vec<Point> = Vec::new();
        let mut h: Vec<Vec<f64>> = Vec::new();
        let (mut cs, mut sn): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
        let mut g = vec![beta];
        let mut residual = beta;
        let mut rw = vec![0.0; p];
        // The residual before each step: `β`, then after steps 0, 1, …
        let mut residuals = vec![beta];
        for it in 0..steps {
            let v = &basis[it];
            rw.iter_mut().zip(&v[n..n + p]).for_each(|(a, b)| *a = -b);
            let zj = self.direction_once(
                normal,
                sc,
                x,
                z,
                w,
                lam,
                &Rhs {
                    rp: &v[..n],
                    rw: &rw,
                    rd: &zero_m,
                    rs: v[n + p],
                    rxz: &zero_m,
                    rwl: &zero_p,
                },
            );
            let mut wv = vec![0.0; len];
            self.krylov_rows(normal, &zj, &mut wv);
            let mut col = vec![0.0; it + 2];
            for (i, vi) in basis.iter().enumerate() {
                let hij = dot(&wv, vi);
                col[i] = hij;
                wv.iter_mut().zip(vi).for_each(|(a, b)| *a -= hij * b);
            }
            let wn = norm2(&wv);
            col[it + 1] = wn;
            for i in 0..it {
                let (c, s_) = (cs[i], sn[i]);
                let (a, b) = (col[i], col[i + 1]);
                col[i] = c * a + s_ * b;
                col[i + 1] = -s_ * a + c * b;
            }
            let rho = col[it].hypot(col[it + 1]);
            let (c, s_) = if rho == 0.0 {
                (1.0, 0.0)
            } else {
                (col[it] / rho, col[it + 1] / rho)
            };
            col[it] = rho;
            col[it + 1] = 0.0;
            cs.push(c);
            sn.push(s_);
            g.push(-s_ * g[it]);
            g[it] *= c;
            h.push(col);
            zs.push(zj);
            let res = g[it + 1].abs();
            residual = res;
            if res <= tolerance || wn == 0.0 || !res.is_finite() {
                break;
            }
            // Stagnated: two steps lowered the residual too little.
            residuals.push(res);
            if it >= 2 && res > self.settings.krylov_stagnation * residuals[it - 1] {
                break;
            }
            wv.iter_mut().for_each(|a| *a /= wn);
            basis.push(wv);
        }
        // Back substitution for the coefficients, then d += Σ y_i z_i.
        let k = zs.len();
        let mut y = vec![0.0; k];
        for i in (0..k).rev() {
            let mut v = g[i];
            for j in i + 1..k {
                v -= h[j][i] * y[j];
            }
            y[i] = v / h[i][i];
        }
        for (zi, yi) in zs.iter().zip(&y) {
            d.add_scaled(*yi, zi);
        }
        (d, residual)
    }

    /// The rows of the Newton system that FGMRES works on, applied to `d`:
    /// `(A dx, dw + E dx − ds e, eᵀdλ)`.
    fn krylov_rows<const D: usize>(&self, normal: &NormalMatrix<D>, d: &Point, out: &mut [f64]) {
        let (m, n, p) = (self.m, normal.n_rows, self.set.len());
        let (dx, dw) = d.primal.split_at(m);
        normal.a_mul(dx, &mut out[..n]);
        for (j, &k) in self.set.iter().enumerate() {
            out[n + j] = dw[j] + self.lengths[k] * dx[k] - d.free_primal[0];
        }
        out[n + p] = d.dual[m..].iter().sum();
    }

    /// One solve of the Newton system through its reduction.
    #[allow(clippy::too_many_arguments)]
    fn direction_once<const D: usize>(
        &self,
        normal: &mut NormalMatrix<D>,
        sc: &Scaling,
        x: &[f64],
        z: &[f64],
        w: &[f64],
        lam: &[f64],
        rhs: &Rhs,
    ) -> Point {
        let g: Vec<f64> = (0..self.m).map(|k| rhs.rxz[k] / x[k] - rhs.rd[k]).collect();
        let h: Vec<f64> = (0..self.set.len())
            .map(|j| rhs.rw[j] + rhs.rwl[j] / lam[j])
            .collect();
        let (mut dx, dlam, dy, ds) = self.solve_reduced(normal, sc, &g, &h, rhs.rp, rhs.rs);
        let mut dz = Vec::with_capacity(self.m + self.set.len());
        dz.extend((0..self.m).map(|k| (rhs.rxz[k] - z[k] * dx[k]) / x[k]));
        let dw = (0..self.set.len()).map(|j| (rhs.rwl[j] - w[j] * dlam[j]) / lam[j]);
        dx.extend(dw);
        dz.extend(dlam);
        Point {
            primal: dx,
            dual: dz,
            free_primal: vec![ds],
            free_dual: dy,
        }
    }
}
