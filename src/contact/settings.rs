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
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            tolerance: 1e-10,
            max_iterations: 100,
            dense_limit: 1000,
            strategies: Strategies::default(),
        }
    }
}

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
    /// preconditioner of CG (docs/method.md §9.2); without it, a factorisation per direction
    /// (and no coupled Coulomb step, which needs it).
    kept_factor,
    /// The kept factor brought to moved curvatures and a shrunk free set by Woodbury's identity.
    low_rank_update,
    /// The kept factor bordered by the rows that joined the free set (their Schur complement).
    border,
    /// The rows a law holds stiffly left out of the kept factor and preconditioned by Jacobi.
    jacobi_rows,
    /// CG stopped at the inexact-Newton accuracy instead of 10⁻¹³.
    inexact_newton,
    /// Single-precision copies of the kept factor and of Q for CG's and the line search's work.
    single_precision,
    /// Products by Q saved: CG's own products reused by the line search, Q r − q carried between
    /// iterations, a solve started from the forces of the last one at the same point.
    product_reuse,
    /// The Newton system in W where it is smaller (docs/method.md §4.6) and has rows.
    system_in_w,
    /// Δ = W G where no row is held or curved (the system in W has no rows, docs/method.md §9.7).
    w_product,
    /// The dense factors' storage kept between factorisations.
    recycled_storage,
    /// The Newton model of the branch a tangential row leaves its kink for (docs/method.md §17.2).
    branch_model,
    /// A full step that halves the residual accepted where the energy cannot show its decrease.
    watchdog,
    /// A residual within 100× the tolerance accepted where the line search reaches round-off.
    round_off_acceptance,
    /// The active set enlarged by the rows near their bound that are pushed into it.
    enlarged_active_set,
    /// The projected path stopped at a row's kink and a pair's origin.
    kink_stops,
    /// A proximal shift of the Newton matrix where Q is singular along rigid motions
    /// (docs/method.md §7.7).
    proximal_shift,
    /// A Newton step on Coulomb's coupled law between the fixed point's rounds.
    coupled_step,
    /// Anderson mixing of the Coulomb fixed point's rounds.
    anderson,
    /// The load-following predictor of a step with friction.
    load_predictor,
    /// Tresca's and Coulomb's rows started at the last step's slip.
    slip_predictor,
    /// Coulomb's first round without normal forces solved on the normal rows alone.
    unloaded_round,
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
