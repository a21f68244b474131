//! Uniform grid over the plane: the spatial index behind every "who is near whom" query.
//!
//! Cells are squares a hair larger than the query distance `reach`, so every point within
//! `reach` of a point lies in the 3x3 block of cells around it even when rounding puts a
//! computed distance of exactly `reach` across two cell borders; a whole-swarm query costs
//! O(n k), not O(n^2). Points are
//! bucketed by a counting sort into CSR order. When the occupied bounding box has few cells
//! (robots spread over an arena: the usual case) the cell table is a dense array. A swarm spread
//! thin over a large arena (hrvo-circle's ring of 10,000 robots, 1.3 km wide) has too many cells
//! but few columns: each column lists its occupied cells by row, found by binary search. Else
//! (a few far-flung robots) a hash map keeps memory O(n).
//!
//! The coordinates are also stored in cell order, and in the dense table the cells of one
//! column are consecutive, so the 3x3 block around a point is three contiguous runs: queries
//! stream through memory instead of jumping to each neighbour's index.

use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::ops::Range;

use crate::parallel::{map_range, split, worth_spreading, TASK_ITEMS};

/// Points bucketed by cell; a cell's points are contiguous in `members`, in increasing index.
#[derive(Debug, Clone)]
pub struct Grid {
    cell: f64,
    table: CellTable,
    starts: Vec<usize>,
    members: Vec<usize>,
    /// `xs[members[k]]` and `ys[members[k]]`: the coordinates in cell order.
    sorted_xs: Vec<f64>,
    sorted_ys: Vec<f64>,
}

#[derive(Debug, Clone)]
enum CellTable {
    /// Slot of cell `(cx, cy)` is `(cx - x0) * rows + (cy - y0)`.
    Dense {
        x0: i64,
        y0: i64,
        columns: i64,
        rows: i64,
    },
    /// The occupied cells column by column, each column's by row: cell `slot` is in row
    /// `rows_of[slot]`, and column `cx` holds the slots `firsts[cx - x0]..firsts[cx - x0 + 1]`.
    Columns {
        x0: i64,
        firsts: Vec<usize>,
        rows_of: Vec<i64>,
    },
    Sparse(FxHashMap<(i64, i64), usize>),
}

impl Grid {
    /// Buckets the points `(xs[i], ys[i])` for queries within `reach`.
    ///
    /// `reach` must be finite and > 0 and the coordinates finite (the callers check).
    pub fn new(xs: &[f64], ys: &[f64], reach: f64) -> Self {
        Self::build(xs, ys, reach * (1.0 + 1e-9), false)
    }

    /// As [`Grid::new`], with cells as wide as keeps the table of cells dense (robots spread
    /// over an arena, each cell far smaller than the space a robot has: the collision search's),
    /// up to twice as wide, or wider while the cells hold few points each. For queries whose
    /// answer does not depend on the order in which the points of a block come: looking cells
    /// up in the dense table costs a fraction of the binary searches of the column table, which
    /// a million robots' collision search spent a third of its time in.
    pub fn loose(xs: &[f64], ys: &[f64], reach: f64) -> Self {
        Self::build(xs, ys, reach * (1.0 + 1e-9), true)
    }

