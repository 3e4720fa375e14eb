//! Rigid obstacles (docs/method.md §14): a plane, a disc/ball, or the zero level set of a
//! function φ (φ > 0 on the body's side). Each gives a contact row its direction and initial gap:
//!
//! * along the obstacle's normal (the default): the foot y of the node x on the surface (the
//!   closest point; for a φ that is not a distance, the end of the gradient projection
//!   y ← y − φ ∇φ / |∇φ|²), n = ∇φ(y)/|∇φ(y)|, the direction d = −n and the gap (x − y)·n;
//! * along the body's normal ν: the first s with φ(x + s ν) = 0 (Newton on the ray; ∞ when the
//!   ray moves away from the obstacle) and n the obstacle's normal where the ray hits.
//!
//! A rigid motion a(t) of the obstacle changes the gap to first order through the tangent plane at
//! the foot: gap(t) = gap₀ + (n·a(t)) / (n·d), exact for a plane.

use crate::expr::Expr;
use crate::mesh::vector::{distance, dot};

/// A rigid obstacle in D dimensions.
#[derive(Clone, Debug)]
pub enum Obstacle<const D: usize> {
    /// φ = (x − point)·normal, |normal| = 1.
    Plane { point: [f64; D], normal: [f64; D] },
    /// φ = |x − centre| − radius.
    Ball { centre: [f64; D], radius: f64 },
    /// φ given; ∇φ by central differences with step `step`.
    Level { phi: Box<Expr>, step: f64 },
}

/// A contact row's direction and gap to an obstacle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gap<const D: usize> {
    /// The direction d of u_ν = d·u (pointing into the obstacle).
    pub direction: [f64; D],
    /// gap₀ (∞ when the body's normal never meets the obstacle).
    pub gap: f64,
    /// ∂gap/∂a: the change of the gap per unit rigid displacement a of the obstacle.
    pub motion: [f64; D],
}

fn unit<const D: usize>(v: [f64; D]) -> Option<[f64; D]> {
    let n = dot(&v, &v).sqrt();
    (n > 0.0 && n.is_finite()).then(|| v.map(|x| x / n))
}

impl<const D: usize> Obstacle<D> {
    /// φ(x).
    pub fn phi(&self, x: &[f64; D]) -> f64 {
        match self {
            Obstacle::Plane { point, normal } => (0..D).map(|k| (x[k] - point[k]) * normal[k]).sum(),
            Obstacle::Ball { centre, radius } => distance(x, centre) - radius,
            Obstacle::Level { phi, .. } => {
                let mut v = [0.0; 3];
                v[..D].copy_from_slice(x);
                phi.eval(&v)
            }
        }
    }

    /// ∇φ(x).
    pub fn gradient(&self, x: &[f64; D]) -> [f64; D] {
        match self {
            Obstacle::Plane { normal, .. } => *normal,
            Obstacle::Ball { centre, .. } => {
                let v: [f64; D] = std::array::from_fn(|k| x[k] - centre[k]);
                // at the centre every direction is as good: take the last axis
                unit(v).unwrap_or_else(|| std::array::from_fn(|k| if k + 1 == D { 1.0 } else { 0.0 }))
            }
            Obstacle::Level { step, .. } => std::array::from_fn(|k| {
                let (mut a, mut b) = (*x, *x);
                a[k] += step;
                b[k] -= step;
                (self.phi(&a) - self.phi(&b)) / (2.0 * step)
            }),
        }
    }

    /// The foot of x on the surface and the outward unit normal there; `length` is the size of
    /// the body (the tolerance of the projection is 1e-13 of it).
    fn foot(&self, x: &[f64; D], length: f64) -> Result<([f64; D], [f64; D]), String> {
        // a plane and a ball in closed form (exact, and no projection to degenerate for a tiny or
        // huge radius)
        match self {
            Obstacle::Plane { normal, .. } => {
                let f = self.phi(x);
                return Ok((std::array::from_fn(|k| x[k] - f * normal[k]), *normal));
            }
            Obstacle::Ball { centre, radius } => {
                let v: [f64; D] = std::array::from_fn(|k| x[k] - centre[k]);
                let n = unit(v).ok_or_else(|| {
                    format!("the node at {x:?} is the ball's centre: it has no closest point on the surface")
                })?;
                return Ok((std::array::from_fn(|k| centre[k] + radius * n[k]), n));
            }
            Obstacle::Level { .. } => {}
        }
        let mut y = *x;
        for _ in 0..100 {
            let (f, g) = (self.phi(&y), self.gradient(&y));
            let gg = dot(&g, &g);
            if !(gg > 0.0 && f.is_finite() && gg.is_finite()) {
                return Err(format!("the obstacle's gradient vanishes or is not finite near {y:?}"));
            }
            if f.abs() <= 1e-13 * length {
                let n = unit(g).ok_or_else(|| format!("the obstacle's gradient vanishes at {y:?}"))?;
                return Ok((y, n));
            }
            for k in 0..D {
                y[k] -= f * g[k] / gg;
            }
        }
        Err(format!(
            "projecting the node at {x:?} onto the obstacle's surface φ = 0 did not converge in 100 steps (is φ smooth \
             near the body, with a non-vanishing gradient?)"
        ))
    }

