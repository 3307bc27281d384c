//! New materials from latent points: `z(x) = mean + k(x)^T K^-1 Z`, then the
//! inverse transform.
//!
//! A [`Blend`] is the cheap handle for one latent point: its `N` weights
//! `w = K^-1 k(x)`. It computes only what is asked: one bin (O(N) per
//! channel, one contiguous row of the store each), a batch of directions,
//! or the whole table (one streaming pass over the store, in parallel).
//! A bin once computed is remembered, so a renderer that asks for the same
//! bins again and again (every frame of a lit sphere does) pays the O(N)
//! sum once per bin; the memo is a lazily allocated table of 8-byte slots
//! that costs no memory until queries touch it. Every path goes through
//! [`crate::simd::dot`] and [`Transform::inverse_run`](crate::data::transform::Transform::inverse_run),
//! so a point query and the same bin of a full table agree bit for bit.
//!
//! Outputs are reflectance clamped to `>= 0` (a weighted sum of BRDFs can go
//! negative); bins that no input material measured keep MERL's invalid marker.
//!
//! If the store changes on disk while the model is open, [`Blend::table`]
//! returns [`CoreError::FileChanged`](crate::CoreError::FileChanged); the
//! point queries, which return plain values, then give numbers of no
//! meaning (never a crash), and [`Model::verify`] says so: check it before
//! using their answers.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

use brdf_merl::table::raw_from_physical;
use brdf_merl::{INVALID, MerlTable, Vec3};
use rayon::prelude::*;

use crate::data::store::Rows;
use crate::error::Result;
use crate::model::Model;
use crate::model::blend::soft_floor::{caps, floor_capped, floor_values, reach_cap};
use crate::simd::dot;

/// One latent point of a model, ready to answer queries.
pub struct Blend<'m> {
    model: &'m Model,
    x: Vec<f64>,
    /// `k(x)`, the kernel between `x` and every input material.
    kernel: Vec<f64>,
    /// The GP's weights `K^-1 k(x)`.
    gp: Vec<f64>,
    /// The weights the blend uses: `gp`, or those it was made with.
    weights: Vec<f64>,
    /// Weights per `theta_h` bin, where a [`crate::model::blend::BlendRule`] moved them.
    bands: Option<Box<Bands>>,
    /// The convex weights `v`, where [`crate::model::blend::BlendRule::Floor`]
    /// lifts every value onto its soft floor ([`crate::model::blend::soft_floor`]).
    floor: Option<Box<[f64]>>,
    /// Under the floor, how far each channel's cap reaches from the convex
    /// blend towards the brightest material ([`crate::model::blend::soft_floor::reach_cap`]).
    reach: [f64; 3],
    /// `value(channel, bin)` of every row asked so far (see [`Memo`]).
    memo: OnceLock<Box<[AtomicU64]>>,
}

/// The weights of a blend that differ from one `theta_h` bin to the next:
/// in bin `b`, `w + t_b (v - w)` (`w` the GP's weights, `v` the convex
/// ones), one weight vector per distinct step.
#[derive(Debug, Clone)]
pub(crate) struct Bands {
    /// The convex weights `v`.
    pub(crate) convex: Vec<f64>,
    /// The step `t_b` of each `theta_h` bin.
    pub(crate) steps: Vec<f64>,
    /// Index into `sets` of each `theta_h` bin.
    of_bin: Vec<usize>,
    /// One weight vector per distinct step.
    sets: Vec<Vec<f64>>,
    /// Bins per `theta_h` bin (`theta_d x phi_d`).
    per: usize,
}

impl Bands {
    /// The banded weights for GP weights `w`, convex weights `v`, steps `t`
    /// per `theta_h` bin, and `per` bins per `theta_h` bin.
    pub(crate) fn new(w: &[f64], convex: Vec<f64>, steps: Vec<f64>, per: usize) -> Bands {
        let mut distinct: Vec<f64> = Vec::new();
        let of_bin = steps
            .iter()
            .map(|&t| {
                distinct.iter().position(|&d| d == t).unwrap_or_else(|| {
                    distinct.push(t);
                    distinct.len() - 1
                })
            })
            .collect();
        let sets = distinct
            .iter()
            .map(|&t| {
                w.iter()
                    .zip(&convex)
                    .map(|(w, v)| w + t * (v - w))
                    .collect()
            })
            .collect();
        Bands {
            convex,
            steps,
            of_bin,
            sets,
            per,
        }
    }

