//! The contact solve's tests: the Newton loop with each direction solver, the kept factor and
//! its update, the product by W, a pair's vector law and the branch model.

use super::condensed::{DenseNormalStiffness, NormalStiffness};
use super::direction::kept::{preconditioned, KeptFactor};
use super::direction::w_product::WProduct;
use super::direction::{DirectionSolver, NewtonSystem};
use super::hessian::LawHessian;
use super::newton::ActiveSetSolver;
use super::nodal::NodalLaws;
use super::outcome::ContactOutcome;
use super::problem::ContactProblem;
use super::settings::ContactSettings;
use super::state::{ContactState, NodeStatus, SolverCache};
use super::trace::Silent;
use crate::linalg::dense::DenseCholesky;

/// A smooth SPD compliance on m nodes of a line: W_pq = e^{−|x_p − x_q|/ℓ} + 0.05 δ_pq, so
/// that Q = W⁻¹ couples every pair, as a contact surface's condensed stiffness does.
fn operator(m: usize) -> DenseNormalStiffness {
    let x = |p: usize| p as f64 / m as f64;
    let w: Vec<f64> = (0..m * m)
        .map(|k| {
            let (p, q) = (k / m, k % m);
            (-(x(p) - x(q)).abs() / 0.1).exp() + if p == q { 0.05 } else { 0.0 }
        })
        .collect();
    DenseNormalStiffness::from_w(w, m).unwrap()
}

/// The tests' surface problem: no origin, a bound per row, pairs where given.
fn problem<'a>(
    operator: &'a dyn NormalStiffness,
    laws: &'a NodalLaws,
    bound: &'a [f64],
    pairs: Option<&'a [Option<usize>]>,
) -> ContactProblem<'a> {
    ContactProblem {
        bound: Some(bound),
        pairs,
        ..ContactProblem::new(operator, laws)
    }
}

/// A `dense_limit` no free set passes: every direction by a dense factorisation.
const ALWAYS_DENSE: usize = usize::MAX;

/// A solver of tolerance 1e-12, at most 100 iterations, its factor kept above `dense_limit` rows.
fn solver(dense_limit: usize) -> ActiveSetSolver<'static> {
    ActiveSetSolver {
        settings: ContactSettings {
            tolerance: 1e-12,
            max_iterations: 100,
            dense_limit,
            ..ContactSettings::default()
        },
        trace: &Silent,
    }
}

/// A growing load's shape along the surface, x ∈ [0, 1) at time t: a moving middle part.
fn shape(x: f64, t: f64) -> f64 {
    t * (std::f64::consts::PI * x).sin() * (1.0 + 0.3 * (7.0 * x + t).cos())
}

/// Steps n = 1..=steps with free displacements d(t_n), t_n = n / steps, from a surface
/// apart: per step d, the state after it and what the solve did.
fn run_steps(
    (problem, solver): (&ContactProblem, &ActiveSetSolver),
    steps: usize,
    d: impl Fn(f64) -> Vec<f64>,
) -> Vec<(Vec<f64>, ContactState, ContactOutcome)> {
    let mut state = ContactState::new(problem.m());
    let mut cache = SolverCache::default();
    (1..=steps)
        .map(|n| {
            let d = d(n as f64 / steps as f64);
            let outcome = solver.solve(problem, &d, &mut state, &mut cache).unwrap();
            (d, state.clone(), outcome)
        })
        .collect()
}

/// Σ of one count of the outcomes.
fn total(run: &[(Vec<f64>, ContactState, ContactOutcome)], count: impl Fn(&ContactOutcome) -> usize) -> usize {
    run.iter().map(|(_, _, o)| count(o)).sum()
}

