//! Voronoi cells of robots that know the others only by what a range radio tells them.
//!
//! Each hearing robot's cell is clipped by the positions it hears, by the robots it sees that no
//! message accounts for, and by its virtual agents: what [`neighbours::within`] (the hearers'
//! rows), [`neighbours::far_from`] and [`voronoi::voronoi_cells`] (without neighbours) give one
//! after the other, to the bit. One pass does it here, looking only at the messages near each
//! cell: a robot in a crowd hears hundreds, of which a dozen shape its cell, and handing every
//! message from kernel to kernel cost more than the cells themselves.
//!
//! The search: a grid of the robots' positions (who hears whom) finds the messages within a
//! growing distance of the cell's site, since a message lies within the largest gap between a
//! robot and what it said. Clipping nearest first in rounds of doubling distance gives the order
//! of clipping them all, and once the cell is settled ([`Clipper::settled`]) the rest change
//! nothing.

use rayon::prelude::*;

use crate::csr::check_offsets;
use crate::draws::Loss;
use crate::error::{check_len, GeomError, Result};
use crate::geom::Arena;
use crate::geom::Vec2;
use crate::grid::Grid;
use crate::neighbours::{in_range, length, radius_squared, Closeness};
use crate::parallel::{first_where, worth_spreading, TASK_ITEMS};
use crate::voronoi::{
    area_centroid, check_cell_parameters, check_coordinates, nearest_first, squared_distance, unit_circle, widest,
    within_reach, Cells, Clipper, PARALLEL_ROBOTS,
};

/// What a range radio lets the robots hear.
#[derive(Debug, Clone, Copy)]
pub struct Radio<'a> {
    /// Where every robot is (n): robots within `range` of each other hear each other.
    pub positions: &'a [Vec2],
    /// Radio range (m), inclusive, as [`crate::neighbours::within`] measures it.
    pub range: f64,
    /// What each robot said before this round (n; NaN: nothing yet)...
    pub said: &'a [Vec2],
    /// ...and after its turn in it (n), which the robots of higher index hear: the robots of one
    /// step take their turns by index.
    pub said_now: &'a [Vec2],
    /// Its losses, drawn for each message looked at (`None`: every message in range is heard):
    /// the messages [`crate::perceive::perceive`] lists with the same loss, to the bit.
    pub loss: Option<Loss>,
    /// The messages lost otherwise, as links `i * n + j` (robot i does not hear robot j),
    /// strictly increasing: what the engine found listing an inbox (a loss burst's).
    pub lost: &'a [i64],
}

/// The robots whose cells are wanted, and what each knows besides its radio.
#[derive(Debug, Clone, Copy)]
pub struct Hearers<'a> {
    /// Their indices among the radio's robots (k, strictly increasing).
    pub ids: &'a [i64],
    /// Where each believes itself (k): its cell's site.
    pub here: &'a [Vec2],
    /// The robots each sees (CSR, k rows): those farther than `same` from every message it
    /// hears clip its cell too, after the messages.
    pub seen_offsets: &'a [i64],
    pub seen: &'a [Vec2],
    pub same: f64,
    /// Its virtual agents (CSR, k rows), clipping after the robots seen.
    pub agents_offsets: &'a [i64],
    pub agents: &'a [Vec2],
}

