//! Real terrain import: digital elevation models and shape models from files (see `shared/data`).
//!
//! Every DEM loader returns a [`Heightmap`]; mesh loaders return a triangle mesh; point-cloud loaders (PLY, PCD,
//! LAS/LAZ) return a [`pointcloud::PointCloud`], which [`pointcloud::thin`] reduces to the flight scan capacity.

pub mod asc;
pub mod geotiff;

/// A regular grid of terrain heights, row-major, row 0 at the minimum y (south) edge.
#[derive(Debug, Clone, PartialEq)]
pub struct Heightmap {
    /// Number of columns (x direction).
    pub width: usize,
    /// Number of rows (y direction).
    pub height: usize,
    /// Horizontal spacing between grid posts, metres.
    pub spacing_m: f64,
    /// Heights in metres, `width * height` values, `None` where the file says "no data".
    pub heights_m: Vec<Option<f64>>,
}

impl Heightmap {
    /// Height at column `ix`, row `iy`, if present.
    pub fn get(&self, ix: usize, iy: usize) -> Option<f64> {
        if ix < self.width && iy < self.height {
            self.heights_m.get(iy * self.width + ix).copied().flatten()
        } else {
            None
        }
    }
}

pub mod npy;
pub mod obj;
pub mod pointcloud;
