//! The recursions against the sums and integrals they stand for, on uniform and on growing steps.

use super::*;
use crate::expr::{Expr, KERNEL_VARIABLES};
use crate::material::{Elasticity, MemoryTensor, MemoryTerm, PlaneModel};

fn elasticity() -> Elasticity {
    Elasticity {
        youngs_modulus: 1.0,
        poisson_ratio: 0.3,
        plane: Some(PlaneModel::Strain),
    }
}

/// Levels t_0 = 0 < t_1 < … of the given sizes.
fn levels(steps: &[f64]) -> Vec<f64> {
    std::iter::once(0.0)
        .chain(steps.iter().scan(0.0, |t, k| {
            *t += k;
            Some(*t)
        }))
        .collect()
}

/// Runs `memory` over scalar "displacements" `us` at `times`, calling `check(n, j, h_n)`.
fn run(memory: &Memory, rules: Rules, times: &[f64], us: &[f64], mut check: impl FnMut(usize, usize, f64)) {
    let mut h = History::new(memory, 1, rules);
    let mut out = [0.0];
    for (n, u) in us.iter().enumerate() {
        let k = if n == 0 { 0.0 } else { times[n] - times[n - 1] };
        h.begin(times[n], k);
        for j in 0..memory.channels().len() {
            h.memory_load(j, &mut out);
            check(n, j, out[0]);
        }
        h.push(&[*u]);
    }
}

/// The trapezoid's h_n by its definition on any levels: Σ_{i<n} ω_i b(t_n − t_i) u_i with
/// ω_i = (k_i + k_{i+1})/2.
fn trapezoid_sum(kernel: &dyn Fn(f64) -> f64, times: &[f64], us: &[f64], n: usize) -> f64 {
    (0..n)
        .map(|i| {
            let left = if i == 0 { 0.0 } else { times[i] - times[i - 1] };
            let right = times[i + 1] - times[i];
            0.5 * (left + right) * kernel(times[n] - times[i]) * us[i]
        })
        .sum()
}

