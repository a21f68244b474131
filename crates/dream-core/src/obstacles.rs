//! Obstacles as virtual agents: how a Voronoi cell learns to stay clear of an obstacle.
//!
//! For each robot p and each convex obstacle whose closest point c is within sensing range, a
//! virtual agent is placed at the mirror image of p across `c - n * offset` (n the unit vector
//! from p to c): the bisector between robot and virtual agent then lies `offset` before the
//! obstacle's surface. With `offset = robot radius + margin` the robot's body stays clear; the
//! original mirrored across c itself (`offset = 0`), which lets the body touch the obstacle.
//! A robot inside or on an obstacle gets no virtual agent for it (no direction is defined).
//! Closest points come from parry2d's point projection.

use parry2d_f64::math::Vector;
use parry2d_f64::query::PointQuery;
use parry2d_f64::shape::ConvexPolygon;

use crate::error::{check_finite, GeomError, Result};
use crate::hrvo::Vec2;

/// Convex obstacles, each the convex hull of its vertices.
#[derive(Debug, Clone)]
pub struct Obstacles {
    polygons: Vec<ConvexPolygon>,
}

impl Obstacles {
    /// Obstacle k is the convex hull of `vertices[offsets[k]..offsets[k + 1]]`.
    ///
    /// # Errors
    /// Non-finite vertices, an invalid `offsets`, or an obstacle with no area.
    pub fn new(vertices: &[Vec2], offsets: &[i64]) -> Result<Self> {
        check_finite("obstacle vertices", vertices.as_flattened())?;
        let rising = offsets.first() == Some(&0)
            && offsets.last() == Some(&(vertices.len() as i64))
            && offsets.windows(2).all(|w| w[0] <= w[1]);
        if !rising {
            return Err(GeomError::InvalidNeighbours {
                robots: offsets.len().saturating_sub(1),
                reason: "obstacle offsets must rise from 0 to the number of vertices".into(),
            });
        }
        let polygons = offsets
            .windows(2)
            .enumerate()
            .map(|(k, w)| {
                let points: Vec<Vector> =
                    vertices[w[0] as usize..w[1] as usize].iter().map(|v| Vector::new(v[0], v[1])).collect();
                ConvexPolygon::from_convex_hull(&points).ok_or(GeomError::DegenerateObstacle(k))
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
pub fn virtual_agents(positions: &[Vec2], obstacles: &Obstacles, range: f64, offset: f64) -> Result<(Vec<i64>, Vec<Vec2>)> {
    check_finite("positions", positions.as_flattened())?;
    for (arg, value) in [("range", range), ("offset", offset)] {
        if !(value.is_finite() && value >= 0.0) {
            return Err(GeomError::InvalidParameter { arg, rule: ">= 0", got: value });
        }
    }
    let mut indptr = Vec::with_capacity(positions.len() + 1);
    let mut points = Vec::new();
    indptr.push(0);
    for &p in positions {
        for k in 0..obstacles.len() {
            let Some(c) = obstacles.closest_point(k, p) else { continue };
            let (dx, dy) = (c[0] - p[0], c[1] - p[1]);
            let distance = (dx * dx + dy * dy).sqrt();
            if distance > range || distance == 0.0 {
                continue;
            }
            let surface = [c[0] - dx / distance * offset, c[1] - dy / distance * offset];
            points.push([2.0 * surface[0] - p[0], 2.0 * surface[1] - p[1]]);
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
        let (indptr, points) = virtual_agents(&[[0.0, 0.0], [-5.0, 0.0]], &square(), 1.5, 0.1).unwrap();
        assert_eq!(indptr, vec![0, 1, 1]); // the far robot does not sense the obstacle
        // Mirror of (0, 0) across x = 0.9 is (1.8, 0).
        assert!((points[0][0] - 1.8).abs() < 1e-12 && points[0][1].abs() < 1e-12);
    }

    #[test]
    fn degenerate_obstacles_are_errors() {
        assert!(Obstacles::new(&[[0.0, 0.0], [1.0, 0.0]], &[0, 2]).is_err());
        assert!(Obstacles::new(&[[0.0, 0.0]], &[0, 2]).is_err());
    }
}
