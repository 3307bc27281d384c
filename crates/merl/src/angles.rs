//! The MERL sampling grid: table dims, the index maps, and the
//! Rusinkiewicz half/difference parameterisation.
//!
//! A MERL table is indexed `[theta_h][theta_d][phi_d]`:
//! - `theta_h` in `[0, pi/2]` through a square-root map, `i = floor(n * sqrt(theta_h / (pi/2)))`,
//!   which puts more bins near the specular peak;
//! - `theta_d` in `[0, pi/2]` uniformly;
//! - `phi_d` in `[0, pi)` uniformly: reciprocity folds `phi_d` and `phi_d + pi` together.
//!
//! Bin `i` of an axis covers the half-open cell `[i, i+1)` of its index
//! coordinate. The representative angles of a bin are the lower corner of its
//! cell, the convention of the MERL sample positions (and of the NBRDF-derived
//! test data).

use std::f64::consts::{FRAC_PI_2, PI};

use crate::error::{MerlError, Result};

/// A unit direction, z up (the surface normal).
pub type Vec3 = [f64; 3];

/// The three table dimensions of a MERL file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Dims {
    /// Bins along theta_h (square-root spaced). 90 in MERL.
    pub theta_h: usize,
    /// Bins along theta_d. 90 in MERL.
    pub theta_d: usize,
    /// Bins along phi_d over `[0, pi)`. 180 in MERL.
    pub phi_d: usize,
}

/// Largest accepted dimension: a table of 1024^3 bins would be 24 GiB.
pub const MAX_DIM: usize = 1024;

impl Dims {
    /// The real MERL resolution, the one BRDF Explorer needs: 90 x 90 x 180.
    pub const MERL: Dims = Dims {
        theta_h: 90,
        theta_d: 90,
        phi_d: 180,
    };

    /// Checked constructor: every dim in `1..=MAX_DIM`.
    pub fn new(theta_h: usize, theta_d: usize, phi_d: usize) -> Result<Dims> {
        let bad = |why| MerlError::InvalidDims {
            a: theta_h,
            b: theta_d,
            c: phi_d,
            why,
        };
        if theta_h == 0 || theta_d == 0 || phi_d == 0 {
            return Err(bad("every dimension must be at least 1"));
        }
        if theta_h > MAX_DIM || theta_d > MAX_DIM || phi_d > MAX_DIM {
            return Err(bad("a dimension is larger than 1024"));
        }
        Ok(Dims {
            theta_h,
            theta_d,
            phi_d,
        })
    }

    /// Number of bins in one colour channel.
    pub fn bins(&self) -> usize {
        self.theta_h * self.theta_d * self.phi_d
    }

    /// Number of values in the table: three channels.
    pub fn values(&self) -> usize {
        3 * self.bins()
    }

    /// Flat bin index of `(i_theta_h, i_theta_d, i_phi_d)`.
    pub fn bin(&self, ih: usize, id: usize, ip: usize) -> usize {
        (ih * self.theta_d + id) * self.phi_d + ip
    }

    /// The three indices of a flat bin.
    pub fn unbin(&self, bin: usize) -> (usize, usize, usize) {
        let ip = bin % self.phi_d;
        let rest = bin / self.phi_d;
        (rest / self.theta_d, rest % self.theta_d, ip)
    }

    /// theta_h -> bin along the theta_h axis (square-root map, clamped).
    pub fn theta_h_index(&self, theta_h: f64) -> usize {
        if theta_h.is_nan() || theta_h <= 0.0 {
            return 0;
        }
        let u = (theta_h / FRAC_PI_2).sqrt();
        clamp_index(u * self.theta_h as f64, self.theta_h)
    }

    /// theta_d -> bin along the theta_d axis (uniform, clamped).
    pub fn theta_d_index(&self, theta_d: f64) -> usize {
        clamp_index(theta_d / FRAC_PI_2 * self.theta_d as f64, self.theta_d)
    }

    /// phi_d -> bin along the phi_d axis; any angle, folded to `[0, pi)` by reciprocity.
    pub fn phi_d_index(&self, phi_d: f64) -> usize {
        let folded = phi_d.rem_euclid(PI);
        clamp_index(folded / PI * self.phi_d as f64, self.phi_d)
    }

    /// Half/difference angles -> flat bin.
    pub fn bin_of(&self, theta_h: f64, theta_d: f64, phi_d: f64) -> usize {
        self.bin(
            self.theta_h_index(theta_h),
            self.theta_d_index(theta_d),
            self.phi_d_index(phi_d),
        )
    }

    /// Incident and outgoing directions -> flat bin, or `None` when either
    /// lies below the horizon or is not a usable direction.
    pub fn bin_of_directions(&self, wi: Vec3, wo: Vec3) -> Option<usize> {
        let hd = HalfDiff::from_directions(wi, wo)?;
        Some(self.bin_of(hd.theta_h, hd.theta_d, hd.phi_d))
    }