    fn build(xs: &[f64], ys: &[f64], cell: f64, loose: bool) -> Self {
        let n = xs.len();
        let key = |i: usize| cell_of(xs[i], ys[i], cell);
        // `cell_of` grows with each coordinate, so the corner cells are those of the least and
        // the greatest coordinates: no table of every point's cell (16 bytes a point) to scan.
        let (low_x, high_x) = extent(xs);
        let (low_y, high_y) = extent(ys);
        let ((x0, y0), (x1, y1)) = if n == 0 {
            ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN))
        } else {
            (cell_of(low_x, low_y, cell), cell_of(high_x, high_y, cell))
        };
        let columns = x1.checked_sub(x0).and_then(|w| w.checked_add(1)).unwrap_or(i64::MAX);
        let rows = y1.checked_sub(y0).and_then(|h| h.checked_add(1)).unwrap_or(i64::MAX);
        let budget = 4 * n as i64 + 1024;
        let cells = columns.saturating_mul(rows);
        if loose && cells > budget {
            // Wider cells by the factor that brings the table within its budget (and a hair more).
            // Up to twice as wide, a cell holds at most about four times the points. Wider still,
            // a crowd amid empty space (a packed cluster and one robot far off) could put
            // thousands in one cell: then the cells stay `cell` wide, in the column or sparse table.
            let wider = Self::build(xs, ys, cell * (cells as f64 / budget as f64).sqrt() * 1.01, false);
            if cells <= 4 * budget || wider.crowding() <= CROWDED * n {
                return wider;
            }
        }
        let (table, starts, members) = if n > 0 && columns <= budget && rows <= budget && columns * rows <= budget {
            let slots = map_range(n, 3.0, |i| {
                let (cx, cy) = key(i);
                ((cx - x0) * rows + (cy - y0)) as usize
            });
            let (starts, members) = bucket(&slots, (columns * rows) as usize);
            (CellTable::Dense { x0, y0, columns, rows }, starts, members)
        } else if n > 0 && columns <= budget {
            // A swarm spread thin over a wide arena (a ring hundreds of metres across): too
            // many cells for a table of them all, few columns.
            let (by_column, order) = bucket(&map_range(n, 3.0, |i| (key(i).0 - x0) as usize), columns as usize);
            // (row, point) in column order, then runs of columns of about COLUMN_POINTS
            // points each, one task a run (a million robots on a ring or a line make a
            // million columns): each column sorted by row (stable: increasing index per
            // cell) and its cells listed.
            let mut entries: Vec<(i64, usize)> = map_range(order.len(), 3.0, |k| (key(order[k]).1, order[k]));
            let mut runs = vec![0];
            for (c, &first) in by_column.iter().enumerate().skip(1) {
                if first - by_column[runs[runs.len() - 1]] >= COLUMN_POINTS || c == columns as usize {
                    runs.push(c);
                }
            }
            let cut: Vec<usize> = runs.iter().map(|&c| by_column[c]).collect();
            let tables: Vec<(Vec<usize>, Vec<i64>, Vec<usize>)> = split(&mut entries, &cut)
                .into_par_iter()
                .zip(runs.par_windows(2))
                .map(|(mut piece, run)| {
                    let (mut firsts, mut rows_of, mut starts) = (Vec::new(), Vec::new(), Vec::new());
                    for column in run[0]..run[1] {
                        let (first, size) = (by_column[column], by_column[column + 1] - by_column[column]);
                        let entries;
                        (entries, piece) = std::mem::take(&mut piece).split_at_mut(size);
                        entries.sort_by_key(|entry| entry.0);
                        firsts.push(rows_of.len());
                        let mut at = first;
                        for cell in entries.chunk_by(|a, b| a.0 == b.0) {
                            rows_of.push(cell[0].0);
                            starts.push(at);
                            at += cell.len();
                        }
                    }
                    (firsts, rows_of, starts)
                })
                .collect();
            let (mut firsts, mut rows_of, mut starts) = (Vec::new(), Vec::new(), Vec::new());
            for (run_firsts, run_rows, run_starts) in tables {
                let before = rows_of.len();
                firsts.extend(run_firsts.iter().map(|f| f + before));
                rows_of.extend(run_rows);
                starts.extend(run_starts);
            }
            firsts.push(rows_of.len());
            starts.push(n);
            let members = map_range(entries.len(), 1.0, |k| entries[k].1);
            (CellTable::Columns { x0, firsts, rows_of }, starts, members)
        } else {
            let mut index: FxHashMap<(i64, i64), usize> = FxHashMap::with_capacity_and_hasher(n, Default::default());
            let slots: Vec<usize> = (0..n)
                .map(|i| {
                    let next = index.len();
                    *index.entry(key(i)).or_insert(next)
                })
                .collect();
            let (starts, members) = bucket(&slots, index.len());
            (CellTable::Sparse(index), starts, members)
        };
        let sorted_xs = map_range(members.len(), 1.0, |k| xs[members[k]]);
        let sorted_ys = map_range(members.len(), 1.0, |k| ys[members[k]]);
        Self {
            cell,
            table,
            starts,
            members,
            sorted_xs,
            sorted_ys,
        }
    }

    /// The cell of `(x, y)`: points with the same cell share their 3x3 block.
    pub fn cell_of(&self, x: f64, y: f64) -> (i64, i64) {
        cell_of(x, y, self.cell)
    }

    /// Point indices in cell order: position `k` of a run holds point `members()[k]`.
    pub fn members(&self) -> &[usize] {
        &self.members
    }

    /// The points' coordinates in cell order (`xs`, `ys`).
    pub fn sorted(&self) -> (&[f64], &[f64]) {
        (&self.sorted_xs, &self.sorted_ys)
    }

    /// Calls `visit(run)` with ranges of positions in cell order (see [`Grid::members`]) that
    /// together cover the 3x3 block of cells around `(x, y)`, each position once: three runs
    /// (one per column) in the dense table, one per cell in the sparse one.
    pub fn for_each_run_near(&self, x: f64, y: f64, mut visit: impl FnMut(Range<usize>)) {
        let (cx, cy) = cell_of(x, y, self.cell);
        match &self.table {
            CellTable::Dense { x0, y0, columns, rows } => {
                // Saturated arithmetic only ever lands outside the table, which is skipped.
                let low = cy.saturating_sub(1).saturating_sub(*y0).max(0);
                let high = cy.saturating_add(1).saturating_sub(*y0).min(rows - 1);
                if low > high {
                    return;
                }
                // Distinct columns only: near i64::MAX, cx + 1 saturates to cx itself.
                for ax in cx.saturating_sub(1)..=cx.saturating_add(1) {
                    let column = ax.saturating_sub(*x0);
                    if (0..*columns).contains(&column) {
                        let first = (column * rows + low) as usize;
                        let last = (column * rows + high) as usize;
                        let run = self.starts[first]..self.starts[last + 1];
                        if !run.is_empty() {
                            visit(run);
                        }
                    }
                }
            }
            CellTable::Columns { .. } => {
                for ax in cx.saturating_sub(1)..=cx.saturating_add(1) {
                    let cells = self.cells_in_column(ax, cy.saturating_sub(1), cy.saturating_add(1));
                    if !cells.is_empty() {
                        visit(self.starts[cells.start]..self.starts[cells.end]);
                    }
                }
            }
            CellTable::Sparse(index) => {
                for (ax, ay) in block(cx, cy) {
                    if let Some(&slot) = index.get(&(ax, ay)) {
                        visit(self.starts[slot]..self.starts[slot + 1]);
                    }
                }
            }
        }
    }

    /// The slots of the occupied cells of column `cx` in rows `low..=high` (consecutive slots).
    fn cells_in_column(&self, cx: i64, low: i64, high: i64) -> Range<usize> {
        let CellTable::Columns { x0, firsts, rows_of } = &self.table else {
            return 0..0;
        };
        let Some(column) = cx
            .checked_sub(*x0)
            .filter(|&c| (0..firsts.len() as i64 - 1).contains(&c))
        else {
            return 0..0;
        };
        let (first, last) = (firsts[column as usize], firsts[column as usize + 1]);
        let rows = &rows_of[first..last];
        first + rows.partition_point(|&row| row < low)..first + rows.partition_point(|&row| row <= high)
    }

    /// Calls `visit(run)` with ranges of positions in cell order (see [`Grid::members`]) that
    /// together cover every cell meeting the square of half-side `half` around `(x, y)`, each
    /// position once: a superset of the points within `half` of it, however far that reaches.
    pub fn for_each_run_within(&self, x: f64, y: f64, half: f64, mut visit: impl FnMut(Range<usize>)) {
        // A hair wider than asked: rounding `x - half` cannot drop a point on the square's edge.
        let pad = half * 1e-9 + (x.abs() + y.abs()) * 1e-12;
        let (x0_cell, y0_cell) = cell_of(x - half - pad, y - half - pad, self.cell);
        let (x1_cell, y1_cell) = cell_of(x + half + pad, y + half + pad, self.cell);
        match &self.table {
            CellTable::Dense { x0, y0, columns, rows } => {
                let low = y0_cell.saturating_sub(*y0).max(0);
                let high = y1_cell.saturating_sub(*y0).min(rows - 1);
                let first = x0_cell.saturating_sub(*x0).max(0);
                let last = x1_cell.saturating_sub(*x0).min(columns - 1);
                if low > high {
                    return;
                }
                for column in first..=last {
                    let run =
                        self.starts[(column * rows + low) as usize]..self.starts[(column * rows + high) as usize + 1];
                    if !run.is_empty() {
                        visit(run);
                    }
                }
            }
            CellTable::Columns { x0, firsts, .. } => {
                let first = x0_cell.max(*x0);
                let last = x1_cell.min(x0.saturating_add(firsts.len() as i64 - 2));
                if first <= last {
                    for ax in first..=last {
                        let cells = self.cells_in_column(ax, y0_cell, y1_cell);
                        if !cells.is_empty() {
                            visit(self.starts[cells.start]..self.starts[cells.end]);
                        }
                    }
                }
            }
            CellTable::Sparse(index) => {
                let width = i128::from(x1_cell) - i128::from(x0_cell) + 1;
                let height = i128::from(y1_cell) - i128::from(y0_cell) + 1;
                if width.saturating_mul(height) > index.len() as i128 {
                    // Fewer occupied cells than cells in the square: visit them all.
                    for slot in 0..index.len() {
                        let run = self.starts[slot]..self.starts[slot + 1];
                        if !run.is_empty() {
                            visit(run);
                        }
                    }
                    return;
                }
                for ax in x0_cell..=x1_cell {
                    for ay in y0_cell..=y1_cell {
                        if let Some(&slot) = index.get(&(ax, ay)) {
                            visit(self.starts[slot]..self.starts[slot + 1]);
                        }
                    }
                }
            }
        }
    }

    /// Calls `visit(j)` for every point in the 3x3 block of cells around `(x, y)`: a superset
    /// of the points within `reach` of it.
    pub fn for_each_near(&self, x: f64, y: f64, mut visit: impl FnMut(usize)) {
        self.for_each_cell_near(x, y, |members| members.iter().for_each(|&j| visit(j)));
    }

    /// Calls `visit(members)` for each non-empty cell of the 3x3 block around `(x, y)`; each
    /// slice lists point indices in increasing order.
    pub fn for_each_cell_near(&self, x: f64, y: f64, mut visit: impl FnMut(&[usize])) {
        let (cx, cy) = cell_of(x, y, self.cell);
        for (ax, ay) in block(cx, cy) {
            if let Some(slot) = self.slot(ax, ay) {
                visit(&self.members[self.starts[slot]..self.starts[slot + 1]]);
            }
        }
    }

    /// The sum over the cells of the square of the number of points in each: `n` when each
    /// point has a cell of its own, about `n` times a cell's points in a crowd.
    fn crowding(&self) -> usize {
        self.starts.par_windows(2).map(|w| (w[1] - w[0]).pow(2)).sum()
    }

    /// The points of each occupied cell (a cell's points are contiguous, in increasing index).
    pub fn occupied(&self) -> impl Iterator<Item = &[usize]> + '_ {
        self.cell_runs().map(|run| &self.members[run])
    }

    /// The positions in cell order (see [`Grid::members`]) of each occupied cell, in cell order.
    pub fn cell_runs(&self) -> impl Iterator<Item = Range<usize>> + '_ {
        self.starts.windows(2).filter(|w| w[1] > w[0]).map(|w| w[0]..w[1])
    }

    /// [`Grid::cell_runs`] on every core, `min_cells` cells (occupied or not) a task: the table
    /// of a million robots' collision search has millions of cells to go through.
    pub fn par_cell_runs(&self, min_cells: usize) -> impl ParallelIterator<Item = Range<usize>> + '_ {
        self.starts
            .par_windows(2)
            .with_min_len(min_cells)
            .filter(|w| w[1] > w[0])
            .map(|w| w[0]..w[1])
    }

    fn slot(&self, cx: i64, cy: i64) -> Option<usize> {
        match &self.table {
            CellTable::Dense { x0, y0, columns, rows } => {
                let (i, j) = (cx.checked_sub(*x0)?, cy.checked_sub(*y0)?);
                (0..*columns).contains(&i).then_some(())?;
                (0..*rows).contains(&j).then_some(())?;
                Some((i * rows + j) as usize)
            }
            CellTable::Columns { .. } => {
                let cells = self.cells_in_column(cx, cy, cy);
                (!cells.is_empty()).then_some(cells.start)
            }
            CellTable::Sparse(index) => index.get(&(cx, cy)).copied(),
        }
    }
}

