//! Numbers as people and tables read them: plain decimals where they fit,
//! scientific notation beyond ([`decimal`], [`readable`]).

/// `v` in plain decimal with at most `digits` significant digits, trailing
/// zeros dropped (`41.65`, `0.002731`, `12.5`): no exponent where a person,
/// or a cutting sheet, reads one badly.
pub fn decimal(v: f64, digits: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (digits as i32 - 1 - v.abs().log10().floor() as i32).clamp(0, 30) as usize;
    without_trailing_zeros(&format!("{v:.decimals$}"))
}

/// `v` for a reader and for a table: [`decimal`] from 1e-3 to 1e6 in
/// magnitude, scientific beyond (`2.134e-7`), at most `digits` significant
/// digits either way; non-finite values as Rust writes them (`NaN`, `inf`).
pub fn readable(v: f64, digits: usize) -> String {
    if v == 0.0 || !v.is_finite() || (1e-3..1e6).contains(&v.abs()) {
        decimal(v, digits)
    } else {
        let text = format!("{v:.*e}", digits.saturating_sub(1));
        let (mantissa, exponent) = text.split_once('e').expect("scientific notation");
        format!("{}e{exponent}", without_trailing_zeros(mantissa))
    }
}

/// `12.500` → `12.5`, `3.000` → `3`; a number without a point is kept.
fn without_trailing_zeros(text: &str) -> String {
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_as_written_in_plain_decimal_where_a_reader_wants_it() {
        assert_eq!(decimal(41.4916, 4), "41.49");
        assert_eq!(decimal(12.5, 13), "12.5");
        assert_eq!(decimal(100.0, 13), "100");
        assert_eq!(decimal(-0.002_731_04, 4), "-0.002731");
        assert_eq!(readable(2.134_04e-7, 4), "2.134e-7");
        assert_eq!(readable(1e-7, 7), "1e-7");
        assert_eq!(readable(2.5e9, 3), "2.5e9");
        assert_eq!(readable(0.0, 7), "0");
        // Every digit kept is a digit read back.
        for v in [
            std::f64::consts::PI * 1e-9,
            2.692_821_634_6,
            6.513_434_591_361e1,
        ] {
            let back: f64 = readable(v, 11).parse().unwrap();
            assert!((back / v - 1.0).abs() < 1e-10, "{v} → {back}");
        }
    }
}
