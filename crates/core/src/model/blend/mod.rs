//! The material at a latent point under a rule ([`BlendRule`]): the GP's
//! blend of the stored materials ([`reconstruct`]), each value on its soft
//! floor ([`soft_floor`]), or the plausible rule's steps
//! ([`plausible_budget`], [`plausible_steps`]); how plausible a blend is
//! ([`plausibility`]), at one point or at many in one pass over the store
//! ([`plausibility_sweep`], with the bins a pass reads, [`pass_bins`], and
//! its weights, [`pass_weights`]).

pub(crate) mod pass_bins;
pub(crate) mod pass_weights;
pub mod plausibility;
pub(crate) mod plausibility_sweep;
pub(crate) mod plausible_budget;
pub(crate) mod plausible_steps;
pub mod reconstruct;
pub mod soft_floor;

pub use plausibility::{BlendRule, Confidence, LOW_CONFIDENCE_VARIANCE, Plausibility};
pub use reconstruct::Blend;
