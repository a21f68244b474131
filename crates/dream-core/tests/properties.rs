//! Property tests of dream-core's public API (issue 14): on random and extreme but legal input
//! every kernel returns finite output that obeys its invariants; on illegal input it returns an
//! error naming the argument, never a panic. Deterministic: a fixed seed, no persistence files.

use std::f64::consts::PI;

use dream_core::dynamics::{self, Wheels};
use dream_core::geom::Arena;
use dream_core::geom::Vec2;
use dream_core::hrvo::{self, HrvoParams};
use dream_core::neighbours;
use dream_core::obstacles::{self, Obstacles};
use dream_core::perceive;
use dream_core::raycast::{self, Ray, Sensors, Wall};
use dream_core::voronoi;
use dream_core::GeomError;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn config() -> Config {
    Config {
        cases: 64,
        rng_seed: RngSeed::Fixed(14),
        failure_persistence: None,
        ..Config::default()
    }
}

/// The lattice step and the box whose edges it hits: robots sit on the edges and on each other.
const STEP: f64 = 0.25;
const BOX: [f64; 4] = [-2.0, 2.0, -1.25, 1.25];

fn arena(scale: f64) -> Arena {
    Arena::new(BOX[0] * scale, BOX[1] * scale, BOX[2] * scale, BOX[3] * scale).unwrap()
}

/// Robots on the lattice (coincident, on the edges) or anywhere in BOX widened by half its size
/// each way, times a scale of 1e-100 to 1e99 (the Voronoi limit is 1e100); returns the
/// positions and the scale.
fn swarm(max_n: usize) -> impl Strategy<Value = (Vec<Vec2>, f64)> {
    let lattice = prop::collection::vec((-10..=10_i32, -6..=6_i32), 0..=max_n).prop_map(|cells| {
        cells
            .into_iter()
            .map(|(i, j)| [i as f64 * STEP, j as f64 * STEP])
            .collect()
    });
    let anywhere = prop::collection::vec((-4.0..=4.0_f64, -2.5..=2.5_f64), 0..=max_n)
        .prop_map(|points| points.into_iter().map(|(x, y)| [x, y]).collect());
    let scale = prop::sample::select(vec![1e-100, 1e-6, 1e-3, 1.0, 1e3, 1e6, 1e99]);
    (prop_oneof![lattice, anywhere], scale).prop_map(|(points, scale): (Vec<Vec2>, f64)| {
        (
            points.into_iter().map(|p| [p[0] * scale, p[1] * scale]).collect(),
            scale,
        )
    })
}

/// The lattice or box points of [`swarm`] at unit scale, for kernels whose parameters are metres.
fn unscaled(points: &[Vec2], scale: f64) -> Vec<Vec2> {
    points.iter().map(|p| [p[0] / scale, p[1] / scale]).collect()
}

fn distance(a: Vec2, b: Vec2) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Indices of the first robot at each distinct position.
fn distinct(points: &[Vec2]) -> Vec<usize> {
    (0..points.len())
        .filter(|&i| !points[..i].contains(&points[i]))
        .collect()
}

fn gritsbot_wheels() -> Wheels {
    Wheels::new(0.016, 0.105, 12.5).unwrap()
}

