//! Planning a run for a target error (`hvi study STUDY.toml --target E`; docs/method.md §6.1):
//! an error model fitted to a study's runs, a cost model
//! fitted to their wall times, and the cheapest (h, k) whose predicted error is at most E.
//!
//! * [`ErrorModel`]: e(h, k) ≈ C_h·√(h^{2p} − h_r^{2p}) + C_k·(k^q − k_r^q), the error against
//!   the reference run (h_r, k_r); against an exact solution (h_r = k_r = 0) it is
//!   C_h h^p + C_k k^q. The orders p, q are measured (fitted), not assumed.
//! * [`CostModel`]: wall ≈ c₀·N^b (setup: mesh, assembly, factorisation, condensation, once per
//!   run) + c₁·N^a·n_steps (the time steps), N the free unknowns.
//! * [`plan`]: the candidate of least predicted wall time among those predicted to meet E.
//!
//! The fits are small least-squares problems written out here (a 2 × 2 normal system inside a
//! grid search over the two orders, and straight lines in log–log): no optimisation crate is
//! needed for two parameters, and a grid cannot stall in a local minimum.

/// One run's measured error against the reference, at mesh size h and time step k.
#[derive(Clone, Copy, Debug)]
pub struct ErrorSample {
    pub h: f64,
    pub k: f64,
    pub error: f64,
}

/// One run's size and measured times.
#[derive(Clone, Copy, Debug)]
pub struct CostSample {
    /// Free unknowns N.
    pub unknowns: f64,
    pub steps: f64,
    /// Seconds not spent in the time steps (mesh, assembly, factorisation, condensation, …).
    pub setup_seconds: f64,
    /// Seconds of the time steps.
    pub steps_seconds: f64,
}

/// The fitted error model (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct ErrorModel {
    pub c_h: f64,
    pub p: f64,
    pub c_k: f64,
    pub q: f64,
    /// The reference's h and k (0 for an exact reference).
    pub h_ref: f64,
    pub k_ref: f64,
    /// Root mean square of the relative residuals (model − e)/e over the samples.
    pub rms_relative_residual: f64,
    /// Number of samples fitted.
    pub samples: usize,
}

/// The range searched for each order, and the grid steps (coarse, then fine around the best).
const ORDER_RANGE: (f64, f64) = (0.2, 4.0);

const COARSE_STEP: f64 = 0.01;

const FINE_STEP: f64 = 0.0005;

fn beyond(x: f64, reference: f64) -> bool {
    x > reference * (1.0 + 1e-9)
}

impl ErrorModel {
    /// The spatial part: C_h·√(h^{2p} − h_r^{2p}) (0 at and below h_r).
    pub fn spatial(&self, h: f64) -> f64 {
        self.c_h * spatial_basis(h, self.h_ref, self.p)
    }

    /// The temporal part: C_k·(k^q − k_r^q) (0 at and below k_r).
    pub fn temporal(&self, k: f64) -> f64 {
        self.c_k * temporal_basis(k, self.k_ref, self.q)
    }

    /// The predicted error against the reference.
    pub fn predict(&self, h: f64, k: f64) -> f64 {
        self.spatial(h) + self.temporal(k)
    }

    /// The predicted error against the exact solution, C_h h^p + C_k k^q.
    pub fn against_exact(&self, h: f64, k: f64) -> f64 {
        self.c_h * h.powf(self.p) + self.c_k * k.powf(self.q)
    }

