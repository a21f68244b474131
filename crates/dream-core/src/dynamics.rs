//! Unicycle dynamics and the Robotarium's validation, for the whole swarm at once.
//!
//! Poses are `(3, n)` row-major (`x` row, `y` row, `theta` row) and unicycle commands `(2, n)`
//! (`v` row, `w` row), the Robotarium's layout, so NumPy arrays pass through without reshaping.
//! The arithmetic follows rps operation by operation, so the Fast backend reproduces its poses.
//!
//! Two generations of rps are covered: 0.0.0 (PyPI) clips `v` and `w` separately, counts every
//! robot outside the arena and every pair of centres within 0.11 m; 2.1 (the lab's, 2026) clips
//! the wheel speeds, counts the boundary once per iteration and compares colliders placed
//! 0.025 m ahead of the centres with a diameter of 0.135 m ([`Checks`]).

use std::f64::consts::PI;
use std::ops::Range;

use rayon::prelude::*;

use crate::error::{check_finite, check_len, check_positive, GeomError, Result};
use crate::geom::Arena;
use crate::grid::Grid;
use crate::neighbours::{in_range, radius_squared};
use crate::parallel::{first_where, map_range, worth_spreading, TASK_ITEMS};

/// Differential-drive geometry: what turns a unicycle command into wheel speeds (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wheels {
    /// Wheel radius (m).
    pub radius: f64,
    /// Distance between the wheels (m).
    pub base_length: f64,
    /// Largest wheel speed (rad/s).
    pub max_speed: f64,
}

impl Wheels {
    /// # Errors
    /// [`GeomError::InvalidParameter`] unless every field is finite and positive.
    pub fn new(radius: f64, base_length: f64, max_speed: f64) -> Result<Self> {
        check_positive("wheel_radius", radius)?;
        check_positive("base_length", base_length)?;
        check_positive("max_wheel", max_speed)?;
        Ok(Self {
            radius,
            base_length,
            max_speed,
        })
    }

    /// Left and right wheel speeds (rad/s) of the command `(v, w)`, written as rps writes them.
    pub fn speeds(&self, v: f64, w: f64) -> (f64, f64) {
        let (r, l) = (self.radius, self.base_length);
        (1.0 / (2.0 * r) * (2.0 * v - l * w), 1.0 / (2.0 * r) * (2.0 * v + l * w))
    }

    /// Whether the command `(v, w)` needs a wheel faster than `max_speed` (rps's criterion).
    fn exceeded_by(&self, v: f64, w: f64) -> bool {
        let (left, right) = self.speeds(v, w);
        left.abs() > self.max_speed || right.abs() > self.max_speed
    }
}

/// How robots outside the arena are counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoundaryCount {
    /// Every robot outside, every iteration (rps 0.0.0).
    Robots,
    /// 1 per iteration in which any robot is outside (rps 2.1).
    Iterations,
}

/// The collision and boundary criteria of one rps generation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Checks {
    /// Two colliders touch when their centres are this close or closer (m).
    pub diameter: f64,
    /// How far ahead of the robot's centre, along its heading, the collider sits (m).
    pub collider_offset: f64,
    pub boundary: BoundaryCount,
}

impl Checks {
    /// # Errors
    /// [`GeomError::InvalidParameter`] unless `diameter > 0` and `collider_offset` is finite.
    pub fn new(diameter: f64, collider_offset: f64, boundary: BoundaryCount) -> Result<Self> {
        check_positive("diameter", diameter)?;
        check_finite("collider_offset", &[collider_offset])?;
        Ok(Self {
            diameter,
            collider_offset,
            boundary,
        })
    }
}

/// The three rps validation counts of one iteration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Violations {
    /// Robots outside the arena, or 1 if any is ([`BoundaryCount`]).
    pub boundary: u64,
    /// Pairs of robots whose colliders are within one diameter.
    pub collision: u64,
    /// 1 if any robot's command needs a wheel faster than allowed, else 0.
    pub actuator: u64,
}

