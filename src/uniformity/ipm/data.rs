//! The problem data: the ratio LP as its callers state it ([`RatioLp`], `D`
//! coordinates per free node) and its checked kernel form (`Program`: the set,
//! the lengths and the shifted lower bounds), with the settings it is solved
//! with.

use super::error::IpmError;
use super::settings::IpmSettings;
use crate::fdm::NONE;

/// The data of the ratio LP in `D` coordinates per free node.
#[derive(Debug, Clone)]
pub(crate) struct RatioLp<const D: usize> {
    /// Number of free nodes (rows of `A`: `D` per free node).
    pub n_free: usize,
    /// Free indices of each cable's ends (`None` for a fixed end): n_cables.
    pub ends: Vec<[Option<usize>; 2]>,
    /// Edge vectors `x_i − x_j` in the `D` coordinates, m: n_cables.
    pub vectors: Vec<[f64; D]>,
    /// Lengths `ℓ_k` whose product with `q_k` is the tension, m: n_cables.
    pub lengths: Vec<f64>,
    /// Whether each cable is in the uniformity set: n_cables.
    pub in_set: Vec<bool>,
    /// Smallest tension of a cable outside the set, per unit smallest set tension.
    pub min_other_tension: f64,
}

/// The LP's data in the kernel's form: the set, lengths, bounds, and the
/// settings.
pub(super) struct Program {
    pub(super) m: usize,
    /// Cables of the set, `S_j`.
    pub(super) set: Vec<usize>,
    /// Set index of each cable, or `NONE`.
    pub(super) in_set: Vec<usize>,
    pub(super) lengths: Vec<f64>,
    pub(super) lower: Vec<f64>,
    pub(super) settings: IpmSettings,
}

impl Program {
    /// The kernel form of `lp`, or why it is not a ratio LP the method solves
    /// (a tension floor that is not positive, an empty set).
    ///
    /// # Panics
    /// If the per-cable vectors of `lp` differ in length.
    pub(super) fn new<const D: usize>(
        lp: &RatioLp<D>,
        settings: IpmSettings,
    ) -> Result<Self, IpmError> {
        let m = lp.lengths.len();
        assert!(
            lp.ends.len() == m && lp.vectors.len() == m && lp.in_set.len() == m,
            "ratio LP: per-cable data of different lengths"
        );
        let f = lp.min_other_tension;
        if !(f.is_finite() && f > 0.0) {
            return Err(IpmError::MinTensionFraction { value: f });
        }
        let set: Vec<usize> = (0..m).filter(|&k| lp.in_set[k]).collect();
        if set.is_empty() {
            return Err(IpmError::EmptySet);
        }
        let mut in_set = vec![NONE; m];
        for (j, &k) in set.iter().enumerate() {
            in_set[k] = j;
        }
        let lower: Vec<f64> = (0..m)
            .map(|k| if lp.in_set[k] { 1.0 } else { f } / lp.lengths[k])
            .collect();
        Ok(Program {
            m,
            set,
            in_set,
            lengths: lp.lengths.clone(),
            lower,
            settings,
        })
    }
}
