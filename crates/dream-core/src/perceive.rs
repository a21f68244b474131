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

use std::f64::consts::TAU;

use rayon::prelude::*;

use crate::error::{check_finite, check_len, try_room, GeomError, Result};
use crate::neighbours::{within, wrap_angle};
use crate::parallel::{concat, map_range};

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

impl Perceived {
    /// Room for `count` more entries (and `rows` more rows); the bearings and offsets only
    /// where `seen`.
    fn room(&mut self, rows: usize, count: usize, seen: bool) -> Result<()> {
        const WHAT: &str = "perceived robots";
        try_room(&mut self.offsets, rows, WHAT)?;
        try_room(&mut self.ids, count, WHAT)?;
        try_room(&mut self.distances, count, WHAT)?;
        if seen {
            try_room(&mut self.bearings, count, WHAT)?;
            try_room(&mut self.dxs, count, WHAT)?;
            try_room(&mut self.dys, count, WHAT)?;
        }
        Ok(())
    }

    /// The parts' rows one after the other (each part's offsets start at 0, the leading 0 left
    /// out, so each is shifted by the entries before it).
    fn join(parts: &[Perceived]) -> Result<Self> {
        const WHAT: &str = "perceived robots";
        let mut shifted = Vec::with_capacity(parts.len() + 1);
        shifted.push(vec![0_i64]);
        let mut base = 0_i64;
        for part in parts {
            shifted.push(part.offsets.iter().map(|o| o + base).collect());
            base += part.ids.len() as i64;
        }
        let column =
            |of: fn(&Perceived) -> &Vec<f64>| concat(&parts.iter().map(|p| &of(p)[..]).collect::<Vec<_>>(), WHAT);
        Ok(Perceived {
            offsets: concat(&shifted.iter().map(|o| &o[..]).collect::<Vec<_>>(), WHAT)?,
            ids: concat(&parts.iter().map(|p| &p.ids[..]).collect::<Vec<_>>(), WHAT)?,
            distances: column(|p| &p.distances)?,
            bearings: column(|p| &p.bearings)?,
            dxs: column(|p| &p.dxs)?,
            dys: column(|p| &p.dys)?,
            carried: Vec::new(),
        })
    }
}

/// Rows one task sorts out: enough to amortise a task, few enough to balance the cores.
const CHUNK_ROWS: usize = 1024;

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
/// is talking), among the robots at `(xs[j], ys[j])` heading `headings[j]`: one neighbour query
/// within the longer range ([`within`]), whose rows are then sorted out into the two. Each of
/// `carried` holds one value per robot, read at every robot seen.
///
/// # Errors
/// Length mismatches, non-finite positions or headings, negative ranges, or rows that are not
/// increasing ids of robots.
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
    let mut asked = vec![false; n];
    for (r, &i) in rows.iter().enumerate() {
        if i < 0 || i as usize >= n || (r > 0 && i <= rows[r - 1]) {
            return Err(GeomError::InvalidCsr {
                arg: "rows",
                rows: rows.len(),
                reason: format!("row {r} is {i}: rows must be increasing robot ids below {n}"),
            });
        }
        asked[i as usize] = true;
    }
    let reach = sight.map_or(0.0, |s| s.range).max(radio.map_or(0.0, |r| r.0));
    let near = within(xs, ys, reach, None, None, Some(&asked))?;
    // Every robot in reach talking, over the longest range: the query's rows are what is heard,
    // as they stand (the rows not asked are empty, so the entries are the asked rows' in order).
    let all_heard = radio.is_some_and(|(range, talking)| range >= reach && talking.iter().all(|&t| t));
    let sort_out = |task: &[i64]| -> Result<(Perceived, Perceived)> {
        let (mut seen, mut heard) = (Perceived::default(), Perceived::default());
        for &i in task {
            let i = i as usize;
            let entries = near.indptr[i] as usize..near.indptr[i + 1] as usize;
            // At most every robot in reach, seen and heard.
            let (may_see, may_hear) = (sight.is_some(), radio.is_some() && !all_heard);
            seen.room(1, usize::from(may_see) * entries.len(), true)?;
            heard.room(1, usize::from(may_hear) * entries.len(), false)?;
            for (&j, &distance) in near.indices[entries.clone()].iter().zip(&near.distances[entries]) {
                let ju = j as usize;
                if let Some(s) = sight {
                    if distance <= s.range {
                        let offset = [xs[ju] - xs[i], ys[ju] - ys[i]];
                        let bearing = offset[1].atan2(offset[0]);
                        let ahead = s.fov >= TAU
                            || distance == 0.0
                            || wrap_angle(bearing - (headings[i] + s.direction)).abs() <= s.fov / 2.0;
                        if ahead {
                            seen.ids.push(j);
                            seen.distances.push(distance);
                            seen.bearings.push(bearing);
                            seen.dxs.push(offset[0]);
                            seen.dys.push(offset[1]);
                        }
                    }
                }
                if let Some((range, talking)) = radio {
                    if !all_heard && distance <= range && talking[ju] {
                        heard.ids.push(j);
                        heard.distances.push(distance);
                    }
                }
            }
            seen.offsets.push(seen.ids.len() as i64);
            heard.offsets.push(heard.ids.len() as i64);
        }
        Ok((seen, heard))
    };
    let parts: Vec<(Perceived, Perceived)> = if rows.len() >= PARALLEL_ROWS {
        rows.par_chunks(CHUNK_ROWS).map(sort_out).collect::<Result<_>>()?
    } else {
        vec![sort_out(rows)?]
    };
    let (seen, heard): (Vec<Perceived>, Vec<Perceived>) = parts.into_iter().unzip();
    let (mut seen, mut heard) = (Perceived::join(&seen)?, Perceived::join(&heard)?);
    seen.carried = carried
        .iter()
        .map(|values| map_range(seen.ids.len(), |e| values[seen.ids[e] as usize]))
        .collect();
    if all_heard {
        heard.offsets = rows.iter().map(|&i| near.indptr[i as usize]).collect();
        heard.offsets.push(near.indptr[n]);
        (heard.ids, heard.distances) = (near.indices, near.distances);
    }
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
        assert!(perceive(&xs, &ys, &headings, &[0], Some(sight), None, &[&speeds[1..]]).is_err());
    }
}
