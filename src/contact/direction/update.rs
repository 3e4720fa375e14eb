//! A kept factorisation A₀ brought to the present Newton matrix by Woodbury's identity
//! (docs/method.md §9.2): P = A₀ + UΔUᵀ on the rows 𝒰 whose curvature moved (Δ the change of the
//! diagonal and of a pair's coupling) and the rows that left the free set (pinned: Δ = ∞, the row
//! held at 0), applied as P⁻¹ = A₀⁻¹ − Z (I + Δ Uᵀ Z)⁻¹ Δ Uᵀ A₀⁻¹ with Z = A₀⁻¹ U, whose columns
//! are kept with the factor (a pinned row's capacitance row is its limit Uᵀ Z).

use crate::linalg::dense::{DenseCholesky, DenseLu};

/// The columns A₀⁻¹ e_k of the factor's rows k that an update has needed so far, kept with the
/// factor (they depend on it alone).
#[derive(Debug, Default)]
pub struct KeptColumns {
    /// Column-major, n numbers each.
    values: Vec<f64>,
    /// Per factor row, its column.
    column_of: Vec<Option<usize>>,
}

impl KeptColumns {
    /// No columns yet, for a factor of order n.
    pub fn new(n: usize) -> Self {
        KeptColumns {
            values: Vec::new(),
            column_of: vec![None; n],
        }
    }

    /// How many columns are kept.
    pub fn len(&self) -> usize {
        self.values.len() / self.column_of.len().max(1)
    }

    /// The factor rows among `rows` without a kept column.
    pub fn missing(&self, rows: &[usize]) -> Vec<usize> {
        rows.iter().copied().filter(|&k| self.column_of[k].is_none()).collect()
    }

    /// Solves and keeps A₀⁻¹ e_k for the factor rows `rows` (one blocked solve).
    pub fn add(&mut self, factor: &DenseCholesky, rows: &[usize]) {
        let n = self.column_of.len();
        let start = self.values.len();
        self.values.resize(start + n * rows.len(), 0.0);
        let x = &mut self.values[start..];
        for (b, &k) in rows.iter().enumerate() {
            x[b * n + k] = 1.0;
            self.column_of[k] = Some(start / n + b);
        }
        factor.solve_columns_in_place(x, rows.len());
    }

    /// A₀⁻¹ e_k.
    fn column(&self, k: usize) -> &[f64] {
        let n = self.column_of.len();
        let c = self.column_of[k].expect("the update's columns are kept before it is formed");
        &self.values[c * n..(c + 1) * n]
    }
}

/// One row of Δ: its diagonal change (∞: pinned) and, for a pair, its partner's place in 𝒰 and
/// the change of their coupling.
#[derive(Clone, Copy)]
pub struct DeltaRow {
    pub diagonal: f64,
    pub pair: Option<(usize, f64)>,
}

/// P = A₀ + UΔUᵀ on the kept factor's rows `rows`.
pub struct LowRankUpdate {
    rows: Vec<usize>,
    delta: Vec<DeltaRow>,
    /// I + Δ Uᵀ Z (a pinned row's: Uᵀ Z).
    capacitance: DenseLu,
}

impl LowRankUpdate {
    /// The update on the factor rows `rows` with Δ `delta` (their columns of Z kept already).
    pub fn new(columns: &KeptColumns, rows: Vec<usize>, delta: Vec<DeltaRow>) -> Self {
        let capacitance = DenseLu::from_columns(rows.len(), |b, out| {
            let zb = columns.column(rows[b]);
            for (a, v) in out.iter_mut().enumerate() {
                let d = delta[a];
                *v = if d.diagonal.is_infinite() {
                    // a pinned row, (I + ΔUᵀZ) divided by Δ → ∞: Uᵀ Z
                    zb[rows[a]]
                } else {
                    let mut v = d.diagonal * zb[rows[a]];
                    if let Some((partner, off)) = d.pair {
                        v += off * zb[rows[partner]];
                    }
                    v + if a == b { 1.0 } else { 0.0 }
                };
            }
        });
        LowRankUpdate {
            rows,
            delta,
            capacitance,
        }
    }

    /// y ← P⁻¹ r from y = A₀⁻¹ r: y − Z (I + Δ Uᵀ Z)⁻¹ Δ Uᵀ y.
    pub fn correct(&self, columns: &KeptColumns, y: &mut [f64]) {
        // T = Δ Uᵀ y (a pinned row: its row of y, the limit of Δ Uᵀ y divided by Δ)
        let mut t: Vec<f64> = (self.delta.iter().zip(&self.rows))
            .map(|(d, &k)| match d.diagonal.is_infinite() {
                true => y[k],
                false => d.diagonal * y[k] + d.pair.map_or(0.0, |(partner, off)| off * y[self.rows[partner]]),
            })
            .collect();
        self.capacitance.solve_in_place(&mut t);
        for (&k, &tk) in self.rows.iter().zip(&t) {
            y.iter_mut().zip(columns.column(k)).for_each(|(y, z)| *y -= tk * z);
        }
    }
}
