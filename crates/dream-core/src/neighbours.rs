//! Who is near whom: range and field-of-view queries for the whole swarm, as CSR rows.
//!
//! Robot j is a neighbour of robot i when j != i (by index, so co-located robots count),
//! `|p_j - p_i| <= radius` and, with a field of view, the direction from i to j lies within
//! `fov / 2` of `heading_i + direction` (a co-located robot is always seen). Each row lists
//! indices in increasing order; with `max_neighbours` only the nearest are kept (ties: lower
//! index first). The arithmetic matches the NumPy reference operation by operation.

use std::f64::consts::{PI, TAU};

use rayon::prelude::*;

use crate::csr::{check_offsets, Csr};
use crate::error::{check_finite, check_len, try_room, GeomError, Result};
use crate::grid::Grid;
use crate::parallel::{gather_rows, join_if, worth_spreading};

/// Rows below this count run on one thread: spawning costs more than it saves.
const PARALLEL_ROWS: usize = 512;

/// A sensor's field of view: robot i looks along `headings[i] + direction` with full aperture `fov`.
#[derive(Debug, Clone, Copy)]
pub struct FieldOfView<'a> {
    pub headings: &'a [f64],
    pub direction: f64,
    pub fov: f64,
}

impl Csr {
    /// Puts the blocks' rows in robot order.
    fn from_blocks(blocks: Vec<Block>, n: usize) -> Result<Self> {
        // Where each robot's row is: (block, start, length); robots not asked have none.
        let mut rows = vec![(0_usize, 0_usize, 0_usize); n];
        for (b, block) in blocks.iter().enumerate() {
            let mut from = 0;
            for (&i, &length) in block.robots.iter().zip(&block.lengths) {
                rows[i] = (b, from, length);
                from += length;
            }
        }
        let mut indptr = Vec::with_capacity(n + 1);
        indptr.push(0_i64);
        for &(_, _, length) in &rows {
            indptr.push(indptr[indptr.len() - 1] + length as i64);
        }
        let block = |i: usize| &blocks[rows[i].0];
        let (indices, distances) = join_if(
            worth_spreading(2 * indptr[n] as usize, 1.0),
            || gather_rows(&indptr, |i| (&block(i).indices[..], rows[i].1), "neighbour indices"),
            || gather_rows(&indptr, |i| (&block(i).distances[..], rows[i].1), "neighbour distances"),
        );
        Ok(Csr {
            indptr,
            indices: indices?,
            distances: distances?,
        })
    }
}

/// Wraps an angle to [-pi, pi) as NumPy's `(a + pi) % (2 pi) - pi` does.
pub(crate) fn wrap_angle(angle: f64) -> f64 {
    (angle + PI).rem_euclid(TAU) - PI
}

