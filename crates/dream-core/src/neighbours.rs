//! Who is near whom: range and field-of-view queries for the whole swarm, as CSR rows.
//!
//! Robot j is a neighbour of robot i when j != i (by index, so co-located robots count),
//! `|p_j - p_i| <= radius` and, with a field of view, the direction from i to j lies within
//! `fov / 2` of `heading_i + direction` (a co-located robot is always seen). Each row lists
//! indices in increasing order; with `max_neighbours` only the nearest are kept (ties: lower
//! index first). The arithmetic matches the NumPy reference operation by operation.

use std::f64::consts::{PI, TAU};

use rayon::prelude::*;

use crate::error::{check_finite, check_len, GeomError, Result};
use crate::grid::Grid;

/// Rows below this count run on one thread: spawning costs more than it saves.
const PARALLEL_ROWS: usize = 2048;

/// A sensor's field of view: robot i looks along `headings[i] + direction` with full aperture `fov`.
#[derive(Debug, Clone, Copy)]
pub struct FieldOfView<'a> {
    pub headings: &'a [f64],
    pub direction: f64,
    pub fov: f64,
}

/// Ragged rows: row i is `indices[indptr[i]..indptr[i + 1]]` (with matching `distances`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Csr {
    pub indptr: Vec<i64>,
    pub indices: Vec<i64>,
    pub distances: Vec<f64>,
}

impl Csr {
    fn from_rows(rows: Vec<Vec<(usize, f64)>>) -> Self {
        let mut csr = Csr { indptr: Vec::with_capacity(rows.len() + 1), ..Csr::default() };
        csr.indptr.push(0);
        let total: usize = rows.iter().map(Vec::len).sum();
        csr.indices.reserve(total);
        csr.distances.reserve(total);
        for row in rows {
            for (j, d) in row {
                csr.indices.push(j as i64);
                csr.distances.push(d);
            }
            csr.indptr.push(csr.indices.len() as i64);
        }
        csr
    }
}

/// Wraps an angle to [-pi, pi) as NumPy's `(a + pi) % (2 pi) - pi` does.
pub(crate) fn wrap_angle(angle: f64) -> f64 {
    (angle + PI).rem_euclid(TAU) - PI
}

/// Neighbours of every robot at `(xs[i], ys[i])` within `radius` (inclusive), as CSR.
///
/// # Errors
/// Length mismatches, non-finite coordinates or headings, a negative or non-finite radius, or a
/// non-finite direction / negative fov.
pub fn within(
    xs: &[f64],
    ys: &[f64],
    radius: f64,
    view: Option<FieldOfView<'_>>,
    max_neighbours: Option<usize>,
) -> Result<Csr> {
    let n = xs.len();
    check_len("ys", n, ys.len())?;
    check_finite("positions", xs)?;
    check_finite("positions", ys)?;
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(GeomError::InvalidParameter { arg: "radius", rule: ">= 0", got: radius });
    }
    if let Some(v) = view {
        check_len("headings", n, v.headings.len())?;
        check_finite("headings", v.headings)?;
        if !v.direction.is_finite() {
            return Err(GeomError::InvalidParameter { arg: "direction", rule: "finite", got: v.direction });
        }
        if v.fov.is_nan() || v.fov < 0.0 {
            return Err(GeomError::InvalidParameter { arg: "fov", rule: ">= 0", got: v.fov });
        }
    }
    // Any cell >= radius finds every neighbour; radius 0 only needs identical points together.
    let grid = Grid::new(xs, ys, if radius > 0.0 { radius } else { 1.0 });
    let row = |i: usize| row_of(&grid, xs, ys, i, radius, view, max_neighbours);
    let rows: Vec<Vec<(usize, f64)>> = if n >= PARALLEL_ROWS {
        (0..n).into_par_iter().map(row).collect()
    } else {
        (0..n).map(row).collect()
    };
    Ok(Csr::from_rows(rows))
}

fn row_of(
    grid: &Grid,
    xs: &[f64],
    ys: &[f64],
    i: usize,
    radius: f64,
    view: Option<FieldOfView<'_>>,
    max_neighbours: Option<usize>,
) -> Vec<(usize, f64)> {
    let mut row = Vec::new();
    grid.for_each_near(xs[i], ys[i], |j| {
        if j == i {
            return;
        }
        let (dx, dy) = (xs[j] - xs[i], ys[j] - ys[i]);
        let distance = (dx * dx + dy * dy).sqrt();
        if distance > radius {
            return;
        }
        if let Some(v) = view {
            let relative = wrap_angle(dy.atan2(dx) - (v.headings[i] + v.direction));
            if !(relative.abs() <= v.fov / 2.0 || distance == 0.0) {
                return;
            }
        }
        row.push((j, distance));
    });
    if let Some(k) = max_neighbours {
        if row.len() > k {
            row.sort_unstable_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            row.truncate(k);
        }
    }
    row.sort_unstable_by_key(|&(j, _)| j);
    row
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(xs: &[f64], ys: &[f64], radius: f64) -> Vec<Vec<i64>> {
        (0..xs.len())
            .map(|i| {
                (0..xs.len())
                    .filter(|&j| j != i && ((xs[j] - xs[i]).powi(2) + (ys[j] - ys[i]).powi(2)).sqrt() <= radius)
                    .map(|j| j as i64)
                    .collect()
            })
            .collect()
    }

    fn rows(csr: &Csr) -> Vec<Vec<i64>> {
        csr.indptr.windows(2).map(|w| csr.indices[w[0] as usize..w[1] as usize].to_vec()).collect()
    }

    #[test]
    fn matches_brute_force_on_a_scatter() {
        // A deterministic scatter (no RNG dependency): a quasi-random sequence.
        let n = 3000;
        let xs: Vec<f64> = (0..n).map(|i| ((i as f64) * 0.754_877_666).fract() * 20.0 - 10.0).collect();
        let ys: Vec<f64> = (0..n).map(|i| ((i as f64) * 0.569_840_290).fract() * 12.0 - 6.0).collect();
        for radius in [0.0, 0.3, 1.7] {
            let csr = within(&xs, &ys, radius, None, None).unwrap();
            assert_eq!(rows(&csr), brute(&xs, &ys, radius));
        }
    }

    #[test]
    fn self_is_excluded_by_index_and_colocated_robots_count() {
        let csr = within(&[1.0, 1.0, 1.5], &[2.0, 2.0, 2.0], 0.5, None, None).unwrap();
        assert_eq!(rows(&csr), vec![vec![1, 2], vec![0, 2], vec![0, 1]]);
        assert_eq!(csr.distances[..2], [0.0, 0.5]);
    }

    #[test]
    fn field_of_view_and_cap() {
        // Robot 0 looks along +x with a 90 degree aperture.
        let xs = [0.0, 1.0, 0.0, -1.0, 0.5];
        let ys = [0.0, 0.2, 1.0, 0.0, -0.1];
        let view = FieldOfView { headings: &[0.0; 5], direction: 0.0, fov: PI / 2.0 };
        let csr = within(&xs, &ys, 2.0, Some(view), None).unwrap();
        assert_eq!(rows(&csr)[0], vec![1, 4]);
        let capped = within(&xs, &ys, 2.0, None, Some(1)).unwrap();
        assert_eq!(rows(&capped)[0], vec![4]);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(within(&[0.0], &[f64::NAN], 1.0, None, None).is_err());
        assert!(within(&[0.0], &[0.0], -1.0, None, None).is_err());
        assert!(within(&[0.0, 1.0], &[0.0], 1.0, None, None).is_err());
    }
}
