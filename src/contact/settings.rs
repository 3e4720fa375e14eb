//! What a contact solve is told: its tolerance and iteration cap, the size above which it keeps a
//! factorisation, and which of its optional strategies it uses (docs/ablation.md).

/// Tolerance and iteration cap of the contact solve, and its strategies.
#[derive(Clone, Copy, Debug)]
pub struct ContactSettings {
    /// Relative complementarity residual at which a step is converged.
    pub tolerance: f64,
    /// Newton iterations per step before giving up.
    pub max_iterations: usize,
    /// Above this many free (inactive) contact nodes the dense Cholesky factorisation of the
    /// Newton matrix is kept and reused: later Newton systems (of this step and the next ones)
    /// are solved by conjugate gradients preconditioned with it, and it is refactored only when
    /// that does not converge quickly (docs/method.md §9.2).
    pub dense_limit: usize,
    /// The optional strategies, each on unless the scene's `solver.without` names it.
    pub strategies: Strategies,
    /// Report every iteration to standard error (`HVI_TRACE_CONTACT=1`, read once when the
    /// contact is set up; docs/troubleshooting.md).
    pub trace: bool,
}

impl ContactSettings {
    /// The same settings with another tolerance (Coulomb's inexact rounds, docs/method.md §17.2).
    pub fn with_tolerance(self, tolerance: f64) -> Self {
        ContactSettings { tolerance, ..self }
    }
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            tolerance: 1e-10,
            max_iterations: 100,
            dense_limit: 1000,
            strategies: Strategies::default(),
            trace: false,
        }
    }
}

/// The contact solve's tuning constants, in one place, each with the reason or the measurement
/// that set it (docs/ablation.md has the measurements of the strategies they tune).
#[derive(Clone, Copy, Debug)]
pub struct Tuning {
    /// Armijo's sufficient decrease: E(r + Δ) − E(r) ≤ −armijo × the path's first-order decrease.
    pub armijo: f64,
    /// The smallest step of the line search: below it the energy cannot decrease measurably.
    pub min_step: f64,
    /// Where the convexified Newton matrix is still not positive definite (round-off), a shift
    /// of `convex_shift` × Q_pp of its first row is added, and multiplied by `convex_growth` until
    /// Cholesky succeeds (docs/method.md §4.4).
    pub convex_shift: f64,
    pub convex_growth: f64,
    /// The proximal shift of a singular Q is min(this, the relative residual) · Q_pp
    /// (docs/method.md §7.7): it bounds the first steps of a body not yet touching.
    pub proximal: f64,
    /// The inexact-Newton forcing term of an iterative direction lies in [forcing_floor,
    /// forcing_cap] (docs/method.md §9.2): the relative residual, which keeps the convergence
    /// quadratic, and no finer than a tenth of what the last step needs.
    pub forcing_floor: f64,
    pub forcing_cap: f64,
    /// The iterations CG may take on a kept factor before refactoring: `cg_iterations` +
    /// |ℐ|/`cg_rows_per_iteration` (about the cost of one factorisation at |ℐ| = 4 000).
    pub cg_iterations: usize,
    pub cg_rows_per_iteration: usize,
    /// A row whose law curvature is this many times its stiffness Q_pp is left out of a kept
    /// factor and preconditioned by Jacobi (docs/method.md §9.2).
    pub stiff: f64,
    /// A kept factor's row whose curvature (or pair coupling) moved by more than this share of
    /// Q_pp + e_p is updated by Woodbury's identity (0.4: 290 against 293 directions and 14
    /// against 18 factorisations on the slab with Coulomb friction, docs/performance.md §9.2).
    pub moved: f64,
    /// The low-rank update refactors past |ℱ|/`new_columns` new columns of Z (they would cost
    /// most of a factorisation: 108 → 60 factorisations on the slab with Coulomb friction against
    /// counting the rows of the update), past |ℱ|/`update_rows` rows in the update or kept
    /// columns (a quarter of the factor's memory).
    pub new_columns: usize,
    pub update_rows: usize,
    /// Where a tangential row is within this many kink widths ε of its kink it is inside the
    /// smoothing zone for the branch model (10 and 100 measured alike on the slab with Coulomb
    /// friction, 10³ and 10⁵ worse; docs/method.md §17.2).
    pub branch_zone: f64,
    /// The branch model reads the branch a row leaves for this many ε from the kink, where the
    /// smoothed |·| gives F (1 − 5·10⁻⁷) and a curvature of 10⁻⁹ F/ε.
    pub branch_edge: f64,
    /// A curvature below this share of a direction's least stiffness 1/(eᵀWe) counts as none for
    /// the product Δ = W G (docs/method.md §4.6): the direction then differs from Newton's by at
    /// most this share along it.
    pub negligible_curvature: f64,
    /// Rounds of Coulomb's fixed point before the step fails.
    pub coulomb_rounds: usize,
    /// Coulomb's first round is solved to at most this relative residual, later ones to
    /// `round_share` of the bound forces' last change (at most `first_round`), the last at the
    /// solver's tolerance (docs/method.md §17.2).
    pub first_round: f64,
    pub round_share: f64,
}