fn rows<'a>(arg: &'static str, data: &'a [f64], count: usize, n: usize) -> Result<Vec<&'a [f64]>> {
    check_len(arg, count * n, data.len())?;
    check_finite(arg, data)?;
    Ok(if n == 0 {
        vec![&data[0..0]; count]
    } else {
        data.chunks(n).collect()
    })
}

/// Clips commands to the linear and angular limits, keeping their signs (rps `set_velocities`).
///
/// # Errors
/// Length or finiteness problems of `velocities` (`2 * n` values).
pub fn threshold_velocities(velocities: &mut [f64], n: usize, max_linear: f64, max_angular: f64) -> Result<()> {
    check_positive("max_linear", max_linear)?;
    check_positive("max_angular", max_angular)?;
    rows("velocities", velocities, 2, n)?;
    let (v, w) = velocities.split_at_mut(n);
    for_each_robot(v, w, 2.0, |_, v, w| {
        if v.abs() > max_linear {
            *v = max_linear * v.signum();
        }
        if w.abs() > max_angular {
            *w = max_angular * w.signum();
        }
    });
    Ok(())
}

/// `update(i, &mut v[i], &mut w[i])` for every robot i, each taking about `ns` nanoseconds: on
/// every core for a large swarm (see [`worth_spreading`]).
fn for_each_robot(v: &mut [f64], w: &mut [f64], ns: f64, update: impl Fn(usize, &mut f64, &mut f64) + Sync + Send) {
    if worth_spreading(v.len(), ns) {
        v.par_iter_mut()
            .zip(w.par_iter_mut())
            .enumerate()
            .with_min_len(TASK_ITEMS)
            .for_each(|(i, (v, w))| update(i, v, w));
    } else {
        v.iter_mut()
            .zip(w.iter_mut())
            .enumerate()
            .for_each(|(i, (v, w))| update(i, v, w));
    }
}

/// Clips each wheel's speed to `max_speed` (keeping its sign) and converts back to `(v, w)`, as
/// rps 2.1's `_threshold`: a command too fast for one wheel keeps its curvature only if both
/// wheels stay within the limit.
///
/// # Errors
/// Length or finiteness problems of `velocities` (`2 * n` values).
pub fn threshold_wheels(velocities: &mut [f64], n: usize, wheels: &Wheels) -> Result<()> {
    rows("velocities", velocities, 2, n)?;
    let (v, w) = velocities.split_at_mut(n);
    let (r, l, top) = (wheels.radius, wheels.base_length, wheels.max_speed);
    let clip = |speed: f64| if speed.abs() > top { top * speed.signum() } else { speed };
    for i in 0..n {
        let (left, right) = wheels.speeds(v[i], w[i]);
        let (left, right) = (clip(left), clip(right));
        v[i] = r / 2.0 * (left + right);
        w[i] = r / l * (right - left);
    }
    Ok(())
}

/// Counts boundary, collision and actuator violations of the current poses and commands with
/// rps 0.0.0's criteria (centres within `diameter`, every robot outside counted).
///
/// # Errors
/// As [`validate_each`].
pub fn validate(
    poses: &[f64],
    velocities: &[f64],
    n: usize,
    arena: &Arena,
    diameter: f64,
    wheels: &Wheels,
) -> Result<Violations> {
    let checks = Checks::new(diameter, 0.0, BoundaryCount::Robots)?;
    Ok(validate_each(poses, velocities, n, arena, &checks, wheels)?.0)
}

