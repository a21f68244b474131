//! The motion guard: which robots, driving on at their speed along their heading, would come
//! within a distance of a robot they see (taken as standing) in the next `horizon` seconds.
//! The last check of a command before it is sent; a guarded robot keeps turning, at no speed.

use crate::csr::check_offsets;
use crate::error::{check_finite, check_len, check_positive, Result};
use crate::parallel::map_range;

/// Whether each robot stops: row r (speed `speeds[r]` m/s, heading `headings[r]`) sees the
/// robots at `dx`, `dy` `[offsets[r]..offsets[r + 1]]` (their positions less its own, m). A
/// robot stops when, driving on, it would come closer than `near` (m) to one of them within
/// `horizon` (s) while closing in: one already closer only counts if it closes in further.
///
/// # Errors
/// Length mismatches, non-finite inputs, an invalid CSR, or `near`, `horizon` not > 0.
pub fn stopping(
    speeds: &[f64],
    headings: &[f64],
    offsets: &[i64],
    dx: &[f64],
    dy: &[f64],
    near: f64,
    horizon: f64,
) -> Result<Vec<bool>> {
    let m = speeds.len();
    check_len("headings", m, headings.len())?;
    check_len("offsets", m + 1, offsets.len())?;
    check_len("dy", dx.len(), dy.len())?;
    check_offsets("offsets", offsets, dx.len(), "entries")?;
    for (arg, values) in [("speeds", speeds), ("headings", headings), ("dx", dx), ("dy", dy)] {
        check_finite(arg, values)?;
    }
    check_positive("near", near)?;
    check_positive("horizon", horizon)?;
    // A row costs a sine and a cosine, and a few nanoseconds an entry.
    let ns = 20.0 + 3.0 * (dx.len() / m.max(1)) as f64;
    Ok(map_range(m, ns, |r| {
        let speed = speeds[r];
        // The reach test first (as the NumPy reference filters): farther robots cannot be hit.
        let reach = near + speed.abs() * horizon + 1e-9;
        let closing = [speed * headings[r].cos(), speed * headings[r].sin()];
        // Squared distances reject the far robots cheaply; the margin (far above rounding)
        // leaves every robot the exact test of the reference would keep.
        let beyond = reach * reach * (1.0 + 1e-9);
        (offsets[r] as usize..offsets[r + 1] as usize).any(|e| {
            let apart = [-dx[e], -dy[e]]; // the robot's position less the other's
            apart[0] * apart[0] + apart[1] * apart[1] <= beyond
                && apart[0].hypot(apart[1]) < reach
                && closes_within(apart, closing, near, horizon)
        })
    }))
}

/// Whether two robots `apart` (m) whose difference of velocities is `closing` (m/s) come closer
/// than `near` within `horizon` while closing in (the pair test of the guard).
pub fn closes_within(apart: [f64; 2], closing: [f64; 2], near: f64, horizon: f64) -> bool {
    let speed2 = closing[0] * closing[0] + closing[1] * closing[1];
    let along = apart[0] * closing[0] + apart[1] * closing[1];
    let when = (-along / if speed2 > 0.0 { speed2 } else { 1.0 }).clamp(0.0, horizon);
    let nearest = (apart[0] + closing[0] * when).hypot(apart[1] + closing[1] * when);
    nearest < near.min(apart[0].hypot(apart[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_robot_stops_short_of_one_ahead_and_not_of_one_behind() {
        // Driving east at 0.2 m/s: a robot 0.1 m ahead stops it, one 0.1 m behind does not.
        let ahead = stopping(&[0.2], &[0.0], &[0, 1], &[0.1], &[0.0], 0.12, 0.25).unwrap();
        let behind = stopping(&[0.2], &[0.0], &[0, 1], &[-0.1], &[0.0], 0.12, 0.25).unwrap();
        let standing = stopping(&[0.0], &[0.0], &[0, 1], &[0.1], &[0.0], 0.12, 0.25).unwrap();
        assert_eq!((ahead, behind, standing), (vec![true], vec![false], vec![false]));
    }

    #[test]
    fn bad_input_is_named() {
        let err = stopping(&[0.2], &[0.0], &[0, 2], &[0.1], &[0.0], 0.12, 0.25).unwrap_err();
        assert!(err.to_string().contains("offsets"));
        assert!(stopping(&[0.2], &[0.0], &[0, 1], &[f64::NAN], &[0.0], 0.12, 0.25).is_err());
        assert!(stopping(&[0.2], &[0.0], &[0, 1], &[0.1], &[0.0], 0.0, 0.25).is_err());
    }
}
