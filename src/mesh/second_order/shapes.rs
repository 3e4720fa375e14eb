//! The second-order shape functions on the reference cells (docs/method.md §19.1), each node's
//! function read off its reference coordinates (mod.rs): Lagrange P2 on triangles and
//! tetrahedra (λ(2λ − 1) at a corner, 4λᵢλⱼ at a midside), tensor Lagrange Q2 on the 9-node
//! quadrangle and the 27-node hexahedron, serendipity on the 8-node quadrangle and the 20-node
//! hexahedron, P2 × Q2 on the 18-node prism and its serendipity reduction on the 15-node one.
//! Values and ξ-gradients come together through [`Vg`], a value with its gradient whose products
//! follow the product rule, so each function is written once, as its formula.

use super::reference_nodes;
use crate::mesh::kind::CellKind;
use std::ops::{Add, Mul, Sub};

/// A function's value and its gradient in (ξ, η, ζ) at one point.
#[derive(Clone, Copy, Debug)]
struct Vg {
    v: f64,
    g: [f64; 3],
}

impl Vg {
    fn constant(v: f64) -> Vg {
        Vg { v, g: [0.0; 3] }
    }

    /// The reference coordinate k at ξ.
    fn coordinate(xi: [f64; 3], k: usize) -> Vg {
        let mut g = [0.0; 3];
        g[k] = 1.0;
        Vg { v: xi[k], g }
    }
}

impl Add for Vg {
    type Output = Vg;
    fn add(self, o: Vg) -> Vg {
        Vg {
            v: self.v + o.v,
            g: std::array::from_fn(|k| self.g[k] + o.g[k]),
        }
    }
}

impl Sub for Vg {
    type Output = Vg;
    fn sub(self, o: Vg) -> Vg {
        self + o * -1.0
    }
}

impl Mul for Vg {
    type Output = Vg;
    // the product rule: (fg)' = f'g + fg'
    #[allow(clippy::suspicious_arithmetic_impl)]
    fn mul(self, o: Vg) -> Vg {
        Vg {
            v: self.v * o.v,
            g: std::array::from_fn(|k| self.g[k] * o.v + self.v * o.g[k]),
        }
    }
}

impl Mul<f64> for Vg {
    type Output = Vg;
    fn mul(self, c: f64) -> Vg {
        Vg {
            v: self.v * c,
            g: self.g.map(|d| d * c),
        }
    }
}

/// The 1D quadratic Lagrange function of the node at r ∈ {−1, 0, 1} on [−1, 1].
fn lagrange(r: f64, t: Vg) -> Vg {
    let one = Vg::constant(1.0);
    if r == 0.0 {
        one - t * t
    } else {
        t * (t + Vg::constant(r)) * 0.5
    }
}

/// The barycentric coordinates (λ₀ = 1 − Σ, λ_k = ξ_k) of the first `dim` coordinates.
fn barycentric(xi: [f64; 3], dim: usize) -> [Vg; 4] {
    let mut l = [Vg::constant(0.0); 4];
    l[0] = Vg::constant(1.0);
    for k in 0..dim {
        l[k + 1] = Vg::coordinate(xi, k);
        l[0] = l[0] - l[k + 1];
    }
    l
}

/// The barycentric coordinates of a reference node: the corners it is on.
fn node_barycentric(r: &[f64; 3], dim: usize) -> [f64; 4] {
    let mut m = [0.0; 4];
    m[0] = 1.0 - r[..dim].iter().sum::<f64>();
    m[1..=dim].copy_from_slice(&r[..dim]);
    m
}

/// The corners a simplex node with barycentric coordinates `m` lies between: (i, None) at corner
/// i (λᵢ = 1), (i, Some(j)) at the midpoint of ij (λᵢ = λⱼ = ½).
fn support(m: &[f64; 4]) -> (usize, Option<usize>) {
    let mut on = (0..4).filter(|&i| m[i] > 0.25);
    let i = on.next().expect("a node has a positive barycentric coordinate");
    (i, on.next())
}

/// The P2 function of the simplex node with barycentric coordinates `m`.
fn simplex_p2(m: &[f64; 4], l: &[Vg; 4]) -> Vg {
    match support(m) {
        (i, None) => l[i] * (l[i] * 2.0 - Vg::constant(1.0)),
        (i, Some(j)) => l[i] * l[j] * 4.0,
    }
}

/// The values and ξ-gradients of a second-order kind's shape functions at ξ, written into the
/// first [`CellKind::nodes`] entries of `v` and `g`.
pub(crate) fn second_order(kind: CellKind, xi: [f64; 3], v: &mut [f64], g: &mut [[f64; 3]]) {
    let x = |k| Vg::coordinate(xi, k);
    let one = Vg::constant(1.0);
    for (a, r) in reference_nodes(kind).iter().enumerate() {
        let n = match kind {
            CellKind::Tri6 => simplex_p2(&node_barycentric(r, 2), &barycentric(xi, 2)),
            CellKind::Tet10 => simplex_p2(&node_barycentric(r, 3), &barycentric(xi, 3)),
            CellKind::Quad9 => lagrange(r[0], x(0)) * lagrange(r[1], x(1)),
            CellKind::Hex27 => lagrange(r[0], x(0)) * lagrange(r[1], x(1)) * lagrange(r[2], x(2)),
            CellKind::Quad8 | CellKind::Hex20 => {
                let d = kind.dim();
                // (1 + r_k ξ_k) over the directions where the node is at ±1
                let mut product = one;
                for k in 0..d {
                    if r[k] != 0.0 {
                        product = product * (one + x(k) * r[k]) * 0.5;
                    }
                }
                match (0..d).find(|&k| r[k] == 0.0) {
                    // a midside: (1 − ξ_k²) along its edge
                    Some(k) => product * (one - x(k) * x(k)),
                    // a corner: Π(1 + r_k ξ_k)/2^d (Σ r_k ξ_k − (d − 1))
                    None => {
                        let mut s = Vg::constant(1.0 - d as f64);
                        for k in 0..d {
                            s = s + x(k) * r[k];
                        }
                        product * s
                    }
                }
            }
            CellKind::Prism18 => simplex_p2(&node_barycentric(r, 2), &barycentric(xi, 2)) * lagrange(r[2], x(2)),
            CellKind::Prism15 => {
                let m = node_barycentric(r, 2);
                let l = barycentric(xi, 2);
                let z = x(2);
                let bubble = one - z * z;
                match (support(&m), r[2]) {
                    // a corner: ½λ(2λ − 1)(1 + r_ζ ζ) − ½λ(1 − ζ²)
                    ((i, None), rz) if rz != 0.0 => {
                        l[i] * (l[i] * 2.0 - one) * (one + z * rz) * 0.5 - l[i] * bubble * 0.5
                    }
                    // the midpoint of a vertical edge: λ(1 − ζ²)
                    ((i, None), _) => l[i] * bubble,
                    // the midpoint of a triangle's edge: 2λᵢλⱼ(1 + r_ζ ζ)
                    ((i, Some(j)), rz) => l[i] * l[j] * (one + z * rz) * 2.0,
                }
            }
            _ => unreachable!("{kind:?} is a first-order kind"),
        };
        v[a] = n.v;
        g[a] = n.g;
    }
}
