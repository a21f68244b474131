//! Reductions over ragged rows (CSR): what each robot makes of its own neighbourhood.
//!
//! A neighbourhood is `offsets` `(m + 1,)` over entries of `width` values each: row r holds
//! entries `offsets[r]..offsets[r + 1]`. Each reduction answers one value per row and column,
//! rows in parallel for large inputs. Empty rows give 0 for a sum and NaN for a mean, a minimum
//! or a maximum (nothing to take them of); NaN entries are skipped by the minimum, the maximum
//! and the nearest, and carried by the sum and the mean.

use std::ops::Range;

use rayon::prelude::*;

use crate::csr::check_offsets;
use crate::error::{GeomError, Result};
use crate::parallel::{first_where, map_range, worth_spreading};

/// What a row's entries become.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reduce {
    Sum,
    Mean,
    Min,
    Max,
}

/// `op` of each row's entries, column by column: `(m, width)` row-major.
///
/// Entry e is row e of `values` (`(k, width)` row-major), or with `index`, row `index[e]`: a
/// neighbourhood's column gathered from a per-robot array (a message field from the board)
/// without copying it out first.
///
/// # Errors
/// `values` not a whole number of rows of `width`, an index out of bounds, or an invalid CSR.
pub fn reduce(values: &[f64], width: usize, offsets: &[i64], index: Option<&[i64]>, op: Reduce) -> Result<Vec<f64>> {
    if width == 0 || !values.len().is_multiple_of(width) {
        return Err(GeomError::LengthMismatch {
            arg: "values",
            expected: width * (values.len() / width.max(1)),
            got: values.len(),
        });
    }
    let rows = values.len() / width;
    let entries = match index {
        Some(index) => {
            check_indices("index", index, rows)?;
            index.len()
        }
        None => rows,
    };
    check_offsets("offsets", offsets, entries, "entries")?;
    let at = |e: usize| index.map_or(e, |index| index[e] as usize);
    // Each row's values are written where they lie in the output: no vector per row. In entry
    // order from +0.0, as the NumPy reference adds: the same bits on both paths.
    let row = |(r, out): (usize, &mut [f64])| {
        let entries = offsets[r] as usize..offsets[r + 1] as usize;
        let count = entries.len();
        let fold = Fold {
            values,
            width,
            entries,
            at: &at,
        };
        match op {
            Reduce::Sum => fold.each_column(out, 0.0, |a, b| a + b),
            Reduce::Mean => {
                fold.each_column(out, 0.0, |a, b| a + b);
                out.iter_mut()
                    .for_each(|slot| *slot = if count > 0 { *slot / count as f64 } else { f64::NAN });
            }
            Reduce::Min => fold.each_column(out, f64::NAN, f64::min),
            Reduce::Max => fold.each_column(out, f64::NAN, f64::max),
        }
    };
    let m = offsets.len() - 1;
    let mut out = vec![0.0; m * width];
    // About a nanosecond a value added, a few a row.
    if worth_spreading(entries * width + 4 * m, 1.0) {
        out.par_chunks_mut(width).enumerate().with_min_len(64).for_each(row);
    } else {
        out.chunks_mut(width).enumerate().for_each(row);
    }
    Ok(out)
}

/// One row's entries of `values` (rows of `width`, entry `e` at row `at(e)`) to fold.
struct Fold<'a, At> {
    values: &'a [f64],
    width: usize,
    entries: Range<usize>,
    at: &'a At,
}

impl<At: Fn(usize) -> usize> Fold<'_, At> {
    /// Each column folded with `combine` from `init`, in entry order, into `out`: the columns of
    /// a narrow row side by side in one pass over the entries (each index read once, and the
    /// columns' additions, which wait on one another within a column, interleaved).
    fn each_column(&self, out: &mut [f64], init: f64, combine: impl Fn(f64, f64) -> f64 + Copy) {
        match self.width {
            1 => self.side_by_side::<1>(out, init, combine),
            2 => self.side_by_side::<2>(out, init, combine),
            3 => self.side_by_side::<3>(out, init, combine),
            4 => self.side_by_side::<4>(out, init, combine),
            width => {
                for (c, slot) in out.iter_mut().enumerate() {
                    let column = self.entries.clone().map(|e| self.values[(self.at)(e) * width + c]);
                    *slot = column.fold(init, combine);
                }
            }
        }
    }

    fn side_by_side<const W: usize>(&self, out: &mut [f64], init: f64, combine: impl Fn(f64, f64) -> f64) {
        let mut folded = [init; W];
        for e in self.entries.clone() {
            let row = &self.values[(self.at)(e) * W..][..W];
            for c in 0..W {
                folded[c] = combine(folded[c], row[c]);
            }
        }
        out.copy_from_slice(&folded);
    }
}

