//! The tether state that survives a reset (issue 24 item 2): a checkpoint of what the rover cannot see again after
//! a watchdog bite or a commanded reset — the anchor history (where the tether touches the terrain, Paton et al.
//! section IV-B), the root anchor, the last tracked body pose and encoder payout — kept in memory the boot code
//! neither loads nor zeroes (the board's `.uninit` SRAM; a battery-backed SRAM on a flight computer that has one).
//!
//! After a reset the map is gone and can be scanned again; the anchor history cannot: the tether may be wrapped on
//! a pole the rover passed minutes ago. So the flight software never resumes assuming a straight tether: it comes
//! back `Safe` with reason `Reset` holding the recovered history, and the ground's next `Configure` with the same
//! root anchor continues from it; with a checkpoint that is present but unreadable it stays `Safe` with reason
//! `TetherStateLost` and refuses goals.
//!
//! The checkpoint also keeps the ground round the rover as the map last showed it ([`GroundPatch`], 2 m x 2 m).
//! The ground's survey after a reset may not see under the rover (behind the test-3 pole the lander's mast is in
//! the pole's shadow, and the rover's own sensor looks ahead of its wheels): without the patch the rover could not
//! settle its own pose on the new map and would refuse every goal (`StartUnobserved`). The patch is written back
//! into the map at the `Configure` that continues from the checkpoint.
//!
//! ## Layout
//! [`RETAINED_BYTES`] bytes: two slots of [`SLOT_BYTES`], written alternately (generation even: slot 0, odd: slot
//! 1), so a reset in the middle of a write leaves the other slot, one generation older, intact. A slot is
//! `magic u32 | generation u32 | root 3 x f32 | body flag u8 | body position 3 x f32 | body yaw f32 | payout f32 |
//! goal id u32 | patch flag u8 | patch centre 2 x f32 | patch z0 f32 | GROUND_PATCH_CELLS x i16 | anchors n u8 |
//! n x (point 3 x f32, gradient 3 x f32) | crc32`, little-endian, the CRC (the protocol's CRC-32/ISO-HDLC) over
//! everything before it. Reading takes the valid slot with the higher generation. The magic names the layout
//! ("TCK2"; a "TCK1" checkpoint of the layout without the patch reads as none: a new deployment).

use crate::config::tether::{
    ANCHOR_HISTORY_CAPACITY, GROUND_PATCH_CELLS, GROUND_PATCH_HALF_CELLS, GROUND_PATCH_SIDE, GROUND_PATCH_SPACING_M,
    RETAINED_SLOT_BYTES,
};
use crate::geom::{Real, Vec3};
use crate::protocol::frame::CRC;
use crate::tether::{Anchor, AnchorHistory};

/// The body pose in a checkpoint: axle centre (world frame, metres) and heading (radians), as the mission tracks it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RetainedPose {
    /// Axle centre.
    pub position: Vec3,
    /// Heading of the body x axis.
    pub yaw: Real,
}

/// Marks a written slot ("TCK2"). Power-on RAM holding exactly this by chance is 1 in 2^32, and then its CRC too.
const MAGIC: u32 = 0x324B_4354;
/// Bytes before the anchors: magic, generation, root, body flag, body position and yaw, payout, goal id, the
/// ground patch, count.
const HEAD_BYTES: usize = 4 + 4 + 12 + 1 + 12 + 4 + 4 + 4 + PATCH_BYTES + 1;
/// Bytes of the ground patch: flag, centre, height reference, heights.
const PATCH_BYTES: usize = 1 + 8 + 4 + GROUND_PATCH_CELLS * 2;
/// Bytes of one anchor: point and gradient.
const ANCHOR_BYTES: usize = 24;
/// Bytes of one slot (the largest history and the CRC; `config::tether::RETAINED_SLOT_BYTES`).
pub const SLOT_BYTES: usize = RETAINED_SLOT_BYTES;
const _: () = assert!(SLOT_BYTES == HEAD_BYTES + ANCHOR_HISTORY_CAPACITY * ANCHOR_BYTES + 4);
pub use crate::config::tether::RETAINED_BYTES;

/// The retained block, as the board and the in-process link hold it.
pub type RetainedBlock = [u8; RETAINED_BYTES];

/// A patch cell without ground (the map showed none, or not with free space above it).
pub const NO_GROUND: i16 = i16::MIN;

