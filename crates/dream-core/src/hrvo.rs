//! Hybrid Reciprocal Velocity Obstacles with candidate sampling.
//!
//! For robot A (previous velocity `v_A`, preferred `v_pref`) and each neighbour B at distance d
//! in unit direction u (from A towards B; (1, 0) for a co-located B) moving with `v_B`, with
//! safety radius r: the cone has half-angle `phi` with `sin phi = r / max(d, r)`, its left edge
//! is u turned by +phi and its right edge u turned by -phi (rotations by `sin phi` and
//! `cos phi = sqrt(1 - sin^2 phi)`: no trigonometry, so Rust and NumPy agree to the bit); the VO's apex is `v_B`, the RVO's `(v_A + v_B) / 2`; HRVO
//! keeps the RVO edge on the side `v_A` is closer to and the VO edge on the other (both VO edges
//! on a tie, as the original; distances within [`TIE`] of each other, relative to `|v_A - apex|`,
//! are a tie, so that symmetric scenes are decided by geometry and not by rounding). A velocity is forbidden by B when it is strictly inside both
//! half-planes.
//!
//! The chosen velocity is the candidate closest to `v_pref` (first in candidate order on ties)
//! that no neighbour forbids and, with bounds, keeps `position + v` strictly inside; zero if
//! none does. Candidates are tested in order of distance and the first valid one returned, so
//! most are never tested. The arithmetic matches the NumPy reference operation by operation.

use std::f64::consts::TAU;

use rayon::prelude::*;

use crate::dynamics::Arena;
use crate::error::{check_finite, check_len, GeomError, Result};
use crate::neighbours::{self, Csr};

/// A 2-D vector `[x, y]`.
pub type Vec2 = [f64; 2];

/// Rows below this count run on one thread.
const PARALLEL_ROBOTS: usize = 256;
/// Relative tolerance under which `v_A` is equally close to both RVO edges.
pub const TIE: f64 = 1e-9;
/// Candidates sorted up front; the rest are sorted only if none of these is valid.
const FIRST_BATCH: usize = 16;

/// Parameters shared by every robot of an HRVO call.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HrvoParams {
    /// Combined safety radius of two robots (m).
    pub safety: f64,
    /// Largest speed (m/s); the preferred-velocity candidate is clamped to it.
    pub v_max: f64,
    /// Keep `position + v` strictly inside these bounds, if any.
    pub bounds: Option<Arena>,
    /// Try the (clamped) preferred velocity before the candidates.
    pub include_preferred: bool,
}

impl HrvoParams {
    /// # Errors
    /// [`GeomError::InvalidParameter`] for a negative or non-finite `safety` or `v_max`.
    pub fn validated(self) -> Result<Self> {
        for (arg, value) in [("safety", self.safety), ("v_max", self.v_max)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(GeomError::InvalidParameter { arg, rule: ">= 0", got: value });
            }
        }
        Ok(self)
    }
}

/// One neighbour as a robot perceives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Neighbour {
    /// Unit vector from the robot towards the neighbour.
    pub direction: Vec2,
    /// Distance between centres (m).
    pub distance: f64,
    /// The neighbour's velocity (m/s).
    pub velocity: Vec2,
}

impl Neighbour {
    /// From a movement-sensor detection `[distance, angle, vx, vy]`, whose angle points from
    /// the detected robot towards the sensing one (the original DREAM convention).
    pub fn from_detection(detection: [f64; 4]) -> Self {
        let [distance, angle, vx, vy] = detection;
        let towards = angle + std::f64::consts::PI;
        Self { direction: [towards.cos(), towards.sin()], distance, velocity: [vx, vy] }
    }

    /// The neighbour at `offset` (its position minus the robot's) moving with `velocity`.
    pub fn from_offset(offset: Vec2, velocity: Vec2) -> Self {
        let distance = (offset[0] * offset[0] + offset[1] * offset[1]).sqrt();
        let direction = if distance > 0.0 { [offset[0] / distance, offset[1] / distance] } else { [1.0, 0.0] };
        Self { direction, distance, velocity }
    }
}

