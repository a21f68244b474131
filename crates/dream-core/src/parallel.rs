//! The one way the kernels spread independent work over threads.

use rayon::prelude::*;

use crate::error::{try_room, Result};

/// Items from which [`map_range`] runs on every thread (below, the thread pool costs more than
/// it saves: per-robot kernels are called with a handful of items, thousands of times a step).
pub(crate) const PARALLEL_ITEMS: usize = 4096;

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

/// Rows whose entries one task of [`gather_rows`] copies.
const GATHER_ROWS: usize = 4096;

/// Entries from which [`gather_rows`] fills and copies on every core (at 100,000 entries the
/// parallel copy measured 10-17 % slower, at 1,000,000 it is 1.14-1.31x faster).
const PARALLEL_GATHER: usize = 400_000;

/// Ragged rows put in order, one column at a time: row r's `offsets[r + 1] - offsets[r]`
/// entries come from `from(r)`, a slice and where the row's entries start in it (the rows of
/// a parallel search, each found by some task in some order). At a million robots the result is
/// hundreds of megabytes, each fresh page faulted in: filled and copied on every core.
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
    let mut out = Vec::new();
    try_room(&mut out, total, what)?;
    let parallel = total >= PARALLEL_GATHER;
    if parallel {
        out.par_extend(
            (0..total)
                .into_par_iter()
                .with_min_len(PARALLEL_ITEMS)
                .map(|_| T::default()),
        );
    } else {
        out.resize(total, T::default());
    }
    let mut tasks = Vec::with_capacity(rows / GATHER_ROWS + 1);
    let mut rest = &mut out[..];
    for first in (0..rows).step_by(GATHER_ROWS) {
        let last = (first + GATHER_ROWS).min(rows);
        let (head, tail) = std::mem::take(&mut rest).split_at_mut((offsets[last] - offsets[first]) as usize);
        tasks.push((first..last, head));
        rest = tail;
    }
    let copy = |(range, head): (std::ops::Range<usize>, &mut [T])| {
        let mut at = 0;
        for r in range {
            let length = (offsets[r + 1] - offsets[r]) as usize;
            let (column, start) = from(r);
            head[at..at + length].copy_from_slice(&column[start..start + length]);
            at += length;
        }
    };
    if parallel {
        tasks.into_par_iter().for_each(copy);
    } else {
        tasks.into_iter().for_each(copy);
    }
    Ok(out)
}
