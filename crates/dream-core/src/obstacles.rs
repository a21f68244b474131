//! Obstacles as virtual agents: how a Voronoi cell learns to stay clear of an obstacle.
//!
//! For each robot p and each convex obstacle whose closest point c is within sensing range
//! (distance d, unit direction n from p to c), a virtual agent is placed so that the bisector
//! between robot and agent lies `offset` before the obstacle's surface: at `p + t n` with
//! `t = max(d - offset, GAP)`, the agent at `p + 2 t n`. With `offset = robot radius + margin`
//! the robot's body stays clear; the original used `offset = 0` (the mirror image of p across
//! c), which lets the body touch the obstacle. A robot already closer than `offset` gets its
//! bisector [`GAP`] ahead of it, so its cell keeps to its own side. A robot inside or on an
//! obstacle gets no agent for it (no direction is defined). Closest points come from parry2d's
//! point projection on the obstacle's convex hull.

use parry2d_f64::math::Vector;
use parry2d_f64::query::PointQuery;
use parry2d_f64::shape::ConvexPolygon;

use crate::csr::check_offsets;
use crate::error::{check_finite, GeomError, Result};
use crate::geom::Vec2;

/// Least distance (m) from a robot to the bisector of its virtual agent.
pub const GAP: f64 = 1e-6;
/// Obstacles whose convex hull is smaller than this (m^2) have no extent.
pub const MIN_AREA: f64 = 1e-12;

/// Convex obstacles, each the convex hull of its vertices.
#[derive(Debug, Clone)]
pub struct Obstacles {
    polygons: Vec<ConvexPolygon>,
}

/// Convex hull, counter-clockwise (Andrew's monotone chain; collinear points dropped).
pub fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let mut sorted = points.to_vec();
    sorted.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    sorted.dedup();
    if sorted.len() < 3 {
        return sorted;
    }
    let turn = |o: Vec2, a: Vec2, b: Vec2| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let mut hull: Vec<Vec2> = Vec::with_capacity(2 * sorted.len());
    for pass in [&sorted[..], &sorted.iter().rev().copied().collect::<Vec<_>>()[..]] {
        let floor = hull.len();
        for &p in pass {
            while hull.len() >= floor + 2 && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop(); // each chain's last point starts the other
    }
    hull
}

