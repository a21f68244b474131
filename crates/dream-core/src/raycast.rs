//! Distance sensors: rays cast from every robot against line-segment walls and the other robots.
//!
//! Each robot carries `k` rays (the GRITSbot has 7 infrared sensors). Ray `j` of robot `i` starts
//! at the body-frame point `(bx_j, by_j)` of a centre `centre_offset` ahead of the robot's pose
//! and points at `heading + angle_j`; it reads the distance to the nearest hit within `range`,
//! or [`NOTHING`]. The criteria are rps 2.1's, so that noiseless readings equal its recordings:
//! - a wall (segment `a`-`b`) is hit at `t` when `start + t d` lies on the segment with
//!   `0 <= t <= range`; walls parallel to the ray (|d x (b - a)| below [`PARALLEL`]) are skipped;
//! - another robot is a disc of `robot_radius` around its own offset centre, hit at
//!   `p - sqrt(r^2 - q^2)` when the disc centre projects at `0 <= p <= range` on the ray with
//!   perpendicular distance `q <= r` and the hit is not behind the start (a ray starting
//!   inside a disc does not see it);
//! - a hit at exactly `range` reads as nothing; the arena's edges are not seen.
//!
//! Robots are bucketed in a grid of cells one ray reach wide, so a swarm costs O(n k m) for `m`
//! robots within reach, not O(n^2 k); robots are processed in parallel.

use rayon::prelude::*;

use crate::error::{check_finite, check_len, check_positive, GeomError, Result};
use crate::grid::Grid;

/// The reading of a ray that hits nothing within range.
pub const NOTHING: f64 = -1.0;
/// Cross products of unit ray direction and wall below this count as parallel (rps 2.1's
/// threshold of 1e-10 on a ray of 1.2 m, scaled to a unit direction).
pub const PARALLEL: f64 = 1e-10 / 1.2;
/// Robots from which rays are cast in parallel; fewer run on the calling thread.
const PARALLEL_ROBOTS: usize = 64;

/// One ray in the body frame of the sensor centre: start point (m) and angle from the heading (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub x: f64,
    pub y: f64,
    pub angle: f64,
}

/// The sensor head shared by every robot.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensors {
    pub rays: Vec<Ray>,
    /// How far ahead of the pose the sensor centre (and the robot's disc) sits (m).
    pub centre_offset: f64,
    /// Radius of the disc other robots' rays see (m).
    pub robot_radius: f64,
    /// Longest distance read (m).
    pub range: f64,
}

impl Sensors {
    /// # Errors
    /// [`GeomError::NonFinite`] for a non-finite ray or offset, [`GeomError::InvalidParameter`]
    /// unless `robot_radius >= 0` and `range > 0`.
    pub fn new(rays: Vec<Ray>, centre_offset: f64, robot_radius: f64, range: f64) -> Result<Self> {
        let values: Vec<f64> = rays.iter().flat_map(|r| [r.x, r.y, r.angle]).collect();
        check_finite("rays", &values)?;
        check_finite("centre_offset", &[centre_offset])?;
        if !(robot_radius.is_finite() && robot_radius >= 0.0) {
            return Err(GeomError::InvalidParameter {
                arg: "robot_diameter",
                rule: ">= 0",
                got: 2.0 * robot_radius,
            });
        }
        check_positive("range", range)?;
        Ok(Self {
            rays,
            centre_offset,
            robot_radius,
            range,
        })
    }

    /// Largest distance from a sensor centre at which a ray can still meet a robot's disc.
    fn reach(&self) -> f64 {
        let start = self.rays.iter().map(|r| r.x.hypot(r.y)).fold(0.0, f64::max);
        start + self.range + self.robot_radius
    }
}

/// A line-segment wall from `a` to `b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    pub a: [f64; 2],
    pub b: [f64; 2],
}

