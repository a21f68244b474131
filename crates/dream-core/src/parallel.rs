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

/// The pieces one after the other in one vector, or [`crate::GeomError::OutOfMemory`] (naming
/// `what`). A large result is filled and copied on every core: at a million robots the
/// perceived rows are hundreds of megabytes, and one thread copying them (faulting each fresh
/// page in) was the step's longest serial part.
///
/// # Errors
/// [`crate::GeomError::OutOfMemory`] when the result cannot be allocated.
pub fn concat<T: Copy + Default + Send + Sync>(pieces: &[&[T]], what: &'static str) -> Result<Vec<T>> {
    let total: usize = pieces.iter().map(|piece| piece.len()).sum();
    let mut out = Vec::new();
    try_room(&mut out, total, what)?;
    if total < PARALLEL_ITEMS {
        pieces.iter().for_each(|piece| out.extend_from_slice(piece));
        return Ok(out);
    }
    out.par_extend((0..total).into_par_iter().map(|_| T::default()));
    let mut jobs = Vec::with_capacity(pieces.len());
    let mut rest = &mut out[..];
    for piece in pieces {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(piece.len());
        jobs.push((head, *piece));
        rest = tail;
    }
    jobs.into_par_iter()
        .for_each(|(head, piece)| head.copy_from_slice(piece));
    Ok(out)
}
