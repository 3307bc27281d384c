//! What a fit records of how each material comes back: the judged
//! predictions of [`crate::fidelity`] (computed there, in one pass over the
//! store) and their spreads. The model file keeps the own-point ones.

use serde::{Deserialize, Serialize};

/// A material's own point gives it back when every channel of its albedo
/// there is within this share of its own: an error a person can just see
/// on a lit sphere beside the original.
pub const GIVES_BACK: f64 = 0.05;

/// A point within this distance of a material's latent point is its marker
/// (a click on the marker of a map a few hundred pixels wide).
pub const MARKER_RADIUS: f64 = 0.01;

/// One material's prediction, judged against the material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Judged {
    /// The material's own albedo, per channel.
    pub albedo: [f64; 3],
    /// The prediction's albedo, per channel.
    pub predicted: [f64; 3],
    /// RMSE of `ln((v' + e) / (v + e))` over the scored bins.
    pub log_rel: f64,
    /// RMSE of `ln(1 + v)` over the same bins (the older measure).
    pub log: f64,
}

impl Judged {
    /// The relative albedo error of each channel, `|predicted / albedo - 1|`
    /// (the absolute error where the albedo is 0).
    pub fn albedo_errors(&self) -> [f64; 3] {
        [0, 1, 2].map(|c| {
            let (a, p) = (self.albedo[c], self.predicted[c]);
            if a > 0.0 {
                (p / a - 1.0).abs()
            } else {
                p.abs()
            }
        })
    }

    /// The largest relative albedo error of the three channels.
    pub fn albedo_error(&self) -> f64 {
        self.albedo_errors().into_iter().fold(0.0, f64::max)
    }

    /// `predicted / albedo` in the channel of the largest relative error.
    pub fn worst_ratio(&self) -> f64 {
        let e = self.albedo_errors();
        let c = (0..3).fold(0, |b, c| if e[c] > e[b] { c } else { b });
        if self.albedo[c] > 0.0 {
            self.predicted[c] / self.albedo[c]
        } else {
            f64::INFINITY
        }
    }

    /// Whether the prediction gives the material back ([`GIVES_BACK`]).
    pub fn gives_back(&self) -> bool {
        self.albedo_error() <= GIVES_BACK
    }

    /// What a person is told of a prediction that does not give its
    /// material back: "gives back 7.8x its albedo" or "... 0.42x ...".
    pub fn describe(&self) -> String {
        let r = self.worst_ratio();
        if r.is_finite() {
            format!(
                "gives back {}x its albedo (worst channel; {:.0}% off)",
                ratio(r),
                100.0 * self.albedo_error()
            )
        } else {
            "gives back albedo where the material has none".into()
        }
    }
}

/// A ratio to two significant figures.
fn ratio(r: f64) -> String {
    if r >= 10.0 {
        format!("{r:.0}")
    } else if r >= 1.0 {
        format!("{r:.1}")
    } else {
        format!("{r:.2}")
    }
}

/// Median, 90th percentile and worst of a set of errors, and which is worst.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Median.
    pub median: f64,
    /// 90th percentile (nearest rank).
    pub p90: f64,
    /// Largest.
    pub worst: f64,
    /// Index of the largest.
    pub worst_index: usize,
}

impl Spread {
    /// The spread of `values` (at least one).
    pub fn of(values: &[f64]) -> Spread {
        let mut sorted: Vec<f64> = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let rank = |p: f64| {
            let k = ((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
            sorted[k - 1]
        };
        let worst_index = (0..values.len()).fold(0, |b, i| {
            if values[i].total_cmp(&values[b]).is_gt() {
                i
            } else {
                b
            }
        });
        let mid = sorted.len() / 2;
        let median = if sorted.len() % 2 == 1 {
            sorted[mid]
        } else {
            0.5 * (sorted[mid - 1] + sorted[mid])
        };
        Spread {
            median,
            p90: rank(0.9),
            worst: sorted.last().copied().unwrap_or(0.0),
            worst_index,
        }
    }
}

/// The fidelity of a fitted model, material by material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fidelity {
    /// Each material at its own point, by the default rule (the soft floor).
    pub own: Vec<Judged>,
    /// Each material at its own point, by the GP's own blend.
    pub own_gp: Vec<Judged>,
    /// Each material predicted from the others at its point (default
    /// rule), when asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_out: Option<Vec<Judged>>,
    /// The same by the GP's own blend, when asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_out_gp: Option<Vec<Judged>>,
}

/// Spreads of a set of judged predictions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Of the relative albedo error of every channel of every material
    /// (`3 N` values; the worst index is a material's).
    pub albedo: Spread,
    /// Of each material's largest relative albedo error over its channels.
    pub albedo_worst_channel: Spread,
    /// Of the log-relative table error.
    pub log_rel: Spread,
    /// Of the `ln(1 + v)` RMSE.
    pub log: Spread,
}

impl Summary {
    /// The spreads of `judged` (at least one).
    pub fn of(judged: &[Judged]) -> Summary {
        let pick = |f: fn(&Judged) -> f64| Spread::of(&judged.iter().map(f).collect::<Vec<_>>());
        let channels: Vec<f64> = judged.iter().flat_map(Judged::albedo_errors).collect();
        let mut albedo = Spread::of(&channels);
        albedo.worst_index /= 3;
        Summary {
            albedo,
            albedo_worst_channel: pick(Judged::albedo_error),
            log_rel: pick(|j| j.log_rel),
            log: pick(|j| j.log),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_takes_nearest_ranks() {
        let v: Vec<f64> = (1..=10).map(f64::from).rev().collect();
        let s = Spread::of(&v);
        assert_eq!(
            (s.median, s.p90, s.worst, s.worst_index),
            (5.5, 9.0, 10.0, 0)
        );
        let s = Spread::of(&[3.0]);
        assert_eq!((s.median, s.p90, s.worst), (3.0, 3.0, 3.0));
    }

    #[test]
    fn judged_errors_are_relative_per_channel() {
        let j = Judged {
            albedo: [0.016, 0.010, 0.009],
            predicted: [0.116, 0.0101, 0.009],
            log_rel: 0.0,
            log: 0.0,
        };
        let e = j.albedo_errors();
        assert!((e[0] - 6.25).abs() < 1e-12 && (e[1] - 0.01).abs() < 1e-12 && e[2] == 0.0);
        assert!((j.worst_ratio() - 7.25).abs() < 1e-12);
        assert!(!j.gives_back());
        assert!(
            j.describe().starts_with("gives back 7.2x its albedo"),
            "{}",
            j.describe()
        );
    }
}
