//! Quadrature rules on the reference cells and the reference interval (docs/method.md §2, §8).
//! Reference points have three coordinates; 2D rules leave the third at 0.

/// A quadrature point on a reference cell: coordinates (ξ, η, ζ) and weight.
#[derive(Clone, Copy, Debug)]
pub struct QuadPoint {
    pub xi: [f64; 3],
    pub weight: f64,
}

const G: f64 = 0.577_350_269_189_625_8; // 1/√3

const fn qp(x: f64, y: f64, z: f64, weight: f64) -> QuadPoint {
    QuadPoint { xi: [x, y, z], weight }
}

/// 2×2 Gauss rule on [−1, 1]²: exact for bicubic integrands (Q1 stiffness on parallelograms).
pub const QUAD_GAUSS_2X2: [QuadPoint; 4] = [
    qp(-G, -G, 0.0, 1.0),
    qp(G, -G, 0.0, 1.0),
    qp(G, G, 0.0, 1.0),
    qp(-G, G, 0.0, 1.0),
];

/// 2×2×2 Gauss rule on [−1, 1]³: exact for tricubic integrands (Q1 stiffness on parallelepipeds).
pub const HEX_GAUSS_2X2X2: [QuadPoint; 8] = [
    qp(-G, -G, -G, 1.0),
    qp(G, -G, -G, 1.0),
    qp(G, G, -G, 1.0),
    qp(-G, G, -G, 1.0),
    qp(-G, -G, G, 1.0),
    qp(G, -G, G, 1.0),
    qp(G, G, G, 1.0),
    qp(-G, G, G, 1.0),
];

/// 3-point rule on the reference triangle {ξ, η ≥ 0, ξ + η ≤ 1}: exact for quadratics.
pub const TRI_3POINT: [QuadPoint; 3] = [
    qp(1.0 / 6.0, 1.0 / 6.0, 0.0, 1.0 / 6.0),
    qp(2.0 / 3.0, 1.0 / 6.0, 0.0, 1.0 / 6.0),
    qp(1.0 / 6.0, 2.0 / 3.0, 0.0, 1.0 / 6.0),
];

/// 6-point rule on the reference prism {ξ, η ≥ 0, ξ + η ≤ 1} × [−1, 1]: the triangle's 3-point
/// rule times 2-point Gauss, exact for quadratics in (ξ, η) times cubics in ζ (the P1 × Q1
/// stiffness on a right prism).
pub const PRISM_6POINT: [QuadPoint; 6] = [
    qp(1.0 / 6.0, 1.0 / 6.0, -G, 1.0 / 6.0),
    qp(2.0 / 3.0, 1.0 / 6.0, -G, 1.0 / 6.0),
    qp(1.0 / 6.0, 2.0 / 3.0, -G, 1.0 / 6.0),
    qp(1.0 / 6.0, 1.0 / 6.0, G, 1.0 / 6.0),
    qp(2.0 / 3.0, 1.0 / 6.0, G, 1.0 / 6.0),
    qp(1.0 / 6.0, 2.0 / 3.0, G, 1.0 / 6.0),
];

/// The 2-point Gauss–Jacobi rule on [0, 1] for the weight (1 − w)² (nodes 1/3 ∓ √(2/45),
/// weights 1/6 ± 1/(72 √(2/45))): ∫₀¹ p(w) (1 − w)² dw exactly for cubics p.
const JACOBI2_2: [(f64, f64); 2] = [
    (0.122_514_822_655_441_38, 0.232_547_451_253_507_9),
    (0.544_151_844_011_225_3, 0.100_785_882_079_825_43),
];

/// The 3-point Gauss–Jacobi rule on [0, 1] for the weight (1 − w)²: exact for quintics.
const JACOBI2_3: [(f64, f64); 3] = [
    (0.072_994_024_073_149_73, 0.157_136_361_064_886_6),
    (0.347_003_766_038_351_9, 0.146_246_269_259_866_02),
    (0.705_002_209_888_498_4, 0.029_950_703_008_580_698),
];

/// A point of the collapsed (Duffy) rule on the reference pyramid {0 ≤ ζ ≤ 1, |ξ|, |η| ≤ 1 − ζ}:
/// the cube point (u, v, w) ∈ [−1, 1]² × [0, 1] goes to ξ = u (1 − w), η = v (1 − w), ζ = w, whose
/// Jacobian (1 − w)² the Gauss–Jacobi weight in w carries.
const fn pyramid_point(u: f64, v: f64, (w, weight): (f64, f64), wu: f64, wv: f64) -> QuadPoint {
    qp(u * (1.0 - w), v * (1.0 - w), w, wu * wv * weight)
}

