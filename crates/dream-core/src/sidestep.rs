//! Stepping aside, on the swarm engine's tables: each robot's decisions left stepping aside
//! (`counters`) and its side (`sides`: 1 right, -1 left), read and written in place at the rows
//! deciding now. The rule is `dream.rules.sidestep_preference` and `sidestep_update`:
//! - a robot stepping aside asks HRVO for its wished velocity turned a quarter turn to its side,
//!   and counts one decision down;
//! - a robot that wished to move and was stopped steps aside for the next `updates` decisions, to
//!   its right, or to the other side if it was stepping aside already.
//!
//! The rows are a scattered fifth of a swarm: gathered, turned and scattered back by NumPy, the
//! rule cost 12 ms a step at a million robots, all of it on one core. Here tasks of consecutive
//! rows (increasing ids) each write the stretch of the tables between their first robot and the
//! next task's, on every core for many.

use rayon::prelude::*;

use crate::csr::check_rows;
use crate::error::{check_len, Result};
use crate::parallel::{split, worth_spreading};

/// Rows one task takes.
const TASK_ROWS: usize = 4096;

/// What the robots `rows` (increasing ids below `n`) ask HRVO for, `(k, 2)` row-major as `want`:
/// `want` itself, or turned to the robot's side while its counter is above zero, which then
/// counts down. `counters` and `sides` hold one value per robot. With `steer`, only the rows it
/// flags (those that go through HRVO): the others ask for `want` and keep their counters.
///
/// # Errors
/// Length mismatches, or rows that are not increasing robot ids.
pub fn ask(
    want: &[f64],
    rows: &[i64],
    counters: &mut [i64],
    sides: &[f64],
    steer: Option<&[bool]>,
) -> Result<Vec<f64>> {
    let n = counters.len();
    check(want, rows, n, sides, steer)?;
    let steered = |r: usize| steer.is_none_or(|steer| steer[r]);
    let mut asked = want.to_vec();
    let bounds = bounds(rows, n);
    let task = |(((r0, rows), asked), (counters, &first)): (((usize, &[i64]), &mut [f64]), (&mut [i64], &usize))| {
        for (r, &i) in rows.iter().enumerate() {
            let i = i as usize;
            let counter = &mut counters[i - first];
            if *counter > 0 && steered(r0 + r) {
                let (s, [x, y]) = (sides[i], [asked[2 * r], asked[2 * r + 1]]);
                (asked[2 * r], asked[2 * r + 1]) = (s * y, s * -x);
                *counter -= 1;
            }
        }
    };
    let tasks = (0..)
        .step_by(TASK_ROWS)
        .zip(rows.chunks(TASK_ROWS))
        .zip(asked.chunks_mut(2 * TASK_ROWS))
        .zip(split(counters, &bounds).into_iter().zip(&bounds));
    if worth_spreading(rows.len(), 4.0) {
        tasks.collect::<Vec<_>>().into_par_iter().for_each(task);
    } else {
        tasks.for_each(task);
    }
    Ok(asked)
}

/// Marks the robots `rows` that HRVO stopped (`chosen` zero) though they wished to move (`want`
/// not zero; a NaN component counts as not zero): each steps aside for `updates` decisions, to
/// its right, or to the other side if its counter was still running. With `steer`, only the
/// rows it flags.
///
/// # Errors
/// Length mismatches, or rows that are not increasing robot ids.
#[allow(clippy::too_many_arguments)]
pub fn mark(
    chosen: &[f64],
    want: &[f64],
    rows: &[i64],
    counters: &mut [i64],
    sides: &mut [f64],
    updates: i64,
    steer: Option<&[bool]>,
) -> Result<()> {
    let n = counters.len();
    check(want, rows, n, sides, steer)?;
    let steered = |r: usize| steer.is_none_or(|steer| steer[r]);
    check_len("chosen", want.len(), chosen.len())?;
    let bounds = bounds(rows, n);
    let task = |((((r0, rows), first), (chosen, want)), (counters, sides)): (
        (((usize, &[i64]), &usize), (&[f64], &[f64])),
        (&mut [i64], &mut [f64]),
    )| {
        for (r, &i) in rows.iter().enumerate() {
            let i = i as usize - first;
            let stopped = chosen[2 * r] == 0.0 && chosen[2 * r + 1] == 0.0;
            let wished = want[2 * r] != 0.0 || want[2 * r + 1] != 0.0;
            if stopped && wished && steered(r0 + r) {
                sides[i] = if counters[i] > 0 { -sides[i] } else { 1.0 };
                counters[i] = updates;
            }
        }
    };
    let tasks = (0..)
        .step_by(TASK_ROWS)
        .zip(rows.chunks(TASK_ROWS))
        .zip(&bounds)
        .zip(chosen.chunks(2 * TASK_ROWS).zip(want.chunks(2 * TASK_ROWS)))
        .zip(split(counters, &bounds).into_iter().zip(split(sides, &bounds)));
    if worth_spreading(rows.len(), 4.0) {
        tasks.collect::<Vec<_>>().into_par_iter().for_each(task);
    } else {
        tasks.for_each(task);
    }
    Ok(())
}

