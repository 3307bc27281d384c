//! The ordered block fold: parallel passes over many rows whose sums do not
//! depend on the thread count.
//!
//! The rows are cut into blocks, the blocks into at most a fixed number of
//! groups of consecutive blocks; each group runs on one thread with its own
//! state and goes through its blocks in order, and the caller folds the
//! groups' states in group order. However rayon schedules the groups, every
//! sum is formed in the same order, so the result has the same bits.

use std::cell::RefCell;
use std::ops::Range;
use std::thread::LocalKey;

use rayon::prelude::*;

/// `f` with the thread's scratch buffers in `slot`, taken out of the slot
/// while `f` runs and put back after. A pass's step that runs a parallel
/// product may let its thread pick up another step of the same pass
/// meanwhile; that step then finds the slot empty and works in buffers of
/// its own, where borrowing the slot for the whole step would panic.
pub(crate) fn with_scratch<T: Default, R>(
    slot: &'static LocalKey<RefCell<T>>,
    f: impl FnOnce(&mut T) -> R,
) -> R {
    let mut scratch = slot.with_borrow_mut(std::mem::take);
    let out = f(&mut scratch);
    slot.with_borrow_mut(|s| *s = scratch);
    out
}

/// The number of groups a pass is split into when the caller does not ask
/// for one per block: enough to keep any core count busy, few enough that
/// the per-group states (an `N x N` matrix for the Gram pass) stay small.
pub const GROUPS: usize = 64;

/// Run `step(&mut state, rows)` over the blocks of `block` rows that cover
/// `0..rows`, in parallel over at most `groups` fixed groups of consecutive
/// blocks, each with its own `init()` state; return the states in group
/// order, for the caller to fold in that order.
pub fn ordered_blocks<S: Send>(
    rows: usize,
    block: usize,
    groups: usize,
    init: impl Fn() -> S + Sync,
    step: impl Fn(&mut S, Range<usize>) + Sync,
) -> Vec<S> {
    ordered_blocks_then(rows, block, groups, init, step, |s| s)
}

/// [`ordered_blocks`], each group's state turned into `finish(state)` as
/// soon as the group is done: what the caller folds is all that stays,
/// the group's buffers are freed then.
pub fn ordered_blocks_then<S, T: Send>(
    rows: usize,
    block: usize,
    groups: usize,
    init: impl Fn() -> S + Sync,
    step: impl Fn(&mut S, Range<usize>) + Sync,
    finish: impl Fn(S) -> T + Sync,
) -> Vec<T> {
    let block = block.max(1);
    let blocks = rows.div_ceil(block);
    let groups = groups.min(blocks).max(1);
    (0..groups)
        .into_par_iter()
        .map(|g| {
            let mut state = init();
            for b in (g * blocks / groups)..((g + 1) * blocks / groups) {
                step(&mut state, b * block..((b + 1) * block).min(rows));
            }
            finish(state)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_row_is_visited_once_in_order_whatever_the_grouping() {
        for (rows, block, groups) in [(0, 4, 8), (1, 4, 8), (10, 3, 2), (100, 7, 64), (64, 1, 5)] {
            let states = ordered_blocks(rows, block, groups, Vec::new, |s, r| s.push(r));
            let flat: Vec<Range<usize>> = states.into_iter().flatten().collect();
            let mut next = 0;
            for r in &flat {
                assert_eq!(r.start, next, "{rows} {block} {groups}");
                assert!(r.end > r.start && r.end - r.start <= block);
                next = r.end;
            }
            assert_eq!(next, rows);
        }
    }

    #[test]
    fn sums_do_not_depend_on_the_thread_count() {
        let values: Vec<f64> = (0..100_000)
            .map(|i| 1.0 / (1.0 + i as f64).sqrt())
            .collect();
        let sum = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                ordered_blocks(
                    values.len(),
                    1000,
                    GROUPS,
                    || 0.0,
                    |s, r| *s += values[r].iter().sum::<f64>(),
                )
                .into_iter()
                .sum::<f64>()
            })
        };
        let one = sum(1);
        assert_eq!(one.to_bits(), sum(2).to_bits());
        assert_eq!(one.to_bits(), sum(3).to_bits());
    }
}
