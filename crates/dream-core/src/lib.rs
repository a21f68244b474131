//! # dream-core
//!
//! The geometry kernels of DREAM, a library for simulating distributed multi-robot algorithms.
//! Pure Rust, no Python: every kernel takes slices of `f64` and parameter structs and returns
//! owned vectors or a [`GeomError`] that names the bad argument. Units are SI (metres,
//! seconds, radians) in the world frame.
//!
//! Shared types:
//! - [`geom`]: the 2-D vector and the arena;
//! - [`csr`]: ragged rows (one per robot) and the checks of ragged inputs;
//! - [`parallel`]: the one way kernels spread independent work over threads;
//! - [`error`]: the one error type, [`GeomError`], and the input checks every kernel shares.
//!
//! Kernels:
//! - [`bursts`]: loss bursts on radio links (Gilbert-Elliott channels), the links in a burst kept sorted.
//! - [`draws`]: counter-based random draws (noise, losses, lies), the same whoever asks and when.
//! - [`dynamics`]: unicycle Euler step, rps velocity thresholding and validation counts,
//!   single-integrator to unicycle conversion and actuator limiting, for the whole swarm.
//! - [`grid`]: the uniform grid behind neighbour queries.
//! - [`length`]: vector lengths rounded as Python's `math.hypot` rounds them.
//! - [`neighbours`]: who is near whom, within a range and field of view, for the whole swarm.
//! - [`perceive`]: who the robots deciding now see and hear, in one neighbour query.
//! - [`reduce`]: sums, means, extremes and nearest entries of ragged rows (a robot's neighbourhood).
//! - [`hrvo`]: Hybrid Reciprocal Velocity Obstacles, for the whole swarm or on each robot's detections.
//! - [`guard`]: the motion guard, the last check of each robot's command against the robots it sees.
//! - [`voronoi`]: disc-bounded Voronoi cells and their centroids.
//! - [`heard`]: Voronoi cells of robots that know the others by range radio, in one pass.
//! - [`obstacles`]: virtual agents that keep robots off convex obstacles.
//! - [`raycast`]: the GRITSbot's infrared distance sensors for the whole swarm (rps 2.1's model).
//! - [`sidestep`]: the side-step counters and sides of the robots deciding, read and written in place.
//! - [`tables`]: rows of per-robot tables copied out and back (the swarm engine's memory).

pub mod bursts;
pub mod csr;
pub mod draws;
pub mod dynamics;
pub mod error;
pub mod geom;
pub mod grid;
pub mod guard;
pub mod heard;
pub mod hrvo;
pub mod length;
pub mod neighbours;
pub mod obstacles;
pub mod parallel;
pub mod perceive;
pub mod raycast;
pub mod reduce;
pub mod sidestep;
pub mod tables;
pub mod voronoi;

pub use error::{GeomError, Result};
