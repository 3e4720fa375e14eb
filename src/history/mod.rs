//! The memory term on time levels t_0 = 0 < t_1 < … of any step sizes k_n (docs/method.md §5,
//! §20.2): at step n
//!
//! ```text
//!     m_n = ∫₀^{t_n} b(t_n − s) u(s) ds  ≈  h_n + β_n u_n,
//! ```
//!
//! h_n from the displacements of the steps before, β_n the share of u_n in the step matrix, with
//! several channels j (docs/method.md §15) one h_n^j each. The kernels' atoms (each distinct τ,
//! each monomial degree, each expression) are accumulated once and shared by the channels, each
//! atom by its rule ([`Quadrature`], `time.quadrature`):
//!
//! * **trapezoid** (the paper's (3.2)): h_n = Σ_{i<n} ω_i b(t_n − t_i) u_i with the node weights
//!   ω_i = (k_i + k_{i+1})/2 (k_0 = 0), β_n = (k_n/2) b(0). The weight of u_{n−1} needs k_n, so it
//!   is added when step n begins. The sums are kept in units of the first step k_1: on uniform
//!   steps the arithmetic of the uniform scheme, bit for bit (ω_0 = ½, ω_i = 1).
//!   - exponentials: S ← e^{−k_n/τ} (S + ω_{n−1} u_{n−1});
//!   - monomials: moments P_j = Σ_{i<n} ω_i (t_n − t_i)^j u_i, shifted binomially by k_n (all
//!     coefficients positive: no cancellation);
//!   - expressions: the direct sum over the stored u_i (O(N) memory and work per step).
//! * **exact** for u linear over each step (Taylor, Pister & Goudreau): the integral I_{n−1} at
//!   t_{n−1} is carried to t_n and the step's weights added, h_n = carry(I_{n−1}) + w_prev u_{n−1},
//!   I_n = h_n + w_cur u_n (src/material/quadrature.rs): exponentials (carry e^{−k_n/τ}) and
//!   monomials (the binomial shift of the moments ∫ (t_n − s)^j u ds).

pub use crate::material::quadrature::Rules;
use crate::material::quadrature::{self, Quadrature};
use crate::material::{Memory, RelaxationKernel};

/// What channel j takes of each accumulated atom: its kernel b_j(s) = Σ c_τ e^{−s/τ} +
/// Σ a_d s^d + Σ w_g e_g(s) on the atoms of the whole memory (docs/method.md §15.3).
#[derive(Clone, Debug)]
struct ChannelCoefficients {
    exponential: Vec<f64>,
    polynomial: Vec<f64>,
    general: Vec<f64>,
}

/// The history of a run: accumulators of the atoms of all the memory's kernels — one per
/// distinct relaxation time, one per monomial degree, and the stored displacements if some
/// kernel is a general expression — shared by the channels.
#[derive(Clone, Debug)]
pub struct History {
    rules: Rules,
    n_dof: usize,
    /// (τ, accumulator) per distinct relaxation time.
    exponentials: Vec<(f64, Vec<f64>)>,
    /// The moments, degree 0 up.
    moments: Vec<Vec<f64>>,
    /// The general kernels e_g (direct sum) and (t_i, ω_i, u_i) of the levels before.
    general: Vec<RelaxationKernel>,
    past: Vec<(f64, f64, Vec<f64>)>,
    channels: Vec<ChannelCoefficients>,
    /// u_{n−1}, the displacement last pushed (None before step 0), its time and step size.
    last: Option<(f64, f64, Vec<f64>)>,
    /// The first non-zero step size: the unit of the trapezoid's sums.
    unit: Option<f64>,
    /// The step begun: its time and size (None after a push).
    begun: Option<(f64, f64)>,
}

