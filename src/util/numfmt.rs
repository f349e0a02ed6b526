//! Numbers in messages: a value the user gave (or one derived from it)
//! printed in a short form whatever its magnitude. `{}` of an `f64` never
//! uses an exponent, so `--max-error 1e-300` printed a 397-character line
//! and a Frame Time of 1e-30 s "999999999999999879147136483328.0000 frames
//! per second". Tested in tests/it/hostile/verbs.rs
//! (`extreme_numbers_print_short_in_messages`).

use std::fmt;

/// An `f64` for a message: plain decimals (at most 4 after the point,
/// trailing zeros dropped) for magnitudes in [10⁻³, 10⁷), otherwise
/// scientific with at most 4 significant digits ("1e-300", "1.235e30");
/// `inf` and `NaN` as Rust writes them. At most 13 characters for any
/// finite value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Short(pub f64);

impl fmt::Display for Short {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if !x.is_finite() || x == 0.0 {
            return write!(f, "{}", if x == 0.0 { 0.0 } else { x });
        }
        let a = x.abs();
        if (1e-3..1e7).contains(&a) {
            let s = format!("{x:.4}");
            let s = s.trim_end_matches('0').trim_end_matches('.');
            // Rounding to 4 decimals can reach 10⁷ (9999999.99996): still
            // short (at most 8 digits before the point).
            return f.write_str(s);
        }
        let s = format!("{x:.3e}");
        let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        write!(f, "{mantissa}e{exp}")
    }
}
