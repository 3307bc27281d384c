//! The four cosines an isotropic microfacet BRDF depends on.

use brdf_merl::{HalfDiff, Vec3};

/// Cosines of a pair of directions in the shading frame (normal `z`):
/// `n.l`, `n.v`, `n.h` and `v.h`, with `h` the half vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// Cosine of the incident (light) direction with the normal.
    pub nl: f64,
    /// Cosine of the outgoing (view) direction with the normal.
    pub nv: f64,
    /// Cosine of the half vector with the normal.
    pub nh: f64,
    /// Cosine of the view direction with the half vector (= `l.h`).
    pub vh: f64,
}

impl Geometry {
    /// The cosines of `(wi, wo)` (not necessarily unit); `None` when either
    /// lies at or below the horizon or is not a usable direction.
    pub fn new(wi: Vec3, wo: Vec3) -> Option<Geometry> {
        let l = unit(wi)?;
        let v = unit(wo)?;
        if l[2] <= 0.0 || v[2] <= 0.0 {
            return None;
        }
        let h = unit([l[0] + v[0], l[1] + v[1], l[2] + v[2]])?;
        Some(Geometry {
            nl: l[2],
            nv: v[2],
            nh: h[2].min(1.0),
            vh: (v[0] * h[0] + v[1] * h[1] + v[2] * h[2]).clamp(0.0, 1.0),
        })
    }

    /// The cosines of a MERL bin's representative angles; `None` when a
    /// direction is at or below the horizon.
    pub fn of_angles(hd: &HalfDiff) -> Option<Geometry> {
        let (ci, co) = hd.cosines();
        if ci <= 0.0 || co <= 0.0 {
            return None;
        }
        Some(Geometry {
            nl: ci,
            nv: co,
            nh: hd.theta_h.cos(),
            vh: hd.theta_d.cos(),
        })
    }
}

fn unit(v: Vec3) -> Option<Vec3> {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (len.is_finite() && len > 0.0).then(|| v.map(|c| c / len))
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf_merl::Dims;

    #[test]
    fn angles_and_directions_agree() {
        let dims = Dims::new(30, 30, 60).unwrap();
        for bin in (0..dims.bins()).step_by(97) {
            let hd = dims.angles_of(bin);
            let (wi, wo) = hd.directions();
            match (Geometry::of_angles(&hd), Geometry::new(wi, wo)) {
                (Some(a), Some(b)) => {
                    for (x, y) in [(a.nl, b.nl), (a.nv, b.nv), (a.nh, b.nh), (a.vh, b.vh)] {
                        assert!((x - y).abs() < 1e-9, "{bin}: {a:?} vs {b:?}");
                    }
                }
                (None, None) => {}
                (a, b) => {
                    // Only at the horizon may the two disagree by rounding.
                    let c = a.or(b).unwrap();
                    assert!(c.nl.min(c.nv) < 1e-9, "{bin}: {a:?} vs {b:?}");
                }
            }
        }
    }
}