/// Steps of a growing load that pushes a moving middle part onto the bound: the active set
/// changes from step to step and within steps. Directions through the reused factorisation
/// (dense_limit = 0) give the dense path's solutions to 1e-10, with fewer factorisations than
/// directions; the contact law (r ≤ g, η ≥ 0 on the bound, λ = 0 off it) holds at the end.
#[test]
fn reused_factorisation_gives_the_dense_directions() {
    let m = 240;
    let op = operator(m);
    let bound = vec![0.2; m];
    let laws = NodalLaws::default();
    let load = |t: f64| (0..m).map(|p| 0.5 * shape(p as f64 / m as f64, t)).collect();
    let p = problem(&op, &laws, &bound, None);
    let dense = run_steps((&p, &solver(ALWAYS_DENSE)), 8, load);
    let reused = run_steps((&p, &solver(0)), 8, load);
    assert_eq!(total(&dense, |o| o.iterative), 0);
    assert_eq!(total(&dense, |o| o.factorisations), total(&dense, |o| o.iterations));
    let (directions, factorisations) = (total(&reused, |o| o.iterations), total(&reused, |o| o.factorisations));
    assert!(
        total(&reused, |o| o.iterative) > 0 && factorisations < directions,
        "{factorisations} of {directions}"
    );
    let mut active_sets = std::collections::HashSet::new();
    for ((d, a, _), (_, b, _)) in dense.iter().zip(&reused) {
        let scale = a.normal_displacement.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        for p in 0..m {
            assert!((a.normal_displacement[p] - b.normal_displacement[p]).abs() <= 1e-10 * scale);
            assert!(b.normal_displacement[p] <= bound[p]);
            match b.status[p] {
                NodeStatus::OnBound => assert!(b.force[p] >= -1e-10 * scale),
                _ => assert!(b.force[p].abs() <= 1e-9 * scale, "λ off the bound at {p}"),
            }
        }
        assert!(d.iter().any(|v| *v > 0.2) == (b.status.contains(&NodeStatus::OnBound)));
        active_sets.insert(b.status.iter().filter(|s| **s == NodeStatus::OnBound).count());
    }
    assert!(active_sets.len() >= 4, "the active set moved: {active_sets:?}");
}

/// A Newton system on the free rows `free` with the laws' diagonal `e`, the pair couplings `c` of
/// `partner` (over all rows), the gradient `grad` and CG's accuracy 10⁻¹³.
fn system<'a>(free: &'a [usize], hessian: &'a LawHessian, zeros: &'a [f64], grad: &'a [f64]) -> NewtonSystem<'a> {
    NewtonSystem {
        free,
        hessian,
        proximal: zeros,
        gradient: grad,
        forcing: 1e-13,
    }
}

/// The laws' Hessian with diagonal `e` and the couplings `c` of the pairs `partner`.
fn hessian_of(e: &[f64], c: &[f64], partner: &[Option<usize>]) -> LawHessian {
    LawHessian {
        coupling: c.to_vec(),
        convex_coupling: c.to_vec(),
        partner: partner.to_vec(),
        ..LawHessian::diagonal(e)
    }
}

/// The direction of (Q_ℐℐ + diag(e) + couplings) x = G_ℐ by a fresh dense factorisation.
fn exact_direction(op: &DenseNormalStiffness, free: &[usize], h: &LawHessian, grad: &[f64]) -> Vec<f64> {
    DenseCholesky::new(free.len(), |i, j| {
        op.q(free[i], free[j])
            + if i == j {
                h.diagonal[i]
            } else if h.partner[i] == Some(j) {
                h.coupling[i]
            } else {
                0.0
            }
    })
    .unwrap()
    .solve(&free.iter().map(|&p| grad[p]).collect::<Vec<_>>())
}

/// x against the exact direction to 1e-10 of its size.
fn assert_direction(x: &[f64], exact: &[f64]) {
    let scale = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for (a, b) in x.iter().zip(exact) {
        assert!((a - b).abs() <= 1e-10 * scale, "{a} against {b}");
    }
}