/// Every entry of `index` must name one of `rows` rows.
fn check_indices(arg: &'static str, index: &[i64], rows: usize) -> Result<()> {
    // On every core for many: a million robots' inboxes hold millions of messages.
    match first_where(index.len(), |k| index[k] < 0 || index[k] as usize >= rows) {
        Some(k) => Err(GeomError::IndexOutOfBounds {
            arg,
            index: index[k],
            len: rows,
        }),
        None => Ok(()),
    }
}

/// Whether any entry of each row is set.
///
/// # Errors
/// An invalid CSR.
pub fn any(flags: &[bool], offsets: &[i64]) -> Result<Vec<bool>> {
    check_offsets("offsets", offsets, flags.len(), "flags")?;
    let rows = offsets.len() - 1;
    Ok(map_range(rows, 1.0 + (flags.len() / rows.max(1)) as f64, |r| {
        flags[offsets[r] as usize..offsets[r + 1] as usize].iter().any(|&f| f)
    }))
}

/// The entry of each row with the smallest `key` (the first of equals), as an index into the
/// entries; -1 for a row that is empty or all NaN.
///
/// # Errors
/// An invalid CSR.
pub fn nearest(keys: &[f64], offsets: &[i64]) -> Result<Vec<i64>> {
    nearest_k(keys, offsets, 1)
}

/// The `k` entries of each row with the smallest `key`, smallest first (of equals, the first
/// entry first; NaN skipped), as indices into the entries, -1 in the slots a row cannot fill:
/// `(m, k)` row-major. One pass per row, keeping the `k` best in order: for a few slots, cheaper
/// than sorting the row.
///
/// # Errors
/// An invalid CSR.
pub fn nearest_k(keys: &[f64], offsets: &[i64], k: usize) -> Result<Vec<i64>> {
    check_offsets("offsets", offsets, keys.len(), "keys")?;
    Ok(pick_nearest(offsets, k, keys.len(), |_, e| keys[e]))
}

/// [`nearest_k`] with each entry's key its point's squared distance to its row's origin: the `k`
/// entries of row r whose `points` lie nearest `origins[r]` (a robot's nearest messages, by
/// the positions they give). With `index`, entry e's point is `points[index[e]]` (read from a
/// per-robot array in place), else `points[e]`. The squares are `dx * dx + dy * dy`, as NumPy
/// computes them from `dx = x - ox` and `dy = y - oy`: the same ranking on both paths.
///
/// # Errors
/// An invalid CSR, an origin per row missing, or an index out of bounds.
pub fn nearest_k_to(
    points: &[[f64; 2]],
    offsets: &[i64],
    origins: &[[f64; 2]],
    index: Option<&[i64]>,
    k: usize,
) -> Result<Vec<i64>> {
    let entries = match index {
        Some(index) => {
            check_indices("index", index, points.len())?;
            index.len()
        }
        None => points.len(),
    };
    check_offsets("offsets", offsets, entries, "points")?;
    if origins.len() + 1 != offsets.len() {
        return Err(GeomError::LengthMismatch {
            arg: "origins",
            expected: offsets.len() - 1,
            got: origins.len(),
        });
    }
    Ok(pick_nearest(offsets, k, entries, |r, e| {
        let q = points[index.map_or(e, |index| index[e] as usize)];
        let (dx, dy) = (q[0] - origins[r][0], q[1] - origins[r][1]);
        dx * dx + dy * dy
    }))
}

