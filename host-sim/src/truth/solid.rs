//! A world's exact geometry as primitive solids, for the judges that must not look at a distance field: the
//! physics judge ([`crate::physics`]) turns each solid into a rigid-body collider, the general true tether
//! ([`crate::truth::taut`]) wraps around their convex edges.
//!
//! The terrain is the union of the solids:
//! - [`Solid::Ground`]: everything below a horizontal plane (the ledge's and the crater wall's flat ground);
//! - [`Solid::Prism`]: a convex polygon extruded along a vector (the ledge body, the crater wall's rim and wall,
//!   a rock);
//! - [`Solid::Cylinder`]: a vertical circular cylinder (the test-3 pole);
//! - [`Solid::HeightGrid`]: a DEM's posts, each cell split into two triangles along its (0,0)-(1,1) diagonal as
//!   [`crate::world::heightmap`] triangulates it, a missing post (NaN) leaves its cells out;
//! - [`Solid::Mesh`]: a closed triangle mesh ([`crate::world::mesh`]).
//!
//! Every [`crate::world::World`] answers [`crate::world::World::exact_geometry`]; each world's own module builds
//! its list from its own parameters, so this description is exactly the world's surface (the cylinder is a true
//! circle here; only the tether's wrap edges approximate it, see [`crate::truth::taut`]).

use firmware::geom::p3::P3;

/// One solid of a world (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub enum Solid {
    /// The half-space below the plane `z = height`.
    Ground {
        /// Height of the ground plane, metres.
        z: f64,
    },
    /// A convex polygon extruded along `extrusion`: the solid is `{ p + s * extrusion : p in polygon, s in [0, 1] }`.
    Prism {
        /// The polygon's corners (a planar convex polygon, in order, at least 3).
        polygon: Vec<P3>,
        /// The extrusion vector (not in the polygon's plane).
        extrusion: P3,
    },
    /// A vertical circular cylinder.
    Cylinder {
        /// Axis position (x, y), metres.
        centre: [f64; 2],
        /// Radius, metres.
        radius: f64,
        /// Bottom height, metres.
        z0: f64,
        /// Top height, metres.
        z1: f64,
    },
    /// A height grid: post (i, j) at `(x0 + i * spacing, y0 + j * spacing, heights[j * nx + i])`.
    HeightGrid {
        /// Posts along x.
        nx: usize,
        /// Posts along y.
        ny: usize,
        /// x of post column 0, metres.
        x0: f64,
        /// y of post row 0, metres.
        y0: f64,
        /// Post spacing, metres.
        spacing: f64,
        /// Heights, row-major (`j * nx + i`), NaN = missing post.
        heights: Vec<f64>,
    },
    /// A closed triangle mesh (counter-clockwise seen from outside).
    Mesh {
        /// Vertices, metres.
        vertices: Vec<P3>,
        /// Triangles as vertex indices.
        triangles: Vec<[u32; 3]>,
    },
}

/// A world's exact geometry: the union of [`Solid`]s.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExactGeometry {
    /// The solids.
    pub solids: Vec<Solid>,
}

impl Solid {
    /// The corners of a prism: the polygon, then the polygon moved by the extrusion (`None` for other solids).
    pub fn prism_corners(&self) -> Option<Vec<P3>> {
        let Solid::Prism { polygon, extrusion: e } = self else { return None };
        let mut v = polygon.clone();
        v.extend(polygon.iter().map(|p| [p[0] + e[0], p[1] + e[1], p[2] + e[2]]));
        Some(v)
    }

    /// A prism standing on a horizontal convex polygon (counter-clockwise seen from above) between `z0` and `z1`.
    pub fn vertical_prism(polygon: &[[f64; 2]], z0: f64, z1: f64) -> Solid {
        Solid::Prism { polygon: polygon.iter().map(|p| [p[0], p[1], z0]).collect(), extrusion: [0.0, 0.0, z1 - z0] }
    }

    /// A prism whose cross-section is a convex polygon in the x-z plane (corners `(x, z)`) at `y = y0`, extruded
    /// along +y to `y1`.
    pub fn xz_prism(section: &[[f64; 2]], y0: f64, y1: f64) -> Solid {
        Solid::Prism { polygon: section.iter().map(|p| [p[0], y0, p[1]]).collect(), extrusion: [0.0, y1 - y0, 0.0] }
    }
}