    /// The weights of `theta_h` bin `b`.
    fn of(&self, b: usize) -> &[f64] {
        &self.sets[self.of_bin[b]]
    }
}

/// Encoding of the memo's slots: a value is stored as its bits XOR a NaN
/// pattern, so the zeroed slot (the bits of that NaN, which no query
/// produces) means "not computed yet", and a second NaN pattern marks
/// "unmeasured". Values keep every bit, the sign of zero included.
struct Memo;

impl Memo {
    const KEY: u64 = 0x7ff8_a71a_5000_0001;
    const EMPTY: u64 = 0;
    const UNMEASURED: u64 = Memo::KEY ^ 0x7ff8_a71a_5000_0002;

    #[inline]
    fn encode(v: Option<f64>) -> u64 {
        v.map_or(Memo::UNMEASURED, |v| v.to_bits() ^ Memo::KEY)
    }

    /// `None` if not computed yet, else the stored answer.
    #[inline]
    fn decode(bits: u64) -> Option<Option<f64>> {
        match bits {
            Memo::EMPTY => None,
            Memo::UNMEASURED => Some(None),
            b => Some(Some(f64::from_bits(b ^ Memo::KEY))),
        }
    }
}

/// Rows a worker of [`Blend::table`] handles at once (fixed, so the work
/// split does not depend on the thread count; results never do).
pub(crate) const TABLE_CHUNK: usize = 4096;

impl<'m> Blend<'m> {
    /// The GP's blend at latent point `x` (`q` finite coordinates).
    /// [`CoreError::FileChanged`](crate::CoreError::FileChanged) once the
    /// store is known to have changed (a model refuses every query then).
    pub(crate) fn gp_at(model: &'m Model, x: &[f64]) -> Result<Blend<'m>> {
        model.store().verify_cheap()?;
        let (kernel, weights) = model.kernel_and_weights_at(x)?;
        Ok(Blend {
            model,
            x: x.to_vec(),
            kernel,
            gp: weights.clone(),
            weights,
            bands: None,
            floor: None,
            reach: [1.0; 3],
            memo: OnceLock::new(),
        })
    }

    /// A blend of the stored rows with any weights (no latent point).
    pub(crate) fn of_weights(model: &'m Model, weights: &[f64]) -> Blend<'m> {
        Blend {
            model,
            x: Vec::new(),
            kernel: Vec::new(),
            gp: weights.to_vec(),
            weights: weights.to_vec(),
            bands: None,
            floor: None,
            reach: [1.0; 3],
            memo: OnceLock::new(),
        }
    }
}

impl<'m> Blend<'m> {
    /// The latent point.
    pub fn point(&self) -> &[f64] {
        &self.x
    }

    /// The blend weights, one per input material: the GP's `K^-1 k(x)`.
    /// Where a [`crate::model::blend::BlendRule`] moved them, the weights differ
    /// from one `theta_h` bin to the next: see [`Blend::weights_in`].
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The weights the blend uses in `theta_h` bin `theta_h` (bins beyond the
    /// table's read as the last).
    pub fn weights_in(&self, theta_h: usize) -> &[f64] {
        match &self.bands {
            Some(b) => b.of(theta_h.min(b.steps.len() - 1)),
            None => &self.weights,
        }
    }

    /// Where a [`crate::model::blend::BlendRule`] moved the weights: the convex
    /// weights `v` and the step `t_b` of each `theta_h` bin (the weights in
    /// bin `b` are `w + t_b (v - w)`). `None` for the GP's own blend.
    pub fn steps(&self) -> Option<(&[f64], &[f64])> {
        self.bands
            .as_deref()
            .map(|b| (b.convex.as_slice(), b.steps.as_slice()))
    }

    /// The weights of store row `row`.
    #[inline]
    pub(crate) fn weights_of_row(&self, row: usize, bins: usize) -> &[f64] {
        match &self.bands {
            Some(b) => b.of((row % bins) / b.per),
            None => &self.weights,
        }
    }

    /// The GP's weights `K^-1 k(x)` at this point, whatever the rule.
    pub fn gp_weights(&self) -> &[f64] {
        &self.gp
    }

    /// `k(x)`: the kernel between the point and each input material.
    pub fn kernel(&self) -> &[f64] {
        &self.kernel
    }

    /// The model the blend reads.
    pub(crate) fn model(&self) -> &Model {
        self.model
    }

    /// The same point with weights per `theta_h` bin (and a fresh memo).
    pub(crate) fn with_bands(&self, bands: Bands) -> Blend<'m> {
        self.moved(Some(Box::new(bands)), None)
    }

    /// The same point with every value lifted onto the soft floor under the
    /// blend of the convex weights `convex` (and a fresh memo).
    pub(crate) fn with_floor(&self, convex: Vec<f64>) -> Blend<'m> {
        self.moved(None, Some(convex.into_boxed_slice()))
    }

    /// The same point and weights under a rule's `bands` or `floor`.
    fn moved(&self, bands: Option<Box<Bands>>, floor: Option<Box<[f64]>>) -> Blend<'m> {
        let reach = floor
            .as_deref()
            .map_or([1.0; 3], |v| self.model.store().energy_bound().reach(v));
        Blend {
            model: self.model,
            x: self.x.clone(),
            kernel: self.kernel.clone(),
            gp: self.gp.clone(),
            weights: self.weights.clone(),
            bands,
            floor,
            reach,
            memo: OnceLock::new(),
        }
    }