/// The kept factor updated on the rows whose curvature moved (a single row stiffened ten
/// thousand times, one dropped to 0, a pair's coupling turned over) is the new Newton matrix:
/// CG converges at once, to the fresh factorisation's direction; Z's columns are kept, so a
/// second change on the same rows needs none; the other rows' small changes (5 %) cost a few
/// iterations more, not a refactorisation.
#[test]
fn a_low_rank_update_of_the_kept_factor_is_the_new_newton_matrix() {
    let m = 120;
    let op = operator(m);
    let (bound, laws) = (vec![0.2; m], NodalLaws::default());
    let p = problem(&op, &laws, &bound, None);
    let on = ContactSettings::default().strategies;
    let free: Vec<usize> = (0..m).collect();
    let zeros = vec![0.0; m];
    let mut partner = vec![None; m];
    for (a, b) in [(10, 11), (40, 41)] {
        (partner[a], partner[b]) = (Some(b), Some(a));
    }
    let e0: Vec<f64> = (0..m).map(|r| 0.3 * p.c(r) * (1 + r % 7) as f64).collect();
    let c0: Vec<f64> = (0..m).map(|r| partner[r].map_or(0.0, |_| 0.05 * p.c(r))).collect();
    let grad: Vec<f64> = (0..m).map(|r| (0.37 * r as f64).sin()).collect();
    let h0 = hessian_of(&e0, &c0, &partner);
    let mut kept = KeptFactor::new(
        &p,
        &system(&free, &h0, &zeros, &grad),
        &free,
        (&mut ContactOutcome::default(), true),
    );
    let mut solve = |e: &[f64], c: &[f64]| {
        let h = hessian_of(e, c, &partner);
        let s = system(&free, &h, &zeros, &grad);
        let (direction, iterations) = preconditioned(&p, &mut kept, &s, &on).unwrap();
        let exact = exact_direction(&op, &free, &h, &grad);
        assert_direction(&direction.x, &exact);
        (iterations, kept.kept_columns())
    };
    let (mut e, mut c) = (e0.clone(), c0.clone());
    e[3] *= 1e4;
    // a row dropped to 0 from 2.1 Q_pp, and the pair's coupling turned over, past `moved` of its
    // rows' Q_pp + e_p
    e[55] = 0.0;
    (c[40], c[41]) = (-1.2 * p.c(40), -1.2 * p.c(40));
    let (iterations, columns) = solve(&e, &c);
    assert!(iterations <= 2);
    // the rows of 𝒰: 3, 55 and both rows of the pair (40, 41)
    assert_eq!(columns, 4);
    e[3] *= 2.0;
    e[55] = 5.0 * p.c(55);
    let (iterations, columns) = solve(&e, &c);
    assert!(iterations <= 2);
    assert_eq!(columns, 4, "no new columns for the same rows");
    for r in (0..m).step_by(5) {
        e[r] *= 1.05;
    }
    let (iterations, _) = solve(&e, &c);
    assert!((3..=12).contains(&iterations), "{iterations} iterations");
}

