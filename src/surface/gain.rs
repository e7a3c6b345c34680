//! Ruze's gain loss: what an RMS half-path-length error costs at a frequency.

use super::SurfaceError;

/// Speed of light in vacuum, m/s (exact, SI).
pub const SPEED_OF_LIGHT_M_PER_S: f64 = 299_792_458.0;

fn check(half_path_rms_m: f64, frequency_hz: f64) -> Result<(), SurfaceError> {
    if !(half_path_rms_m.is_finite() && half_path_rms_m >= 0.0) {
        return Err(SurfaceError::HalfPathRms {
            rms_m: half_path_rms_m,
        });
    }
    if !(frequency_hz.is_finite() && frequency_hz > 0.0) {
        return Err(SurfaceError::Frequency { frequency_hz });
    }
    Ok(())
}

/// Ruze's gain ratio `G/G₀ = exp(−(4π ε/λ)²)` of a reflector whose RMS
/// half-path-length error is `ε = half_path_rms_m` (random, spatially
/// correlated over regions small against the aperture; Ruze, Proc. IEEE 54,
/// 1966), at `λ = c/frequency_hz`.
///
/// # Errors
/// `ε` negative or not finite, a frequency that is not positive.
pub fn ruze_gain_ratio(half_path_rms_m: f64, frequency_hz: f64) -> Result<f64, SurfaceError> {
    check(half_path_rms_m, frequency_hz)?;
    let phase =
        4.0 * std::f64::consts::PI * half_path_rms_m * frequency_hz / SPEED_OF_LIGHT_M_PER_S;
    Ok((-phase * phase).exp())
}

/// The gain Ruze's formula loses, dB, as a positive number:
/// `−10 log₁₀(G/G₀) = (10/ln 10)(4π ε/λ)² ≈ 4.343 (4π ε/λ)²`.
///
/// # Errors
/// As [`ruze_gain_ratio`].
pub fn ruze_gain_loss_db(half_path_rms_m: f64, frequency_hz: f64) -> Result<f64, SurfaceError> {
    check(half_path_rms_m, frequency_hz)?;
    let phase =
        4.0 * std::f64::consts::PI * half_path_rms_m * frequency_hz / SPEED_OF_LIGHT_M_PER_S;
    Ok(10.0 / std::f64::consts::LN_10 * phase * phase)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ruze_loss_follows_the_formula() {
        // ε = λ/(4π): the exponent is −1, G/G₀ = 1/e, 10 log₁₀ e dB lost.
        let f = 2.2e9;
        let lambda = SPEED_OF_LIGHT_M_PER_S / f;
        let eps = lambda / (4.0 * std::f64::consts::PI);
        let ratio = ruze_gain_ratio(eps, f).unwrap();
        assert!((ratio - (-1.0f64).exp()).abs() < 1e-15, "{ratio}");
        let loss = ruze_gain_loss_db(eps, f).unwrap();
        assert!(
            (loss - 10.0 * std::f64::consts::E.log10()).abs() < 1e-13,
            "{loss}"
        );
        // ε = λ/16: (π/4)² = 0.617 of a neper, 2.68 dB.
        let loss = ruze_gain_loss_db(lambda / 16.0, f).unwrap();
        let expected = -10.0 * (-(std::f64::consts::PI / 4.0).powi(2)).exp().log10();
        assert!(
            (loss - expected).abs() < 1e-13 && (loss - 2.68).abs() < 5e-3,
            "{loss}"
        );
        // Quadratic in ε and in f, and the two functions agree.
        let (e, g) = (1.5e-3, 8.4e9);
        let l1 = ruze_gain_loss_db(e, g).unwrap();
        assert!((ruze_gain_loss_db(2.0 * e, g).unwrap() - 4.0 * l1).abs() < 1e-12 * l1);
        assert!((ruze_gain_loss_db(e, 2.0 * g).unwrap() - 4.0 * l1).abs() < 1e-12 * l1);
        let from_ratio = -10.0 * ruze_gain_ratio(e, g).unwrap().log10();
        assert!((from_ratio - l1).abs() < 1e-12 * l1);
        assert_eq!(ruze_gain_loss_db(0.0, g).unwrap(), 0.0);
    }

    #[test]
    fn ruze_rejects_what_is_not_a_length_or_a_frequency() {
        assert!(matches!(
            ruze_gain_loss_db(-1e-3, 1e9),
            Err(SurfaceError::HalfPathRms { .. })
        ));
        assert!(matches!(
            ruze_gain_ratio(f64::NAN, 1e9),
            Err(SurfaceError::HalfPathRms { .. })
        ));
        assert!(matches!(
            ruze_gain_loss_db(1e-3, 0.0),
            Err(SurfaceError::Frequency { .. })
        ));
        assert!(matches!(
            ruze_gain_ratio(1e-3, f64::INFINITY),
            Err(SurfaceError::Frequency { .. })
        ));
    }
}
