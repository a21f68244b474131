//! What the robots deciding now perceive of the others: the robots their movement sensor sees
//! and the robots their radio hears, as two CSRs over those robots' rows.
//!
//! Robot j is seen by robot i when j != i, `|p_j - p_i| <= sensor range` and the direction from
//! i to j lies within `fov / 2` of `heading_i + direction` (a co-located robot is always seen);
//! it is heard when `|p_j - p_i| <= radio range` and j is talking (has a message out). Each row
//! lists ids in increasing order, and a row is the same whichever other rows are asked: the
//! robots can be perceived for one at a time or all at once. Distances are the neighbour
//! query's, to the bit. Per-robot values `carried` (the velocities a movement sensor reports,
//! say) are read at each robot seen, on every core; a radio that sums ([`Radio::summed`]) adds
//! per-robot values up over each row heard instead of listing it (an inbox only summed). A radio
//! that loses messages ([`Loss`]) draws each one's fate where it finds it, and counts those lost.
//!
//! A radio over a communication graph ([`linked`]) is heard by its links instead, whatever the
//! distance.

use std::f64::consts::TAU;

use rayon::prelude::*;

use crate::csr::check_rows;
use crate::draws::Loss;
use crate::error::{check_finite, check_len, try_filled, try_room, GeomError, Result};
use crate::grid::Grid;
use crate::neighbours::{length, radius_squared, within_squared, wrap_angle};
use crate::parallel::{map_range, try_filled_on_every_core, worth_spreading, TASK_ITEMS};

/// A movement sensor's reach: range (m), full aperture `fov` (rad) about the heading turned by
/// `direction` (rad); `bearings`: whether the bearings of the robots seen are wanted (an `atan2`
/// each, 15-20 % of a crowd's perception; without, the column is left empty).
#[derive(Debug, Clone, Copy)]
pub struct Sight {
    pub range: f64,
    pub fov: f64,
    pub direction: f64,
    pub bearings: bool,
}

/// Ragged rows of seen or heard robots: row r is `ids[offsets[r]..offsets[r + 1]]`, with the
/// distance of each and, for the seen ones, the bearing (world frame, from the perceiving robot
/// towards the other; where [`Sight::bearings`]) and the offset `(dx, dy)` (the other's position
/// less the perceiving robot's); those three are empty for the heard ones, whom no one needs the
/// direction of.
/// `carried[c]` holds the `c`-th carried column's values at the robots seen (none for the heard).
/// `summed[c]`, for the heard rows of a radio that sums ([`Radio::summed`]), holds each row's sum
/// of the `c`-th summed column; the rows' ids and distances are then left empty. `lost`, for the
/// heard rows of a radio that loses messages ([`Radio::loss`]), holds how many each row lost
/// (else it is empty).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Perceived {
    pub offsets: Vec<i64>,
    pub ids: Vec<i64>,
    pub distances: Vec<f64>,
    pub bearings: Vec<f64>,
    pub dxs: Vec<f64>,
    pub dys: Vec<f64>,
    pub carried: Vec<Vec<f64>>,
    pub summed: Vec<Vec<f64>>,
    pub lost: Vec<i64>,
}

/// A range radio: its `range` (m), who is `talking` (has a message out), the per-robot values
/// `summed` over each row of what is heard instead of listing the rows (where `None`, the rows
/// are listed; where no values, they are only counted), and its `loss` (where `None`, every
/// message in range gets through). A sum adds the values of the robots heard in increasing id
/// from +0.0, as `reduce::reduce` adds a listed row's: the same bits, without the rows written (a
/// robot in a crowd hears tens of messages, and a consensus rule reads only their sum).
#[derive(Debug, Clone, Copy)]
pub struct Radio<'a> {
    pub range: f64,
    pub talking: &'a [bool],
    pub summed: Option<&'a [&'a [f64]]>,
    pub loss: Option<Loss>,
}

impl Perceived {
    /// Room for the entries of the seen rows its offsets hold: every column but the bearings
    /// unless `bearings`, zeroed on every core (fresh memory).
    fn room_for_seen(&mut self, bearings: bool) -> Result<()> {
        let total = self.offsets.last().map_or(0, |&last| last as usize);
        self.ids = try_filled_on_every_core(total, 0, WHAT)?;
        self.distances = try_filled_on_every_core(total, 0.0, WHAT)?;
        if bearings {
            self.bearings = try_filled_on_every_core(total, 0.0, WHAT)?;
        }
        self.dxs = try_filled_on_every_core(total, 0.0, WHAT)?;
        self.dys = try_filled_on_every_core(total, 0.0, WHAT)?;
        Ok(())
    }

    /// Room for the entries of the heard rows its offsets hold: ids and distances.
    fn room_for_heard(&mut self) -> Result<()> {
        let total = self.offsets.last().map_or(0, |&last| last as usize);
        self.ids = try_filled_on_every_core(total, 0, WHAT)?;
        self.distances = try_filled_on_every_core(total, 0.0, WHAT)?;
        Ok(())
    }
}

/// What a failed allocation names.
const WHAT: &str = "perceived robots";

/// Rows from which the robots are perceived for on every thread.
const PARALLEL_ROWS: usize = 512;

/// Rows one task finds at least: enough to amortise a task.
const TASK_ROWS: usize = 256;

/// Tasks a thread, where there are many rows: enough to balance the cores, few enough that each
/// task's robots, taken cell by cell, are near each other.
const TASKS_A_THREAD: usize = 4;

fn check_range(arg: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(GeomError::InvalidParameter {
            arg,
            rule: ">= 0",
            got: value,
        })
    }
}

