//! Counter-based random draws: each number a hash of (seed, stream, step, keys).
//!
//! A robot's noise, a message's loss or a liar's value depends only on who, when and what, never
//! on the order in which the engine asks for it: one robot at a time and the whole swarm at once
//! draw the same numbers. The hash absorbs one 64-bit word at a time, the word times the golden
//! ratio XORed in and SplitMix64's finaliser applied; a draw is uniform in [0, 1), the hash's 53
//! high bits over 2^53. `dream.swarm.draws` names the streams and makes other laws of these (a
//! normal draw is NumPy's Box-Muller of two, the same bits with or without this kernel); the
//! NumPy reference (`dream._reference.draws`) is the definition this kernel follows to the bit.
//!
//! The draws come as a table of `rows x columns`: each key is one word for every draw, one per
//! row (a robot, a message) or one per column (a value of a reading). Words absorbed before the
//! first column key are shared by the row's columns, so they are hashed once a row.

use rayon::prelude::*;

use crate::error::{check_len, try_filled, GeomError, Result};
use crate::parallel::{worth_spreading, TASK_ITEMS};

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;
const M1: u64 = 0xBF58_476D_1CE4_E5B9;
const M2: u64 = 0x94D0_49BB_1331_11EB;

/// One key of a table of draws.
#[derive(Debug, Clone, Copy)]
pub enum Key<'a> {
    /// The same word for every draw.
    All(i64),
    /// Word `r` for the draws of row r.
    Row(&'a [i64]),
    /// Word `j` for the draws of column j.
    Column(&'a [i64]),
}

/// SplitMix64's finaliser.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(M1);
    z = (z ^ (z >> 27)).wrapping_mul(M2);
    z ^ (z >> 31)
}

/// The hash `h` with one more word absorbed (a negative word as its two's complement).
fn absorb(h: u64, word: i64) -> u64 {
    mix(h ^ (word as u64).wrapping_mul(GOLDEN))
}

/// A uniform draw in [0, 1) of a hash.
fn unit(h: u64) -> f64 {
    (h >> 11) as f64 * (1.0 / (1_u64 << 53) as f64)
}

/// The uniform draws of stream `stream` at step `step` for the keys `keys`, a `rows x columns`
/// table in row-major order: draw `(r, j)` hashes `seed`, `stream`, `step` and then each key's
/// word for row r and column j, in order.
///
/// # Errors
/// [`GeomError::LengthMismatch`] for a row key of other than `rows` words or a column key of other
/// than `columns`; [`GeomError::InvalidParameter`] for more draws than a `usize` counts;
/// [`GeomError::OutOfMemory`] where the table cannot be allocated.
pub fn draws(seed: u64, stream: i64, step: i64, keys: &[Key<'_>], rows: usize, columns: usize) -> Result<Vec<f64>> {
    for key in keys {
        match key {
            Key::All(_) => {}
            Key::Row(words) => check_len("row keys", rows, words.len())?,
            Key::Column(words) => check_len("column keys", columns, words.len())?,
        }
    }
    let Some(count) = rows.checked_mul(columns) else {
        return Err(GeomError::InvalidParameter {
            arg: "rows",
            rule: "such that rows x columns draws can be counted",
            got: rows as f64,
        });
    };
    let mut out = try_filled(count, 0.0, "random draws")?;
    if columns == 0 {
        return Ok(out);
    }
    // Words shared by every draw are absorbed once; those shared by a row's columns once a row.
    let shared = keys.iter().take_while(|key| matches!(key, Key::All(_))).count();
    let split = keys
        .iter()
        .position(|key| matches!(key, Key::Column(_)))
        .unwrap_or(keys.len());
    let word = |key: &Key<'_>, r: usize, j: usize| match *key {
        Key::All(word) => word,
        Key::Row(words) => words[r],
        Key::Column(words) => words[j],
    };
    let start = keys[..shared]
        .iter()
        .fold(absorb(absorb(seed, stream), step), |h, key| absorb(h, word(key, 0, 0)));
    let row = |(r, out): (usize, &mut [f64])| {
        let at_row = keys[shared..split]
            .iter()
            .fold(start, |h, key| absorb(h, word(key, r, 0)));
        for (j, value) in out.iter_mut().enumerate() {
            let h = keys[split..].iter().fold(at_row, |h, key| absorb(h, word(key, r, j)));
            *value = unit(h);
        }
    };
    if worth_spreading(out.len(), 3.0) {
        let least = TASK_ITEMS.div_ceil(columns);
        out.par_chunks_mut(columns)
            .enumerate()
            .with_min_len(least)
            .for_each(row);
    } else {
        out.chunks_mut(columns).enumerate().for_each(row);
    }
    Ok(out)
}

/// A radio's losses at one step: the message robot i hears from robot j at distance `d` gets
/// through when the draw of (`stream`, step, i, j) is below `keep * max(1 - per_metre * d, 0)`
/// (the distance not read where `per_metre` is 0: a graph radio may not measure it). The
/// perception and the Voronoi cells of what is heard draw it where they find the message, so no
/// list of the messages is needed to lose some; `dream._reference.draws.delivered` is its NumPy
/// twin, which the engine draws with where it lists the messages itself.
#[derive(Debug, Clone, Copy)]
pub struct Loss {
    /// The hash with seed, stream and step absorbed.
    start: u64,
    keep: f64,
    per_metre: f64,
}

