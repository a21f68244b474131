//! What the robots deciding now perceive of the others, in one pass: the robots their movement
//! sensor sees and the robots their radio hears, as two CSRs over those robots' rows.
//!
//! Robot j is seen by robot i when j != i, `|p_j - p_i| <= sensor range` and the direction from
//! i to j lies within `fov / 2` of `heading_i + direction` (a co-located robot is always seen);
//! it is heard when `|p_j - p_i| <= radio range` and j is talking (has a message out). Each row
//! lists ids in increasing order, and a row is the same whichever other rows are asked: the
//! robots can be perceived for one at a time or all at once.

use std::f64::consts::TAU;

use rayon::prelude::*;

use crate::error::{check_finite, check_len, GeomError, Result};
use crate::neighbours::{wrap_angle, Near};

/// Rows from which the robots are perceived for on every thread.
const PARALLEL_ROWS: usize = 512;

/// A movement sensor's reach: range (m), full aperture `fov` (rad) about the heading turned by
/// `direction` (rad).
#[derive(Debug, Clone, Copy)]
pub struct Sight {
    pub range: f64,
    pub fov: f64,
    pub direction: f64,
}

/// Ragged rows of seen or heard robots: row r is `ids[offsets[r]..offsets[r + 1]]`, with the
/// distance of each and, for the seen ones, the bearing (world frame, from the perceiving robot
/// towards the other) and the offset `(dx, dy)` (the other's position less the perceiving
/// robot's); those three are empty for the heard ones, whom no one needs the direction of.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Perceived {
    pub offsets: Vec<i64>,
    pub ids: Vec<i64>,
    pub distances: Vec<f64>,
    pub bearings: Vec<f64>,
    pub dxs: Vec<f64>,
    pub dys: Vec<f64>,
}

/// One perceived robot: id, distance, bearing and offset.
type Entry = (i64, f64, f64, [f64; 2]);

impl Perceived {
    /// Appends one row, sorted by id, from `row` (which it empties).
    fn push_row(&mut self, row: &mut Vec<Entry>, directions: bool) {
        row.sort_unstable_by_key(|e| e.0);
        for &(j, distance, bearing, offset) in row.iter() {
            self.ids.push(j);
            self.distances.push(distance);
            if directions {
                self.bearings.push(bearing);
                self.dxs.push(offset[0]);
                self.dys.push(offset[1]);
            }
        }
        self.offsets.push(self.ids.len() as i64);
        row.clear();
    }

    /// The rows of `parts` (each with offsets from 0, leading 0 left out) put in the order
    /// `place` gives: `place[r] = (part, row within it)` of output row r.
    fn gather(parts: &[Perceived], place: &[(usize, usize)], directions: bool) -> Perceived {
        let span = |&(p, k): &(usize, usize)| {
            let offsets = &parts[p].offsets;
            let start = if k == 0 { 0 } else { offsets[k - 1] as usize };
            (p, start, offsets[k] as usize)
        };
        let spans: Vec<(usize, usize, usize)> = place.iter().map(span).collect();
        let mut out = Perceived {
            offsets: Vec::with_capacity(place.len() + 1),
            ..Perceived::default()
        };
        out.offsets.push(0);
        for &(_, start, end) in &spans {
            out.offsets
                .push(out.offsets[out.offsets.len() - 1] + (end - start) as i64);
        }
        let total = out.offsets[place.len()] as usize;
        out.ids.reserve(total);
        out.distances.reserve(total);
        for &(p, start, end) in &spans {
            out.ids.extend_from_slice(&parts[p].ids[start..end]);
            out.distances.extend_from_slice(&parts[p].distances[start..end]);
            if directions {
                out.bearings.extend_from_slice(&parts[p].bearings[start..end]);
                out.dxs.extend_from_slice(&parts[p].dxs[start..end]);
                out.dys.extend_from_slice(&parts[p].dys[start..end]);
            }
        }
        out
    }
}

/// Rows one task perceives for: enough to amortise a task, few enough to balance the cores.
const CHUNK_ROWS: usize = 256;

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

