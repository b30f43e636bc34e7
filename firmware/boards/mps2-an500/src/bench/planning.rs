//! On-target planning workloads: `workloads::run_all` with static arenas, each workload timed by
//! [`super::measure::measure`] (one iteration each) and its outcome printed as
//! `bench: result name=<workload> summary=<one line>`; the host (`tetherbot board bench`) runs the same workloads
//! and compares the summaries. Finally the stack high-water mark of the whole bench run:
//! `bench: stack_high_water_bytes=<B> stack_size_bytes=<S>`.
//!
//! Then the homotopy phases on the embedded HiRISE tile (`workloads::homotopy_tile`), reusing the BTM and the
//! homotopy workspace.
//!
//! Arenas: all in `.psram` (16 MiB, zeroed at boot, never loaded), so the flight mode's SRAM layout and boot are
//! those of a board without these workloads (the opt-in ledge-with-pole workload's storage is in SRAM's `.uninit`
//! instead: `ledge_pole.rs`). The ABIT* arena (~1.7 MiB) and the scan start all-zero (`Lent`);
//! the local planner, D* Lite arena, BTM and homotopy workspace have non-zero empty states and are initialised in
//! place from their `const` images in flash when the bench takes them (`UninitSlot::take_init`). The local planner
//! and the D* Lite arena are the flight loop's team storage (`storage::TEAM_PLANNER`, `TEAM_DSTAR`), which a bench
//! boot does not use otherwise.

use firmware::geom::Vec3;
use firmware::plan::homotopy::control::ControlGrid;
use firmware::plan::homotopy::{Btm, SearchArena, Workspace};
use workloads::homotopy_tile::{self, TileStorage, CELLS};
use workloads::{Arenas, WallGapArena, SCAN_POINTS};

use super::measure::Board;
use crate::clock::SysTickClock;
use crate::storage::{ConstInit, Lent, UninitSlot, TEAM_DSTAR, TEAM_PLANNER};

impl ConstInit for Btm {
    const INIT: Self = Btm::new();
}
impl ConstInit for Workspace {
    const INIT: Self = Workspace {
        search: SearchArena::new(),
        grid: ControlGrid::new(),
        classes: heapless::Vec::new(),
    };
}

// The ABIT* arena's empty state is all zero bytes (empty `heapless` vectors): a plain `Lent` in `.psram`.
#[link_section = ".psram"]
static ABIT: Lent<WallGapArena> = Lent::new(WallGapArena::new());
#[link_section = ".psram"]
static SCAN: Lent<[Vec3; SCAN_POINTS]> = Lent::new([Vec3::new(0.0, 0.0, 0.0); SCAN_POINTS]);
// The local planner and D* Lite arena are the flight loop's team storage (`storage::TEAM_PLANNER`, `TEAM_DSTAR`):
// a bench boot never runs the flight loop.
#[link_section = ".psram"]
static BTM: UninitSlot<Btm> = UninitSlot::new();
#[link_section = ".psram"]
static HOMOTOPY: UninitSlot<Workspace> = UninitSlot::new();

// The homotopy tile workloads: the tile and the segmentation scratch (all zero bytes when empty), the heights decoded
// from the embedded tile (the HiRISE scarp tile of `mission_homotopy_hirise.toml`, little-endian f32, written by
// `tests/tests/board_homotopy_tile.rs`; a wrong size does not compile).
#[link_section = ".psram"]
static TILE: Lent<TileStorage> = Lent::new(TileStorage::new());
#[link_section = ".psram"]
static TILE_HEIGHTS: Lent<[f32; CELLS]> = Lent::new([0.0; CELLS]);
static TILE_BYTES: &[u8; CELLS * 4] = include_bytes!("../../data/hirise_tile_80x80.f32le");

/// Runs the planning workloads (once; a second call finds the arenas taken and does nothing).
pub fn run(clock: &mut SysTickClock) {
    let (Some(abit), Some(local), Some(scan), Some(dstar), Some(btm), Some(homotopy)) = (
        ABIT.take(),
        TEAM_PLANNER.take_init(),
        SCAN.take(),
        TEAM_DSTAR.take_init(),
        BTM.take_init(),
        HOMOTOPY.take_init(),
    ) else {
        return;
    };
    let mut arenas = Arenas {
        abit,
        local,
        scan,
        dstar,
        btm,
        homotopy,
    };
    let mut board = Board {
        clock,
        iterations: 1,
    };
    workloads::run_all(&mut arenas, &mut board);
    let (Some(tile), Some(heights)) = (TILE.take(), TILE_HEIGHTS.take()) else {
        return;
    };
    for (h, b) in heights.iter_mut().zip(TILE_BYTES.chunks_exact(4)) {
        if let [b0, b1, b2, b3] = *b {
            *h = f32::from_le_bytes([b0, b1, b2, b3]);
        }
    }
    homotopy_tile::run(
        tile,
        arenas.btm,
        arenas.homotopy,
        heights.as_slice(),
        &mut board,
    );
}