    /// The representative angles of a flat bin: the lower corner of its cell.
    pub fn angles_of(&self, bin: usize) -> HalfDiff {
        let (ih, id, ip) = self.unbin(bin);
        let u = ih as f64 / self.theta_h as f64;
        HalfDiff {
            theta_h: u * u * FRAC_PI_2,
            phi_h: 0.0,
            theta_d: id as f64 / self.theta_d as f64 * FRAC_PI_2,
            phi_d: ip as f64 / self.phi_d as f64 * PI,
        }
    }
}

impl std::fmt::Display for Dims {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}x{}", self.theta_h, self.theta_d, self.phi_d)
    }
}

fn clamp_index(x: f64, n: usize) -> usize {
    if x.is_nan() || x <= 0.0 {
        0
    } else {
        (x as usize).min(n - 1)
    }
}

/// Rusinkiewicz half/difference angles of a pair of directions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfDiff {
    /// Angle between the half vector and the normal.
    pub theta_h: f64,
    /// Azimuth of the half vector (irrelevant for isotropic BRDFs).
    pub phi_h: f64,
    /// Angle between the incident direction and the half vector.
    pub theta_d: f64,
    /// Azimuth of the incident direction around the half vector.
    pub phi_d: f64,
}

impl HalfDiff {
    /// Convert `(wi, wo)` (not necessarily normalised) to half/difference
    /// angles, as MERL's `std_coords_to_half_diff_coords` does.
    /// `None` when either direction is at or below the horizon, zero or not finite.
    pub fn from_directions(wi: Vec3, wo: Vec3) -> Option<HalfDiff> {
        let wi = normalize(wi)?;
        let wo = normalize(wo)?;
        if wi[2] <= 0.0 || wo[2] <= 0.0 {
            return None;
        }
        let h = normalize(add(wi, wo))?;
        let theta_h = h[2].clamp(-1.0, 1.0).acos();
        let phi_h = h[1].atan2(h[0]);
        let t = rotate_z(wi, -phi_h);
        let d = rotate_y(t, -theta_h);
        Some(HalfDiff {
            theta_h,
            phi_h,
            theta_d: d[2].clamp(-1.0, 1.0).acos(),
            phi_d: d[1].atan2(d[0]),
        })
    }

    /// The incident and outgoing directions of these angles (inverse of
    /// [`HalfDiff::from_directions`]). Either may lie below the horizon.
    pub fn directions(&self) -> (Vec3, Vec3) {
        let (sd, cd) = self.theta_d.sin_cos();
        let (sp, cp) = self.phi_d.sin_cos();
        let d = [sd * cp, sd * sp, cd];
        let wi = rotate_z(rotate_y(d, self.theta_h), self.phi_h);
        let (sh, ch) = self.theta_h.sin_cos();
        let (sph, cph) = self.phi_h.sin_cos();
        let h = [sh * cph, sh * sph, ch];
        let k = 2.0 * dot(wi, h);
        let wo = [k * h[0] - wi[0], k * h[1] - wi[1], k * h[2] - wi[2]];
        (wi, wo)
    }

    /// `(cos theta_i, cos theta_o)`, the elevation cosines of the pair
    /// (negative below the horizon); phi_h does not matter.
    pub fn cosines(&self) -> (f64, f64) {
        let (sd, cd) = self.theta_d.sin_cos();
        let (sh, ch) = self.theta_h.sin_cos();
        let x = sd * self.phi_d.cos() * sh;
        (cd * ch - x, cd * ch + x)
    }
}

/// Direction from spherical angles (theta from the normal, phi azimuth).
pub fn direction(theta: f64, phi: f64) -> Vec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    [st * cp, st * sp, ct]
}

fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(v: Vec3) -> Option<Vec3> {
    let n = dot(v, v).sqrt();
    if !(n.is_finite() && n > 1e-300) {
        return None;
    }
    Some([v[0] / n, v[1] / n, v[2] / n])
}

/// Rotate about the z axis (the normal) by `a`.
fn rotate_z(v: Vec3, a: f64) -> Vec3 {
    let (s, c) = a.sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]
}