/// The most [`Grid::crowding`] a point of a loose grid's cells widened more than twice: a
/// swarm spread over an arena gives 1.0-1.3 (the built-in experiments at 100,000 robots),
/// where the dense table's lookups beat the column table's binary searches by 1.1-1.4x.
const CROWDED: usize = 4;

/// Points whose columns one task sorts out when building the column table.
const COLUMN_POINTS: usize = 16_384;

/// Counting sort of point indices by `slots[point]` into `cells` buckets: the buckets' starts
/// (`cells + 1` of them) and the points in bucket order, each bucket in increasing index. On
/// every core for many points ([`bucket_in_bands`]); the same answer either way.
fn bucket(slots: &[usize], cells: usize) -> (Vec<usize>, Vec<usize>) {
    if slots.len() >= PARALLEL_BUCKET && rayon::current_num_threads() > 1 {
        bucket_in_bands(slots, cells)
    } else {
        bucket_on_one_thread(slots, cells)
    }
}

fn bucket_on_one_thread(slots: &[usize], cells: usize) -> (Vec<usize>, Vec<usize>) {
    // Each bucket's end, then filled from its end with the points taken last to first, which
    // leaves each bucket's start (and no second table of the size of the cells').
    let mut starts = vec![0_usize; cells + 1];
    for &slot in slots {
        starts[slot] += 1;
    }
    for s in 1..=cells {
        starts[s] += starts[s - 1];
    }
    let mut members = vec![0; slots.len()];
    for (point, &slot) in slots.iter().enumerate().rev() {
        starts[slot] -= 1;
        members[starts[slot]] = point;
    }
    (starts, members)
}

