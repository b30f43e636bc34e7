//! The navigator: the flight executive's [`Autonomy`] implementation.
//!
//! Paton et al. (section IV) plan on a map the rover builds itself from its own range sensor. The navigator is
//! where that happens on board: every complete scan the executive reassembles from the link is integrated into
//! the onboard TSDF ([`Map::integrate_points`]) and the ESDF is brought up to date ([`Map::update_esdf`]) within the
//! map's own budgets; the map's state goes out in every `Telemetry` frame ([`MapStatus`]).
//!
//! Planning on this map (the tether-aware ABIT* of [`crate::plan::abit`] over [`crate::rover`], [`crate::tether`]
//! and [`crate::stability`]) is the next step: until it is wired in, goal requests are answered with
//! `PlannerUnavailable` by the [`Autonomy`] defaults, never with a fake plan.
//!
//! ## Storage
//! The block pool and the block index are owned by the caller and lent to the navigator for good (`Vec`s on the
//! host, `&'static mut` slices in the board's PSRAM). The navigator keeps them and builds a short-lived [`Map`]
//! view per call ([`Map::reattach`]), so it holds no borrow between calls.
//!
//! ## Parameters
//! - the map: [`MapConfig`] (default [`MapConfig::DEFAULT`]: 5 cm voxels, 15 cm truncation, 32 ESDF sweeps);
//! - [`NAV_POINT_BATCH`](crate::config::map::NAV_POINT_BATCH): points converted and integrated per batch
//!   (default 256), the only stack buffer.
//!
//! Work per scan is bounded by `points * max_ray_voxels` voxel updates plus `esdf_max_sweeps` ESDF sweeps; an
//! ESDF that runs out of sweeps is counted and continues with the next scan.

use core::borrow::BorrowMut;

use hal::Instant;

use crate::config::map::{MapConfig, NAV_POINT_BATCH};
use crate::exec::{Autonomy, Scan};
use crate::geom::{Pose3, Rot3, Vec3};
use crate::map::{Block, Map, MapError};
use crate::protocol::{MapStatus, Pose};

/// The executive's autonomy: builds the onboard map from scans (see the module docs).
pub struct Navigator<B, I> {
    cfg: MapConfig,
    blocks: B,
    index: I,
    used: usize,
    status: MapStatus,
}

impl<B: BorrowMut<[Block]>, I: BorrowMut<[u32]>> Navigator<B, I> {
    /// A navigator over lent map storage, which is cleared. Errors as [`Map::from_slices`].
    pub fn new(cfg: MapConfig, mut blocks: B, mut index: I) -> Result<Self, MapError> {
        let capacity = Map::from_slices(cfg, blocks.borrow_mut(), index.borrow_mut())?.blocks_capacity();
        let status = MapStatus {
            blocks_capacity: u32::try_from(capacity).unwrap_or(u32::MAX),
            ..MapStatus::default()
        };
        Ok(Self { cfg, blocks, index, used: 0, status })
    }

    /// The onboard map (a view over the navigator's storage), for planners, tests and pictures.
    pub fn map(&mut self) -> Option<Map<'_>> {
        Map::reattach(self.cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), self.used).ok()
    }
}