    /// Where [`crate::model::blend::BlendRule::Floor`] formed the blend: the convex
    /// weights `v` whose blend sets each value's floor.
    pub fn floor(&self) -> Option<&[f64]> {
        self.floor.as_deref()
    }

    /// Under [`crate::model::blend::BlendRule::Floor`], how far each channel's cap
    /// reaches from the convex blend towards the brightest material (1:
    /// all the way; [`crate::model::blend::soft_floor::reach_cap`]); 1 under the other
    /// rules, which have no cap.
    pub fn reach(&self) -> [f64; 3] {
        self.reach
    }

    /// The reconstruction of store row `row` in transformed space, `mean + w . z`
    /// (lifted onto its soft floor under [`crate::model::blend::BlendRule::Floor`]).
    #[inline]
    pub fn transformed(&self, row: usize) -> f64 {
        let store = self.model.store();
        let n = store.n();
        let blend = |w: &[f64]| {
            let z = match store.z() {
                Rows::F32(z) => dot::dot(w, &z[row * n..(row + 1) * n]),
                Rows::F64(z) => dot::dot(w, &z[row * n..(row + 1) * n]),
            };
            store.mean()[row] + z
        };
        let bins = self.model.dims().bins();
        let g = blend(self.weights_of_row(row, bins));
        match &self.floor {
            Some(v) => {
                let (c, top) = (blend(v), store.mean()[row] + row_top(store, row));
                floor_capped(g, c, reach_cap(c, top, self.reach[row / bins]))
            }
            None => g,
        }
    }

