//! The one way the kernels spread independent work over threads.

use rayon::prelude::*;

/// Items from which [`map_range`] runs on every thread (below, the thread pool costs more than
/// it saves: per-robot kernels are called with a handful of items, thousands of times a step).
const PARALLEL_ITEMS: usize = 4096;

/// `value(i)` for every `i < n`, in order: in parallel for many items.
pub fn map_range<T: Send>(n: usize, value: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    if n >= PARALLEL_ITEMS {
        (0..n)
            .into_par_iter()
            .with_min_len(PARALLEL_ITEMS / 4)
            .map(value)
            .collect()
    } else {
        (0..n).map(value).collect()
    }
}
