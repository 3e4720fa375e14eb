//! GMRES, right-preconditioned, for the few non-symmetric systems of the contact solve (the
//! Newton step on Coulomb's coupled law, docs/method.md §17.2). Written here because faer 0.24's
//! `operator` module has CG, BiCGSTAB and LSMR but no GMRES, and the systems it meets need a
//! handful of iterations with a good preconditioner, where GMRES's minimal residual is the
//! natural choice (BiCGSTAB takes two products and two preconditioner solves per iteration).

/// Solves A x = b by GMRES with right preconditioning (A M⁻¹ y = b, x = M⁻¹ y), without
/// restarts, to ‖b − A x‖ ≤ `relative` ‖b‖ within `iterations` iterations. `apply(x, y)` sets
/// y = A x, `precondition(r, z)` sets z = M⁻¹ r. The residual is GMRES's own (the least-squares
/// one), which equals the true one in exact arithmetic. Returns x and the iterations taken, or
/// None where it did not reach the tolerance.
pub fn gmres(
    mut apply: impl FnMut(&[f64], &mut [f64]),
    mut precondition: impl FnMut(&[f64], &mut [f64]),
    b: &[f64],
    relative: f64,
    iterations: usize,
) -> Option<(Vec<f64>, usize)> {
    let n = b.len();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let norm_b = dot(b, b).sqrt();
    if norm_b == 0.0 {
        return Some((vec![0.0; n], 0));
    }
    // the Arnoldi basis V (each v_j of norm 1), the preconditioned vectors Z = M⁻¹ V, the
    // Hessenberg matrix's columns reduced by Givens rotations (c, s) to R, and g = β e₁ rotated
    let mut basis: Vec<Vec<f64>> = vec![b.iter().map(|v| v / norm_b).collect()];
    let mut preconditioned: Vec<Vec<f64>> = Vec::new();
    let mut r_columns: Vec<Vec<f64>> = Vec::new();
    let mut rotations: Vec<(f64, f64)> = Vec::new();
    let mut g = vec![norm_b];
    let mut w = vec![0.0; n];
    for k in 0..iterations {
        let mut z = vec![0.0; n];
        precondition(&basis[k], &mut z);
        apply(&z, &mut w);
        preconditioned.push(z);
        // modified Gram–Schmidt
        let mut h = vec![0.0; k + 2];
        for (j, v) in basis.iter().enumerate() {
            h[j] = dot(&w, v);
            w.iter_mut().zip(v).for_each(|(a, b)| *a -= h[j] * b);
        }
        h[k + 1] = dot(&w, &w).sqrt();
        for (j, &(c, s)) in rotations.iter().enumerate() {
            let (a, b) = (h[j], h[j + 1]);
            h[j] = c * a + s * b;
            h[j + 1] = -s * a + c * b;
        }
        let rho = h[k].hypot(h[k + 1]);
        if rho == 0.0 {
            return None;
        }
        let (c, s) = (h[k] / rho, h[k + 1] / rho);
        h[k] = rho;
        let next = h[k + 1];
        h.truncate(k + 1);
        rotations.push((c, s));
        g.push(-s * g[k]);
        g[k] *= c;
        r_columns.push(h);
        if g[k + 1].abs() <= relative * norm_b {
            // y = R⁻¹ g, x = Z y
            let size = k + 1;
            let mut y = vec![0.0; size];
            for i in (0..size).rev() {
                let mut v = g[i];
                for (j, yj) in y.iter().enumerate().skip(i + 1) {
                    v -= r_columns[j][i] * yj;
                }
                y[i] = v / r_columns[i][i];
            }
            let mut x = vec![0.0; n];
            for (yj, z) in y.iter().zip(&preconditioned) {
                x.iter_mut().zip(z).for_each(|(a, b)| *a += yj * b);
            }
            return Some((x, size));
        }
        if next == 0.0 {
            return None;
        }
        basis.push(w.iter().map(|v| v / next).collect());
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A non-symmetric, diagonally dominant test matrix.
    fn entry(i: usize, j: usize) -> f64 {
        let (a, b) = (i as f64, j as f64);
        if i == j {
            4.0 + (a * 0.3).sin()
        } else {
            (-(a - b).abs() / 3.0).exp() * if i < j { 0.9 } else { -0.4 }
        }
    }

    fn product(n: usize, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate() {
            *yi = (0..n).map(|j| entry(i, j) * x[j]).sum();
        }
    }

    /// Unpreconditioned and with the Jacobi preconditioner, GMRES meets the tolerance it was
    /// given in the true residual ‖b − A x‖ (to a few roundings), and in n iterations at most
    /// (exact arithmetic: the Krylov space is then all of ℝⁿ); a tolerance it cannot meet in the
    /// iterations allowed gives None.
    #[test]
    fn gmres_meets_its_tolerance_in_the_true_residual() {
        let n = 60;
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos()).collect();
        let norm_b = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        for jacobi in [false, true] {
            for tolerance in [1e-3, 1e-10] {
                let precondition = |r: &[f64], z: &mut [f64]| {
                    for (i, (z, r)) in z.iter_mut().zip(r).enumerate() {
                        *z = if jacobi { r / entry(i, i) } else { *r };
                    }
                };
                let (x, its) = gmres(|x, y| product(n, x, y), precondition, &b, tolerance, n).unwrap();
                let mut ax = vec![0.0; n];
                product(n, &x, &mut ax);
                let residual = ax.iter().zip(&b).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt();
                assert!(
                    residual <= tolerance * norm_b * (1.0 + 1e-4),
                    "jacobi {jacobi}, tolerance {tolerance:e}: {residual:e} after {its} iterations"
                );
                assert!(its < n);
            }
        }
        assert!(gmres(|x, y| product(n, x, y), |r, z| z.copy_from_slice(r), &b, 1e-12, 2).is_none());
    }
}
