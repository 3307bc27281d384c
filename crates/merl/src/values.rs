//! MERL's raw values: their per-channel scales to reflectance, and which a
//! file may hold: finite, and no reflectance
//! beyond [`MAX_REFLECTANCE`]; negative values mark unmeasured bins. The
//! readers' scans ([`crate::MerlFile::open`], and a fit's store pass in
//! runs) test every value cheaply and branch-free, and name the first one
//! that fails.

use std::path::Path;

use crate::angles::Dims;
use crate::error::{MerlError, Result};

/// MERL's per-channel scales from raw file units to reflectance (1/sr).
pub const SCALE: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];

/// Channel names, for messages.
pub const CHANNELS: [&str; 3] = ["red", "green", "blue"];

/// Raw file value of `channel` -> reflectance. The one place the scales apply.
#[inline]
pub fn physical(channel: usize, raw: f64) -> f64 {
    raw * SCALE[channel]
}

/// Reflectance of `channel` -> raw file value (inverse of [`physical`]).
#[inline]
pub fn raw_from_physical(channel: usize, value: f64) -> f64 {
    value / SCALE[channel]
}

/// Is `v` infinite or NaN? Branch-free on the bits, so loops that OR it
/// over many values vectorise (the readers' validity scans).
#[inline(always)]
pub fn is_non_finite(v: f64) -> bool {
    (v.to_bits() & EXPONENT) == EXPONENT
}

/// The largest reflectance (1/sr) a MERL file may hold. A perfect mirror
/// averaged over MERL's finest half-angle bin (theta_h below 0.011 degrees)
/// reflects about 2e6; measured materials stay below 1e4. A value beyond
/// 1e8 is no reflectance but a broken file, and its squares and sums over a
/// table (4.4e22 at most here) stay far from overflowing a double or the
/// store's single precision, whatever the transform.
pub const MAX_REFLECTANCE: f64 = 1e8;

/// Raw values above this are beyond [`MAX_REFLECTANCE`] in the channel with
/// the largest scale (blue), so at or below it no channel's is.
const RAW_SUSPECT: f64 = MAX_REFLECTANCE / SCALE[2];

/// Might raw value `v` be out of range (not finite, or beyond
/// [`MAX_REFLECTANCE`] in some channel)? Branch-free like
/// [`is_non_finite`]; a `true` is settled by [`crate::MerlFile::check_values`].
#[inline(always)]
pub fn is_suspect(v: f64) -> bool {
    is_non_finite(v) | (v > RAW_SUSPECT)
}

/// Is raw value `v` of `channel` out of range: not finite, or a reflectance
/// beyond [`MAX_REFLECTANCE`]? (Negative values mark unmeasured bins.)
#[inline]
pub(crate) fn out_of_range(channel: usize, v: f64) -> bool {
    !v.is_finite() || physical(channel, v) > MAX_REFLECTANCE
}

/// Does a raw value mark an unmeasured sample?
#[inline]
pub fn is_invalid(raw: f64) -> bool {
    raw < 0.0
}

/// Check every value is finite and within [`MAX_REFLECTANCE`]; count the
/// negative (unmeasured) ones per channel.
pub(crate) fn scan_values(path: &Path, dims: Dims, data: &[u8]) -> Result<[usize; 3]> {
    let per_channel = data.len() / 24;
    let mut invalid = [0usize; 3];
    for (channel, block) in data.chunks_exact(8 * per_channel).enumerate() {
        // A branch-free pass (vectorises): count the negatives and see whether
        // any value may be out of range; find it only if so.
        let (mut negative, mut suspect) = (0usize, 0u64);
        for b in block.chunks_exact(8) {
            let v = f64::from_le_bytes(b.try_into().expect("8 bytes"));
            negative += is_invalid(v) as usize;
            suspect |= is_suspect(v) as u64;
        }
        if suspect != 0 {
            let values = block
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")));
            if let Some(e) = first_out_of_range(path, dims, channel * per_channel, values) {
                return Err(e);
            }
        }
        invalid[channel] = negative;
    }
    Ok(invalid)
}

/// The exponent field of an f64: all ones for infinities and NaNs.
const EXPONENT: u64 = 0x7ff0_0000_0000_0000;

/// The error for the first out-of-range value of `values`, which start at
/// flat index `start` of a file of `dims`, if there is one.
pub(crate) fn first_out_of_range(
    path: &Path,
    dims: Dims,
    start: usize,
    values: impl Iterator<Item = f64>,
) -> Option<MerlError> {
    let bins = dims.bins();
    let (index, value) = values
        .enumerate()
        .map(|(k, v)| (start + k, v))
        .find(|&(index, v)| out_of_range(index / bins, v))?;
    let (path, channel, bin) = (path.to_path_buf(), index / bins, index % bins);
    let name = CHANNELS[channel];
    Some(if value.is_finite() {
        let (theta_h, rest) = (
            bin / (dims.theta_d * dims.phi_d),
            bin % (dims.theta_d * dims.phi_d),
        );
        MerlError::Absurd {
            path,
            index,
            channel: name,
            bin: [theta_h, rest / dims.phi_d, rest % dims.phi_d],
            reflectance: physical(channel, value),
        }
    } else {
        MerlError::NonFinite {
            path,
            index,
            channel: name,
            bin,
            value,
        }
    })
}
