//! Fuzz target: the PCD reader (`host_sim::terrain::pointcloud::pcd::parse_pcd`: ASCII and binary) with a fuzzed point
//! limit, then voxel thinning of what it accepts to a fuzzed capacity; the contract checked is
//! `firmware_fuzz::point_cloud`'s.
#![no_main]

use host_sim::terrain::pointcloud::pcd;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| firmware_fuzz::point_cloud(data, pcd::parse_pcd));
