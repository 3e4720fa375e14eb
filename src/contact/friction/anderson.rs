//! Anderson mixing of Coulomb's fixed point (docs/method.md §17.2).

use super::super::settings::TUNING;

/// Anderson mixing of Coulomb's fixed point F ← Φ(F) = μ(s) λ_ν(F) (docs/method.md §17.2). The
/// next round's bound forces combine the last rounds' outputs Φ(F_j) with the weights whose
/// residuals Φ(F_j) − F_j combine to the least length; on a linear Φ that is GMRES on I − Φ',
/// where the plain fixed point gains only Φ's contraction per round. Only Coulomb's rows are
/// mixed (Tresca's bound is fixed, a potential's an output); a round whose residual grew starts
/// the history afresh (the plain round).
pub struct Anderson {
    coulomb: Vec<bool>,
    /// the last rounds' residuals Φ(F_j) − F_j (0 off Coulomb's rows) and outputs Φ(F_j),
    /// oldest first
    rounds: Vec<(Vec<f64>, Vec<f64>)>,
}

impl Anderson {
    pub fn new(coulomb: Vec<bool>) -> Self {
        Anderson {
            coulomb,
            rounds: Vec::new(),
        }
    }

    /// The next round's bound forces, given this round's F and Φ(F).
    pub fn next(&mut self, input: &[f64], output: Vec<f64>) -> Vec<f64> {
        let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
        // the residual Φ(F) − F on Coulomb's rows (0 elsewhere)
        let f: Vec<f64> = (input.iter().zip(&output).zip(&self.coulomb))
            .map(|((x, g), &c)| if c { g - x } else { 0.0 })
            .collect();
        if self.rounds.last().is_some_and(|(last, _)| norm(&f) > norm(last)) {
            self.rounds.clear();
        }
        self.rounds.push((f, output));
        if self.rounds.len() > TUNING.anderson_depth + 1 {
            self.rounds.remove(0);
        }
        let k = self.rounds.len() - 1;
        let (f, newest) = &self.rounds[k];
        if k == 0 {
            return newest.clone();
        }
        // γ = argmin |f_k − Σ_j γ_j (f_{j+1} − f_j)|, by an SVD that drops directions below 10⁻¹²
        // of |f_k| (rounds whose residuals are nearly parallel)
        let n = f.len();
        let differences = nalgebra::DMatrix::from_fn(n, k, |i, j| self.rounds[j + 1].0[i] - self.rounds[j].0[i]);
        let target = nalgebra::DVector::from_column_slice(f);
        let Ok(gamma) = differences.svd(true, true).solve(&target, 1e-12 * norm(f)) else {
            return newest.clone();
        };
        (0..n)
            .map(|i| {
                if !self.coulomb[i] {
                    return newest[i];
                }
                let mut v = newest[i];
                for j in 0..k {
                    v -= gamma[j] * (self.rounds[j + 1].1[i] - self.rounds[j].1[i]);
                }
                v.max(0.0)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear contraction Φ(F) = A F + b on n rows (A symmetric, eigenvalues spread over
    /// [0.05, `largest`]) and its fixed point: the Coulomb map's linearisation.
    fn linear_map(n: usize, largest: f64) -> (impl Fn(&[f64]) -> Vec<f64>, Vec<f64>) {
        // A = V diag(θ) Vᵀ with V the orthonormal sine basis
        let v = |i: usize, j: usize| {
            (2.0 / (n as f64 + 1.0)).sqrt()
                * (((i + 1) * (j + 1)) as f64 * std::f64::consts::PI / (n as f64 + 1.0)).sin()
        };
        let theta: Vec<f64> = (0..n)
            .map(|j| 0.05 + (largest - 0.05) * j as f64 / (n - 1) as f64)
            .collect();
        let a: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|k| (0..n).map(|j| v(i, j) * theta[j] * v(k, j)).sum())
                    .collect()
            })
            .collect();
        let b: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * i as f64).collect();
        // the fixed point (I − A)⁻¹ b = V diag(1/(1 − θ)) Vᵀ b
        let vb: Vec<f64> = (0..n).map(|j| (0..n).map(|i| v(i, j) * b[i]).sum()).collect();
        let fixed: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| v(i, j) * vb[j] / (1.0 - theta[j])).sum())
            .collect();
        let map = move |f: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| b[i] + (0..n).map(|k| a[i][k] * f[k]).sum::<f64>())
                .collect()
        };
        (map, fixed)
    }

    /// Rounds until max |F − F*| ≤ 10⁻¹⁰ max |F*|, mixed or plain, and the error then.
    fn rounds(n: usize, largest: f64, mixed: bool) -> (usize, f64) {
        let (map, fixed) = linear_map(n, largest);
        let scale = fixed.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let mut mixing = Anderson::new(vec![true; n]);
        let mut f = vec![0.0; n];
        for round in 1..=5000 {
            let next = map(&f);
            f = if mixed { mixing.next(&f, next) } else { next };
            let error = f.iter().zip(&fixed).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            if error <= 1e-10 * scale {
                return (round, error / scale);
            }
        }
        (usize::MAX, f64::INFINITY)
    }

    #[test]
    fn anderson_mixing_reaches_the_fixed_point_in_fewer_rounds() {
        // the plain fixed point gains the contraction per round: log(1e-10)/log(θ) rounds
        for (largest, plain_at_least) in [(0.9, 150), (0.99, 1500)] {
            let (plain, _) = rounds(40, largest, false);
            let (mixed, error) = rounds(40, largest, true);
            assert!(
                (plain_at_least..usize::MAX).contains(&plain),
                "plain {plain} rounds at θ = {largest}"
            );
            assert!(error <= 1e-10, "mixed error {error:e}");
            assert!(
                3 * mixed <= plain,
                "θ ≤ {largest}: {mixed} mixed rounds against {plain} plain"
            );
        }
    }

    #[test]
    fn anderson_mixing_leaves_other_rows_and_keeps_forces_non_negative() {
        // rows 1 and 3 are not Coulomb's: they take Φ's output as it is (row 3 a potential's
        // output, negative where its μ falls)
        let mut mixing = Anderson::new(vec![true, false, true, false]);
        let phi = |f: &[f64]| vec![0.5 * f[0] + 1.0, 7.0, (0.5 * f[2] - 1.0).max(0.0), f[3] - 1.0];
        let mut f = vec![0.0, 0.0, 3.0, 0.0];
        for _ in 0..6 {
            let next = phi(&f);
            let expected = next.clone();
            f = mixing.next(&f, next);
            assert_eq!((f[1], f[3]), (expected[1], expected[3]));
            assert!(f[0] >= 0.0 && f[2] >= 0.0, "{f:?}");
        }
        // the Coulomb rows reach their fixed points 2 and 0 (Φ ≥ 0, as μ λ_ν)
        assert!((f[0] - 2.0).abs() <= 1e-12 && f[2].abs() <= 1e-12, "{f:?}");
    }
}
