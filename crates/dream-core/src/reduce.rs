//! Reductions over ragged rows (CSR): what each robot makes of its own neighbourhood.
//!
//! A neighbourhood is `offsets` `(m + 1,)` over entries of `width` values each: row r holds
//! entries `offsets[r]..offsets[r + 1]`. Each reduction answers one value per row and column,
//! rows in parallel for large inputs. Empty rows give 0 for a sum and NaN for a mean, a minimum
//! or a maximum (nothing to take them of); NaN entries are skipped by the minimum, the maximum
//! and the nearest, and carried by the sum and the mean.

use rayon::prelude::*;

use crate::error::{check_offsets, GeomError, Result};

/// Rows from which a reduction runs on every thread (below, the thread pool costs more).
const PARALLEL_ROWS: usize = 4096;

/// What a row's entries become.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reduce {
    Sum,
    Mean,
    Min,
    Max,
}

fn rows_of<T: Send>(rows: usize, row: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    if rows >= PARALLEL_ROWS {
        (0..rows)
            .into_par_iter()
            .with_min_len(PARALLEL_ROWS / 4)
            .map(row)
            .collect()
    } else {
        (0..rows).map(row).collect()
    }
}

/// `op` of each row's entries, column by column: `(m, width)` row-major. Entry e is row e of
/// `values` (`width` values each), or with `index` row `index[e]` of it: a neighbourhood of
/// messages reduced straight from the board, by sender, without gathering it first.
///
/// # Errors
/// `values` not a whole number of rows of `width`, an index out of its rows, or an invalid CSR.
pub fn reduce(values: &[f64], width: usize, offsets: &[i64], op: Reduce, index: Option<&[i64]>) -> Result<Vec<f64>> {
    if width == 0 || values.len() % width != 0 {
        return Err(GeomError::LengthMismatch {
            arg: "values",
            expected: width * (values.len() / width.max(1)),
            got: values.len(),
        });
    }
    let rows = values.len() / width;
    let entries = index.map_or(rows, <[i64]>::len);
    check_offsets("offsets", offsets, entries, "entries")?;
    if let Some(bad) = index.and_then(|ix| ix.iter().find(|&&i| i < 0 || i as usize >= rows)) {
        return Err(GeomError::InvalidParameter {
            arg: "index",
            rule: "rows of `values`",
            got: *bad as f64,
        });
    }
    let at = |e: usize| index.map_or(e, |ix| ix[e] as usize) * width;
    let row = |r: usize| {
        let (start, end) = (offsets[r] as usize, offsets[r + 1] as usize);
        let mut out = vec![0.0; width];
        for (c, slot) in out.iter_mut().enumerate() {
            let column = (start..end).map(|e| values[at(e) + c]);
            *slot = match op {
                Reduce::Sum => column.sum(),
                Reduce::Mean if end > start => column.sum::<f64>() / (end - start) as f64,
                Reduce::Min => column.fold(f64::NAN, f64::min),
                Reduce::Max => column.fold(f64::NAN, f64::max),
                Reduce::Mean => f64::NAN,
            };
        }
        out
    };
    Ok(rows_of(offsets.len() - 1, row).into_iter().flatten().collect())
}

/// Whether any entry of each row is set.
///
/// # Errors
/// An invalid CSR.
pub fn any(flags: &[bool], offsets: &[i64]) -> Result<Vec<bool>> {
    check_offsets("offsets", offsets, flags.len(), "flags")?;
    Ok(rows_of(offsets.len() - 1, |r| {
        flags[offsets[r] as usize..offsets[r + 1] as usize].iter().any(|&f| f)
    }))
}

/// The entry of each row with the smallest `key` (the first of equals), as an index into the
/// entries; -1 for a row that is empty or all NaN.
///
/// # Errors
/// An invalid CSR.
pub fn nearest(keys: &[f64], offsets: &[i64]) -> Result<Vec<i64>> {
    check_offsets("offsets", offsets, keys.len(), "keys")?;
    Ok(rows_of(offsets.len() - 1, |r| {
        let (start, end) = (offsets[r] as usize, offsets[r + 1] as usize);
        let mut best = -1i64;
        let mut least = f64::INFINITY;
        for (e, &key) in keys[start..end].iter().enumerate() {
            if !key.is_nan() && (best < 0 || key < least) {
                least = key;
                best = (start + e) as i64;
            }
        }
        best
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_rows_and_nan() {
        let values = [1.0, 2.0, f64::NAN, 4.0];
        let offsets = [0, 0, 3, 4];
        let sums = reduce(&values, 1, &offsets, Reduce::Sum, None).unwrap();
        assert_eq!(sums[0], 0.0);
        assert!(sums[1].is_nan());
        assert_eq!(sums[2], 4.0);
        let mins = reduce(&values, 1, &offsets, Reduce::Min, None).unwrap();
        let gathered = reduce(&values, 1, &[0, 2], Reduce::Sum, Some(&[3, 3])).unwrap();
        assert_eq!(gathered, vec![8.0]);
        assert!(reduce(&values, 1, &[0, 1], Reduce::Sum, Some(&[4])).is_err());
        assert!(mins[0].is_nan());
        assert_eq!(mins[1], 1.0);
        assert_eq!(nearest(&values, &offsets).unwrap(), vec![-1, 0, 3]);
        assert_eq!(
            any(&[false, true, false, false], &offsets).unwrap(),
            vec![false, true, false]
        );
    }

    #[test]
    fn bad_offsets_are_named() {
        assert!(reduce(&[1.0], 1, &[0, 2], Reduce::Sum, None).is_err());
        assert!(reduce(&[1.0, 2.0], 1, &[0, 2, 1, 2], Reduce::Sum, None).is_err());
        assert!(reduce(&[1.0, 2.0, 3.0], 2, &[0, 1], Reduce::Sum, None).is_err());
    }
}
