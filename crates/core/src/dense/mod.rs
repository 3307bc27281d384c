//! Dense linear algebra of the library's own: the Gram kernel of the store
//! pass, Cholesky factorisation, solves and inverse, a symmetric
//! eigen-decomposition and a general product.
//!
//! Why not the matrix library's: faer 0.24's x86 products (through
//! `private-gemm-x86`) reserve, in each thread, on its first product of
//! more than 16 x 16 x 16 (and on every triangular product), a scratch
//! buffer of twice the L3 cache size the CPU reports, and its
//! factorisations, solves with several right-hand sides, inverses and
//! eigen-decompositions reach those products from sizes of 24 to 100.
//! Where the reported L3 is large (260 MiB on some virtual machines), that
//! is over 500 MB of private memory in every thread that touches it,
//! including a host program's threads calling the C library; nothing in
//! faer or that crate sets the size. So no product the library runs
//! outside its tests goes through faer; faer remains the matrix type and
//! the tests' reference. Every kernel here is sequential with a fixed
//! order of operations, so results do not depend on the thread count.

pub mod cholesky;
pub mod eigen;
pub mod gram;
pub mod gram32;
pub mod product;

pub use cholesky::{Cholesky, NotPositive};
pub use eigen::symmetric_eigen;