/// The robots `rows` (ids, increasing) see with `sight` and hear within `radio` (range, and who
/// is talking), among the robots at `(xs[j], ys[j])` heading `headings[j]`. One grid over the
/// longer range, whose cell-ordered coordinates each robot asked for streams through (five runs
/// of memory). Two passes over the asked robots, on every core: the first counts what each sees
/// and hears, which places every row in the output (a radio that sums has no rows to place: its
/// robots are counted in the second pass); the second writes the rows in place, tasks
/// of consecutive rows each filling its own stretch of the columns. The output is allocated
/// once, on the calling thread, and nothing is copied after: before, each task grew its own
/// buffers on its worker thread and they were copied into row order on return, a fifth of the
/// kernel's time, and the allocator kept those buffers on each worker thread (with 16 threads,
/// 190 MiB for 100,000 robots). Each of `carried` holds one value per robot, read at every robot
/// seen; each of the radio's `summed`, one value per robot, is added up over every row heard.
///
/// # Errors
/// Length mismatches, non-finite positions or headings, negative ranges, rows that are not
/// increasing ids of robots, or rows too large for memory.
pub fn perceive(
    xs: &[f64],
    ys: &[f64],
    headings: &[f64],
    rows: &[i64],
    sight: Option<Sight>,
    radio: Option<Radio<'_>>,
    carried: &[&[f64]],
) -> Result<(Perceived, Perceived)> {
    let n = xs.len();
    check_len("ys", n, ys.len())?;
    check_len("headings", n, headings.len())?;
    check_finite("positions", xs)?;
    check_finite("positions", ys)?;
    check_finite("headings", headings)?;
    for values in carried {
        check_len("carried", n, values.len())?;
    }
    if let Some(s) = sight {
        check_range("sensor range", s.range)?;
        check_range("fov", s.fov)?;
        check_finite("direction", &[s.direction])?;
    }
    if let Some(radio) = radio {
        check_range("radio range", radio.range)?;
        check_len("talking", n, radio.talking.len())?;
        for values in radio.summed.unwrap_or_default() {
            check_len("summed", n, values.len())?;
        }
    }
    check_rows(rows, n)?;
    if n > u32::MAX as usize {
        // Each robot near another is a key of two 32-bit halves (see Find::near).
        return Err(GeomError::InvalidParameter {
            arg: "positions",
            rule: "at most 4,294,967,295 robots",
            got: n as f64,
        });
    }
    let reach = sight.map_or(0.0, |s| s.range).max(radio.map_or(0.0, |r| r.range));
    // Cells half the reach: the 5x5 block around a robot holds 0.69 times the robots of the 3x3
    // block of cells as wide as the reach. Reach 0 only needs identical points together.
    let grid = Grid::new(
        xs,
        ys,
        if reach > 0.0 {
            (reach / 2.0).max(f64::MIN_POSITIVE)
        } else {
            1.0
        },
    );
    let summed = radio.and_then(|r| r.summed).unwrap_or_default();
    let summing = !summed.is_empty();
    // A radio that sums has no rows to place: its robots are counted as they are summed, in the
    // second pass, and the first looks only as far as an all-around sensor sees (a radio
    // reaching twice as far has four times the robots to look at; a narrower sensor's count
    // goes through `near`, as far as the radio reaches). One that only counts is counted in the
    // first pass, and the second gathers only what the sensor sees.
    let counting = radio.is_some_and(|r| r.summed.is_some()) && !summing;
    let sight_range = sight.map_or(0.0, |s| s.range);
    let counted = if summing { sight_range } else { reach };
    let gathered = if counting { sight_range } else { reach };
    let find = Find {
        grid: &grid,
        headings,
        reach,
        reach_squared: radius_squared(reach),
        gathered,
        gathered_squared: radius_squared(gathered),
        counted,
        counted_squared: radius_squared(counted),
        sight,
        radio_range: radio.map(|r| r.range),
        talking_by_cell: match radio {
            Some(r) => map_range(n, 1.0, |k| r.talking[grid.members()[k]]),
            None => try_filled(n, false, WHAT)?,
        },
        summing,
        heard_in_fill: radio.is_some() && !counting,
        summed: summed.len(),
        summed_by_cell: map_range(n * summed.len(), 1.0, |e| {
            let m = summed.len();
            summed[e % m][grid.members()[e / m]]
        }),
        loss: radio.and_then(|r| r.loss),
        sight_within: sight.map_or(-1.0, |s| within_squared(s.range)),
        radio_within: radio.map_or(-1.0, |r| within_squared(r.range)),
    };
    let bearings = sight.is_some_and(|s| s.bearings);
    let spread = rows.len() >= PARALLEL_ROWS;
    // Tasks of consecutive rows, a few a thread, each going through its robots cell by cell: at a
    // million robots the grid's coordinates are far larger than a core's cache, and robots taken
    // in row order cost a cache miss each (perceive measured 0.61x in row order; in cell order
    // the robots of one cell read the same stretch of the grid).
    let task_rows = TASK_ROWS.max(rows.len().div_ceil(rayon::current_num_threads() * TASKS_A_THREAD));
    let by_cell = rows_by_cell(&grid, rows)?;
    // `order[first + t] = (u, k)`: the t-th robot in cell order of the task from row `first` on
    // is its u-th row, at place k of the grid's cell order.
    let mut order = try_filled(rows.len(), (0_u32, 0_u32), WHAT)?;
    let mut counts = try_filled(rows.len(), Counts::default(), WHAT)?;
    // The first pass: each row's counts, seen, heard and lost, and from them the offsets.
    let first_pass = |(first, (order, counts)): (usize, (&mut [(u32, u32)], &mut [Counts]))| {
        let rows_here = first as u32..(first + order.len()) as u32;
        let mut places = order.iter_mut();
        for &(r, k) in by_cell.iter().filter(|(r, _)| rows_here.contains(r)) {
            if let Some(place) = places.next() {
                *place = (r - rows_here.start, k);
            }
        }
        for &(u, k) in order.iter() {
            counts[u as usize] = find.count(&find.asked(k as usize));
        }
    };
    if spread {
        (0..rows.len())
            .into_par_iter()
            .step_by(task_rows)
            .zip(order.par_chunks_mut(task_rows).zip(counts.par_chunks_mut(task_rows)))
            .for_each(first_pass);
    } else {
        (0..rows.len())
            .step_by(task_rows)
            .zip(order.chunks_mut(task_rows).zip(counts.chunks_mut(task_rows)))
            .for_each(first_pass);
    }
    let (mut seen, mut heard) = (Perceived::default(), Perceived::default());
    (seen.offsets, heard.offsets) = offsets(&counts)?;
    if find.loss.is_some() {
        // Lost where counted: in the first pass unless the radio sums (then in the second).
        heard.lost = map_range(rows.len(), 1.0, |r| i64::from(counts[r].lost));
    }
    drop(counts);
    if sight.is_some() {
        seen.room_for_seen(bearings)?;
    }
    let mut heard_counts = Vec::new();
    if summing {
        heard.offsets.fill(0); // the first pass did not count them: the second does
        heard_counts = try_filled(rows.len(), 0_i64, WHAT)?;
        heard.summed = (0..find.summed)
            .map(|_| try_filled(rows.len(), 0.0, WHAT))
            .collect::<Result<_>>()?;
    } else if radio.is_some() && !counting {
        heard.room_for_heard()?;
    }
    // The second pass: each task given its rows' stretch of every column.
    let mut tasks = Vec::new();
    let mut rest = Out {
        seen_ids: &mut seen.ids,
        seen_distances: &mut seen.distances,
        bearings: &mut seen.bearings,
        dxs: &mut seen.dxs,
        dys: &mut seen.dys,
        heard_ids: &mut heard.ids,
        heard_distances: &mut heard.distances,
        sums: heard.summed.iter_mut().map(|column| &mut column[..]).collect(),
        heard_counts: &mut heard_counts,
        lost: &mut heard.lost,
    };
    for (first, task_order) in (0..rows.len()).step_by(task_rows).zip(order.chunks(task_rows)) {
        let last = (first + task_rows).min(rows.len());
        let seen_len = (seen.offsets[last] - seen.offsets[first]) as usize;
        let heard_len = (heard.offsets[last] - heard.offsets[first]) as usize;
        let head;
        (head, rest) = rest.split_at(seen_len, heard_len, last - first);
        let task = Task {
            order: task_order,
            seen_offsets: &seen.offsets[first..=last],
            heard_offsets: &heard.offsets[first..=last],
        };
        tasks.push((task, head));
    }
    if spread {
        tasks.into_par_iter().for_each(|(task, out)| find.fill(&task, out));
    } else {
        tasks.into_iter().for_each(|(task, out)| find.fill(&task, out));
    }
    for (r, &count) in heard_counts.iter().enumerate() {
        heard.offsets[r + 1] = heard.offsets[r] + count;
    }
    seen.carried = carried
        .iter()
        .map(|values| map_range(seen.ids.len(), 1.0, |e| values[seen.ids[e] as usize]))
        .collect();
    Ok((seen, heard))
}