/// Counts boundary, collision and actuator violations of the current poses and commands with
/// the criteria `checks`, and lists the robots in a collision (ascending): the robots of the
/// pairs counted, from the same search (a reward's penalty, say). Collisions use a grid, so
/// the cost is O(n).
///
/// # Errors
/// Length or finiteness problems of `poses` (`3 * n`) or `velocities` (`2 * n`).
pub fn validate_each(
    poses: &[f64],
    velocities: &[f64],
    n: usize,
    arena: &Arena,
    checks: &Checks,
    wheels: &Wheels,
) -> Result<(Violations, Vec<usize>)> {
    let p = rows("poses", poses, 3, n)?;
    let u = rows("velocities", velocities, 2, n)?;
    let (xs, ys) = (p[0], p[1]);

    let out = |i: usize| !arena.contains(xs[i], ys[i]);
    let outside = if worth_spreading(n, 2.0) {
        (0..n).into_par_iter().filter(|&i| out(i)).count()
    } else {
        (0..n).filter(|&i| out(i)).count()
    } as u64;
    let boundary = match checks.boundary {
        BoundaryCount::Robots => outside,
        BoundaryCount::Iterations => u64::from(outside > 0),
    };
    let pairs = collision_pairs(&p, n, checks);
    let fast = |i: usize| wheels.exceeded_by(u[0][i], u[1][i]);
    let actuator = u64::from(if worth_spreading(n, 2.0) {
        (0..n).into_par_iter().any(fast)
    } else {
        (0..n).any(fast)
    });
    let mut robots: Vec<usize> = pairs.iter().flat_map(|&(i, j)| [i, j]).collect();
    robots.sort_unstable();
    robots.dedup();
    let counts = Violations {
        boundary,
        collision: pairs.len() as u64,
        actuator,
    };
    Ok((counts, robots))
}

/// Cells (occupied or not) a task counts the collisions of.
const PARALLEL_CELLS: usize = 4096;

/// Which robots are in a collision by the criteria `checks`: the robots of the pairs
/// [`validate_each`] counts, found the same way.
///
/// # Errors
/// Length or finiteness problems of `poses` (`3 * n`).
pub fn colliding(poses: &[f64], n: usize, checks: &Checks) -> Result<Vec<bool>> {
    let p = rows("poses", poses, 3, n)?;
    let mut flags = vec![false; n];
    for (i, j) in collision_pairs(&p, n, checks) {
        flags[i] = true;
        flags[j] = true;
    }
    Ok(flags)
}

/// The pairs `(i, j)`, `i < j`, whose colliders are within `checks.diameter`, cell by cell.
fn collision_pairs(p: &[&[f64]], n: usize, checks: &Checks) -> Vec<(usize, usize)> {
    let grid = colliders(p, n, checks);
    let pairs = |cell: Range<usize>| {
        let mut found = Vec::new();
        pairs_in(&grid, &cell, checks.diameter, |i, j| found.push((i, j)));
        found
    };
    if worth_spreading(n, 50.0) {
        grid.par_cell_runs(PARALLEL_CELLS).flat_map_iter(pairs).collect()
    } else {
        grid.cell_runs().flat_map(pairs).collect()
    }
}

/// The grid of the robots' colliders, `checks.collider_offset` ahead of their centres.
fn colliders(p: &[&[f64]], n: usize, checks: &Checks) -> Grid {
    let (xs, ys, offset) = (p[0], p[1], checks.collider_offset);
    if offset == 0.0 {
        return Grid::loose(xs, ys, checks.diameter);
    }
    let cx = map_range(n, 20.0, |i| xs[i] + offset * p[2][i].cos());
    let cy = map_range(n, 20.0, |i| ys[i] + offset * p[2][i].sin());
    Grid::loose(&cx, &cy, checks.diameter)
}

