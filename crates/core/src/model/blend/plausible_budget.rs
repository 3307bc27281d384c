//! The step of [`crate::BlendRule::Plausible`].
//!
//! A blend's weights `w` (the GP's) are moved towards the kernel's convex
//! weights `v` (a kernel-weighted average of the materials, plausible by
//! construction): `(1 - t) w + t v`, with the smallest `t` of [`STEPS`] for
//! which the reflectance the clamp removes is at most [`CLAMP_BUDGET`] of
//! the blend's cosine-weighted reflectance. Both blends are linear in the
//! weights before the inverse transform, so one pass over the store gives
//! the reflectance and its clamped part at every step: per row, the GP value
//! `g`, the convex value `c`, and `g + t (c - g)` for each `t`.

use crate::data::store::Store;
use crate::data::transform::{InverseForm, Transform};
use crate::model::Model;
use crate::simd::fastexp;

/// The steps tried, smallest first: the rule takes the first that meets the budget.
pub const STEPS: [f64; 13] = [
    0.0,
    1.0 / 64.0,
    1.0 / 32.0,
    1.0 / 16.0,
    1.0 / 8.0,
    3.0 / 16.0,
    1.0 / 4.0,
    3.0 / 8.0,
    1.0 / 2.0,
    5.0 / 8.0,
    3.0 / 4.0,
    7.0 / 8.0,
    1.0,
];

/// The reflectance `f(g + t (c - g))` of a row at each of [`STEPS`], from its
/// GP value `g` and convex value `c` (transformed space) and its inverse
/// transform. Under `e^t - 1` the thirteen exponentials are two, `e^g` and
/// `r = e^((c - g) / 64)`, and powers of `r` by products (each step a whole
/// number of 64ths): within a few ulps of the direct exponentials, which is
/// far below any budget. `e^t - 1` cancels near `t = 0` to an absolute error
/// of about 1e-16 s either way.
#[inline]
pub(crate) fn step_values(g: f64, c: f64, form: InverseForm) -> [f64; 13] {
    let mut v = [0.0; 13];
    match form {
        InverseForm::Linear(s) => {
            for (v, t) in v.iter_mut().zip(STEPS) {
                *v = s * (g + t * (c - g));
            }
        }
        InverseForm::Exp(s) => {
            let (base, r) = (fastexp::exp(g), fastexp::exp((c - g) / 64.0));
            // Powers by squaring: at most six products deep.
            let r2 = r * r;
            let r4 = r2 * r2;
            let r8 = r4 * r4;
            let r16 = r8 * r8;
            let r32 = r16 * r16;
            let r48 = r32 * r16;
            let pows = [
                1.0,
                r,
                r2,
                r4,
                r8,
                r8 * r4,
                r16,
                r16 * r8,
                r32,
                r32 * r8,
                r48,
                r48 * r8,
                r32 * r32,
            ];
            for (v, p) in v.iter_mut().zip(pows) {
                *v = s * (base * p - 1.0);
            }
        }
    }
    v
}

/// The length scale of the convex blend the rule steps towards, as a
/// share of the GP kernel's: 0.3, the best of 1, 0.3, 0.15 and 0.08 for the
/// rule's leave-one-out error on the 100 NBRDF-derived materials
/// (docs/plausibility.md).
pub const CONVEX_LENGTH_RATIO: f64 = 0.3;

/// The convex weights at `x`: `exp(-|x - x_i|^2 / (2 l^2)) / |x - x_i|^2`,
/// normalised, with `l` the kernel's length scale times
/// [`CONVEX_LENGTH_RATIO`], computed relative to the nearest material so
/// they never underflow (far from the data they tend to the nearest
/// material alone). The inverse square distance (Shepard's) makes the blend
/// interpolate: at a material's own point it is that material alone, so a
/// rule that lies on the convex blend there gives the material back. A
/// point within [`SAME_POINT`] of materials gives them equal weights, all
/// others none. Material `skip` (if any) gets weight 0, as in
/// leave-one-out.
pub(crate) fn convex_weights(
    latent: &[Vec<f64>],
    x: &[f64],
    length_scale: f64,
    skip: Option<usize>,
) -> Vec<f64> {
    let l = length_scale * CONVEX_LENGTH_RATIO;
    let d2: Vec<f64> = latent
        .iter()
        .enumerate()
        .map(|(i, xi)| {
            if Some(i) == skip {
                f64::INFINITY
            } else {
                xi.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum()
            }
        })
        .collect();
    let nearest = d2.iter().copied().fold(f64::INFINITY, f64::min);
    let same = (SAME_POINT * l).powi(2);
    let k: Vec<f64> = if nearest <= same {
        d2.iter().map(|&d| f64::from(u8::from(d <= same))).collect()
    } else {
        d2.iter()
            .map(|&d| (-(d - nearest) / (2.0 * l * l)).exp() * (nearest / d))
            .collect()
    };
    let sum: f64 = k.iter().sum();
    k.iter().map(|v| v / sum).collect()
}

/// Within this share of the convex length scale a point is a material's
/// own (see [`convex_weights`]): far below any distance the fit leaves
/// between distinct materials, far above rounding.
pub(crate) const SAME_POINT: f64 = 1e-9;

