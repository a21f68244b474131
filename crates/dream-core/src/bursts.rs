//! Loss bursts: each radio link a Gilbert-Elliott channel, the links in a burst a sorted array.
//!
//! A link (a receiver and a sender, as one integer) enters a burst with probability `enter` at
//! each message sent over it and leaves it with probability `leave`; every message sent in a
//! burst is lost. The links in a burst are kept as a strictly increasing array: a step's links
//! (sorted, as a swarm's inboxes list them) are looked up by one merge with it, and the array is
//! updated by another, both linear.

use std::borrow::Cow;

use rayon::prelude::*;

use crate::error::{check_len, try_room, GeomError, Result};
use crate::parallel::worth_spreading;

/// Links one task looks up at least.
const TASK_LINKS: usize = 16_384;

/// The messages over `links` at one step, in a burst or not, and the links in a burst after them.
///
/// Message k goes over link `links[k]`; its link was in a burst if it is in `lossy` (strictly
/// increasing); it flips state if `draws[k]` (uniform in [0, 1)) is below `leave` (in a burst) or
/// `enter` (not), and is sent in a burst if its link is in one after the flip. Returns whether
/// each message was sent in a burst, and `lossy` less the links whose burst ended and with those
/// whose burst began. A link with several messages in the step: each flips from the state before
/// the step; the link's burst ends if one of them ends it, begins if one begins it. `links` in any
/// order; sorted (a range radio's inboxes: rows by increasing id, each row by increasing id) they
/// need no sort (a graph radio's come in the graph's order, and are sorted first).
///
/// # Errors
/// [`GeomError::LengthMismatch`] for `draws`; [`GeomError::InvalidParameter`] for a probability
/// outside [0, 1]; [`GeomError::NotIncreasing`] for a `lossy` that is not strictly increasing;
/// [`GeomError::OutOfMemory`].
pub fn bursts(lossy: &[i64], links: &[i64], draws: &[f64], enter: f64, leave: f64) -> Result<(Vec<bool>, Vec<i64>)> {
    check_len("draws", links.len(), draws.len())?;
    for (arg, p) in [("enter", enter), ("leave", leave)] {
        if !(0.0..=1.0).contains(&p) {
            return Err(GeomError::InvalidParameter {
                arg,
                rule: "a probability in [0, 1]",
                got: p,
            });
        }
    }
    if let Some(k) = lossy.windows(2).position(|pair| pair[0] >= pair[1]) {
        return Err(GeomError::NotIncreasing {
            arg: "lossy",
            index: k + 1,
        });
    }
    // The messages in order of their links: as given when sorted, else through a sorted order.
    let order: Option<Vec<usize>> = (!links.is_sorted()).then(|| {
        let mut order: Vec<usize> = (0..links.len()).collect();
        order.par_sort_by_key(|&k| links[k]);
        order
    });
    let keys: Cow<'_, [i64]> = match &order {
        None => Cow::Borrowed(links),
        Some(order) => Cow::Owned(order.iter().map(|&k| links[k]).collect()),
    };
    let was = in_sorted(lossy, &keys);
    let mut now = vec![false; links.len()];
    let (mut ended, mut began) = (Vec::new(), Vec::new());
    for (s, (&inside, &link)) in was.iter().zip(keys.iter()).enumerate() {
        let k = order.as_ref().map_or(s, |order| order[s]);
        let flips = draws[k] < if inside { leave } else { enter };
        now[k] = inside != flips;
        if flips && inside {
            ended.push(link);
        } else if flips && began.last() != Some(&link) {
            began.push(link);
        }
    }
    ended.dedup();
    Ok((now, merged(lossy, &ended, &began)?))
}

