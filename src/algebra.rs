//! Small dense vector kernels shared by every module (Clarabel keeps its
//! `algebra/` apart from the solvers the same way): dot products and norms of
//! slices and of 3-vectors. Anything larger goes to faer or nalgebra.

/// `aᵀb` of two slices of equal length.
///
/// # Panics
/// In debug builds, when the lengths differ.
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Euclidean norm `‖a‖₂` of a slice.
#[inline]
pub fn norm2(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Largest magnitude `‖a‖∞` of a slice (0 for an empty one), NaN if any
/// entry is NaN: `f64::max` drops a NaN, so a residual with one read as
/// converged (a curved element whose rotation's derivative was NaN at
/// exactly a quarter turn 'converged' without moving).
#[inline]
pub fn norm_inf(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m: f64, v| {
        if m.is_nan() || v.is_nan() {
            f64::NAN
        } else {
            m.max(v.abs())
        }
    })
}

/// Euclidean norm of a 3-vector.
#[inline]
pub fn norm3(v: [f64; 3]) -> f64 {
    let squared = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    if squared.is_finite() && squared >= f64::MIN_POSITIVE {
        squared.sqrt()
    } else {
        // Components beyond 1e154 overflow when squared, below 1e-154
        // underflow: `hypot` scales.
        v[0].hypot(v[1]).hypot(v[2])
    }
}

/// `a − b` of two 3-vectors.
#[inline]
pub fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// A linear-algebra failure in words, for messages a user reads (faer's
/// errors print as `Debug`: `Numeric(NonPositivePivot { index: 3 })`).
pub trait Plain {
    /// What went wrong, in words.
    fn plain(&self) -> String;
}

impl Plain for faer::sparse::FaerError {
    fn plain(&self) -> String {
        match self {
            faer::sparse::FaerError::IndexOverflow => {
                "the problem is too large to index (index overflow)".to_string()
            }
            faer::sparse::FaerError::OutOfMemory => "out of memory".to_string(),
            _ => format!("{self}"),
        }
    }
}

impl Plain for faer::sparse::CreationError {
    fn plain(&self) -> String {
        match self {
            faer::sparse::CreationError::Generic(e) => e.plain(),
            faer::sparse::CreationError::OutOfBounds { row, col } => {
                format!("entry ({row}, {col}) outside the matrix")
            }
        }
    }
}

impl Plain for faer::sparse::linalg::LltError {
    fn plain(&self) -> String {
        match self {
            faer::sparse::linalg::LltError::Numeric(e) => e.plain(),
            faer::sparse::linalg::LltError::Generic(e) => e.plain(),
        }
    }
}

impl Plain for faer::linalg::cholesky::llt::factor::LltError {
    fn plain(&self) -> String {
        match self {
            faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                format!("not positive definite (pivot {index} is not positive)")
            }
        }
    }
}

impl Plain for faer::sparse::linalg::LuError {
    fn plain(&self) -> String {
        match self {
            faer::sparse::linalg::LuError::SymbolicSingular { index } => {
                format!("structurally singular (no pivot at step {index})")
            }
            faer::sparse::linalg::LuError::Generic(e) => e.plain(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn norms_of_a_pythagorean_vector() {
        assert_eq!(norm2(&[3.0, 4.0]), 5.0);
        assert_eq!(norm3([2.0, 3.0, 6.0]), 7.0);
        assert_eq!(norm_inf(&[1.0, -8.0, 2.0]), 8.0);
        assert_eq!(norm_inf(&[]), 0.0);
        assert!(norm_inf(&[1.0, f64::NAN, 2.0]).is_nan());
        assert!(norm_inf(&[f64::NAN, 3.0]).is_nan());
        assert_eq!(dot(&[1.0, 2.0], &[3.0, -1.0]), 1.0);
        assert_eq!(sub3([1.0, 2.0, 3.0], [1.0, 1.0, 1.0]), [0.0, 1.0, 2.0]);
    }
}
