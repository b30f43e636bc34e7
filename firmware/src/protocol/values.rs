//! The wire's shared values and their validation: [`Point3`], [`Invalid`], [`Validate`] and the float checks every
//! message's validation uses (`message.rs` and `team.rs` both build on them; neither imports the other's types
//! through this module).

use serde::{Deserialize, Serialize};

/// A point or vector, metres, `f32` little-endian on the wire (postcard encodes `f32` as 4 raw bytes).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Point3 {
    /// x, metres.
    pub x: f32,
    /// y, metres.
    pub y: f32,
    /// z, metres.
    pub z: f32,
}

impl Point3 {
    /// A point from its coordinates.
    pub const fn new(x: f32, y: f32, z: f32) -> Self {
        Self { x, y, z }
    }
}

/// Why a decoded body is not a valid message (narrow: only what validation can find).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Invalid {
    /// A float is NaN or infinite.
    NonFinite,
    /// A quaternion is not unit.
    NotUnitQuaternion,
    /// A value is outside its range.
    OutOfRange,
    /// A terrain tile has more posts on a side than `MAX_TILE_SIDE`.
    TileTooLarge,
    /// A terrain tile's post spacing is outside its range.
    TileResolution,
    /// A robot index outside `0..TEAM_SIZE` (v8).
    UnknownRobot,
    /// A chunk count of 0 or above its limit (v8 team scans).
    TooManyChunks,
    /// A chunk index not below the chunk count (v8 team scans).
    ChunkIndexOutOfRange,
}

/// Semantic validation after decoding.
pub trait Validate {
    /// `Ok` when every float is finite and every value in its documented range.
    fn validate(&self) -> Result<(), Invalid>;
}

pub(crate) fn finite(v: f32) -> Result<(), Invalid> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Invalid::NonFinite)
    }
}

pub(crate) fn positive(v: f32) -> Result<(), Invalid> {
    finite(v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(Invalid::OutOfRange)
    }
}

pub(crate) fn non_negative(v: f32) -> Result<(), Invalid> {
    finite(v)?;
    if v >= 0.0 {
        Ok(())
    } else {
        Err(Invalid::OutOfRange)
    }
}

impl Validate for Point3 {
    fn validate(&self) -> Result<(), Invalid> {
        finite(self.x)?;
        finite(self.y)?;
        finite(self.z)
    }
}
