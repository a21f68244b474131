//! Rows of per-robot tables copied out and back: the swarm engine's memory of the robots deciding
//! now, every field at once.
//!
//! A table is `n` rows of `width` bytes (a field of any type and shape, one row a robot). The
//! robots deciding are a scattered quarter or fifth of the swarm, so each row is a cache miss
//! or two: the copies of all the fields, spread over the cores, run as fast as memory serves them
//! (at 100,000 robots, a formation's 16 fields took 12 ms copied one after the other on one core).

use rayon::prelude::*;

use crate::csr::check_rows;
use crate::error::{try_filled, GeomError, Result};
use crate::parallel::worth_spreading;

/// Rows one task copies.
const TASK_ROWS: usize = 2048;

/// A table's rows: `bytes` of `bytes.len() / width` rows of `width` bytes each.
#[derive(Debug, Clone, Copy)]
pub struct Table<'a> {
    pub bytes: &'a [u8],
    pub width: usize,
}

/// A table whose rows are written (see [`Table`]).
#[derive(Debug)]
pub struct TableMut<'a> {
    pub bytes: &'a mut [u8],
    pub width: usize,
}

/// Fails unless every table holds `n` rows and `rows` are strictly increasing row indices below `n`.
fn check(widths_and_lengths: impl Iterator<Item = (usize, usize)>, n: usize, rows: &[i64]) -> Result<()> {
    for (t, (width, length)) in widths_and_lengths.enumerate() {
        if length != n * width {
            return Err(GeomError::InvalidCsr {
                arg: "tables",
                rows: n,
                reason: format!("table {t} holds {length} bytes, not {n} rows of {width}"),
            });
        }
    }
    check_rows(rows, n)
}

/// The rows `rows` (strictly increasing, below `n`) of each of `tables` (`n` rows each), one
/// table of `rows.len()` rows for each, copied on every core for many.
///
/// # Errors
/// A table that does not hold `n` rows, rows that are not increasing indices below `n`, or an
/// allocation that fails.
pub fn take_rows(tables: &[Table<'_>], n: usize, rows: &[i64]) -> Result<Vec<Vec<u8>>> {
    check(tables.iter().map(|t| (t.width, t.bytes.len())), n, rows)?;
    let take = |table: &Table<'_>| -> Result<Vec<u8>> {
        let w = table.width;
        let mut out = try_filled(rows.len() * w, 0_u8, "memory rows")?;
        let copy = |(c, block): (usize, &mut [u8])| {
            let rows = &rows[c * TASK_ROWS..];
            match w {
                1 => copy_rows::<1>(block, table.bytes, rows),
                8 => copy_rows::<8>(block, table.bytes, rows),
                16 => copy_rows::<16>(block, table.bytes, rows),
                _ => {
                    for (row, &i) in block.chunks_exact_mut(w).zip(rows) {
                        row.copy_from_slice(&table.bytes[i as usize * w..(i as usize + 1) * w]);
                    }
                }
            }
        };
        if w == 0 {
            return Ok(out);
        }
        if worth_spreading(rows.len() * w, 0.25) {
            out.par_chunks_mut(TASK_ROWS * w).enumerate().for_each(copy);
        } else {
            out.chunks_mut(TASK_ROWS * w).enumerate().for_each(copy);
        }
        Ok(out)
    };
    if worth_spreading(rows.len() * tables.len(), 1.0) {
        tables.par_iter().map(take).collect()
    } else {
        tables.iter().map(take).collect()
    }
}