proptest! {
    #![proptest_config(config())]

    /// Issue 14: a disc larger than the arena, up to f64::MAX, clips nothing: the cells of
    /// distinct robots tile the arena with finite centroids.
    #[test]
    fn voronoi_cells_with_a_covering_radius_tile_the_arena(
        (points, scale) in swarm(12),
        radius in prop::sample::select(vec![20.0, 1e10, 1e20, 1e50, 1e300, f64::MAX]),
        resolution in prop::sample::select(vec![3_usize, 8, 64]),
    ) {
        // Robots are within 7.1 box units of every corner; a polygon of radius r contains the
        // disc of r / 2, so 20 units cover the box.
        let bounds = arena(scale);
        let radius = (radius * scale).min(f64::MAX);
        let cells = voronoi::voronoi_cells(&points, radius, &bounds, None, resolution, true).unwrap();
        prop_assert!(cells.centroids.as_flattened().iter().all(|v| v.is_finite()));
        prop_assert!(cells.areas.iter().all(|a| a.is_finite() && *a >= 0.0));
        if !points.is_empty() {
            let total: f64 = distinct(&points).iter().map(|&i| cells.areas[i]).sum();
            let want = (bounds.xmax - bounds.xmin) * (bounds.ymax - bounds.ymin);
            prop_assert!((total - want).abs() <= 1e-9 * want, "areas sum to {total}, not {want}");
        }
    }

    /// Every cell lies in the arena and in its robot's disc, and every vertex is at least as
    /// close to its robot as to any other distinct robot: cells do not overlap.
    #[test]
    fn voronoi_cells_lie_in_the_arena_and_do_not_overlap(
        (points, scale) in swarm(12),
        radius in prop::sample::select(vec![0.1, 0.5, 1.0, 3.0]),
        resolution in prop::sample::select(vec![3_usize, 5, 16, 64]),
    ) {
        let (bounds, radius, tol) = (arena(scale), radius * scale, 1e-9 * scale);
        let cells = voronoi::voronoi_cells(&points, radius, &bounds, None, resolution, true).unwrap();
        prop_assert_eq!(cells.offsets.len(), points.len() + 1);
        for (i, &p) in points.iter().enumerate() {
            let polygon = &cells.vertices[cells.offsets[i] as usize..cells.offsets[i + 1] as usize];
            prop_assert!(cells.centroids[i].iter().all(|v| v.is_finite()));
            for &v in polygon {
                prop_assert!(bounds.xmin - tol <= v[0] && v[0] <= bounds.xmax + tol);
                prop_assert!(bounds.ymin - tol <= v[1] && v[1] <= bounds.ymax + tol);
                prop_assert!(distance(v, p) <= radius + tol);
                for &q in points.iter().filter(|&&q| q != p) {
                    prop_assert!(distance(v, p) <= distance(v, q) + tol, "vertex {v:?} of {p:?} is nearer {q:?}");
                }
            }
            // One robot's cell from what it knows is its row of the whole swarm's cells.
            let others: Vec<Vec2> = points.iter().enumerate().filter(|&(j, _)| j != i).map(|(_, &q)| q).collect();
            let alone = voronoi::voronoi_cell(p, &others, &[], radius, &bounds, resolution).unwrap();
            let (area, _) = voronoi::area_centroid(&alone, p);
            prop_assert!((area - cells.areas[i]).abs() <= 1e-12 * (1.0 + cells.areas[i]).max(scale * scale));
        }
    }

    /// Neighbours within a radius are symmetric and match the brute force, at any scale.
    #[test]
    fn neighbours_are_symmetric_and_match_brute_force(
        (points, scale) in swarm(20),
        radius in prop::sample::select(vec![0.0, 0.25, 1.0, 3.0, 1e6, 1e300]),
    ) {
        let radius = (radius * scale).min(f64::MAX);
        let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|p| (p[0], p[1])).unzip();
        let csr = neighbours::within(&xs, &ys, radius, None, None, None).unwrap();
        let n = points.len();
        let row = |i: usize| &csr.indices[csr.indptr[i] as usize..csr.indptr[i + 1] as usize];
        for i in 0..n {
            let want: Vec<i64> = (0..n)
                .filter(|&j| {
                    let (dx, dy) = (xs[j] - xs[i], ys[j] - ys[i]);
                    j != i && (dx * dx + dy * dy).sqrt() <= radius
                })
                .map(|j| j as i64)
                .collect();
            prop_assert_eq!(row(i), want.as_slice());
            for &j in row(i) {
                prop_assert!(row(j as usize).contains(&(i as i64)));
            }
        }
        prop_assert!(csr.distances.iter().all(|d| d.is_finite()));
    }

    /// What robots see all around and hear matches the brute force, at any scale: each row by
    /// increasing id, and the rows asked for alone as among all.
    #[test]
    fn perceive_matches_brute_force(
        (points, scale) in swarm(40),
        sight in prop::sample::select(vec![None, Some(0.0), Some(0.25), Some(1.0), Some(1e300)]),
        radio in prop::sample::select(vec![None, Some(0.0), Some(0.5), Some(3.0)]),
    ) {
        let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|p| (p[0], p[1])).unzip();
        let n = points.len();
        let talking: Vec<bool> = (0..n).map(|j| j % 3 != 0).collect();
        let sight = sight.map(|range: f64| perceive::Sight {
            range: (range * scale).min(f64::MAX),
            fov: 2.0 * PI,
            direction: 0.0,
            bearings: false,
        });
        let radio = radio.map(|range: f64| perceive::Radio {
            range: (range * scale).min(f64::MAX),
            talking: &talking[..],
            summed: None,
            loss: None,
        });
        let rows: Vec<i64> = (0..n as i64).collect();
        let headings = vec![0.0; n];
        let (seen, heard) = perceive::perceive(&xs, &ys, &headings, &rows, sight, radio, &[]).unwrap();
        let within = |i: usize, j: usize, range: f64| {
            let (dx, dy) = (xs[j] - xs[i], ys[j] - ys[i]);
            j != i && (dx * dx + dy * dy).sqrt() <= range
        };
        for i in 0..n {
            let row = |p: &perceive::Perceived| p.ids[p.offsets[i] as usize..p.offsets[i + 1] as usize].to_vec();
            let want_seen: Vec<i64> = match sight {
                Some(s) => (0..n).filter(|&j| within(i, j, s.range)).map(|j| j as i64).collect(),
                None => Vec::new(),
            };
            let want_heard: Vec<i64> = match radio {
                Some(r) => (0..n).filter(|&j| within(i, j, r.range) && talking[j]).map(|j| j as i64).collect(),
                None => Vec::new(),
            };
            prop_assert_eq!(row(&seen), want_seen);
            prop_assert_eq!(row(&heard), want_heard);
            let (alone_seen, alone_heard) =
                perceive::perceive(&xs, &ys, &headings, &[i as i64], sight, radio, &[]).unwrap();
            prop_assert_eq!(alone_seen.ids, row(&seen));
            prop_assert_eq!(alone_heard.ids, row(&heard));
        }
        // Summed instead of listed: each row's listed values added in increasing id from +0.0.
        if let Some(radio) = radio {
            let summed: &[&[f64]] = &[&xs];
            let summing = perceive::Radio {
                summed: Some(summed),
                ..radio
            };
            let (_, sums) = perceive::perceive(&xs, &ys, &headings, &rows, sight, Some(summing), &[]).unwrap();
            prop_assert_eq!(&sums.offsets, &heard.offsets);
            for i in 0..n {
                let listed = &heard.ids[heard.offsets[i] as usize..heard.offsets[i + 1] as usize];
                let want = listed.iter().fold(0.0, |sum: f64, &j| sum + xs[j as usize]);
                prop_assert_eq!(sums.summed[0][i].to_bits(), want.to_bits());
            }
        }
    }

    /// HRVO picks zero, a grid candidate or the preferred velocity shortened to v_max, keeps
    /// `position + v` strictly inside the bounds, and never exceeds v_max.
    #[test]
    fn hrvo_batch_stays_within_v_max_and_picks_a_candidate(
        (points, scale) in swarm(10),
        seeds in prop::collection::vec((-0.3..0.3_f64, -0.3..0.3_f64, -1e6..1e6_f64, -1e6..1e6_f64), 10),
        v_max in prop::sample::select(vec![0.0, 0.05, 0.2, 1.0]),
        with_bounds in any::<bool>(),
    ) {
        let n = points.len();
        let velocities: Vec<Vec2> = seeds[..n].iter().map(|s| [s.0, s.1]).collect();
        let preferred: Vec<Vec2> = seeds[..n].iter().map(|s| [s.2, s.3]).collect();
        let bounds = with_bounds.then(|| arena(1.0));
        let params = HrvoParams { safety: 0.24, v_max, bounds, include_preferred: true };
        let grid = hrvo::candidate_grid(v_max, 20, 10);
        // unit scale: HRVO's safety radius and speeds are in metres
        let positions = unscaled(&points, scale);
        let chosen = hrvo::hrvo_batch(&positions, &velocities, &preferred, None, 1.0, &grid, &params).unwrap();
        for ((v, pref), p) in chosen.iter().zip(&preferred).zip(&positions) {
            let speed = v[0].hypot(v[1]);
            prop_assert!(speed.is_finite() && speed <= v_max * (1.0 + 1e-12));
            let on_grid = grid.contains(v);
            let pref_speed = pref[0].hypot(pref[1]);
            let along_preferred = (speed - pref_speed.min(v_max)).abs() <= 1e-12 * speed
                && (v[0] * pref[1] - v[1] * pref[0]).abs() <= 1e-12 * speed * pref_speed;
            prop_assert!(speed == 0.0 || on_grid || along_preferred, "{v:?} is no candidate");
            if let (Some(b), true) = (bounds, speed > 0.0) {
                let (x, y) = (p[0] + v[0], p[1] + v[1]);
                prop_assert!(b.xmin < x && x < b.xmax && b.ymin < y && y < b.ymax);
            }
        }
    }

    /// A unicycle step is finite, wraps the heading to [-pi, pi] (the float -pi lies above the
    /// real -pi) and moves each robot dt |v| along its heading.
    #[test]
    fn unicycle_step_is_finite_with_wrapped_headings(
        rows in prop::collection::vec((-1e6..1e6_f64, -1e6..1e6_f64, -1e3..1e3_f64, -1e3..1e3_f64, -1e3..1e3_f64), 0..8),
        dt in 1e-6..1.0_f64,
    ) {
        let n = rows.len();
        let mut poses: Vec<f64> = rows.iter().map(|r| r.0).chain(rows.iter().map(|r| r.1)).chain(rows.iter().map(|r| r.2)).collect();
        let before = poses.clone();
        let commands: Vec<f64> = rows.iter().map(|r| r.3).chain(rows.iter().map(|r| r.4)).collect();
        dynamics::unicycle_step(&mut poses, &commands, n, dt).unwrap();
        prop_assert!(poses.iter().all(|v| v.is_finite()));
        for i in 0..n {
            prop_assert!(poses[2 * n + i].abs() <= PI);
            let moved = (poses[i] - before[i]).hypot(poses[n + i] - before[n + i]);
            prop_assert!((moved - dt * commands[i].abs()).abs() <= 1e-9 * (1.0 + before[i].abs().max(before[n + i].abs())));
        }
    }

    /// Actuator limiting keeps v and w within their limits and every wheel within its own.
    #[test]
    fn actuator_limit_keeps_every_wheel_within_its_limit(
        rows in prop::collection::vec((-1e6..1e6_f64, -1e6..1e6_f64), 0..8),
    ) {
        let n = rows.len();
        let mut dxu: Vec<f64> = rows.iter().map(|r| r.0).chain(rows.iter().map(|r| r.1)).collect();
        let wheels = gritsbot_wheels();
        dynamics::actuator_limit(&mut dxu, n, 0.2, 3.636363, &wheels).unwrap();
        for i in 0..n {
            let (v, w) = (dxu[i], dxu[n + i]);
            prop_assert!(v.abs() <= 0.2 && w.abs() <= 3.636363);
            let (left, right) = wheels.speeds(v, w);
            prop_assert!(left.abs().max(right.abs()) <= 12.5 * (1.0 + 1e-12));
        }
    }

    /// Ray readings are a distance within range or -1.
    #[test]
    fn distance_rays_read_within_range_or_minus_one(
        (points, scale) in swarm(8),
        headings in prop::collection::vec(-10.0..10.0_f64, 8),
        walls in prop::collection::vec((-2.0..2.0_f64, -2.0..2.0_f64, -2.0..2.0_f64, -2.0..2.0_f64), 0..4),
        range in prop::sample::select(vec![0.1, 1.2, 5.0]),
    ) {
        let points = unscaled(&points, scale); // the sensor head is in metres
        let n = points.len();
        let poses: Vec<f64> = points.iter().map(|p| p[0]).chain(points.iter().map(|p| p[1])).chain(headings[..n].iter().copied()).collect();
        let walls: Vec<Wall> = walls.iter().map(|w| Wall { a: [w.0, w.1], b: [w.2, w.3] }).collect();
        let rays = (0..7).map(|k| Ray { x: 0.04, y: 0.0, angle: PI * (k as f64 - 3.0) / 3.0 }).collect();
        let sensors = Sensors::new(rays, 0.01, 0.055, range).unwrap();
        let readings = raycast::distance_rays(&poses, n, &walls, &sensors, None).unwrap();
        prop_assert_eq!(readings.len(), 7 * n);
        prop_assert!(readings.iter().all(|&r| r == -1.0 || (0.0..range).contains(&r)));
    }

    /// Each virtual agent puts the bisector max(d - offset, 1 um) from its robot, towards the
    /// obstacle's closest point; a robot gets at most one agent per obstacle.
    #[test]
    fn virtual_agents_put_each_bisector_offset_before_the_obstacle(
        (points, scale) in swarm(10),
        corners in prop::collection::vec((-2.0..1.5_f64, -1.25..0.75_f64, 0.01..0.5_f64, 0.01..0.5_f64), 0..3),
        range in prop::sample::select(vec![0.0, 0.3, 1.0, 1e300]),
        offset in prop::sample::select(vec![0.0, 0.055, 0.2]),
    ) {
        let points = unscaled(&points, scale); // obstacles and offsets are in metres
        let vertices: Vec<Vec2> = corners.iter().flat_map(|&(x, y, w, h)| [[x, y], [x + w, y], [x + w, y + h], [x, y + h]]).collect();
        let offsets: Vec<i64> = (0..=corners.len() as i64).map(|k| 4 * k).collect();
        let obstacles = Obstacles::new(&vertices, &offsets).unwrap();
        let (indptr, agents) = obstacles::virtual_agents(&points, &obstacles, range, offset).unwrap();
        prop_assert_eq!(indptr.len(), points.len() + 1);
        for (i, &p) in points.iter().enumerate() {
            let mine = &agents[indptr[i] as usize..indptr[i + 1] as usize];
            prop_assert!(mine.len() <= obstacles.len());
            let sensed: Vec<Vec2> = (0..obstacles.len())
                .filter_map(|k| obstacles.closest_point(k, p))
                .filter(|&c| distance(c, p) > 0.0 && distance(c, p) <= range)
                .collect();
            prop_assert_eq!(mine.len(), sensed.len());
            for (a, c) in mine.iter().zip(&sensed) {
                prop_assert!(a.iter().all(|v| v.is_finite()));
                let want = (distance(*c, p) - offset).max(1e-6);
                prop_assert!((distance(*a, p) / 2.0 - want).abs() <= 1e-9 * want);
            }
        }
    }

    /// A non-finite value anywhere is an error naming the argument, never a panic.
    #[test]
    fn non_finite_input_is_an_error_naming_the_argument(
        n in 1_usize..6,
        at in any::<prop::sample::Index>(),
        bad in prop::sample::select(vec![f64::NAN, f64::INFINITY, f64::NEG_INFINITY]),
    ) {
        let spoiled = |len: usize| {
            let mut values = vec![0.1; len];
            values[at.index(len)] = bad;
            values
        };
        let named = |result: Result<(), GeomError>, arg: &str| match result {
            Err(GeomError::NonFinite { arg: got, .. }) => got == arg,
            _ => false,
        };
        let good: Vec<Vec2> = (0..n).map(|i| [i as f64, 0.0]).collect();
        let points = |values: Vec<f64>| -> Vec<Vec2> { values.chunks(2).map(|c| [c[0], c[1]]).collect() };
        let bounds = arena(1.0);
        let wheels = gritsbot_wheels();
        prop_assert!(named(dynamics::unicycle_step(&mut spoiled(3 * n), &vec![0.0; 2 * n], n, 0.033), "poses"));
        prop_assert!(named(dynamics::unicycle_step(&mut vec![0.0; 3 * n], &spoiled(2 * n), n, 0.033), "velocities"));
        prop_assert!(named(dynamics::actuator_limit(&mut spoiled(2 * n), n, 0.2, 3.6, &wheels), "dxu"));
        prop_assert!(named(dynamics::dxi_to_dxu(&spoiled(2 * n), &vec![0.0; 3 * n], n, 0.8, 3.0).map(|_| ()), "dxi"));
        prop_assert!(named(voronoi::voronoi_cells(&points(spoiled(2 * n)), 1.0, &bounds, None, 16, true).map(|_| ()), "positions"));
        let grid = hrvo::candidate_grid(0.2, 20, 10);
        let params = HrvoParams { safety: 0.24, v_max: 0.2, bounds: None, include_preferred: true };
        let velocities = vec![[0.0; 2]; n];
        prop_assert!(named(
            hrvo::hrvo_batch(&good, &velocities, &points(spoiled(2 * n)), None, 1.0, &grid, &params).map(|_| ()),
            "preferred"
        ));
        let (xs, ys) = (spoiled(n), vec![0.0; n]);
        prop_assert!(named(neighbours::within(&xs, &ys, 1.0, None, None, None).map(|_| ()), "positions"));
        prop_assert!(named(obstacles::virtual_agents(&points(spoiled(2 * n)), &Obstacles::new(&[], &[0]).unwrap(), 1.0, 0.0).map(|_| ()), "positions"));
    }
}

