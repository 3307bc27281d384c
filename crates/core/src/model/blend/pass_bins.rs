//! Which bins a pass over the store reads ([`Every`]), and the albedo
//! weights of the bins it keeps.

use brdf_merl::Dims;
use brdf_merl::albedo::Quadrature;

/// Which bins a pass reads: every `theta_d`-th along theta_d and every
/// `phi_d`-th along phi_d, all of theta_h (the highlight lives there), each
/// kept bin in the middle of the cell of bins it stands for. A kept bin's
/// albedo weight is the dense rule's over its cell, so the albedo stays an
/// integral over the whole table of a piecewise-constant surrogate. The
/// integrand is smooth in phi_d: every 4th phi_d bin (a quarter of the
/// bins) is within 0.01% of the dense rule at the MERL resolution on
/// sharp synthetic metals and their blends, every 8th within 0.03%
/// (tested), where every 2nd theta_d bin is 4% off. The table errors are then RMSEs over the kept
/// bins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Every {
    /// Step along theta_d.
    pub theta_d: usize,
    /// Step along phi_d.
    pub phi_d: usize,
}

impl Every {
    /// Every bin.
    pub const BIN: Every = Every {
        theta_d: 1,
        phi_d: 1,
    };
    /// Every 4th phi_d bin: a quarter of the bins.
    pub const QUARTER: Every = Every {
        theta_d: 1,
        phi_d: 4,
    };
    /// Every 8th phi_d bin: an eighth of the bins, within 0.03% of the
    /// dense albedo where the quarter is within 0.01% (tested); what `fit`
    /// judges its own points on.
    pub const EIGHTH: Every = Every {
        theta_d: 1,
        phi_d: 8,
    };

    /// The first index of the cell of index `i` with step `step`.
    fn cell(i: usize, step: usize) -> usize {
        let step = step.max(1);
        i / step * step
    }

    /// The kept index of the cell starting at `start`, clipped to `len`.
    fn kept_in(start: usize, step: usize, len: usize) -> usize {
        (start + step.max(1) / 2).min(len - 1)
    }

    /// Whether every bin is kept (a step of at most 1 both ways).
    pub(crate) fn keeps_every_bin(self) -> bool {
        self.theta_d <= 1 && self.phi_d <= 1
    }

    /// Whether `bin` is kept: the definition [`Every::rows`] lists.
    #[cfg(test)]
    fn keeps(self, dims: Dims, bin: usize) -> bool {
        let (_, id, ip) = dims.unbin(bin);
        let keep = |i: usize, step: usize, len: usize| {
            i == Every::kept_in(Every::cell(i, step), step, len)
        };
        keep(id, self.theta_d, dims.theta_d) && keep(ip, self.phi_d, dims.phi_d)
    }

    /// The kept rows (all channels), or `None` when every row is kept.
    pub(crate) fn rows(self, dims: Dims, rows: usize) -> Option<Vec<u32>> {
        if self.keeps_every_bin() {
            return None;
        }
        let band = dims.theta_d * dims.phi_d;
        let mut out = Vec::new();
        for start in (0..rows).step_by(band.max(1)) {
            self.push_band(dims, start, rows, &mut out);
        }
        Some(out)
    }

    /// The kept rows of the theta_h band whose first row is `start`,
    /// ascending.
    pub(crate) fn band_rows(self, dims: Dims, start: usize) -> Vec<u32> {
        let mut out = Vec::new();
        self.push_band(dims, start, usize::MAX, &mut out);
        out
    }

    /// Appends the kept rows below `end` of the theta_h band whose first
    /// row is `start`: the bins [`Every::keeps`] accepts, listed without
    /// testing each.
    fn push_band(self, dims: Dims, start: usize, end: usize, out: &mut Vec<u32>) {
        let kept = |step: usize, len: usize| -> Vec<usize> {
            (0..len)
                .step_by(step.max(1))
                .map(|cell| Every::kept_in(cell, step, len))
                .collect()
        };
        let phi_d = kept(self.phi_d, dims.phi_d);
        for id in kept(self.theta_d, dims.theta_d) {
            for &ip in &phi_d {
                let r = start + id * dims.phi_d + ip;
                if r < end {
                    out.push(r as u32);
                }
            }
        }
    }

    /// The dense albedo rule ([`Quadrature::dense`], 2 sub-cells a bin, the
    /// rule the model's exact albedo uses) as a weight per bin, each bin's
    /// weight gathered onto the kept bin of its cell.
    pub(crate) fn weights(self, dims: Dims) -> Vec<f64> {
        let rule = Quadrature::dense(dims, 2);
        let mut w = vec![0.0; dims.bins()];
        for (&bin, &wb) in rule.bins().iter().zip(rule.weights()) {
            let (ih, id, ip) = dims.unbin(bin as usize);
            let kept = dims.bin(
                ih,
                Every::kept_in(Every::cell(id, self.theta_d), self.theta_d, dims.theta_d),
                Every::kept_in(Every::cell(ip, self.phi_d), self.phi_d, dims.phi_d),
            );
            w[kept] += wb;
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn listed_rows_are_the_kept_bins_of_every_channel() {
        for (h, d, p) in [(90, 90, 180), (5, 7, 13), (3, 1, 2)] {
            let dims = Dims::new(h, d, p).unwrap();
            for every in [
                Every::QUARTER,
                Every::EIGHTH,
                Every {
                    theta_d: 3,
                    phi_d: 5,
                },
                Every {
                    theta_d: 2,
                    phi_d: 1,
                },
            ] {
                let rows = 3 * dims.bins();
                let by_test: Vec<u32> = (0..rows)
                    .filter(|&r| every.keeps(dims, r % dims.bins()))
                    .map(|r| r as u32)
                    .collect();
                assert_eq!(every.rows(dims, rows), Some(by_test), "{dims} {every:?}");
            }
            assert_eq!(Every::BIN.rows(dims, 3 * dims.bins()), None);
        }
    }
}