/// The tuning of every contact solve.
pub const TUNING: Tuning = Tuning {
    armijo: 1e-4,
    min_step: 1e-12,
    convex_shift: 1e-12,
    convex_growth: 10.0,
    proximal: 1e-6,
    forcing_floor: 1e-13,
    forcing_cap: 1e-2,
    cg_iterations: 10,
    cg_rows_per_iteration: 200,
    stiff: 100.0,
    moved: 0.4,
    new_columns: 8,
    update_rows: 4,
    branch_zone: 10.0,
    branch_edge: 1e3,
    negligible_curvature: 1e-8,
    coulomb_rounds: 50,
    first_round: 1e-3,
    round_share: 1e-2,
};

macro_rules! strategies {
    ($($(#[$doc:meta])* $name:ident,)*) => {
        /// The contact solve's optional strategies: each can be switched off (`solver.without =
        /// ["name", …]` in a scene) to measure what it is worth; docs/ablation.md has the table
        /// that decided which are kept. All on by default.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub struct Strategies {
            $($(#[$doc])* pub $name: bool,)*
        }

        impl Default for Strategies {
            fn default() -> Self {
                Strategies { $($name: true,)* }
            }
        }

        impl Strategies {
            /// Every strategy's name, as `solver.without` spells it.
            pub const NAMES: &'static [&'static str] = &[$(stringify!($name),)*];

            /// Switches the strategy `name` off; false where no strategy has that name.
            pub fn switch_off(&mut self, name: &str) -> bool {
                match name {
                    $(stringify!($name) => self.$name = false,)*
                    _ => return false,
                }
                true
            }
        }
    };
}

strategies! {
    /// A factorisation of the Newton matrix kept above `dense_limit` free rows and reused as the
    /// preconditioner of CG (docs/method.md §9.2); without it, a factorisation per direction.
    kept_factor,
    /// The kept factor brought to moved curvatures and a shrunk free set by Woodbury's identity.
    low_rank_update,
    /// The rows a law holds stiffly left out of the kept factor and preconditioned by Jacobi.
    jacobi_rows,
    /// CG stopped at the inexact-Newton accuracy instead of 10⁻¹³.
    inexact_newton,
    /// Δ = W G where no row is held or curved (docs/method.md §4.6, §9.7).
    w_product,
    /// The Newton model of the branch a tangential row leaves its kink for (docs/method.md §17.2).
    branch_model,
    /// The projected path stopped at a row's kink and a pair's origin.
    kink_stops,
    /// A proximal shift of the Newton matrix where Q is singular along rigid motions
    /// (docs/method.md §7.7).
    proximal_shift,
    /// Coulomb's first round without normal forces solved on the normal rows alone.
    unloaded_round,
    /// The load-following predictor of a step with friction.
    load_predictor,
    /// Tresca's and Coulomb's rows started at the last step's slip.
    slip_predictor,
    /// Coulomb's rounds solved inexactly while the bound forces move.
    inexact_rounds,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_strategy_switches_off_by_its_name_and_no_other() {
        for name in Strategies::NAMES {
            let mut s = Strategies::default();
            assert!(s.switch_off(name));
            for other in Strategies::NAMES {
                let mut t = Strategies::default();
                t.switch_off(other);
                assert_eq!(t == s, name == other, "{name} against {other}");
            }
            assert_ne!(s, Strategies::default(), "{name}");
        }
        assert!(!Strategies::default().switch_off("no_such_strategy"));
    }
}