/// The ground round the rover as the map showed it: a grid of [`GROUND_PATCH_SIDE`] x [`GROUND_PATCH_SIDE`] cells
/// [`GROUND_PATCH_SPACING_M`] apart, centred on the axle, each the height of the highest observed surface of its
/// column (with observed free space above it, `config::tether::GROUND_PATCH_CLEAR_M`).
#[derive(Debug, Clone, PartialEq)]
pub struct GroundPatch {
    /// Centre of the grid (x, y), world frame, metres.
    pub centre: [Real; 2],
    /// Height reference, metres (the axle's height when it was taken).
    pub z0: Real,
    /// Heights above `z0`, millimetres, x fastest; [`NO_GROUND`] where there is none.
    pub heights_mm: [i16; GROUND_PATCH_CELLS],
}

impl GroundPatch {
    /// A patch centred on `centre` at height reference `z0`, every cell without ground.
    pub fn empty(centre: [Real; 2], z0: Real) -> Self {
        GroundPatch { centre, z0, heights_mm: [NO_GROUND; GROUND_PATCH_CELLS] }
    }

    /// The (x, y) of cell `k` (x fastest), world frame.
    pub fn cell_xy(&self, k: usize) -> (Real, Real) {
        let h = GROUND_PATCH_HALF_CELLS as Real;
        let (i, j) = ((k % GROUND_PATCH_SIDE) as Real, (k / GROUND_PATCH_SIDE) as Real);
        (self.centre[0] + (i - h) * GROUND_PATCH_SPACING_M, self.centre[1] + (j - h) * GROUND_PATCH_SPACING_M)
    }

    /// Sets cell `k`'s ground height `z` (world, metres); a height beyond the millimetre range is left out.
    pub fn set(&mut self, k: usize, z: Real) {
        let mm = libm::roundf((z - self.z0) * 1000.0);
        if let Some(c) = self.heights_mm.get_mut(k) {
            *c = if mm.is_finite() && mm > Real::from(NO_GROUND) && mm <= Real::from(i16::MAX) { mm as i16 } else { NO_GROUND };
        }
    }

    /// The ground points of the patch (world, metres), cell by cell.
    pub fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.heights_mm.iter().enumerate().filter(|(_, h)| **h != NO_GROUND).map(|(k, h)| {
            let (x, y) = self.cell_xy(k);
            Vec3::new(x, y, self.z0 + Real::from(*h) * 1e-3)
        })
    }
}

/// What the mission checkpoints.
#[derive(Debug, Clone, PartialEq)]
pub struct TetherCheckpoint {
    /// Counts the checkpoints of this flight and the ones before its resets; selects the slot.
    pub generation: u32,
    /// The root anchor of the `Configure` the history belongs to.
    pub root: Vec3,
    /// The tracked anchor history, root first.
    pub anchors: AnchorHistory,
    /// The last tracked body pose, if one was known.
    pub body: Option<RetainedPose>,
    /// The last accepted encoder payout, metres (0 before the first reading).
    pub payout_m: f32,
    /// The goal being pursued (0: none).
    pub goal_id: u32,
    /// The ground round the rover from the map after its last complete scan, if taken (`GroundPatch`).
    pub ground: Option<GroundPatch>,
}

/// What a boot finds in the retained block.
// Returned once per boot, by value: there is no heap to box the checkpoint into.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum Recovered {
    /// No slot was ever written (power-on, or a fresh emulator): a new deployment.
    Empty,
    /// The newest readable checkpoint.
    Valid(TetherCheckpoint),
    /// A slot was written but none reads back (its CRC or contents are wrong): the tether state is lost.
    Corrupt,
}

/// Writes `cp` into its slot of `block` (the slot of `cp.generation`), leaving the other slot as it was.
pub fn write(block: &mut RetainedBlock, cp: &TetherCheckpoint) {
    let slot_at = (cp.generation as usize % 2) * SLOT_BYTES;
    let Some(slot) = block.get_mut(slot_at..slot_at + SLOT_BYTES) else { return };
    let mut w = Writer { buf: slot, at: 0 };
    w.u32(MAGIC);
    w.u32(cp.generation);
    w.vec3(&cp.root);
    let body = cp.body.unwrap_or(RetainedPose { position: Vec3::zeros(), yaw: 0.0 });
    w.u8(u8::from(cp.body.is_some()));
    w.vec3(&body.position);
    w.f32(body.yaw);
    w.f32(cp.payout_m);
    w.u32(cp.goal_id);
    w.u8(u8::from(cp.ground.is_some()));
    let none = GroundPatch::empty([0.0; 2], 0.0);
    let g = cp.ground.as_ref().unwrap_or(&none);
    w.f32(g.centre[0]);
    w.f32(g.centre[1]);
    w.f32(g.z0);
    for h in g.heights_mm.iter() {
        w.bytes(&h.to_le_bytes());
    }
    let anchors = cp.anchors.as_slice();
    w.u8(u8::try_from(anchors.len()).unwrap_or(u8::MAX));
    for a in anchors {
        w.vec3(&a.point);
        w.vec3(&a.gradient);
    }
    let end = w.at;
    let crc = slot.get(..end).map_or(0, |b| CRC.checksum(b));
    let mut w = Writer { buf: slot, at: end };
    w.u32(crc);
}