impl History {
    /// An empty history (before step 0) of `memory`'s channels for `n_dof` unknowns.
    pub fn new(memory: &Memory, n_dof: usize, rules: Rules) -> Self {
        let terms = memory.terms();
        let mut taus: Vec<f64> = Vec::new();
        let mut degree = 0;
        let mut general = Vec::new();
        for t in terms {
            match &t.kernel {
                RelaxationKernel::Exponentials { terms } => {
                    for (_, tau) in terms {
                        if !taus.contains(tau) {
                            taus.push(*tau);
                        }
                    }
                }
                RelaxationKernel::Polynomial { coefficients } => degree = degree.max(coefficients.len()),
                RelaxationKernel::General { .. } => general.push(t.kernel.clone()),
            }
        }
        let channels = memory
            .channels()
            .iter()
            .map(|c| {
                let mut coefficients = ChannelCoefficients {
                    exponential: vec![0.0; taus.len()],
                    polynomial: vec![0.0; degree],
                    general: Vec::new(),
                };
                for (t, &w) in terms.iter().zip(&c.weights) {
                    // w = 1 (a single kernel) keeps the kernel's own coefficients exactly
                    match &t.kernel {
                        RelaxationKernel::Exponentials { terms } => {
                            for (c, tau) in terms {
                                let at = taus.iter().position(|t| t == tau).expect("collected above");
                                coefficients.exponential[at] += w * c;
                            }
                        }
                        RelaxationKernel::Polynomial { coefficients: a } => {
                            for (d, a) in a.iter().enumerate() {
                                coefficients.polynomial[d] += w * a;
                            }
                        }
                        RelaxationKernel::General { .. } => coefficients.general.push(w),
                    }
                }
                coefficients
            })
            .collect();
        History {
            rules,
            n_dof,
            exponentials: taus.into_iter().map(|tau| (tau, vec![0.0; n_dof])).collect(),
            moments: vec![vec![0.0; n_dof]; degree],
            general,
            past: Vec::new(),
            channels,
            last: None,
            unit: None,
            begun: None,
        }
    }

    /// How the history is accumulated: "recursive (exponential accumulators)", "recursive
    /// (polynomial moments)", both, "direct sum", or a recursion and the direct sum; each
    /// recursion with its rule when it is exact.
    pub fn algorithm(&self) -> String {
        let exact = |q: Quadrature| if q == Quadrature::Exact { ", exact" } else { "" };
        let e = format!("exponential accumulators{}", exact(self.rules.exponential));
        let p = format!("polynomial moments{}", exact(self.rules.polynomial));
        let recursive: Vec<&str> = [
            (!self.exponentials.is_empty()).then_some(e.as_str()),
            (!self.moments.is_empty()).then_some(p.as_str()),
        ]
        .into_iter()
        .flatten()
        .collect();
        match (recursive.is_empty(), self.general.is_empty()) {
            (false, true) => format!("recursive ({})", recursive.join(" + ")),
            (true, _) => "direct sum".to_string(),
            (false, false) => format!("recursive ({}) + direct sum", recursive.join(" + ")),
        }
    }

    /// Bytes of displacement history held now.
    pub fn bytes_held(&self) -> usize {
        let vectors = self.exponentials.len() + self.moments.len() + self.past.len() + usize::from(self.last.is_some());
        vectors * self.n_dof * std::mem::size_of::<f64>()
    }

    /// The number of channels.
    pub fn channels(&self) -> usize {
        self.channels.len()
    }