/// The original polar sampling without duplicates: zero first, then for each of the
/// `n_angles` angles in [0, 2 pi) (the duplicate 2 pi dropped) every non-zero speed of
/// `n_speeds` in [0, v_max].
pub fn candidate_grid(v_max: f64, n_angles: usize, n_speeds: usize) -> Vec<Vec2> {
    let angle_step = if n_angles > 1 { TAU / (n_angles - 1) as f64 } else { 0.0 };
    let speed_step = if n_speeds > 1 { v_max / (n_speeds - 1) as f64 } else { 0.0 };
    let distinct_angles = if n_angles > 1 { n_angles - 1 } else { n_angles };
    let mut grid = vec![[0.0, 0.0]];
    for a in 0..distinct_angles {
        let angle = a as f64 * angle_step;
        for s in 1..n_speeds {
            // linspace pins its last sample to the end point exactly.
            let speed = if s == n_speeds - 1 { v_max } else { s as f64 * speed_step };
            grid.push([speed * angle.cos(), speed * angle.sin()]);
        }
    }
    grid
}

fn cross(a: Vec2, b: Vec2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// The two half-planes of one neighbour's HRVO.
#[derive(Debug, Clone, Copy)]
struct Cone {
    left: Vec2,
    left_apex: Vec2,
    right: Vec2,
    right_apex: Vec2,
}

impl Cone {
    fn new(velocity: Vec2, b: &Neighbour, safety: f64) -> Self {
        let sin = if safety > 0.0 { safety / b.distance.max(safety) } else { 0.0 };
        let cos = (1.0 - sin * sin).sqrt();
        let [ux, uy] = b.direction;
        let left = [ux * cos - uy * sin, ux * sin + uy * cos];
        let right = [ux * cos + uy * sin, uy * cos - ux * sin];
        let vo = b.velocity;
        let rvo = [(velocity[0] + vo[0]) / 2.0, (velocity[1] + vo[1]) / 2.0];
        let from_rvo = [velocity[0] - rvo[0], velocity[1] - rvo[1]];
        let (to_left, to_right) = (cross(left, from_rvo).abs(), cross(right, from_rvo).abs());
        let tie = (to_left - to_right).abs() <= TIE * from_rvo[0].hypot(from_rvo[1]);
        Cone {
            left,
            left_apex: if !tie && to_left < to_right { rvo } else { vo },
            right,
            right_apex: if !tie && to_left > to_right { rvo } else { vo },
        }
    }

    fn forbids(&self, v: Vec2) -> bool {
        cross(self.left, [v[0] - self.left_apex[0], v[1] - self.left_apex[1]]) < 0.0
            && cross(self.right, [v[0] - self.right_apex[0], v[1] - self.right_apex[1]]) > 0.0
    }
}

/// Scratch space reused between robots, so a batch call allocates once per thread.
#[derive(Debug, Default)]
struct Scratch {
    cones: Vec<Cone>,
    candidates: Vec<Vec2>,
    order: Vec<(f64, usize)>,
}

/// One robot's HRVO velocity.
///
/// `position` is only read when `params.bounds` is set. Inputs are trusted finite: the public
/// entry points ([`hrvo_one`], [`hrvo_batch`]) check them.
fn choose(
    scratch: &mut Scratch,
    velocity: Vec2,
    preferred: Vec2,
    position: Vec2,
    neighbours: impl Iterator<Item = Neighbour>,
    grid: &[Vec2],
    params: &HrvoParams,
) -> Vec2 {
    scratch.cones.clear();
    scratch.cones.extend(neighbours.map(|b| Cone::new(velocity, &b, params.safety)));
    scratch.candidates.clear();
    if params.include_preferred {
        let norm = preferred[0].hypot(preferred[1]);
        let scale = if norm > params.v_max { params.v_max / norm } else { 1.0 };
        scratch.candidates.push(if scale < 1.0 { [preferred[0] * scale, preferred[1] * scale] } else { preferred });
    }
    scratch.candidates.extend_from_slice(grid);

    // Candidates are tested nearest first; the cone that forbade the last one is asked first,
    // since neighbouring candidates are usually forbidden by the same neighbour.
    let mut blocker = 0;
    let mut valid = |v: Vec2, cones: &[Cone]| {
        let inside = params.bounds.is_none_or(|b| {
            let (x, y) = (position[0] + v[0], position[1] + v[1]);
            b.xmin < x && x < b.xmax && b.ymin < y && y < b.ymax
        });
        if !inside {
            return false;
        }
        if cones.get(blocker).is_some_and(|c| c.forbids(v)) {
            return false;
        }
        match cones.iter().position(|c| c.forbids(v)) {
            Some(k) => {
                blocker = k;
                false
            }
            None => true,
        }
    };

    scratch.order.clear();
    scratch.order.extend(scratch.candidates.iter().enumerate().map(|(k, v)| {
        let (dx, dy) = (v[0] - preferred[0], v[1] - preferred[1]);
        (dx * dx + dy * dy, k)
    }));
    let by_distance = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
    // Most robots take their nearest candidate (a free way): find it with one scan first.
    let Some(&nearest) = scratch.order.iter().min_by(|a, b| by_distance(a, b)) else {
        return [0.0, 0.0];
    };
    if valid(scratch.candidates[nearest.1], &scratch.cones) {
        return scratch.candidates[nearest.1];
    }
    let first = FIRST_BATCH.min(scratch.order.len());
    if first < scratch.order.len() {
        scratch.order.select_nth_unstable_by(first, by_distance);
    }
    let (head, tail) = scratch.order.split_at_mut(first);
    head.sort_unstable_by(by_distance);
    for &(_, k) in head.iter().skip(1) {
        if valid(scratch.candidates[k], &scratch.cones) {
            return scratch.candidates[k];
        }
    }
    tail.sort_unstable_by(by_distance);
    for &(_, k) in tail.iter() {
        if valid(scratch.candidates[k], &scratch.cones) {
            return scratch.candidates[k];
        }
    }
    [0.0, 0.0]
}

fn check_vec2s(arg: &'static str, values: &[Vec2]) -> Result<()> {
    check_finite(arg, values.as_flattened())
}

/// One robot's HRVO velocity from its neighbours as it perceives them.
///
/// # Errors
/// Non-finite inputs, a negative `safety` / `v_max`, or a negative neighbour distance.
pub fn hrvo_one(
    velocity: Vec2,
    preferred: Vec2,
    position: Vec2,
    neighbours: &[Neighbour],
    grid: &[Vec2],
    params: &HrvoParams,
) -> Result<Vec2> {
    let params = params.validated()?;
    check_finite("velocity", &velocity)?;
    check_finite("preferred", &preferred)?;
    check_finite("position", &position)?;
    check_vec2s("candidates", grid)?;
    for (index, b) in neighbours.iter().enumerate() {
        let values = [b.direction[0], b.direction[1], b.distance, b.velocity[0], b.velocity[1]];
        if !values.iter().all(|v| v.is_finite()) {
            return Err(GeomError::NonFinite { arg: "detections", index });
        }
        if b.distance < 0.0 {
            return Err(GeomError::InvalidParameter { arg: "detection distance", rule: ">= 0", got: b.distance });
        }
    }
    Ok(choose(&mut Scratch::default(), velocity, preferred, position, neighbours.iter().copied(), grid, &params))
}

/// HRVO velocities of the whole swarm.
///
/// Robot i's neighbours are `neighbours` row i (CSR `(indptr, indices)`), or, with `None`,
/// every other robot within `radius`. Neighbour velocities are rows of `velocities`.
///
/// # Errors
/// Length mismatches, non-finite inputs, invalid parameters or an invalid CSR.
pub fn hrvo_batch(
    positions: &[Vec2],
    velocities: &[Vec2],
    preferred: &[Vec2],
    neighbours: Option<(&[i64], &[i64])>,
    radius: f64,
    grid: &[Vec2],
    params: &HrvoParams,
) -> Result<Vec<Vec2>> {
    let params = params.validated()?;
    let n = positions.len();
    check_len("velocities", n, velocities.len())?;
    check_len("preferred", n, preferred.len())?;
    check_vec2s("positions", positions)?;
    check_vec2s("velocities", velocities)?;
    check_vec2s("preferred", preferred)?;
    check_vec2s("candidates", grid)?;
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(GeomError::InvalidParameter { arg: "radius", rule: ">= 0", got: radius });
    }
    let found;
    let (indptr, indices) = match neighbours {
        Some(csr) => {
            check_csr(csr.0, csr.1, n)?;
            csr
        }
        None => {
            let xs: Vec<f64> = positions.iter().map(|p| p[0]).collect();
            let ys: Vec<f64> = positions.iter().map(|p| p[1]).collect();
            found = neighbours::within(&xs, &ys, radius, None, None)?;
            let Csr { indptr, indices, .. } = &found;
            (indptr.as_slice(), indices.as_slice())
        }
    };
    let robot = |scratch: &mut Scratch, i: usize| {
        let p = positions[i];
        let row = &indices[indptr[i] as usize..indptr[i + 1] as usize];
        let around = row.iter().map(|&j| {
            let q = positions[j as usize];
            Neighbour::from_offset([q[0] - p[0], q[1] - p[1]], velocities[j as usize])
        });
        choose(scratch, velocities[i], preferred[i], p, around, grid, &params)
    };
    Ok(if n >= PARALLEL_ROBOTS {
        (0..n).into_par_iter().map_init(Scratch::default, robot).collect()
    } else {
        let mut scratch = Scratch::default();
        (0..n).map(|i| robot(&mut scratch, i)).collect()
    })
}

