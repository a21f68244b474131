//! Hybrid Reciprocal Velocity Obstacles with candidate sampling.
//!
//! For robot A (previous velocity `v_A`, preferred `v_pref`) and each neighbour B at distance d
//! in unit direction u (from A towards B; (1, 0) for a co-located B) moving with `v_B`, with
//! safety radius r:
//! - the cone has half-angle phi with `sin phi = r / max(d, r)`; its left edge is u turned by
//!   +phi, its right edge u turned by -phi (rotations by `sin phi` and `sqrt(1 - sin^2 phi)`:
//!   no trigonometry, so Rust and NumPy agree to the bit);
//! - the VO's apex is `v_B`, the RVO's `(v_A + v_B) / 2`; HRVO keeps the RVO edge on the side
//!   `v_A` is closer to and the VO edge on the other (both VO edges on a tie, as the original;
//!   distances within [`TIE`] of each other, relative to `|v_A - apex|`, are a tie, so that
//!   symmetric scenes are decided by geometry and not by rounding);
//! - a velocity v is forbidden by B when it is strictly inside both half-planes:
//!   `left x (v - apex_left) < 0` and `right x (v - apex_right) > 0`.
//!
//! The chosen velocity is the candidate closest to `v_pref` (first in candidate order on ties)
//! that no neighbour forbids and, with bounds, keeps `position + v` strictly inside; zero if
//! none does. A free preferred velocity is taken after one test per neighbour. Otherwise the
//! candidates, grouped once per call into small clusters of consecutive ones (a few speeds along
//! one direction of the polar grid), are searched cluster by cluster, nearest clusters first: a
//! cluster that cannot beat the best candidate so far is passed over, and one that a single cone
//! surely forbids whole (its edge tests at the cluster's centre clear the cluster's radius plus a
//! bound on rounding) costs one test. Each candidate that is tested goes through exactly the
//! reference's arithmetic, so the answer is the reference's to the bit.

use std::f64::consts::TAU;

use rayon::prelude::*;

use crate::csr::{check_csr, check_offsets};
use crate::error::{check_finite, check_len, GeomError, Result};
use crate::geom::{Arena, Vec2};
use crate::neighbours::Near;
use crate::parallel::{first_where, map_range};

/// Rows below this count run on one thread.
const PARALLEL_ROBOTS: usize = 256;
/// Distance rings the candidates' clusters are sorted into (see `choose`): with ~60 clusters,
/// 12 rings cost fewer instructions than 6 or 24 (callgrind, benches/scenes.py).
const BANDS: usize = 12;
/// Relative tolerance under which `v_A` is equally close to both RVO edges.
pub const TIE: f64 = 1e-9;

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
                return Err(GeomError::InvalidParameter {
                    arg,
                    rule: ">= 0",
                    got: value,
                });
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
        Self {
            direction: [towards.cos(), towards.sin()],
            distance,
            velocity: [vx, vy],
        }
    }

    /// The neighbour at `offset` (its position minus the robot's) moving with `velocity`.
    pub fn from_offset(offset: Vec2, velocity: Vec2) -> Self {
        Self::at(offset, (offset[0] * offset[0] + offset[1] * offset[1]).sqrt(), velocity)
    }

    /// From a detection `[distance, dx, dy, vx, vy]` that gives the detected robot's offset (its
    /// position less the sensing robot's) with its distance: the direction is the offset over
    /// the distance ((1, 0) at distance 0), two divisions where an angle costs a sine and a cosine.
    pub fn from_sensed(detection: [f64; 5]) -> Self {
        let [distance, dx, dy, vx, vy] = detection;
        Self::at([dx, dy], distance, [vx, vy])
    }

    /// [`Neighbour::from_offset`] with the offset's length already known.
    fn at(offset: Vec2, distance: f64, velocity: Vec2) -> Self {
        let direction = if distance > 0.0 {
            [offset[0] / distance, offset[1] / distance]
        } else {
            [1.0, 0.0]
        };
        Self {
            direction,
            distance,
            velocity,
        }
    }
}

/// The original polar sampling without duplicates: zero first, then for each of the
/// `n_angles` angles in [0, 2 pi) (the duplicate 2 pi dropped) every non-zero speed of
/// `n_speeds` in [0, v_max].
pub fn candidate_grid(v_max: f64, n_angles: usize, n_speeds: usize) -> Vec<Vec2> {
    let angle_step = if n_angles > 1 { TAU / (n_angles - 1) as f64 } else { 0.0 };
    let speed_step = if n_speeds > 1 {
        v_max / (n_speeds - 1) as f64
    } else {
        0.0
    };
    let distinct_angles = if n_angles > 1 { n_angles - 1 } else { n_angles };
    let mut grid = vec![[0.0, 0.0]];
    for a in 0..distinct_angles {
        let angle = a as f64 * angle_step;
        for s in 1..n_speeds {
            // linspace pins its last sample to the end point exactly.
            let speed = if s == n_speeds - 1 {
                v_max
            } else {
                s as f64 * speed_step
            };
            grid.push([speed * angle.cos(), speed * angle.sin()]);
        }
    }
    grid
}