    /// [`Blend::transformed`] for rows `r0 .. r0 + out.len()`. Under the
    /// floor a run of rows at a time, on the stack: the GP's and the convex
    /// blend (from one read of each row, [`dot::rows2`], unless the GP's
    /// weights change along the run with the theta_h bands, when its blend
    /// comes first), the caps, then the floor.
    pub fn transformed_rows(&self, r0: usize, out: &mut [f64]) {
        let Some(v) = &self.floor else {
            return self.blended_rows(r0, out);
        };
        let banded = self.bands.is_some();
        if banded {
            self.blended_rows(r0, out);
        }
        let store = self.model.store();
        let n = store.n();
        let (mut convex, mut top) = ([0.0f64; 256], [0.0f64; 256]);
        for (k, out) in out.chunks_mut(convex.len()).enumerate() {
            let r = r0 + k * convex.len();
            let (mean, c, top) = (
                &store.mean()[r..r + out.len()],
                &mut convex[..out.len()],
                &mut top[..out.len()],
            );
            let rows = r * n..(r + out.len()) * n;
            match store.z() {
                Rows::F32(z) => self.floor_inputs(v, banded, &z[rows], mean, out, c, top),
                Rows::F64(z) => self.floor_inputs(v, banded, &z[rows], mean, out, c, top),
            }
            let bins = self.model.dims().bins();
            for (k, (top, &c)) in top.iter_mut().zip(c.iter()).enumerate() {
                *top = reach_cap(c, *top, self.reach[(r + k) / bins]);
            }
            floor_values(out, c, top);
        }
    }

    /// The soft floor's inputs for a run of store rows `z`: the convex
    /// blend `c` (convex weights `v`), the caps `top`, and the GP's blend
    /// into `gp` unless it is there already (`banded`).
    #[allow(clippy::too_many_arguments)]
    fn floor_inputs<T: dot::Element + PartialOrd>(
        &self,
        v: &[f64],
        banded: bool,
        z: &[T],
        mean: &[f64],
        gp: &mut [f64],
        c: &mut [f64],
        top: &mut [f64],
    ) {
        if banded {
            dot::rows(v, z, mean, c);
        } else {
            dot::rows2(&self.weights, v, z, mean, gp, c);
        }
        caps(z, v.len(), mean, top);
    }

    /// `mean + w . z` of rows `r0 .. r0 + out.len()`, with each row's weights.
    fn blended_rows(&self, r0: usize, out: &mut [f64]) {
        let store = self.model.store();
        let n = store.n();
        let (bins, end) = (self.model.dims().bins(), r0 + out.len());
        let mut r = r0;
        while r < end {
            // One run of rows with the same weights: the rest of the table,
            // or of the current theta_h bin.
            let (w, run_end) = match &self.bands {
                None => (self.weights.as_slice(), end),
                Some(b) => {
                    let bin = r % bins;
                    let th = bin / b.per;
                    (b.of(th), end.min(r - bin + (th + 1) * b.per))
                }
            };
            let (mean, out) = (&store.mean()[r..], &mut out[r - r0..run_end - r0]);
            match store.z() {
                Rows::F32(z) => dot::rows(w, &z[r * n..], mean, out),
                Rows::F64(z) => dot::rows(w, &z[r * n..], mean, out),
            }
            r = run_end;
        }
    }

    /// Reflectance of `channel` at `bin`, clamped to `>= 0`; `None` where no
    /// input material was measured. Remembered after the first call.
    #[inline]
    pub fn value(&self, channel: usize, bin: usize) -> Option<f64> {
        let bins = self.model.dims().bins();
        let row = channel * bins + bin;
        let memo = self
            .memo
            .get_or_init(|| bytemuck::zeroed_slice_box(3 * bins));
        if let Some(v) = Memo::decode(memo[row].load(Ordering::Relaxed)) {
            return v;
        }
        let v = self.compute(row, bins);
        memo[row].store(Memo::encode(v), Ordering::Relaxed);
        v
    }

    /// [`Blend::value`] of store row `row` without the memo.
    fn compute(&self, row: usize, bins: usize) -> Option<f64> {
        if self.model.store().unmeasured()[row] != 0 {
            return None;
        }
        let mut out = [0.0];
        self.model
            .transform()
            .inverse_run(row % bins, &[self.transformed(row)], &mut out);
        Some(out[0])
    }

    /// RGB reflectance at `bin`; `None` where some channel was never measured.
    pub fn rgb(&self, bin: usize) -> Option<[f64; 3]> {
        Some([
            self.value(0, bin)?,
            self.value(1, bin)?,
            self.value(2, bin)?,
        ])
    }

