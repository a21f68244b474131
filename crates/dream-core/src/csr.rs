//! Ragged rows (CSR): one row per robot, `offsets` `(rows + 1,)` cutting the entries into rows.
//! The neighbour lists, a robot's detections or messages, virtual agents: every ragged result
//! of the kernels, and the checks of every ragged input.

use crate::error::{GeomError, Result};

/// Ragged rows: row i is `indices[indptr[i]..indptr[i + 1]]` (with matching `distances`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Csr {
    pub indptr: Vec<i64>,
    pub indices: Vec<i64>,
    pub distances: Vec<f64>,
}

/// Fails with [`GeomError::InvalidCsr`] unless `offsets` rise from 0 to `len`, the number of
/// entries of the rows they cut (`what`: those entries, for the message).
pub fn check_offsets(arg: &'static str, offsets: &[i64], len: usize, what: &str) -> Result<()> {
    let rising = offsets.first() == Some(&0)
        && offsets.last() == Some(&(len as i64))
        && offsets.windows(2).all(|w| w[0] <= w[1]);
    if rising {
        Ok(())
    } else {
        Err(GeomError::InvalidCsr {
            arg,
            rows: offsets.len().saturating_sub(1),
            reason: format!("its offsets must rise from 0 to the number of {what}"),
        })
    }
}

/// Fails with [`GeomError::InvalidCsr`] unless `rows` are increasing ids of the `n` robots (fewer
/// than `u32::MAX` of them): the robots a kernel reads and writes at.
///
/// # Errors
/// [`GeomError::InvalidCsr`] naming the first bad row.
pub fn check_rows(rows: &[i64], n: usize) -> Result<()> {
    for (r, &i) in rows.iter().enumerate() {
        if i < 0 || i as usize >= n || (r > 0 && i <= rows[r - 1]) || r >= u32::MAX as usize {
            return Err(GeomError::InvalidCsr {
                arg: "rows",
                rows: rows.len(),
                reason: format!("row {r} is {i}: rows must be increasing robot ids below {n}"),
            });
        }
    }
    Ok(())
}

/// Checks that `(indptr, indices)` has `n` rows of ids in `[0, n)`.
///
/// # Errors
/// [`GeomError::InvalidCsr`] saying what is wrong.
pub fn check_csr(indptr: &[i64], indices: &[i64], n: usize) -> Result<()> {
    let fail = |reason: String| {
        Err(GeomError::InvalidCsr {
            arg: "neighbours",
            rows: n,
            reason,
        })
    };
    if indptr.len() != n + 1 {
        return fail(format!("indptr has {} entries, expected {}", indptr.len(), n + 1));
    }
    if indptr[0] != 0 || indptr[n] != indices.len() as i64 {
        return fail(format!("indptr must run from 0 to len(indices) = {}", indices.len()));
    }
    if let Some(i) = indptr.windows(2).position(|w| w[1] < w[0]) {
        return fail(format!("indptr decreases at row {i}"));
    }
    if let Some(&j) = indices.iter().find(|&&j| j < 0 || j >= n as i64) {
        return fail(format!("index {j} is not a robot id in [0, {n})"));
    }
    Ok(())
}
