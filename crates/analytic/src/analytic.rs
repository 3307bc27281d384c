//! What the fitter needs of an analytic BRDF: its parameters as a vector
//! within a box, and its value for the cosines of a pair of directions.

use brdf_merl::Vec3;

use crate::geometry::Geometry;

/// An analytic, isotropic BRDF with a fixed number of bounded parameters.
pub trait Analytic: Clone + std::fmt::Debug {
    /// The model's name, as reports print it.
    const NAME: &'static str;
    /// Lower and upper bound of each parameter, in [`Analytic::to_params`] order.
    fn bounds() -> Vec<(f64, f64)>;
    /// The parameters as a vector.
    fn to_params(&self) -> Vec<f64>;
    /// The model of a parameter vector (each clamped into its bounds; a
    /// short vector leaves the rest at their lower bounds).
    fn from_params(p: &[f64]) -> Self;
    /// RGB reflectance (1/sr) for the cosines of a pair of directions.
    fn eval_geometry(&self, g: &Geometry) -> [f64; 3];
    /// The fit's starting points, in the order they are tried, from the
    /// table's albedo (each channel in `[0, 1]`).
    fn starts(albedo: [f64; 3]) -> Vec<Self>;

    /// RGB reflectance (1/sr) of `(wi, wo)` in the shading frame (normal
    /// `z`); zero at or below the horizon.
    fn eval(&self, wi: Vec3, wo: Vec3) -> [f64; 3] {
        Geometry::new(wi, wo).map_or([0.0; 3], |g| self.eval_geometry(&g))
    }
}

/// `p[k]` clamped into `bounds[k]`; the lower bound where `p` is short or
/// not a number.
pub(crate) fn param(p: &[f64], bounds: &[(f64, f64)], k: usize) -> f64 {
    let (lo, hi) = bounds[k];
    match p.get(k) {
        Some(v) if !v.is_nan() => v.clamp(lo, hi),
        _ => lo,
    }
}