/// Whether each of `keys` (increasing) is in `set` (strictly increasing): one merge, in pieces
/// on every core for many keys (each piece starting where its first key would be in `set`).
fn in_sorted(set: &[i64], keys: &[i64]) -> Vec<bool> {
    let piece = |keys: &[i64], found: &mut [bool]| {
        let mut i = set.partition_point(|&v| v < keys.first().copied().unwrap_or(i64::MIN));
        for (key, found) in keys.iter().zip(found) {
            while i < set.len() && set[i] < *key {
                i += 1;
            }
            *found = i < set.len() && set[i] == *key;
        }
    };
    let mut found = vec![false; keys.len()];
    if worth_spreading(keys.len() + set.len(), 2.0) {
        keys.par_chunks(TASK_LINKS)
            .zip(found.par_chunks_mut(TASK_LINKS))
            .for_each(|(keys, found)| piece(keys, found));
    } else {
        piece(keys, &mut found);
    }
    found
}

/// `set` (strictly increasing) without `removed` (increasing, all in `set`) and with `added`
/// (strictly increasing, none in `set`), strictly increasing.
fn merged(set: &[i64], removed: &[i64], added: &[i64]) -> Result<Vec<i64>> {
    let mut out = Vec::new();
    try_room(&mut out, set.len() - removed.len() + added.len(), "links in a burst")?;
    let (mut r, mut a) = (0, 0);
    for &link in set {
        if r < removed.len() && removed[r] == link {
            r += 1;
            continue;
        }
        while a < added.len() && added[a] < link {
            out.push(added[a]);
            a += 1;
        }
        out.push(link);
    }
    out.extend_from_slice(&added[a..]);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    /// The definition on a set, message by message from the state before the step.
    fn on_a_set(lossy: &BTreeSet<i64>, links: &[i64], draws: &[f64], enter: f64, leave: f64) -> (Vec<bool>, Vec<i64>) {
        let was: Vec<bool> = links.iter().map(|l| lossy.contains(l)).collect();
        let now: Vec<bool> = (0..links.len())
            .map(|k| was[k] != (draws[k] < if was[k] { leave } else { enter }))
            .collect();
        let mut after = lossy.clone();
        for k in 0..links.len() {
            if was[k] && !now[k] {
                after.remove(&links[k]);
            }
        }
        for k in 0..links.len() {
            if now[k] && !was[k] {
                after.insert(links[k]);
            }
        }
        (now, after.into_iter().collect())
    }

    /// A small deterministic generator (no dependency for a test).
    fn lcg(state: &mut u64) -> u64 {
        *state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        *state >> 33
    }

    #[test]
    fn bursts_follow_a_set_of_links_sorted_or_not() {
        let mut state = 7;
        for sorted in [true, false] {
            let mut lossy: BTreeSet<i64> = BTreeSet::new();
            let mut array: Vec<i64> = Vec::new();
            for _ in 0..40 {
                let count = (lcg(&mut state) % 3000) as usize;
                let mut links: Vec<i64> = (0..count).map(|_| (lcg(&mut state) % 5000) as i64 - 100).collect();
                if sorted {
                    links.sort_unstable();
                }
                let draws: Vec<f64> = (0..count)
                    .map(|_| lcg(&mut state) as f64 / (1_u64 << 31) as f64)
                    .collect();
                let (now, after) = bursts(&array, &links, &draws, 0.2, 0.4).unwrap();
                let (expected_now, expected_after) = on_a_set(&lossy, &links, &draws, 0.2, 0.4);
                assert_eq!(now, expected_now);
                assert_eq!(after, expected_after);
                lossy = after.iter().copied().collect();
                array = after;
            }
            assert!(!array.is_empty());
        }
    }

    #[test]
    fn bad_input_is_named() {
        assert!(matches!(
            bursts(&[1, 3, 2], &[], &[], 0.1, 0.1),
            Err(GeomError::NotIncreasing { arg: "lossy", index: 2 })
        ));
        assert!(bursts(&[i64::MIN, i64::MAX], &[i64::MAX], &[0.5], 0.1, 0.1).is_ok());
        assert!(matches!(
            bursts(&[], &[1], &[], 0.1, 0.1),
            Err(GeomError::LengthMismatch { arg: "draws", .. })
        ));
        assert!(matches!(
            bursts(&[], &[], &[], 1.5, 0.1),
            Err(GeomError::InvalidParameter { arg: "enter", .. })
        ));
        assert_eq!(bursts(&[], &[], &[], 0.1, 0.1).unwrap(), (vec![], vec![]));
    }
}