/// Points from which [`bucket`] sorts on every core: one thread's counting sort of a million
/// points scatters them over millions of cells, a cache miss each (by estimate, about half of
/// `validate` on 16 threads).
const PARALLEL_BUCKET: usize = 1 << 17;

/// Points a task of [`bucket_in_bands`] takes apart by band.
const BAND_CHUNK: usize = 1 << 15;

/// [`bucket`] on every core, in two passes. The cells are cut into bands of consecutive cells
/// (about 1,024 bands). Each chunk of points is sorted by band on its own. Then each band
/// gathers its points from the chunks, in chunk order, and counts them into its cells, writing
/// its own stretch of the starts and of the members. Every pass keeps the points' order within a
/// bucket, so each bucket lists them by increasing index, as the one-thread sort does.
fn bucket_in_bands(slots: &[usize], cells: usize) -> (Vec<usize>, Vec<usize>) {
    let shift = (cells / 1024).max(1).ilog2() as usize;
    let bands = (cells >> shift) + 1;
    // Each chunk's points grouped by band (its own counting sort), with where each band starts.
    let chunks: Vec<(Vec<usize>, Vec<usize>)> = slots
        .par_chunks(BAND_CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut firsts = vec![0_usize; bands + 1];
            for &slot in chunk {
                firsts[(slot >> shift) + 1] += 1;
            }
            for b in 1..=bands {
                firsts[b] += firsts[b - 1];
            }
            let mut next = firsts.clone();
            let mut grouped = vec![0_usize; chunk.len()];
            for (k, &slot) in chunk.iter().enumerate() {
                let band = slot >> shift;
                grouped[next[band]] = c * BAND_CHUNK + k;
                next[band] += 1;
            }
            (firsts, grouped)
        })
        .collect();
    // Where each band's points start among all the points.
    let mut band_starts = vec![0_usize; bands + 1];
    for b in 0..bands {
        let size: usize = chunks.iter().map(|(firsts, _)| firsts[b + 1] - firsts[b]).sum();
        band_starts[b + 1] = band_starts[b] + size;
    }
    let mut starts = vec![0_usize; cells + 1];
    let mut members = vec![0_usize; slots.len()];
    let cell_bounds: Vec<usize> = (0..=bands).map(|b| (b << shift).min(cells)).collect();
    split(&mut members, &band_starts)
        .into_par_iter()
        .zip(split(&mut starts[..cells], &cell_bounds))
        .enumerate()
        .for_each(|(b, (band_members, band_cells))| {
            let first_cell = b << shift;
            let points = || {
                chunks
                    .iter()
                    .flat_map(move |(firsts, grouped)| grouped[firsts[b]..firsts[b + 1]].iter().copied())
            };
            for point in points() {
                band_cells[slots[point] - first_cell] += 1;
            }
            let mut at = band_starts[b];
            for count in band_cells.iter_mut() {
                (*count, at) = (at, at + *count);
            }
            let mut next = band_cells.to_vec();
            for point in points() {
                let cell = slots[point] - first_cell;
                band_members[next[cell] - band_starts[b]] = point;
                next[cell] += 1;
            }
        });
    starts[cells] = slots.len();
    (starts, members)
}