/// The kept factor serves a free set that moved since it was formed (docs/method.md §9.2): rows
/// that left the free set are pinned by the update, rows a law holds stiffly stay outside the
/// factor (Jacobi), a row whose curvature moved is updated; CG reaches the dense direction of the
/// new free set to 10⁻¹³ in a few iterations (4: the stiff rows' coupling left to CG is about
/// 1/√(10⁵) of their diagonal). A row outside the factor that no law holds stiffly any more is
/// not served: the solver refactors.
#[test]
fn the_kept_factor_serves_a_free_set_that_moved() {
    let m = 120;
    let op = operator(m);
    let (bound, laws) = (vec![0.2; m], NodalLaws::default());
    let p = problem(&op, &laws, &bound, None);
    let on = ContactSettings::default().strategies;
    let zeros = vec![0.0; m];
    let grad: Vec<f64> = (0..m).map(|r| (0.37 * r as f64).sin()).collect();
    // formed with every row free and rows 100..120 held stiffly: those stay out of it
    let mut e: Vec<f64> = (0..m).map(|r| 0.3 * p.c(r) * (1 + r % 7) as f64).collect();
    for v in &mut e[100..] {
        *v *= 1e5;
    }
    let all: Vec<usize> = (0..m).collect();
    let h = LawHessian::diagonal(&e);
    let formed = system(&all, &h, &zeros, &grad);
    let factored: Vec<usize> = (0..m)
        .filter(|&i| !super::direction::kept::stiff(&p, &formed, &e, i, super::settings::TUNING.stiff))
        .collect();
    assert_eq!(factored, (0..100).collect::<Vec<_>>());
    let mut kept = KeptFactor::new(&p, &formed, &factored, (&mut ContactOutcome::default(), true));
    // now rows 0..5, 30 and 31 are on their bound and row 50 stiffened a hundred times
    let free: Vec<usize> = (5..m).filter(|r| ![30, 31].contains(r)).collect();
    e[50] *= 100.0;
    let curvature: Vec<f64> = free.iter().map(|&r| e[r]).collect();
    let h = LawHessian::diagonal(&curvature);
    let s = system(&free, &h, &zeros, &grad);
    let (direction, iterations) = preconditioned(&p, &mut kept, &s, &on).unwrap();
    let exact = exact_direction(&op, &free, &h, &grad);
    assert_direction(&direction.x, &exact);
    assert!(iterations <= 6, "{iterations} iterations");
    // rows 100..106 leave the stiff part of their law: outside the factor and soft, not served
    let mut curvature = curvature;
    for (i, &r) in free.iter().enumerate() {
        if (100..106).contains(&r) {
            curvature[i] = 0.5 * p.c(r);
        }
    }
    let h = LawHessian::diagonal(&curvature);
    let s = system(&free, &h, &zeros, &grad);
    assert!(preconditioned(&p, &mut kept, &s, &on).is_none());
}

/// Q without W formed: the solver cannot take a direction in W, except (with
/// `products`, as on the trailing block's condensation, docs/method.md §9.7) where the
/// system has no rows and a product by W is all it needs.
struct WithoutW<'a> {
    op: &'a DenseNormalStiffness,
    products: bool,
}

impl NormalStiffness for WithoutW<'_> {
    fn m(&self) -> usize {
        self.op.m
    }
    fn apply_q(&self, x: &[f64], y: &mut [f64]) {
        self.op.apply_q(x, y)
    }
    fn q(&self, p: usize, r: usize) -> f64 {
        self.op.q(p, r)
    }
    fn apply_w(&self, x: &[f64], y: &mut [f64]) -> bool {
        if self.products {
            crate::linalg::dense::matvec_row_major(&self.op.w, self.op.m, x, y);
        }
        self.products
    }
}

