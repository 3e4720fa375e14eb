//! What a contact with friction is (docs/method.md §17): the tangential rows after the normal
//! ones, their laws (Tresca, Coulomb, a potential) and, in 3D, their pairs.

use super::super::condensed::ContactNodes;
use super::super::nodal::NodalLaws;
use crate::expr::Expr;

/// The friction law of one tangential row.
#[derive(Clone, Debug)]
pub enum FrictionLaw {
    /// F_b(x, y, z, t), a traction: the row's bound force is w_p F_b(x_p, t).
    Tresca(Expr),
    /// μ, a number or an expression of the accumulated slip s: the row's bound force is
    /// μ λ_ν of its normal row in the same step.
    Coulomb(Coefficient),
    /// w_p j_τ(u_τ), j_τ an odd law on the total tangential displacement (the hemivariational
    /// case, docs/method.md §17.1); the law is the row's term in [`Friction::laws_of_rows`].
    Potential,
}

/// A Coulomb coefficient: constant, or μ(s) of the accumulated slip.
#[derive(Clone, Debug)]
pub enum Coefficient {
    Constant(f64),
    OfSlip(Expr),
}

impl Coefficient {
    /// μ at accumulated slip s.
    pub fn at(&self, s: f64) -> f64 {
        match self {
            Coefficient::Constant(mu) => *mu,
            Coefficient::OfSlip(e) => e.eval(&[s]),
        }
    }
}

/// The tangential rows of a contact with friction (docs/method.md §17): the condensation holds
/// the normal rows first, then these.
#[derive(Clone, Debug)]
pub struct Friction<const D: usize> {
    /// Every row the condensation holds: the m normal rows, then the tangential ones.
    pub rows: ContactNodes<D>,
    /// Per tangential row: its normal row.
    pub normal_row: Vec<usize>,
    /// Over all rows: the other tangential row of the same normal row in 3D, whose slip with
    /// this one is a vector of the tangent plane (docs/method.md §17.3); None in 2D.
    pub pairs: Option<Vec<Option<usize>>>,
    /// Per tangential row: its law.
    pub laws: Vec<FrictionLaw>,
    /// The laws of every row, built once: the normal rows' terms, then one term per tangential
    /// row — the odd law of constant profile μ ≡ 1 and the group's ε for Tresca and Coulomb
    /// (its weight, the bound force, set every step), the group's own law with weight w_p for a
    /// potential (docs/method.md §17.2).
    pub laws_of_rows: NodalLaws,
}

impl<const D: usize> Friction<D> {
    /// The tangential rows of each of the m normal rows (none, one, or in 3D two).
    pub fn rows_of(&self, m: usize) -> Vec<Vec<usize>> {
        let mut out = vec![Vec::new(); m];
        for (k, &p) in self.normal_row.iter().enumerate() {
            out[p].push(k);
        }
        out
    }

    /// The other tangential row of tangential row k's pair (3D), if it has one.
    pub fn partner(&self, k: usize) -> Option<usize> {
        let m = self.rows.len() - self.normal_row.len();
        self.pairs.as_ref().and_then(|p| p[m + k]).map(|q| q - m)
    }

    /// The length of tangential row k's value v(k): |v(k)|, or in 3D the length of its pair's
    /// vector (docs/method.md §17.3).
    pub fn length(&self, k: usize, v: impl Fn(usize) -> f64) -> f64 {
        match self.partner(k) {
            Some(j) => v(k).hypot(v(j)),
            None => v(k).abs(),
        }
    }

    /// The fixed unit tangents of a normal ν (docs/method.md §17.3). 2D: τ = (−ν_y, ν_x). 3D:
    /// τ₁ the axis e_k least aligned with ν (the first of equals) made orthogonal to it,
    /// τ₁ = (e_k − ν_k ν)/|e_k − ν_k ν|, and τ₂ = ν × τ₁; so a face normal to an axis gets
    /// axis tangents, and a symmetry plane's prescribed component is one whole tangential row.
    pub fn tangents(nu: [f64; D]) -> Vec<[f64; D]> {
        let mut t = [0.0; D];
        if D == 2 {
            t[0] = -nu[1];
            t[1] = nu[0];
            return vec![t];
        }
        let k = (0..D).fold(0, |k, c| if nu[c].abs() < nu[k].abs() { c } else { k });
        for c in 0..D {
            t[c] = f64::from(u8::from(c == k)) - nu[k] * nu[c];
        }
        let norm = t.iter().map(|v| v * v).sum::<f64>().sqrt();
        t.iter_mut().for_each(|v| *v /= norm);
        let mut t2 = [0.0; D];
        for c in 0..D {
            let (a, b) = ((c + 1) % D, (c + 2) % D);
            t2[c] = nu[a] * t[b] - nu[b] * t[a];
        }
        vec![t, t2]
    }
}