/// The cells (k rows, see [`Cells`]) of the `hearers`, each the disc of `radius` within the
/// arena clipped by what its robot hears on the `radio` (in order of index), the robots it sees
/// that no message accounts for (in the given order), then its virtual agents, nearest first.
///
/// # Errors
/// Non-finite positions, a message that is neither a point nor all NaN, coordinates beyond
/// [`crate::voronoi::MAX_COORDINATE`], hearer indices that are not strictly increasing robot
/// indices, mismatched lengths or CSR offsets, a negative range or `same`, `lost` links that are
/// not strictly increasing, or the cell parameters of [`crate::voronoi::voronoi_cells`].
pub fn heard_cells(
    radio: &Radio<'_>,
    hearers: &Hearers<'_>,
    radius: f64,
    arena: &Arena,
    resolution: usize,
) -> Result<Cells> {
    check(radio, hearers)?;
    check_cell_parameters(radius, arena, resolution)?;
    let (xs, ys): (Vec<f64>, Vec<f64>) = radio.positions.iter().map(|p| (p[0], p[1])).unzip();
    let drift = drift(radio);
    // A quarter of the farthest a message can be heard from: a crowd's cell settles within the
    // first 3x3 block. At least 1e-150, whose square is still a normal number: below, the squared
    // distances of the rounds underflow and a point beyond the searched box could pass for within.
    let cell = ((radio.range + drift) / 4.0).max(1e-150);
    let search = Search {
        radio,
        hearers,
        grid: Grid::new(&xs, &ys, cell),
        cell,
        drift,
        range_squared: radius_squared(radio.range),
        close: Closeness::new(hearers.same),
        widest: widest_point(radio, hearers),
        circle: unit_circle(resolution),
        radius,
        arena,
    };
    let k = hearers.ids.len();
    let per_robot: Vec<(Vec<Vec2>, f64, Vec2)> = if k >= PARALLEL_ROBOTS {
        (0..k)
            .into_par_iter()
            .map_init(Vec::new, |scratch, r| search.cell(r, scratch))
            .collect()
    } else {
        let mut scratch = Vec::new();
        (0..k).map(|r| search.cell(r, &mut scratch)).collect()
    };
    Ok(Cells::from_rows(per_robot))
}

fn check(radio: &Radio<'_>, hearers: &Hearers<'_>) -> Result<()> {
    let n = radio.positions.len();
    if !(radio.range.is_finite() && radio.range >= 0.0) {
        return Err(GeomError::InvalidParameter {
            arg: "range",
            rule: ">= 0",
            got: radio.range,
        });
    }
    if !(hearers.same.is_finite() && hearers.same >= 0.0) {
        return Err(GeomError::InvalidParameter {
            arg: "same",
            rule: ">= 0",
            got: hearers.same,
        });
    }
    for (arg, said) in messages(radio) {
        check_said(arg, said, n)?;
    }
    if let Some(k) = radio.lost.windows(2).position(|pair| pair[0] >= pair[1]) {
        return Err(GeomError::NotIncreasing {
            arg: "lost",
            index: k + 1,
        });
    }
    // Coordinates within reach of the clipping's arithmetic also keep every search distance finite.
    check_coordinates("positions", radio.positions.as_flattened())?;
    let k = hearers.ids.len();
    check_len("here", k, hearers.here.len())?;
    check_coordinates("here", hearers.here.as_flattened())?;
    let mut previous = -1;
    for &id in hearers.ids {
        if id <= previous || id >= n as i64 {
            return Err(GeomError::InvalidParameter {
                arg: "hearers",
                rule: "strictly increasing robot indices below the number of positions",
                got: id as f64,
            });
        }
        previous = id;
    }
    for (arg, offsets, points) in [
        ("seen", hearers.seen_offsets, hearers.seen),
        ("virtual", hearers.agents_offsets, hearers.agents),
    ] {
        check_len(arg, k + 1, offsets.len())?;
        check_offsets(arg, offsets, points.len(), "points")?;
        check_coordinates(arg, points.as_flattened())?;
    }
    Ok(())
}

/// Fails unless `said` holds one message a robot (`n`), each a point within reach or NaN in
/// both coordinates (nothing said): one pass, on every core for many.
fn check_said(arg: &'static str, said: &[Vec2], n: usize) -> Result<()> {
    check_len(arg, n, said.len())?;
    let wrong = |q: Vec2| q[0].is_nan() != q[1].is_nan() || (!q[0].is_nan() && !q.iter().all(|&v| within_reach(v)));
    let Some(index) = first_where(said.len(), |i| wrong(said[i])) else {
        return Ok(());
    };
    let q = said[index];
    if q[0].is_nan() != q[1].is_nan() {
        return Err(GeomError::PartlyNaN { arg, index });
    }
    let k = usize::from(within_reach(q[0])); // the coordinate out of reach
    check_coordinates(arg, &q[k..=k]).map_err(|error| match error {
        GeomError::NonFinite { arg, .. } => GeomError::NonFinite {
            arg,
            index: 2 * index + k,
        },
        other => other,
    })
}