/// Area of a counter-clockwise polygon (shoelace).
pub fn polygon_area(polygon: &[Vec2]) -> f64 {
    let twice: f64 = (0..polygon.len())
        .map(|k| {
            let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    twice / 2.0
}

impl Obstacles {
    /// Obstacle k is the convex hull of `vertices[offsets[k]..offsets[k + 1]]`.
    ///
    /// # Errors
    /// Non-finite vertices, invalid `offsets`, or an obstacle whose hull has an area below
    /// [`MIN_AREA`] ([`GeomError::DegenerateObstacle`]).
    pub fn new(vertices: &[Vec2], offsets: &[i64]) -> Result<Self> {
        check_finite("obstacle vertices", vertices.as_flattened())?;
        check_offsets("obstacles", offsets, vertices.len(), "vertices")?;
        let polygons = offsets
            .windows(2)
            .enumerate()
            .map(|(k, w)| {
                let hull = convex_hull(&vertices[w[0] as usize..w[1] as usize]);
                if hull.len() < 3 || polygon_area(&hull) <= MIN_AREA {
                    return Err(GeomError::DegenerateObstacle(k));
                }
                let points = hull.iter().map(|v| Vector::new(v[0], v[1])).collect();
                ConvexPolygon::from_convex_polyline_unmodified(points).ok_or(GeomError::DegenerateObstacle(k))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self { polygons })
    }

    /// Number of obstacles.
    pub fn len(&self) -> usize {
        self.polygons.len()
    }

    /// Whether there is no obstacle.
    pub fn is_empty(&self) -> bool {
        self.polygons.is_empty()
    }

    /// The closest point of obstacle `k` to `p`, or `None` when `p` is inside it.
    pub fn closest_point(&self, k: usize, p: Vec2) -> Option<Vec2> {
        let projection = self.polygons[k].project_local_point(Vector::new(p[0], p[1]), true);
        (!projection.is_inside).then_some([projection.point.x, projection.point.y])
    }
}

/// Virtual agents of every robot as CSR `(indptr (n + 1,), points)`, obstacles in order.
///
/// # Errors
/// Non-finite positions, a negative range or a negative offset.
pub fn virtual_agents(
    positions: &[Vec2],
    obstacles: &Obstacles,
    range: f64,
    offset: f64,
) -> Result<(Vec<i64>, Vec<Vec2>)> {
    check_finite("positions", positions.as_flattened())?;
    for (arg, value) in [("range", range), ("offset", offset)] {
        if !(value.is_finite() && value >= 0.0) {
            return Err(GeomError::InvalidParameter {
                arg,
                rule: ">= 0",
                got: value,
            });
        }
    }
    let mut indptr = Vec::with_capacity(positions.len() + 1);
    let mut points = Vec::new();
    indptr.push(0);
    for &p in positions {
        for k in 0..obstacles.len() {
            let Some(c) = obstacles.closest_point(k, p) else {
                continue;
            };
            let (dx, dy) = (c[0] - p[0], c[1] - p[1]);
            let distance = (dx * dx + dy * dy).sqrt();
            if distance > range || distance == 0.0 {
                continue;
            }
            let reach = 2.0 * (distance - offset).max(GAP);
            points.push([p[0] + reach * (dx / distance), p[1] + reach * (dy / distance)]);
        }
        indptr.push(points.len() as i64);
    }
    Ok((indptr, points))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Obstacles {
        Obstacles::new(&[[1.0, -0.5], [2.0, -0.5], [2.0, 0.5], [1.0, 0.5]], &[0, 4]).unwrap()
    }

    #[test]
    fn closest_point_of_a_square() {
        let c = square().closest_point(0, [0.0, 0.2]).unwrap();
        assert!((c[0] - 1.0).abs() < 1e-12 && (c[1] - 0.2).abs() < 1e-12);
        assert!(square().closest_point(0, [1.5, 0.0]).is_none());
    }

    #[test]
    fn virtual_agent_keeps_the_bisector_before_the_surface() {
        let (indptr, points) = virtual_agents(&[[0.0, 0.0], [-5.0, 0.0], [0.95, 0.0]], &square(), 1.5, 0.1).unwrap();
        assert_eq!(indptr, vec![0, 1, 1, 2]); // the far robot does not sense the obstacle
                                              // Bisector at x = 0.9: the agent of (0, 0) is at (1.8, 0).
        assert!((points[0][0] - 1.8).abs() < 1e-12 && points[0][1].abs() < 1e-12);
        // A robot closer than the offset: the bisector is just ahead of it.
        assert!((points[1][0] - (0.95 + 2.0 * GAP)).abs() < 1e-12);
    }

    #[test]
    fn hull_ignores_interior_and_collinear_points() {
        let hull = convex_hull(&[
            [0.0, 0.0],
            [1.0, 0.0],
            [0.5, 0.0],
            [1.0, 1.0],
            [0.5, 0.5],
            [0.0, 1.0],
            [0.0, 1.0],
        ]);
        assert_eq!(hull, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        assert!((polygon_area(&hull) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn degenerate_obstacles_are_errors() {
        let degenerate = |vertices: &[Vec2]| {
            matches!(
                Obstacles::new(vertices, &[0, vertices.len() as i64]),
                Err(GeomError::DegenerateObstacle(0))
            )
        };
        assert!(degenerate(&[]));
        assert!(degenerate(&[[0.0, 0.0]]));
        assert!(degenerate(&[[0.0, 0.0], [1.0, 0.0]]));
        assert!(degenerate(&[[1.0, 1.0]; 3]));
        assert!(degenerate(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]));
        assert!(!degenerate(&[[0.0, 0.0], [1.0, 0.0], [0.5, 1e-6]]));
        assert!(Obstacles::new(&[[0.0, 0.0]], &[0, 2]).is_err());
    }
}