fn check_trapezoid(memory: Memory, times: &[f64]) {
    let us: Vec<f64> = (0..times.len())
        .map(|i| (0.37 * i as f64).sin() + 0.1 * times[i])
        .collect();
    let algorithm = History::new(&memory, 1, Rules::TRAPEZOID).algorithm();
    run(&memory, Rules::TRAPEZOID, times, &us, |n, j, got| {
        let want = trapezoid_sum(&|s| memory.kernel_value(j, s), times, &us, n);
        assert!(
            (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
            "{algorithm} channel {j} n={n}: {got} vs {want}",
        );
    });
}

fn kernels() -> Vec<RelaxationKernel> {
    vec![
        RelaxationKernel::Polynomial {
            coefficients: vec![0.25, 1.0, 1.0],
        },
        RelaxationKernel::Polynomial {
            coefficients: vec![1.0, -2.0, 0.5, 0.3],
        },
        RelaxationKernel::Exponentials {
            terms: vec![(1.0, 0.5), (0.3, 0.01), (2.0, 10.0)],
        },
        RelaxationKernel::General {
            expression: Box::new(Expr::parse("1/(1 + s)", &KERNEL_VARIABLES).unwrap()),
        },
    ]
}

#[test]
fn recursions_equal_the_trapezoid_sum_on_uniform_steps() {
    let times = levels(&[1.0 / 64.0; 200]);
    for kernel in kernels() {
        check_trapezoid(Memory::identity(kernel, &elasticity()), &times);
    }
}

/// Steps growing by 1.2 from 10⁻³ and then cut: the node weights (k_i + k_{i+1})/2 follow.
#[test]
fn recursions_equal_the_trapezoid_sum_on_growing_steps() {
    let mut steps: Vec<f64> = (0..40).map(|n| 1e-3 * 1.2f64.powi(n)).collect();
    steps.extend([0.05, 0.3, 0.01]);
    let times = levels(&steps);
    for kernel in kernels() {
        check_trapezoid(Memory::identity(kernel, &elasticity()), &times);
    }
}

/// ∫ₐᵇ f by 4-point Gauss on 256 panels (degree 7 each: round-off for these smooth integrands).
fn integrate(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let panels = 256;
    let h = (b - a) / panels as f64;
    (0..panels)
        .map(|p| {
            let left = a + p as f64 * h;
            crate::mesh::quadrature::gauss(4)
                .iter()
                .map(|(x, w)| 0.5 * h * w * f(left + 0.5 * h * (x + 1.0)))
                .sum::<f64>()
        })
        .sum()
}

/// ∫₀^{t_n} b(t_n − s) ū(s) ds for the piecewise-linear ū through (t_i, u_i), step by step.
fn linear_integral(kernel: &dyn Fn(f64) -> f64, times: &[f64], us: &[f64], n: usize) -> f64 {
    (1..=n)
        .map(|i| {
            let (a, b) = (times[i - 1], times[i]);
            integrate(a, b, |s| {
                let theta = (s - a) / (b - a);
                kernel(times[n] - s) * (us[i - 1] * (1.0 - theta) + us[i] * theta)
            })
        })
        .sum()
}

/// The exact rule: h_n + β_n u_n (what the step solves) is the integral of the kernel against the
/// piecewise-linear displacement, on growing steps, for exponentials and monomials.
#[test]
fn exact_rule_integrates_the_piecewise_linear_displacement() {
    let mut steps: Vec<f64> = (0..30).map(|n| 2e-3 * 1.25f64.powi(n)).collect();
    steps.extend([0.2, 0.05]);
    let times = levels(&steps);
    let us: Vec<f64> = (0..times.len())
        .map(|i| (0.37 * i as f64).sin() + 0.1 * times[i])
        .collect();
    let rules = Rules {
        exponential: Quadrature::Exact,
        polynomial: Quadrature::Exact,
    };
    for kernel in kernels().into_iter().take(3) {
        let memory = Memory::identity(kernel, &elasticity());
        let algorithm = History::new(&memory, 1, rules).algorithm();
        for (n, got) in memory_integrals(&memory, rules, &times, &us).into_iter().enumerate() {
            let want = linear_integral(&|s| memory.kernel_value(0, s), &times, &us, n);
            assert!(
                (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                "{algorithm} n={n}: {got} vs {want}"
            );
        }
    }
}

/// m_n = h_n + β_n u_n of channel 0 at every level: what the step solves with.
fn memory_integrals(memory: &Memory, rules: Rules, times: &[f64], us: &[f64]) -> Vec<f64> {
    let mut h = History::new(memory, 1, rules);
    let mut out = [0.0];
    (0..times.len())
        .map(|n| {
            let k = if n == 0 { 0.0 } else { times[n] - times[n - 1] };
            h.begin(times[n], k);
            h.memory_load(0, &mut out);
            let m = out[0] + memory.step_coefficients(k, rules)[0] * us[n];
            h.push(&[us[n]]);
            m
        })
        .collect()
}

/// A held displacement: the exact rule gives c τ (1 − e^{−t/τ}) to round-off on steps from 10⁻⁸ τ
/// to 10⁴ τ, where the trapezoid is off by O(1).
#[test]
fn exact_rule_is_exact_for_a_held_displacement_on_any_steps() {
    let tau = 3.0;
    let steps: Vec<f64> = (0..60).map(|n| 3e-8 * 1.6f64.powi(n)).collect();
    let times = levels(&steps);
    let memory = Memory::identity(
        RelaxationKernel::Exponentials {
            terms: vec![(-2.0, tau)],
        },
        &elasticity(),
    );
    let rules = Rules {
        exponential: Quadrature::Exact,
        polynomial: Quadrature::Trapezoid,
    };
    let held = vec![1.0; times.len()];
    for (n, got) in memory_integrals(&memory, rules, &times, &held).into_iter().enumerate() {
        let want = -2.0 * tau * -(-times[n] / tau).exp_m1();
        assert!(
            (got - want).abs() <= 4e-15 * want.abs().max(1e-300),
            "t = {:e}: {got} vs {want}",
            times[n]
        );
    }
    assert!(times.last().unwrap() / tau > 1e4);
}

/// Two channels from terms of every kind, sharing a relaxation time: each channel's recursion
/// equals the trapezoid sum of its own kernel, and the shared atoms are held once.
#[test]
fn channels_share_the_atoms_and_equal_their_sums() {
    let term = |kernel, tensor| MemoryTerm { kernel, tensor };
    let memory = Memory::new(
        vec![
            term(
                RelaxationKernel::Exponentials {
                    terms: vec![(-1.0, 0.5), (0.3, 0.05)],
                },
                MemoryTensor::Moduli { bulk: 1.0, shear: 0.0 },
            ),
            term(
                RelaxationKernel::Exponentials {
                    terms: vec![(-2.0, 0.5)],
                },
                MemoryTensor::Moduli { bulk: 0.0, shear: 1.0 },
            ),
            term(
                RelaxationKernel::Polynomial {
                    coefficients: vec![0.25, 1.0],
                },
                MemoryTensor::Identity,
            ),
            term(
                RelaxationKernel::General {
                    expression: Box::new(Expr::parse("1/(1 + s)", &KERNEL_VARIABLES).unwrap()),
                },
                MemoryTensor::Elasticity,
            ),
        ],
        &elasticity(),
    )
    .unwrap();
    assert_eq!(memory.channels().len(), 2);
    let h = History::new(&memory, 3, Rules::TRAPEZOID);
    assert_eq!(h.exponentials.len(), 2, "τ = 0.5 is shared");
    assert_eq!(
        h.algorithm(),
        "recursive (exponential accumulators + polynomial moments) + direct sum"
    );
    check_trapezoid(memory, &levels(&[0.01; 150]));
}

/// The local error estimate is the difference between the quadratic and the linear
/// interpolant's integrals over the last step: zero for a displacement linear in t (exact rule),
/// and for a quadratic one the estimate matches that difference computed by quadrature.
#[test]
fn local_error_is_the_quadratic_interpolants_excess() {
    let tau = 0.7;
    let memory = Memory::identity(
        RelaxationKernel::Exponentials {
            terms: vec![(1.5, tau)],
        },
        &elasticity(),
    );
    let rules = Rules {
        exponential: Quadrature::Exact,
        polynomial: Quadrature::Exact,
    };
    let times = [0.0, 0.1, 0.25, 0.5];
    for (name, f) in [
        ("linear", (|t: f64| 1.0 + 2.0 * t) as fn(f64) -> f64),
        ("quadratic", |t| t * t),
    ] {
        let mut h = History::new(&memory, 1, rules);
        let mut out = [0.0];
        for n in 0..times.len() {
            let k = if n == 0 { 0.0 } else { times[n] - times[n - 1] };
            h.begin(times[n], k);
            if n == 3 {
                let (u, older) = ([f(times[3])], [f(times[1])]);
                h.local_error(0, &u, Some((&older, times[2] - times[1])), &mut out);
                // ∫ b(t₃ − s) (f − linear interpolant)(s) ds over the last step
                let (a, b) = (times[2], times[3]);
                let want = integrate(a, b, |s| {
                    let theta = (s - a) / (b - a);
                    let linear = f(a) * (1.0 - theta) + f(b) * theta;
                    1.5 * (-(b - s) / tau).exp() * (f(s) - linear)
                });
                assert!((out[0] - want).abs() <= 1e-14, "{name}: {} vs {want}", out[0]);
            }
            h.push(&[f(times[n])]);
        }
    }
}

/// On uniform steps the trapezoid is the uniform scheme's arithmetic bit for bit — what keeps the
/// paper's outputs byte-identical (docs/method.md §20.2): the recursions as they were before steps
/// of any size (u_n's weight ω_n ∈ {½, 1} added when u_n is pushed, then the shift by k; h_n =
/// k Σ c S), written out here, against [`History`] with `==` on every h_n.
#[test]
fn the_uniform_trapezoid_is_the_old_arithmetic_bit_for_bit() {
    let k = 1.0f64 / 32.0;
    let us: Vec<f64> = (0..100).map(|i| (0.37 * i as f64).sin() + 0.1 * i as f64 * k).collect();
    let times: Vec<f64> = (0..us.len()).map(|n| n as f64 * k).collect();
    let (a, terms) = ([0.25, 1.0, 1.0], [(0.5, 0.1), (0.25, 1.0)]);
    for kernel in [
        RelaxationKernel::Polynomial {
            coefficients: a.to_vec(),
        },
        RelaxationKernel::Exponentials { terms: terms.to_vec() },
    ] {
        let polynomial = matches!(kernel, RelaxationKernel::Polynomial { .. });
        let memory = Memory::identity(kernel, &elasticity());
        let (mut moments, mut sums) = (vec![0.0f64; a.len()], vec![0.0f64; terms.len()]);
        let mut h = History::new(&memory, 1, Rules::TRAPEZOID);
        let mut out = [0.0];
        for (n, &u) in us.iter().enumerate() {
            h.begin(times[n], if n == 0 { 0.0 } else { k });
            h.memory_load(0, &mut out);
            let old: f64 = if polynomial {
                a.iter().zip(&moments).map(|(c, p)| k * c * p).fold(0.0, |s, v| s + v)
            } else {
                terms
                    .iter()
                    .zip(&sums)
                    .map(|((c, _), s)| k * c * s)
                    .fold(0.0, |s, v| s + v)
            };
            assert_eq!(out[0].to_bits(), old.to_bits(), "n = {n}: {} against {old}", out[0]);
            h.push(&[u]);
            let omega = if n == 0 { 0.5 } else { 1.0 };
            moments[0] += omega * u;
            for j in (1..moments.len()).rev() {
                let mut binom = 1.0;
                for l in (0..j).rev() {
                    binom = binom * (l + 1) as f64 / (j - l) as f64;
                    let add = binom * k.powi((j - l) as i32) * moments[l];
                    moments[j] += add;
                }
            }
            for ((_, tau), s) in terms.iter().zip(sums.iter_mut()) {
                *s = (-k / tau).exp() * (*s + omega * u);
            }
        }
    }
}