/// The `k` entries of smallest `key(row, entry)` of each row (checked CSR over `entries`), as
/// [`nearest_k`] gives them.
fn pick_nearest(offsets: &[i64], k: usize, entries: usize, key: impl Fn(usize, usize) -> f64 + Sync) -> Vec<i64> {
    if k == 0 {
        return Vec::new();
    }
    // Each row's slots are filled where they lie in the output, with one buffer of the kept keys
    // per task: no vector per row to allocate and then copy out.
    let row = |least: &mut Vec<f64>, (r, best): (usize, &mut [i64])| {
        least.clear();
        least.resize(k, f64::INFINITY);
        let mut filled = 0;
        for e in offsets[r] as usize..offsets[r + 1] as usize {
            let key = key(r, e);
            // Not kept: NaN, or no nearer than the k kept (a tie keeps the earlier entry).
            if key.is_nan() || (filled == k && key >= least[k - 1]) {
                continue;
            }
            // Insertion from the back, past the kept entries whose key is larger.
            let mut slot = filled.min(k - 1);
            while slot > 0 && least[slot - 1] > key {
                (least[slot], best[slot]) = (least[slot - 1], best[slot - 1]);
                slot -= 1;
            }
            (least[slot], best[slot]) = (key, e as i64);
            filled = (filled + 1).min(k);
        }
    };
    let rows = offsets.len() - 1;
    let mut picked = vec![-1_i64; rows * k];
    // A few nanoseconds an entry ranked (the messages of a few thousand robots, a few dozen each).
    if worth_spreading(entries + rows, 4.0) {
        picked
            .par_chunks_mut(k)
            .enumerate()
            .with_min_len(64)
            .for_each_init(Vec::new, row);
    } else {
        let mut least = Vec::new();
        picked
            .chunks_mut(k)
            .enumerate()
            .for_each(|slots| row(&mut least, slots));
    }
    picked
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_rows_and_nan() {
        let values = [1.0, 2.0, f64::NAN, 4.0];
        let offsets = [0, 0, 3, 4];
        let sums = reduce(&values, 1, &offsets, None, Reduce::Sum).unwrap();
        assert_eq!(sums[0], 0.0);
        assert!(sums[1].is_nan());
        assert_eq!(sums[2], 4.0);
        let mins = reduce(&values, 1, &offsets, None, Reduce::Min).unwrap();
        assert!(mins[0].is_nan());
        assert_eq!(mins[1], 1.0);
        assert_eq!(nearest(&values, &offsets).unwrap(), vec![-1, 0, 3]);
        assert_eq!(
            nearest_k(&values, &offsets, 3).unwrap(),
            vec![-1, -1, -1, 0, 1, -1, 3, -1, -1]
        );
        assert_eq!(
            any(&[false, true, false, false], &offsets).unwrap(),
            vec![false, true, false]
        );
    }

    #[test]
    fn the_k_nearest_come_in_order_the_first_of_equals_first() {
        let keys = [3.0, 1.0, 2.0, 1.0, f64::NAN, 0.5, 5.0];
        let offsets = [0, 7];
        assert_eq!(nearest_k(&keys, &offsets, 4).unwrap(), vec![5, 1, 3, 2]);
        assert_eq!(nearest_k(&keys, &offsets, 0).unwrap(), Vec::<i64>::new());
        assert_eq!(
            nearest_k(&keys, &offsets, 9).unwrap(),
            vec![5, 1, 3, 2, 0, 6, -1, -1, -1]
        );
        assert!(nearest_k(&keys, &[0, 8], 1).is_err());
    }

    #[test]
    fn the_nearest_points_are_the_nearest_keys() {
        let points = [[0.0, 0.0], [3.0, 0.0], [1.0, 1.0], [f64::NAN, 0.0], [0.5, 0.0]];
        let offsets = [0, 3, 5];
        let origins = [[1.0, 0.0], [0.0, 0.0]];
        let keys = [1.0, 4.0, 1.0, f64::NAN, 0.25];
        assert_eq!(
            nearest_k_to(&points, &offsets, &origins, None, 2).unwrap(),
            nearest_k(&keys, &offsets, 2).unwrap()
        );
        let index = [4, 0, 1];
        assert_eq!(
            nearest_k_to(&points, &[0, 3], &[[0.0, 0.0]], Some(&index), 2).unwrap(),
            vec![1, 0]
        );
        assert!(nearest_k_to(&points, &offsets, &origins[..1], None, 2).is_err());
        assert!(nearest_k_to(&points, &[0, 1], &[[0.0, 0.0]], Some(&[5]), 1).is_err());
    }

    #[test]
    fn an_index_gathers_rows() {
        let values = [10.0, 20.0, 30.0];
        let sums = reduce(&values, 1, &[0, 2, 3], Some(&[2, 2, 0]), Reduce::Sum).unwrap();
        assert_eq!(sums, vec![60.0, 10.0]);
        assert!(reduce(&values, 1, &[0, 1], Some(&[3]), Reduce::Sum).is_err());
        assert!(reduce(&values, 1, &[0, 1], Some(&[-1]), Reduce::Sum).is_err());
    }

    #[test]
    fn bad_offsets_are_named() {
        assert!(reduce(&[1.0], 1, &[0, 2], None, Reduce::Sum).is_err());
        assert!(reduce(&[1.0, 2.0], 1, &[0, 2, 1, 2], None, Reduce::Sum).is_err());
        assert!(reduce(&[1.0, 2.0, 3.0], 2, &[0, 1], None, Reduce::Sum).is_err());
    }
}
