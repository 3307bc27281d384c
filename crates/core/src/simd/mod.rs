//! Vectorised kernels shared by the hot loops: dot products, symmetric
//! products, exp and log1p. Each has a portable path and an AVX2 (+FMA) path
//! that give the same bits; the CPU's features are detected here, once.

pub mod dot;
pub mod fastexp;
pub mod fastlog;
pub mod fold;
pub mod symmetric;

/// Whether the CPU has AVX2: every AVX2 path of the crate is chosen by this
/// one test (the standard library caches the CPU's answer).
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn has_avx2() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

/// Whether the CPU has AVX-512F (the Gram kernel's widest path).
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn has_avx512f() -> bool {
    std::arch::is_x86_feature_detected!("avx512f")
}

/// Whether the CPU has AVX2 and FMA, for the paths written with fused
/// multiply-adds.
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn has_avx2_fma() -> bool {
    has_avx2() && std::arch::is_x86_feature_detected!("fma")
}