/// Whether the robots said the same before and after their turns (one array for both: no turns).
fn said_once(radio: &Radio<'_>) -> bool {
    std::ptr::eq(radio.said, radio.said_now)
}

/// The arrays of messages, by name: `said`, and `said_now` unless it is the same array.
fn messages<'a>(radio: &Radio<'a>) -> Vec<(&'static str, &'a [Vec2])> {
    let mut arrays = vec![("said", radio.said)];
    if !said_once(radio) {
        arrays.push(("said_now", radio.said_now));
    }
    arrays
}

/// The largest of `value(i)` for `i < n` (at least 0; NaN passed over), on every core for many.
fn largest(n: usize, value: impl Fn(usize) -> f64 + Sync + Send) -> f64 {
    if worth_spreading(n, 1.0) {
        (0..n)
            .into_par_iter()
            .with_min_len(TASK_ITEMS)
            .map(value)
            .reduce(|| 0.0, f64::max)
    } else {
        (0..n).map(value).fold(0.0, f64::max)
    }
}

/// A bound on how far any message lies from the robot that said it (m): messages near a point
/// are found among the robots within this much more of it. One message far from its robot
/// widens every search by as much (the messages of a range radio lie a few steps of travel off).
fn drift(radio: &Radio<'_>) -> f64 {
    let off = |said: &[Vec2]| {
        largest(said.len(), |i| {
            let q = said[i];
            if q[0].is_nan() {
                0.0
            } else {
                squared_distance(radio.positions[i], q)
            }
        })
    };
    let gap = messages(radio)
        .into_iter()
        .map(|(_, said)| off(said))
        .fold(0.0, f64::max);
    gap.sqrt() * (1.0 + 1e-9)
}

/// [`widest`] of every point a cell may be clipped by: the messages said (NaN: none), the robots
/// seen and the virtual agents, on every core for many.
fn widest_point(radio: &Radio<'_>, hearers: &Hearers<'_>) -> f64 {
    let of = |points: &[Vec2]| {
        largest(points.len(), |i| {
            widest(std::iter::once(points[i]).filter(|q| !q[0].is_nan()))
        })
    };
    let said = messages(radio).into_iter().map(|(_, said)| said);
    said.chain([hearers.seen, hearers.agents]).map(of).fold(0.0, f64::max)
}

/// One call's shared inputs.
struct Search<'a> {
    radio: &'a Radio<'a>,
    hearers: &'a Hearers<'a>,
    grid: Grid,
    cell: f64,
    drift: f64,
    range_squared: f64,
    close: Closeness,
    widest: f64,
    circle: Vec<Vec2>,
    radius: f64,
    arena: &'a Arena,
}

/// A hearer: its index, [`Search::hearer`]'s hash, its lost links and the first link of its row.
type Hearer<'a> = (usize, u64, &'a [i64], i64);

/// A clipping point of a cell: `(|q - p|^2 as bits, rank, index, q)`, clipped in that order
/// (rank 0: messages, by the sender's index; 1: robots seen; 2: virtual agents).
type Candidate = (u64, u8, usize, Vec2);

