//! Fuzz target: the LAS/LAZ reader (`host_sim::terrain::pointcloud::las::parse_las`, over the `las` and `laz` crates)
//! with a fuzzed point limit, then voxel thinning of what it accepts to a fuzzed capacity; the contract checked is
//! `firmware_fuzz::point_cloud`'s.
#![no_main]

use host_sim::terrain::pointcloud::las;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| firmware_fuzz::point_cloud(data, las::parse_las));
