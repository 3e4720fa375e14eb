//! Quadrature rules on the reference cells and the reference interval.

/// A quadrature point on a reference cell: coordinates (ξ, η) and weight.
#[derive(Clone, Copy, Debug)]
pub struct QuadPoint {
    pub xi: [f64; 2],
    pub weight: f64,
}

const G: f64 = 0.577_350_269_189_625_8; // 1/√3

/// 2×2 Gauss rule on [−1, 1]²: exact for bicubic integrands (Q1 stiffness on parallelograms).
pub const QUAD_GAUSS_2X2: [QuadPoint; 4] = [
    QuadPoint {
        xi: [-G, -G],
        weight: 1.0,
    },
    QuadPoint {
        xi: [G, -G],
        weight: 1.0,
    },
    QuadPoint {
        xi: [G, G],
        weight: 1.0,
    },
    QuadPoint {
        xi: [-G, G],
        weight: 1.0,
    },
];

/// 3-point rule on the reference triangle {ξ, η ≥ 0, ξ + η ≤ 1}: exact for quadratics.
pub const TRI_3POINT: [QuadPoint; 3] = [
    QuadPoint {
        xi: [1.0 / 6.0, 1.0 / 6.0],
        weight: 1.0 / 6.0,
    },
    QuadPoint {
        xi: [2.0 / 3.0, 1.0 / 6.0],
        weight: 1.0 / 6.0,
    },
    QuadPoint {
        xi: [1.0 / 6.0, 2.0 / 3.0],
        weight: 1.0 / 6.0,
    },
];

/// 1-point (centroid) rule on the reference triangle: exact for P1 stiffness (constant strain).
pub const TRI_CENTROID: [QuadPoint; 1] = [QuadPoint {
    xi: [1.0 / 3.0, 1.0 / 3.0],
    weight: 0.5,
}];

/// 2-point Gauss rule on [0, 1] (parameter s along an edge), weights summing to 1: exact for cubics.
pub const EDGE_GAUSS_2: [(f64, f64); 2] = [(0.5 - 0.5 * G, 0.5), (0.5 + 0.5 * G, 0.5)];

/// 3-point Gauss rule on [0, 1], weights summing to 1: exact for quintics.
pub const EDGE_GAUSS_3: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
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
        // ∫_T ξ η = 1/24
        let t: f64 = TRI_3POINT.iter().map(|p| p.weight * p.xi[0] * p.xi[1]).sum();
        assert!((t - 1.0 / 24.0).abs() < 1e-14);
        // ∫_0^1 s^3 = 1/4, ∫_0^1 s^5 = 1/6
        let e: f64 = EDGE_GAUSS_2.iter().map(|(s, w)| w * s.powi(3)).sum();
        assert!((e - 0.25).abs() < 1e-14);
        let e5: f64 = EDGE_GAUSS_3.iter().map(|(s, w)| w * s.powi(5)).sum();
        assert!((e5 - 1.0 / 6.0).abs() < 1e-14);
    }
}