impl Search<'_> {
    /// Robot i as a hearer: its index, the hash of its loss draws, its row of the lost links and
    /// the row's first link `i * n` (found once a cell).
    fn hearer(&self, i: usize) -> Hearer<'_> {
        let n = self.radio.positions.len() as i64;
        let lost = self.radio.lost;
        let (first, last) = ((i as i64).saturating_mul(n), (i as i64 + 1).saturating_mul(n));
        let row = &lost[lost.partition_point(|&link| link < first)..lost.partition_point(|&link| link < last)];
        (i, self.radio.loss.map_or(0, |loss| loss.hearer(i)), row, first)
    }

    /// What robot `i` hears from robot `j`, if anything.
    fn heard(&self, (i, hash, lost, first): Hearer<'_>, j: usize) -> Option<Vec2> {
        let (p, o) = (self.radio.positions[i], self.radio.positions[j]);
        let (dx, dy) = (o[0] - p[0], o[1] - p[1]);
        if j == i || !in_range(dx, dy, self.radio.range, self.range_squared) {
            return None;
        }
        let q = if j < i {
            self.radio.said_now[j]
        } else {
            self.radio.said[j]
        };
        let through = || {
            let distance = || length(dx * dx + dy * dy, dx, dy);
            self.radio.loss.is_none_or(|loss| loss.delivered(hash, j, distance))
        };
        let kept = || lost.binary_search(&first.saturating_add(j as i64)).is_err();
        (!q[0].is_nan() && through() && kept()).then_some(q)
    }

    /// Calls `visit(j)` for the robots `j` in the square of half-width `half` about `at`, until
    /// one returns true; returns whether one did. The grid's runs cover more (whole cells); the
    /// coordinates in cell order rule those out before anything else of them is read.
    fn robots_near(&self, at: Vec2, half: f64, mut visit: impl FnMut(usize) -> bool) -> bool {
        let (members, (xs, ys)) = (self.grid.members(), self.grid.sorted());
        let pad = half * (1.0 + 1e-9); // above the rounding of the differences
        let mut found = false;
        self.grid.for_each_run_within(at[0], at[1], half, |run| {
            found = found
                || run
                    .into_iter()
                    .any(|m| (xs[m] - at[0]).abs() <= pad && (ys[m] - at[1]).abs() <= pad && visit(members[m]));
        });
        found
    }

    /// Calls `visit(q)` for what robot `i` hears from robots near `at`: every message within
    /// `distance` of it (said by a robot within `distance + drift`), and maybe more.
    fn heard_near(&self, i: Hearer<'_>, at: Vec2, distance: f64, mut visit: impl FnMut(usize, Vec2)) {
        self.robots_near(at, distance + self.drift, |j| {
            if let Some(q) = self.heard(i, j) {
                visit(j, q);
            }
            false
        });
    }

    /// Whether robot `i` hears a message within `same` of the robot it sees at `s`. The search
    /// stops at the first such message: most robots seen are heard, near where they are.
    fn accounted(&self, i: Hearer<'_>, s: Vec2) -> bool {
        self.robots_near(s, self.hearers.same + self.drift, |j| {
            self.heard(i, j).is_some_and(|q| self.close.within(s, q))
        })
    }

    /// Row `r`'s polygon, area and centroid.
    fn cell(&self, r: usize, candidates: &mut Vec<Candidate>) -> (Vec<Vec2>, f64, Vec2) {
        let h = self.hearers;
        let (i, p) = (h.ids[r] as usize, h.here[r]);
        let hearer = self.hearer(i);
        let seen = &h.seen[h.seen_offsets[r] as usize..h.seen_offsets[r + 1] as usize];
        let agents = &h.agents[h.agents_offsets[r] as usize..h.agents_offsets[r + 1] as usize];
        // Every robot seen is a candidate; whether a message accounts for it (then it clips
        // nothing) is asked only of those reached before the cell settles: in a crowd, a few of
        // the dozens seen. The order of the rest is that of the silent ones alone.
        let extras = || {
            let ranked = |rank: u8| move |(k, &q): (usize, &Vec2)| (rank, k, q);
            seen.iter()
                .enumerate()
                .map(ranked(1))
                .chain(agents.iter().enumerate().map(ranked(2)))
        };
        // Beyond this distance from the site no message is heard: the robot's own position is
        // within it of the site, the senders within range of that, the messages within drift
        // (with a margin far above the rounding of the three).
        let own = squared_distance(p, self.radio.positions[i]).sqrt();
        let last_message = (self.radio.range + self.drift + own) * (1.0 + 1e-9);
        let last_extra = extras().map(|(_, _, q)| squared_distance(p, q)).fold(0.0, f64::max);
        let mut clipper = Clipper::new(p, self.radius, self.arena, &self.circle);
        let (mut reach, mut low) = (self.cell, f64::NEG_INFINITY);
        loop {
            // A square that overflows belongs to a box around every robot (coordinates <= 1e100).
            let last = (reach >= last_message && reach * reach >= last_extra) || reach * reach == f64::INFINITY;
            let high = if last { f64::INFINITY } else { reach * reach };
            let window = |d: f64| d > low && d <= high;
            candidates.clear();
            self.heard_near(hearer, p, reach, |j, q| {
                let d = squared_distance(p, q);
                if window(d) {
                    candidates.push((d.to_bits(), 0, j, q));
                }
            });
            for (rank, k, q) in extras() {
                let d = squared_distance(p, q);
                if window(d) {
                    candidates.push((d.to_bits(), rank, k, q));
                }
            }
            let settled = nearest_first(
                candidates,
                |&(d, rank, k, _)| (d, rank, k),
                |&(d, rank, _, q)| {
                    if clipper.settled(f64::from_bits(d), self.widest) {
                        return true;
                    }
                    if !(rank == 1 && self.accounted(hearer, q)) {
                        clipper.cut(q);
                    }
                    false
                },
            );
            if settled {
                return finish(clipper, p);
            }
            // Every later point lies farther than `high`.
            if last || clipper.settled(high, self.widest) {
                return finish(clipper, p);
            }
            (low, reach) = (high, 2.0 * reach);
        }
    }
}

