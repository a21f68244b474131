//! The plane's shared types: a 2-D vector and the arena every kernel keeps robots in.

use crate::error::{GeomError, Result};

/// A 2-D vector `[x, y]` (m, or m/s).
pub type Vec2 = [f64; 2];

/// Axis-aligned rectangular arena (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arena {
    pub xmin: f64,
    pub xmax: f64,
    pub ymin: f64,
    pub ymax: f64,
}

impl Arena {
    /// # Errors
    /// [`GeomError::InvalidBounds`] unless the bounds are finite with `xmin < xmax`, `ymin < ymax`.
    pub fn new(xmin: f64, xmax: f64, ymin: f64, ymax: f64) -> Result<Self> {
        let finite = [xmin, xmax, ymin, ymax].iter().all(|v| v.is_finite());
        if finite && xmin < xmax && ymin < ymax {
            Ok(Self { xmin, xmax, ymin, ymax })
        } else {
            Err(GeomError::InvalidBounds { xmin, xmax, ymin, ymax })
        }
    }

    /// Whether `(x, y)` is inside or on the border (the rps boundary criterion).
    pub fn contains(&self, x: f64, y: f64) -> bool {
        !(x < self.xmin || x > self.xmax || y < self.ymin || y > self.ymax)
    }
}
