//! What the robots deciding now perceive of the others, in one pass: the robots their movement
//! sensor sees and the robots their radio hears, as two CSRs over those robots' rows.
//!
//! Robot j is seen by robot i when j != i, `|p_j - p_i| <= sensor range` and the direction from
//! i to j lies within `fov / 2` of `heading_i + direction` (a co-located robot is always seen);
//! it is heard when `|p_j - p_i| <= radio range` and j is talking (has a message out). Each row
//! lists ids in increasing order, and a row is the same whichever other rows are asked: the
//! robots can be perceived for one at a time or all at once. Distances are the neighbour
//! query's, to the bit. Per-robot values `carried` (the velocities a movement sensor reports,
//! say) are read at each robot seen, on every core.
//!
//! A radio over a communication graph ([`linked`]) is heard by its links instead, whatever the
//! distance.

use std::f64::consts::TAU;

use rayon::prelude::*;

use crate::error::{check_finite, check_len, try_filled, try_room, GeomError, Result};
use crate::grid::Grid;
use crate::neighbours::{length, radius_squared, wrap_angle};
use crate::parallel::{gather_rows, join_if, map_range, worth_spreading, TASK_ITEMS};

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
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Perceived {
    pub offsets: Vec<i64>,
    pub ids: Vec<i64>,
    pub distances: Vec<f64>,
    pub bearings: Vec<f64>,
    pub dxs: Vec<f64>,
    pub dys: Vec<f64>,
    pub carried: Vec<Vec<f64>>,
}

/// Rows from which the robots are perceived for on every thread.
const PARALLEL_ROWS: usize = 512;

/// Rows one task finds: enough to amortise a task, few enough to balance the cores.
const TASK_ROWS: usize = 256;

/// What one task found, its rows in the order it went through them: the `t`-th is row
/// `rows[t]` (an index into the asked rows), with `seen_counts[t]` entries in `seen`'s columns
/// and `heard_counts[t]` in `heard`'s (their offsets are left empty).
#[derive(Debug, Default)]
struct Part {
    rows: Vec<u32>,
    seen_counts: Vec<u32>,
    heard_counts: Vec<u32>,
    seen: Perceived,
    heard: Perceived,
}

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
/// longer range; the robots asked for go cell by cell (those of one cell share their candidates,
/// and neighbouring robots' data share cache lines), each finding what it sees and hears in one
/// pass, and the rows are then copied into row order on every core. Each of `carried` holds one
/// value per robot, read at every robot seen.
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
    radio: Option<(f64, &[bool])>,
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
    if let Some((range, talking)) = radio {
        check_range("radio range", range)?;
        check_len("talking", n, talking.len())?;
    }
    check_rows(rows, n)?;
    let reach = sight.map_or(0.0, |s| s.range).max(radio.map_or(0.0, |r| r.0));
    // Any cell >= reach finds every robot in reach; reach 0 only needs identical points together.
    let grid = Grid::new(xs, ys, if reach > 0.0 { reach } else { 1.0 });
    let find = Find {
        grid: &grid,
        xs,
        ys,
        headings,
        reach,
        reach_squared: radius_squared(reach),
        sight,
        radio,
    };
    let parts: Vec<Part> = if rows.len() >= PARALLEL_ROWS {
        // The asked robots in the grid's cell order, as (robot, row).
        let mut row_of = Vec::new();
        try_room(&mut row_of, n, "perceived robots")?;
        row_of.resize(n, u32::MAX);
        for (r, &i) in rows.iter().enumerate() {
            row_of[i as usize] = r as u32;
        }
        let asked = |&i: &usize| (row_of[i] != u32::MAX).then(|| (i, row_of[i]));
        let members = grid.members();
        let order: Vec<(usize, u32)> = if worth_spreading(n, 1.0) {
            members.par_iter().with_min_len(TASK_ITEMS).filter_map(asked).collect()
        } else {
            members.iter().filter_map(asked).collect()
        };
        drop(row_of);
        order
            .par_chunks(TASK_ROWS)
            .map(|task| find.part(task))
            .collect::<Result<_>>()?
    } else {
        let order: Vec<(usize, u32)> = rows.iter().enumerate().map(|(r, &i)| (i as usize, r as u32)).collect();
        vec![find.part(&order)?]
    };
    let bearings = sight.is_some_and(|s| s.bearings);
    let (mut seen, heard) = in_row_order(&parts, rows.len(), bearings)?;
    seen.carried = carried
        .iter()
        .map(|values| map_range(seen.ids.len(), 1.0, |e| values[seen.ids[e] as usize]))
        .collect();
    Ok((seen, heard))
}