/// Reads the newest valid checkpoint of `block`.
pub fn read(block: &RetainedBlock) -> Recovered {
    let mut best: Option<TetherCheckpoint> = None;
    let mut written = false;
    for k in 0..2 {
        let Some(slot) = block.get(k * SLOT_BYTES..(k + 1) * SLOT_BYTES) else { continue };
        let mut r = Reader { buf: slot, at: 0 };
        if r.u32() != Some(MAGIC) {
            continue;
        }
        written = true;
        if let Some(cp) = read_slot(slot) {
            if best.as_ref().is_none_or(|b| cp.generation > b.generation) {
                best = Some(cp);
            }
        }
    }
    match (best, written) {
        (Some(cp), _) => Recovered::Valid(cp),
        (None, true) => Recovered::Corrupt,
        (None, false) => Recovered::Empty,
    }
}

fn read_slot(slot: &[u8]) -> Option<TetherCheckpoint> {
    let mut r = Reader { buf: slot, at: 4 };
    let generation = r.u32()?;
    let root = r.vec3()?;
    let has_body = r.u8()?;
    let position = r.vec3()?;
    let yaw = r.f32()?;
    let payout_m = r.f32()?;
    let goal_id = r.u32()?;
    let has_ground = r.u8()?;
    let mut ground = GroundPatch::empty([r.f32()?, r.f32()?], r.f32()?);
    for h in ground.heights_mm.iter_mut() {
        *h = i16::from_le_bytes(r.take::<2>()?);
    }
    let n = usize::from(r.u8()?);
    if n == 0 || n > ANCHOR_HISTORY_CAPACITY || has_body > 1 || has_ground > 1 {
        return None;
    }
    let mut anchors = AnchorHistory::empty();
    for _ in 0..n {
        let point = r.vec3()?;
        let gradient = r.vec3()?;
        anchors.push(Anchor { point, gradient }).ok()?;
    }
    let end = r.at;
    let crc = r.u32()?;
    if CRC.checksum(slot.get(..end)?) != crc {
        return None;
    }
    // a CRC-valid slot is what this module wrote; finiteness is checked anyway, the planner must never see NaN
    let finite = root.iter().chain(position.iter()).all(|v| v.is_finite()) && yaw.is_finite() && payout_m.is_finite();
    let anchors_finite = anchors.as_slice().iter().all(|a| a.point.iter().chain(a.gradient.iter()).all(|v| v.is_finite()));
    let ground_finite = ground.centre.iter().all(|v| v.is_finite()) && ground.z0.is_finite();
    if !finite || !anchors_finite || !ground_finite {
        return None;
    }
    let body = (has_body == 1).then_some(RetainedPose { position, yaw });
    let ground = (has_ground == 1).then_some(ground);
    Some(TetherCheckpoint { generation, root, anchors, body, payout_m, goal_id, ground })
}

struct Writer<'a> {
    buf: &'a mut [u8],
    at: usize,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) {
        if let Some(dst) = self.buf.get_mut(self.at..self.at + b.len()) {
            dst.copy_from_slice(b);
        }
        self.at += b.len();
    }
    fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }
    fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    fn f32(&mut self, v: Real) {
        self.bytes(&v.to_le_bytes());
    }
    fn vec3(&mut self, v: &Vec3) {
        self.f32(v.x);
        self.f32(v.y);
        self.f32(v.z);
    }
}