/// Calls `pair(i, j)`, `i < j`, for each pair within `diameter` whose first point in the grid's
/// order lies in `cell` (a run of the grid's positions): each pair once, from the point of the
/// two that comes first, which looks only at the points after it in its 3x3 block (half the
/// block). The queries go through the grid in cell order, on the coordinates stored in that
/// order, and the block around a cell is looked up once for all its points: at a million robots
/// in index order, the lookups and the reads of each neighbour's coordinates were cache misses
/// that took 8 times as long.
fn pairs_in(grid: &Grid, cell: &Range<usize>, diameter: f64, mut pair: impl FnMut(usize, usize)) {
    let (xs, ys) = grid.sorted();
    let members = grid.members();
    let reach_squared = radius_squared(diameter);
    let (mut runs, mut found) = ([(0_usize, 0_usize); 9], 0);
    grid.for_each_run_near(xs[cell.start], ys[cell.start], |run| {
        runs[found] = (run.start, run.end);
        found += 1;
    });
    for a in cell.clone() {
        let (x, y) = (xs[a], ys[a]);
        for &(first, last) in &runs[..found] {
            for b in first.max(a + 1)..last {
                if in_range(xs[b] - x, ys[b] - y, diameter, reach_squared) {
                    let (i, j) = (members[a], members[b]);
                    pair(i.min(j), i.max(j));
                }
            }
        }
    }
}

/// Advances every pose by one forward-Euler step of the unicycle model and wraps the heading
/// to (-pi, pi], as rps's `step` does (to within a rounding of the heading).
///
/// # Errors
/// Length or finiteness problems of `poses` (`3 * n`) or `velocities` (`2 * n`), a
/// non-positive `dt`, or a `dt` so large that a pose overflows ([`GeomError::Overflow`], the
/// poses then partly advanced).
pub fn unicycle_step(poses: &mut [f64], velocities: &[f64], n: usize, dt: f64) -> Result<()> {
    check_positive("dt", dt)?;
    rows("poses", poses, 3, n)?;
    let u = rows("velocities", velocities, 2, n)?;
    let (xs, rest) = poses.split_at_mut(n);
    let (ys, thetas) = rest.split_at_mut(n);
    let advance = |(((x, y), theta), (&v, &w)): (((&mut f64, &mut f64), &mut f64), (&f64, &f64))| {
        let heading = *theta;
        *x += dt * heading.cos() * v;
        *y += dt * heading.sin() * v;
        let turned = heading + dt * w;
        // rps wraps with atan2(sin, cos), which gives a heading already in (-pi, pi] back to
        // within a rounding: that one is kept as it is (two libm calls of five saved).
        *theta = if -PI < turned && turned <= PI {
            turned
        } else {
            turned.sin().atan2(turned.cos())
        };
    };
    if worth_spreading(n, 60.0) {
        // Five calls of libm a robot.
        let robots = xs.par_iter_mut().zip(ys.par_iter_mut()).zip(thetas.par_iter_mut());
        robots
            .zip(u[0].par_iter().zip(u[1].par_iter()))
            .with_min_len(TASK_ITEMS)
            .for_each(advance);
    } else {
        xs.iter_mut()
            .zip(ys.iter_mut())
            .zip(thetas.iter_mut())
            .zip(u[0].iter().zip(u[1].iter()))
            .for_each(advance);
    }
    // Looked for on every core (a million robots' poses on one took a millisecond a step).
    match first_where(poses.len(), |k| !poses[k].is_finite()) {
        Some(k) => Err(GeomError::Overflow { dt, robot: k % n }),
        None => Ok(()),
    }
}

/// Converts single-integrator velocities `(2, n)` to unicycle commands `(2, n)` for robots at
/// `poses` `(3, n)`: `v = kv (c dx + s dy)`, `w = kw atan2(-s dx + c dy, v) / (pi/2)`.
///
/// # Errors
/// Length or finiteness problems of `dxi` or `poses`.
pub fn dxi_to_dxu(dxi: &[f64], poses: &[f64], n: usize, vel_gain: f64, ang_gain: f64) -> Result<Vec<f64>> {
    let d = rows("dxi", dxi, 2, n)?;
    let p = rows("poses", poses, 3, n)?;
    let mut dxu = vec![0.0; 2 * n];
    let (v, w) = dxu.split_at_mut(n);
    for_each_robot(v, w, 50.0, |i, v, w| {
        let (c, s) = (p[2][i].cos(), p[2][i].sin());
        *v = vel_gain * (c * d[0][i] + s * d[1][i]);
        *w = ang_gain * (-s * d[0][i] + c * d[1][i]).atan2(*v) / std::f64::consts::FRAC_PI_2;
    });
    Ok(dxu)
}