/// Neighbours of every robot at `(xs[i], ys[i])` within `radius` (inclusive), as CSR. With
/// `rows`, only the rows of robots i with `rows[i]` are found (the others stay empty): the
/// robots whose sensors read this step, say; every robot can still be their neighbour.
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
    rows: Option<&[bool]>,
) -> Result<Csr> {
    let n = xs.len();
    check_len("ys", n, ys.len())?;
    if let Some(rows) = rows {
        check_len("rows", n, rows.len())?;
    }
    check_finite("positions", xs)?;
    check_finite("positions", ys)?;
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(GeomError::InvalidParameter {
            arg: "radius",
            rule: ">= 0",
            got: radius,
        });
    }
    if let Some(v) = view {
        check_len("headings", n, v.headings.len())?;
        check_finite("headings", v.headings)?;
        if !v.direction.is_finite() {
            return Err(GeomError::InvalidParameter {
                arg: "direction",
                rule: "finite",
                got: v.direction,
            });
        }
        if v.fov.is_nan() || v.fov < 0.0 {
            return Err(GeomError::InvalidParameter {
                arg: "fov",
                rule: ">= 0",
                got: v.fov,
            });
        }
    }
    // Any cell >= radius finds every neighbour; radius 0 only needs identical points together.
    let grid = Grid::new(xs, ys, if radius > 0.0 { radius } else { 1.0 });
    let query = Query {
        grid: &grid,
        xs,
        ys,
        radius,
        radius_squared: radius_squared(radius),
        view,
        max_neighbours,
        rows,
    };
    // Robots are processed cell by cell: the robots of one cell share their candidates (the
    // 3x3 block of cells around it), gathered and sorted once.
    let cells: Vec<&[usize]> = grid
        .occupied()
        .filter(|members| query.asks(members).next().is_some())
        .collect();
    let asked = rows.map_or(n, |rows| rows.iter().filter(|&&r| r).count());
    let blocks: Vec<Block> = if asked >= PARALLEL_ROWS {
        let mut chunks = Vec::new();
        let (mut first, mut robots) = (0, 0);
        for (c, members) in cells.iter().enumerate() {
            robots += query.asks(members).count();
            if robots >= BLOCK_ROWS {
                chunks.push(first..c + 1);
                (first, robots) = (c + 1, 0);
            }
        }
        chunks.push(first..cells.len());
        chunks
            .into_par_iter()
            .map(|range| query.block(&cells[range]))
            .collect::<Result<_>>()?
    } else {
        vec![query.block(&cells)?]
    };
    Csr::from_blocks(blocks, n)
}

/// The range part of a neighbour query: a grid of the robots and the radius, shared by the
/// whole-swarm queries of this module and of HRVO.
pub(crate) struct Near<'a> {
    grid: Grid,
    xs: &'a [f64],
    ys: &'a [f64],
    radius: f64,
    /// A hair above radius^2: beyond it a point is surely out; below it `sqrt` decides exactly.
    radius_squared: f64,
}

impl<'a> Near<'a> {
    /// `xs`, `ys` finite and `radius` finite and >= 0 (the callers check).
    pub(crate) fn new(xs: &'a [f64], ys: &'a [f64], radius: f64) -> Self {
        // Any cell >= radius finds every neighbour; radius 0 only needs identical points together.
        let grid = Grid::new(xs, ys, if radius > 0.0 { radius } else { 1.0 });
        Self {
            grid,
            xs,
            ys,
            radius,
            radius_squared: radius_squared(radius),
        }
    }

    /// Robot indices in cell order: robots that are near in it are near in the plane.
    pub(crate) fn order(&self) -> &[usize] {
        self.grid.members()
    }

    /// Calls `visit(j, offset, distance)` for every robot j != i within the radius of robot i,
    /// in no particular order; `offset` is `p_j - p_i` and `distance` its length.
    ///
    /// `scratch` holds the candidates of one run between the two steps below.
    pub(crate) fn for_each(
        &self,
        i: usize,
        scratch: &mut Vec<(usize, f64)>,
        mut visit: impl FnMut(usize, [f64; 2], f64),
    ) {
        let (x, y) = (self.xs[i], self.ys[i]);
        let (sx, sy) = self.grid.sorted();
        let members = self.grid.members();
        self.grid.for_each_run_near(x, y, |run| {
            // No data-dependent branch in the hot loop: every candidate is written, the length
            // only advances for those whose squared distance may be in range. The buffer only
            // grows, so it is neither cleared nor filled per run.
            if scratch.len() < run.len() {
                scratch.resize(run.len(), (0, 0.0));
            }
            let mut count = 0;
            for (k, (&px, &py)) in run.clone().zip(sx[run.clone()].iter().zip(&sy[run])) {
                let (dx, dy) = (px - x, py - y);
                let squared = dx * dx + dy * dy;
                if let Some(slot) = scratch.get_mut(count) {
                    *slot = (k, squared);
                }
                count += usize::from(squared <= self.radius_squared);
            }
            for &(k, squared) in &scratch[..count] {
                let (j, distance) = (members[k], length(squared, sx[k] - x, sy[k] - y));
                if j != i && distance <= self.radius {
                    visit(j, [sx[k] - x, sy[k] - y], distance);
                }
            }
        });
    }
}

