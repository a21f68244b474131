//! Criterion benchmarks of the core kernels on swarms with ~10 robots within 1 m of each: the
//! easy jittered lattice and, for neighbours and HRVO, uniformly random positions (some robots
//! closer than the safety radius), as in `benches/scenes.py`.
//!
//!     cargo bench -p dream-core

use std::f64::consts::PI;
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use dream_core::dynamics::{self, Wheels};
use dream_core::geom::Arena;
use dream_core::geom::Vec2;
use dream_core::hrvo::{self, HrvoParams};
use dream_core::{neighbours, voronoi};

/// `n` robots on a jittered lattice with ~10 within 1 m of each (a deterministic jitter).
fn swarm(n: usize) -> (Vec<f64>, Vec<f64>, f64) {
    let spacing = (PI / 10.0).sqrt();
    let columns = (n as f64).sqrt().ceil() as usize;
    let jitter = |i: usize, k: f64| ((i as f64 * k).fract() - 0.5) * spacing / 2.0;
    let xs = (0..n)
        .map(|i| (i / columns) as f64 * spacing + jitter(i, 0.754_877_666))
        .collect();
    let ys = (0..n)
        .map(|i| (i % columns) as f64 * spacing + jitter(i, 0.569_840_290))
        .collect();
    (xs, ys, columns as f64 * spacing)
}

/// `n` robots uniformly at random (the xorshift sequence from `seed`, not 0) in the square that
/// puts ~10 within 1 m of each.
fn uniform(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let side = (n as f64 * PI / 10.0).sqrt();
    let mut state = seed;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1_u64 << 53) as f64 * side
    };
    (0..n).map(|_| (next(), next())).unzip()
}

/// Both scenes by name.
fn scenes(n: usize) -> [(&'static str, Vec<f64>, Vec<f64>); 2] {
    let (xs, ys, _) = swarm(n);
    let (uxs, uys) = uniform(n, 0x9e37_79b9_7f4a_7c15);
    [("lattice", xs, ys), ("uniform", uxs, uys)]
}

fn points(xs: &[f64], ys: &[f64]) -> Vec<Vec2> {
    xs.iter().zip(ys).map(|(&x, &y)| [x, y]).collect()
}

fn bench_neighbours(c: &mut Criterion) {
    let mut group = c.benchmark_group("neighbours");
    for n in [1_000, 10_000, 100_000] {
        for (scene, xs, ys) in scenes(n) {
            group.bench_with_input(BenchmarkId::new(scene, format!("n={n}")), &n, |b, _| {
                b.iter(|| neighbours::within(black_box(&xs), black_box(&ys), 1.0, None, None, None).unwrap())
            });
        }
    }
    group.finish();
}

/// The original candidate grid and the experiments' HRVO parameters, for both HRVO benches.
fn hrvo_setup() -> (Vec<Vec2>, HrvoParams) {
    let params = HrvoParams {
        safety: 0.24,
        v_max: 0.2,
        bounds: None,
        include_preferred: true,
    };
    (hrvo::candidate_grid(0.2, 20, 10), params)
}

fn bench_hrvo(c: &mut Criterion) {
    let mut group = c.benchmark_group("hrvo");
    let (grid, params) = hrvo_setup();
    for n in [100, 1_000, 10_000] {
        let v: Vec<Vec2> = (0..n)
            .map(|i| [0.1 * (i as f64).sin(), 0.1 * (i as f64).cos()])
            .collect();
        let pref: Vec<Vec2> = (0..n)
            .map(|i| [0.2 * (3.0 * i as f64).cos(), 0.2 * (3.0 * i as f64).sin()])
            .collect();
        for (scene, xs, ys) in scenes(n) {
            let p = points(&xs, &ys);
            group.bench_with_input(BenchmarkId::new(scene, format!("n={n}")), &n, |b, _| {
                b.iter(|| hrvo::hrvo_batch(black_box(&p), &v, &pref, None, 1.0, &grid, &params).unwrap())
            });
        }
    }
    group.finish();
}

/// HRVO on 32 different small uniform swarms in turn, one call each per iteration. One swarm
/// called again and again lets the branch predictor learn its branches by heart (n = 100 then
/// looks twice as fast as in a simulation, whose swarm moves between calls).
fn bench_hrvo_varied(c: &mut Criterion) {
    let (grid, params) = hrvo_setup();
    let n = 100;
    let swarms: Vec<[Vec<Vec2>; 3]> = (1..=32_u64)
        .map(|seed| {
            let (xs, ys) = uniform(n, seed.wrapping_mul(0x9e37_79b9_7f4a_7c15));
            let turn = seed as f64;
            let v = (0..n)
                .map(|i| [0.1 * (i as f64 + turn).sin(), 0.1 * (i as f64 + turn).cos()])
                .collect();
            let pref = (0..n)
                .map(|i| [0.2 * (3.0 * i as f64 + turn).cos(), 0.2 * (3.0 * i as f64 + turn).sin()])
                .collect();
            [points(&xs, &ys), v, pref]
        })
        .collect();
    c.bench_function("hrvo_varied/uniform/n=100, 32 swarms", |b| {
        b.iter(|| {
            for [p, v, pref] in &swarms {
                black_box(hrvo::hrvo_batch(black_box(p), v, pref, None, 1.0, &grid, &params).unwrap());
            }
        })
    });
}

fn bench_voronoi(c: &mut Criterion) {
    let mut group = c.benchmark_group("voronoi");
    for n in [100, 1_000, 10_000] {
        let (xs, ys, side) = swarm(n);
        let p = points(&xs, &ys);
        let arena = Arena::new(-1.0, side, -1.0, side).unwrap();
        group.bench_with_input(BenchmarkId::new("n", n), &n, |b, _| {
            b.iter(|| voronoi::voronoi_cells(black_box(&p), 0.5, &arena, None, 64, true).unwrap())
        });
    }
    group.finish();
}

fn bench_dynamics(c: &mut Criterion) {
    let mut group = c.benchmark_group("dynamics");
    let wheels = Wheels::new(0.016, 0.105, 12.5).unwrap();
    for n in [100, 1_000, 10_000] {
        let (xs, ys, side) = swarm(n);
        let poses: Vec<f64> = xs
            .iter()
            .chain(&ys)
            .copied()
            .chain((0..n).map(|i| i as f64 % 6.0 - 3.0))
            .collect();
        let commands: Vec<f64> = (0..2 * n).map(|i| 0.3 * ((i as f64) * 0.37).sin()).collect();
        let arena = Arena::new(-1.0, side, -1.0, side).unwrap();
        group.bench_with_input(BenchmarkId::new("n", n), &n, |b, _| {
            b.iter(|| {
                let counts = dynamics::validate(black_box(&poses), &commands, n, &arena, 0.11, &wheels).unwrap();
                let mut next = poses.clone();
                dynamics::unicycle_step(&mut next, &commands, n, 0.033).unwrap();
                (counts, next)
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    bench_neighbours,
    bench_hrvo,
    bench_hrvo_varied,
    bench_voronoi,
    bench_dynamics
);
criterion_main!(benches);
