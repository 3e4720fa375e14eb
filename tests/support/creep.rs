//! The asphalt concrete of examples/gallery/asphalt, the creep compliance of a Prony series, and
//! the cube of a uniaxial creep test: the exact solutions and the test bodies of docs/method.md
//! §20's tests and benchmark (tests/common.rs and benches/time_scales.rs include this file).
#![allow(dead_code)]

use hvi::mesh::structured::{block, SolidShape};
use hvi::mesh::{Facet, Mesh, PhysicalGroup};

/// The faces of group `from` whose nodes all satisfy `keep`, as a new group `name` (a side of a
/// structured block or rectangle).
pub fn sub_group<const D: usize>(mesh: &mut Mesh<D>, from: &str, name: &str, keep: impl Fn(&[f64; D]) -> bool) {
    let facets: Vec<Facet> = mesh
        .groups
        .iter()
        .find(|g| g.name.as_deref() == Some(from))
        .unwrap()
        .facets
        .iter()
        .filter(|f| f.nodes().iter().all(|&p| keep(&mesh.points[p])))
        .cloned()
        .collect();
    let tag = 100 + mesh.groups.len() as i32;
    mesh.groups.push(PhysicalGroup {
        dim: (D - 1) as u8,
        tag,
        name: Some(name.into()),
        facets,
        cells: vec![],
        nodes: vec![],
    });
}

/// The unit cube (one hexahedron) of a uniaxial test: the block's groups and X1 (x = 1), Z0 (z = 0).
pub fn creep_cube() -> Mesh<3> {
    let mut m = block([1.0; 3], [1, 1, 1], SolidShape::Hex);
    sub_group(&mut m, "Gamma2", "X1", |p| (p[0] - 1.0).abs() < 1e-12);
    sub_group(&mut m, "Sides", "Z0", |p| p[2].abs() < 1e-12);
    m
}

/// The cube on rollers (u_x = 0 on x = 0, u_y = 0 on y = 0, u_z = 0 on z = 0) pulled by the stress
/// σ(t) (an expression of t) on x = 1: uniaxial stress, ε_xx(t) = (σ * dD)(t) whatever the steps
/// (the fields are linear, exact on the cell). `material` and `time` are the scene's sections.
pub fn uniaxial_scene(material: &str, time: &str, stress: &str) -> String {
    format!(
        "{material}[time]\n{time}\n\
         [[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\"]\n\
         [[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"y\"]\n\
         [[dirichlet]]\ngroup = \"Z0\"\ncomponents = [\"z\"]\n\
         [[traction]]\ngroup = \"X1\"\nvalue = [\"{stress}\", \"0\", \"0\"]\n"
    )
}

/// (E_i [MPa], ρ_i [s]) of the asphalt concrete of examples/gallery/asphalt: Gibson, Schwartz,
/// Schapery & Witczak, Transportation Research Record 1860 (2003) 3–15, as transcribed in the public
/// data file `relaxation-modulus/Gibson2003.csv` of github.com/rubensocj/viscomodule (E∞ = 412.8 MPa
/// from the same repository; the transcription is not checked against the paper here).
pub const ASPHALT: [(f64, f64); 12] = [
    (1.430e1, 1.500e7),
    (3.210e1, 8.005e5),
    (7.420e1, 4.272e4),
    (1.796e2, 2.280e3),
    (4.588e2, 1.217e2),
    (1.232e3, 6.493e0),
    (2.956e3, 3.465e-1),
    (5.286e3, 1.849e-2),
    (6.531e3, 9.869e-4),
    (5.727e3, 5.267e-5),
    (3.848e3, 2.811e-6),
    (2.160e3, 1.500e-7),
];
/// E∞ [MPa] and the Poisson's ratio held of the asphalt.
pub const ASPHALT_E_INF: f64 = 412.8;
pub const ASPHALT_NU: f64 = 0.35;

/// The creep compliance of a Prony relaxation function f(t) = f∞ + Σ f_i e^{−t/ρ_i}: the inverse of
/// its Carson transform F(s) = f∞ + Σ f_i s/(s + 1/ρ_i), D(t) = 1/f∞ + Σ_j e^{s_j t}/(s_j F′(s_j)) over
/// the roots s_j < 0 of F, which interlace its poles −1/ρ_i (the exact solutions of docs/method.md
/// §20's tests; computed here from the series, independently of hvi).
pub struct Compliance {
    long_term: f64,
    /// (1/(s_j F′(s_j)), s_j).
    terms: Vec<(f64, f64)>,
}

impl Compliance {
    /// Of f(t) = `long_term` + Σ f_i e^{−t/ρ_i} for `terms` (f_i, ρ_i): one root of F in each gap
    /// between the poles and one between the slowest pole and 0, by bisection in log|s|.
    pub fn of(long_term: f64, terms: &[(f64, f64)]) -> Self {
        let f = |s: f64| long_term + terms.iter().map(|(fi, rho)| fi * s / (s + 1.0 / rho)).sum::<f64>();
        let df = |s: f64| {
            terms
                .iter()
                .map(|(fi, rho)| fi / rho / (s + 1.0 / rho).powi(2))
                .sum::<f64>()
        };
        let mut poles: Vec<f64> = terms.iter().map(|(_, rho)| 1.0 / rho).collect();
        poles.sort_by(f64::total_cmp);
        let mut roots = Vec::new();
        for i in 0..poles.len() {
            // s in (−poles[i], −poles[i−1]), or (−poles[0], 0), as s = −e^x: F decreases in x
            let (mut a, mut b) = (
                if i == 0 {
                    (poles[0] * 1e-30).ln()
                } else {
                    poles[i - 1].ln()
                },
                poles[i].ln(),
            );
            for _ in 0..200 {
                let mid = 0.5 * (a + b);
                if f(-mid.exp()) > 0.0 {
                    a = mid;
                } else {
                    b = mid;
                }
            }
            roots.push(-(0.5 * (a + b)).exp());
        }
        Compliance {
            long_term: 1.0 / long_term,
            terms: roots.iter().map(|&s| (1.0 / (s * df(s)), s)).collect(),
        }
    }

    /// The asphalt's uniaxial creep compliance D(t) (of its E(t)).
    pub fn asphalt() -> Self {
        Self::of(ASPHALT_E_INF, &ASPHALT)
    }

    /// D(t).
    pub fn at(&self, t: f64) -> f64 {
        self.long_term + self.terms.iter().map(|(c, s)| c * (s * t).exp()).sum::<f64>()
    }
}