/// 8-point collapsed rule on the reference pyramid (docs/method.md §8.1): 2 × 2 Gauss in (u, v)
/// times 2-point Gauss–Jacobi in w, no point at the apex. In these coordinates the rational
/// basis is the trilinear one of a hexahedron whose top face is collapsed to the apex, and the
/// Jacobian of the pyramid's map and the ξ-gradients of its basis depend on (u, v) only, so the
/// rule integrates exactly ∫ ∇N_a dx on any pyramid (the patch test: cubics in u and v), the
/// stiffness of an affine pyramid (quadratics in u and v) and its loads (cubics in w).
pub const PYRAMID_8POINT: [QuadPoint; 8] = [
    pyramid_point(-G, -G, JACOBI2_2[0], 1.0, 1.0),
    pyramid_point(G, -G, JACOBI2_2[0], 1.0, 1.0),
    pyramid_point(G, G, JACOBI2_2[0], 1.0, 1.0),
    pyramid_point(-G, G, JACOBI2_2[0], 1.0, 1.0),
    pyramid_point(-G, -G, JACOBI2_2[1], 1.0, 1.0),
    pyramid_point(G, -G, JACOBI2_2[1], 1.0, 1.0),
    pyramid_point(G, G, JACOBI2_2[1], 1.0, 1.0),
    pyramid_point(-G, G, JACOBI2_2[1], 1.0, 1.0),
];

/// 27-point collapsed rule on the reference pyramid: 3 × 3 Gauss in (u, v) times 3-point
/// Gauss–Jacobi in w (error integrals, where its cost does not matter).
pub fn pyramid_collapsed_27() -> Vec<QuadPoint> {
    let mut out = Vec::with_capacity(27);
    for &jw in &JACOBI2_3 {
        for &(v, wv) in &GAUSS_3 {
            for &(u, wu) in &GAUSS_3 {
                out.push(pyramid_point(u, v, jw, wu, wv));
            }
        }
    }
    out
}

/// 1-point (centroid) rule on the reference triangle: exact for P1 stiffness (constant strain).
pub const TRI_CENTROID: [QuadPoint; 1] = [qp(1.0 / 3.0, 1.0 / 3.0, 0.0, 0.5)];

/// 1-point (centroid) rule on the reference tetrahedron {ξ, η, ζ ≥ 0, ξ + η + ζ ≤ 1}: exact for
/// P1 stiffness.
pub const TET_CENTROID: [QuadPoint; 1] = [qp(0.25, 0.25, 0.25, 1.0 / 6.0)];

const TA: f64 = 0.585_410_196_624_968_5; // (5 + 3√5)/20

const TB: f64 = 0.138_196_601_125_010_5; // (5 − √5)/20

/// 4-point rule on the reference tetrahedron: exact for quadratics.
pub const TET_4POINT: [QuadPoint; 4] = [
    qp(TB, TB, TB, 1.0 / 24.0),
    qp(TA, TB, TB, 1.0 / 24.0),
    qp(TB, TA, TB, 1.0 / 24.0),
    qp(TB, TB, TA, 1.0 / 24.0),
];

/// 2-point Gauss rule on [0, 1] (parameter s along an edge), weights summing to 1: exact for cubics.
pub const EDGE_GAUSS_2: [(f64, f64); 2] = [(0.5 - 0.5 * G, 0.5), (0.5 + 0.5 * G, 0.5)];

/// 3-point Gauss rule on [0, 1], weights summing to 1: exact for quintics.
pub const EDGE_GAUSS_3: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];

/// 3-point Gauss rule on [−1, 1].
pub const GAUSS_3: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// 4-point Gauss rule on [−1, 1]: exact for degree 7.
pub const GAUSS_4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];

/// The n-point Gauss rule on [−1, 1] (n = 2, 3 or 4).
pub fn gauss(n: usize) -> &'static [(f64, f64)] {
    const GAUSS_2: [(f64, f64); 2] = [(-G, 1.0), (G, 1.0)];
    match n {
        2 => &GAUSS_2,
        3 => &GAUSS_3,
        _ => &GAUSS_4,
    }
}