    /// Fits C_h, p, C_k, q jointly to all samples by least squares on the relative residuals
    /// (errors span decades): for each (p, q) of a grid the model is linear in (C_h, C_k) and
    /// solved exactly (non-negative constants), then the grid is refined around the best pair.
    /// Needs at least two distinct h > h_ref and two distinct k > k_ref among the samples,
    /// else the orders are not determined: an error says which is missing.
    pub fn fit(samples: &[ErrorSample], h_ref: f64, k_ref: f64) -> Result<Self, String> {
        let samples: Vec<ErrorSample> = samples
            .iter()
            .copied()
            .filter(|s| s.error.is_finite() && s.error > 0.0 && s.h > 0.0 && s.k > 0.0)
            .collect();
        let distinct = |values: Vec<f64>| {
            let mut v = values;
            v.sort_by(f64::total_cmp);
            v.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * b.abs());
            v.len()
        };
        let hs = distinct(samples.iter().filter(|s| beyond(s.h, h_ref)).map(|s| s.h).collect());
        let ks = distinct(samples.iter().filter(|s| beyond(s.k, k_ref)).map(|s| s.k).collect());
        if hs < 2 || ks < 2 {
            return Err(format!(
                "the error model e ≈ C_h h^p + C_k k^q needs runs at two or more mesh sizes h coarser than the \
                 reference's and two or more time steps k longer than the reference's, to measure the orders p \
                 and q; this study has {hs} such h and {ks} such k (with a positive error): add an h path and a k \
                 path with two or more entries each"
            ));
        }
        let objective = |p: f64, q: f64| -> (f64, f64, f64) {
            // minimise Σ (C_h a_i/e_i + C_k b_i/e_i − 1)², C_h, C_k ≥ 0
            let (mut saa, mut sab, mut sbb, mut sa, mut sb) = (0.0, 0.0, 0.0, 0.0, 0.0);
            let rows: Vec<(f64, f64)> = samples
                .iter()
                .map(|s| {
                    (
                        spatial_basis(s.h, h_ref, p) / s.error,
                        temporal_basis(s.k, k_ref, q) / s.error,
                    )
                })
                .collect();
            for &(a, b) in &rows {
                saa += a * a;
                sab += a * b;
                sbb += b * b;
                sa += a;
                sb += b;
            }
            let residual = |ch: f64, ck: f64| rows.iter().map(|&(a, b)| (ch * a + ck * b - 1.0).powi(2)).sum::<f64>();
            let mut best = (f64::INFINITY, 0.0, 0.0);
            let det = saa * sbb - sab * sab;
            let mut consider = |ch: f64, ck: f64| {
                if ch >= 0.0 && ck >= 0.0 && ch.is_finite() && ck.is_finite() {
                    let r = residual(ch, ck);
                    if r < best.0 {
                        best = (r, ch, ck);
                    }
                }
            };
            if det > 1e-300 * (saa * sbb).max(1e-300) {
                consider((sa * sbb - sb * sab) / det, (sb * saa - sa * sab) / det);
            }
            if saa > 0.0 {
                consider(sa / saa, 0.0);
            }
            if sbb > 0.0 {
                consider(0.0, sb / sbb);
            }
            best
        };
        let search = |p_range: (f64, f64), q_range: (f64, f64), step: f64, best: &mut (f64, f64, f64, f64, f64)| {
            let count = |r: (f64, f64)| ((r.1 - r.0) / step).round() as usize;
            for i in 0..=count(p_range) {
                let p = p_range.0 + i as f64 * step;
                for j in 0..=count(q_range) {
                    let q = q_range.0 + j as f64 * step;
                    let (r, ch, ck) = objective(p, q);
                    if r < best.0 {
                        *best = (r, p, q, ch, ck);
                    }
                }
            }
        };
        let mut best = (f64::INFINITY, 1.0, 1.0, 0.0, 0.0);
        search(ORDER_RANGE, ORDER_RANGE, COARSE_STEP, &mut best);
        let around = |x: f64| {
            (
                (x - COARSE_STEP).max(ORDER_RANGE.0),
                (x + COARSE_STEP).min(ORDER_RANGE.1),
            )
        };
        let (p0, q0) = (best.1, best.2);
        search(around(p0), around(q0), FINE_STEP, &mut best);
        let (r, p, q, c_h, c_k) = best;
        if !r.is_finite() {
            return Err("the error model could not be fitted (no finite least-squares solution)".into());
        }
        Ok(ErrorModel {
            c_h,
            p,
            c_k,
            q,
            h_ref,
            k_ref,
            rms_relative_residual: (r / samples.len() as f64).sqrt(),
            samples: samples.len(),
        })
    }
}

/// √(h^{2p} − h_r^{2p}): the H¹ (energy) error of a Galerkin solution on a mesh nested in the
/// reference's, measured against the reference, when the error against the exact solution is
/// ∝ h^p (Galerkin orthogonality: |u − u_h|² = |u − u_ref|² + |u_ref − u_h|²).
fn spatial_basis(h: f64, h_ref: f64, p: f64) -> f64 {
    if beyond(h, h_ref) {
        (h.powf(2.0 * p) - h_ref.powf(2.0 * p)).max(0.0).sqrt()
    } else {
        0.0
    }
}

