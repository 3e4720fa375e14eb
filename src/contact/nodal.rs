//! The compliance laws of the contact rows (docs/method.md §14): each row p carries a list of
//! terms w_t j_t — one per contact group that meets at the row, with the group's law and its
//! nodal weight — acting on the penetration s = r_p − o_p past the row's initial gap o_p.
//! One group without an obstacle is one term per row with o_p = 0: the paper's w_p j(r_p).

use super::law::ContactLaw;

/// One term w j of a row's energy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LawTerm {
    /// Index into [`NodalLaws::laws`].
    pub law: usize,
    /// The nodal weight w of the term's group at the row.
    pub weight: f64,
    /// The contact group the term belongs to (for the totals).
    pub group: usize,
}

/// Per contact row, the terms of its energy Σ_t w_t j_t(s).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodalLaws {
    pub laws: Vec<ContactLaw>,
    /// Row p's terms are `terms[start[p]..start[p + 1]]`; empty when no row has a law.
    start: Vec<usize>,
    terms: Vec<LawTerm>,
}

impl NodalLaws {
    /// From the terms of each row (rows without a law have none).
    pub fn new(laws: Vec<ContactLaw>, rows: &[Vec<LawTerm>]) -> Self {
        if rows.iter().all(|r| r.is_empty()) {
            return NodalLaws::default();
        }
        let mut start = vec![0];
        let mut terms = Vec::new();
        for r in rows {
            terms.extend_from_slice(r);
            start.push(terms.len());
        }
        NodalLaws { laws, start, terms }
    }

    /// One law for every row, with the rows' weights (one group of the paper).
    pub fn uniform(law: ContactLaw, weights: &[f64]) -> Self {
        let rows: Vec<Vec<LawTerm>> = weights
            .iter()
            .map(|&w| {
                vec![LawTerm {
                    law: 0,
                    weight: w,
                    group: 0,
                }]
            })
            .collect();
        NodalLaws::new(vec![law], &rows)
    }

    /// Sets the weight of row p's one term (a row of one term: friction's tangential rows,
    /// whose bound force changes with the step, docs/method.md §17.2).
    pub fn set_weight(&mut self, p: usize, weight: f64) {
        debug_assert_eq!(self.start[p + 1] - self.start[p], 1, "row {p} has one term");
        self.terms[self.start[p]].weight = weight;
    }

    /// True if no row has a law.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// The terms of row p.
    #[inline]
    pub fn terms(&self, p: usize) -> &[LawTerm] {
        if self.terms.is_empty() {
            &[]
        } else {
            &self.terms[self.start[p]..self.start[p + 1]]
        }
    }

    /// The law of every term when all terms share one (None without a law or with several).
    pub fn single(&self) -> Option<&ContactLaw> {
        let first = self.terms.first()?.law;
        self.terms.iter().all(|t| t.law == first).then(|| &self.laws[first])
    }

    /// The laws some row uses, in order.
    pub fn used(&self) -> Vec<&ContactLaw> {
        (0..self.laws.len())
            .filter(|&i| self.terms.iter().any(|t| t.law == i))
            .map(|i| &self.laws[i])
            .collect()
    }

    /// Σ_t w_t j_t'(s): the compliance force of row p at penetration s.
    #[inline]
    pub fn force(&self, p: usize, s: f64) -> f64 {
        self.terms(p)
            .iter()
            .map(|t| t.weight * self.laws[t.law].derivative(s))
            .sum()
    }

    /// Σ_t w_t j_t''(s).
    #[inline]
    pub fn stiffness(&self, p: usize, s: f64) -> f64 {
        self.terms(p)
            .iter()
            .map(|t| t.weight * self.laws[t.law].second_derivative(s))
            .sum()
    }

    /// Σ_t w_t [j_t(s + ds) − j_t(s) − j_t'(s) ds], from its Taylor expansion ½ j''(s) ds² when ds
    /// is tiny (the difference of j values would be below their rounding near convergence).
    pub fn energy_increment(&self, p: usize, s: f64, ds: f64) -> f64 {
        self.terms(p)
            .iter()
            .map(|t| {
                let law = &self.laws[t.law];
                let rest = if ds.abs() <= 1e-4 * s.abs().max(law.epsilon) {
                    0.5 * law.second_derivative(s) * ds * ds
                } else {
                    law.potential(s + ds) - law.potential(s) - law.derivative(s) * ds
                };
                t.weight * rest
            })
            .sum()
    }

    /// The width ε of the smoothed kink of row p's laws at s = 0 (∂j(0) an interval), or ∞.
    pub fn kink_width(&self, p: usize) -> f64 {
        self.terms(p)
            .iter()
            .map(|t| &self.laws[t.law])
            .filter(|l| {
                let (lo, hi) = l.clarke_interval(0.0);
                hi > lo
            })
            .map(|l| l.epsilon)
            .fold(f64::INFINITY, f64::min)
    }

    /// max_p Σ_t w_t S_t sup|μ_t|: a force scale of the laws.
    pub fn force_scale(&self, m: usize) -> f64 {
        (0..m)
            .map(|p| {
                self.terms(p)
                    .iter()
                    .map(|t| t.weight * self.laws[t.law].force_scale())
                    .sum::<f64>()
            })
            .fold(0.0, f64::max)
    }

    /// Per row Σ_t w_t α_t (α the relaxed-monotonicity constant): the weights of the smallness
    /// condition (docs/method.md §1).
    pub fn monotonicity_weights(&self, m: usize) -> Vec<f64> {
        (0..m)
            .map(|p| {
                self.terms(p)
                    .iter()
                    .map(|t| t.weight * self.laws[t.law].relaxed_monotonicity())
                    .sum()
            })
            .collect()
    }
}