/// A surface that starts apart against a rigid bound, no law: the first direction has every
/// row free and none curved, so with products by W (and no W) it is Δ = W G. Over steps of a
/// growing load that moves the active set, the solutions are those of the path in Q to
/// 1e-10 with the same Newton iterations, and only such directions go by W (the others need
/// W's entries).
#[test]
fn a_direction_without_rows_in_w_is_a_product_by_w() {
    let m = 240;
    let op = operator(m);
    let bound = vec![0.2; m];
    let laws = NodalLaws::default();
    // the direction itself: Q Δ = G on all rows, to round-off
    let products = WithoutW {
        op: &op,
        products: true,
    };
    let by_products = problem(&products, &laws, &bound, None);
    let dense = solver(ALWAYS_DENSE);
    let free: Vec<usize> = (0..m).collect();
    let g: Vec<f64> = (0..m).map(|p| (0.05 * p as f64).cos()).collect();
    let zeros = vec![0.0; m];
    let in_w = |free: &[usize]| {
        let hessian = LawHessian::at(&by_products, &zeros, free);
        let s = system(free, &hessian, &zeros[..free.len()], &g);
        WProduct
            .direction(&by_products, &s, &mut ContactOutcome::default())
            .map(|d| d.x)
    };
    let x = in_w(&free).unwrap();
    let mut qx = vec![0.0; m];
    op.apply_q(&x, &mut qx);
    for (a, b) in qx.iter().zip(&g) {
        assert!((a - b).abs() <= 1e-11, "Q Δ = {a} against G = {b}");
    }
    // a held row: the system in W has a row, whose entries W would have to give
    assert!(in_w(&free[1..]).is_none());
    let load = |t: f64| (0..m).map(|p| 0.5 * shape(p as f64 / m as f64, t)).collect();
    let only_q = WithoutW {
        op: &op,
        products: false,
    };
    let in_q = run_steps((&problem(&only_q, &laws, &bound, None), &dense), 6, load);
    let by_w = run_steps((&by_products, &dense), 6, load);
    assert_eq!(total(&in_q, |o| o.in_w), 0);
    let (in_w, directions) = (total(&by_w, |o| o.in_w), total(&by_w, |o| o.iterations));
    assert_eq!(total(&in_q, |o| o.iterations), directions);
    // step 1 starts apart (every row free, no curvature); later steps start from a held set
    assert!(in_w >= 1 && in_w < directions, "{in_w} of {directions} directions by W");
    let scale = in_q.last().unwrap().1.force.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for ((_, a, _), (_, b, _)) in in_q.iter().zip(&by_w) {
        assert_eq!(a.status, b.status);
        for (x, y) in a.force.iter().zip(&b.force) {
            assert!((x - y).abs() <= 1e-10 * scale, "{x} against {y}");
        }
        for (x, y) in a.normal_displacement.iter().zip(&b.normal_displacement) {
            assert!((x - y).abs() <= 1e-10, "{x} against {y}");
        }
    }
}

/// The tests' tangential rows: no bound, the branch model from `branch_from`; solved to 1e-13
/// by dense directions.
fn tangential_rows<'a>(
    operator: &'a DenseNormalStiffness,
    laws: &'a NodalLaws,
    pairs: Option<&'a [Option<usize>]>,
    branch_from: Option<usize>,
) -> (ContactProblem<'a>, ActiveSetSolver<'static>) {
    let problem = ContactProblem {
        pairs,
        branch_from,
        ..ContactProblem::new(operator, laws)
    };
    let mut solver = solver(ALWAYS_DENSE);
    solver.settings.tolerance = 1e-13;
    (problem, solver)
}

/// The branch-model tests' tangential rows under the load q, solved with the laws' own model
/// and with the branch model.
fn with_and_without_branch_model(
    operator: &DenseNormalStiffness,
    laws: &NodalLaws,
    pairs: Option<&[Option<usize>]>,
    q: &[f64],
) -> [(ContactState, ContactOutcome); 2] {
    [None, Some(0)].map(|branch_from| {
        let mut state = ContactState::new(q.len());
        let (problem, solver) = tangential_rows(operator, laws, pairs, branch_from);
        let outcome = (solver.solve_forces(&problem, q, &mut state, &mut SolverCache::default())).unwrap();
        (state, outcome)
    })
}

/// The tests' operator on k nodes (single rows), and the same for k nodes of two uncoupled
/// tangential rows each (3D pairs), with the pairing.
fn single_and_paired(k: usize) -> (DenseNormalStiffness, DenseNormalStiffness, Vec<Option<usize>>) {
    let scalar = operator(k);
    let w: Vec<f64> = (0..4 * k * k)
        .map(|i| {
            let (p, q) = (i / (2 * k), i % (2 * k));
            if p % 2 == q % 2 {
                scalar.w[(p / 2) * k + q / 2]
            } else {
                0.0
            }
        })
        .collect();
    let paired = DenseNormalStiffness::from_w(w, 2 * k).unwrap();
    (scalar, paired, (0..2 * k).map(|p| Some(p ^ 1)).collect())
}