/// The 6-point rule on the reference triangle ([`TRI6`], exact for quartics) as quadrature points.
pub const TRI_6POINT: [QuadPoint; 6] = [
    qp(TRI6[0].0[0], TRI6[0].0[1], 0.0, TRI6[0].1),
    qp(TRI6[1].0[0], TRI6[1].0[1], 0.0, TRI6[1].1),
    qp(TRI6[2].0[0], TRI6[2].0[1], 0.0, TRI6[2].1),
    qp(TRI6[3].0[0], TRI6[3].0[1], 0.0, TRI6[3].1),
    qp(TRI6[4].0[0], TRI6[4].0[1], 0.0, TRI6[4].1),
    qp(TRI6[5].0[0], TRI6[5].0[1], 0.0, TRI6[5].1),
];

/// A triangle rule times the n-point Gauss rule in ζ: a rule on the reference prism.
pub fn prism_rule(triangle: &[QuadPoint], n: usize) -> Vec<QuadPoint> {
    triangle
        .iter()
        .flat_map(|t| {
            gauss(n)
                .iter()
                .map(move |&(z, wz)| qp(t.xi[0], t.xi[1], z, t.weight * wz))
        })
        .collect()
}

/// A collapsed (Duffy) rule on the reference triangle from n Gauss points per direction (n²
/// points, positive weights, exact for degree 2n − 2): error integrals on 6-node triangles.
pub fn triangle_duffy(n: usize) -> Vec<QuadPoint> {
    let mut out = Vec::with_capacity(n * n);
    for &(a, wa) in gauss(n) {
        for &(b, wb) in gauss(n) {
            // (u, v) ∈ [0, 1]² → ξ = u, η = (1 − u) v
            let (u, v) = (0.5 * (a + 1.0), 0.5 * (b + 1.0));
            out.push(qp(u, (1.0 - u) * v, 0.0, wa * wb / 4.0 * (1.0 - u)));
        }
    }
    out
}

/// The collapsed (Duffy) rule on the reference tetrahedron from n Gauss points per direction (n³
/// points, positive weights, exact for degree 2n − 3: n = 3 for error integrals on 4-node
/// tetrahedra, where its cost does not matter).
pub fn tet_duffy(n: usize) -> Vec<QuadPoint> {
    let mut out = Vec::with_capacity(n * n * n);
    for &(a, wa) in gauss(n) {
        for &(b, wb) in gauss(n) {
            for &(c, wc) in gauss(n) {
                // (u, v, w) ∈ [0, 1]³ → ξ = u, η = (1 − u) v, ζ = (1 − u)(1 − v) w
                let (u, v, w) = (0.5 * (a + 1.0), 0.5 * (b + 1.0), 0.5 * (c + 1.0));
                let jac = (1.0 - u) * (1.0 - u) * (1.0 - v);
                out.push(qp(
                    u,
                    (1.0 - u) * v,
                    (1.0 - u) * (1.0 - v) * w,
                    wa * wb * wc / 8.0 * jac,
                ));
            }
        }
    }
    out
}

/// n × n (× n) Gauss on [−1, 1]^d (n = 3: error integrals on quadrilaterals and hexahedra).
pub fn tensor_gauss(n: usize, dim: usize) -> Vec<QuadPoint> {
    let mut out = Vec::new();
    for &(a, wa) in gauss(n) {
        for &(b, wb) in gauss(n) {
            if dim == 2 {
                out.push(qp(a, b, 0.0, wa * wb));
            } else {
                for &(c, wc) in gauss(n) {
                    out.push(qp(a, b, c, wa * wb * wc));
                }
            }
        }
    }
    out
}

