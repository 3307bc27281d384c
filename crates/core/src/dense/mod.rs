//! Dense linear algebra: the library's own Gram kernel of the store pass,
//! Cholesky factorisation, solves and inverse and general product, and
//! faer's symmetric eigen-decomposition under the library's contract.
//!
//! Why the kernels are the library's own: faer 0.24's x86 products
//! (through `private-gemm-x86`) reserve, in each thread, on its first
//! product of more than 16 x 16 x 16 (and on every triangular product), a
//! scratch buffer of twice the L3 cache size the CPU reports, and its
//! factorisations, solves with several right-hand sides and inverses reach
//! those products from sizes of 24 to 100. Where the reported L3 is large
//! (260 MiB on some virtual machines), that is over 500 MB of reserved
//! private memory in every thread that touches it, including a host
//! program's threads calling the C library; nothing in faer or that crate
//! sets the size. These kernels run in every step of the fit, are as fast
//! as faer's or faster at its sizes, and are sequential with a fixed order
//! of operations, so their results do not depend on the thread count.
//!
//! The eigen-decomposition ([`symmetric_eigen`]: the PCA start, once per
//! fit, and PCA leave-one-out) is faer's, sequential (`Par::Seq`), several
//! times faster than a hand-written one from a few hundred rows (figures in
//! `docs/performance.md`). It runs on a thread of its own that ends with
//! the call, so the scratch faer's products reserve there (twice the
//! reported L3, barely touched: resident private memory, `RssAnon`, grows
//! by about 0.4 MB at N = 100 and 2 MB at N = 1000) is given back at once
//! and no caller's thread keeps it. Its results do not depend on the
//! thread count; unlike the kernels', their last bits may differ from one
//! CPU to another (faer picks its SIMD path at run time).

pub mod cholesky;
pub mod eigen;
pub mod gram;
pub mod gram32;
pub mod product;

pub use cholesky::{Cholesky, NotPositive};
pub use eigen::symmetric_eigen;
