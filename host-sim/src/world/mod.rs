//! Ground-truth worlds: signed distance and ray casts.
//!
//! A world is the simulator's truth. The flight software never sees it directly: it sees sensor frames ray-cast
//! into it and tether readings computed from it. Tests compare the onboard map and the planners' decisions against
//! it. Every world implements [`firmware::map::DistanceField`] (exact signed distance, negative inside terrain)
//! and [`World`].

pub mod crater;
pub mod geometry;
pub mod heightmap;
pub mod ledge;
pub mod mesh;

use firmware::geom::{Real, Vec3};
use firmware::map::{DistanceField, DistanceQuery};

use crate::truth::solid::ExactGeometry;

/// Axis-aligned bounds of a world, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

/// A ground-truth world.
pub trait World: DistanceField + Send + Sync {
    /// A short name for logs and pictures.
    fn name(&self) -> &str;
    /// Bounds of the terrain (the region where the world is defined and interesting).
    fn bounds(&self) -> Aabb;
    /// Distance along the unit direction `dir` from `origin` to the first surface hit, up to `max_range`.
    fn raycast(&self, origin: &Vec3, dir: &Vec3, max_range: Real) -> Option<Real>;
    /// Terrain height under (x, y) if the world is a height field (top surface), else `None`.
    fn height_at(&self, x: Real, y: Real) -> Option<Real>;
    /// The signed distance where only values up to `limit` matter (a TSDF truncated at `limit`): exact when the
    /// true distance is at most `limit`, otherwise of the right sign and larger than `limit` in magnitude. The
    /// default is the exact [`DistanceField::query`]; worlds whose exact query slows with the distance override it.
    fn query_up_to(&self, p: &Vec3, limit: Real) -> DistanceQuery {
        let _ = limit;
        self.query(p)
    }
    /// The world's exact geometry as primitive solids ([`crate::truth::solid`]), for the judges that must not
    /// use a distance field (the physics judge, the general true tether).
    fn exact_geometry(&self) -> ExactGeometry;
}
