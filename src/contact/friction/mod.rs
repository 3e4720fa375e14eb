//! Friction (docs/method.md §17): what a contact with friction is (`law.rs`: its tangential
//! rows, their laws and pairs) and the contact solve of a step with it (`rounds.rs`: the slip
//! frame, the predictor, Coulomb's fixed point in rounds, its first round
//! without normal forces on the normal rows alone, `unloaded.rs`).

mod law;
mod rounds;
mod unloaded;

pub use law::{Coefficient, Friction, FrictionLaw};
pub use rounds::{solve, FrictionStep};