/// Rotate about the y axis (the binormal) by `a`.
fn rotate_y(v: Vec3, a: f64) -> Vec3 {
    let (s, c) = a.sin_cos();
    [c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    const M: Dims = Dims::MERL;

    #[test]
    fn theta_h_index_endpoints_and_sqrt_map() {
        assert_eq!(M.theta_h_index(0.0), 0);
        assert_eq!(M.theta_h_index(-0.1), 0);
        assert_eq!(M.theta_h_index(f64::NAN), 0);
        assert_eq!(M.theta_h_index(FRAC_PI_2), 89);
        assert_eq!(M.theta_h_index(10.0), 89);
        // The square-root map: bin 1 starts at (1/90)^2 * pi/2, far below 1 degree.
        let start1 = (1.0f64 / 90.0).powi(2) * FRAC_PI_2;
        assert_eq!(M.theta_h_index(start1 * 0.999), 0);
        assert_eq!(M.theta_h_index(start1 * 1.001), 1);
        // Half way in angle is bin floor(90 * sqrt(0.5)) = 63.
        assert_eq!(M.theta_h_index(FRAC_PI_2 / 2.0), 63);
    }

    #[test]
    fn theta_d_and_phi_d_endpoints() {
        assert_eq!(M.theta_d_index(0.0), 0);
        assert_eq!(M.theta_d_index(FRAC_PI_2), 89);
        assert_eq!(M.theta_d_index(FRAC_PI_2 * 0.5), 45);
        assert_eq!(M.phi_d_index(0.0), 0);
        assert_eq!(M.phi_d_index(PI - 1e-12), 179);
        // Reciprocity: phi_d and phi_d + pi share a bin; negative angles fold up.
        assert_eq!(M.phi_d_index(PI), 0);
        assert_eq!(M.phi_d_index(-PI / 2.0), 90);
        assert_eq!(M.phi_d_index(0.3 + PI), M.phi_d_index(0.3));
    }

    #[test]
    fn bin_and_unbin_agree() {
        let d = Dims::new(5, 7, 11).unwrap();
        for b in 0..d.bins() {
            let (i, j, k) = d.unbin(b);
            assert_eq!(d.bin(i, j, k), b);
        }
        assert_eq!(M.bin(89, 89, 179), M.bins() - 1);
    }

    #[test]
    fn dims_are_checked() {
        assert!(Dims::new(0, 90, 180).is_err());
        assert!(Dims::new(90, 90, 5000).is_err());
        assert_eq!(Dims::new(90, 90, 180).unwrap(), Dims::MERL);
    }

    #[test]
    fn every_bin_maps_back_to_itself() {
        // The lower corner of a cell, nudged inside, must index that cell.
        let d = Dims::new(9, 10, 12).unwrap();
        for b in 0..d.bins() {
            let (ih, id, ip) = d.unbin(b);
            let u = (ih as f64 + 0.5) / d.theta_h as f64;
            let th = u * u * FRAC_PI_2;
            let td = (id as f64 + 0.5) / d.theta_d as f64 * FRAC_PI_2;
            let pd = (ip as f64 + 0.5) / d.phi_d as f64 * PI;
            assert_eq!(d.bin_of(th, td, pd), b);
        }
    }

    #[test]
    fn half_diff_round_trip() {
        for &(th, td, pd, ph) in &[
            (0.3, 0.2, 1.0, 0.0),
            (0.05, 0.7, -2.0, 1.3),
            (0.6, 0.4, 2.9, -0.4),
        ] {
            let hd = HalfDiff {
                theta_h: th,
                phi_h: ph,
                theta_d: td,
                phi_d: pd,
            };
            let (wi, wo) = hd.directions();
            assert!((dot(wi, wi) - 1.0).abs() < 1e-12 && (dot(wo, wo) - 1.0).abs() < 1e-12);
            let back = HalfDiff::from_directions(wi, wo).unwrap();
            assert!((back.theta_h - th).abs() < 1e-9, "{back:?}");
            assert!((back.theta_d - td).abs() < 1e-9, "{back:?}");
            assert!((back.phi_d - pd).abs() < 1e-9, "{back:?}");
            let (ci, co) = hd.cosines();
            assert!((ci - wi[2]).abs() < 1e-12 && (co - wo[2]).abs() < 1e-12);
        }
    }

    #[test]
    fn mirror_pair_is_theta_h_zero() {
        let wi = direction(0.7, 0.4);
        let wo = direction(0.7, 0.4 + PI);
        let hd = HalfDiff::from_directions(wi, wo).unwrap();
        assert!(hd.theta_h.abs() < 1e-7);
        assert!((hd.theta_d - 0.7).abs() < 1e-9);
        assert_eq!(M.theta_h_index(hd.theta_h), 0);
    }

    #[test]
    fn below_horizon_and_garbage_have_no_bin() {
        assert!(
            M.bin_of_directions([0.0, 0.0, 1.0], [0.0, 0.3, -1.0])
                .is_none()
        );
        assert!(
            M.bin_of_directions([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
                .is_none()
        );
        assert!(
            M.bin_of_directions([f64::NAN, 0.0, 1.0], [0.0, 0.0, 1.0])
                .is_none()
        );
        assert_eq!(
            M.bin_of_directions([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
            Some(0)
        );
    }
}
