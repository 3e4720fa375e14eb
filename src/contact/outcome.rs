//! What a contact solve reports: the work it did and its residual, or why it stopped.

/// What one contact solve did.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct ContactOutcome {
    pub iterations: usize,
    /// Final complementarity residual relative to the force scale.
    pub residual: f64,
    /// Line-search step halvings over the solve.
    pub line_search_cuts: usize,
    /// Iterations whose Hessian was indefinite and was convexified.
    pub convexified: usize,
    /// Newton directions computed by conjugate gradients preconditioned with an earlier
    /// factorisation (more free nodes than `dense_limit`).
    pub iterative: usize,
    /// Dense Cholesky factorisations of the Newton matrix (one per direction below
    /// `dense_limit`; above it, only when the reused one no longer serves).
    pub factorisations: usize,
    /// Of those, the directions Δ = W G (docs/method.md §4.6), each counted as a factorisation.
    pub in_w: usize,
    /// Nodes on the bound at the end.
    pub active: usize,
}

impl ContactOutcome {
    /// Adds another solve's work (its iterations, cuts, convexifications, iterative directions
    /// and factorisations) to this one's; the residual and the active count stay this one's.
    pub fn add_work(&mut self, other: &ContactOutcome) {
        self.iterations += other.iterations;
        self.line_search_cuts += other.line_search_cuts;
        self.convexified += other.convexified;
        self.iterative += other.iterative;
        self.factorisations += other.factorisations;
        self.in_w += other.in_w;
    }

    /// How many numbers [`Self::to_numbers`] gives (a broadcast of the outcome, src/petsc).
    pub const NUMBERS: usize = 8;

    /// The outcome as numbers, in the order [`Self::from_numbers`] reads them.
    pub fn to_numbers(&self) -> [f64; Self::NUMBERS] {
        [
            self.iterations as f64,
            self.residual,
            self.line_search_cuts as f64,
            self.convexified as f64,
            self.iterative as f64,
            self.factorisations as f64,
            self.in_w as f64,
            self.active as f64,
        ]
    }

    /// The outcome of [`Self::to_numbers`]'s numbers.
    pub fn from_numbers(n: &[f64]) -> Self {
        ContactOutcome {
            iterations: n[0] as usize,
            residual: n[1],
            line_search_cuts: n[2] as usize,
            convexified: n[3] as usize,
            iterative: n[4] as usize,
            factorisations: n[5] as usize,
            in_w: n[6] as usize,
            active: n[7] as usize,
        }
    }
}

/// Why a contact solve stopped without converging.
#[derive(Clone, Debug)]
pub struct ContactFailure {
    pub outcome: ContactOutcome,
    pub reason: String,
    /// The smallest relative residual the solve reached: where it stalled, if it did.
    pub smallest_residual: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The numbers a PETSc run broadcasts give back the outcome, field by field.
    #[test]
    fn outcome_numbers_round_trip() {
        let o = ContactOutcome {
            iterations: 1,
            residual: 2.5e-11,
            line_search_cuts: 3,
            convexified: 4,
            iterative: 5,
            factorisations: 6,
            in_w: 7,
            active: 8,
        };
        let back = ContactOutcome::from_numbers(&o.to_numbers());
        assert_eq!(format!("{back:?}"), format!("{o:?}"));
    }
}