/// The rows (places in `rows`, robot ids) in the grid's cell order, each with its robot's place in
/// that order: its members, which it sorted by cell, filtered.
fn rows_by_cell(grid: &Grid, rows: &[i64]) -> Result<Vec<(u32, u32)>> {
    let n = grid.members().len();
    let mut row_of = try_filled_on_every_core(n, u32::MAX, WHAT)?;
    for (r, &i) in rows.iter().enumerate() {
        row_of[i as usize] = r as u32;
    }
    let asked = |(k, &i): (usize, &usize)| (row_of[i] != u32::MAX).then_some((row_of[i], k as u32));
    Ok(if worth_spreading(n, 1.0) {
        grid.members()
            .par_iter()
            .enumerate()
            .with_min_len(TASK_ITEMS)
            .filter_map(asked)
            .collect()
    } else {
        grid.members().iter().enumerate().filter_map(asked).collect()
    })
}

/// What the first pass counts of a row: the robots seen and heard, and the messages lost.
#[derive(Debug, Clone, Copy, Default)]
struct Counts {
    seen: u32,
    heard: u32,
    lost: u32,
}

/// The seen and the heard offsets of rows with `counts` each.
fn offsets(counts: &[Counts]) -> Result<(Vec<i64>, Vec<i64>)> {
    let mut seen = try_filled(counts.len() + 1, 0_i64, WHAT)?;
    let mut heard = try_filled(counts.len() + 1, 0_i64, WHAT)?;
    for (r, count) in counts.iter().enumerate() {
        seen[r + 1] = seen[r] + i64::from(count.seen);
        heard[r + 1] = heard[r] + i64::from(count.heard);
    }
    Ok((seen, heard))
}

