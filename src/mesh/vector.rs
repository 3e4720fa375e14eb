//! Small vectors as arrays of D components: the products the geometry, the contact rows and the
//! obstacles share, written once.

/// a · b.
pub fn dot<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    (0..D).map(|k| a[k] * b[k]).sum()
}

/// |v|.
pub fn norm<const D: usize>(v: &[f64; D]) -> f64 {
    dot(v, v).sqrt()
}

/// a × b.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