/// The least and the greatest of `values` (infinities for none), on every core for many.
fn extent(values: &[f64]) -> (f64, f64) {
    let fold = |(low, high): (f64, f64), &v: &f64| (low.min(v), high.max(v));
    let merge = |a: (f64, f64), b: (f64, f64)| (a.0.min(b.0), a.1.max(b.1));
    let none = (f64::INFINITY, f64::NEG_INFINITY);
    if worth_spreading(values.len(), 0.5) {
        values
            .par_iter()
            .with_min_len(TASK_ITEMS)
            .fold(|| none, fold)
            .reduce(|| none, merge)
    } else {
        values.iter().fold(none, fold)
    }
}

/// The distinct cells of the 3x3 block around cell `(cx, cy)`: fewer at the saturated edges of
/// i64, where `cx + 1` is `cx` itself (listing it twice would report its points twice).
fn block(cx: i64, cy: i64) -> impl Iterator<Item = (i64, i64)> {
    (cx.saturating_sub(1)..=cx.saturating_add(1))
        .flat_map(move |ax| (cy.saturating_sub(1)..=cy.saturating_add(1)).map(move |ay| (ax, ay)))
}

fn cell_of(x: f64, y: f64, cell: f64) -> (i64, i64) {
    (floor(x / cell), floor(y / cell))
}