fn check(want: &[f64], rows: &[i64], n: usize, sides: &[f64], steer: Option<&[bool]>) -> Result<()> {
    check_len("sides", n, sides.len())?;
    check_len("want", 2 * rows.len(), want.len())?;
    if let Some(steer) = steer {
        check_len("steer", rows.len(), steer.len())?;
    }
    check_rows(rows, n)
}

/// Where each task's stretch of the tables starts (its first robot; 0 for the first task), and
/// `n`: each task's rows lie in its stretch, since the rows increase.
fn bounds(rows: &[i64], n: usize) -> Vec<usize> {
    let mut bounds: Vec<usize> = rows.iter().step_by(TASK_ROWS).map(|&i| i as usize).collect();
    if let Some(first) = bounds.first_mut() {
        *first = 0;
    }
    bounds.push(n);
    bounds
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_robot_stopped_steps_aside_then_back() {
        let (mut counters, mut sides) = (vec![0, 0, 2], vec![1.0, -1.0, -1.0]);
        let want = [1.0, 2.0, 0.5, 0.0];
        // Robot 0 is not stepping aside; robot 2 is, to its left: (x, y) turned to (-y, x).
        let asked = ask(&want, &[0, 2], &mut counters, &sides, None).unwrap();
        assert_eq!(asked, vec![1.0, 2.0, -0.0, 0.5]);
        assert_eq!(counters, vec![0, 0, 1]);
        // Both stopped: robot 0 starts to its right, robot 2 (still counting) turns the other way.
        mark(
            &[0.0, 0.0, 0.0, -0.0],
            &want,
            &[0, 2],
            &mut counters,
            &mut sides,
            10,
            None,
        )
        .unwrap();
        assert_eq!(
            (counters.clone(), sides.clone()),
            (vec![10, 0, 10], vec![1.0, -1.0, 1.0])
        );
        // A robot that wished nothing is not blocked, nor is one that moves.
        mark(
            &[0.0, 0.0, 0.1, 0.0],
            &[0.0, 0.0, 1.0, 1.0],
            &[0, 1],
            &mut counters,
            &mut sides,
            3,
            None,
        )
        .unwrap();
        assert_eq!(counters, vec![10, 0, 10]);
    }

    #[test]
    fn bad_rows_and_lengths_are_errors() {
        let (mut counters, sides) = (vec![0; 3], vec![1.0; 3]);
        assert!(ask(&[0.0; 4], &[1, 1], &mut counters, &sides, None).is_err());
        assert!(ask(&[0.0; 2], &[3], &mut counters, &sides, None).is_err());
        assert!(ask(&[0.0; 3], &[1], &mut counters, &sides, None).is_err());
        assert!(ask(&[0.0; 2], &[1], &mut counters, &sides[..2], None).is_err());
        let mut sides = sides;
        assert!(mark(&[0.0; 4], &[1.0; 2], &[1], &mut counters, &mut sides, 1, None).is_err());
        assert!(ask(&[0.0; 2], &[1], &mut counters, &sides, Some(&[true, false])).is_err());
    }
}