/// Fails unless `rows` are increasing ids of the `n` robots (fewer than `u32::MAX`).
fn check_rows(rows: &[i64], n: usize) -> Result<()> {
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
    xs: &'a [f64],
    ys: &'a [f64],
    headings: &'a [f64],
    reach: f64,
    /// A hair above reach^2: beyond it a robot is surely out; below it `sqrt` decides exactly.
    reach_squared: f64,
    sight: Option<Sight>,
    radio: Option<(f64, &'a [bool])>,
}

impl Find<'_> {
    /// What the robots `task` (robot, row) see and hear.
    fn part(&self, task: &[(usize, u32)]) -> Result<Part> {
        const WHAT: &str = "perceived robots";
        let mut part = Part::default();
        try_room(&mut part.rows, task.len(), WHAT)?;
        try_room(&mut part.seen_counts, task.len(), WHAT)?;
        try_room(&mut part.heard_counts, task.len(), WHAT)?;
        let mut shared = Shared::default();
        let mut near: Vec<Near> = Vec::new();
        for &(i, r) in task {
            near.clear();
            self.near(i, &mut shared, &mut near);
            let (seen_before, heard_before) = (part.seen.ids.len(), part.heard.ids.len());
            self.sort_out(i, &near, &mut part)?;
            part.rows.push(r);
            part.seen_counts.push((part.seen.ids.len() - seen_before) as u32);
            part.heard_counts.push((part.heard.ids.len() - heard_before) as u32);
        }
        Ok(part)
    }

    /// The robots near robot i, by increasing id, from candidates shared with the robot before
    /// it when both are in one cell: the 3x3 block around it, sorted once. (Each robot sorting
    /// only the few dozen in its reach, read from the grid in place, measured 1.2-1.4 times
    /// slower, even with a fifth of the robots asked for, about one a cell.)
    fn near(&self, i: usize, shared: &mut Shared, near: &mut Vec<Near>) {
        let (x, y) = (self.xs[i], self.ys[i]);
        let cell = self.grid.cell_of(x, y);
        let Shared {
            cell: last,
            ids,
            xs,
            ys,
        } = shared;
        if *last != Some(cell) {
            *last = Some(cell);
            ids.clear();
            self.grid
                .for_each_cell_near(x, y, |members| ids.extend_from_slice(members));
            ids.sort_unstable();
            xs.clear();
            ys.clear();
            xs.extend(ids.iter().map(|&j| self.xs[j]));
            ys.extend(ids.iter().map(|&j| self.ys[j]));
        }
        // No data-dependent branch in the hot loop (it measured 1.4 times slower with one):
        // every candidate is written, the count only advances for those that may be in reach.
        near.resize(ids.len(), Near::default());
        let mut count = 0;
        for ((&cx, &cy), &j) in xs.iter().zip(ys.iter()).zip(ids.iter()) {
            let (dx, dy) = (cx - x, cy - y);
            let squared = dx * dx + dy * dy;
            near[count] = Near { j, dx, dy, squared };
            count += usize::from((squared <= self.reach_squared) & (j != i));
        }
        near.truncate(count);
    }

    /// What robot i sees and hears of the robots `near` it, appended to the part's columns.
    fn sort_out(&self, i: usize, near: &[Near], part: &mut Part) -> Result<()> {
        let Part { seen, heard, .. } = part;
        // At most every robot in reach, seen and heard.
        if let Some(s) = self.sight {
            seen.room(near.len(), true, s.bearings)?;
        }
        if self.radio.is_some() {
            heard.room(near.len(), false, false)?;
        }
        for &Near { j, dx, dy, squared } in near {
            let distance = length(squared, dx, dy);
            if distance > self.reach {
                continue;
            }
            if let Some(s) = self.sight {
                if distance <= s.range {
                    let bearing = (s.bearings || s.fov < TAU).then(|| dy.atan2(dx));
                    let ahead = s.fov >= TAU
                        || distance == 0.0
                        || bearing
                            .is_some_and(|b| wrap_angle(b - (self.headings[i] + s.direction)).abs() <= s.fov / 2.0);
                    if ahead {
                        seen.ids.push(j as i64);
                        seen.distances.push(distance);
                        if let (true, Some(b)) = (s.bearings, bearing) {
                            seen.bearings.push(b);
                        }
                        seen.dxs.push(dx);
                        seen.dys.push(dy);
                    }
                }
            }
            if let Some((range, talking)) = self.radio {
                if distance <= range && talking[j] {
                    heard.ids.push(j as i64);
                    heard.distances.push(distance);
                }
            }
        }
        Ok(())
    }
}

