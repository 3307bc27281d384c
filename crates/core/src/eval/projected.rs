//! A candidate the plausible rule was compared with: the GP's weights
//! constrained rather than adapted. The least change (in the Euclidean
//! norm) to the GP's absolute weights that makes them non-negative with a
//! sum of at most one, the rest of the unit sum going to the mean. Every
//! transform's blend of valid materials with such weights is valid (a
//! convex blend), so nothing is ever clamped; the cost is accuracy, which
//! [`projected_predictor`] lets the leave-one-out pass measure.

use faer::{Mat, MatRef};

use crate::error::Result;

/// The point of `{u : u >= 0, sum u <= 1}` nearest to `w`: `max(w, 0)` when
/// its sum is at most one, else `max(w - theta, 0)` with the `theta >= 0`
/// that makes the sum one (the projection onto the simplex, by sorting).
pub fn capped_simplex(w: &[f64]) -> Vec<f64> {
    let positive: Vec<f64> = w.iter().map(|&v| v.max(0.0)).collect();
    if positive.iter().sum::<f64>() <= 1.0 {
        return positive;
    }
    let mut sorted = w.to_vec();
    sorted.sort_by(|a, b| b.total_cmp(a));
    let (mut sum, mut theta) = (0.0, 0.0);
    for (k, &v) in sorted.iter().enumerate() {
        sum += v;
        let t = (sum - 1.0) / (k + 1) as f64;
        if v > t {
            theta = t;
        }
    }
    w.iter().map(|&v| (v - theta).max(0.0)).collect()
}

/// The leave-one-out predictor of the GP's weights projected onto the
/// capped simplex, from the GP's leave-one-out predictor `gp` (see
/// [`super::loo::gp_predictor`], with the mean refitted): row `i`'s
/// absolute weights on the other materials, `a_ij = P_ij + (1 - sum_k
/// P_ik) / N` (the refitted mean's share spread over all, which leaves
/// `a_ii = 0`), are projected by [`capped_simplex`], and what they leave of
/// the unit sum goes to the others' mean. Rows sum to one with a zero
/// diagonal, so the centred and absolute forms agree.
pub fn projected_predictor(gp: MatRef<'_, f64>) -> Result<Mat<f64>> {
    let n = gp.nrows();
    super::predictors::needs_two(n)?;
    let mut p = Mat::<f64>::zeros(n, n);
    for i in 0..n {
        let share = (1.0 - (0..n).map(|j| gp[(i, j)]).sum::<f64>()) / n as f64;
        let others: Vec<usize> = (0..n).filter(|&j| j != i).collect();
        let a: Vec<f64> = others.iter().map(|&j| gp[(i, j)] + share).collect();
        let u = capped_simplex(&a);
        let rest = (1.0 - u.iter().sum::<f64>()).max(0.0) / (n - 1) as f64;
        for (&j, uj) in others.iter().zip(&u) {
            p[(i, j)] = uj + rest;
        }
    }
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdf_merl::synth::SplitMix64;

    /// The projection's optimality conditions, checked directly: feasible,
    /// and either `max(w, 0)` (when that is feasible) or `max(w - theta, 0)`
    /// summing to one for one `theta >= 0` shared by every kept weight,
    /// with every dropped weight at most `theta`.
    #[test]
    fn the_projection_meets_its_optimality_conditions() {
        let mut rng = SplitMix64::new(29);
        for case in 0..500 {
            let n = 1 + case % 40;
            let scale = [0.05, 0.5, 3.0][case % 3];
            let w: Vec<f64> = (0..n).map(|_| rng.range(-1.0, 1.0) * scale).collect();
            let u = capped_simplex(&w);
            assert!(u.iter().all(|&v| v >= 0.0));
            let sum: f64 = u.iter().sum();
            assert!(sum <= 1.0 + 1e-12, "{sum}");
            let positive: f64 = w.iter().map(|v| v.max(0.0)).sum();
            if positive <= 1.0 {
                assert!(u.iter().zip(&w).all(|(a, b)| *a == b.max(0.0)));
                continue;
            }
            assert!((sum - 1.0).abs() <= 1e-12, "{sum}");
            let (kept, dropped): (Vec<_>, Vec<_>) = u.iter().zip(&w).partition(|(a, _)| **a > 0.0);
            let theta = kept[0].1 - kept[0].0;
            assert!(theta >= -1e-12);
            for (a, b) in &kept {
                assert!((*b - *a - theta).abs() <= 1e-12);
            }
            for (_, b) in &dropped {
                assert!(**b <= theta + 1e-12);
            }
        }
    }

    /// The predictor's rows are convex weights on the other materials; where
    /// the GP's own absolute weights are already convex they are kept.
    #[test]
    fn rows_are_convex_weights_on_the_others() {
        // A GP predictor whose row 0 is convex and row 1 is not (absolute
        // weights: the refitted mean's share spread over all three).
        let gp = Mat::from_fn(3, 3, |i, j| match (i, j) {
            (0, 1) => 0.6,
            (0, 2) => 0.4,
            (1, 0) => 1.5,
            (1, 2) => -0.5,
            (2, 0) => 0.2,
            (2, 1) => 0.3,
            _ => 0.0,
        });
        let p = projected_predictor(gp.as_ref()).unwrap();
        for i in 0..3 {
            assert_eq!(p[(i, i)], 0.0);
            assert!((0..3).all(|j| p[(i, j)] >= 0.0));
            assert!(((0..3).map(|j| p[(i, j)]).sum::<f64>() - 1.0).abs() < 1e-15);
        }
        assert_eq!((p[(0, 1)], p[(0, 2)]), (0.6, 0.4));
        // Row 1: weights (1.5, -0.5) project to (1, 0).
        assert_eq!((p[(1, 0)], p[(1, 2)]), (1.0, 0.0));
        // Row 2: (0.2, 0.3) sum to 0.5; the rest goes to the others' mean.
        assert!((p[(2, 0)] - 0.45).abs() < 1e-15 && (p[(2, 1)] - 0.55).abs() < 1e-15);
    }
}
