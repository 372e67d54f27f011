//! Numbers from user input in messages and CSV files: shortest round-trip
//! digits, in exponent form outside `[1e-4, 1e15)`, so `1e300` prints as
//! `1e300` and not as 301 digits (Rust's `{}` never uses an exponent, and
//! `{:.N}` pads huge values with all their digits).

/// `x` in the shortest form that parses back to it: `0.08`, `1e300`,
/// `-2.5e-7`, `inf`, `NaN`.
pub fn short(x: impl std::borrow::Borrow<f64>) -> String {
    let x = *x.borrow();
    let a = x.abs();
    if a == 0.0 || !a.is_finite() || (1e-4..1e15).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `[a, b, ...]` with each number in [`short`] form.
pub fn list(xs: &[f64]) -> String {
    let parts: Vec<String> = xs.iter().map(|&x| short(x)).collect();
    format!("[{}]", parts.join(", "))
}

/// The power of two nearest below `1 / m` (`1` for a zero or non-finite
/// `m`): a scale that rounds nothing.
pub fn inverse_power_of_two(m: f64) -> f64 {
    if m > 0.0 && m.is_finite() {
        (-m.log2().ceil()).exp2()
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shortest_round_trip_or_exponent_form() {
        assert_eq!(short(1e300), "1e300");
        assert_eq!(short(-1e300), "-1e300");
        assert_eq!(short(0.08), "0.08");
        assert_eq!(short(1.8), "1.8");
        assert_eq!(short(1e9), "1000000000");
        assert_eq!(short(2.5e-7), "2.5e-7");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(f64::INFINITY), "inf");
        assert_eq!(short(f64::MIN_POSITIVE), "2.2250738585072014e-308");
        for x in [1e300, 0.1 + 0.2, 1.0 / 3.0, 6.02e23, 1e-320] {
            assert_eq!(short(x).parse::<f64>().unwrap(), x);
        }
        assert_eq!(list(&[1.0, 1e300]), "[1, 1e300]");
    }
}