/// Checks that `(indptr, indices)` has `n` rows of ids in `[0, n)`.
///
/// # Errors
/// [`GeomError::InvalidCsr`] saying what is wrong.
pub fn check_csr(indptr: &[i64], indices: &[i64], n: usize) -> Result<()> {
    let fail = |reason: String| Err(GeomError::InvalidCsr { arg: "neighbours", rows: n, reason });
    if indptr.len() != n + 1 {
        return fail(format!("indptr has {} entries, expected {}", indptr.len(), n + 1));
    }
    if indptr[0] != 0 || indptr[n] != indices.len() as i64 {
        return fail(format!("indptr must run from 0 to len(indices) = {}", indices.len()));
    }
    if let Some(i) = indptr.windows(2).position(|w| w[1] < w[0]) {
        return fail(format!("indptr decreases at row {i}"));
    }
    if let Some(&j) = indices.iter().find(|&&j| j < 0 || j >= n as i64) {
        return fail(format!("index {j} is not a robot id in [0, {n})"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const PARAMS: HrvoParams = HrvoParams { safety: 0.24, v_max: 0.2, bounds: None, include_preferred: true };

    fn grid() -> Vec<Vec2> {
        candidate_grid(0.2, 20, 10)
    }

    #[test]
    fn grid_has_the_original_distinct_samples() {
        let g = grid();
        assert_eq!(g.len(), 172);
        assert_eq!(g[0], [0.0, 0.0]);
        assert_eq!(g[9], [0.2, 0.0]);
        assert!(g.iter().all(|v| v[0].hypot(v[1]) <= 0.2 + 1e-15));
    }

    #[test]
    fn free_robot_takes_its_clamped_preference() {
        let v = hrvo_one([0.0, 0.0], [0.3, 0.4], [0.0, 0.0], &[], &grid(), &PARAMS).unwrap();
        assert!((v[0] - 0.12).abs() < 1e-15 && (v[1] - 0.16).abs() < 1e-15);
    }

    #[test]
    fn head_on_robot_does_not_drive_into_its_neighbour() {
        let ahead = Neighbour { direction: [1.0, 0.0], distance: 0.5, velocity: [-0.2, 0.0] };
        let v = hrvo_one([0.2, 0.0], [0.2, 0.0], [0.0, 0.0], &[ahead], &grid(), &PARAMS).unwrap();
        assert_ne!(v, [0.2, 0.0]);
        // Relative to the neighbour's velocity the choice leaves the collision cone.
        let relative = (v[1] - ahead.velocity[1]).atan2(v[0] - ahead.velocity[0]);
        assert!(relative.abs() >= (0.24_f64 / 0.5).asin() - 1e-12);
    }

    #[test]
    fn surrounded_robot_stops() {
        let ring: Vec<Neighbour> = (0..8)
            .map(|k| {
                let angle = k as f64 * TAU / 8.0;
                Neighbour { direction: [angle.cos(), angle.sin()], distance: 0.1, velocity: [0.0, 0.0] }
            })
            .collect();
        let v = hrvo_one([0.0, 0.0], [0.2, 0.0], [0.0, 0.0], &ring, &grid(), &PARAMS).unwrap();
        assert_eq!(v, [0.0, 0.0]);
    }

    #[test]
    fn bounds_keep_the_robot_inside() {
        let walled = HrvoParams { bounds: Some(Arena::new(-1.0, 1.0, -1.0, 1.0).unwrap()), ..PARAMS };
        let v = hrvo_one([0.0, 0.0], [0.2, 0.0], [0.9, 0.0], &[], &grid(), &walled).unwrap();
        assert!(0.9 + v[0] < 1.0);
        assert!(v[0] > 0.0);
    }

    #[test]
    fn batch_equals_one_by_one_and_is_deterministic() {
        let n = 600;
        let positions: Vec<Vec2> =
            (0..n).map(|i| [((i as f64) * 0.754_877_666).fract() * 6.0, ((i as f64) * 0.569_840_29).fract() * 4.0]).collect();
        let velocities: Vec<Vec2> = (0..n).map(|i| [0.1 * (i as f64).sin(), 0.1 * (i as f64).cos()]).collect();
        let preferred: Vec<Vec2> = (0..n).map(|i| [0.2 * (2.0 * i as f64).cos(), 0.2 * (2.0 * i as f64).sin()]).collect();
        let g = grid();
        let batch = hrvo_batch(&positions, &velocities, &preferred, None, 0.5, &g, &PARAMS).unwrap();
        assert_eq!(batch, hrvo_batch(&positions, &velocities, &preferred, None, 0.5, &g, &PARAMS).unwrap());
        for i in (0..n).step_by(37) {
            let around: Vec<Neighbour> = (0..n)
                .filter(|&j| j != i)
                .map(|j| Neighbour::from_offset([positions[j][0] - positions[i][0], positions[j][1] - positions[i][1]], velocities[j]))
                .filter(|b| b.distance <= 0.5)
                .collect();
            let one = hrvo_one(velocities[i], preferred[i], positions[i], &around, &g, &PARAMS).unwrap();
            assert_eq!(batch[i], one);
        }
    }

    #[test]
    fn invalid_neighbour_lists_are_errors() {
        let p = [[0.0, 0.0]; 2];
        let g = grid();
        let bad = |indptr: &[i64], indices: &[i64]| hrvo_batch(&p, &p, &p, Some((indptr, indices)), 1.0, &g, &PARAMS).is_err();
        assert!(bad(&[0, 1], &[1]));
        assert!(bad(&[0, 1, 1], &[2]));
        assert!(bad(&[0, 1, 0], &[1]));
        assert!(!bad(&[0, 1, 2], &[1, 0]));
    }
}