/// Coordinates beyond 1e100 would overflow the centroid sums: an error naming the argument.
#[test]
fn voronoi_coordinates_beyond_the_limit_are_errors() {
    let beyond = |result: Result<(), GeomError>, name: &str| matches!(result, Err(GeomError::InvalidParameter { arg, got, .. }) if arg == name && got.abs() > 1e100);
    let (near, far) = ([[0.0, 0.0]], [[2e100, 0.0]]);
    let bounds = arena(1.0);
    let wide = Arena::new(-2e100, 1.0, -1.0, 1.0).unwrap();
    assert!(beyond(
        voronoi::voronoi_cells(&far, 1.0, &bounds, None, 16, true).map(|_| ()),
        "positions"
    ));
    assert!(beyond(
        voronoi::voronoi_cells(&near, 1.0, &wide, None, 16, true).map(|_| ()),
        "bounds"
    ));
    assert!(beyond(
        voronoi::voronoi_cells(&near, 1.0, &bounds, Some((&[0, 1], &far)), 16, true).map(|_| ()),
        "virtual"
    ));
    assert!(beyond(
        voronoi::voronoi_cell(far[0], &near, &[], 1.0, &bounds, 16).map(|_| ()),
        "position"
    ));
    assert!(beyond(
        voronoi::voronoi_cell(near[0], &far, &[], 1.0, &bounds, 16).map(|_| ()),
        "others"
    ));
    assert!(beyond(
        voronoi::voronoi_cell(near[0], &[], &far, 1.0, &bounds, 16).map(|_| ()),
        "virtual"
    ));
}