/// The vector law of a pair (docs/method.md §17.3): k pairs with an isotropic compliance
/// W = W₁ ⊗ I₂ (each pair's two rows see the same scalar coupling) and Tresca's law F ρ_ε(|s|).
/// The problem is then equivariant under a rotation of every pair's plane: the free
/// displacements rotated by θ give the solution rotated by θ (to 1e-12), which two scalar
/// laws on the rows would break (their square cone has axes). At every pair the force is the
/// law's, F ρ/√(ρ² + ε²) along the slip where it slips, shorter than F where it sticks, and
/// both kinds occur.
#[test]
fn a_pair_law_acts_on_the_vector_and_is_isotropic() {
    use crate::contact::law::ContactLaw;
    let k = 40;
    let m = 2 * k;
    let (_, op, pairs) = single_and_paired(k);
    let epsilon = 1e-8;
    let law = ContactLaw::smoothed_magnitude(epsilon);
    let bound_force = 0.3;
    let laws = NodalLaws::uniform(law, &vec![bound_force; m]);
    let solve = |theta: f64| {
        let (c, s) = (theta.cos(), theta.sin());
        // a slip field that is large at one end and small at the other: both zones
        let d: Vec<f64> = (0..k)
            .flat_map(|i| {
                let x = i as f64 / k as f64;
                let (a, b) = (1.2 * x * x, 0.4 * x);
                [c * a - s * b, s * a + c * b]
            })
            .collect();
        let mut state = ContactState::new(m);
        let (problem, solver) = tangential_rows(&op, &laws, Some(&pairs), None);
        solver
            .solve(&problem, &d, &mut state, &mut SolverCache::default())
            .unwrap();
        state
    };
    let base = solve(0.0);
    let theta: f64 = 0.7;
    let turned = solve(theta);
    let (c, s) = (theta.cos(), theta.sin());
    let scale = base.normal_displacement.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let (mut stick, mut slip) = (0, 0);
    for i in 0..k {
        let (x, y) = (base.normal_displacement[2 * i], base.normal_displacement[2 * i + 1]);
        let (u, v) = (turned.normal_displacement[2 * i], turned.normal_displacement[2 * i + 1]);
        assert!((c * x - s * y - u).abs() <= 1e-12 * scale && (s * x + c * y - v).abs() <= 1e-12 * scale);
        let (f, g) = (base.force[2 * i], base.force[2 * i + 1]);
        let rho = x.hypot(y);
        let along = bound_force / rho.hypot(epsilon);
        if f.hypot(g) < bound_force * (1.0 - 1e-6) {
            stick += 1;
        } else {
            slip += 1;
            assert!((f - along * x).abs() <= 1e-10 * bound_force && (g - along * y).abs() <= 1e-10 * bound_force);
        }
    }
    assert!(stick > 0 && slip > 0, "{stick} stick, {slip} slip");
}