/// `values[t]` (`rows.len()` rows each) written into each of `tables` at the rows `rows`
/// (strictly increasing, below `n`), on every core for many.
///
/// # Errors
/// A table that does not hold `n` rows, values that do not hold a row for each of `rows`, or
/// rows that are not increasing indices below `n` (then no table is written).
pub fn put_rows(tables: &mut [TableMut<'_>], n: usize, rows: &[i64], values: &[&[u8]]) -> Result<()> {
    check(tables.iter().map(|t| (t.width, t.bytes.len())), n, rows)?;
    if values.len() != tables.len() {
        return Err(GeomError::LengthMismatch {
            arg: "values",
            expected: tables.len(),
            got: values.len(),
        });
    }
    for (t, (table, source)) in tables.iter().zip(values).enumerate() {
        if source.len() != rows.len() * table.width {
            return Err(GeomError::InvalidCsr {
                arg: "values",
                rows: rows.len(),
                reason: format!(
                    "values {t} hold {} bytes, not {} rows of {}",
                    source.len(),
                    rows.len(),
                    table.width
                ),
            });
        }
    }
    let put = |(table, source): (&mut TableMut<'_>, &&[u8])| {
        let w = table.width;
        if w == 0 {
            return;
        }
        // The rows increase: each task's rows lie in a stretch of the table of its own.
        let mut tasks = Vec::with_capacity(rows.len() / TASK_ROWS + 1);
        let mut rest = &mut table.bytes[..];
        let mut start = 0;
        for first in (0..rows.len()).step_by(TASK_ROWS) {
            let last = (first + TASK_ROWS).min(rows.len());
            let end = if last == rows.len() { n } else { rows[last] as usize };
            let (head, tail) = std::mem::take(&mut rest).split_at_mut((end - start) * w);
            tasks.push((first..last, start, head));
            (rest, start) = (tail, end);
        }
        let write = |(range, offset, stretch): (std::ops::Range<usize>, usize, &mut [u8])| match w {
            1 => write_rows::<1>(stretch, offset, &rows[range.clone()], &source[range.start..range.end]),
            8 => write_rows::<8>(
                stretch,
                offset,
                &rows[range.clone()],
                &source[range.start * 8..range.end * 8],
            ),
            16 => write_rows::<16>(
                stretch,
                offset,
                &rows[range.clone()],
                &source[range.start * 16..range.end * 16],
            ),
            _ => {
                for r in range {
                    let at = (rows[r] as usize - offset) * w;
                    stretch[at..at + w].copy_from_slice(&source[r * w..(r + 1) * w]);
                }
            }
        };
        if worth_spreading(rows.len() * w, 0.25) {
            tasks.into_par_iter().for_each(write);
        } else {
            tasks.into_iter().for_each(write);
        }
    };
    if worth_spreading(rows.len() * tables.len(), 1.0) {
        tables.par_iter_mut().zip(values).for_each(put);
    } else {
        tables.iter_mut().zip(values).for_each(put);
    }
    Ok(())
}

/// [`take_rows`]'s copy for rows of `W` bytes, a width known when compiled: each row one move
/// instead of a call to `memcpy` (a float or an index, the usual field, is 8 bytes).
fn copy_rows<const W: usize>(block: &mut [u8], table: &[u8], rows: &[i64]) {
    let (table, _) = table.as_chunks::<W>();
    let (block, _) = block.as_chunks_mut::<W>();
    for (row, &i) in block.iter_mut().zip(rows) {
        *row = table[i as usize];
    }
}

/// [`put_rows`]'s write for rows of `W` bytes: `source`'s rows into `stretch`, which starts at
/// row `offset` of the table.
fn write_rows<const W: usize>(stretch: &mut [u8], offset: usize, rows: &[i64], source: &[u8]) {
    let (stretch, _) = stretch.as_chunks_mut::<W>();
    let (source, _) = source.as_chunks::<W>();
    for (&i, row) in rows.iter().zip(source) {
        stretch[i as usize - offset] = *row;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_out_and_back() {
        let n = 10_000;
        let wide: Vec<u8> = (0..n * 24).map(|b| (b % 251) as u8).collect();
        let narrow: Vec<u8> = (0..n).map(|b| (b % 7) as u8).collect();
        let rows: Vec<i64> = (0..n as i64).filter(|i| i % 3 == 1).collect();
        let tables = [
            Table {
                bytes: &wide,
                width: 24,
            },
            Table {
                bytes: &narrow,
                width: 1,
            },
        ];
        let taken = take_rows(&tables, n, &rows).unwrap();
        for (r, &i) in rows.iter().enumerate() {
            let i = i as usize;
            assert_eq!(taken[0][r * 24..(r + 1) * 24], wide[i * 24..(i + 1) * 24]);
            assert_eq!(taken[1][r], narrow[i]);
        }
        let (mut wide_copy, mut narrow_copy) = (vec![0_u8; n * 24], vec![0_u8; n]);
        let mut into = [
            TableMut {
                bytes: &mut wide_copy,
                width: 24,
            },
            TableMut {
                bytes: &mut narrow_copy,
                width: 1,
            },
        ];
        put_rows(&mut into, n, &rows, &[&taken[0], &taken[1]]).unwrap();
        assert!(put_rows(&mut into, n, &rows, &[&taken[0]]).is_err());
        assert!(put_rows(&mut into, n, &rows[1..], &[&taken[0], &taken[1]]).is_err());
        for i in 0..n {
            let row = &wide_copy[i * 24..(i + 1) * 24];
            if i % 3 == 1 {
                assert_eq!((row, narrow_copy[i]), (&wide[i * 24..(i + 1) * 24], narrow[i]));
            } else {
                assert!(row.iter().all(|&b| b == 0) && narrow_copy[i] == 0);
            }
        }
        assert!(take_rows(&tables, n, &[2, 1]).is_err());
        assert!(take_rows(&tables, n, &[n as i64]).is_err());
        assert!(take_rows(&tables, n + 1, &[0]).is_err());
    }
}