/// A 6-point rule on the reference triangle, exact for quartics (weights summing to 1/2,
/// the reference area).
pub const TRI6: [([f64; 2], f64); 6] = [
    ([0.445_948_490_915_965, 0.445_948_490_915_965], 0.111_690_794_839_005),
    ([0.445_948_490_915_965, 0.108_103_018_168_070], 0.111_690_794_839_005),
    ([0.108_103_018_168_070, 0.445_948_490_915_965], 0.111_690_794_839_005),
    ([0.091_576_213_509_771, 0.091_576_213_509_771], 0.054_975_871_827_661),
    ([0.091_576_213_509_771, 0.816_847_572_980_459], 0.054_975_871_827_661),
    ([0.816_847_572_980_459, 0.091_576_213_509_771], 0.054_975_871_827_661),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_integrate_monomials_exactly() {
        // ∫_{[-1,1]^2} ξ² η² = 4/9
        let q: f64 = QUAD_GAUSS_2X2
            .iter()
            .map(|p| p.weight * p.xi[0].powi(2) * p.xi[1].powi(2))
            .sum();
        assert!((q - 4.0 / 9.0).abs() < 1e-14);
        // ∫_{[-1,1]^3} ξ² η² ζ² = 8/27
        let h: f64 = HEX_GAUSS_2X2X2
            .iter()
            .map(|p| p.weight * (p.xi[0] * p.xi[1] * p.xi[2]).powi(2))
            .sum();
        assert!((h - 8.0 / 27.0).abs() < 1e-14);
        // ∫_T ξ η = 1/24
        let t: f64 = TRI_3POINT.iter().map(|p| p.weight * p.xi[0] * p.xi[1]).sum();
        assert!((t - 1.0 / 24.0).abs() < 1e-14);
        // ∫_tet ξ² = 1/60, ∫_tet ξ η = 1/120, volume 1/6
        let t2: f64 = TET_4POINT.iter().map(|p| p.weight * p.xi[0] * p.xi[0]).sum();
        let t11: f64 = TET_4POINT.iter().map(|p| p.weight * p.xi[0] * p.xi[1]).sum();
        assert!((t2 - 1.0 / 60.0).abs() < 1e-15 && (t11 - 1.0 / 120.0).abs() < 1e-15);
        let d = tet_duffy(3);
        let vol: f64 = d.iter().map(|p| p.weight).sum();
        // ∫_tet ξ ζ² = 2!·1!/(3+3)! ·... = 1/360 (Dirichlet integral a!b!c!/(a+b+c+3)!)
        let xz2: f64 = d.iter().map(|p| p.weight * p.xi[0] * p.xi[2] * p.xi[2]).sum();
        assert!((vol - 1.0 / 6.0).abs() < 1e-15 && (xz2 - 2.0 / 720.0).abs() < 1e-15);
        // ∫_0^1 s^3 = 1/4, ∫_0^1 s^5 = 1/6
        let e: f64 = EDGE_GAUSS_2.iter().map(|(s, w)| w * s.powi(3)).sum();
        assert!((e - 0.25).abs() < 1e-14);
        let e5: f64 = EDGE_GAUSS_3.iter().map(|(s, w)| w * s.powi(5)).sum();
        assert!((e5 - 1.0 / 6.0).abs() < 1e-14);
    }

    /// The Gauss–Jacobi rules for (1 − w)² on [0, 1] against the moments ∫₀¹ wᵏ (1 − w)² dw =
    /// 2/((k + 1)(k + 2)(k + 3)) up to their degrees (3 and 5), and the pyramid rules against
    /// the reference pyramid's moments ∫ ξ^{2i} η^{2j} ζᵏ = 4/((2i + 1)(2j + 1)) B(k + 1, 2i + 2j + 3)
    /// (odd powers of ξ, η give 0) of total degree up to 3 (the 8-point rule) and 5 (the
    /// 27-point rule), the volume 4/3 among them. Round-off: 1e-15.
    #[test]
    fn pyramid_rules_integrate_monomials_exactly() {
        let moment = |k: i32| 2.0 / f64::from((k + 1) * (k + 2) * (k + 3));
        for (rule, degree) in [(&JACOBI2_2[..], 3), (&JACOBI2_3[..], 5)] {
            for k in 0..=degree {
                let q: f64 = rule.iter().map(|(w, c)| c * w.powi(k)).sum();
                assert!((q - moment(k)).abs() < 1e-15, "degree {k}: {q} vs {}", moment(k));
            }
        }
        // B(a, b) for integers: (a − 1)! (b − 1)! / (a + b − 1)!
        let fact = |n: i32| (1..=n).map(f64::from).product::<f64>();
        let beta = |a: i32, b: i32| fact(a - 1) * fact(b - 1) / fact(a + b - 1);
        let exact = |p: [i32; 3]| {
            if p[0] % 2 == 1 || p[1] % 2 == 1 {
                0.0
            } else {
                4.0 / f64::from((p[0] + 1) * (p[1] + 1)) * beta(p[2] + 1, p[0] + p[1] + 3)
            }
        };
        assert!((exact([0, 0, 0]) - 4.0 / 3.0).abs() < 1e-15);
        for (rule, degree) in [(PYRAMID_8POINT.to_vec(), 3), (pyramid_collapsed_27(), 5)] {
            for i in 0..=degree {
                for j in 0..=degree - i {
                    for k in 0..=degree - i - j {
                        let q: f64 = rule
                            .iter()
                            .map(|p| p.weight * p.xi[0].powi(i) * p.xi[1].powi(j) * p.xi[2].powi(k))
                            .sum();
                        let want = exact([i, j, k]);
                        assert!((q - want).abs() < 1e-15, "ξ^{i} η^{j} ζ^{k}: {q} vs {want}");
                    }
                }
            }
        }
    }
}
