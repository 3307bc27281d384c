//! From MERL files to the data a fit and every query read: the directory
//! scan, the data transform, and the store with its Gram matrix.

mod dataset;
pub mod store;
pub mod transform;

pub use dataset::Dataset;
pub use store::{Precision, Rows, Store, StoreIdentity, build_scratch_store, build_store};
pub use transform::TransformKind;

/// Write `count` synthetic materials (seed 5) of `dims` into `dir`, for tests.
#[cfg(test)]
pub(crate) fn synth_dir(dir: &std::path::Path, count: usize, dims: brdf_merl::Dims) {
    for m in brdf_merl::synth::database(count, 5) {
        m.brdf
            .table(dims)
            .write(dir.join(format!("{}.binary", m.name)))
            .unwrap();
    }
}
