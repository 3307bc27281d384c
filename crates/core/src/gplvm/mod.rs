//! The Gaussian Process Latent Variable Model: parameters, the kernel, the
//! likelihood of latent points given the Gram matrix, the PCA start, the
//! incremental cost updates and the optimisers.

pub mod incremental;
pub mod kernel;
pub mod likelihood;
pub mod optim;
mod params;
pub mod pca;

pub use incremental::DriftStats;
pub use kernel::Kernel;
pub use likelihood::GramData;
pub use optim::OptimizerKind;
pub use params::{CheckedParams, Fit, GplvmParams};
