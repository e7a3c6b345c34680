//! How a structure as built differs from its design ([`Perturbation`]):
//! cables cut to other lengths or of another stiffness, truss rods with a
//! free stretch (a temperature change, a tube cut long), hinge bodies built
//! off their place. A thermal load case and a manufacturing-tolerance sample
//! are each one perturbation; the assembly ([`super::assemble`]) takes any.

use super::VerifyError;

/// Deviations of the structure as built from its design; `None` is none.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Perturbation {
    /// Factor on each cable's unstressed (cut) length, network order: n_edges.
    pub cable_length_factors: Option<Vec<f64>>,
    /// Factor on each cable's axial stiffness EA: n_edges.
    pub cable_stiffness_factors: Option<Vec<f64>>,
    /// Free stretch of each truss rod (the frame's build order:
    /// [`crate::scene::RodProperties`]), `[length factor, section factor]`
    /// ([`crate::mechanics::ModelBuilder::stretch_rods`]): 5N.
    pub rod_stretch: Option<Vec<[f64; 2]>>,
    /// Displacement of each hinge body (top hinges, then bottom), m: 2N × 3.
    pub hinge_offsets_m: Option<Vec<[f64; 3]>>,
}

impl Perturbation {
    /// The design as designed.
    pub fn none() -> Self {
        Perturbation::default()
    }

    /// True when the perturbation changes nothing it could.
    pub fn is_none(&self) -> bool {
        self == &Perturbation::default()
    }

    /// Checks the sizes against `cables`, `rods` and `hinges` and the values
    /// (finite, factors positive).
    ///
    /// # Errors
    /// [`VerifyError::Perturbation`] naming the field.
    pub fn check(&self, cables: usize, rods: usize, hinges: usize) -> Result<(), VerifyError> {
        let bad =
            |field: &'static str, reason: String| Err(VerifyError::Perturbation { field, reason });
        let factors = |field: &'static str, v: &Option<Vec<f64>>, n: usize| match v {
            Some(v) if v.len() != n => bad(field, format!("{} values for {n} items", v.len())),
            Some(v) if v.iter().any(|f| !(f.is_finite() && *f > 0.0)) => {
                bad(field, "a factor is not finite and positive".into())
            }
            _ => Ok(()),
        };
        factors("cable_length_factors", &self.cable_length_factors, cables)?;
        factors(
            "cable_stiffness_factors",
            &self.cable_stiffness_factors,
            cables,
        )?;
        let flat = self.rod_stretch.as_ref().map(|v| v.concat());
        match &self.rod_stretch {
            Some(v) if v.len() != rods => {
                return bad("rod_stretch", format!("{} values for {rods} rods", v.len()))
            }
            _ => factors("rod_stretch", &flat, 2 * rods)?,
        }
        match &self.hinge_offsets_m {
            Some(v) if v.len() != hinges => bad(
                "hinge_offsets_m",
                format!("{} values for {hinges} hinges", v.len()),
            ),
            Some(v) if v.iter().flatten().any(|c| !c.is_finite()) => {
                bad("hinge_offsets_m", "an offset is not finite".into())
            }
            _ => Ok(()),
        }
    }
}