/// What the robots `rows` (ids, increasing) hear over the communication `graph` `(indptr,
/// indices)` (robot i is linked to the robots `indices[indptr[i]..indptr[i + 1]]`), `talking[j]`
/// those of the `n` robots with a message out: each row's links that are talking, not the robot
/// itself, in the graph's order, and, given the robots' `positions` `(xs, ys)`, the distance to
/// each (`hypot`, as NumPy's; NaN without). Only the rows asked for are read (and checked) of
/// the graph, whose links are most of a step's radio; the distances only matter to a loss that
/// grows with distance, and cost more than the rest.
///
/// # Errors
/// Length mismatches, non-finite positions, rows that are not increasing robot ids, or a row
/// asked for whose links are not robot ids within `indices`.
pub fn linked(
    positions: Option<(&[f64], &[f64])>,
    graph: (&[i64], &[i64]),
    rows: &[i64],
    talking: &[bool],
) -> Result<Perceived> {
    const WHAT: &str = "heard robots";
    let n = talking.len();
    if let Some((xs, ys)) = positions {
        check_len("positions", n, xs.len())?;
        check_len("positions", n, ys.len())?;
        check_finite("positions", xs)?;
        check_finite("positions", ys)?;
    }
    let (indptr, indices) = graph;
    check_len("graph", n + 1, indptr.len())?;
    check_rows(rows, n)?;
    let bad = |reason: String| GeomError::InvalidCsr {
        arg: "graph",
        rows: n,
        reason,
    };
    let mut links = Vec::new();
    try_room(&mut links, rows.len(), WHAT)?;
    for &i in rows {
        let (first, last) = (indptr[i as usize], indptr[i as usize + 1]);
        if first < 0 || first > last || last > indices.len() as i64 {
            let len = indices.len();
            return Err(bad(format!(
                "row {i}'s links run from {first} to {last}, not within the {len} indices"
            )));
        }
        links.push(&indices[first as usize..last as usize]);
    }
    let most = links.iter().map(|row| row.len()).sum();
    let mut offsets = try_filled(rows.len() + 1, 0_i64, WHAT)?;
    let (mut ids, mut owners) = (Vec::new(), Vec::new());
    try_room(&mut ids, most, WHAT)?;
    try_room(&mut owners, most, WHAT)?;
    // The ids and their rows in one pass; the distances, a hypot each, on every core for many.
    for (r, (&i, row)) in rows.iter().zip(&links).enumerate() {
        for &j in *row {
            if j < 0 || j >= n as i64 {
                return Err(bad(format!("row {i} links {j}, which is not a robot id in [0, {n})")));
            }
            if talking[j as usize] && j != i {
                ids.push(j);
                owners.push(i as usize);
            }
        }
        offsets[r + 1] = ids.len() as i64;
    }
    let distances = match positions {
        Some((xs, ys)) => map_range(ids.len(), 20.0, |e| {
            let (i, j) = (owners[e], ids[e] as usize);
            (xs[j] - xs[i]).hypot(ys[j] - ys[i])
        }),
        None => try_filled(ids.len(), f64::NAN, WHAT)?,
    };
    Ok(Perceived {
        offsets,
        ids,
        distances,
        ..Perceived::default()
    })
}

/// One perception's inputs, shared by every task.
struct Find<'a> {
    grid: &'a Grid,
    headings: &'a [f64],
    reach: f64,
    /// A hair above reach^2: beyond it a robot is surely out; below it `sqrt` decides exactly.
    reach_squared: f64,
    /// How far the second pass gathers the robots it sorts out (the reach, or the sensor's range
    /// where the radio only counts), and a hair above its square.
    gathered: f64,
    gathered_squared: f64,
    /// How far the first pass looks for the robots it counts (see `perceive`), and a hair above
    /// its square.
    counted: f64,
    counted_squared: f64,
    sight: Option<Sight>,
    radio_range: Option<f64>,
    /// Who is talking, in the grid's cell order (all silent without a radio): read beside the
    /// cell-ordered coordinates, not at each robot's id.
    talking_by_cell: Vec<bool>,
    /// Whether the radio sums its rows instead of listing them, whether the second pass hears
    /// (not where the radio only counts its rows, in the first), and how many columns it sums.
    summing: bool,
    heard_in_fill: bool,
    summed: usize,
    /// The radio's summed columns in the grid's cell order, interleaved: robot k's values are
    /// `summed_by_cell[k * summed..][..summed]`, in one cache line where the columns' own lines
    /// cost a miss each (a robot's neighbours are read by id, not in cell order).
    summed_by_cell: Vec<f64>,
    /// [`within_squared`] of the sensor's and the radio's ranges, -1 without (no square is
    /// within): a sensor that sees all around decides by these alone.
    sight_within: f64,
    radio_within: f64,
    /// The radio's losses, drawn for each robot heard (`None`: every one gets through).
    loss: Option<Loss>,
}

/// A robot within reach (by the squared distance's margin) of the one perceiving: its id, whether
/// it is talking, its offset from it and the offset's squared length.
#[derive(Debug, Clone, Copy, Default)]
struct Near {
    j: usize,
    talking: bool,
    dx: f64,
    dy: f64,
    squared: f64,
}

/// A robot perceiving: its id and position, read at its place in the grid's cell order (its
/// neighbours' stretch of the grid), not at its id (a cache miss each at a million robots).
struct Asked {
    i: usize,
    /// Its place in the grid's cell order.
    at: usize,
    x: f64,
    y: f64,
}

/// What a robot near the one perceiving is to it: seen (with the bearing, where wanted), heard,
/// or its message lost.
struct Sorted {
    seen: bool,
    bearing: f64,
    heard: bool,
    lost: bool,
}

/// A task's stretch of the output columns (empty where nothing of that kind is perceived).
struct Out<'a> {
    seen_ids: &'a mut [i64],
    seen_distances: &'a mut [f64],
    bearings: &'a mut [f64],
    dxs: &'a mut [f64],
    dys: &'a mut [f64],
    heard_ids: &'a mut [i64],
    heard_distances: &'a mut [f64],
    /// Each summed column's stretch, one value a row.
    sums: Vec<&'a mut [f64]>,
    /// Where the radio sums, how many robots each row heard (else empty).
    heard_counts: &'a mut [i64],
    /// Where the radio loses messages, how many each row lost (else empty).
    lost: &'a mut [i64],
}