/// A robot within reach (by the squared distance's margin) of the one perceiving: its id, its
/// offset from it and the offset's squared length.
#[derive(Debug, Clone, Copy, Default)]
struct Near {
    j: usize,
    dx: f64,
    dy: f64,
    squared: f64,
}

/// The candidates of the last cell a task went through: its 3x3 block's robots by increasing id,
/// with their coordinates.
#[derive(Debug, Default)]
struct Shared {
    cell: Option<(i64, i64)>,
    ids: Vec<usize>,
    xs: Vec<f64>,
    ys: Vec<f64>,
}

impl Perceived {
    /// Room for `count` more entries; the offsets only where `seen`, the bearings where `bearings`.
    fn room(&mut self, count: usize, seen: bool, bearings: bool) -> Result<()> {
        const WHAT: &str = "perceived robots";
        try_room(&mut self.ids, count, WHAT)?;
        try_room(&mut self.distances, count, WHAT)?;
        if bearings {
            try_room(&mut self.bearings, count, WHAT)?;
        }
        if seen {
            try_room(&mut self.dxs, count, WHAT)?;
            try_room(&mut self.dys, count, WHAT)?;
        }
        Ok(())
    }
}

/// The parts' rows, seen and heard, in row order (`rows` of them), the columns side by side; the
/// bearings where the parts have them.
fn in_row_order(parts: &[Part], rows: usize, with_bearings: bool) -> Result<(Perceived, Perceived)> {
    const WHAT: &str = "perceived robots";
    // Each row's part and where its entries start in that part's seen and heard columns.
    let mut at = try_filled(rows, (0_usize, 0_usize, 0_usize), WHAT)?;
    let mut seen_offsets = try_filled(rows + 1, 0_i64, WHAT)?;
    let mut heard_offsets = try_filled(rows + 1, 0_i64, WHAT)?;
    for (p, part) in parts.iter().enumerate() {
        let (mut seen_from, mut heard_from) = (0, 0);
        for ((&r, &seen), &heard) in part.rows.iter().zip(&part.seen_counts).zip(&part.heard_counts) {
            let r = r as usize;
            at[r] = (p, seen_from, heard_from);
            seen_offsets[r + 1] = i64::from(seen);
            heard_offsets[r + 1] = i64::from(heard);
            (seen_from, heard_from) = (seen_from + seen as usize, heard_from + heard as usize);
        }
    }
    for r in 0..rows {
        seen_offsets[r + 1] += seen_offsets[r];
        heard_offsets[r + 1] += heard_offsets[r];
    }
    let seen_at = |r: usize| (&parts[at[r].0].seen, at[r].1);
    let heard_at = |r: usize| (&parts[at[r].0].heard, at[r].2);
    let seen_ids = || gather_rows(&seen_offsets, |r| (&seen_at(r).0.ids[..], seen_at(r).1), WHAT);
    let seen_column =
        |of: fn(&Perceived) -> &Vec<f64>| gather_rows(&seen_offsets, |r| (&of(seen_at(r).0)[..], seen_at(r).1), WHAT);
    let heard_ids = || gather_rows(&heard_offsets, |r| (&heard_at(r).0.ids[..], heard_at(r).1), WHAT);
    let heard_distances = || gather_rows(&heard_offsets, |r| (&heard_at(r).0.distances[..], heard_at(r).1), WHAT);
    // The seven columns copied side by side where there is much to copy: each is a pass over
    // fresh memory, bound by its page faults and cache misses.
    let spread = worth_spreading(
        (4 + usize::from(with_bearings)) * seen_offsets[rows] as usize + 2 * heard_offsets[rows] as usize,
        1.0,
    );
    let (((ids, distances), (bearings, (dxs, dys))), (heard_ids, heard_distances)) = join_if(
        spread,
        || {
            join_if(
                spread,
                || join_if(spread, seen_ids, || seen_column(|p| &p.distances)),
                || {
                    join_if(
                        spread,
                        || {
                            if with_bearings {
                                seen_column(|p| &p.bearings)
                            } else {
                                Ok(Vec::new())
                            }
                        },
                        || join_if(spread, || seen_column(|p| &p.dxs), || seen_column(|p| &p.dys)),
                    )
                },
            )
        },
        || join_if(spread, heard_ids, heard_distances),
    );
    let seen = Perceived {
        offsets: seen_offsets,
        ids: ids?,
        distances: distances?,
        bearings: bearings?,
        dxs: dxs?,
        dys: dys?,
        carried: Vec::new(),
    };
    let heard = Perceived {
        offsets: heard_offsets,
        ids: heard_ids?,
        distances: heard_distances?,
        ..Perceived::default()
    };
    Ok((seen, heard))
}

#[cfg(test)]
mod tests {
    use super::*;

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
            Some((1.0, &talking)),
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
