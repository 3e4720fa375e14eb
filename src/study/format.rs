//! Numbers as a study's text writes them.

/// `1/n` when 1/x is within 1e-9 of an integer n ≥ 1, else x in scientific notation.
pub fn fraction(x: f64) -> String {
    let n = 1.0 / x;
    if n >= 1.0 && (n - n.round()).abs() <= 1e-9 * n {
        format!("1/{}", n.round() as u64)
    } else {
        format!("{x:.4e}")
    }
}
