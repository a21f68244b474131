//! The one error type of the core: every kernel validates its input and reports what is wrong,
//! and the buffers whose size follows from the input (neighbour pairs, say) are allocated
//! fallibly, so that a query too large for the memory fails instead of aborting.

use crate::parallel::first_where;

/// Invalid input to a kernel. The message names the argument and what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GeomError {
    /// An array does not hold one entry per robot.
    #[error("`{arg}` has {got} values, expected {expected}")]
    LengthMismatch {
        arg: &'static str,
        expected: usize,
        got: usize,
    },
    /// A value that must be finite is NaN or infinite.
    #[error("`{arg}` contains a non-finite value (NaN or inf) at index {index}")]
    NonFinite { arg: &'static str, index: usize },
    /// A row of a message array with one coordinate NaN: a message is a point, or all NaN (none).
    #[error("`{arg}` row {index} is half NaN: a message is a finite point, or NaN in both coordinates (nothing said)")]
    PartlyNaN { arg: &'static str, index: usize },
    /// A length, radius or limit that must be positive (or non-negative) is not.
    #[error("`{arg}` must be finite and {rule}, got {got}")]
    InvalidParameter {
        arg: &'static str,
        rule: &'static str,
        got: f64,
    },
    /// Ragged rows (CSR) that do not fit: wrong length, decreasing offsets, ids out of range.
    #[error("`{arg}` is not a valid CSR of {rows} rows: {reason}")]
    InvalidCsr {
        arg: &'static str,
        rows: usize,
        reason: String,
    },
    /// Values that must be strictly increasing (a sorted set) are not, first at `index`.
    #[error("`{arg}` is not strictly increasing at index {index}")]
    NotIncreasing { arg: &'static str, index: usize },
    /// An index into a per-robot array that names no row of it.
    #[error("`{arg}` holds {index}, which is not a row of the {len} it indexes")]
    IndexOutOfBounds { arg: &'static str, index: i64, len: usize },
    /// An obstacle whose vertices enclose no area.
    #[error("obstacle {0} is degenerate: its vertices enclose no area")]
    DegenerateObstacle(usize),
    /// An arena whose minimum is not below its maximum.
    #[error("arena bounds must satisfy xmin < xmax and ymin < ymax, got ({xmin}, {xmax}, {ymin}, {ymax})")]
    InvalidBounds { xmin: f64, xmax: f64, ymin: f64, ymax: f64 },
    /// A time step so large that a robot's pose is no longer finite after it.
    #[error("`dt` = {dt} overflows: robot {robot}'s pose is no longer finite after the step")]
    Overflow { dt: f64, robot: usize },
    /// A buffer the input calls for could not be allocated.
    #[error("out of memory: {what} needed {bytes} more bytes")]
    OutOfMemory { what: &'static str, bytes: usize },
}

/// Result of a core kernel.
pub type Result<T> = std::result::Result<T, GeomError>;

/// Fails with [`GeomError::NonFinite`] at the first NaN or infinite value of `values` (looked
/// for on every core for many: a million robots' coordinates, several arrays a kernel).
pub fn check_finite(arg: &'static str, values: &[f64]) -> Result<()> {
    match first_where(values.len(), |i| !values[i].is_finite()) {
        Some(index) => Err(GeomError::NonFinite { arg, index }),
        None => Ok(()),
    }
}

/// Fails with [`GeomError::LengthMismatch`] unless `got == expected`.
pub fn check_len(arg: &'static str, expected: usize, got: usize) -> Result<()> {
    if got == expected {
        Ok(())
    } else {
        Err(GeomError::LengthMismatch { arg, expected, got })
    }
}

/// Fails with [`GeomError::InvalidParameter`] unless `value` is finite and > 0.
pub fn check_positive(arg: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(GeomError::InvalidParameter {
            arg,
            rule: "> 0",
            got: value,
        })
    }
}

/// Makes room in `buffer` for `additional` more items, failing with [`GeomError::OutOfMemory`]
/// (naming `what`) where the allocation fails instead of aborting.
pub fn try_room<T>(buffer: &mut Vec<T>, additional: usize, what: &'static str) -> Result<()> {
    buffer.try_reserve(additional).map_err(|_| GeomError::OutOfMemory {
        what,
        bytes: additional.saturating_mul(std::mem::size_of::<T>()),
    })
}

/// `len` copies of `value`, or [`GeomError::OutOfMemory`] (naming `what`).
pub fn try_filled<T: Clone>(len: usize, value: T, what: &'static str) -> Result<Vec<T>> {
    let mut buffer = Vec::new();
    try_room(&mut buffer, len, what)?;
    buffer.resize(len, value);
    Ok(buffer)
}