impl<'a> Out<'a> {
    /// The first `seen` seen entries, `heard` heard ones and `rows` rows' sums, heard counts and
    /// lost counts, and the rest (a column left empty stays empty).
    fn split_at(self, seen: usize, heard: usize, rows: usize) -> (Self, Self) {
        fn cut<T>(column: &mut [T], at: usize) -> (&mut [T], &mut [T]) {
            column.split_at_mut(at.min(column.len()))
        }
        let (seen_ids, seen_ids_rest) = cut(self.seen_ids, seen);
        let (seen_distances, seen_distances_rest) = cut(self.seen_distances, seen);
        let (bearings, bearings_rest) = cut(self.bearings, seen);
        let (dxs, dxs_rest) = cut(self.dxs, seen);
        let (dys, dys_rest) = cut(self.dys, seen);
        let (heard_ids, heard_ids_rest) = cut(self.heard_ids, heard);
        let (heard_distances, heard_distances_rest) = cut(self.heard_distances, heard);
        let (sums, sums_rest) = self.sums.into_iter().map(|column| cut(column, rows)).unzip();
        let (heard_counts, heard_counts_rest) = cut(self.heard_counts, rows);
        let (lost, lost_rest) = cut(self.lost, rows);
        (
            Out {
                seen_ids,
                seen_distances,
                bearings,
                dxs,
                dys,
                heard_ids,
                heard_distances,
                sums,
                heard_counts,
                lost,
            },
            Out {
                seen_ids: seen_ids_rest,
                seen_distances: seen_distances_rest,
                bearings: bearings_rest,
                dxs: dxs_rest,
                dys: dys_rest,
                heard_ids: heard_ids_rest,
                heard_distances: heard_distances_rest,
                sums: sums_rest,
                heard_counts: heard_counts_rest,
                lost: lost_rest,
            },
        )
    }
}

