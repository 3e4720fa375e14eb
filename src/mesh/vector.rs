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

/// |a − b|.
pub fn distance<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    (0..D).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// a × b (nalgebra's).
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    nalgebra::Vector3::from(a).cross(&nalgebra::Vector3::from(b)).into()
}
