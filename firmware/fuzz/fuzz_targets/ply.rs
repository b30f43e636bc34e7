//! Fuzz target: the PLY reader (`host_sim::terrain::pointcloud::ply::parse_ply`: ASCII, binary little and big endian)
//! with a fuzzed point limit, then voxel thinning of what it accepts to a fuzzed capacity; the contract checked is
//! `firmware_fuzz::point_cloud`'s.
#![no_main]

use host_sim::terrain::pointcloud::ply;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| firmware_fuzz::point_cloud(data, ply::parse_ply));