    /// The row's direction, gap and motion coefficient at node x with body normal ν.
    pub fn gap(
        &self,
        x: &[f64; D],
        body_normal: &[f64; D],
        along_obstacle: bool,
        length: f64,
    ) -> Result<Gap<D>, String> {
        if along_obstacle {
            let (y, n) = self.foot(x, length)?;
            let diff: [f64; D] = std::array::from_fn(|k| x[k] - y[k]);
            return Ok(Gap {
                direction: n.map(|v| -v),
                gap: dot(&diff, &n),
                motion: n.map(|v| -v),
            });
        }
        // along the body's normal: Newton on s ↦ φ(x + s ν)
        let nu = *body_normal;
        let at = |s: f64| -> [f64; D] { std::array::from_fn(|k| x[k] + s * nu[k]) };
        let mut s = 0.0;
        for _ in 0..100 {
            let p = at(s);
            let (f, g) = (self.phi(&p), self.gradient(&p));
            let slope = dot(&g, &nu);
            if f.abs() <= 1e-13 * length {
                let n = unit(g).ok_or_else(|| format!("the obstacle's gradient vanishes at {p:?}"))?;
                return Ok(Gap {
                    direction: nu,
                    gap: s,
                    motion: n.map(|v| v / dot(&n, &nu)),
                });
            }
            if slope >= 0.0 || slope.is_nan() || !f.is_finite() {
                // the ray moves away from the surface: this node never meets the obstacle
                return Ok(Gap {
                    direction: nu,
                    gap: f64::INFINITY,
                    motion: [0.0; D],
                });
            }
            s -= f / slope;
            if s.abs() > 1e6 * length {
                break;
            }
        }
        Ok(Gap {
            direction: nu,
            gap: f64::INFINITY,
            motion: [0.0; D],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_gap_both_directions() {
        let o = Obstacle::<2>::Plane {
            point: [0.0, -0.1],
            normal: [0.0, 1.0],
        };
        // along the obstacle's normal: straight down, gap 0.1, independent of ν
        let g = o.gap(&[0.3, 0.0], &[0.6, -0.8], true, 1.0).unwrap();
        assert_eq!(g.direction, [0.0, -1.0]);
        assert!((g.gap - 0.1).abs() < 1e-15);
        // along ν = (0.6, −0.8): the ray travels 0.1/0.8
        let g = o.gap(&[0.3, 0.0], &[0.6, -0.8], false, 1.0).unwrap();
        assert!((g.gap - 0.125).abs() < 1e-14, "{}", g.gap);
        // the plane moving up by a: the gap along ν shrinks by a/0.8
        assert!((g.motion[1] + 1.25).abs() < 1e-14);
        // a normal pointing away never meets the plane
        assert!(o.gap(&[0.3, 0.0], &[0.0, 1.0], false, 1.0).unwrap().gap.is_infinite());
    }

    /// A ball's closest point in closed form: the gap is |x − c| − R for any radius (the
    /// gradient projection it replaced failed for a radius of 1e-300).
    #[test]
    fn ball_gap_is_exact_for_tiny_and_large_radii() {
        for radius in [1e-300, 1e-6, 0.5, 1e6] {
            let ball = Obstacle::<2>::Ball {
                centre: [0.3, -0.52 - radius],
                radius,
            };
            let g = ball.gap(&[0.0, 0.0], &[0.0, -1.0], true, 1.0).unwrap();
            let exact = (0.09f64 + (0.52 + radius).powi(2)).sqrt() - radius;
            assert!(
                (g.gap - exact).abs() <= 1e-15 * (0.52 + radius),
                "R = {radius}: {} vs {exact}",
                g.gap
            );
            let n = (0.09f64 + (0.52 + radius).powi(2)).sqrt();
            assert!((g.direction[0] - 0.3 / n).abs() < 1e-15);
        }
        let ball = Obstacle::<2>::Ball {
            centre: [0.0, 0.0],
            radius: 1.0,
        };
        assert!(ball.gap(&[0.0, 0.0], &[0.0, -1.0], true, 1.0).is_err());
    }

    #[test]
    fn ball_and_level_set_agree() {
        let ball = Obstacle::<3>::Ball {
            centre: [0.0, 0.0, 1.5],
            radius: 0.5,
        };
        let phi = Expr::parse("sqrt(x^2 + y^2 + (z - 1.5)^2) - 0.5", &["x", "y", "z"]).unwrap();
        let level = Obstacle::<3>::Level {
            phi: Box::new(phi),
            step: 1e-6,
        };
        for x in [[0.0, 0.0, 1.0], [0.3, 0.1, 0.9], [-0.4, 0.2, 0.8]] {
            let a = ball.gap(&x, &[0.0, 0.0, 1.0], true, 1.0).unwrap();
            let b = level.gap(&x, &[0.0, 0.0, 1.0], true, 1.0).unwrap();
            // the closest point of a sphere: gap = |x − c| − R exactly; the finite-difference
            // gradient is accurate to O(step²) ~ 1e-12
            let exact = (x[0] * x[0] + x[1] * x[1] + (x[2] - 1.5f64).powi(2)).sqrt() - 0.5;
            assert!((a.gap - exact).abs() < 1e-14);
            assert!((b.gap - exact).abs() < 1e-9);
            for k in 0..3 {
                assert!((a.direction[k] - b.direction[k]).abs() < 1e-8);
            }
            // along the body normal (0, 0, 1): the ray hits the sphere at z = 1.5 − √(R² − ρ²)
            let rho2 = x[0] * x[0] + x[1] * x[1];
            let up = ball.gap(&x, &[0.0, 0.0, 1.0], false, 1.0).unwrap();
            assert!((up.gap - (1.5 - (0.25 - rho2).sqrt() - x[2])).abs() < 1e-12);
        }
    }
}