fn finish(clipper: Clipper, p: Vec2) -> (Vec<Vec2>, f64, Vec2) {
    let polygon = clipper.polygon();
    let (area, centroid) = area_centroid(&polygon, p);
    (polygon, area, centroid)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::neighbours::{far_from, within, RowsOf};
    use crate::voronoi::voronoi_cells;

    /// A pseudo-random stream in [0, 1) (no test dependency for a few numbers).
    fn stream(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The same cells from the three kernels one after the other.
    fn composed(radio: &Radio<'_>, hearers: &Hearers<'_>, radius: f64, arena: &Arena) -> Cells {
        let n = radio.positions.len();
        let (xs, ys): (Vec<f64>, Vec<f64>) = radio.positions.iter().map(|p| (p[0], p[1])).unzip();
        let mut rows = vec![false; n];
        hearers.ids.iter().for_each(|&i| rows[i as usize] = true);
        let near = within(&xs, &ys, radio.range, None, None, Some(&rows)).unwrap();
        let mut heard: Vec<Vec<Vec2>> = Vec::new();
        for &i in hearers.ids {
            let i = i as usize;
            let (a, b) = (near.indptr[i] as usize, near.indptr[i + 1] as usize);
            let through = |e: usize| {
                let (j, distance) = (near.indices[e] as usize, near.distances[e]);
                let kept = radio.lost.binary_search(&((i * n + j) as i64)).is_err();
                kept && radio
                    .loss
                    .is_none_or(|loss| loss.delivered(loss.hearer(i), j, || distance))
            };
            heard.push(
                (a..b)
                    .filter(|&e| through(e))
                    .map(|e| {
                        let j = near.indices[e] as usize;
                        if j < i {
                            radio.said_now[j]
                        } else {
                            radio.said[j]
                        }
                    })
                    .filter(|q| !q[0].is_nan())
                    .collect(),
            );
        }
        let mut heard_offsets = vec![0_i64];
        heard
            .iter()
            .for_each(|h| heard_offsets.push(heard_offsets.last().unwrap() + h.len() as i64));
        let flat: Vec<Vec2> = heard.concat();
        let silent = far_from(
            RowsOf {
                points: hearers.seen,
                points_offsets: hearers.seen_offsets,
                others: &flat,
                others_offsets: &heard_offsets,
            },
            hearers.same,
        )
        .unwrap();
        let (mut offsets, mut points) = (vec![0_i64], Vec::new());
        for (r, messages) in heard.iter().enumerate() {
            points.extend(messages);
            let (a, b) = (hearers.seen_offsets[r] as usize, hearers.seen_offsets[r + 1] as usize);
            points.extend((a..b).filter(|&s| silent[s]).map(|s| hearers.seen[s]));
            let (a, b) = (
                hearers.agents_offsets[r] as usize,
                hearers.agents_offsets[r + 1] as usize,
            );
            points.extend(&hearers.agents[a..b]);
            offsets.push(points.len() as i64);
        }
        voronoi_cells(hearers.here, radius, arena, Some((&offsets, &points)), 32, false).unwrap()
    }

    #[test]
    fn equals_the_three_kernels_in_a_row() {
        let lossy = |keep, per_metre| Some(Loss::new(5, 0, 2, keep, per_metre).unwrap());
        for (seed, n, side, range, loss, dropped) in [
            (1, 60, 2.0, 0.6, None, 0.0),
            (2, 300, 3.0, 2.0, None, 0.0),
            (3, 40, 10.0, 1.0, None, 0.0),
            (4, 5, 1.0, 0.0, None, 0.0),
            (5, 300, 3.0, 2.0, lossy(0.7, 0.0), 0.0),
            (6, 200, 2.0, 1.0, lossy(0.9, 0.5), 0.0),
            (7, 300, 3.0, 2.0, None, 0.3),
            (8, 200, 2.0, 1.0, lossy(0.9, 0.0), 0.2),
        ] {
            let mut u = stream(seed);
            let arena = Arena::new(-side / 2.0, side / 2.0, -side / 2.0, side / 2.0).unwrap();
            let positions: Vec<Vec2> = (0..n).map(|_| [side * (u() - 0.5), side * (u() - 0.5)]).collect();
            let moved = |p: &Vec2, u: &mut dyn FnMut() -> f64| {
                if u() < 0.1 {
                    [f64::NAN, f64::NAN]
                } else {
                    [p[0] + 0.05 * (u() - 0.5), p[1] + 0.05 * (u() - 0.5)]
                }
            };
            let said: Vec<Vec2> = positions.iter().map(|p| moved(p, &mut u)).collect();
            let said_now: Vec<Vec2> = said
                .iter()
                .zip(&positions)
                .map(|(q, p)| if u() < 0.3 { moved(p, &mut u) } else { *q })
                .collect();
            let ids: Vec<i64> = (0..n as i64).filter(|_| u() < 0.5).collect();
            // Links lost otherwise (a burst's), in increasing order: some in range, some not.
            let lost: Vec<i64> = (0..(n * n) as i64).filter(|_| u() < dropped).collect();
            let here: Vec<Vec2> = ids
                .iter()
                .map(|&i| [positions[i as usize][0] + 0.02 * (u() - 0.5), positions[i as usize][1]])
                .collect();
            let (mut seen_offsets, mut seen) = (vec![0_i64], Vec::new());
            let (mut agents_offsets, mut agents) = (vec![0_i64], Vec::new());
            for &i in &ids {
                for (j, q) in positions.iter().enumerate() {
                    if j != i as usize && squared_distance(*q, positions[i as usize]) < 0.09 {
                        seen.push([q[0] + 0.1 * (u() - 0.5), q[1] + 0.1 * (u() - 0.5)]);
                    }
                }
                seen_offsets.push(seen.len() as i64);
                if u() < 0.5 {
                    agents.push([side * (u() - 0.5), side * (u() - 0.5)]);
                }
                agents_offsets.push(agents.len() as i64);
            }
            let radio = Radio {
                positions: &positions,
                range,
                said: &said,
                said_now: &said_now,
                loss,
                lost: &lost,
            };
            let hearers = Hearers {
                ids: &ids,
                here: &here,
                seen_offsets: &seen_offsets,
                seen: &seen,
                same: 0.04,
                agents_offsets: &agents_offsets,
                agents: &agents,
            };
            let fused = heard_cells(&radio, &hearers, 0.5, &arena, 32).unwrap();
            assert_eq!(fused, composed(&radio, &hearers, 0.5, &arena), "seed {seed}");
            if loss.is_some() || !lost.is_empty() {
                let lossless = Radio {
                    loss: None,
                    lost: &[],
                    ..radio
                };
                assert_ne!(
                    fused,
                    heard_cells(&lossless, &hearers, 0.5, &arena, 32).unwrap(),
                    "seed {seed}"
                );
            }
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        let positions = [[0.0, 0.0], [1.0, 0.0]];
        let said = [[0.0, 0.0], [f64::NAN, 1.0]];
        let radio = Radio {
            positions: &positions,
            range: 1.0,
            said: &said,
            said_now: &positions,
            loss: None,
            lost: &[],
        };
        let hearers = Hearers {
            ids: &[0],
            here: &[[0.0, 0.0]],
            seen_offsets: &[0, 0],
            seen: &[],
            same: 0.1,
            agents_offsets: &[0, 0],
            agents: &[],
        };
        let arena = Arena::new(-1.0, 1.0, -1.0, 1.0).unwrap();
        assert!(matches!(
            heard_cells(&radio, &hearers, 1.0, &arena, 16),
            Err(GeomError::PartlyNaN { arg: "said", index: 1 })
        ));
        let radio = Radio {
            said: &positions,
            ..radio
        };
        let twice = Hearers {
            ids: &[1, 1],
            here: &[[0.0, 0.0]; 2],
            seen_offsets: &[0, 0, 0],
            agents_offsets: &[0, 0, 0],
            ..hearers
        };
        assert!(heard_cells(&radio, &twice, 1.0, &arena, 16).is_err());
        assert!(heard_cells(&Radio { range: -1.0, ..radio }, &hearers, 1.0, &arena, 16).is_err());
        assert!(matches!(
            heard_cells(&Radio { lost: &[3, 3], ..radio }, &hearers, 1.0, &arena, 16),
            Err(GeomError::NotIncreasing { arg: "lost", index: 1 })
        ));
        assert!(heard_cells(&radio, &hearers, 1.0, &arena, 16).is_ok());
    }

    #[test]
    fn a_message_out_of_reach_is_named_by_its_value_index() {
        let unsaid = [f64::NAN, f64::NAN];
        let check = |said: &[Vec2]| check_said("said", said, said.len());
        assert_eq!(check(&[[0.0, 1.0], unsaid, [2.0, 3.0]]), Ok(()));
        assert_eq!(
            check(&[unsaid, [0.0, f64::INFINITY], [f64::NAN, 1.0]]),
            Err(GeomError::NonFinite { arg: "said", index: 3 })
        );
        assert_eq!(
            check(&[[0.0, 1.0], [f64::NAN, 1.0], [0.0, f64::INFINITY]]),
            Err(GeomError::PartlyNaN { arg: "said", index: 1 })
        );
        assert!(matches!(
            check(&[[0.0, 1.0], [-1e200, 0.0]]),
            Err(GeomError::InvalidParameter { arg: "said", got, .. }) if got == -1e200
        ));
        assert!(matches!(
            check_said("said", &[[0.0, 1.0]], 2),
            Err(GeomError::LengthMismatch { .. })
        ));
    }

    #[test]
    fn one_array_said_before_and_after_gives_what_two_copies_give() {
        let mut next = stream(3);
        let positions: Vec<Vec2> = (0..400).map(|_| [next() * 6.0, next() * 4.0]).collect();
        let said: Vec<Vec2> = positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if i % 7 == 0 {
                    [f64::NAN; 2]
                } else {
                    [p[0] + 0.01, p[1] - 0.02]
                }
            })
            .collect();
        let copy = said.clone();
        let ids: Vec<i64> = (0..400).step_by(3).collect();
        let here: Vec<Vec2> = ids.iter().map(|&i| positions[i as usize]).collect();
        let zeros = vec![0_i64; ids.len() + 1];
        let hearers = Hearers {
            ids: &ids,
            here: &here,
            seen_offsets: &zeros,
            seen: &[],
            same: 0.05,
            agents_offsets: &zeros,
            agents: &[],
        };
        let radio = Radio {
            positions: &positions,
            range: 1.0,
            said: &said,
            said_now: &said,
            loss: None,
            lost: &[],
        };
        assert!(said_once(&radio));
        let arena = Arena::new(0.0, 6.0, 0.0, 4.0).unwrap();
        let twice = Radio {
            said_now: &copy,
            ..radio
        };
        assert!(!said_once(&twice));
        assert_eq!(
            heard_cells(&radio, &hearers, 0.5, &arena, 32).unwrap(),
            heard_cells(&twice, &hearers, 0.5, &arena, 32).unwrap()
        );
        assert_eq!(drift(&radio), drift(&twice));
    }
}
