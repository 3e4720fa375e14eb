//! Isotropic linear elasticity on full symmetric tensors in any dimension (docs/method.md §1,
//! §8): every tensor hvi uses is isotropic, Aε = λ tr(ε) I + 2μ ε, so a pair (λ, μ) carries it.
//!
//! * 3D and 2D plane strain: the Lamé constants of (E, ν).
//! * 2D plane stress (the paper's (5.1), docs/example.md): (Aε)ᵢⱼ = Eν/(1−ν²) tr ε δᵢⱼ + E/(1+ν) εᵢⱼ,
//!   i.e. λ* = Eν/(1−ν²) and the same μ.
//! * The paper's memory tensor B₀ = I (B₀ε = ε): λ = 0, μ = ½.

/// An isotropic fourth-order tensor: C ε = λ tr(ε) I + 2μ ε.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Isotropic {
    pub lambda: f64,
    pub mu: f64,
}

/// The identity tensor, B₀ = I: (B₀ε) = ε. The paper's relaxation tensor (docs/example.md:
/// (B(s)ε, τ) = b(s)(ε, τ)).
pub const IDENTITY_TENSOR: Isotropic = Isotropic { lambda: 0.0, mu: 0.5 };

impl Isotropic {
    /// The tensor of bulk modulus κ and shear modulus G: λ = κ − 2G/3, μ = G (3D relations).
    pub fn from_moduli(bulk: f64, shear: f64) -> Isotropic {
        Isotropic {
            lambda: bulk - 2.0 * shear / 3.0,
            mu: shear,
        }
    }

    /// σ = C ε.
    pub fn apply<const D: usize>(&self, e: &[[f64; D]; D]) -> [[f64; D]; D] {
        let tr: f64 = (0..D).map(|i| e[i][i]).sum();
        let mut s = [[0.0; D]; D];
        for i in 0..D {
            for j in 0..D {
                s[i][j] = 2.0 * self.mu * e[i][j];
            }
            s[i][i] += self.lambda * tr;
        }
        s
    }

    /// The 2D Voigt matrix D acting on [ε₁₁, ε₂₂, γ₁₂ = 2ε₁₂] (for writing the tractions of a
    /// known stress, and for readers used to the Voigt form).
    pub fn voigt_2d(&self) -> [[f64; 3]; 3] {
        let (l, m) = (self.lambda, self.mu);
        [[l + 2.0 * m, l, 0.0], [l, l + 2.0 * m, 0.0], [0.0, 0.0, m]]
    }
}

/// Which 2D reduction of 3D elasticity; `None` in 3D.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlaneModel {
    /// σ₃₃ = 0 (thin plate; the paper's (5.1)).
    Stress,
    /// ε₃₃ = 0 (long body).
    Strain,
    /// A body of revolution: x = r, y = z, the third strain the hoop strain u_r/r (docs/method.md
    /// §8.6); the 3D moduli.
    Axisymmetric,
}

/// Isotropic elasticity with Young's modulus E and Poisson's ratio ν; `plane` is the 2D
/// reduction (None for a 3D body).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Elasticity {
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub plane: Option<PlaneModel>,
}

impl Elasticity {
    /// The tensor A as (λ, μ) on the tensors of the body's dimension.
    pub fn tensor(&self) -> Isotropic {
        let (e, nu) = (self.youngs_modulus, self.poisson_ratio);
        let (lambda, mu) = self.lame();
        match self.plane {
            Some(PlaneModel::Stress) => Isotropic {
                lambda: e * nu / (1.0 - nu * nu),
                mu,
            },
            Some(PlaneModel::Strain) | Some(PlaneModel::Axisymmetric) | None => Isotropic { lambda, mu },
        }
    }

    /// K/G, the bulk over the shear modulus of the 3D material: 2(1 + ν) / (3(1 − 2ν)), infinite
    /// at ν = 1/2. What measures how nearly incompressible the body is (docs/troubleshooting.md).
    pub fn bulk_to_shear(&self) -> f64 {
        let nu = self.poisson_ratio;
        2.0 * (1.0 + nu) / (3.0 * (1.0 - 2.0 * nu))
    }

    /// Lamé constants (λ, μ) of the 3D material.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.youngs_modulus, self.poisson_ratio);
        (e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)))
    }

    /// The out-of-plane stress σ₃₃ of a 2D strain (zero in plane stress and in 3D, where the
    /// strain has its own third component).
    pub fn out_of_plane_stress(&self, trace: f64) -> f64 {
        match self.plane {
            Some(PlaneModel::Strain) => self.lame().0 * trace,
            // (the hoop stress is the stress's own, src/fem/stress.rs)
            Some(PlaneModel::Axisymmetric) => 0.0,
            _ => 0.0,
        }
    }

    /// Coercivity constant m_A of A on symmetric tensors (Frobenius inner product): the
    /// smallest eigenvalue, min(2μ, 2μ + Dλ) for Aε = λ tr ε I + 2μ ε in dimension D.
    pub fn coercivity(&self, dim: usize) -> f64 {
        let t = self.tensor();
        (2.0 * t.mu).min(2.0 * t.mu + dim as f64 * t.lambda)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_stress_matches_paper_formula() {
        let a = Elasticity {
            youngs_modulus: 1.0,
            poisson_ratio: 0.3,
            plane: Some(PlaneModel::Stress),
        };
        let eps = [[0.1, 0.03], [0.03, -0.2]];
        let s = a.tensor().apply(&eps);
        let (e, k) = (1.0, 0.3);
        let tr = eps[0][0] + eps[1][1];
        let s11 = e * k / (1.0 - k * k) * tr + e / (1.0 + k) * eps[0][0];
        let s12 = e / (1.0 + k) * 0.03;
        assert!((s[0][0] - s11).abs() < 1e-15 && (s[0][1] - s12).abs() < 1e-15);
    }

    #[test]
    fn three_d_tensor_is_hookes_law() {
        // uniaxial stress σ₁₁ = E ε₁₁ with ε₂₂ = ε₃₃ = −ν ε₁₁
        let a = Elasticity {
            youngs_modulus: 3.0,
            poisson_ratio: 0.25,
            plane: None,
        };
        let eps = [[1.0, 0.0, 0.0], [0.0, -0.25, 0.0], [0.0, 0.0, -0.25]];
        let s = a.tensor().apply(&eps);
        assert!((s[0][0] - 3.0).abs() < 1e-14 && s[1][1].abs() < 1e-14 && s[2][2].abs() < 1e-14);
    }
}