    /// [`Blend::rgb`] without the memo, for a one-off sweep over bins that
    /// nothing asks for again (the albedo of a blend under test): the same
    /// bits, without touching a fresh memo's pages.
    pub(crate) fn rgb_once(&self, bin: usize) -> Option<[f64; 3]> {
        let bins = self.model.dims().bins();
        Some([
            self.compute(bin, bins)?,
            self.compute(bins + bin, bins)?,
            self.compute(2 * bins + bin, bins)?,
        ])
    }

    /// RGB reflectance for a pair of directions (nearest bin, as MERL's own
    /// lookup); `None` below the horizon or where unmeasured.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Option<[f64; 3]> {
        self.rgb(self.model.dims().bin_of_directions(wi, wo)?)
    }

    /// [`Blend::eval`] for many direction pairs, in parallel (fixed chunks;
    /// the answers do not depend on the thread count).
    pub fn eval_batch(&self, pairs: &[(Vec3, Vec3)]) -> Vec<Option<[f64; 3]>> {
        pairs
            .par_iter()
            .with_min_len(1024)
            .map(|(wi, wo)| self.eval(*wi, *wo))
            .collect()
    }

    /// The whole table in MERL raw units: one parallel pass over the store.
    /// [`CoreError::FileChanged`](crate::CoreError::FileChanged) if the
    /// store changed on disk since the model was opened.
    pub fn table(&self) -> Result<MerlTable> {
        Ok(self.table_with(|_, _| ())?.0)
    }

    /// [`Blend::table`], handing each chunk of transformed values (its
    /// first row and the values, before the inverse transform and the
    /// clamp) to `each` on the way: what it returns, in chunk order. For
    /// figures of the same material that would otherwise take a pass over
    /// the store of their own ([`Blend::table_and_plausibility`]).
    pub(crate) fn table_with<T: Send>(
        &self,
        each: impl Fn(usize, &[f64]) -> T + Sync,
    ) -> Result<(MerlTable, Vec<T>)> {
        self.model.store().verify_cheap()?;
        let dims = self.model.dims();
        let bins = dims.bins();
        let store = self.model.store();
        let unmeasured = store.unmeasured();
        let mut values = vec![0.0f64; dims.values()];
        let seen: Vec<T> = values
            .par_chunks_mut(TABLE_CHUNK)
            .enumerate()
            .map_init(
                || vec![0.0f64; TABLE_CHUNK],
                |t, (k, out)| {
                    let r0 = k * TABLE_CHUNK;
                    let t = &mut t[..out.len()];
                    self.transformed_rows(r0, t);
                    let seen = each(r0, t);
                    // Split the chunk where it crosses from one channel to the next.
                    let mut j = 0;
                    while j < out.len() {
                        let (c, bin0) = ((r0 + j) / bins, (r0 + j) % bins);
                        let len = (out.len() - j).min(bins - bin0);
                        let run = &mut out[j..j + len];
                        self.model
                            .transform()
                            .inverse_run(bin0, &t[j..j + len], run);
                        for (o, &u) in run.iter_mut().zip(&unmeasured[r0 + j..r0 + j + len]) {
                            *o = if u != 0 {
                                INVALID
                            } else {
                                raw_from_physical(c, *o)
                            };
                        }
                        j += len;
                    }
                    seen
                },
            )
            .collect();
        self.model.verify()?;
        let table = MerlTable::from_raw(dims, values).expect("length matches dims");
        Ok((table, seen))
    }
}

/// The largest centred value of store row `row` over the materials (the
/// soft floor's cap less the mean, [`floor_capped`]).
fn row_top(store: &crate::data::Store, row: usize) -> f64 {
    let n = store.n();
    match store.z() {
        Rows::F32(z) => crate::model::blend::soft_floor::top_of(&z[row * n..(row + 1) * n]),
        Rows::F64(z) => crate::model::blend::soft_floor::top_of(&z[row * n..(row + 1) * n]),
    }
}
