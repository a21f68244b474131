//! Voronoi cells bounded by a disc and the arena, by exact convex polygon clipping.
//!
//! Robot i's cell starts as the disc of `radius` around it (a regular polygon of `resolution`
//! vertices, the first at angle 0), is clipped by the arena, then by the perpendicular-bisector
//! half-plane of every other robot within `2 radius` and of each of its virtual agents, nearest
//! first (ties: robots by increasing index, then virtual agents in the given order). A robot
//! whose cell is empty gets area 0 and its own position as centroid. The arithmetic matches the
//! NumPy reference operation by operation.
//!
//! A disc far larger than the arena clips nothing but ruins the clipping's precision (at a
//! radius of 1e20 the intersections with the walls lose every digit), so each robot's disc is
//! first shrunk to [`covering_radius`], which still contains the whole arena.

use std::f64::consts::TAU;

use rayon::prelude::*;

use crate::csr::check_offsets;
use crate::error::{check_len, GeomError, Result};
use crate::geom::Arena;
use crate::geom::Vec2;
use crate::neighbours;
use crate::parallel::first_where;

/// Largest number of vertices of a cell's disc (far beyond any use; keeps memory bounded).
pub const MAX_RESOLUTION: usize = 1 << 20;

/// Largest coordinate magnitude (m) of robots, agents and bounds: the centroid sums products of
/// three coordinates, which overflow beyond ~1e102.
pub const MAX_COORDINATE: f64 = 1e100;

/// Rows below this count run on one thread.
pub(crate) const PARALLEL_ROBOTS: usize = 256;

/// Every robot's cell: centroid, area and polygon (CSR: robot i's vertices are
/// `vertices[offsets[i]..offsets[i + 1]]`, counter-clockwise).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Cells {
    pub centroids: Vec<Vec2>,
    pub areas: Vec<f64>,
    pub vertices: Vec<Vec2>,
    pub offsets: Vec<i64>,
}

impl Cells {
    /// The cells of robots given one after the other as `(polygon, area, centroid)`.
    pub(crate) fn from_rows(rows: Vec<(Vec<Vec2>, f64, Vec2)>) -> Self {
        let mut cells = Cells {
            offsets: Vec::with_capacity(rows.len() + 1),
            ..Cells::default()
        };
        cells.offsets.push(0);
        for (polygon, area, centroid) in rows {
            cells.vertices.extend(polygon);
            cells.offsets.push(cells.vertices.len() as i64);
            cells.areas.push(area);
            cells.centroids.push(centroid);
        }
        cells
    }
}

/// Keeps the part of the convex `polygon` where `(q - point) . normal <= 0`, into `out`.
fn clip(polygon: &[Vec2], point: Vec2, normal: Vec2, out: &mut Vec<Vec2>) {
    out.clear();
    let side = |q: Vec2| (q[0] - point[0]) * normal[0] + (q[1] - point[1]) * normal[1];
    for k in 0..polygon.len() {
        let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
        let (sa, sb) = (side(a), side(b));
        if sa <= 0.0 {
            out.push(a);
        }
        if (sa <= 0.0) != (sb <= 0.0) {
            let t = sa / (sa - sb);
            out.push([a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]);
        }
    }
}

