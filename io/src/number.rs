//! Numbers written so that they read back to the same `f64`.
//!
//! Rust's `Display` for `f64` prints the shortest decimal that round-trips, but
//! never in exponent form (so `1e-300` would take 300 digits); `LowerExp` is
//! shortest too. [`shortest`] takes the plain form for magnitudes in
//! `[1e-5, 1e16)` (and zero) and the exponent form otherwise.

use std::fmt::Write;

/// Appends the shortest round-trip form of `x` to `out`.
pub(crate) fn push_shortest(out: &mut String, x: f64) {
    let a = x.abs();
    // Writing into a String cannot fail.
    let _ =
        if a == 0.0 || (1e-5..1e16).contains(&a) || !x.is_finite() { write!(out, "{x}") } else { write!(out, "{x:e}") };
}

/// The shortest round-trip form of `x`.
#[cfg(test)]
pub(crate) fn shortest(x: f64) -> String {
    let mut s = String::new();
    push_shortest(&mut s, x);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_stays_short() {
        for x in [0.0, -0.0, 1.0, 0.1, 29.719, 1e-9, 6.02e23, -1.0 / 3.0, f64::MIN_POSITIVE, f64::MAX, 1e-5, 1e16] {
            let s = shortest(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{x} -> {s}");
            assert!(s.len() <= 24, "{x} -> {s}");
        }
        assert_eq!(shortest(0.2), "0.2");
        assert_eq!(shortest(1e-9), "1e-9");
    }
}