    /// Begins the step that ends at `time` after a step of size `k` (0 for step 0): carries the
    /// accumulators to it and adds the weight of u_{n−1} that depends on k (docs/method.md
    /// §20.2). [`Self::memory_load`] then gives h_n.
    pub fn begin(&mut self, time: f64, k: f64) {
        debug_assert!(self.begun.is_none(), "a step begun twice");
        self.begun = Some((time, k));
        let Some((_, k_last, u)) = &self.last else {
            return;
        };
        if k > 0.0 && self.unit.is_none() {
            self.unit = Some(k);
        }
        let unit = self.unit.unwrap_or(1.0);
        // the trapezoid's node weight of u_{n−1}, in units of the first step (½ at n − 1 = 0)
        let omega = (k_last + k) / (2.0 * unit);
        match self.rules.exponential {
            Quadrature::Trapezoid => {
                for (tau, s) in self.exponentials.iter_mut() {
                    let decay = (-k / *tau).exp();
                    for (sv, uv) in s.iter_mut().zip(u) {
                        *sv = decay * (*sv + omega * uv);
                    }
                }
            }
            Quadrature::Exact => {
                for (tau, s) in self.exponentials.iter_mut() {
                    let w = quadrature::exponential(Quadrature::Exact, k, *tau);
                    for (sv, uv) in s.iter_mut().zip(u) {
                        *sv = w.decay * *sv + w.previous * uv;
                    }
                }
            }
        }
        let moments = &mut self.moments;
        if !moments.is_empty() {
            if self.rules.polynomial == Quadrature::Trapezoid {
                moments[0].iter_mut().zip(u).for_each(|(p, uv)| *p += omega * uv);
            }
            // P_j(t_n) = Σ_{l ≤ j} C(j,l) k^{j−l} P_l(t_{n−1}) in descending j (uses old P_l, l < j).
            for j in (1..moments.len()).rev() {
                let (lower, upper) = moments.split_at_mut(j);
                let pj = &mut upper[0];
                let mut binom = 1.0;
                for l in (0..j).rev() {
                    // C(j, l) built incrementally from C(j, j) = 1.
                    binom = binom * (l + 1) as f64 / (j - l) as f64;
                    let coef = binom * k.powi((j - l) as i32);
                    axpy(coef, &lower[l], pj);
                }
            }
            if self.rules.polynomial == Quadrature::Exact {
                for (d, p) in moments.iter_mut().enumerate() {
                    let w = quadrature::monomial(Quadrature::Exact, k, d);
                    axpy(w.previous, u, p);
                }
            }
        }
        if !self.general.is_empty() {
            // u_{n−1}'s node weight is complete now
            if let Some(last) = self.past.last_mut() {
                last.1 = 0.5 * (k_last + k);
            }
        }
    }

    /// The scale of an accumulator's sum in h_n: the trapezoid's sums are in units of the first
    /// step.
    fn unit_of(&self, rule: Quadrature) -> f64 {
        match rule {
            Quadrature::Trapezoid => self.unit.unwrap_or(0.0),
            Quadrature::Exact => 1.0,
        }
    }

    /// h_n of channel `j` for the step begun (zero for step 0), written into `out`.
    pub fn memory_load(&self, j: usize, out: &mut [f64]) {
        let c = &self.channels[j];
        out.iter_mut().for_each(|v| *v = 0.0);
        let unit = self.unit_of(self.rules.exponential);
        for (cm, (_, s)) in c.exponential.iter().zip(&self.exponentials) {
            if *cm != 0.0 {
                axpy(unit * cm, s, out);
            }
        }
        let unit = self.unit_of(self.rules.polynomial);
        for (a, p) in c.polynomial.iter().zip(&self.moments) {
            if *a != 0.0 {
                axpy(unit * a, p, out);
            }
        }
        if !self.general.is_empty() {
            let (t, _) = self.begun.expect("memory_load after begin");
            for (t_i, omega, u) in &self.past {
                let s = t - t_i;
                let b = match (&self.general[..], &c.general[..]) {
                    ([g], [w]) if *w == 1.0 => g.value(s),
                    _ => self.general.iter().zip(&c.general).map(|(g, w)| w * g.value(s)).sum(),
                };
                axpy(omega * b, u, out);
            }
        }
    }