/// Rows that start a solve at their kink (the slip increments' origin, as every step of
/// Tresca or Coulomb friction does) and must slip: with the branch model (docs/method.md
/// §17.2) the solve reaches the law's own solution (to 10⁻¹² of the largest slip) in fewer
/// directions, for single rows and for the pairs of 3D, where the slip field mixes stick
/// and slip.
#[test]
fn rows_leaving_their_kink_take_the_branch_model() {
    use crate::contact::law::ContactLaw;
    let k = 40;
    let (scalar, paired, pairs) = single_and_paired(k);
    let single = |i: usize| 1.2 * (i as f64 / k as f64).powi(2) - 0.3;
    // (operator, pairs, free displacements d)
    type Case<'a> = (&'a DenseNormalStiffness, Option<&'a [Option<usize>]>, Vec<f64>);
    let cases: [Case; 2] = [
        (&scalar, None, (0..k).map(single).collect()),
        (
            &paired,
            Some(&pairs),
            (0..k).flat_map(|i| [single(i), 0.4 * i as f64 / k as f64]).collect(),
        ),
    ];
    for (op, pairs, d) in cases {
        let m = d.len();
        let laws = NodalLaws::uniform(ContactLaw::smoothed_magnitude(1e-8), &vec![0.3; m]);
        let mut q = vec![0.0; m];
        op.apply_q(&d, &mut q);
        let [(own, own_outcome), (branch, branch_outcome)] = with_and_without_branch_model(op, &laws, pairs, &q);
        let scale = own.normal_displacement.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (a, b) in own.normal_displacement.iter().zip(&branch.normal_displacement) {
            assert!((a - b).abs() <= 1e-12 * scale, "{a} against {b}");
        }
        let stuck = own
            .normal_displacement
            .iter()
            .filter(|v| v.abs() < 1e-6 * scale)
            .count();
        assert!(stuck > 0 && stuck < m, "{stuck} of {m} rows stick");
        eprintln!(
            "pairs {}: {} directions with the branch model, {} with the law's own",
            pairs.is_some(),
            branch_outcome.iterations,
            own_outcome.iterations
        );
        assert!(branch_outcome.iterations < own_outcome.iterations);
    }
}

/// Rows that stick, pressed by less than their bound force F (here 0.5 F to 0.99 F): the
/// smoothed law's solution lies inside its kink, at |s| = ε t/√(F² − t²) (up to 7 ε), which
/// the law's own Newton model, concave there, reaches only by steps that fall short each time.
/// The stick side of the branch model (the law's tangent where it balances t, docs/method.md
/// §17.2) reaches the same solution (to 10⁻⁹ of its largest |s|) in fewer directions, for
/// single rows and for pairs.
#[test]
fn rows_that_stick_inside_their_kink_take_the_stick_side_model() {
    use crate::contact::law::ContactLaw;
    let k = 40;
    let (scalar, paired, pairs) = single_and_paired(k);
    let bound = 0.3;
    // the demand of node i: between 0.5 F and 0.99 F, its sign (its direction) turning
    let share = |i: usize| 0.5 + 0.49 * (i as f64 / (k - 1) as f64);
    let angle = |i: usize| 0.37 * i as f64;
    type Case<'a> = (&'a DenseNormalStiffness, Option<&'a [Option<usize>]>, Vec<f64>);
    let cases: [Case; 2] = [
        (
            &scalar,
            None,
            (0..k).map(|i| bound * share(i) * angle(i).cos().signum()).collect(),
        ),
        (
            &paired,
            Some(&pairs),
            (0..k)
                .flat_map(|i| [bound * share(i) * angle(i).cos(), bound * share(i) * angle(i).sin()])
                .collect(),
        ),
    ];
    for (op, pairs, q) in cases {
        let m = q.len();
        let laws = NodalLaws::uniform(ContactLaw::smoothed_magnitude(1e-8), &vec![bound; m]);
        let [(own, own_outcome), (model, model_outcome)] = with_and_without_branch_model(op, &laws, pairs, &q);
        let largest = own.normal_displacement.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        // every row inside its kink: |s| of a few ε, the largest about 7 ε
        assert!(largest > 3e-8 && largest < 1e-7, "largest |s| {largest}");
        for (a, b) in own.normal_displacement.iter().zip(&model.normal_displacement) {
            assert!((a - b).abs() <= 1e-9 * largest, "{a} against {b}");
        }
        eprintln!(
            "pairs {}: {} directions with the stick-side model, {} with the law's own",
            pairs.is_some(),
            model_outcome.iterations,
            own_outcome.iterations
        );
        assert!(model_outcome.iterations < own_outcome.iterations);
    }
}