/// A hair above `radius^2`: beyond it a point is surely out of range; below it `sqrt` decides.
/// Never below the least normal number: subnormal squares round too coarsely for the margin.
pub(crate) fn radius_squared(radius: f64) -> f64 {
    (radius * radius).max(f64::MIN_POSITIVE) * (1.0 + 4.0 * f64::EPSILON)
}

/// The largest finite square whose root is within `radius` (finite, >= 0): for a finite
/// `squared`, `squared <= within_squared(radius)` exactly when `length(squared, ..) <= radius`
/// (`sqrt` is correctly rounded and never decreasing), so a count needs no root.
pub(crate) fn within_squared(radius: f64) -> f64 {
    let mut bound = (radius * radius).min(f64::MAX);
    while bound > 0.0 && bound.sqrt() > radius {
        bound = bound.next_down();
    }
    while bound < f64::MAX && bound.next_up().sqrt() <= radius {
        bound = bound.next_up();
    }
    bound
}

/// Whether the offset `(dx, dy)` lies within `radius` (inclusive), as every neighbour query
/// decides it; `radius_squared` is [`radius_squared`]`(radius)`.
#[inline]
pub(crate) fn in_range(dx: f64, dy: f64, radius: f64, radius_squared: f64) -> bool {
    let squared = dx * dx + dy * dy;
    squared <= radius_squared && length(squared, dx, dy) <= radius
}

/// `sqrt(squared)`, the length of `(dx, dy)` whose `squared` is `dx^2 + dy^2`; `hypot` when the
/// squares overflowed (beyond ~1.3e154 m), which a huge radius still lets through.
#[inline]
pub(crate) fn length(squared: f64, dx: f64, dy: f64) -> f64 {
    if squared.is_finite() {
        squared.sqrt()
    } else {
        dx.hypot(dy)
    }
}

/// Rows of `points` and `others`: row r is `points[points_offsets[r]..points_offsets[r + 1]]`
/// with `others[others_offsets[r]..others_offsets[r + 1]]`.
#[derive(Debug, Clone, Copy)]
pub struct RowsOf<'a> {
    pub points: &'a [[f64; 2]],
    pub points_offsets: &'a [i64],
    pub others: &'a [[f64; 2]],
    pub others_offsets: &'a [i64],
}

/// Which `points` lie farther than `distance` from every one of `others` in the same row (all
/// of them in a row with no others): each robot's detections that no message accounts for, say.
/// Distances are `hypot(p - q)`, as in the NumPy reference.
///
/// # Errors
/// Non-finite points, offsets that do not cut both arrays into as many rows, or a negative or
/// non-finite distance.
pub fn far_from(rows: RowsOf<'_>, distance: f64) -> Result<Vec<bool>> {
    let RowsOf {
        points,
        points_offsets,
        others,
        others_offsets,
    } = rows;
    check_finite("points", points.as_flattened())?;
    check_finite("others", others.as_flattened())?;
    check_offsets("points_offsets", points_offsets, points.len(), "points")?;
    check_offsets("others_offsets", others_offsets, others.len(), "others")?;
    check_len("others_offsets", points_offsets.len(), others_offsets.len())?;
    if !(distance.is_finite() && distance >= 0.0) {
        return Err(GeomError::InvalidParameter {
            arg: "distance",
            rule: ">= 0",
            got: distance,
        });
    }
    // A hair wider than `distance`: rounding cannot drop a match from the box.
    let margin = distance * (1.0 + 1e-9);
    let close = Closeness::new(distance);
    let row = |r: usize| -> Vec<bool> {
        let mine = &points[points_offsets[r] as usize..points_offsets[r + 1] as usize];
        let theirs = &others[others_offsets[r] as usize..others_offsets[r + 1] as usize];
        // Only the others near the box around this row's points can match: a robot in a crowd
        // hears hundreds of robots and sees a few.
        let (mut low, mut high) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in mine {
            for axis in 0..2 {
                low[axis] = low[axis].min(p[axis]);
                high[axis] = high[axis].max(p[axis]);
            }
        }
        let near: Vec<[f64; 2]> = theirs
            .iter()
            .filter(|q| (0..2).all(|axis| q[axis] >= low[axis] - margin && q[axis] <= high[axis] + margin))
            .copied()
            .collect();
        mine.iter()
            .map(|p| !near.iter().any(|q| close.within(*p, *q)))
            .collect()
    };
    let count = points_offsets.len() - 1;
    Ok(if points.len() + others.len() >= PARALLEL_POINTS {
        (0..count).into_par_iter().flat_map_iter(row).collect()
    } else {
        (0..count).flat_map(row).collect()
    })
}

