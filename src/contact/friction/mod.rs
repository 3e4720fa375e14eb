//! Friction (docs/method.md §17): what a contact with friction is (`law.rs`: its tangential
//! rows, their laws and pairs) and the contact solve of a step with it (`rounds.rs`: the slip
//! frame, the predictor, Coulomb's fixed point in rounds, mixed by `anderson.rs`).

mod anderson;
mod law;
mod rounds;

pub use law::{Coefficient, Friction, FrictionLaw};
pub use rounds::{solve, FrictionStep};
