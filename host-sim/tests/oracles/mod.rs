//! What `tests/crate_oracles.rs` and `benches/crates.rs` share: the shared data files, the maintained crates set up
//! the way both use them, and a priority-queue item for the planners' heap.

use firmware::plan::heap::HeapSlot;
use host_sim::terrain::obj::TriMesh;
use parry3d_f64::math::Vector;
use parry3d_f64::shape::{TriMesh as ParryMesh, TriMeshFlags};
use std::path::PathBuf;

/// The bytes of a file under `shared/data`; a missing file fails (it does not skip).
pub fn shared_bytes(rel: &str) -> Vec<u8> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data")
        .join(rel);
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The shared HiRISE crop, 120 x 70 `<f4`.
pub const HIRISE: &str = "terrain/hirise_DTEEC_010228_1490_016320_1490_crop_120x70.npy";

/// `tobj` reading OBJ text as ours does: faces triangulated (fans), positions indexed on their own, no materials.
pub fn tobj_parse(text: &str) -> Result<Vec<tobj::Model>, tobj::LoadError> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    tobj::load_obj_buf(&mut text.as_bytes(), &opts, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map(|(m, _)| m)
}

/// A point as parry's vector.
pub fn pv(p: [f64; 3]) -> Vector {
    Vector::new(p[0], p[1], p[2])
}

/// The mesh as parry sees it, with the orientation `MeshWorld` settles on (outward normals, the whole mesh
/// flipped if its signed volume is negative) and pseudo-normals for the inside test (`TriMeshFlags::ORIENTED`).
pub fn parry_mesh(mesh: &TriMesh) -> ParryMesh {
    let v: Vec<Vector> = mesh.vertices.iter().map(|p| pv(*p)).collect();
    let vol: f64 = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| v[i as usize]))
        .map(|[a, b, c]| a.dot(b.cross(c)))
        .sum();
    let tris = mesh
        .triangles
        .iter()
        .map(|t| if vol < 0.0 { [t[0], t[2], t[1]] } else { *t })
        .collect();
    ParryMesh::with_flags(v, tris, TriMeshFlags::ORIENTED).expect("parry trimesh")
}

/// A queued item of the planners' heap: smallest key first, ties to the lower id (as the planners break them).
pub struct Entry {
    /// Priority, smaller first.
    pub key: u64,
    /// Heap position, recorded by the heap.
    pub pos: u32,
}

impl HeapSlot for Entry {
    fn before(&self, id: u32, other: &Self, other_id: u32) -> bool {
        (self.key, id) < (other.key, other_id)
    }
    fn heap_position(&self) -> u32 {
        self.pos
    }
    fn set_heap_position(&mut self, pos: u32) {
        self.pos = pos;
    }
}