/// The test of [`far_from`]: `hypot(p - q) <= distance`, with `hypot` only where the squared
/// distance is too close to call (it is the slow part).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Closeness {
    distance: f64,
    surely_in: f64,
    surely_out: f64,
}

impl Closeness {
    /// `distance` finite and >= 0 (the callers check).
    pub(crate) fn new(distance: f64) -> Self {
        let squared = distance * distance;
        let (surely_in, surely_out) = if squared > 1e-300 {
            (squared * (1.0 - 1e-9), squared * (1.0 + 1e-9))
        } else {
            (f64::NEG_INFINITY, f64::INFINITY) // squares of tiny distances lose their precision
        };
        Self {
            distance,
            surely_in,
            surely_out,
        }
    }

    pub(crate) fn within(&self, p: [f64; 2], q: [f64; 2]) -> bool {
        let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
        let square = dx * dx + dy * dy;
        square < self.surely_in || (square <= self.surely_out && dx.hypot(dy) <= self.distance)
    }
}

/// Points and others below this count are matched on one thread (a few microseconds of work).
const PARALLEL_POINTS: usize = 32_768;

/// Robots per parallel task (whole cells at a time).
const BLOCK_ROWS: usize = 256;

/// The rows of some robots, flat: row k belongs to robot `robots[k]`.
#[derive(Debug, Default)]
struct Block {
    robots: Vec<usize>,
    lengths: Vec<usize>,
    indices: Vec<i64>,
    distances: Vec<f64>,
}

/// One whole-swarm query's inputs, shared by all rows.
struct Query<'a> {
    grid: &'a Grid,
    xs: &'a [f64],
    ys: &'a [f64],
    radius: f64,
    /// A hair above radius^2: beyond it a point is surely out; below it `sqrt` decides exactly.
    radius_squared: f64,
    view: Option<FieldOfView<'a>>,
    max_neighbours: Option<usize>,
    rows: Option<&'a [bool]>,
}

/// Candidates shared by the robots of one cell, in increasing index order.
#[derive(Debug, Default)]
struct Candidates {
    indices: Vec<usize>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    /// Squared distances of the current robot's kept candidates: `(position in candidates, d^2)`.
    kept: Vec<(usize, f64)>,
}