/// k^q − k_r^q: the time-stepping error, the same smooth function of time times k^q in every
/// run, measured against the reference's.
fn temporal_basis(k: f64, k_ref: f64, q: f64) -> f64 {
    if beyond(k, k_ref) {
        (k.powf(q) - k_ref.powf(q)).max(0.0)
    } else {
        0.0
    }
}

/// y ≈ c·x^a by least squares on (log x, log y); None for fewer than two distinct x.
pub fn power_fit(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = pts.len() as f64;
    let (mx, my) = pts.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if pts.len() < 2 || sxx <= 1e-12 * n {
        return None;
    }
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let a = sxy / sxx;
    Some(((my - a * mx).exp(), a))
}

/// The fitted cost model (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct CostModel {
    /// Setup seconds c₀·N^b.
    pub c_setup: f64,
    pub b: f64,
    /// Seconds per step c₁·N^a.
    pub c_step: f64,
    pub a: f64,
}

impl CostModel {
    /// Fits both power laws by least squares in log–log; needs runs of two or more sizes N.
    pub fn fit(samples: &[CostSample]) -> Result<Self, String> {
        let floor = 1e-6; // seconds: a timer's resolution, so that no log is taken of 0
        let setup: Vec<(f64, f64)> = samples
            .iter()
            .map(|s| (s.unknowns, s.setup_seconds.max(floor)))
            .collect();
        let per_step: Vec<(f64, f64)> = samples
            .iter()
            .filter(|s| s.steps > 0.0)
            .map(|s| (s.unknowns, (s.steps_seconds / s.steps).max(floor)))
            .collect();
        let missing = || {
            "the cost model (wall ≈ c₀ N^b + c₁ N^a · steps) needs runs of two or more sizes N: add an h path"
                .to_string()
        };
        let (c_setup, b) = power_fit(&setup).ok_or_else(missing)?;
        let (c_step, a) = power_fit(&per_step).ok_or_else(missing)?;
        Ok(CostModel { c_setup, b, c_step, a })
    }

    /// Predicted wall seconds of a run with N unknowns and `steps` steps.
    pub fn predict(&self, unknowns: f64, steps: f64) -> f64 {
        self.c_setup * unknowns.powf(self.b) + self.c_step * unknowns.powf(self.a) * steps
    }
}

/// A run the planner may choose: h = 1/n, k = T/steps, with N unknowns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    pub n: usize,
    pub steps: usize,
    pub h: f64,
    pub k: f64,
    pub unknowns: f64,
}

/// The planner's choice and what it predicts.
#[derive(Clone, Copy, Debug)]
pub struct PlannedRun {
    pub run: Candidate,
    pub error: f64,
    pub spatial: f64,
    pub temporal: f64,
    pub wall: f64,
}

/// The candidate of least predicted wall time whose predicted error is at most `target`
/// (ties: the smaller error); None if no candidate meets it.
pub fn plan(
    error: &ErrorModel,
    cost: &CostModel,
    candidates: impl IntoIterator<Item = Candidate>,
    target: f64,
) -> Option<PlannedRun> {
    candidates
        .into_iter()
        .map(|c| PlannedRun {
            run: c,
            error: error.predict(c.h, c.k),
            spatial: error.spatial(c.h),
            temporal: error.temporal(c.k),
            wall: cost.predict(c.unknowns, c.steps as f64),
        })
        .filter(|p| p.error <= target)
        .min_by(|x, y| x.wall.total_cmp(&y.wall).then(x.error.total_cmp(&y.error)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_fit_recovers_a_power_law() {
        let pts: Vec<(f64, f64)> = [10.0, 100.0, 1000.0]
            .iter()
            .map(|&x: &f64| (x, 3.0 * x.powf(1.3)))
            .collect();
        let (c, a) = power_fit(&pts).unwrap();
        assert!((c - 3.0).abs() < 1e-9 && (a - 1.3).abs() < 1e-12, "{c} {a}");
        assert!(power_fit(&pts[..1]).is_none());
    }

    #[test]
    fn one_mesh_size_is_not_enough_for_the_error_model() {
        let s = [0.25, 0.125].map(|k| ErrorSample {
            h: 0.1,
            k,
            error: k * k,
        });
        let err = ErrorModel::fit(&s, 0.1, 0.01).unwrap_err();
        assert!(err.contains("0 such h") && err.contains("2 such k"), "{err}");
    }
}
