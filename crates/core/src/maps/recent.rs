//! The last few values of one kind an atlas computed for its maps (albedo
//! fields, per-pixel rules), kept for the next map: a short list, oldest
//! first.

use std::sync::{Arc, Mutex, MutexGuard};

/// A short list of recently computed values, oldest first.
pub(crate) struct Recent<T> {
    items: Mutex<Vec<Arc<T>>>,
}

impl<T> Default for Recent<T> {
    fn default() -> Recent<T> {
        Recent {
            items: Mutex::new(Vec::new()),
        }
    }
}

impl<T> Recent<T> {
    /// The oldest kept value for which `wanted` holds.
    pub(crate) fn find(&self, wanted: impl Fn(&T) -> bool) -> Option<Arc<T>> {
        self.lock().iter().find(|v| wanted(v)).cloned()
    }

    /// Every kept value, oldest first.
    pub(crate) fn all(&self) -> Vec<Arc<T>> {
        self.lock().clone()
    }

    /// Keep `item`, unless a value for which `wanted` holds was kept
    /// meanwhile (by another thread): first drop the kept values that `item`
    /// replaces, then the oldest values while `cap` or more are kept.
    pub(crate) fn keep(
        &self,
        item: Arc<T>,
        cap: usize,
        wanted: impl Fn(&T) -> bool,
        replaces: impl Fn(&T) -> bool,
    ) {
        let mut items = self.lock();
        if items.iter().any(|v| wanted(v)) {
            return;
        }
        items.retain(|v| !replaces(v));
        while !items.is_empty() && items.len() >= cap {
            items.remove(0);
        }
        items.push(item);
    }

    /// The list, whatever a panicking holder left (each value is whole:
    /// values are only added or removed, never changed).
    fn lock(&self) -> MutexGuard<'_, Vec<Arc<T>>> {
        self.items.lock().unwrap_or_else(|e| e.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_the_newest_few_and_replaces_as_asked() {
        let recent = Recent::default();
        for k in 0..5u32 {
            recent.keep(Arc::new(k), 3, |&v| v == k, |_| false);
        }
        // Capacity 3: 0 and 1 dropped, oldest first.
        assert!(recent.find(|&v| v < 2).is_none());
        assert_eq!(*recent.find(|&v| v >= 2).unwrap(), 2);
        // Already kept: not kept twice.
        recent.keep(Arc::new(3u32), 3, |&v| v == 3, |_| false);
        assert_eq!(recent.lock().len(), 3);
        // Replacing drops what it replaces before the capacity counts.
        recent.keep(Arc::new(9u32), 3, |&v| v == 9, |&v| v == 3);
        assert!(recent.find(|&v| v == 3).is_none());
        assert!(recent.find(|&v| v == 2).is_some());
        assert!(recent.find(|&v| v == 4).is_some());
        assert!(recent.find(|&v| v == 9).is_some());
    }
}