impl Find<'_> {
    /// The robot at place `k` of the grid's cell order, perceiving.
    fn asked(&self, k: usize) -> Asked {
        let (sorted_xs, sorted_ys) = self.grid.sorted();
        Asked {
            i: self.grid.members()[k],
            at: k,
            x: sorted_xs[k],
            y: sorted_ys[k],
        }
    }

    /// The robots within `reach` of robot i (by the squared distance's margin, `reach_squared`)
    /// as keys `j << 32 | k` (robot j at place k of the grid's cell order), in the grid's order:
    /// its block of cells streamed from the grid's cell-ordered coordinates. Sorted, the keys go
    /// by id; 8 bytes each sort faster than the robots' offsets with them (measured 1.12x on the
    /// rendezvous example's perception).
    fn near(&self, &Asked { i, x, y, .. }: &Asked, (reach, reach_squared): (f64, f64), keys: &mut Vec<u64>) {
        let (sorted_xs, sorted_ys) = self.grid.sorted();
        let members = self.grid.members();
        keys.clear();
        self.grid.for_each_run_within(x, y, reach, |run| {
            // No data-dependent branch in the hot loop (it measured 1.4 times slower with one):
            // every candidate is written, the count only advances for those that may be in reach.
            let mut count = keys.len();
            keys.resize(count + run.len(), 0);
            for k in run {
                let (j, dx, dy) = (members[k], sorted_xs[k] - x, sorted_ys[k] - y);
                let squared = dx * dx + dy * dy;
                keys[count] = (j as u64) << 32 | k as u64;
                count += usize::from((squared <= reach_squared) & (j != i));
            }
            keys.truncate(count);
        });
    }

    /// The robot of a key of [`Find::near`] and its offset from robot i, with the offset's
    /// squared length.
    fn unkey(&self, asked: &Asked, key: u64) -> Near {
        let (sorted_xs, sorted_ys) = self.grid.sorted();
        let k = (key & u64::from(u32::MAX)) as usize;
        let (dx, dy) = (sorted_xs[k] - asked.x, sorted_ys[k] - asked.y);
        Near {
            j: (key >> 32) as usize,
            talking: self.talking_by_cell[k],
            dx,
            dy,
            squared: dx * dx + dy * dy,
        }
    }

    /// What robot i makes of robot `other` near it.
    fn sort(&self, i: usize, other: &Near) -> Sorted {
        let &Near {
            talking,
            dx,
            dy,
            squared,
            ..
        } = other;
        let distance = length(squared, dx, dy);
        let mut sorted = Sorted {
            seen: false,
            bearing: f64::NAN,
            heard: false,
            lost: false,
        };
        if distance > self.reach {
            return sorted;
        }
        if let Some(s) = self.sight {
            if distance <= s.range {
                if s.bearings || s.fov < TAU {
                    sorted.bearing = dy.atan2(dx);
                }
                sorted.seen = s.fov >= TAU
                    || distance == 0.0
                    || wrap_angle(sorted.bearing - (self.headings[i] + s.direction)).abs() <= s.fov / 2.0;
            }
        }
        if let Some(range) = self.radio_range {
            let offered = distance <= range && talking;
            sorted.heard = offered && self.through(self.hearer(i), other.j, || distance);
            sorted.lost = offered && !sorted.heard;
        }
        sorted
    }

    /// The hash of robot i's loss draws ([`Loss::hearer`]; 0 without losses).
    fn hearer(&self, i: usize) -> u64 {
        self.loss.map_or(0, |loss| loss.hearer(i))
    }

    /// Whether the message of robot j, in range of the robot of `hearer` ([`Find::hearer`]) at
    /// `distance`, gets through the radio's losses.
    #[inline]
    fn through(&self, hearer: u64, j: usize, distance: impl FnOnce() -> f64) -> bool {
        self.loss.is_none_or(|loss| loss.delivered(hearer, j, distance))
    }

    /// How many robots robot i sees and how many it hears, and how many messages it loses: as
    /// [`Find::sort`] decides, without a list of the robots near (where the radio sums, the
    /// robots heard are not all looked at: those counts are not used). A sensor that sees all
    /// around (or none) needs no bearing, and then the count is one pass over the block without
    /// a data-dependent branch (but for a lossy radio's draws), nor a root: `squared <=
    /// within_squared(range)` decides as `sqrt(squared) <= range`.
    fn count(&self, asked: &Asked) -> Counts {
        let &Asked { i, at, x, y } = asked;
        let mut counts = Counts::default();
        let mut add = |sorted: &Sorted| {
            counts.seen += u32::from(sorted.seen);
            counts.heard += u32::from(sorted.heard);
            counts.lost += u32::from(sorted.lost);
        };
        if self.sight.is_some_and(|s| s.fov < TAU) {
            KEYS.with_borrow_mut(|keys| {
                self.near(asked, (self.reach, self.reach_squared), keys);
                keys.iter().for_each(|&key| add(&self.sort(i, &self.unkey(asked, key))));
            });
            return counts;
        }
        let (sorted_xs, sorted_ys) = self.grid.sorted();
        let members = self.grid.members();
        // A radio that sums counts what it hears in the second pass: its losses are drawn there.
        let (lossy, hearer) = (self.loss.is_some() && !self.summing, self.hearer(i));
        self.grid.for_each_run_within(x, y, self.counted, |run| {
            let candidates = sorted_xs[run.clone()]
                .iter()
                .zip(&sorted_ys[run.clone()])
                .zip(run.clone().zip(&self.talking_by_cell[run]));
            for ((&cx, &cy), (k, &talking)) in candidates {
                let (dx, dy) = (cx - x, cy - y);
                let squared = dx * dx + dy * dy;
                // The robots near() keeps, as it keeps them (itself by its place, not its id:
                // the ids are not read here).
                let near = (squared <= self.counted_squared) & (k != at);
                if !squared.is_finite() {
                    // Past ~1.3e154 m the squares overflow: the rule itself decides.
                    if near {
                        let other = Near {
                            j: members[k],
                            talking,
                            dx,
                            dy,
                            squared,
                        };
                        add(&self.sort(i, &other));
                    }
                    continue;
                }
                let offered = near & (squared <= self.radio_within) & talking;
                let heard = if lossy {
                    offered && self.through(hearer, members[k], || length(squared, dx, dy))
                } else {
                    offered
                };
                add(&Sorted {
                    seen: near & (squared <= self.sight_within),
                    bearing: f64::NAN,
                    heard,
                    lost: offered & !heard,
                });
            }
        });
        counts
    }

    /// Writes what the robots of `task` see and hear into `out`, its rows' stretch of the
    /// columns, each row by increasing id; the stretch holds exactly what [`Find::count`]
    /// counted for them (the same robots near, sorted out alike: the writes stay within it).
    /// Where the radio sums, the robots heard and the messages lost are counted here, into
    /// `out.heard_counts` and `out.lost`; where it only counts, it is not heard here at all.
    fn fill(&self, task: &Task<'_>, out: Out<'_>) {
        match self.summed {
            1 => self.fill_summing::<1>(task, out),
            2 => self.fill_summing::<2>(task, out),
            3 => self.fill_summing::<3>(task, out),
            4 => self.fill_summing::<4>(task, out),
            _ => self.fill_summing::<0>(task, out),
        }
    }

    /// [`Find::fill`] where the radio sums `M` columns, each row's sums then kept in registers
    /// (kept in memory, each waited on its last store: measured 1.09x on the rendezvous
    /// example's perception); `M = 0` where it lists its rows or sums more columns.
    fn fill_summing<const M: usize>(&self, task: &Task<'_>, mut out: Out<'_>) {
        let bearings = self.sight.is_some_and(|s| s.bearings);
        let (seen_first, heard_first) = (task.seen_offsets[0], task.heard_offsets[0]);
        let (summing, m) = (self.summing, self.summed);
        let all_around = self.sight.is_none_or(|s| s.fov >= TAU);
        let mut sums = vec![0.0; if M == 0 { m } else { 0 }];
        let (hears, lossy) = (self.heard_in_fill, self.loss.is_some());
        KEYS.with_borrow_mut(|keys| {
            for &(t, k) in task.order {
                let t = t as usize;
                let asked = self.asked(k as usize);
                let mut seen_at = (task.seen_offsets[t] - seen_first) as usize;
                let mut heard_at = (task.heard_offsets[t] - heard_first) as usize;
                self.near(&asked, (self.gathered, self.gathered_squared), keys);
                keys.sort_unstable();
                sums.fill(0.0);
                let mut lanes = [0.0; M];
                let (hearer, mut lost) = (self.hearer(asked.i), 0);
                for &key in keys.iter() {
                    let other = self.unkey(&asked, key);
                    // A sensor that sees all around (or none) decides by the squares, as `count`
                    // does: a root only for the robots written, a bearing only for those seen.
                    let (seen, heard, bearing) = if all_around && other.squared.is_finite() {
                        let offered = (other.squared <= self.radio_within) & other.talking & hears;
                        let heard = if lossy {
                            let distance = || length(other.squared, other.dx, other.dy);
                            offered && self.through(hearer, other.j, distance)
                        } else {
                            offered
                        };
                        lost += usize::from(offered & !heard);
                        (other.squared <= self.sight_within, heard, f64::NAN)
                    } else {
                        let sorted = self.sort(asked.i, &other);
                        lost += usize::from(sorted.lost & hears);
                        (sorted.seen, sorted.heard & hears, sorted.bearing)
                    };
                    if summing {
                        // In increasing id, from +0.0: as `reduce` adds a listed row. A robot not
                        // heard adds +0.0 (a sum from +0.0 is never -0.0: the same bits), without
                        // a branch on whether it is heard.
                        let (at, mask) = ((key & u64::from(u32::MAX)) as usize, u64::from(heard).wrapping_neg());
                        let values = &self.summed_by_cell[at * m..][..m];
                        let add = |(sum, value): (&mut f64, &f64)| *sum += f64::from_bits(value.to_bits() & mask);
                        if M > 0 {
                            lanes.iter_mut().zip(values).for_each(add);
                        } else {
                            sums.iter_mut().zip(values).for_each(add);
                        }
                        heard_at += usize::from(heard);
                    } else if heard {
                        out.heard_ids[heard_at] = other.j as i64;
                        out.heard_distances[heard_at] = length(other.squared, other.dx, other.dy);
                        heard_at += 1;
                    }
                    if seen {
                        let e = seen_at;
                        out.seen_ids[e] = other.j as i64;
                        out.seen_distances[e] = length(other.squared, other.dx, other.dy);
                        if bearings {
                            // All around, `sort` takes the same `atan2` where it takes one at all.
                            out.bearings[e] = if all_around { other.dy.atan2(other.dx) } else { bearing };
                        }
                        out.dxs[e] = other.dx;
                        out.dys[e] = other.dy;
                        seen_at += 1;
                    }
                }
                for (column, &sum) in out.sums.iter_mut().zip(if M > 0 { &lanes[..] } else { &sums }) {
                    column[t] = sum;
                }
                if summing {
                    out.heard_counts[t] = heard_at as i64;
                }
                if summing && lossy {
                    out.lost[t] = lost as i64;
                }
                debug_assert_eq!(seen_at as i64, task.seen_offsets[t + 1] - seen_first);
                debug_assert!(summing || !hears || heard_at as i64 == task.heard_offsets[t + 1] - heard_first);
            }
        });
    }
}