impl Query<'_> {
    /// The robots of `members` whose rows are asked for.
    fn asks<'m>(&'m self, members: &'m [usize]) -> impl Iterator<Item = usize> + 'm {
        let rows = self.rows;
        members
            .iter()
            .copied()
            .filter(move |&i| rows.is_none_or(|rows| rows[i]))
    }

    /// # Errors
    /// [`GeomError::OutOfMemory`] when the rows do not fit.
    fn block(&self, cells: &[&[usize]]) -> Result<Block> {
        let mut out = Block::default();
        let mut near = Candidates::default();
        for members in cells {
            let first = members[0];
            near.indices.clear();
            self.grid
                .for_each_cell_near(self.xs[first], self.ys[first], |m| near.indices.extend_from_slice(m));
            near.indices.sort_unstable();
            near.xs.clear();
            near.ys.clear();
            near.xs.extend(near.indices.iter().map(|&j| self.xs[j]));
            near.ys.extend(near.indices.iter().map(|&j| self.ys[j]));
            for i in self.asks(members) {
                self.row(i, &mut near, &mut out)?;
            }
        }
        Ok(out)
    }

    fn row(&self, i: usize, near: &mut Candidates, out: &mut Block) -> Result<()> {
        let (x, y) = (self.xs[i], self.ys[i]);
        // No data-dependent branch in the hot loop: every candidate is written, the length only
        // advances for those whose squared distance may be in range. The buffer only grows.
        let Candidates { indices, xs, ys, kept } = near;
        if kept.len() < indices.len() {
            kept.resize(indices.len(), (0, 0.0));
        }
        let mut count = 0;
        for (k, ((&cx, &cy), &j)) in xs.iter().zip(ys.iter()).zip(indices.iter()).enumerate() {
            let (dx, dy) = (cx - x, cy - y);
            let squared = dx * dx + dy * dy;
            if let Some(slot) = kept.get_mut(count) {
                *slot = (k, squared);
            }
            count += usize::from((squared <= self.radius_squared) & (j != i));
        }
        let start = out.indices.len();
        try_room(&mut out.indices, count, "neighbour indices")?;
        try_room(&mut out.distances, count, "neighbour distances")?;
        for &(k, squared) in &kept[..count] {
            let distance = length(squared, xs[k] - x, ys[k] - y);
            if distance > self.radius {
                continue;
            }
            if let Some(v) = self.view {
                let relative = wrap_angle((ys[k] - y).atan2(xs[k] - x) - (v.headings[i] + v.direction));
                if !(relative.abs() <= v.fov / 2.0 || distance == 0.0) {
                    continue;
                }
            }
            out.indices.push(indices[k] as i64);
            out.distances.push(distance);
        }
        if let Some(limit) = self.max_neighbours.filter(|&limit| out.indices.len() - start > limit) {
            let mut row: Vec<(i64, f64)> = out.indices[start..]
                .iter()
                .copied()
                .zip(out.distances[start..].iter().copied())
                .collect();
            row.sort_unstable_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            row.truncate(limit);
            row.sort_unstable_by_key(|&(j, _)| j);
            out.indices.truncate(start);
            out.distances.truncate(start);
            for (j, d) in row {
                out.indices.push(j);
                out.distances.push(d);
            }
        }
        out.robots.push(i);
        out.lengths.push(out.indices.len() - start);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn within_squared_decides_as_the_root_does() {
        // Squares a few ulps either side of each radius's bound, and radii at the extremes.
        for radius in [
            0.0,
            5e-324,
            1e-160,
            0.1,
            0.3,
            0.7,
            1.0,
            2.5,
            1e150,
            1.3e154,
            1e200,
            f64::MAX,
        ] {
            let bound = within_squared(radius);
            assert!(bound.sqrt() <= radius, "{radius}: the bound's root is out");
            let mut squared = bound;
            for _ in 0..4 {
                squared = squared.next_down();
            }
            for _ in 0..9 {
                if squared >= 0.0 {
                    assert_eq!(
                        squared <= bound,
                        squared.sqrt() <= radius,
                        "radius {radius}, squared {squared}"
                    );
                }
                squared = squared.next_up();
            }
        }
    }

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
        csr.indptr
            .windows(2)
            .map(|w| csr.indices[w[0] as usize..w[1] as usize].to_vec())
            .collect()
    }

    #[test]
    fn matches_brute_force_on_a_scatter() {
        // A deterministic scatter (no RNG dependency): a quasi-random sequence.
        let n = 3000;
        let xs: Vec<f64> = (0..n)
            .map(|i| ((i as f64) * 0.754_877_666).fract() * 20.0 - 10.0)
            .collect();
        let ys: Vec<f64> = (0..n)
            .map(|i| ((i as f64) * 0.569_840_290).fract() * 12.0 - 6.0)
            .collect();
        for radius in [0.0, 0.3, 1.7] {
            let csr = within(&xs, &ys, radius, None, None, None).unwrap();
            assert_eq!(rows(&csr), brute(&xs, &ys, radius));
        }
    }

    #[test]
    fn self_is_excluded_by_index_and_colocated_robots_count() {
        let csr = within(&[1.0, 1.0, 1.5], &[2.0, 2.0, 2.0], 0.5, None, None, None).unwrap();
        assert_eq!(rows(&csr), vec![vec![1, 2], vec![0, 2], vec![0, 1]]);
        assert_eq!(csr.distances[..2], [0.0, 0.5]);
    }

    #[test]
    fn field_of_view_and_cap() {
        // Robot 0 looks along +x with a 90 degree aperture.
        let xs = [0.0, 1.0, 0.0, -1.0, 0.5];
        let ys = [0.0, 0.2, 1.0, 0.0, -0.1];
        let view = FieldOfView {
            headings: &[0.0; 5],
            direction: 0.0,
            fov: PI / 2.0,
        };
        let csr = within(&xs, &ys, 2.0, Some(view), None, None).unwrap();
        assert_eq!(rows(&csr)[0], vec![1, 4]);
        let capped = within(&xs, &ys, 2.0, None, Some(1), None).unwrap();
        assert_eq!(rows(&capped)[0], vec![4]);
    }

    #[test]
    fn rows_leave_the_others_empty() {
        let n = 500;
        let xs: Vec<f64> = (0..n).map(|i| ((i as f64) * 0.754_877_666).fract() * 6.0).collect();
        let ys: Vec<f64> = (0..n).map(|i| ((i as f64) * 0.569_840_290).fract() * 4.0).collect();
        let asked: Vec<bool> = (0..n).map(|i| i % 3 == 1).collect();
        let all = rows(&within(&xs, &ys, 0.7, None, None, None).unwrap());
        let some = rows(&within(&xs, &ys, 0.7, None, None, Some(&asked)).unwrap());
        for i in 0..n {
            assert_eq!(some[i], if asked[i] { all[i].clone() } else { vec![] });
        }
        assert!(within(&xs, &ys, 0.7, None, None, Some(&asked[1..])).is_err());
    }

    #[test]
    fn far_from_matches_within_rows_only() {
        let points = [[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]];
        let others = [[0.05, 0.0], [5.0, 5.05], [1.0, 0.1]];
        let rows = RowsOf {
            points: &points,
            points_offsets: &[0, 2, 3],
            others: &others,
            others_offsets: &[0, 2, 3],
        };
        // Row 0 hears (0.05, 0) and (5, 5.05): robot 0 matched, robot 1 not (its match is in row 1).
        assert_eq!(far_from(rows, 0.08).unwrap(), vec![false, true, true]);
        assert_eq!(far_from(rows, 0.1).unwrap(), vec![false, true, true]);
        let inclusive = RowsOf {
            points_offsets: &[0, 3],
            others_offsets: &[0, 3],
            ..rows
        };
        assert_eq!(far_from(inclusive, 0.1).unwrap(), vec![false, false, false]);
        assert!(far_from(
            RowsOf {
                points_offsets: &[0, 3],
                ..rows
            },
            0.1
        )
        .is_err());
        assert!(far_from(rows, -1.0).is_err());
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(within(&[0.0], &[f64::NAN], 1.0, None, None, None).is_err());
        assert!(within(&[0.0], &[0.0], -1.0, None, None, None).is_err());
        assert!(within(&[0.0, 1.0], &[0.0], 1.0, None, None, None).is_err());
    }
}
