//! New materials from latent points: `z(x) = mean + k(x)^T K^-1 Z`, then the
//! inverse transform.
//!
//! A [`Blend`] is the cheap handle for one latent point: its `N` weights
//! `w = K^-1 k(x)`. It computes only what is asked: one bin (O(N) per
//! channel, one contiguous row of the store each), a batch of directions,
//! or the whole table (one streaming pass over the store, in parallel).
//! Every path goes through [`Blend::value`]'s arithmetic, so a point query
//! and the same bin of a full table agree bit for bit.
//!
//! Outputs are reflectance clamped to `>= 0` (a weighted sum of BRDFs can go
//! negative); bins that no input material measured keep MERL's invalid marker.

use brdf_merl::table::raw_from_physical;
use brdf_merl::{INVALID, MerlTable, Vec3};
use rayon::prelude::*;

use crate::error::Result;
use crate::model::Model;
use crate::store::Rows;

/// One latent point of a model, ready to answer queries.
pub struct Blend<'m> {
    model: &'m Model,
    x: Vec<f64>,
    weights: Vec<f64>,
}

/// `w . z_row`, accumulated in f64 with four independent partial sums (fixed
/// order); f32 store values are widened.
#[inline]
fn dot<T: Copy + Into<f64>>(w: &[f64], z: &[T]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (wc, wr) = w.split_at(w.len() / 4 * 4);
    let (zc, zr) = z.split_at(wc.len());
    for (a, b) in wc.chunks_exact(4).zip(zc.chunks_exact(4)) {
        for k in 0..4 {
            acc[k] += a[k] * b[k].into();
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (a, b) in wr.iter().zip(zr) {
        s += a * (*b).into();
    }
    s
}

impl Model {
    /// The blend at latent point `x` (`q` finite coordinates).
    pub fn at(&self, x: &[f64]) -> Result<Blend<'_>> {
        let weights = self.weights_at(x)?;
        Ok(Blend {
            model: self,
            x: x.to_vec(),
            weights,
        })
    }
}

impl<'m> Blend<'m> {
    /// The latent point.
    pub fn point(&self) -> &[f64] {
        &self.x
    }

    /// The blend weights `K^-1 k(x)`, one per input material.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The reconstruction of store row `row` in transformed space, `mean + w . z`.
    #[inline]
    pub fn transformed(&self, row: usize) -> f64 {
        let store = self.model.store();
        let n = store.n();
        let z = match store.z() {
            Rows::F32(z) => dot(&self.weights, &z[row * n..(row + 1) * n]),
            Rows::F64(z) => dot(&self.weights, &z[row * n..(row + 1) * n]),
        };
        store.mean()[row] + z
    }

    /// Reflectance of `channel` at `bin`, clamped to `>= 0`; `None` where no
    /// input material was measured.
    #[inline]
    pub fn value(&self, channel: usize, bin: usize) -> Option<f64> {
        let store = self.model.store();
        let row = channel * store.dims().bins() + bin;
        if store.unmeasured()[row] != 0 {
            return None;
        }
        Some(self.model.transform.inverse(bin, self.transformed(row)))
    }

    /// RGB reflectance at `bin`; `None` where some channel was never measured.
    pub fn rgb(&self, bin: usize) -> Option<[f64; 3]> {
        Some([
            self.value(0, bin)?,
            self.value(1, bin)?,
            self.value(2, bin)?,
        ])
    }

    /// RGB reflectance for a pair of directions (nearest bin, as MERL's own
    /// lookup); `None` below the horizon or where unmeasured.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Option<[f64; 3]> {
        self.rgb(self.model.dims().bin_of_directions(wi, wo)?)
    }

    /// [`Blend::eval`] for many direction pairs.
    pub fn eval_batch(&self, pairs: &[(Vec3, Vec3)]) -> Vec<Option<[f64; 3]>> {
        pairs.iter().map(|(wi, wo)| self.eval(*wi, *wo)).collect()
    }

    /// The whole table in MERL raw units: one parallel pass over the store.
    pub fn table(&self) -> MerlTable {
        let dims = self.model.dims();
        let bins = dims.bins();
        let mut values = vec![0.0f64; dims.values()];
        values
            .par_chunks_mut(8192)
            .enumerate()
            .for_each(|(k, out)| {
                let r0 = k * 8192;
                for (j, o) in out.iter_mut().enumerate() {
                    let row = r0 + j;
                    let (c, bin) = (row / bins, row % bins);
                    *o = match self.value(c, bin) {
                        Some(v) => raw_from_physical(c, v),
                        None => INVALID,
                    };
                }
            });
        MerlTable::from_raw(dims, values).expect("length matches dims")
    }
}