fn cross(a: Vec2, b: Vec2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// `a` if `pick`, else `b`, without a branch: which side of a cone `v_A` is nearer to is a coin
/// flip, and a missed branch cost more than the rest of the cone (8 % of a whole call). Plain
/// x86-64 has no branch-free select of floats, so LLVM turns any select it recognises into a
/// branch; `black_box` hides that the mask is one, so the bits are blended as written.
fn select(pick: bool, a: Vec2, b: Vec2) -> Vec2 {
    let mask = std::hint::black_box(u64::from(pick).wrapping_neg());
    let blend = |a: f64, b: f64| f64::from_bits((a.to_bits() & mask) | (b.to_bits() & !mask));
    [blend(a[0], b[0]), blend(a[1], b[1])]
}

/// The two half-planes of one neighbour's HRVO: edge directions and the apexes they pass through.
#[derive(Debug, Clone, Copy)]
struct Cone {
    left: Vec2,
    left_apex: Vec2,
    right: Vec2,
    right_apex: Vec2,
}

impl Cone {
    // Inlined into the neighbour search's loop, which then overlaps one cone's divisions and
    // square roots with the next neighbour's (2 % of a call).
    #[inline(always)]
    fn new(velocity: Vec2, b: &Neighbour, safety: f64) -> Self {
        let sin = if safety > 0.0 {
            safety / b.distance.max(safety)
        } else {
            0.0
        };
        let cos = (1.0 - sin * sin).sqrt();
        let [ux, uy] = b.direction;
        let left = [ux * cos - uy * sin, ux * sin + uy * cos];
        let right = [ux * cos + uy * sin, uy * cos - ux * sin];
        let vo = b.velocity;
        let rvo = [(velocity[0] + vo[0]) / 2.0, (velocity[1] + vo[1]) / 2.0];
        let from_rvo = [velocity[0] - rvo[0], velocity[1] - rvo[1]];
        let (to_left, to_right) = (cross(left, from_rvo).abs(), cross(right, from_rvo).abs());
        let gap = (to_left - to_right).abs();
        // hypot(a, b) < 2 max(|a|, |b|), so a gap above that bound is no tie and libm's hypot (the
        // reference's) is only called for the rare near-tie; hypot(0, 0) is 0, so not for `v_A`
        // at the apex either (robots and neighbours that stand still).
        let widest = from_rvo[0].abs().max(from_rvo[1].abs());
        let tie = gap <= 2.0 * TIE * widest && (widest == 0.0 || gap <= TIE * from_rvo[0].hypot(from_rvo[1]));
        let left_apex = select(!tie & (to_left < to_right), rvo, vo);
        let right_apex = select(!tie & (to_left > to_right), rvo, vo);
        Cone {
            left,
            left_apex,
            right,
            right_apex,
        }
    }

    /// Strictly right of the left edge and strictly left of the right edge. The differences to
    /// the apexes come first: a candidate on an edge then stays on it, whatever the rounding.
    fn forbids(&self, vx: f64, vy: f64) -> bool {
        let [l0, l1] = self.left;
        let [r0, r1] = self.right;
        let ([la0, la1], [ra0, ra1]) = (self.left_apex, self.right_apex);
        (l0 * (vy - la1) - l1 * (vx - la0) < 0.0) & (r0 * (vy - ra1) - r1 * (vx - ra0) > 0.0)
    }
}

/// Relative slack in the bounds that settle a whole cluster at once: far above the few units
/// in the last place that rounding can move the per-candidate arithmetic.
const SLACK: f64 = 1e-12;
/// Absolute slack for the same bounds, covering subnormal rounding.
const TINY: f64 = 1e-300;
/// Bounds at or above this are not trusted (the per-candidate arithmetic might overflow).
const HUGE: f64 = 1e100;
/// A cluster holds at most this many consecutive candidates ...
const CLUSTER_SIZE: usize = 8;
/// ... within a circle whose half-width is at most this part of the grid's reach.
const CLUSTER_SPAN: f64 = 1.0 / 8.0;

impl Cone {
    /// Whether `forbids` holds for every candidate within `radius` of `centre`: both edge tests
    /// at the centre clear the circle's width plus a bound on the rounding of either evaluation
    /// (`pad` is [`pad`] of the circle).
    fn covers(&self, [cx, cy]: Vec2, pad: f64) -> bool {
        let margin =
            |[e0, e1]: Vec2, [a0, a1]: Vec2| (e0.abs() + e1.abs()) * (pad + SLACK * (a0.abs() + a1.abs())) + TINY;
        let ([l0, l1], [r0, r1]) = (self.left, self.right);
        let ([la0, la1], [ra0, ra1]) = (self.left_apex, self.right_apex);
        let (left, right) = (l0 * (cy - la1) - l1 * (cx - la0), r0 * (cy - ra1) - r1 * (cx - ra0));
        let (to_left, to_right) = (margin(self.left, self.left_apex), margin(self.right, self.right_apex));
        to_left < HUGE && to_right < HUGE && left + to_left < 0.0 && right - to_right > 0.0
    }
}

/// The part of [`Cone::covers`]'s margin that depends on the circle only: its radius, and
/// the rounding of an edge test at any of its points.
fn pad([cx, cy]: Vec2, radius: f64) -> f64 {
    radius * (1.0 + SLACK) + SLACK * (cx.abs() + cy.abs() + 2.0 * radius)
}

/// Consecutive candidates that lie close together, as columns: cluster c holds candidates
/// `starts[c]..starts[c + 1]`, all within `radii[c]` of `(xs[c], ys[c])`, and `pads[c]` is
/// [`pad`] of that circle. In the polar grid a cluster is a few speeds along one direction.
#[derive(Debug, Clone, Default)]
struct Clusters {
    xs: Vec<f64>,
    ys: Vec<f64>,
    radii: Vec<f64>,
    pads: Vec<f64>,
    /// The largest radius.
    widest: f64,
    starts: Vec<usize>,
}

impl Clusters {
    /// Candidate 0 alone when `alone` (the clamped preferred velocity, placed per robot), then
    /// the others grouped greedily in order.
    fn new(xs: &[f64], ys: &[f64], alone: bool) -> Self {
        let mut clusters = Self::default();
        let reach = xs.iter().chain(ys).fold(0.0, |far: f64, v| far.max(v.abs()));
        let mut start = 0;
        let mut bounds = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
        for k in 0..xs.len() {
            let grown = [
                bounds[0].min(xs[k]),
                bounds[1].max(xs[k]),
                bounds[2].min(ys[k]),
                bounds[3].max(ys[k]),
            ];
            let wide = (grown[1] - grown[0]).max(grown[3] - grown[2]) > 2.0 * CLUSTER_SPAN * reach;
            if k > start && ((alone && start == 0) || k - start == CLUSTER_SIZE || wide) {
                clusters.push(xs, ys, start, k);
                start = k;
                bounds = [xs[k], xs[k], ys[k], ys[k]];
            } else {
                bounds = grown;
            }
        }
        if start < xs.len() {
            clusters.push(xs, ys, start, xs.len());
        }
        clusters.starts.push(xs.len());
        clusters
    }

    fn push(&mut self, xs: &[f64], ys: &[f64], start: usize, end: usize) {
        let middle = |v: &[f64]| {
            let (low, high) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
            low + (high - low) / 2.0
        };
        let (cx, cy) = (middle(&xs[start..end]), middle(&ys[start..end]));
        let radius = (start..end).fold(0.0, |r: f64, k| r.max((xs[k] - cx).hypot(ys[k] - cy)));
        self.xs.push(cx);
        self.ys.push(cy);
        self.radii.push(radius);
        self.widest = self.widest.max(radius);
        self.pads.push(pad([cx, cy], radius));
        self.starts.push(start);
    }
}

/// A lower bound on the squared distance, as `choose` computes it, from a point to any
/// candidate within `radius` of a centre at squared distance `squared` (computed as
/// `dx * dx + dy * dy`, or any lower bound of that).
fn lower_bound(squared: f64, radius: f64) -> f64 {
    let gap = (squared.sqrt() * (1.0 - SLACK) - radius * (1.0 + SLACK)).max(0.0);
    (gap * gap * (1.0 - SLACK) - TINY).max(0.0)
}

/// Scratch space reused between robots, so a batch call allocates once per thread.
#[derive(Debug, Clone, Default)]
struct Scratch {
    /// The current robot's cones, filled by the caller of `choose`.
    cones: Vec<Cone>,
    /// The candidates as columns: slot 0 holds the robot's clamped preferred velocity when it is
    /// tried, the grid follows.
    xs: Vec<f64>,
    ys: Vec<f64>,
    /// The candidates' clusters; cluster 0 is slot 0 alone when the preferred velocity is tried.
    clusters: Clusters,
    /// Squared distance of each cluster's centre to the preferred velocity.
    centres: Vec<f64>,
    /// Bit j of `bands[w][band]` is set when cluster `64 w + j` lies in that distance band.
    bands: Vec<[u64; BANDS]>,
    /// The neighbour search's buffer.
    run: Vec<(usize, f64)>,
}

impl Scratch {
    fn new(grid: &[Vec2], params: &HrvoParams) -> Self {
        let slot = usize::from(params.include_preferred);
        let column = |axis: usize| {
            let mut values = vec![0.0; slot];
            values.extend(grid.iter().map(|v| v[axis]));
            values
        };
        let (xs, ys) = (column(0), column(1));
        Self {
            clusters: Clusters::new(&xs, &ys, params.include_preferred),
            xs,
            ys,
            ..Self::default()
        }
    }
}

/// Whether any cone forbids `(x, y)`. The cone that does moves to the front: it usually
/// forbids the next candidates too (the answer does not depend on the cones' order).
fn forbidden(cones: &mut [Cone], x: f64, y: f64) -> bool {
    match cones.iter().position(|c| c.forbids(x, y)) {
        Some(c) => {
            if c > 0 {
                cones.swap(0, c);
            }
            true
        }
        None => false,
    }
}

/// The largest value, at least 0: `max` is exact, so lanes give a sequential fold's answer, and
/// plain arrays of lanes let LLVM use vector instructions.
fn largest(values: &[f64]) -> f64 {
    const LANES: usize = 4;
    let mut lanes = [0.0; LANES];
    let chunks = values.chunks_exact(LANES);
    let rest = chunks.remainder();
    for chunk in chunks {
        for (far, &d) in lanes.iter_mut().zip(chunk) {
            *far = if d > *far { d } else { *far };
        }
    }
    rest.iter()
        .chain(&lanes)
        .fold(0.0, |far, &d| if d > far { d } else { far })
}

/// `x` rounded to the nearest integer, for `0 <= x <= BANDS`: adding 2^52 leaves it in the
/// mantissa's low bits. A band only has to grow with the distance, and this costs two
/// instructions where a saturating float-to-int conversion costs ten on plain x86-64.
fn round_small(x: f64) -> usize {
    const SHIFT: f64 = (1_u64 << 52) as f64;
    ((x + SHIFT).to_bits() & 0xff) as usize
}

/// One robot's HRVO velocity, its cones already in `scratch.cones`.
///
/// Candidate 0 is the clamped preferred velocity when `params.include_preferred`, the grid
/// follows. `position` is only read when `params.bounds` is set. Inputs are trusted finite:
/// the public entry points ([`hrvo_one`], [`hrvo_batch`]) check them.
fn choose(scratch: &mut Scratch, preferred: Vec2, position: Vec2, params: &HrvoParams) -> Vec2 {
    let Scratch {
        cones,
        xs,
        ys,
        clusters,
        centres,
        bands,
        ..
    } = scratch;
    let inside = |vx: f64, vy: f64| {
        params.bounds.is_none_or(|b| {
            let (x, y) = (position[0] + vx, position[1] + vy);
            b.xmin < x && x < b.xmax && b.ymin < y && y < b.ymax
        })
    };
    // The preferred velocity, when within the speed limit, is at distance 0: nothing comes
    // before it, so a free way costs one test per neighbour.
    let [px, py] = preferred;
    let norm = px.hypot(py);
    if params.include_preferred && norm <= params.v_max && inside(px, py) && !forbidden(cones, px, py) {
        return preferred;
    }
    if params.include_preferred {
        [xs[0], ys[0]] = if norm > params.v_max {
            let scale = params.v_max / norm;
            [px * scale, py * scale]
        } else {
            preferred
        };
        (clusters.xs[0], clusters.ys[0]) = (xs[0], ys[0]);
        clusters.pads[0] = pad([xs[0], ys[0]], 0.0);
    }
    // Clusters in rings of their centres' distance, as bit sets, visited ring by ring: a cluster
    // that cannot hold a candidate as near as the best so far is passed over, and the search
    // ends at the first ring that cannot. Ties go to the first candidate, whatever the order.
    centres.clear();
    centres.extend(clusters.xs.iter().zip(&clusters.ys).map(|(&cx, &cy)| {
        let (dx, dy) = (cx - px, cy - py);
        dx * dx + dy * dy
    }));
    let farthest = largest(centres);
    let scale = if farthest > 0.0 {
        (BANDS - 1) as f64 / farthest
    } else {
        0.0
    };
    bands.clear();
    bands.resize(centres.len().div_ceil(64), [0; BANDS]);
    for (chunk, sets) in centres.chunks(64).zip(bands.iter_mut()) {
        for (j, &d) in chunk.iter().enumerate() {
            sets[round_small(d * scale).min(BANDS - 1)] |= 1 << j;
        }
    }
    let mut best: Option<(f64, usize)> = None;
    for band in 0..BANDS {
        // A centre in this ring or a later one has `d * scale` rounded to `band` or more.
        let closest = |bd: f64| lower_bound((band as f64 - 0.5) / scale * (1.0 - SLACK), clusters.widest) > bd;
        if band > 0 && best.is_some_and(|(bd, _)| closest(bd)) {
            break;
        }
        for (w, sets) in bands.iter().enumerate() {
            let mut bits = sets[band];
            while bits != 0 {
                let c = w * 64 + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if best.is_some_and(|(bd, _)| lower_bound(centres[c], clusters.radii[c]) > bd) {
                    continue;
                }
                // The cone that forbade the last candidate often forbids this whole cluster.
                if cones
                    .first()
                    .is_some_and(|cone| cone.covers([clusters.xs[c], clusters.ys[c]], clusters.pads[c]))
                {
                    continue;
                }
                for k in clusters.starts[c]..clusters.starts[c + 1] {
                    let (x, y) = (xs[k], ys[k]);
                    let (dx, dy) = (x - px, y - py);
                    let d = dx * dx + dy * dy;
                    if best.is_some_and(|(bd, bk)| d > bd || (d == bd && k > bk)) {
                        continue;
                    }
                    if inside(x, y) && !forbidden(cones, x, y) {
                        best = Some((d, k));
                    }
                }
            }
        }
    }
    best.map_or([0.0, 0.0], |(_, k)| [xs[k], ys[k]])
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
    check_neighbours(neighbours)?;
    let mut scratch = Scratch::new(grid, &params);
    scratch
        .cones
        .extend(neighbours.iter().map(|b| Cone::new(velocity, b, params.safety)));
    Ok(choose(&mut scratch, preferred, position, &params))
}

/// Fails at the first neighbour with a non-finite value or a negative distance.
fn check_neighbours(neighbours: &[Neighbour]) -> Result<()> {
    let bad = |b: &Neighbour| {
        let values = [b.direction[0], b.direction[1], b.distance, b.velocity[0], b.velocity[1]];
        !values.iter().all(|v| v.is_finite()) || b.distance < 0.0
    };
    // The first bad one, found on every core for many.
    let Some(k) = first_where(neighbours.len(), |k| bad(&neighbours[k])) else {
        return Ok(());
    };
    let b = &neighbours[k];
    if b.distance.is_finite() && b.direction.iter().chain(&b.velocity).all(|v| v.is_finite()) {
        Err(GeomError::InvalidParameter {
            arg: "detection distance",
            rule: ">= 0",
            got: b.distance,
        })
    } else {
        Err(GeomError::NonFinite {
            arg: "detections",
            index: k,
        })
    }
}

/// What movement sensors report of the robots they detect, as columns, one entry a detection
/// (a sensor's columns, read where they lie: a million robots' detections are tens of
/// megabytes, which interleaved into rows, then turned into neighbours, were written twice).
#[derive(Debug, Clone, Copy)]
pub enum Detections<'a> {
    /// `distance, angle, vx, vy`, as in [`Neighbour::from_detection`].
    Polar([&'a [f64]; 4]),
    /// `distance, dx, dy, vx, vy`, as in [`Neighbour::from_sensed`].
    Offsets([&'a [f64]; 5]),
}

impl Detections<'_> {
    fn columns(&self) -> &[&[f64]] {
        match self {
            Detections::Polar(columns) => columns,
            Detections::Offsets(columns) => columns,
        }
    }

    fn len(&self) -> usize {
        self.columns()[0].len()
    }

    /// Detection `e` as the neighbour it describes.
    fn neighbour(&self, e: usize) -> Neighbour {
        match self {
            Detections::Polar(columns) => Neighbour::from_detection(columns.map(|column| column[e])),
            Detections::Offsets(columns) => Neighbour::from_sensed(columns.map(|column| column[e])),
        }
    }

    /// The neighbours they describe, checked, on every core for many (a million robots see
    /// millions of others): the columns as long as each other, and every neighbour valid. An
    /// offset is read only at a distance above 0: every value of the offsets' columns is checked
    /// (a non-finite one named by its place in the rows `(k, 5)` the columns stand for).
    fn neighbours(&self) -> Result<Vec<Neighbour>> {
        let columns = self.columns();
        let n = self.len();
        for column in columns {
            check_len("detections", n, column.len())?;
        }
        if let Detections::Offsets(_) = self {
            let bad = |e: usize| columns.iter().any(|column| !column[e].is_finite());
            if let Some(e) = first_where(n, bad) {
                let c = columns.iter().position(|column| !column[e].is_finite()).unwrap_or(0);
                return Err(GeomError::NonFinite {
                    arg: "detections",
                    index: e * columns.len() + c,
                });
            }
        }
        // A sine and a cosine an angle; two divisions an offset.
        let cost = if let Detections::Polar(_) = self { 20.0 } else { 3.0 };
        let around = map_range(n, cost, |e| self.neighbour(e));
        check_neighbours(&around)?;
        Ok(around)
    }
}

/// HRVO velocities of the robots deciding now, each from its own detections (what its movement
/// sensor reported): row r's are `detections[offsets[r]..offsets[r + 1]]`. Row r gets exactly
/// [`hrvo_one`]'s answer for those detections' neighbours, rows in parallel for a large swarm;
/// with `steer`, only the rows it flags: the others get their preferred velocity as it is (robots
/// driving straight, whose rows a caller would otherwise gather out of every input).
///
/// # Errors
/// Length mismatches, non-finite inputs, negative distances, invalid parameters or offsets.
#[allow(clippy::too_many_arguments)]
pub fn hrvo_rows(
    velocities: &[Vec2],
    preferred: &[Vec2],
    positions: &[Vec2],
    offsets: &[i64],
    detections: Detections<'_>,
    grid: &[Vec2],
    params: &HrvoParams,
    steer: Option<&[bool]>,
) -> Result<Vec<Vec2>> {
    let params = params.validated()?;
    let m = positions.len();
    check_len("velocities", m, velocities.len())?;
    check_len("preferred", m, preferred.len())?;
    check_len("offsets", m + 1, offsets.len())?;
    check_offsets("offsets", offsets, detections.len(), "detections")?;
    check_vec2s("velocities", velocities)?;
    check_vec2s("preferred", preferred)?;
    check_vec2s("positions", positions)?;
    check_vec2s("candidates", grid)?;
    if let Some(steer) = steer {
        check_len("steer", m, steer.len())?;
    }
    let around = detections.neighbours()?;
    let robot = |scratch: &mut Scratch, r: usize| {
        if steer.is_some_and(|steer| !steer[r]) {
            return preferred[r];
        }
        scratch.cones.clear();
        let row = &around[offsets[r] as usize..offsets[r + 1] as usize];
        scratch
            .cones
            .extend(row.iter().map(|b| Cone::new(velocities[r], b, params.safety)));
        choose(scratch, preferred[r], positions[r], &params)
    };
    Ok(for_each_robot(m, Scratch::new(grid, &params), |r| r, robot))
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
        return Err(GeomError::InvalidParameter {
            arg: "radius",
            rule: ">= 0",
            got: radius,
        });
    }
    let scratch = Scratch::new(grid, &params);
    let decide = |scratch: &mut Scratch, i: usize| choose(scratch, preferred[i], positions[i], &params);
    let cone = |i: usize, b: &Neighbour| Cone::new(velocities[i], b, params.safety);
    if let Some((indptr, indices)) = neighbours {
        check_csr(indptr, indices, n)?;
        let robot = |scratch: &mut Scratch, i: usize| {
            let p = positions[i];
            let row = &indices[indptr[i] as usize..indptr[i + 1] as usize];
            scratch.cones.clear();
            scratch.cones.extend(row.iter().map(|&j| {
                let q = positions[j as usize];
                let j = j as usize;
                cone(i, &Neighbour::from_offset([q[0] - p[0], q[1] - p[1]], velocities[j]))
            }));
            decide(scratch, i)
        };
        return Ok(for_each_robot(n, scratch, |i| i, robot));
    }
    // Without lists, each robot's neighbours come straight from the grid (no CSR is built), and
    // robots go in the grid's cell order, so that neighbouring robots share cache lines.
    let xs: Vec<f64> = positions.iter().map(|p| p[0]).collect();
    let ys: Vec<f64> = positions.iter().map(|p| p[1]).collect();
    let near = Near::new(&xs, &ys, radius);
    let robot = |scratch: &mut Scratch, i: usize| {
        let Scratch { cones, run, .. } = scratch;
        cones.clear();
        near.for_each(i, run, |j, offset, distance| {
            // The search's distance is `from_offset`'s unless the squares overflowed (beyond
            // ~1.3e154 m, where the search takes `hypot`).
            let b = if distance < 1e150 {
                Neighbour::at(offset, distance, velocities[j])
            } else {
                Neighbour::from_offset(offset, velocities[j])
            };
            cones.push(cone(i, &b));
        });
        decide(scratch, i)
    };
    let order = near.order();
    let chosen = for_each_robot(n, scratch, |k| order[k], robot);
    let mut out = vec![[0.0; 2]; n];
    for (&i, v) in order.iter().zip(chosen) {
        out[i] = v;
    }
    Ok(out)
}

/// `robot(scratch, robots(k))` for k in `0..n`, in that order; on all threads for a large
/// swarm, on this one (no thread pool) for a small one. Each piece of work rayon makes
/// (dozens at n = 10,000) gets a copy of `scratch`: building one costs ~55k instructions (a
/// `hypot` per candidate for the clusters), a copy a few hundred.
fn for_each_robot(
    n: usize,
    mut scratch: Scratch,
    robots: impl Fn(usize) -> usize + Sync + Send,
    robot: impl Fn(&mut Scratch, usize) -> Vec2 + Sync + Send,
) -> Vec<Vec2> {
    if n >= PARALLEL_ROBOTS {
        (0..n)
            .into_par_iter()
            .with_min_len(PARALLEL_ROBOTS)
            .map_init(|| scratch.clone(), |scratch, k| robot(scratch, robots(k)))
            .collect()
    } else {
        (0..n).map(|k| robot(&mut scratch, robots(k))).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const PARAMS: HrvoParams = HrvoParams {
        safety: 0.24,
        v_max: 0.2,
        bounds: None,
        include_preferred: true,
    };

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
    fn round_small_rounds_to_the_nearest_band() {
        for (x, want) in [(0.0, 0), (0.49, 0), (0.51, 1), (7.0, 7), (22.6, 23), (23.0, 23)] {
            assert_eq!(round_small(x), want, "{x}");
        }
    }

    #[test]
    fn cluster_bounds_hold_for_every_member() {
        // Points of a cluster at the edge of its circle, cones through or near it: whenever a
        // cone is said to cover the circle it forbids every point, and the lower bound never
        // exceeds a point's squared distance as `choose` computes it.
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut uniform = |low: f64, high: f64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            low + (high - low) * (seed >> 11) as f64 / (1_u64 << 53) as f64
        };
        let mut covered = 0;
        for _ in 0..20_000 {
            let [cx, cy, radius] = [uniform(-0.2, 0.2), uniform(-0.2, 0.2), uniform(0.0, 0.05)];
            let points: Vec<Vec2> = (0..6)
                .map(|_| {
                    let angle = uniform(0.0, TAU);
                    let r = radius * uniform(0.98, 1.0);
                    [cx + r * angle.cos(), cy + r * angle.sin()]
                })
                .collect();
            let neighbour = Neighbour::from_offset(
                [uniform(-1.0, 1.0), uniform(-1.0, 1.0)],
                [uniform(-0.2, 0.2), uniform(-0.2, 0.2)],
            );
            let cone = Cone::new([uniform(-0.2, 0.2), uniform(-0.2, 0.2)], &neighbour, 0.24);
            let reach = points.iter().fold(0.0, |r: f64, q| r.max((q[0] - cx).hypot(q[1] - cy)));
            if cone.covers([cx, cy], pad([cx, cy], reach)) {
                covered += 1;
                assert!(points.iter().all(|q| cone.forbids(q[0], q[1])));
            }
            let [px, py] = [uniform(-0.3, 0.3), uniform(-0.3, 0.3)];
            let (dx, dy) = (cx - px, cy - py);
            let bound = lower_bound(dx * dx + dy * dy, reach);
            for q in &points {
                let (dx, dy) = (q[0] - px, q[1] - py);
                assert!(bound <= dx * dx + dy * dy);
            }
        }
        assert!(covered > 1_000, "{covered}");
    }

    #[test]
    fn velocity_at_the_apex_is_a_tie() {
        // v_A = v_B: v_A sits on the RVO's apex, equally close to both edges, so both are the VO's.
        for v in [[0.0, 0.0], [0.1, -0.05]] {
            let b = Neighbour::from_offset([0.3, 0.4], v);
            let cone = Cone::new(v, &b, 0.24);
            assert_eq!((cone.left_apex, cone.right_apex), (v, v));
        }
    }

    #[test]
    fn free_robot_takes_its_clamped_preference() {
        let v = hrvo_one([0.0, 0.0], [0.3, 0.4], [0.0, 0.0], &[], &grid(), &PARAMS).unwrap();
        assert!((v[0] - 0.12).abs() < 1e-15 && (v[1] - 0.16).abs() < 1e-15);
    }

    #[test]
    fn head_on_robot_does_not_drive_into_its_neighbour() {
        let ahead = Neighbour {
            direction: [1.0, 0.0],
            distance: 0.5,
            velocity: [-0.2, 0.0],
        };
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
                Neighbour {
                    direction: [angle.cos(), angle.sin()],
                    distance: 0.1,
                    velocity: [0.0, 0.0],
                }
            })
            .collect();
        let v = hrvo_one([0.0, 0.0], [0.2, 0.0], [0.0, 0.0], &ring, &grid(), &PARAMS).unwrap();
        assert_eq!(v, [0.0, 0.0]);
    }

    #[test]
    fn bounds_keep_the_robot_inside() {
        let walled = HrvoParams {
            bounds: Some(Arena::new(-1.0, 1.0, -1.0, 1.0).unwrap()),
            ..PARAMS
        };
        let v = hrvo_one([0.0, 0.0], [0.2, 0.0], [0.9, 0.0], &[], &grid(), &walled).unwrap();
        assert!(0.9 + v[0] < 1.0);
        assert!(v[0] > 0.0);
    }

    #[test]
    fn batch_equals_one_by_one_and_is_deterministic() {
        let n = 600;
        let positions: Vec<Vec2> = (0..n)
            .map(|i| {
                [
                    ((i as f64) * 0.754_877_666).fract() * 6.0,
                    ((i as f64) * 0.569_840_29).fract() * 4.0,
                ]
            })
            .collect();
        let velocities: Vec<Vec2> = (0..n)
            .map(|i| [0.1 * (i as f64).sin(), 0.1 * (i as f64).cos()])
            .collect();
        let preferred: Vec<Vec2> = (0..n)
            .map(|i| [0.2 * (2.0 * i as f64).cos(), 0.2 * (2.0 * i as f64).sin()])
            .collect();
        let g = grid();
        let batch = hrvo_batch(&positions, &velocities, &preferred, None, 0.5, &g, &PARAMS).unwrap();
        assert_eq!(
            batch,
            hrvo_batch(&positions, &velocities, &preferred, None, 0.5, &g, &PARAMS).unwrap()
        );
        for i in (0..n).step_by(37) {
            let around: Vec<Neighbour> = (0..n)
                .filter(|&j| j != i)
                .map(|j| {
                    Neighbour::from_offset(
                        [positions[j][0] - positions[i][0], positions[j][1] - positions[i][1]],
                        velocities[j],
                    )
                })
                .filter(|b| b.distance <= 0.5)
                .collect();
            let one = hrvo_one(velocities[i], preferred[i], positions[i], &around, &g, &PARAMS).unwrap();
            assert_eq!(batch[i], one);
        }
    }

    #[test]
    fn offsets_steer_as_the_angles_they_stand_for() {
        // Robots straight ahead (angle -pi from them: direction (1, 0) exactly, as the offsets').
        let (v, pref, at) = ([[0.1, 0.0]; 2], [[0.2, 0.05]; 2], [[0.0, 0.0]; 2]);
        let polar = [[0.3, -PI, 0.0, 0.0], [0.0, -PI, 0.1, 0.0], [0.25, -PI, -0.1, 0.0]];
        let sensed = [
            [0.3, 0.3, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.1, 0.0],
            [0.25, 0.25, 0.0, -0.1, 0.0],
        ];
        let offsets = [0, 1, 3];
        let g = grid();
        let (polar, sensed) = (columns(&polar), columns(&sensed));
        let by_polar = Detections::Polar(by_ref(&polar));
        let by_angle = hrvo_rows(&v, &pref, &at, &offsets, by_polar, &g, &PARAMS, None).unwrap();
        let seen = Detections::Offsets(by_ref(&sensed));
        let by_offset = hrvo_rows(&v, &pref, &at, &offsets, seen, &g, &PARAMS, None).unwrap();
        assert_eq!(by_angle, by_offset);
        assert_ne!(by_offset[0], pref[0]); // the robot ahead is in the way
                                           // Only the rows flagged steer: the other keeps its preferred velocity as it is.
        let steered = hrvo_rows(&v, &pref, &at, &offsets, seen, &g, &PARAMS, Some(&[false, true])).unwrap();
        assert_eq!(steered, vec![pref[0], by_offset[1]]);
        assert!(hrvo_rows(&v, &pref, &at, &offsets, seen, &g, &PARAMS, Some(&[true])).is_err());
        // Every value is checked, the offset at distance 0 too.
        let mut bad = sensed.clone();
        bad[1][1] = f64::NAN; // dx of the detection at distance 0
        let seen = Detections::Offsets(by_ref(&bad));
        let index = Err(GeomError::NonFinite {
            arg: "detections",
            index: 6,
        });
        assert_eq!(hrvo_rows(&v, &pref, &at, &offsets, seen, &g, &PARAMS, None), index);
        let mut bad = sensed.clone();
        bad[0][1] = -0.1;
        let seen = Detections::Offsets(by_ref(&bad));
        assert!(hrvo_rows(&v, &pref, &at, &offsets, seen, &g, &PARAMS, None).is_err());
        let short = [&sensed[0][..], &sensed[1], &sensed[2], &sensed[3], &sensed[4][..2]];
        assert!(hrvo_rows(&v, &pref, &at, &offsets, Detections::Offsets(short), &g, &PARAMS, None).is_err());
    }

    /// Rows of `W` values as `W` columns.
    fn columns<const W: usize>(rows: &[[f64; W]]) -> [Vec<f64>; W] {
        std::array::from_fn(|c| rows.iter().map(|row| row[c]).collect())
    }

    fn by_ref<const W: usize>(columns: &[Vec<f64>; W]) -> [&[f64]; W] {
        columns.each_ref().map(Vec::as_slice)
    }

    #[test]
    fn invalid_neighbour_lists_are_errors() {
        let p = [[0.0, 0.0]; 2];
        let g = grid();
        let bad = |indptr: &[i64], indices: &[i64]| {
            hrvo_batch(&p, &p, &p, Some((indptr, indices)), 1.0, &g, &PARAMS).is_err()
        };
        assert!(bad(&[0, 1], &[1]));
        assert!(bad(&[0, 1, 1], &[2]));
        assert!(bad(&[0, 1, 0], &[1]));
        assert!(!bad(&[0, 1, 2], &[1, 0]));
    }
}
