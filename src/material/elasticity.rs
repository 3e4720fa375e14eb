//! Isotropic linear elasticity in 2D (EXAMPLE.md (5.1)), in Voigt form with engineering
//! shear strain: stress [σ₁₁, σ₂₂, σ₁₂] = D · [ε₁₁, ε₂₂, γ₁₂ = 2ε₁₂].

/// A 3×3 matrix acting on Voigt strain vectors.
pub type VoigtMatrix = [[f64; 3]; 3];

/// The identity fourth-order tensor, B₀ = I: (B₀ε) = ε, i.e. σ₁₂ = ε₁₂ = γ₁₂ / 2.
/// The paper's relaxation tensor (EXAMPLE.md: (B(s)ε, τ) = b(s)(ε, τ)).
pub const IDENTITY_TENSOR: VoigtMatrix = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.5]];

/// Which 2D reduction of 3D elasticity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlaneModel {
    /// σ₃₃ = 0 (thin plate; the paper's (5.1)).
    Stress,
    /// ε₃₃ = 0 (long body).
    Strain,
}

/// Isotropic elasticity with Young's modulus E and Poisson's ratio ν.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Elasticity {
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub plane: PlaneModel,
}

impl Elasticity {
    /// The Voigt matrix D of A.
    ///
    /// Plane stress (5.1): (Aε)ᵢⱼ = Eν/(1−ν²)(ε₁₁+ε₂₂)δᵢⱼ + E/(1+ν) εᵢⱼ.
    /// Plane strain: λ tr ε δᵢⱼ + 2μ εᵢⱼ with the Lamé constants of (E, ν).
    pub fn voigt(&self) -> VoigtMatrix {
        let (e, nu) = (self.youngs_modulus, self.poisson_ratio);
        match self.plane {
            PlaneModel::Stress => {
                let c = e / (1.0 - nu * nu);
                [[c, c * nu, 0.0], [c * nu, c, 0.0], [0.0, 0.0, c * (1.0 - nu) / 2.0]]
            }
            PlaneModel::Strain => {
                let (lambda, mu) = self.lame();
                [
                    [lambda + 2.0 * mu, lambda, 0.0],
                    [lambda, lambda + 2.0 * mu, 0.0],
                    [0.0, 0.0, mu],
                ]
            }
        }
    }

    /// Lamé constants (λ, μ) of the 3D material.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.youngs_modulus, self.poisson_ratio);
        (e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)))
    }

    /// The out-of-plane stress σ₃₃ for an in-plane strain (zero in plane stress).
    pub fn out_of_plane_stress(&self, strain: &[f64; 3]) -> f64 {
        match self.plane {
            PlaneModel::Stress => 0.0,
            PlaneModel::Strain => self.lame().0 * (strain[0] + strain[1]),
        }
    }

    /// Coercivity constant m_A of A on symmetric tensors: the smallest eigenvalue of A as a
    /// map on (ε₁₁, ε₂₂, ε₁₂) with the Frobenius inner product (used by the smallness check).
    pub fn coercivity(&self) -> f64 {
        let d = self.voigt();
        // Volumetric/deviatoric split: eigenvalues d00 + d01, d00 − d01 and 2·d22 (shear, Frobenius scaling).
        (d[0][0] + d[0][1]).min(d[0][0] - d[0][1]).min(2.0 * d[2][2])
    }
}

/// σ = D ε for a Voigt matrix.
pub fn apply(d: &VoigtMatrix, e: &[f64; 3]) -> [f64; 3] {
    let mut s = [0.0; 3];
    for (r, row) in d.iter().enumerate() {
        s[r] = row[0] * e[0] + row[1] * e[1] + row[2] * e[2];
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_stress_matches_paper_formula() {
        let a = Elasticity {
            youngs_modulus: 1.0,
            poisson_ratio: 0.3,
            plane: PlaneModel::Stress,
        };
        let eps = [0.1, -0.2, 0.06]; // γ = 0.06 → ε₁₂ = 0.03
        let s = apply(&a.voigt(), &eps);
        let (e, k) = (1.0, 0.3);
        let tr = eps[0] + eps[1];
        let s11 = e * k / (1.0 - k * k) * tr + e / (1.0 + k) * eps[0];
        let s12 = e / (1.0 + k) * 0.03;
        assert!((s[0] - s11).abs() < 1e-15 && (s[2] - s12).abs() < 1e-15);
    }
}