/// The convex weights ([`convex_weights`]) at each of `points`, with the
/// model's latent points and length scale: what the plausible rule steps
/// towards and the soft floor lies under.
pub(crate) fn convex_weights_at<P: AsRef<[f64]>>(model: &Model, points: &[P]) -> Vec<Vec<f64>> {
    let latent = crate::gplvm::kernel::rows_of(model.latent().as_ref());
    let l = model.file().kernel.length_scale;
    points
        .iter()
        .map(|x| convex_weights(&latent, x.as_ref(), l, None))
        .collect()
}

/// The share of a blend's cosine-weighted reflectance that the clamp may
/// remove before the weights are moved: 0.05%.
pub const CLAMP_BUDGET: f64 = 5e-4;

/// Per band of the table, predicted material and each of [`STEPS`]: the
/// cosine-weighted reflectance of the blend (absolute values) and the part
/// the clamp removes. One band is the whole table.
#[derive(Clone)]
pub(crate) struct Budget {
    n: usize,
    total: Vec<[f64; STEPS.len()]>,
    clamped: Vec<[f64; STEPS.len()]>,
}

impl Budget {
    /// `n` materials in `bands` bands.
    pub(crate) fn new(n: usize, bands: usize) -> Budget {
        Budget {
            n,
            total: vec![[0.0; STEPS.len()]; n * bands],
            clamped: vec![[0.0; STEPS.len()]; n * bands],
        }
    }

    /// Add one row of band `band`: `g[i]`, `c[i]` are the GP and convex
    /// values of material `i` in transformed space (mean included), `form`
    /// the row's inverse transform, `cos` its `cos_i cos_o`.
    #[inline]
    pub(crate) fn add(&mut self, band: usize, g: &[f64], c: &[f64], form: InverseForm, cos: f64) {
        let (total, clamped) = (
            &mut self.total[band * self.n..(band + 1) * self.n],
            &mut self.clamped[band * self.n..(band + 1) * self.n],
        );
        for i in 0..g.len() {
            let v = step_values(g[i], c[i], form);
            for k in 0..STEPS.len() {
                total[i][k] += v[k].abs() * cos;
                clamped[i][k] += (-v[k]).max(0.0) * cos;
            }
        }
    }

    /// [`Budget::add`] at step 0 alone: `g[i]` the GP value of material
    /// `i` (the other steps' sums are left as they are).
    #[inline]
    pub(crate) fn add_at_zero(&mut self, band: usize, g: &[f64], form: InverseForm, cos: f64) {
        let (total, clamped) = (
            &mut self.total[band * self.n..(band + 1) * self.n],
            &mut self.clamped[band * self.n..(band + 1) * self.n],
        );
        for i in 0..g.len() {
            // `step_values(g, c, form)[0]`, bit for bit (`t = 0`, `r^0 = 1`).
            let v = match form {
                InverseForm::Linear(s) => s * g[i],
                InverseForm::Exp(s) => s * (fastexp::exp(g[i]) - 1.0),
            };
            total[i][0] += v.abs() * cos;
            clamped[i][0] += (-v).max(0.0) * cos;
        }
    }

    /// Whether material `i` of band `band` meets `budget` at step 0 (the
    /// test [`Budget::steps`] makes first).
    pub(crate) fn within_at_zero(&self, band: usize, i: usize, budget: f64) -> bool {
        let at = band * self.n + i;
        self.clamped[at][0] <= budget * self.total[at][0]
    }

    /// Fold another partial sum in (call in a fixed order).
    pub(crate) fn merge(&mut self, other: &Budget) {
        for i in 0..self.total.len() {
            for k in 0..STEPS.len() {
                self.total[i][k] += other.total[i][k];
                self.clamped[i][k] += other.clamped[i][k];
            }
        }
    }

    /// The step each material takes in each band under `budget` (a share
    /// of the band's reflectance), band by band.
    pub(crate) fn steps(&self, budget: f64) -> Vec<f64> {
        (0..self.total.len())
            .map(|i| {
                (0..STEPS.len())
                    .find(|&k| self.clamped[i][k] <= budget * self.total[i][k])
                    .map_or(1.0, |k| STEPS[k])
            })
            .collect()
    }
}

/// The inverse transform's form at `row`, or `None` where the row does not
/// count: unmeasured, or zeroed by the transform whatever its value.
#[inline]
pub(crate) fn counted(store: &Store, transform: &dyn Transform, row: usize) -> Option<InverseForm> {
    if store.unmeasured()[row] != 0 {
        return None;
    }
    match transform.inverse_form(row % store.dims().bins()) {
        InverseForm::Exp(s) | InverseForm::Linear(s) if s == 0.0 => None,
        form => Some(form),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_values_are_the_blend_at_every_step() {
        for (g, c) in [
            (0.3, -0.2),
            (-2.0, 4.5),
            (7.0, 0.0),
            (0.0, 0.0),
            (-1e-9, 1e-9),
            (1.2, 1.2),
        ] {
            for form in [InverseForm::Exp(0.8), InverseForm::Linear(1.7)] {
                let v = step_values(g, c, form);
                for (k, &t) in STEPS.iter().enumerate() {
                    let b: f64 = g + t * (c - g);
                    let want = match form {
                        InverseForm::Exp(s) => s * b.exp_m1(),
                        InverseForm::Linear(s) => s * b,
                    };
                    // Relative to e^b: `e^b - 1` cancels near b = 0.
                    let scale = b.exp().max(1.0);
                    assert!(
                        (v[k] - want).abs() <= 1e-13 * scale,
                        "{form:?} g {g} c {c} step {t}: {} vs {want}",
                        v[k]
                    );
                }
            }
        }
    }
}