/// A task of the second pass: consecutive rows in `order` (their places among them, by cell, each
/// with its robot's place in the grid's cell order) and their offsets into the seen and heard
/// columns (one more than the rows).
struct Task<'a> {
    order: &'a [(u32, u32)],
    seen_offsets: &'a [i64],
    heard_offsets: &'a [i64],
}

std::thread_local! {
    /// The keys of the robots near the one perceiving ([`Find::near`]): a buffer each thread
    /// reuses from robot to robot.
    static KEYS: std::cell::RefCell<Vec<u64>> = const { std::cell::RefCell::new(Vec::new()) };
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Many rows, on every thread: tasks of rows, each in cell order, write each row where the
    /// counts put it (the debug build checks each row's writes against its counts).
    #[test]
    fn many_rows_match_brute_force() {
        let n = 3000;
        // A fixed scatter: a linear congruential sequence, some robots on the same spot.
        let mut state: u64 = 7;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut xs, mut ys): (Vec<f64>, Vec<f64>) = (0..n).map(|_| (8.0 * next(), 8.0 * next())).unzip();
        for i in (1..n).step_by(9) {
            (xs[i], ys[i]) = (xs[i - 1], ys[i - 1]);
        }
        let headings: Vec<f64> = (0..n).map(|_| TAU * next() - PI).collect();
        let talking: Vec<bool> = (0..n).map(|j| j % 4 != 0).collect();
        let rows: Vec<i64> = (0..n as i64).filter(|i| i % 3 != 1).collect();
        for fov in [TAU, 1.5] {
            let sight = Sight {
                range: 0.4,
                fov,
                direction: 0.3,
                bearings: true,
            };
            let radio = Radio {
                range: 0.7,
                talking: &talking,
                summed: None,
                loss: None,
            };
            let (seen, heard) = perceive(&xs, &ys, &headings, &rows, Some(sight), Some(radio), &[]).unwrap();
            // The same radio summing two columns: each row's sums in increasing id from +0.0.
            let (values, signs): (Vec<f64>, Vec<f64>) = (0..n).map(|j| (next() - 0.5, -(j as f64))).unzip();
            let summed: &[&[f64]] = &[&values, &signs];
            let summing = Radio {
                summed: Some(summed),
                ..radio
            };
            let (_, sums) = perceive(&xs, &ys, &headings, &rows, Some(sight), Some(summing), &[]).unwrap();
            assert_eq!(sums.offsets, heard.offsets);
            assert!(sums.ids.is_empty() && sums.distances.is_empty());
            for r in 0..rows.len() {
                let listed = &heard.ids[heard.offsets[r] as usize..heard.offsets[r + 1] as usize];
                for (column, got) in summed.iter().zip(&sums.summed) {
                    let want = listed.iter().fold(0.0, |sum, &j| sum + column[j as usize]);
                    assert_eq!(got[r].to_bits(), want.to_bits(), "row {r}'s sum");
                }
            }
            // The same radio losing messages, by distance too: each row the lossless one's
            // through the loss's draws, listed, counted or summed; what is seen is unchanged.
            let loss = Loss::new(9, 0, 4, 0.8, 0.6).unwrap();
            let lossy = Radio {
                loss: Some(loss),
                ..radio
            };
            let with = |radio| perceive(&xs, &ys, &headings, &rows, Some(sight), Some(radio), &[]).unwrap();
            let (seen_too, kept) = with(lossy);
            let (_, counted) = with(Radio {
                summed: Some(&[]),
                ..lossy
            });
            let (_, kept_sums) = with(Radio {
                summed: Some(summed),
                ..lossy
            });
            assert_eq!(seen_too, seen);
            assert_eq!(counted.offsets, kept.offsets);
            assert!(heard.lost.is_empty() && counted.ids.is_empty() && counted.summed.is_empty());
            let mut lost_any = 0;
            for (r, &i) in rows.iter().enumerate() {
                let (a, b) = (heard.offsets[r] as usize, heard.offsets[r + 1] as usize);
                let through =
                    |&e: &usize| loss.delivered(loss.hearer(i as usize), heard.ids[e] as usize, || heard.distances[e]);
                let want: Vec<usize> = (a..b).filter(through).collect();
                let (c, d) = (kept.offsets[r] as usize, kept.offsets[r + 1] as usize);
                assert_eq!(
                    kept.ids[c..d],
                    want.iter().map(|&e| heard.ids[e]).collect::<Vec<_>>()[..]
                );
                assert_eq!(
                    kept.distances[c..d],
                    want.iter().map(|&e| heard.distances[e]).collect::<Vec<_>>()[..]
                );
                let lost = (b - a - want.len()) as i64;
                assert_eq!((kept.lost[r], counted.lost[r], kept_sums.lost[r]), (lost, lost, lost));
                lost_any += lost;
                for (column, got) in summed.iter().zip(&kept_sums.summed) {
                    let sum = want.iter().fold(0.0, |sum, &e| sum + column[heard.ids[e] as usize]);
                    assert_eq!(got[r].to_bits(), sum.to_bits(), "row {r}'s sum of what got through");
                }
            }
            assert!(lost_any > 0 && (lost_any as usize) < heard.ids.len() / 2);
            for (r, &i) in rows.iter().enumerate() {
                let i = i as usize;
                let row = |p: &Perceived| p.ids[p.offsets[r] as usize..p.offsets[r + 1] as usize].to_vec();
                let distance = |j: usize| ((xs[j] - xs[i]).powi(2) + (ys[j] - ys[i]).powi(2)).sqrt();
                let ahead = |j: usize| {
                    let bearing = (ys[j] - ys[i]).atan2(xs[j] - xs[i]);
                    fov >= TAU || distance(j) == 0.0 || wrap_angle(bearing - (headings[i] + 0.3)).abs() <= fov / 2.0
                };
                let want_seen: Vec<i64> = (0..n)
                    .filter(|&j| j != i && distance(j) <= 0.4 && ahead(j))
                    .map(|j| j as i64)
                    .collect();
                let want_heard: Vec<i64> = (0..n)
                    .filter(|&j| j != i && distance(j) <= 0.7 && talking[j])
                    .map(|j| j as i64)
                    .collect();
                assert_eq!(row(&seen), want_seen, "row {r}, fov {fov}");
                assert_eq!(row(&heard), want_heard, "row {r}, fov {fov}");
            }
        }
    }

    #[test]
    fn sight_and_radio() {
        let (xs, ys, headings) = ([0.0, 0.2, -0.2, 0.9], [0.0; 4], [0.0, 0.0, 0.0, 0.0]);
        let sight = Sight {
            range: 0.3,
            fov: 1.0,
            direction: 0.0,
            bearings: true,
        };
        let talking = [true, true, false, true];
        let speeds: &[f64] = &[0.5, 0.1, 0.2, 0.3];
        let (seen, heard) = perceive(
            &xs,
            &ys,
            &headings,
            &[0, 3],
            Some(sight),
            Some(Radio {
                range: 1.0,
                talking: &talking,
                summed: None,
                loss: None,
            }),
            &[speeds],
        )
        .unwrap();
        assert_eq!(seen.offsets, vec![0, 1, 1]);
        assert_eq!(seen.ids, vec![1]); // robot 2 is behind robot 0
        assert_eq!(seen.carried, vec![vec![0.1]]); // robot 1's value
        assert_eq!(heard.offsets, vec![0, 2, 4]);
        assert_eq!(heard.ids, vec![1, 3, 0, 1]); // robot 2 is silent; 0 and 3 are 0.9 apart
        assert!(heard.carried.is_empty());
        assert!(perceive(&xs, &ys, &headings, &[4], Some(sight), None, &[]).is_err());
        // Without bearings: the same robots seen (the field of view still decides), no bearings.
        let unturned = Sight {
            bearings: false,
            ..sight
        };
        let (bare, _) = perceive(&xs, &ys, &headings, &[0, 3], Some(unturned), None, &[]).unwrap();
        assert_eq!((bare.ids, bare.dxs), (seen.ids.clone(), seen.dxs.clone()));
        assert!(bare.bearings.is_empty() && seen.bearings.len() == 1);
        // Over a graph: robot 0 is linked to 3 (0.9 away), to itself and to the silent 2.
        let graph: (&[i64], &[i64]) = (&[0, 3, 3, 3, 4], &[3, 0, 2, 0]);
        let at = Some((&xs[..], &ys[..]));
        let heard = linked(at, graph, &[0, 1, 3], &talking).unwrap();
        assert_eq!(heard.offsets, vec![0, 1, 1, 2]);
        assert_eq!(heard.ids, vec![3, 0]);
        assert_eq!(heard.distances, vec![0.9, 0.9]);
        let unmeasured = linked(None, graph, &[0, 1, 3], &talking).unwrap();
        assert_eq!(unmeasured.ids, heard.ids);
        assert!(unmeasured.distances.iter().all(|d| d.is_nan()));
        assert!(linked(at, (&[0, 1, 1, 1, 1], &[4]), &[0], &talking).is_err()); // 4 is no robot
        assert!(linked(at, (&[0, 1, 1, 1, 1], &[4]), &[1], &talking).is_ok()); // row 0 not asked
        assert!(linked(at, (&[0, 2, 1, 1, 1], &[0, 1]), &[1], &talking).is_err());
        assert!(linked(at, graph, &[1, 0], &talking).is_err());
        assert!(perceive(&xs, &ys, &headings, &[0], Some(sight), None, &[&speeds[1..]]).is_err());
    }
}