/// Area and centroid of a simple polygon (shoelace); `fallback` is the centroid of an empty one.
pub fn area_centroid(polygon: &[Vec2], fallback: Vec2) -> (f64, Vec2) {
    let (mut twice, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for k in 0..polygon.len() {
        let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
        let cross = a[0] * b[1] - b[0] * a[1];
        twice += cross;
        cx += (a[0] + b[0]) * cross;
        cy += (a[1] + b[1]) * cross;
    }
    if polygon.len() < 3 || twice <= 0.0 {
        (0.0, fallback)
    } else {
        (twice / 2.0, [cx / (3.0 * twice), cy / (3.0 * twice)])
    }
}

/// A disc radius around `p` whose polygon (of any resolution >= 3) contains the whole arena.
///
/// The arena lies in the disc of `|p - centre| + half diagonal` around `p`, and a regular
/// polygon of at least 3 vertices contains the disc of half its radius. Only `+ - * sqrt`, so
/// that the NumPy reference gets the same bits; it is infinite only for coordinates beyond
/// ~1e154, where it leaves the radius as given.
pub fn covering_radius(p: Vec2, arena: &Arena) -> f64 {
    let (dx, dy) = (
        p[0] - (0.5 * arena.xmin + 0.5 * arena.xmax),
        p[1] - (0.5 * arena.ymin + 0.5 * arena.ymax),
    );
    let (width, height) = (arena.xmax - arena.xmin, arena.ymax - arena.ymin);
    2.0 * ((dx * dx + dy * dy).sqrt() + 0.5 * (width * width + height * height).sqrt())
}

/// The directions `(cos, sin)` of a disc polygon's `resolution` vertices, the first at angle 0.
pub(crate) fn unit_circle(resolution: usize) -> Vec<Vec2> {
    (0..resolution)
        .map(|k| {
            let angle = TAU * k as f64 / resolution as f64;
            [angle.cos(), angle.sin()]
        })
        .collect()
}

/// A cell being clipped: the disc around `p` cut by the arena, then by one bisector after
/// another (nearest agent first), with the distance `reach` to its farthest vertex.
pub(crate) struct Clipper {
    p: Vec2,
    polygon: Vec<Vec2>,
    scratch: Vec<Vec2>,
    reach: f64,
}

impl Clipper {
    /// The disc of `radius` around `p` (vertex directions `circle`, [`unit_circle`]) within the arena.
    pub(crate) fn new(p: Vec2, radius: f64, arena: &Arena, circle: &[Vec2]) -> Self {
        let radius = radius.min(covering_radius(p, arena));
        let mut polygon: Vec<Vec2> = circle
            .iter()
            .map(|u| [p[0] + radius * u[0], p[1] + radius * u[1]])
            .collect();
        let mut scratch = Vec::with_capacity(circle.len() + 8);
        // Each wall with whether the disc's square lies within it: then so does every vertex
        // (rounding is monotone), and the clip would give the polygon back as it is.
        let walls = [
            ([arena.xmin, 0.0], [-1.0, 0.0], p[0] - radius >= arena.xmin),
            ([arena.xmax, 0.0], [1.0, 0.0], p[0] + radius <= arena.xmax),
            ([0.0, arena.ymin], [0.0, -1.0], p[1] - radius >= arena.ymin),
            ([0.0, arena.ymax], [0.0, 1.0], p[1] + radius <= arena.ymax),
        ];
        for (point, normal, within) in walls {
            if !within {
                clip(&polygon, point, normal, &mut scratch);
                std::mem::swap(&mut polygon, &mut scratch);
            }
        }
        let reach = farthest(&polygon, p);
        Self {
            p,
            polygon,
            scratch,
            reach,
        }
    }

    /// Clips the cell by the bisector of `p` and `q`, unless it surely misses the cell.
    pub(crate) fn cut(&mut self, q: Vec2) {
        if beyond(self.p, q, self.reach) {
            return;
        }
        let p = self.p;
        let middle = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
        clip(&self.polygon, middle, [q[0] - p[0], q[1] - p[1]], &mut self.scratch);
        std::mem::swap(&mut self.polygon, &mut self.scratch);
        self.reach = farthest(&self.polygon, p);
    }

    /// Whether every agent farther than `sqrt(squared)` from `p` whose `|x| + |y|` is at most
    /// `widest` surely misses the cell (so do all of them when the cell is empty): clipping
    /// nearest first may stop there.
    pub(crate) fn settled(&self, squared: f64, widest: f64) -> bool {
        let bound = skip_bound(self.p, widest, self.reach);
        self.polygon.is_empty() || (bound > 1e-100 && squared > bound * bound)
    }

    pub(crate) fn polygon(self) -> Vec<Vec2> {
        self.polygon
    }
}

/// The largest `|x| + |y|` of `points` (0 for none): with it [`Clipper::settled`] holds for all.
pub(crate) fn widest(points: impl Iterator<Item = Vec2>) -> f64 {
    points.map(|q| q[0].abs() + q[1].abs()).fold(0.0, f64::max)
}

/// The cell around `p` from the disc of `radius` (vertex directions `circle`, [`unit_circle`]).
fn cell(p: Vec2, radius: f64, arena: &Arena, agents: impl Iterator<Item = Vec2>, circle: &[Vec2]) -> Vec<Vec2> {
    let mut cell = Clipper::new(p, radius, arena, circle);
    // Nearest first (ties in the given order): the first few clips shrink the cell and the rest
    // lie beyond it. Only a batch of the nearest is sorted at a time, and once the next agent
    // lies beyond the cell, so do all later ones: a robot in a crowd hears hundreds of robots,
    // of which a dozen shape its cell.
    let mut agents: Vec<Agent> = agents
        .enumerate()
        .map(|(k, q)| (squared_distance(p, q).to_bits(), k, q))
        .collect();
    let widest = widest(agents.iter().map(|&(_, _, q)| q));
    nearest_first(
        &mut agents,
        |&(d, k, _)| (d, k),
        |&(squared, _, q)| {
            // Nonnegative floats order as their bits do.
            if cell.settled(f64::from_bits(squared), widest) {
                return true;
            }
            cell.cut(q);
            false
        },
    );
    cell.polygon()
}

/// Calls `stop(item)` on `items` in increasing `key` (a total order), until it returns true;
/// returns whether it did. Only a batch of the nearest is sorted at a time: a cell's first few
/// clips settle it, and the rest lie beyond.
pub(crate) fn nearest_first<T: Copy, K: Ord>(
    items: &mut [T],
    key: impl Fn(&T) -> K + Copy,
    mut stop: impl FnMut(&T) -> bool,
) -> bool {
    let mut done = 0;
    while done < items.len() {
        let rest = &mut items[done..];
        let batch = rest.len().min(NEAREST_BATCH);
        if batch < rest.len() {
            rest.select_nth_unstable_by_key(batch - 1, key);
        }
        rest[..batch].sort_unstable_by_key(key);
        if rest[..batch].iter().any(&mut stop) {
            return true;
        }
        done += batch;
    }
    false
}

/// An agent of a cell: `(|q - p|^2 as bits, place in the given order, q)`.
type Agent = (u64, usize, Vec2);

/// Agents sorted at a time, nearest first (a cell in a crowd has a dozen sides).
const NEAREST_BATCH: usize = 32;

/// `|q - p|^2`, as the NumPy reference computes it.
pub(crate) fn squared_distance(p: Vec2, q: Vec2) -> f64 {
    let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
    dx * dx + dy * dy
}

/// Distance (m) from `p` to the farthest vertex of `polygon`.
fn farthest(polygon: &[Vec2], p: Vec2) -> f64 {
    polygon
        .iter()
        .map(|&v| squared_distance(p, v))
        .fold(0.0, f64::max)
        .sqrt()
}

/// Whether the bisector of `p` and `q` surely misses a cell around `p` whose vertices lie within
/// `reach` of it, so that clipping by it would return the cell unchanged, bit for bit (every
/// vertex's side test stays <= 0): `q` lies beyond twice the reach, with margins far above the
/// rounding of the side tests (relative 1e-6, and 1e-12 of the coordinates, which round the
/// bisector's midpoint). Skipping such points costs one distance instead of a pass over the
/// cell: a robot in a crowd hears hundreds of robots, of which a dozen shape its cell.
fn beyond(p: Vec2, q: Vec2, reach: f64) -> bool {
    let bound = skip_bound(p, q[0].abs() + q[1].abs(), reach);
    // Below ~1e-100 the squares lose their precision to underflow: no skipping there.
    bound > 1e-100 && squared_distance(p, q) > bound * bound
}

/// The distance from `p` beyond which [`beyond`] skips an agent whose `|x| + |y|` is `size`; it
/// grows with `size`, so with the largest `size` of a cell's agents it holds for all of them.
fn skip_bound(p: Vec2, size: f64, reach: f64) -> f64 {
    2.0 * (reach * (1.0 + 1e-6) + 1e-12 * (p[0].abs() + p[1].abs() + size))
}

/// One robot's cell at `p`, clipped by the robots `others` (those beyond `2 radius` change
/// nothing) and its virtual `agents`, in that order: counter-clockwise vertices, empty if
/// nothing is left.
///
/// # Errors
/// Non-finite input or coordinates beyond [`MAX_COORDINATE`], a non-positive radius or a
/// resolution outside 3..=2^20.
pub fn voronoi_cell(
    p: Vec2,
    others: &[Vec2],
    agents: &[Vec2],
    radius: f64,
    arena: &Arena,
    resolution: usize,
) -> Result<Vec<Vec2>> {
    check_coordinates("position", &p)?;
    check_coordinates("others", others.as_flattened())?;
    check_coordinates("virtual", agents.as_flattened())?;
    check_cell_parameters(radius, arena, resolution)?;
    let agents = others.iter().chain(agents).copied();
    Ok(cell(p, radius, arena, agents, &unit_circle(resolution)))
}

/// Whether `value` is finite and at most [`MAX_COORDINATE`] in magnitude (NaN is not).
pub(crate) fn within_reach(value: f64) -> bool {
    value.abs() <= MAX_COORDINATE
}

/// Finite values of magnitude at most [`MAX_COORDINATE`].
pub(crate) fn check_coordinates(arg: &'static str, values: &[f64]) -> Result<()> {
    // One pass, on every core for many.
    match first_where(values.len(), |i| !within_reach(values[i])) {
        None => Ok(()),
        Some(index) if !values[index].is_finite() => Err(GeomError::NonFinite { arg, index }),
        Some(index) => Err(GeomError::InvalidParameter {
            arg,
            rule: "at most 1e100 in magnitude",
            got: values[index],
        }),
    }
}

pub(crate) fn check_cell_parameters(radius: f64, arena: &Arena, resolution: usize) -> Result<()> {
    check_coordinates("bounds", &[arena.xmin, arena.xmax, arena.ymin, arena.ymax])?;
    if !(radius.is_finite() && radius > 0.0) {
        return Err(GeomError::InvalidParameter {
            arg: "radius",
            rule: "> 0",
            got: radius,
        });
    }
    if !(3..=MAX_RESOLUTION).contains(&resolution) {
        return Err(GeomError::InvalidParameter {
            arg: "resolution",
            rule: "between 3 and 2^20",
            got: resolution as f64,
        });
    }
    Ok(())
}

/// Cells of every robot. `virtual_agents` is CSR `(indptr, points)`: robot i's virtual agents
/// are `points[indptr[i]..indptr[i + 1]]`. Without `neighbours`, a cell is clipped by its
/// virtual agents alone, not by the other robots: the cells of robots that each know only what
/// they were told (say, the positions their radio heard, given as virtual agents).
///
/// # Errors
/// Non-finite input or coordinates beyond [`MAX_COORDINATE`], a non-positive radius, a
/// resolution outside 3..=2^20, or an invalid virtual-agent CSR.
pub fn voronoi_cells(
    positions: &[Vec2],
    radius: f64,
    arena: &Arena,
    virtual_agents: Option<(&[i64], &[Vec2])>,
    resolution: usize,
    neighbours: bool,
) -> Result<Cells> {
    let n = positions.len();
    check_coordinates("positions", positions.as_flattened())?;
    check_cell_parameters(radius, arena, resolution)?;
    if let Some((indptr, points)) = virtual_agents {
        check_len("virtual indptr", n + 1, indptr.len())?;
        check_coordinates("virtual", points.as_flattened())?;
        check_offsets("virtual", indptr, points.len(), "points")?;
    }
    let (xs, ys): (Vec<f64>, Vec<f64>) = positions.iter().map(|p| (p[0], p[1])).unzip();
    // Robots beyond twice a robot's (shrunk) disc radius cannot clip its cell.
    let reach = positions
        .iter()
        .map(|&p| radius.min(covering_radius(p, arena)))
        .fold(0.0, f64::max);
    let near = if neighbours {
        Some(neighbours::within(
            &xs,
            &ys,
            (2.0 * reach).min(f64::MAX),
            None,
            None,
            None,
        )?)
    } else {
        None
    };
    let circle = unit_circle(resolution);
    let robot = |i: usize| {
        let others = match &near {
            Some(near) => &near.indices[near.indptr[i] as usize..near.indptr[i + 1] as usize],
            None => &[][..],
        };
        let others = others.iter().map(|&j| positions[j as usize]);
        let own: &[Vec2] = match virtual_agents {
            Some((indptr, points)) => &points[indptr[i] as usize..indptr[i + 1] as usize],
            None => &[],
        };
        let polygon = cell(positions[i], radius, arena, others.chain(own.iter().copied()), &circle);
        let (area, centroid) = area_centroid(&polygon, positions[i]);
        (polygon, area, centroid)
    };
    let per_robot: Vec<(Vec<Vec2>, f64, Vec2)> = if n >= PARALLEL_ROBOTS {
        (0..n).into_par_iter().map(robot).collect()
    } else {
        (0..n).map(robot).collect()
    };
    Ok(Cells::from_rows(per_robot))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arena() -> Arena {
        Arena::new(-1.6, 1.6, -1.0, 1.0).unwrap()
    }

    #[test]
    fn lone_robot_gets_its_disc() {
        let cells = voronoi_cells(&[[0.0, 0.0]], 0.5, &arena(), None, 256, true).unwrap();
        let disc = std::f64::consts::PI * 0.25;
        assert!((cells.areas[0] - disc).abs() < 1e-3 * disc);
        assert!(cells.centroids[0][0].abs() < 1e-12 && cells.centroids[0][1].abs() < 1e-12);
    }

    #[test]
    fn two_robots_split_the_plane_at_the_bisector() {
        let cells = voronoi_cells(&[[-0.2, 0.0], [0.2, 0.0]], 0.5, &arena(), None, 64, true).unwrap();
        let left = &cells.vertices[cells.offsets[0] as usize..cells.offsets[1] as usize];
        assert!(left.iter().all(|v| v[0] <= 1e-12));
        assert!((cells.areas[0] - cells.areas[1]).abs() < 1e-12);
        assert!(cells.centroids[0][0] < -0.2);
    }

    #[test]
    fn arena_and_virtual_agents_cut_the_cell() {
        // A robot in the corner: the arena takes three quarters of its small disc.
        let corner = voronoi_cells(&[[1.6, 1.0]], 0.1, &arena(), None, 400, true).unwrap();
        assert!((corner.areas[0] - std::f64::consts::PI * 0.01 / 4.0).abs() < 1e-4);
        // A virtual agent straight above at 0.4 m keeps the cell below y = 0.2.
        let cut = voronoi_cells(&[[0.0, 0.0]], 0.5, &arena(), Some((&[0, 1], &[[0.0, 0.4]])), 64, true).unwrap();
        assert!(cut.vertices.iter().all(|v| v[1] <= 0.2 + 1e-12));
    }

    #[test]
    fn robot_outside_the_arena_has_an_empty_cell() {
        let cells = voronoi_cells(&[[5.0, 5.0]], 0.5, &arena(), None, 64, true).unwrap();
        assert_eq!(cells.areas[0], 0.0);
        assert_eq!(cells.centroids[0], [5.0, 5.0]);
        assert_eq!(cells.offsets, vec![0, 0]);
    }
}