struct Reader<'a> {
    buf: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let b = self.buf.get(self.at..self.at + N)?.try_into().ok()?;
        self.at += N;
        Some(b)
    }
    fn u8(&mut self) -> Option<u8> {
        self.take::<1>().map(|[b]| b)
    }
    fn u32(&mut self) -> Option<u32> {
        self.take::<4>().map(u32::from_le_bytes)
    }
    fn f32(&mut self) -> Option<Real> {
        self.take::<4>().map(f32::from_le_bytes)
    }
    fn vec3(&mut self) -> Option<Vec3> {
        Some(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checkpoint(generation: u32, anchors: usize) -> TetherCheckpoint {
        let mut h = AnchorHistory::new(Anchor::root(Vec3::new(6.7, 0.0, 6.35)));
        for i in 1..anchors {
            let _ = h.push(Anchor { point: Vec3::new(i as f32, 0.5, 2.0), gradient: Vec3::new(0.0, 1.0, 0.0) });
        }
        TetherCheckpoint {
            generation,
            root: Vec3::new(6.7, 0.0, 6.35),
            anchors: h,
            body: Some(RetainedPose { position: Vec3::new(1.0, 2.0, 3.0), yaw: 0.25 }),
            payout_m: 7.5,
            goal_id: 2,
            ground: None,
        }
    }

    /// A checkpoint with a ground patch: a 10-degree slope with a hole (cells without ground).
    fn with_ground(generation: u32) -> TetherCheckpoint {
        let mut g = GroundPatch::empty([-3.9, 0.1], 4.35);
        for k in 0..GROUND_PATCH_CELLS {
            let (x, _) = g.cell_xy(k);
            if k % 7 != 3 {
                g.set(k, 4.0 + 0.176 * (x + 3.9));
            }
        }
        TetherCheckpoint { ground: Some(g), ..checkpoint(generation, 4) }
    }

    #[test]
    fn a_fresh_block_is_empty_and_a_written_one_reads_back_exactly() {
        let mut block = [0u8; RETAINED_BYTES];
        assert_eq!(read(&block), Recovered::Empty);
        let cp = checkpoint(5, 3);
        write(&mut block, &cp);
        assert_eq!(read(&block), Recovered::Valid(cp));
        let full = checkpoint(6, ANCHOR_HISTORY_CAPACITY);
        write(&mut block, &full);
        assert_eq!(read(&block), Recovered::Valid(full));
        let ground = TetherCheckpoint { anchors: checkpoint(7, ANCHOR_HISTORY_CAPACITY).anchors, ..with_ground(7) };
        write(&mut block, &ground);
        assert_eq!(read(&block), Recovered::Valid(ground));
    }

    #[test]
    fn a_ground_patch_keeps_its_heights_to_the_millimetre_and_leaves_out_the_cells_without_ground() {
        let cp = with_ground(3);
        let g = cp.ground.as_ref().unwrap();
        let pts: std::vec::Vec<Vec3> = g.points().collect();
        assert_eq!(pts.len(), (0..GROUND_PATCH_CELLS).filter(|k| k % 7 != 3).count());
        for p in &pts {
            assert!((p.z - (4.0 + 0.176 * (p.x + 3.9))).abs() <= 0.0006, "{p:?}");
            assert!((p.x + 3.9).abs() <= 1.0 + 1e-5 && (p.y - 0.1).abs() <= 1.0 + 1e-5);
        }
        // the corners are 1 m from the centre each way
        let (x0, y0) = g.cell_xy(0);
        assert!((x0 + 4.9).abs() < 1e-5 && (y0 + 0.9).abs() < 1e-5, "({x0}, {y0})");
        let mut far = GroundPatch::empty([0.0, 0.0], 0.0);
        far.set(0, 40.0);
        far.set(1, f32::NAN);
        far.set(2, -0.25);
        assert_eq!(&far.heights_mm[..3], &[NO_GROUND, NO_GROUND, -250]);
        // a bit flip in a height is caught by the CRC
        let mut block = [0u8; RETAINED_BYTES];
        write(&mut block, &cp);
        block[SLOT_BYTES + 100] ^= 0x01; // generation 3 is in slot 1; byte 100 is in the patch
        assert_eq!(read(&block), Recovered::Corrupt);
    }

    #[test]
    fn the_newer_slot_wins_and_a_torn_write_leaves_the_older_one() {
        let mut block = [0u8; RETAINED_BYTES];
        let (older, newer) = (checkpoint(7, 2), checkpoint(8, 4));
        write(&mut block, &older);
        write(&mut block, &newer);
        assert_eq!(read(&block), Recovered::Valid(newer.clone()));
        // a reset while generation 9 was being written: slot 1 (generation 7) half overwritten
        let mut torn = block;
        let mut next = [0u8; RETAINED_BYTES];
        write(&mut next, &checkpoint(9, 5));
        torn[SLOT_BYTES..SLOT_BYTES + 40].copy_from_slice(&next[SLOT_BYTES..SLOT_BYTES + 40]);
        assert_eq!(read(&torn), Recovered::Valid(newer));
    }

    #[test]
    fn a_written_block_that_no_slot_reads_back_is_corrupt() {
        let mut block = [0u8; RETAINED_BYTES];
        write(&mut block, &checkpoint(1, 3));
        block[SLOT_BYTES + 20] ^= 0x10; // generation 1 is in slot 1
        assert_eq!(read(&block), Recovered::Corrupt);
        // power-on noise without the magic is a new deployment, not a lost state
        let noise: RetainedBlock = core::array::from_fn(|i| (i * 37 % 251) as u8);
        assert_eq!(read(&noise), Recovered::Empty);
    }
}