/// `value.floor() as i64` without the call to libm's `floor` (plain x86-64 has no rounding
/// instruction). `as` saturates for huge coordinates, which only merges far-away cells.
fn floor(value: f64) -> i64 {
    let truncated = value as i64;
    truncated.saturating_sub(i64::from((truncated as f64) > value))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_banded_counting_sort_is_the_one_thread_sort() {
        let mut state = 12345_u64;
        let mut next = |below: usize| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as usize) % below
        };
        for (points, cells) in [
            (1, 1),
            (300_000, 7),
            (300_000, 1024),
            (300_000, 4_000_017),
            (70_000, 200_000),
        ] {
            let slots: Vec<usize> = (0..points).map(|_| next(cells)).collect();
            assert_eq!(
                bucket_in_bands(&slots, cells),
                bucket_on_one_thread(&slots, cells),
                "{points} in {cells}"
            );
        }
    }

    fn near(grid: &Grid, x: f64, y: f64) -> Vec<usize> {
        let mut seen = Vec::new();
        grid.for_each_near(x, y, |j| seen.push(j));
        seen.sort();
        seen
    }

    #[test]
    fn near_points_are_visited_once() {
        let xs = [0.0, 0.05, 0.3, -0.09, 5.0];
        let ys = [0.0, 0.02, 0.0, 0.0, 5.0];
        let grid = Grid::new(&xs, &ys, 0.1);
        assert_eq!(near(&grid, 0.0, 0.0), vec![0, 1, 3]);
        assert_eq!(near(&grid, 5.0, 5.0), vec![4]);
    }

    #[test]
    fn far_flung_points_use_the_sparse_table() {
        let xs = [0.0, 1e12, -1e12, 1e12 + 0.05];
        let ys = [0.0, 1e12, 0.0, 1e12];
        let grid = Grid::new(&xs, &ys, 0.1);
        assert!(matches!(grid.table, CellTable::Sparse(_)));
        assert_eq!(near(&grid, 1e12, 1e12), vec![1, 3]);
        assert_eq!(near(&grid, 0.0, 0.0), vec![0]);
    }

    #[test]
    fn a_thin_ring_uses_the_column_table_and_finds_every_point_of_each_block() {
        let cell = 0.25;
        let (xs, ys): (Vec<f64>, Vec<f64>) = (0..2000)
            .map(|i| {
                let angle = i as f64 * std::f64::consts::TAU / 2000.0;
                (
                    300.0 * angle.cos() + (i as f64 * 0.754_877_666).fract() * 0.3,
                    190.0 * angle.sin(),
                )
            })
            .unzip();
        let grid = Grid::new(&xs, &ys, cell);
        assert!(matches!(grid.table, CellTable::Columns { .. }));
        let key = |x: f64, y: f64| cell_of(x, y, cell * (1.0 + 1e-9));
        let queries = xs
            .iter()
            .zip(&ys)
            .map(|(&x, &y)| (x, y))
            .chain([(0.0, 0.0), (300.2, 0.1), (-1e4, 3.0)]);
        for (x, y) in queries {
            let (cx, cy) = key(x, y);
            let expected: Vec<usize> = (0..xs.len())
                .filter(|&j| {
                    let (jx, jy) = key(xs[j], ys[j]);
                    (jx - cx).abs() <= 1 && (jy - cy).abs() <= 1
                })
                .collect();
            assert_eq!(near(&grid, x, y), expected, "around ({x}, {y})");
            assert_eq!(near_by_runs(&grid, x, y), expected, "runs around ({x}, {y})");
            let mut within = Vec::new();
            grid.for_each_run_within(x, y, 0.6, |run| within.extend(run.map(|k| grid.members()[k])));
            within.sort_unstable();
            let inside: Vec<usize> = (0..xs.len())
                .filter(|&j| (xs[j] - x).abs() <= 0.6 && (ys[j] - y).abs() <= 0.6)
                .collect();
            assert!(
                inside.iter().all(|j| within.binary_search(j).is_ok()),
                "square around ({x}, {y})"
            );
        }
        // Cells list their points in increasing index, as the other tables do.
        assert!(grid.occupied().all(|members| members.windows(2).all(|w| w[0] < w[1])));
    }

    #[test]
    fn a_ring_of_many_points_builds_its_column_table_in_runs_and_finds_every_block() {
        // More points than one run of columns holds (COLUMN_POINTS), so that several tasks
        // build the table.
        let (n, cell) = (3 * COLUMN_POINTS + 123, 0.25);
        let (xs, ys): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|i| {
                let angle = i as f64 * std::f64::consts::TAU / n as f64;
                (
                    3000.0 * angle.cos(),
                    1900.0 * angle.sin() + (i as f64 * 0.569_840_29).fract() * 0.4,
                )
            })
            .unzip();
        let grid = Grid::new(&xs, &ys, cell);
        assert!(matches!(grid.table, CellTable::Columns { .. }));
        let mut all = grid.members().to_vec();
        all.sort_unstable();
        assert!(all.iter().copied().eq(0..n), "every point once");
        assert!(grid.occupied().all(|members| members.windows(2).all(|w| w[0] < w[1])));
        let key = |x: f64, y: f64| cell_of(x, y, cell * (1.0 + 1e-9));
        for q in (0..n).step_by(331) {
            let (cx, cy) = key(xs[q], ys[q]);
            let expected: Vec<usize> = (0..n)
                .filter(|&j| {
                    let (jx, jy) = key(xs[j], ys[j]);
                    (jx - cx).abs() <= 1 && (jy - cy).abs() <= 1
                })
                .collect();
            assert_eq!(near(&grid, xs[q], ys[q]), expected, "around point {q}");
        }
    }

    #[test]
    fn a_loose_grid_widens_its_cells_to_stay_dense_and_misses_no_neighbour() {
        // Points spread so that cells of `reach` would make about twice the dense budget.
        let (n, reach) = (5000, 0.1);
        let side = (8.0 * n as f64).sqrt() * reach;
        let (xs, ys): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|i| {
                let i = i as f64;
                ((i * 0.754_877_666).fract() * side, (i * 0.569_840_29).fract() * side)
            })
            .unzip();
        assert!(matches!(Grid::new(&xs, &ys, reach).table, CellTable::Columns { .. }));
        let grid = Grid::loose(&xs, &ys, reach);
        assert!(matches!(grid.table, CellTable::Dense { .. }));
        assert!(grid.cell > reach && grid.cell <= 2.0 * reach * 1.02);
        for q in (0..n).step_by(7) {
            let found = near(&grid, xs[q], ys[q]);
            for j in 0..n {
                if ((xs[j] - xs[q]).powi(2) + (ys[j] - ys[q]).powi(2)).sqrt() <= reach {
                    assert!(found.binary_search(&j).is_ok(), "{j} near {q}");
                }
            }
        }
    }

    fn brute_force_near(xs: &[f64], ys: &[f64], q: usize, reach: f64) -> Vec<usize> {
        (0..xs.len())
            .filter(|&j| ((xs[j] - xs[q]).powi(2) + (ys[j] - ys[q]).powi(2)).sqrt() <= reach)
            .collect()
    }

    #[test]
    fn a_loose_grid_of_a_sparse_swarm_widens_its_cells_past_twice_and_misses_no_neighbour() {
        // Robots about 1 m apart: cells of 0.1 m would make about 25 times the dense budget.
        let (n, reach) = (4000, 0.1);
        let side = (n as f64).sqrt();
        let (xs, ys): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|i| {
                let i = i as f64;
                ((i * 0.754_877_666).fract() * side, (i * 0.569_840_29).fract() * side)
            })
            .unzip();
        let grid = Grid::loose(&xs, &ys, reach);
        assert!(matches!(grid.table, CellTable::Dense { .. }));
        assert!(grid.cell > 2.0 * reach * 1.02);
        assert!(grid.crowding() <= CROWDED * n);
        for q in (0..n).step_by(7) {
            let found = near(&grid, xs[q], ys[q]);
            for j in brute_force_near(&xs, &ys, q, reach) {
                assert!(found.binary_search(&j).is_ok(), "{j} near {q}");
            }
        }
    }

    #[test]
    fn a_loose_grid_of_a_crowd_and_one_far_point_keeps_cells_of_reach() {
        // 2,000 points packed 0.05 m apart and one 10 km away: cells wide enough for a dense
        // table would hold the whole crowd.
        let (side, reach) = (45_usize, 0.1);
        let (mut xs, mut ys): (Vec<f64>, Vec<f64>) = (0..side * side)
            .map(|k| ((k % side) as f64 * 0.05, (k / side) as f64 * 0.05))
            .unzip();
        xs.push(1e4);
        ys.push(1e4);
        let grid = Grid::loose(&xs, &ys, reach);
        assert!(!matches!(grid.table, CellTable::Dense { .. }));
        assert!(grid.cell <= reach * 1.02);
        for q in (0..xs.len()).step_by(11) {
            let found = near(&grid, xs[q], ys[q]);
            for j in brute_force_near(&xs, &ys, q, reach) {
                assert!(found.binary_search(&j).is_ok(), "{j} near {q}");
            }
        }
    }

    #[test]
    fn a_pair_exactly_reach_apart_across_two_borders_is_found() {
        // The exact distance is a hair over 0.11 but computes to 0.11: it must still be found.
        let grid = Grid::new(&[0.0, 0.0], &[-1e-18, 0.11], 0.11);
        assert_eq!(near(&grid, 0.0, -1e-18), vec![0, 1]);
    }

    fn near_by_runs(grid: &Grid, x: f64, y: f64) -> Vec<usize> {
        let mut seen = Vec::new();
        grid.for_each_run_near(x, y, |run| {
            for k in run {
                assert_eq!(grid.sorted().0[k], grid.sorted_xs[k]);
                seen.push(grid.members()[k]);
            }
        });
        seen.sort();
        seen
    }

    #[test]
    fn runs_cover_the_same_points_as_cells() {
        // Dense and sparse tables, queries at points, between them, and far outside.
        let xs: Vec<f64> = (0..500).map(|i| ((i as f64) * 0.754_877_666).fract() * 3.0).collect();
        let ys: Vec<f64> = (0..500).map(|i| ((i as f64) * 0.569_840_290).fract() * 2.0).collect();
        let mut far_xs = xs.clone();
        far_xs.extend([1e12, -1e12]);
        let mut far_ys = ys.clone();
        far_ys.extend([1e12, 0.0]);
        for (xs, ys) in [(&xs, &ys), (&far_xs, &far_ys)] {
            let grid = Grid::new(xs, ys, 0.3);
            for (x, y) in
                xs.iter()
                    .zip(ys.iter())
                    .map(|(&x, &y)| (x, y))
                    .chain([(-0.31, 1.0), (9.0, 9.0), (1e12, 1e12)])
            {
                assert_eq!(near_by_runs(&grid, x, y), near(&grid, x, y));
            }
        }
    }

    #[test]
    fn runs_within_cover_every_point_in_the_square() {
        let xs: Vec<f64> = (0..400).map(|i| ((i as f64) * 0.754_877_666).fract() * 4.0).collect();
        let ys: Vec<f64> = (0..400).map(|i| ((i as f64) * 0.569_840_290).fract() * 3.0).collect();
        let mut far_xs = xs.clone();
        far_xs.extend([1e12, -1e12]);
        let mut far_ys = ys.clone();
        far_ys.extend([1e12, 0.0]);
        for (xs, ys) in [(&xs, &ys), (&far_xs, &far_ys)] {
            let grid = Grid::new(xs, ys, 0.25);
            for (x, y, half) in [
                (1.0, 1.0, 0.1),
                (2.0, 0.5, 0.7),
                (-3.0, 1.0, 3.5),
                (1e12, 1e12, 0.3),
                (0.0, 0.0, 1e13),
            ] {
                let mut seen = Vec::new();
                grid.for_each_run_within(x, y, half, |run| seen.extend(run.map(|k| grid.members()[k])));
                let before = seen.len();
                seen.sort_unstable();
                seen.dedup();
                assert_eq!(seen.len(), before, "a point visited twice");
                for j in 0..xs.len() {
                    if (xs[j] - x).abs() <= half && (ys[j] - y).abs() <= half {
                        assert!(
                            seen.binary_search(&j).is_ok(),
                            "point {j} missed around ({x}, {y}) +- {half}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn floor_matches_the_library_floor() {
        for value in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            -1.0,
            3.0,
            -3.000_000_1,
            2.5e15,
            -2.5e15,
            1e300,
            -1e300,
            -1e-300,
        ] {
            assert_eq!(floor(value), value.floor() as i64, "{value}");
        }
    }

    #[test]
    fn empty_grid_visits_nothing() {
        let grid = Grid::new(&[], &[], 1.0);
        assert!(near(&grid, 0.0, 0.0).is_empty());
        assert!(near_by_runs(&grid, 0.0, 0.0).is_empty());
    }
}