/// The robots `rows` (ids) see with `sight` and hear within `radio` (range, and who is talking),
/// among the robots at `(xs[j], ys[j])` heading `headings[j]`.
///
/// # Errors
/// Length mismatches, non-finite positions or headings, negative ranges or ids out of range.
pub fn perceive(
    xs: &[f64],
    ys: &[f64],
    headings: &[f64],
    rows: &[i64],
    sight: Option<Sight>,
    radio: Option<(f64, &[bool])>,
) -> Result<(Perceived, Perceived)> {
    let n = xs.len();
    check_len("ys", n, ys.len())?;
    check_len("headings", n, headings.len())?;
    check_finite("positions", xs)?;
    check_finite("positions", ys)?;
    check_finite("headings", headings)?;
    if let Some(s) = sight {
        check_range("sensor range", s.range)?;
        check_range("fov", s.fov)?;
        check_finite("direction", &[s.direction])?;
    }
    if let Some((range, talking)) = radio {
        check_range("radio range", range)?;
        check_len("talking", n, talking.len())?;
    }
    if let Some(r) = rows.iter().position(|&i| i < 0 || i as usize >= n) {
        return Err(GeomError::InvalidParameter {
            arg: "rows",
            rule: "ids of robots",
            got: rows[r] as f64,
        });
    }
    let reach = sight.map_or(0.0, |s| s.range).max(radio.map_or(0.0, |r| r.0));
    let near = Near::new(xs, ys, reach);
    // One task's rows (indices into `rows`), each row sorted by id; offsets without the leading 0.
    let chunk = |task: &[usize]| {
        let (mut seen, mut heard) = (Perceived::default(), Perceived::default());
        let (mut scratch, mut seen_row, mut heard_row) = (Vec::new(), Vec::new(), Vec::new());
        for &r in task {
            let i = rows[r] as usize;
            near.for_each(i, &mut scratch, |j, offset, distance| {
                if let Some(s) = sight {
                    if distance <= s.range {
                        let bearing = offset[1].atan2(offset[0]);
                        let ahead = s.fov >= TAU
                            || distance == 0.0
                            || wrap_angle(bearing - (headings[i] + s.direction)).abs() <= s.fov / 2.0;
                        if ahead {
                            seen_row.push((j as i64, distance, bearing, offset));
                        }
                    }
                }
                if let Some((range, talking)) = radio {
                    if distance <= range && talking[j] {
                        heard_row.push((j as i64, distance, 0.0, [0.0; 2]));
                    }
                }
            });
            seen.push_row(&mut seen_row, true);
            heard.push_row(&mut heard_row, false);
        }
        (seen, heard)
    };
    // The rows go in the grid's cell order, so that a task's robots share their cells' memory
    // (in the given order, robots spread at random touch a new part of the arena each time).
    let mut rank = vec![0_usize; n];
    for (k, &i) in near.order().iter().enumerate() {
        rank[i] = k;
    }
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.sort_unstable_by_key(|&r| rank[rows[r] as usize]);
    let parts: Vec<(Perceived, Perceived)> = if rows.len() >= PARALLEL_ROWS {
        order.par_chunks(CHUNK_ROWS).map(chunk).collect()
    } else {
        vec![chunk(&order)]
    };
    let chunk_rows = if rows.len() >= PARALLEL_ROWS {
        CHUNK_ROWS
    } else {
        rows.len().max(1)
    };
    let mut place = vec![(0, 0); rows.len()];
    for (k, &r) in order.iter().enumerate() {
        place[r] = (k / chunk_rows, k % chunk_rows);
    }
    let (seen, heard): (Vec<Perceived>, Vec<Perceived>) = parts.into_iter().unzip();
    Ok((
        Perceived::gather(&seen, &place, true),
        Perceived::gather(&heard, &place, false),
    ))
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
        };
        let talking = [true, true, false, true];
        let (seen, heard) = perceive(&xs, &ys, &headings, &[0, 3], Some(sight), Some((1.0, &talking))).unwrap();
        assert_eq!(seen.offsets, vec![0, 1, 1]);
        assert_eq!(seen.ids, vec![1]); // robot 2 is behind robot 0
        assert_eq!(heard.offsets, vec![0, 2, 4]);
        assert_eq!(heard.ids, vec![1, 3, 0, 1]); // robot 2 is silent; 0 and 3 are 0.9 apart
        assert!(perceive(&xs, &ys, &headings, &[4], Some(sight), None).is_err());
    }
}
