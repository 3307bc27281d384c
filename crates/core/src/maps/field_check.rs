//! How far a sampled field is from the exact albedo, measured when it is
//! built: its value at a few seeded random points of its domain against
//! exact albedos there (the nodes' rule over the full reconstruction,
//! within 0.1% of the dense rule). The refinement's estimate says how well
//! the polynomial follows the sampled rule's node values; only exact
//! albedos say how far those values are from the albedo itself, which for
//! a sampled field is most of its error (docs/performance.md, "Sampled
//! fields").

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::map_error::albedo_error;
use crate::maps::Atlas;
use crate::maps::view::View;

/// Points a sampled field is checked at: 32 exact albedos, 0.17 s for 100
/// materials at the MERL resolution on two cores (a sampled field of the
/// default view takes about 2 s to build).
pub const CHECK_POINTS: usize = 32;

/// A sampled field's error against exact albedos at [`CHECK_POINTS`]
/// seeded random points of its domain ([`check_points`]), each relative to
/// the exact albedo's largest channel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FieldCheck {
    /// Points checked.
    pub points: usize,
    /// The largest error over the points and channels.
    pub worst: f64,
    /// The mean error over the points and channels.
    pub mean: f64,
}

/// The points a field of `domain` is checked at: [`CHECK_POINTS`] points
/// drawn uniformly from it with a fixed seed, so the same domain is
/// always checked at the same points.
pub fn check_points(domain: View) -> Vec<[f64; 2]> {
    let mut rng = brdf_merl::synth::SplitMix64::new(0x5eed_c4ec);
    (0..CHECK_POINTS)
        .map(|_| {
            [
                rng.range(domain.x0, domain.x1),
                rng.range(domain.y0, domain.y1),
            ]
        })
        .collect()
}

impl Atlas {
    /// The check ([`FieldCheck`]) of a field of `domain` whose albedo at a
    /// point is `albedo` (a built field's
    /// [`AlbedoField::at`](crate::AlbedoField::at)), against one pass over
    /// the nodes' rule's rows for all the points. `floor`: every value on
    /// its soft floor.
    pub(crate) fn check_field(
        &self,
        domain: View,
        albedo: impl Fn([f64; 2]) -> [f64; 3],
        floor: bool,
    ) -> Result<FieldCheck> {
        let points = check_points(domain);
        let exact = self.albedos_over(self.node_rows(), &points, floor)?;
        let got: Vec<[f64; 3]> = points.iter().map(|&x| albedo(x)).collect();
        let (worst, mean) = albedo_error(&got, &exact);
        Ok(FieldCheck {
            points: points.len(),
            worst,
            mean,
        })
    }
}
