//! How good a fit is: leave-one-out errors in closed form, and the accuracy
//! of albedo maps against a dense reference.

mod albedo_floor;
pub mod fidelity;
pub mod loo;
pub mod measure;
mod nonneg;
mod predictors;
mod projected;