impl Loss {
    /// # Errors
    /// [`GeomError::InvalidParameter`] unless `keep` is within [0, 1] and `per_metre` finite and
    /// >= 0.
    pub fn new(seed: u64, stream: i64, step: i64, keep: f64, per_metre: f64) -> Result<Self> {
        if !(0.0..=1.0).contains(&keep) {
            return Err(GeomError::InvalidParameter {
                arg: "keep",
                rule: "within [0, 1]",
                got: keep,
            });
        }
        if !(per_metre.is_finite() && per_metre >= 0.0) {
            return Err(GeomError::InvalidParameter {
                arg: "per_metre",
                rule: ">= 0",
                got: per_metre,
            });
        }
        Ok(Loss {
            start: absorb(absorb(seed, stream), step),
            keep,
            per_metre,
        })
    }

    /// The hash of hearer `i`'s draws: absorbed once for all its messages.
    #[inline]
    pub fn hearer(&self, i: usize) -> u64 {
        absorb(self.start, i as i64)
    }

    /// Whether the distance is read.
    #[inline]
    fn by_distance(&self) -> bool {
        self.per_metre > 0.0
    }

    /// Whether the message from robot `j` to the hearer of `hearer` (its [`Loss::hearer`]) gets
    /// through, `distance` (m) apart (worked out only where read).
    #[inline]
    pub fn delivered(&self, hearer: u64, j: usize, distance: impl FnOnce() -> f64) -> bool {
        let keep = if self.by_distance() {
            self.keep * (1.0 - self.per_metre * distance()).max(0.0)
        } else {
            self.keep
        };
        unit(absorb(hearer, j as i64)) < keep
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hash of `seed` and `words`, one word at a time: the definition.
    fn hash(seed: u64, words: &[i64]) -> u64 {
        words.iter().fold(seed, |h, &w| absorb(h, w))
    }

    #[test]
    fn splitmix_finaliser_of_known_values() {
        // SplitMix64's first output from state 0 is mix(0 + GOLDEN).
        assert_eq!(mix(GOLDEN), 0xE220_A839_7B1D_CDAF);
        assert_eq!(mix(0), 0);
    }

    #[test]
    fn every_draw_hashes_its_own_words_in_order() {
        let (rows, cols) = ([7_i64, -1, 40], [0_i64, 1, 2, 3]);
        let keys = [Key::All(5), Key::Row(&rows), Key::Column(&cols), Key::All(9)];
        let table = draws(11, 2, 30, &keys, 3, 4).unwrap();
        for (r, &row) in rows.iter().enumerate() {
            for (j, &col) in cols.iter().enumerate() {
                let expected = unit(hash(11, &[2, 30, 5, row, col, 9]));
                assert_eq!(table[r * 4 + j].to_bits(), expected.to_bits());
            }
        }
    }

    #[test]
    fn a_column_key_before_a_row_key() {
        let (rows, cols) = ([3_i64, 4], [8_i64, 9, 10]);
        let table = draws(1, 0, 0, &[Key::Column(&cols), Key::Row(&rows)], 2, 3).unwrap();
        for r in 0..2 {
            for j in 0..3 {
                let expected = unit(hash(1, &[0, 0, cols[j], rows[r]]));
                assert_eq!(table[r * 3 + j].to_bits(), expected.to_bits());
            }
        }
    }

    #[test]
    fn uniform_draws_lie_in_the_unit_interval() {
        let many: Vec<i64> = (0..50_000).collect();
        let u = draws(0, 0, 0, &[Key::Row(&many)], many.len(), 1).unwrap();
        assert!(u.iter().all(|&v| (0.0..1.0).contains(&v)));
        let mean = u.iter().sum::<f64>() / u.len() as f64;
        assert!((mean - 0.5).abs() < 0.01, "mean {mean}");
    }

    #[test]
    fn keys_of_the_wrong_length_are_errors() {
        let three = [1_i64, 2, 3];
        assert!(draws(0, 0, 0, &[Key::Row(&three)], 2, 1).is_err());
        assert!(draws(0, 0, 0, &[Key::Column(&three)], 1, 2).is_err());
        assert_eq!(draws(0, 0, 0, &[Key::Row(&[])], 0, 5).unwrap().len(), 0);
        assert_eq!(draws(0, 0, 0, &[], 4, 0).unwrap().len(), 0);
        assert!(matches!(
            draws(0, 0, 0, &[], usize::MAX, 2),
            Err(GeomError::InvalidParameter { arg: "rows", .. })
        ));
    }

    #[test]
    fn a_loss_draws_the_table_of_its_hearer_and_sender() {
        let (hearers, senders) = ([3_i64, 3, 8, 0], [1_i64, 7, 2, 5]);
        let table = draws(42, 0, 17, &[Key::Row(&hearers), Key::Row(&senders)], 4, 1).unwrap();
        let distances = [0.5, 1.0, 0.1, 3.0];
        for (keep, per_metre) in [(0.7, 0.0), (1.0, 0.4), (0.9, 0.25), (0.0, 0.0)] {
            let loss = Loss::new(42, 0, 17, keep, per_metre).unwrap();
            for e in 0..4 {
                let (i, j) = (hearers[e] as usize, senders[e] as usize);
                let expected = table[e]
                    < keep
                        * if per_metre > 0.0 {
                            (1.0 - per_metre * distances[e]).max(0.0)
                        } else {
                            1.0
                        };
                assert_eq!(loss.delivered(loss.hearer(i), j, || distances[e]), expected);
            }
        }
        // Without loss by distance, the distance is not read (a graph radio may not measure it).
        let loss = Loss::new(42, 0, 17, 1.0, 0.0).unwrap();
        assert!(loss.delivered(loss.hearer(3), 1, || unreachable!()));
        assert!(Loss::new(1, 0, 0, 1.5, 0.0).is_err());
        assert!(Loss::new(1, 0, 0, f64::NAN, 0.0).is_err());
        assert!(Loss::new(1, 0, 0, 0.5, -1.0).is_err());
        assert!(Loss::new(1, 0, 0, 0.5, f64::INFINITY).is_err());
    }
}