impl Wall {
    /// Squared distance from `p` to the closest point of the segment.
    fn distance_squared(&self, p: [f64; 2]) -> f64 {
        let e = [self.b[0] - self.a[0], self.b[1] - self.a[1]];
        let w = [p[0] - self.a[0], p[1] - self.a[1]];
        let length_squared = e[0] * e[0] + e[1] * e[1];
        let t = if length_squared > 0.0 {
            ((w[0] * e[0] + w[1] * e[1]) / length_squared).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (dx, dy) = (w[0] - t * e[0], w[1] - t * e[1]);
        dx * dx + dy * dy
    }
}

fn cross(u: [f64; 2], v: [f64; 2]) -> f64 {
    u[0] * v[1] - u[1] * v[0]
}

/// Distance along the unit ray `start + t d` to the wall, if it is hit with `0 <= t <= range`.
fn wall_hit(start: [f64; 2], d: [f64; 2], wall: &Wall, range: f64) -> Option<f64> {
    let e = [wall.b[0] - wall.a[0], wall.b[1] - wall.a[1]];
    let denominator = cross(d, e);
    if denominator.abs() < PARALLEL {
        return None;
    }
    let w = [wall.a[0] - start[0], wall.a[1] - start[1]];
    let t = cross(w, e) / denominator;
    let u = cross(w, d) / denominator;
    ((0.0..=range).contains(&t) && (0.0..=1.0).contains(&u)).then_some(t)
}

/// Distance along the unit ray to the disc of `radius` around `centre`, by rps 2.1's criterion.
fn disc_hit(start: [f64; 2], d: [f64; 2], centre: [f64; 2], radius: f64, range: f64) -> Option<f64> {
    let to = [centre[0] - start[0], centre[1] - start[1]];
    let along = to[0] * d[0] + to[1] * d[1];
    if !(0.0..=range).contains(&along) {
        return None;
    }
    let (px, py) = (start[0] + along * d[0] - centre[0], start[1] + along * d[1] - centre[1]);
    // Squared distances: `hypot` costs more than the rest of the test.
    let off_squared = px * px + py * py;
    if off_squared.sqrt() > radius {
        return None;
    }
    let hit = along - (radius * radius - off_squared).sqrt();
    (hit >= 0.0).then_some(hit)
}

/// Readings `(k, n)` (row-major: ray `j` of robot `i` at `j * n + i`) of the rays of the robots
/// `sources` (all robots when `None`) at `poses` `(3, n)`; columns of robots not in `sources`
/// read [`NOTHING`].
///
/// # Errors
/// Length or finiteness problems of `poses`, non-finite walls, or a source id `>= n`.
pub fn distance_rays(
    poses: &[f64],
    n: usize,
    walls: &[Wall],
    sensors: &Sensors,
    sources: Option<&[usize]>,
) -> Result<Vec<f64>> {
    check_len("poses", 3 * n, poses.len())?;
    check_finite("poses", poses)?;
    let corners: Vec<f64> = walls.iter().flat_map(|w| [w.a[0], w.a[1], w.b[0], w.b[1]]).collect();
    check_finite("walls", &corners)?;
    let all: Vec<usize>;
    let sources = match sources {
        Some(ids) => {
            if let Some(&bad) = ids.iter().find(|&&i| i >= n) {
                return Err(GeomError::InvalidParameter {
                    arg: "robots",
                    rule: "a robot id < n",
                    got: bad as f64,
                });
            }
            ids
        }
        None => {
            all = (0..n).collect();
            &all
        }
    };
    let (xs, rest) = poses.split_at(n);
    let (ys, thetas) = rest.split_at(n);
    let offset = sensors.centre_offset;
    let centres: Vec<[f64; 2]> = (0..n)
        .map(|i| [xs[i] + offset * thetas[i].cos(), ys[i] + offset * thetas[i].sin()])
        .collect();
    let (cx, cy): (Vec<f64>, Vec<f64>) = centres.iter().map(|c| (c[0], c[1])).unzip();
    let reach = sensors.reach();
    let grid = Grid::new(&cx, &cy, reach);

    let robot = |i: usize| -> Vec<f64> {
        // Only robots whose disc some ray can reach: the grid block is ~3x larger than that circle.
        let mut near = Vec::new();
        grid.for_each_near(cx[i], cy[i], |m| {
            let (dx, dy) = (cx[m] - cx[i], cy[m] - cy[i]);
            if m != i && dx * dx + dy * dy <= reach * reach {
                near.push(m);
            }
        });
        // Walls out of reach cannot be hit (the margin covers rounding in the distance).
        let reachable: Vec<&Wall> = walls
            .iter()
            .filter(|w| w.distance_squared(centres[i]) <= (reach + 1e-9) * (reach + 1e-9))
            .collect();
        let (c, s) = (thetas[i].cos(), thetas[i].sin());
        sensors
            .rays
            .iter()
            .map(|ray| {
                let start = [
                    centres[i][0] + c * ray.x - s * ray.y,
                    centres[i][1] + s * ray.x + c * ray.y,
                ];
                let heading = thetas[i] + ray.angle;
                let d = [heading.cos(), heading.sin()];
                let range = sensors.range;
                let walls = reachable.iter().filter_map(|w| wall_hit(start, d, w, range));
                let robots = near
                    .iter()
                    .filter_map(|&m| disc_hit(start, d, centres[m], sensors.robot_radius, range));
                let nearest = walls.chain(robots).fold(range, f64::min);
                if nearest < range {
                    nearest
                } else {
                    NOTHING
                }
            })
            .collect()
    };
    let columns: Vec<Vec<f64>> = if sources.len() >= PARALLEL_ROBOTS {
        sources.par_iter().map(|&i| robot(i)).collect()
    } else {
        sources.iter().map(|&i| robot(i)).collect()
    };
    let k = sensors.rays.len();
    let mut readings = vec![NOTHING; k * n];
    for (&i, column) in sources.iter().zip(&columns) {
        for (j, &value) in column.iter().enumerate() {
            readings[j * n + i] = value;
        }
    }
    Ok(readings)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn forward(range: f64) -> Sensors {
        let ray = Ray {
            x: 0.0,
            y: 0.0,
            angle: 0.0,
        };
        Sensors::new(vec![ray], 0.0, 0.055, range).unwrap()
    }

    #[test]
    fn ray_reads_the_nearest_of_wall_and_robot() {
        let wall = Wall {
            a: [0.5, -1.0],
            b: [0.5, 1.0],
        };
        // Robot 0 at the origin facing +x, robot 1 at x = 0.3 (its disc starts at 0.245).
        let poses = [0.0, 0.3, 0.0, 0.0, 0.0, 0.0];
        let got = distance_rays(&poses, 2, &[wall], &forward(1.2), None).unwrap();
        assert!((got[0] - 0.245).abs() < 1e-15);
        // Robot 1 sees the wall 0.2 ahead; nothing else.
        assert!((got[1] - 0.2).abs() < 1e-15);
        let only = distance_rays(&poses, 2, &[wall], &forward(1.2), Some(&[1])).unwrap();
        assert_eq!(only[0], NOTHING);
        assert_eq!(only[1], got[1]);
    }

    #[test]
    fn nothing_in_range_parallel_walls_and_discs_around_the_start_read_nothing() {
        let far = Wall {
            a: [1.5, -1.0],
            b: [1.5, 1.0],
        };
        let parallel = Wall {
            a: [0.0, 0.0],
            b: [1.0, 0.0],
        };
        // Robot 1 sits on robot 0's ray start: inside its disc, so unseen.
        let poses = [0.0, 0.01, 0.0, 0.0, 0.0, 0.0];
        let got = distance_rays(&poses, 2, &[far, parallel], &forward(1.2), Some(&[0])).unwrap();
        assert_eq!(got[0], NOTHING);
        // A hit at exactly the range reads nothing, as in rps 2.1.
        let edge = Wall {
            a: [1.0, -1.0],
            b: [1.0, 1.0],
        };
        let got = distance_rays(&[0.0, 0.0, 0.0], 1, &[edge], &forward(1.0), None).unwrap();
        assert_eq!(got[0], NOTHING);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(matches!(
            distance_rays(&[0.0; 5], 2, &[], &forward(1.2), None),
            Err(GeomError::LengthMismatch { arg: "poses", .. })
        ));
        assert!(distance_rays(&[0.0; 3], 1, &[], &forward(1.2), Some(&[1])).is_err());
        assert!(Sensors::new(vec![], 0.0, -1.0, 1.2).is_err());
        assert!(Sensors::new(vec![], 0.0, 0.05, 0.0).is_err());
        assert!(distance_rays(&[], 0, &[], &forward(1.2), None).unwrap().is_empty());
    }
}
