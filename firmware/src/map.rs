//! The onboard terrain map (Paton et al. section IV; Voxblox TSDF -> ESDF). Not yet implemented beyond the query
//! trait that the rover, tether and planners program against.

use crate::geom::{Real, Vec3};

/// What a signed-distance query can say about a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DistanceQuery {
    /// The point is in observed space: signed distance to the nearest surface (metres, negative inside terrain)
    /// and the distance gradient (points away from the terrain, unit length where defined).
    Known {
        /// Signed distance, metres.
        distance: Real,
        /// Gradient of the distance field.
        gradient: Vec3,
    },
    /// Nobody has observed this point: neither free nor occupied. Callers treat it as unsafe.
    Unknown,
}

/// A Euclidean signed distance field: the onboard ESDF implements it, and so do the simulator's ground-truth worlds
/// and analytic test scenes, so rover settling, anchor prediction and planning can be tested on exact geometry.
pub trait DistanceField {
    /// Signed distance and gradient at `p`.
    fn query(&self, p: &Vec3) -> DistanceQuery;
}
