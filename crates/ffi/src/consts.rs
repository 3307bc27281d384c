//! The constants the header exports: the library's version and the limits
//! every call checks against.
//!
//! cbindgen copies a constant's literal into the header, so each one is a
//! literal here, and a compile-time assertion ties it to its one source of
//! truth: the package version for the version macros,
//! [`brdf_atlas_core::limits`] for the limits. The header spells the version
//! string `BRDF_ATLAS_VERSION` from the three numbers (cbindgen.toml).

use brdf_atlas_core::limits;

/// The library's major version (`MAJOR` of "MAJOR.MINOR.PATCH").
pub const BRDF_ATLAS_VERSION_MAJOR: u32 = 0;

/// The library's minor version.
pub const BRDF_ATLAS_VERSION_MINOR: u32 = 1;

/// The library's patch version.
pub const BRDF_ATLAS_VERSION_PATCH: u32 = 0;

/// The largest latent dimension of a model: a latent point has at most this
/// many coordinates.
pub const BRDF_ATLAS_MAX_Q: usize = 16;

/// The largest number of materials of a model.
pub const BRDF_ATLAS_MAX_MATERIALS: usize = 1 << 20;

/// The largest absolute latent coordinate a model file holds (its fitted
/// materials lie in [-1, 1] on every axis).
pub const BRDF_ATLAS_LATENT_LIMIT: f64 = 1e3;

/// The largest side, in pixels, of an albedo map.
pub const BRDF_ATLAS_MAX_MAP_SIDE: usize = 16384;

/// Half-width of the default view of a map (`brdf_atlas_model_view`): the
/// view is [-w, w]^2 around the fitted materials' box [-1, 1]^2.
pub const BRDF_ATLAS_DEFAULT_VIEW_HALF_WIDTH: f64 = 1.1;

/// Above this predictive variance (`brdf_atlas_model_confidence`,
/// `brdf_atlas_model_variance_map`) the model knows little: the data explain
/// less than half of what the material there could be.
pub const BRDF_ATLAS_LOW_CONFIDENCE_VARIANCE: f64 = 0.5;

/// A material's own point gives it back when every channel of its albedo
/// there is within this share of its own (`brdf_atlas_model_marker`).
pub const BRDF_ATLAS_GIVES_BACK: f64 = 0.05;

/// A latent point within this distance of a material's point is its marker
/// (`brdf_atlas_model_marker`).
pub const BRDF_ATLAS_MARKER_RADIUS: f64 = 0.01;

/// The largest quadrature sample count a map accepts (2^24): more would only
/// take hours.
pub const BRDF_ATLAS_MAX_SAMPLES: usize = 1 << 24;

/// `s` as a decimal number; a compile error if it is not one.
const fn decimal(s: &str) -> u32 {
    let bytes = s.as_bytes();
    assert!(!bytes.is_empty(), "an empty version number");
    let mut value = 0u32;
    let mut i = 0;
    while i < bytes.len() {
        assert!(
            bytes[i].is_ascii_digit(),
            "a version number with a non-digit"
        );
        value = value * 10 + (bytes[i] - b'0') as u32;
        i += 1;
    }
    value
}

// The version macros are the package's version (workspace Cargo.toml): bump
// them together.
const _: () = {
    assert!(BRDF_ATLAS_VERSION_MAJOR == decimal(env!("CARGO_PKG_VERSION_MAJOR")));
    assert!(BRDF_ATLAS_VERSION_MINOR == decimal(env!("CARGO_PKG_VERSION_MINOR")));
    assert!(BRDF_ATLAS_VERSION_PATCH == decimal(env!("CARGO_PKG_VERSION_PATCH")));
};

// The limits are the core's.
const _: () = {
    assert!(BRDF_ATLAS_MAX_Q == limits::MAX_Q);
    assert!(BRDF_ATLAS_MAX_MATERIALS == limits::MAX_MATERIALS);
    assert!(BRDF_ATLAS_LATENT_LIMIT == limits::LATENT_LIMIT);
    assert!(BRDF_ATLAS_MAX_MAP_SIDE == limits::MAX_MAP_SIDE);
    assert!(BRDF_ATLAS_DEFAULT_VIEW_HALF_WIDTH == limits::DEFAULT_VIEW_HALF_WIDTH);
    assert!(BRDF_ATLAS_LOW_CONFIDENCE_VARIANCE == brdf_atlas_core::LOW_CONFIDENCE_VARIANCE);
    assert!(BRDF_ATLAS_GIVES_BACK == brdf_atlas_core::fidelity::GIVES_BACK);
    assert!(BRDF_ATLAS_MARKER_RADIUS == brdf_atlas_core::fidelity::MARKER_RADIUS);
};
