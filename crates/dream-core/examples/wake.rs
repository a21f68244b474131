//! What spreading a small loop over the threads costs when the pool has fallen asleep, as it has
//! between two kernel calls of a run (Python works in between): the median and 90th-percentile
//! time of a check of `n` values (is any NaN?) on the calling thread and on rayon's pool, each
//! call after a pause. The figure behind `parallel::worth_spreading`'s threshold.
//!
//! Run: `cargo run --release -p dream-core --example wake` (`RAYON_NUM_THREADS` sets the pool).

use std::time::{Duration, Instant};

use rayon::prelude::*;

const CALLS: usize = 2000;
const PAUSE: Duration = Duration::from_micros(200);

fn main() {
    let values: Vec<f64> = (0..1 << 20).map(|i| f64::from(i) * 0.5).collect();
    println!("threads: {}", rayon::current_num_threads());
    println!("| values | one thread (us) | the pool (us), median | the pool, 90th percentile |");
    println!("|---|---|---|---|");
    for n in [4096, 65_536, 262_144, 1 << 20] {
        let slice = &values[..n];
        let (mut alone, mut spread) = (Vec::with_capacity(CALLS), Vec::with_capacity(CALLS));
        for _ in 0..CALLS {
            std::thread::sleep(PAUSE);
            let start = Instant::now();
            std::hint::black_box(slice.iter().fold(false, |bad, x| bad | !x.is_finite()));
            alone.push(start.elapsed());
            std::thread::sleep(PAUSE);
            let start = Instant::now();
            let chunk = n.div_ceil(rayon::current_num_threads());
            std::hint::black_box(
                slice
                    .par_chunks(chunk)
                    .any(|c| c.iter().fold(false, |bad, x| bad | !x.is_finite())),
            );
            spread.push(start.elapsed());
        }
        alone.sort();
        spread.sort();
        let us = |d: Duration| d.as_secs_f64() * 1e6;
        println!(
            "| {n} | {:.1} | {:.1} | {:.1} |",
            us(alone[CALLS / 2]),
            us(spread[CALLS / 2]),
            us(spread[CALLS * 9 / 10])
        );
    }
}
