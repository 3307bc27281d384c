//! The last few values of one kind a model computed for its maps (albedo
//! fields, per-pixel rules), kept for the next map: a short list, oldest
//! first. The values' types belong to the query modules, so the list holds
//! them as `Any` and the model does not name them.

use std::any::Any;
use std::sync::{Arc, Mutex, MutexGuard};

/// A short list of recently computed values, oldest first.
#[derive(Default)]
pub(crate) struct Recent {
    items: Mutex<Vec<Arc<dyn Any + Send + Sync>>>,
}

impl Recent {
    /// The oldest kept `T` for which `wanted` holds.
    pub(crate) fn find<T: Any + Send + Sync>(&self, wanted: impl Fn(&T) -> bool) -> Option<Arc<T>> {
        first(&self.lock(), &wanted)
    }

    /// Keep `item`, unless a `T` for which `wanted` holds was kept meanwhile
    /// (by another thread): first drop the kept `T`s that `item` replaces,
    /// then the oldest values while `cap` or more are kept.
    pub(crate) fn keep<T: Any + Send + Sync>(
        &self,
        item: Arc<T>,
        cap: usize,
        wanted: impl Fn(&T) -> bool,
        replaces: impl Fn(&T) -> bool,
    ) {
        let mut items = self.lock();
        if first(&items, &wanted).is_some() {
            return;
        }
        items.retain(|v| v.clone().downcast::<T>().map_or(true, |v| !replaces(&v)));
        while !items.is_empty() && items.len() >= cap {
            items.remove(0);
        }
        items.push(item);
    }

    /// The list, whatever a panicking holder left (each value is whole:
    /// values are only added or removed, never changed).
    fn lock(&self) -> MutexGuard<'_, Vec<Arc<dyn Any + Send + Sync>>> {
        self.items.lock().unwrap_or_else(|e| e.into_inner())
    }
}

fn first<T: Any + Send + Sync>(
    items: &[Arc<dyn Any + Send + Sync>],
    wanted: &impl Fn(&T) -> bool,
) -> Option<Arc<T>> {
    items
        .iter()
        .filter_map(|v| v.clone().downcast::<T>().ok())
        .find(|v| wanted(v))
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
        assert!(recent.find(|&v: &u32| v < 2).is_none());
        assert_eq!(*recent.find(|&v: &u32| v >= 2).unwrap(), 2);
        // Already kept: not kept twice.
        recent.keep(Arc::new(3u32), 3, |&v| v == 3, |_| false);
        assert_eq!(recent.lock().len(), 3);
        // A value of another type is found only by its own type.
        recent.keep(Arc::new("field"), 3, |_| false, |_| false);
        assert!(recent.find(|_: &&str| true).is_some());
        assert!(recent.find(|&v: &u32| v == 2).is_none(), "the oldest went");
        // Replacing drops what it replaces before the capacity counts.
        recent.keep(Arc::new(9u32), 3, |&v| v == 9, |&v| v == 3);
        assert!(recent.find(|&v: &u32| v == 3).is_none());
        assert!(recent.find(|&v: &u32| v == 4).is_some());
        assert!(recent.find(|&v: &u32| v == 9).is_some());
    }
}
