//! The incremental cost against dense recomputations.

use super::*;
use crate::gplvm::likelihood::cost;
use brdf_merl::synth::SplitMix64;

fn problem(n: usize, d: usize, seed: u64) -> (GramData, Mat<f64>) {
    let mut rng = SplitMix64::new(seed);
    let z = Mat::<f64>::from_fn(n, d, |_, _| rng.range(-1.0, 1.0));
    let x = Mat::<f64>::from_fn(n, 2, |_, _| rng.range(-1.0, 1.0));
    (GramData::new(&z * z.transpose(), d).unwrap(), x)
}

#[test]
fn one_trial_matches_dense_recomputation() {
    let (data, x) = problem(12, 200, 4);
    let kernel = Kernel::default();
    let mut s = IncrementalCost::new(kernel, &data, x.as_ref(), 1000).unwrap();
    let base = cost(&kernel, &data, x.as_ref()).unwrap();
    assert!((s.cost() - base).abs() <= 1e-12 * base.abs());
    let to = [0.3, -0.8];
    let t = s.trial(5, &to);
    let mut x2 = x.clone();
    x2[(5, 0)] = to[0];
    x2[(5, 1)] = to[1];
    let want = cost(&kernel, &data, x2.as_ref()).unwrap();
    assert!(
        (base + t.delta - want).abs() <= 1e-9 * want.abs(),
        "{} vs {want}",
        base + t.delta
    );
    s.accept(t).unwrap();
    assert!((s.cost() - want).abs() <= 1e-9 * want.abs());
    let fresh = crate::gplvm::likelihood::factor(kernel.matrix(x2.as_ref()).as_ref(), "t")
        .unwrap()
        .1;
    let err = (&s.inverse() - &fresh).norm_max() / fresh.norm_max();
    assert!(err < 1e-9, "{err}");
}

/// The acceptance test of the fit issue: 10^5 random accepted moves, then
/// the incremental cost equals a dense recomputation to 1e-9 relative.
#[test]
fn cost_survives_a_hundred_thousand_moves() {
    let (data, x) = problem(40, 300, 9);
    let kernel = Kernel::default();
    let mut s = IncrementalCost::new(kernel, &data, x.as_ref(), 64).unwrap();
    let mut rng = SplitMix64::new(1);
    for k in 0..100_000 {
        let i = (rng.next_u64() % 40) as usize;
        let to = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let t = s.trial(i, &to);
        assert!(t.delta.is_finite());
        s.accept(t).unwrap();
        if k % 4999 == 0 {
            let want = cost(&kernel, &data, s.latent().as_ref()).unwrap();
            assert!(
                (s.cost() - want).abs() <= 1e-9 * want.abs(),
                "move {k}: {} vs {want}",
                s.cost()
            );
        }
    }
    let want = cost(&kernel, &data, s.latent().as_ref()).unwrap();
    assert!(
        (s.cost() - want).abs() <= 1e-9 * want.abs(),
        "{} vs {want}",
        s.cost()
    );
    let st = s.stats();
    assert_eq!(st.updates + st.dense_fallbacks, 100_000);
    assert!(st.refreshes > 1000, "{st:?}");
}

/// Trials that are not applied, several in a row on the same point (where
/// `Y K^-1 e_i` is reused) and on others, each against a dense
/// recomputation; `K^-1` stays exactly symmetric through the updates.
#[test]
fn rejected_and_repeated_trials_match_dense_recomputation() {
    let (data, x) = problem(30, 200, 5);
    let kernel = Kernel::default();
    let mut s = IncrementalCost::new(kernel, &data, x.as_ref(), 64).unwrap();
    let mut rng = SplitMix64::new(3);
    let mut reused = 0;
    for k in 0..3000 {
        let i = (rng.next_u64() % 3) as usize;
        reused += usize::from(s.ym_of == Some(i));
        let mut to = s.point(i).to_vec();
        let c = (rng.next_u64() % 2) as usize;
        to[c] = (to[c] + rng.range(-0.3, 0.3)).clamp(-1.0, 1.0);
        let t = s.trial(i, &to);
        let mut x2 = s.latent();
        x2[(i, 0)] = to[0];
        x2[(i, 1)] = to[1];
        // The change of the cost against a dense one (the state's own
        // drift is the 10^5-move test's subject).
        let want = cost(&kernel, &data, x2.as_ref()).unwrap()
            - cost(&kernel, &data, s.latent().as_ref()).unwrap();
        assert!(
            (t.delta - want).abs() <= 1e-9 * s.cost().abs(),
            "trial {k}: {} vs {want}",
            t.delta
        );
        if rng.next_u64().is_multiple_of(3) {
            s.accept(t).unwrap();
            let m = s.inverse();
            assert!((0..30).all(|r| (0..30).all(|c| m[(r, c)] == m[(c, r)])));
        }
    }
    assert!(reused > 400, "{reused}");
}