    /// Records u_n of the step begun.
    pub fn push(&mut self, u: &[f64]) {
        let (t, k) = self.begun.take().expect("push after begin");
        if self.rules.exponential == Quadrature::Exact {
            for (tau, s) in self.exponentials.iter_mut() {
                let w = quadrature::exponential(Quadrature::Exact, k, *tau);
                axpy(w.current, u, s);
            }
        }
        if self.rules.polynomial == Quadrature::Exact {
            for (d, p) in self.moments.iter_mut().enumerate() {
                let w = quadrature::monomial(Quadrature::Exact, k, d);
                axpy(w.current, u, p);
            }
        }
        if !self.general.is_empty() {
            // the weight k_n/2 now, the rest when step n + 1 begins
            self.past.push((t, 0.5 * k, u.to_vec()));
        }
        match &mut self.last {
            Some((t_last, k_last, last)) => {
                *t_last = t;
                *k_last = k;
                last.copy_from_slice(u);
            }
            None => self.last = Some((t, k, u.to_vec())),
        }
    }

    /// The local error of the memory term of the step just solved (before [`Self::push`]) for
    /// channel j, written into `out` (docs/method.md §20.4): what the quadratic through
    /// u_{n−2}, u_{n−1}, u_n adds to the step's integral over the linear interpolant the scheme
    /// uses, −u[t_{n−2}, t_{n−1}, t_n] ∫₀ᵏ b(σ) σ (k − σ) dσ, and where an atom takes the trapezoid,
    /// the trapezoid's own error on the step against the exact rule (expressions: Simpson's).
    /// `older` is (u_{n−2}, k_{n−1}); without it (the first step) only the rule's part counts.
    pub fn local_error(&self, j: usize, u: &[f64], older: Option<(&[f64], f64)>, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        let (Some((_, k)), Some((_, _, last))) = (self.begun, &self.last) else {
            return;
        };
        if k == 0.0 {
            return;
        }
        let c = &self.channels[j];
        // the step's kernel integrals: curvature ∫ b σ(k−σ), and the rule's excess on u_n, u_{n−1}
        let (mut curvature, mut excess_current, mut excess_previous) = (0.0, 0.0, 0.0);
        for (cm, (tau, _)) in c.exponential.iter().zip(&self.exponentials) {
            curvature += cm * quadrature::exponential_curvature(k, *tau);
            if self.rules.exponential == Quadrature::Trapezoid {
                let (t, x) = (
                    quadrature::exponential(Quadrature::Trapezoid, k, *tau),
                    quadrature::exponential(Quadrature::Exact, k, *tau),
                );
                excess_current += cm * (t.current - x.current);
                excess_previous += cm * (t.previous - x.previous);
            }
        }
        for (d, a) in c.polynomial.iter().enumerate() {
            curvature += a * quadrature::monomial_curvature(k, d);
            if self.rules.polynomial == Quadrature::Trapezoid {
                let (t, x) = (
                    quadrature::monomial(Quadrature::Trapezoid, k, d),
                    quadrature::monomial(Quadrature::Exact, k, d),
                );
                excess_current += a * (t.current - x.current);
                excess_previous += a * (t.previous - x.previous);
            }
        }
        for (g, w) in self.general.iter().zip(&c.general) {
            // Simpson's rule against the trapezoid on b times the linear interpolant
            let (b0, bh, bk) = (g.value(0.0), g.value(0.5 * k), g.value(k));
            curvature += w * k * k * k * bh / 6.0;
            excess_current += w * (0.5 * k * b0 - k / 6.0 * (b0 + 2.0 * bh));
            excess_previous += w * (0.5 * k * bk - k / 6.0 * (bk + 2.0 * bh));
        }
        axpy(excess_current, u, out);
        axpy(excess_previous, last, out);
        if let Some((older, k_last)) = older.filter(|&(_, k_last)| k_last > 0.0) {
            // −u[t_{n−2}, t_{n−1}, t_n] times the curvature integral
            let scale = -curvature / (k + k_last);
            for (((o, un), ul), uo) in out.iter_mut().zip(u).zip(last).zip(older) {
                let divided = (un - ul) / k - (ul - uo) / k_last;
                *o += scale * divided;
            }
        }
    }
}

fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    y.iter_mut().zip(x).for_each(|(yv, xv)| *yv += a * xv);
}

#[cfg(test)]
mod tests;