/// The protocol's pose as a rigid transform (the protocol validated it: finite, unit quaternion within tolerance).
fn pose3(p: &Pose) -> Pose3 {
    let q = nalgebra::Quaternion::new(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
    Pose3::from_parts(
        nalgebra::Translation3::new(p.position.x, p.position.y, p.position.z),
        Rot3::from_quaternion(q),
    )
}

fn add(counter: &mut u32, n: u32) {
    *counter = counter.saturating_add(n);
}

impl<B: BorrowMut<[Block]>, I: BorrowMut<[u32]>> Autonomy for Navigator<B, I> {
    fn scan(&mut self, scan: &Scan<'_>, _now: Instant) {
        let sensor_pose = pose3(&scan.sensor_pose);
        let mut status = self.status;
        let Some(mut map) = self.map() else {
            // Unreachable with storage that `new` accepted; counted rather than ignored.
            add(&mut status.pool_errors, 1);
            self.status = status;
            return;
        };
        let mut batch = [Vec3::zeros(); NAV_POINT_BATCH];
        let mut pool_error = false;
        for chunk in scan.points.chunks(NAV_POINT_BATCH) {
            for (dst, p) in batch.iter_mut().zip(chunk) {
                *dst = Vec3::new(p.x, p.y, p.z);
            }
            let out = map.integrate_points(&sensor_pose, batch.get(..chunk.len()).unwrap_or(&[]));
            add(&mut status.points_integrated, out.points_integrated);
            add(&mut status.points_rejected, out.points_rejected);
            add(&mut status.voxels_dropped, out.voxels_dropped);
            pool_error |= out.pool_error.is_some();
        }
        if pool_error {
            add(&mut status.pool_errors, 1);
            log::warn!("map: pool full or index probe exhausted during scan {}", scan.scan_id);
        }
        if !map.update_esdf().converged {
            add(&mut status.esdf_budget_exhausted, 1);
        }
        let used = map.blocks_used();
        status.blocks_used = u32::try_from(used).unwrap_or(u32::MAX);
        add(&mut status.scans_integrated, 1);
        self.used = used;
        self.status = status;
    }

    fn map_status(&self) -> MapStatus {
        self.status
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{DistanceField, DistanceQuery};
    use crate::protocol::{Point3, Quat};
    use std::vec;

    /// A downward-looking scan of flat ground z = 0 from 2 m up lands in the map, and the map answers queries.
    #[test]
    fn scans_build_the_map_and_report_status() {
        let cfg = MapConfig::with_voxel_size(0.1);
        let mut nav = Navigator::new(cfg, vec![Block::EMPTY; 512], vec![0u32; 1024]).unwrap();
        assert_eq!(nav.map_status().blocks_capacity, 512);
        let mut pts = vec![];
        for i in 0..30 {
            for j in 0..30 {
                let (x, y) = (-1.5 + 0.1 * i as f32, -1.5 + 0.1 * j as f32);
                pts.push(Point3 { x, y, z: -2.0 }); // sensor frame = world axes, sensor at z = 2
            }
        }
        let pose = Pose {
            position: Point3 { x: 0.0, y: 0.0, z: 2.0 },
            orientation: Quat { x: 0.0, y: 0.0, z: 0.0, w: 1.0 },
        };
        nav.scan(&Scan { scan_id: 1, sensor_pose: pose, points: &pts }, Instant::from_micros(0));
        let st = nav.map_status();
        assert_eq!(st.scans_integrated, 1);
        assert_eq!(st.points_integrated, 900);
        assert!(st.blocks_used > 0 && st.voxels_dropped == 0 && st.pool_errors == 0);
        let map = nav.map().unwrap();
        match map.query(&Vec3::new(0.0, 0.0, 0.3)) {
            DistanceQuery::Known { distance, .. } => assert!((distance - 0.3).abs() < 0.1, "{distance}"),
            DistanceQuery::Unknown => panic!("observed free space above the ground reported unknown"),
        }
        assert_eq!(map.query(&Vec3::new(40.0, 40.0, 40.0)), DistanceQuery::Unknown);
    }

    /// A pool too small for the scan: counted, the blocks that fit are kept, nothing panics.
    #[test]
    fn full_pool_is_counted_not_fatal() {
        let cfg = MapConfig::with_voxel_size(0.05);
        let mut nav = Navigator::new(cfg, vec![Block::EMPTY; 2], vec![0u32; 4]).unwrap();
        let pts: vec::Vec<Point3> =
            (0..200).map(|i| Point3 { x: -2.0 + 0.02 * i as f32, y: 0.0, z: -1.0 }).collect();
        let pose = Pose {
            position: Point3 { x: 0.0, y: 0.0, z: 1.0 },
            orientation: Quat { x: 0.0, y: 0.0, z: 0.0, w: 1.0 },
        };
        nav.scan(&Scan { scan_id: 7, sensor_pose: pose, points: &pts }, Instant::from_micros(0));
        let st = nav.map_status();
        assert_eq!(st.blocks_used, 2);
        assert_eq!(st.pool_errors, 1);
        assert!(st.voxels_dropped > 0);
    }
}