/// Negative or non-finite radii and limits are errors naming the parameter.
#[test]
fn illegal_parameters_are_errors_naming_them() {
    let invalid = |result: Result<(), GeomError>, name: &str| matches!(result, Err(GeomError::InvalidParameter { arg, .. }) if arg == name);
    let bounds = arena(1.0);
    let points = [[0.0, 0.0], [0.5, 0.0]];
    for bad in [-1.0, 0.0, f64::NAN, f64::INFINITY] {
        assert!(invalid(
            voronoi::voronoi_cells(&points, bad, &bounds, None, 16, true).map(|_| ()),
            "radius"
        ));
    }
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(invalid(
            neighbours::within(&[0.0], &[0.0], bad, None, None, None).map(|_| ()),
            "radius"
        ));
        let params = HrvoParams {
            safety: bad,
            v_max: 0.2,
            bounds: None,
            include_preferred: true,
        };
        assert!(invalid(params.validated().map(|_| ()), "safety"));
        assert!(invalid(Sensors::new(Vec::new(), 0.0, 0.05, bad).map(|_| ()), "range"));
        let obstacles = Obstacles::new(&[], &[0]).unwrap();
        assert!(invalid(
            obstacles::virtual_agents(&points, &obstacles, bad, 0.0).map(|_| ()),
            "range"
        ));
    }
    assert!(Arena::new(1.0, -1.0, 0.0, 1.0).is_err() && Arena::new(0.0, 1.0, f64::NAN, 1.0).is_err());
    assert!(invalid(
        dynamics::unicycle_step(&mut [0.0; 3], &[0.0; 2], 1, -0.1),
        "dt"
    ));
}