#[test]
fn colliding_points_and_tiny_noise_stay_finite() {
    let (data, _) = problem(6, 50, 2);
    for noise in [1e-4, 1e-10] {
        let kernel = Kernel {
            length_scale: 1.0,
            noise,
        };
        let x = Mat::<f64>::from_fn(6, 2, |i, _| if i < 3 { 0.25 } else { -0.5 });
        let mut s = IncrementalCost::new(kernel, &data, x.as_ref(), 64).unwrap();
        assert!(s.cost().is_finite());
        // Move a point onto another: K keeps positive definite only through mu.
        let t = s.trial(0, &[-0.5, -0.5]);
        assert!(t.delta.is_finite() || t.delta == f64::INFINITY);
        if t.delta.is_finite() {
            s.accept(t).unwrap();
            assert!(s.cost().is_finite());
            let want = cost(&kernel, &data, s.latent().as_ref()).unwrap();
            assert!(
                (s.cost() - want).abs() <= 1e-6 * want.abs(),
                "{noise}: {} vs {want}",
                s.cost()
            );
        }
    }
}

/// A pair of trials gives the bits of two single trials (at a size where
/// `K^-1` and `Y` fit in a core's cache and one where they do not on
/// most), and accepting either
/// of the pair leaves the state a single trial would.
#[test]
fn a_pair_of_trials_is_two_single_trials() {
    for n in [9, 600] {
        let (data, x) = problem(n, 400, 8);
        let kernel = Kernel::default();
        let mut pairs = IncrementalCost::new(kernel, &data, x.as_ref(), 64).unwrap();
        let mut singles = IncrementalCost::new(kernel, &data, x.as_ref(), 64).unwrap();
        let mut rng = SplitMix64::new(11);
        for k in 0..200 {
            let i = (rng.next_u64() % n as u64) as usize;
            let step = rng.range(0.001, 0.3);
            let (mut plus, mut minus) = (pairs.point(i).to_vec(), pairs.point(i).to_vec());
            plus[k % 2] += step;
            minus[k % 2] -= step;
            let pair = pairs.trial_pair(i, [&plus, &minus]);
            let second = singles.trial(i, &minus);
            let first = singles.trial(i, &plus);
            assert_eq!(
                pair[0].delta.to_bits(),
                first.delta.to_bits(),
                "n {n}, trial {k}"
            );
            assert_eq!(
                pair[1].delta.to_bits(),
                second.delta.to_bits(),
                "n {n}, trial {k}"
            );
            // Accept one of the pair (alternately) and the same single trial.
            let (chosen, to) = if k % 3 == 0 {
                (pair[1], &minus)
            } else {
                (pair[0], &plus)
            };
            pairs.accept(chosen).unwrap();
            let again = singles.trial(i, to);
            singles.accept(again).unwrap();
            assert_eq!(
                pairs.cost().to_bits(),
                singles.cost().to_bits(),
                "n {n}, trial {k}"
            );
        }
        assert_eq!(pairs.inverse(), singles.inverse(), "n {n}");
        let want = cost(&kernel, &data, pairs.latent().as_ref()).unwrap();
        assert!((pairs.cost() - want).abs() <= 1e-9 * want.abs());
    }
}