/// Converts unicycle commands `(2, n)` of robots of headings `(n,)` to the velocities `(2, n)`
/// of the points `projection` ahead of them: `dx = v c - p w s`, `dy = v s + p w c` (rps's
/// `uni_to_si`; a movement sensor's reading). The products are taken in the order of NumPy's
/// reference, so both give the same bits where their `sin` and `cos` do.
///
/// # Errors
/// Length or finiteness problems of `dxu` or `headings`, or a non-finite `projection`.
pub fn dxu_to_dxi(dxu: &[f64], headings: &[f64], n: usize, projection: f64) -> Result<Vec<f64>> {
    check_finite("projection", &[projection])?;
    let u = rows("dxu", dxu, 2, n)?;
    let theta = rows("headings", headings, 1, n)?[0];
    let mut dxi = vec![0.0; 2 * n];
    let (dx, dy) = dxi.split_at_mut(n);
    for_each_robot(dx, dy, 20.0, |i, dx, dy| {
        let (c, s, ahead) = (theta[i].cos(), theta[i].sin(), projection * u[1][i]);
        *dx = u[0][i] * c - ahead * s;
        *dy = u[0][i] * s + ahead * c;
    });
    Ok(dxi)
}

/// Limits unicycle commands `(2, n)` in place as DREAM's `Robot.actuator_limit`: clip `v` and `w`
/// to their limits, then, if the faster wheel would exceed `max_wheel`, shrink `|v|` (keeping its
/// sign and keeping `w`: turning matters more) so that it does not.
///
/// # Errors
/// Length or finiteness problems of `dxu`.
pub fn actuator_limit(dxu: &mut [f64], n: usize, max_linear: f64, max_angular: f64, wheels: &Wheels) -> Result<()> {
    rows("dxu", dxu, 2, n)?;
    threshold_velocities(dxu, n, max_linear, max_angular)?;
    let (v, w) = dxu.split_at_mut(n);
    let (r, half_l) = (wheels.radius, wheels.base_length / 2.0);
    for_each_robot(v, w, 2.0, |_, v, w| {
        if v.abs() / r + w.abs() * half_l / r > wheels.max_speed {
            let speed = (wheels.max_speed * r - half_l * w.abs()).max(0.0);
            *v = if *v > 0.0 { speed } else { -speed };
        }
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::GeomError;

    const MAX_ANGULAR: f64 = 2.0 * (0.016 / 0.11) * (0.2 / 0.016);

    fn gritsbot() -> Wheels {
        Wheels::new(0.016, 0.105, 0.2 / 0.016).unwrap()
    }

    fn robotarium() -> Arena {
        Arena::new(-1.6, 1.6, -1.0, 1.0).unwrap()
    }

    #[test]
    fn step_moves_along_heading_and_wraps_angle() {
        let mut poses = vec![0.0, 1.0, 0.0, 0.0, 0.0, 3.1];
        unicycle_step(&mut poses, &[0.1, 0.0, 0.0, 10.0], 2, 0.033).unwrap();
        assert!((poses[0] - 0.0033).abs() < 1e-15);
        assert!((poses[5] - (3.1 + 0.33 - 2.0 * std::f64::consts::PI)).abs() < 1e-12);
    }

    #[test]
    fn validate_counts_like_rps() {
        // robots 0 and 1 touch (0.11 apart: inclusive), robot 2 is out, robot 3 spins too fast.
        let poses = [0.0, 0.11, 1.7, -1.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0];
        let velocities = [0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 1.0];
        let counts = validate(&poses, &velocities, 4, &robotarium(), 0.11, &gritsbot()).unwrap();
        assert_eq!(
            counts,
            Violations {
                boundary: 1,
                collision: 1,
                actuator: 1
            }
        );
    }

    #[test]
    fn rps2_checks_use_offset_colliders_and_count_the_boundary_once() {
        // Robots 0 and 1 are 0.15 m apart (no collision in rps 0.0.0) but face each other, so
        // their colliders are 0.10 m apart; robots 2 and 3 are both outside.
        let poses = [
            0.0,
            0.15,
            1.7,
            -1.7,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            std::f64::consts::PI,
            0.0,
            0.0,
        ];
        let checks = Checks::new(0.135, 0.025, BoundaryCount::Iterations).unwrap();
        let (counts, _) = validate_each(&poses, &[0.0; 8], 4, &robotarium(), &checks, &gritsbot()).unwrap();
        assert_eq!((counts.boundary, counts.collision), (1, 1));
        let counts = validate(&poses, &[0.0; 8], 4, &robotarium(), 0.11, &gritsbot()).unwrap();
        assert_eq!((counts.boundary, counts.collision), (2, 0));
    }

    #[test]
    fn threshold_wheels_clips_the_faster_wheel_only() {
        let wheels = Wheels::new(0.016, 0.11, 12.5).unwrap();
        // v = 0.2 with a turn: the outer wheel is too fast, the inner one is not.
        let mut u = vec![0.2, 0.0, 1.0, 0.1];
        threshold_wheels(&mut u, 2, &wheels).unwrap();
        let (left, right) = wheels.speeds(u[0], u[2]);
        assert!((right - 12.5).abs() < 1e-12);
        assert!((left - (0.2 - 0.055) / 0.016).abs() < 1e-12);
        assert!((u[1] - 0.0).abs() < 1e-15 && (u[3] - 0.1).abs() < 1e-15);
    }

    #[test]
    fn actuator_limit_keeps_turning() {
        let mut dxu = vec![-0.2, 3.0];
        actuator_limit(&mut dxu, 1, 0.2, MAX_ANGULAR, &gritsbot()).unwrap();
        assert!((dxu[0] + (0.2 - 3.0 * 0.0525)).abs() < 1e-15);
        assert_eq!(dxu[1], 3.0);
    }

    #[test]
    fn dxu_to_dxi_moves_the_point_ahead() {
        // Facing +y at 0.1 m/s while turning at 2 rad/s: the point 0.05 m ahead also sweeps
        // sideways, at 0.1 m/s towards -x.
        let got = dxu_to_dxi(&[0.1, 2.0], &[std::f64::consts::FRAC_PI_2], 1, 0.05).unwrap();
        assert!((got[0] + 0.1).abs() < 1e-15 && (got[1] - 0.1).abs() < 1e-15);
        assert!(matches!(
            dxu_to_dxi(&[0.0; 4], &[0.0], 2, 0.05),
            Err(GeomError::LengthMismatch { arg: "headings", .. })
        ));
        assert!(matches!(
            dxu_to_dxi(&[0.0; 2], &[0.0], 1, f64::NAN),
            Err(GeomError::NonFinite { arg: "projection", .. })
        ));
        assert!(dxu_to_dxi(&[], &[], 0, 0.05).unwrap().is_empty());
    }

    #[test]
    fn bad_lengths_and_values_are_errors() {
        assert!(matches!(
            validate(&[0.0; 5], &[0.0; 4], 2, &robotarium(), 0.11, &gritsbot()),
            Err(GeomError::LengthMismatch {
                arg: "poses",
                expected: 6,
                got: 5
            })
        ));
        assert!(matches!(
            unicycle_step(&mut [f64::NAN, 0.0, 0.0], &[0.0, 0.0], 1, 0.033),
            Err(GeomError::NonFinite { arg: "poses", index: 0 })
        ));
        assert!(Arena::new(1.0, -1.0, 0.0, 1.0).is_err());
    }

    #[test]
    fn empty_swarm_is_fine() {
        let counts = validate(&[], &[], 0, &robotarium(), 0.11, &gritsbot()).unwrap();
        assert_eq!(counts, Violations::default());
        unicycle_step(&mut [], &[], 0, 0.033).unwrap();
    }
}
