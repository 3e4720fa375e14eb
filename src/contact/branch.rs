//! The Newton model of the branch a tangential row leaves its kink for (docs/method.md §17.2).
//!
//! A row inside the smoothing zone of its kink (|s| ≤ [`TUNING`]`.branch_zone` ε) feels the
//! smoothed law's curvature F/ε there, so a Newton step from it moves it by about ε, the next by a
//! few ε more: a row about to slip crept out of the zone over four or five directions, each a
//! change of hundreds of rows' curvature for the kept factor. Where the elastic force on the row,
//! t = λ_law − G (a pair: the vector), asks for more than the kink's force F, the row takes
//! instead the model of the branch it leaves for, read [`TUNING`]`.branch_edge` ε out along t: the
//! force F t/|t| in place of the law's in the right-hand side, and the branch's curvature along t
//! (the pair's across t kept). Where t asks for less than F the row sticks inside its kink, at the
//! s_t where the law's force is t (a few ε out), which the law's concave force there lets Newton
//! reach only by steps that each fall short: it takes the law's tangent at s_t instead (force
//! t + j''(s_t)(s − s_t); a pair the Hessian of w j(|x|) at s_t t/|t|), the stick side of the
//! model. Only the direction changes: the line search still measures the energy and its true
//! slope, and a direction that does not descend is replaced by the law's own.

use super::hessian::{pair_block, LawHessian};
use super::problem::ContactProblem;
use super::settings::TUNING;

/// The branch model's Hessian and gradient on the free rows `free` at r, or None where no row
/// takes it. `kink` is each row's kink width ε (∞: none).
pub fn model(
    problem: &ContactProblem,
    r: &[f64],
    free: &[usize],
    (hessian, grad): (&LawHessian, &[f64]),
    kink: &[f64],
) -> Option<(LawHessian, Vec<f64>)> {
    let first = problem.branch_from.filter(|&f| f < problem.m())?;
    let laws = problem.laws;
    let mut h = hessian.clone();
    let mut g = grad.to_vec();
    let mut changed = 0;
    for (i, &p) in free.iter().enumerate() {
        let kw = kink[p];
        if p < first || !kw.is_finite() {
            continue;
        }
        let edge = TUNING.branch_edge * kw;
        match problem.partner(p) {
            None => {
                let s = r[p] - problem.origin(p);
                if s.abs() > TUNING.branch_zone * kw {
                    continue;
                }
                let law = laws.force(p, s);
                let t = law - grad[p];
                let f = laws.force(p, t.signum() * edge);
                let (f, k) = if t.abs() <= f.abs() {
                    // the stick side: the law's tangent where it balances t
                    let Some(st) = balancing_point(problem, p, t.abs(), edge) else {
                        continue;
                    };
                    let st = t.signum() * st;
                    let k = laws.stiffness(p, st);
                    (t + k * (s - st), k)
                } else {
                    (f, laws.stiffness(p, t.signum() * edge))
                };
                if k.is_nan() || k <= 0.0 {
                    continue;
                }
                g[p] = grad[p] - law + f;
                h.diagonal[i] = k;
                h.convex_diagonal[i] = k.max(0.0);
                changed += 1;
            }
            Some(q) if q > p => {
                let Some(j) = h.partner[i] else {
                    continue;
                };
                let (x, rho) = problem.pair_at(r, p, q);
                if rho > TUNING.branch_zone * kw {
                    continue;
                }
                let fl = if rho > 0.0 { laws.force(p, rho) / rho } else { 0.0 };
                let t = [fl * x[0] - grad[p], fl * x[1] - grad[q]];
                let tn = t[0].hypot(t[1]);
                let f = laws.force(p, edge);
                if tn == 0.0 {
                    continue;
                }
                let n = [t[0] / tn, t[1] / tn];
                let (a, b) = if tn <= f {
                    // the stick side: the law's tangent at x_t = ρ_t t/|t|, where it balances t
                    let Some(rt) = balancing_point(problem, p, tn, edge) else {
                        continue;
                    };
                    let (a, b) = (laws.stiffness(p, rt), tn / rt);
                    let (d, c) = pair_block(a, b, n);
                    let e = [x[0] - rt * n[0], x[1] - rt * n[1]];
                    g[p] = grad[p] - fl * x[0] + t[0] + d * e[0] + c * e[1];
                    let (d, c) = pair_block(a, b, [n[1], n[0]]);
                    g[q] = grad[q] - fl * x[1] + t[1] + d * e[1] + c * e[0];
                    (a, b)
                } else {
                    g[p] = grad[p] - fl * x[0] + f * n[0];
                    g[q] = grad[q] - fl * x[1] + f * n[1];
                    (laws.stiffness(p, edge), h.pair[i].1)
                };
                if !(a > 0.0 && b > 0.0) {
                    continue;
                }
                // row q sees the pair from its side (n with its components swapped); the two
                // rows share row p's coupling
                h.set_pair_row(i, (a, b, n));
                h.set_pair_row(j, (a, b, [n[1], n[0]]));
                (h.coupling[j], h.convex_coupling[j]) = (h.coupling[i], h.convex_coupling[i]);
                changed += 2;
            }
            _ => {}
        }
    }
    (changed > 0).then_some((h, g))
}

/// The ρ in (0, edge) where row p's law gives the force `target` (0 < target below its force at
/// `edge`), by bisection (the law's force grows from 0 at the kink), or None.
fn balancing_point(problem: &ContactProblem, p: usize, target: f64, edge: f64) -> Option<f64> {
    if target.is_nan() || target <= 0.0 {
        return None;
    }
    let (mut lo, mut hi) = (0.0f64, edge);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if problem.laws.force(p, mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (hi > 0.0).then_some(0.5 * (lo + hi))
}
