//! The one way the kernels spread independent work over threads.

use rayon::prelude::*;

use crate::error::{try_filled, try_room, Result};

/// Serial work, in nanoseconds, from which a loop is spread over the threads. Between kernel
/// calls rayon's threads sleep, and waking them costs tens of microseconds: on a 2-core VM
/// (`cargo run --release -p dream-core --example wake`), checking 65,536 values took 18 µs on the
/// calling thread and 72 µs on the pool, 262,144 values 70 and 122 µs, a million 275 and 238 µs.
/// Work shorter than a fifth of a millisecond is done sooner by the calling thread alone.
const PARALLEL_WORK_NS: f64 = 200_000.0;

/// Whether `n` items of about `ns` nanoseconds each are worth spreading over the threads. `ns`
/// is a rough figure: a quarter for a check the compiler vectorises, 1 for a copy, 3 for a
/// division and a rounding, 10 for a square root or a `hypot`, 20 for a sine and a cosine.
pub(crate) fn worth_spreading(n: usize, ns: f64) -> bool {
    n as f64 * ns >= PARALLEL_WORK_NS
}

/// Items one task takes at least, where a loop is spread over the threads.
pub(crate) const TASK_ITEMS: usize = 1024;

/// `values` cut into consecutive pieces at `bounds` (piece k is `bounds[k]..bounds[k + 1]`): each
/// task its own stretch to write.
pub(crate) fn split<'a, T>(mut values: &'a mut [T], bounds: &[usize]) -> Vec<&'a mut [T]> {
    let mut pieces = Vec::with_capacity(bounds.len().saturating_sub(1));
    for bound in bounds.windows(2) {
        let (head, tail) = std::mem::take(&mut values).split_at_mut(bound[1] - bound[0]);
        pieces.push(head);
        values = tail;
    }
    pieces
}

/// `value(i)` for every `i < n`, in order, each taking about `ns` nanoseconds (see
/// [`worth_spreading`]): on every thread for much work.
pub fn map_range<T: Send>(n: usize, ns: f64, value: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    if worth_spreading(n, ns) {
        (0..n).into_par_iter().with_min_len(TASK_ITEMS).map(value).collect()
    } else {
        (0..n).map(value).collect()
    }
}

/// Items one task of [`first_where`] checks.
const CHECK_ITEMS: usize = 8192;

/// The first of items `0..n` that `bad` holds for, if any: the check of a kernel's input (an index out of
/// bounds, a NaN). Whether any does is found first, without a branch an item (a loop the compiler
/// can vectorise), in chunks on every core for many; the first is then looked for only if one
/// does. (Rayon's `position_first` and `any` check a shared flag at every item: on 65,000
/// message indices that took 4-6 times as long as the reduction they guarded.)
pub(crate) fn first_where(n: usize, bad: impl Fn(usize) -> bool + Sync) -> Option<usize> {
    let any_bad = |items: std::ops::Range<usize>| items.fold(false, |found, i| found | bad(i));
    let found = if worth_spreading(n, 0.25) {
        (0..n.div_ceil(CHECK_ITEMS))
            .into_par_iter()
            .any(|chunk| any_bad(chunk * CHECK_ITEMS..n.min((chunk + 1) * CHECK_ITEMS)))
    } else {
        any_bad(0..n)
    };
    if found {
        (0..n).position(bad)
    } else {
        None
    }
}

/// Rows whose entries one task of [`gather_rows`] copies.
const GATHER_ROWS: usize = 4096;

/// Entries from which [`gather_rows`] fills and copies on every core (at 100,000 entries the
/// parallel copy measured 10-17 % slower, at 1,000,000 it is 1.14-1.31x faster).
const PARALLEL_GATHER: usize = 400_000;

/// `(a(), b())`, side by side on the threads when `spread`.
pub(crate) fn join_if<RA: Send, RB: Send>(
    spread: bool,
    a: impl FnOnce() -> RA + Send,
    b: impl FnOnce() -> RB + Send,
) -> (RA, RB) {
    if spread {
        rayon::join(a, b)
    } else {
        (a(), b())
    }
}

/// `len` copies of `value`, written on every core where there are many: a large output is fresh
/// memory, and writing it first faults its pages in, which one thread does at a fraction of the
/// speed of all (hundreds of megabytes for a million robots' perception).
///
/// # Errors
/// [`crate::GeomError::OutOfMemory`] (naming `what`) when it cannot be allocated.
pub(crate) fn try_filled_on_every_core<T: Copy + Send + Sync>(
    len: usize,
    value: T,
    what: &'static str,
) -> Result<Vec<T>> {
    if !worth_spreading(len, 1.0) {
        return try_filled(len, value, what);
    }
    let mut out = Vec::new();
    try_room(&mut out, len, what)?;
    out.par_extend((0..len).into_par_iter().with_min_len(TASK_ITEMS).map(|_| value));
    Ok(out)
}

/// Ragged rows put in order, one column at a time: row r's `offsets[r + 1] - offsets[r]`
/// entries come from `from(r)`, a slice and where the row's entries start in it (the rows of
/// a parallel search, each found by some task in some order). At a million robots the result is
/// hundreds of megabytes, each fresh page faulted in: filled and copied on every core. Fewer
/// entries are appended on the calling thread, each written once.
///
/// # Errors
/// [`crate::GeomError::OutOfMemory`] (naming `what`) when the result cannot be allocated.
pub(crate) fn gather_rows<'a, T: Copy + Default + Send + Sync + 'a>(
    offsets: &[i64],
    from: impl Fn(usize) -> (&'a [T], usize) + Sync,
    what: &'static str,
) -> Result<Vec<T>> {
    let rows = offsets.len() - 1;
    let total = offsets[rows] as usize;
    let row = |r: usize| {
        let (column, start) = from(r);
        &column[start..start + (offsets[r + 1] - offsets[r]) as usize]
    };
    if total < PARALLEL_GATHER {
        let mut out = Vec::new();
        try_room(&mut out, total, what)?;
        for r in 0..rows {
            out.extend_from_slice(row(r));
        }
        return Ok(out);
    }
    let mut out = try_filled_on_every_core(total, T::default(), what)?;
    let mut tasks = Vec::with_capacity(rows / GATHER_ROWS + 1);
    let mut rest = &mut out[..];
    for first in (0..rows).step_by(GATHER_ROWS) {
        let last = (first + GATHER_ROWS).min(rows);
        let (head, tail) = std::mem::take(&mut rest).split_at_mut((offsets[last] - offsets[first]) as usize);
        tasks.push((first..last, head));
        rest = tail;
    }
    tasks.into_par_iter().for_each(|(range, head)| {
        let mut at = 0;
        for r in range {
            let entries = row(r);
            head[at..at + entries.len()].copy_from_slice(entries);
            at += entries.len();
        }
    });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_bad_item_whatever_the_count() {
        for n in [0, 1, 100, 1 << 20, (1 << 20) + 3 * CHECK_ITEMS + 7] {
            assert_eq!(first_where(n, |_| false), None);
            for bad in [0, n / 2, n.saturating_sub(1)] {
                if bad < n {
                    assert_eq!(first_where(n, |i| i >= bad), Some(bad), "{n} items, bad from {bad}");
                }
            }
        }
    }
}
