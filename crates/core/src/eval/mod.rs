//! How good a fit is: leave-one-out errors in closed form, and how each
//! material comes back at its own point.

mod albedo_floor;
pub mod fidelity;
pub mod loo;
mod nonneg;
mod predictors;
mod projected;
mod score;
