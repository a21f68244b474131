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
/// distance and the bearing (world frame, from the perceiving robot towards the other) of each.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Perceived {
    pub offsets: Vec<i64>,
    pub ids: Vec<i64>,
    pub distances: Vec<f64>,
    pub bearings: Vec<f64>,
}

impl Perceived {
    fn from_rows(rows: Vec<Vec<(i64, f64, f64)>>) -> Self {
        let total = rows.iter().map(Vec::len).sum();
        let mut out = Perceived {
            offsets: Vec::with_capacity(rows.len() + 1),
            ids: Vec::with_capacity(total),
            distances: Vec::with_capacity(total),
            bearings: Vec::with_capacity(total),
        };
        out.offsets.push(0);
        for row in rows {
            for (j, distance, bearing) in row {
                out.ids.push(j);
                out.distances.push(distance);
                out.bearings.push(bearing);
            }
            out.offsets.push(out.ids.len() as i64);
        }
        out
    }
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
    let row = |scratch: &mut Vec<(usize, f64)>, i: usize| {
        let (mut seen, mut heard) = (Vec::new(), Vec::new());
        near.for_each(i, scratch, |j, offset, distance| {
            let bearing = offset[1].atan2(offset[0]);
            if let Some(s) = sight {
                let ahead = s.fov >= TAU || distance == 0.0 || {
                    wrap_angle(bearing - (headings[i] + s.direction)).abs() <= s.fov / 2.0
                };
                if distance <= s.range && ahead {
                    seen.push((j as i64, distance, bearing));
                }
            }
            if let Some((range, talking)) = radio {
                if distance <= range && talking[j] {
                    heard.push((j as i64, distance, bearing));
                }
            }
        });
        seen.sort_unstable_by_key(|e| e.0);
        heard.sort_unstable_by_key(|e| e.0);
        (seen, heard)
    };
    let both: Vec<_> = if rows.len() >= PARALLEL_ROWS {
        rows.par_iter()
            .map_init(Vec::new, |scratch, &i| row(scratch, i as usize))
            .collect()
    } else {
        let mut scratch = Vec::new();
        rows.iter().map(|&i| row(&mut scratch, i as usize)).collect()
    };
    let (seen, heard): (Vec<_>, Vec<_>) = both.into_iter().unzip();
    Ok((Perceived::from_rows(seen), Perceived::from_rows(heard)))
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
