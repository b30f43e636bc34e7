//! The terrain tile on board (issue 20 item 4, protocol v7): an orbital DEM patch uploaded in `TileChunk`s for the
//! homotopy planner ([`crate::plan::homotopy::dem`]).
//!
//! Chunks (in order, checked by the executive's `TileAssembler`) are copied into a **staging** tile; the tile in use
//! ([`HeightTile`]) is replaced only when the last chunk arrived and [`HeightTile::load`] accepts the whole staged
//! tile (shape, spacing, finite heights). An upload that is abandoned (a chunk 0 of another tile), rejected chunk by
//! chunk, or refused at the end leaves the tile in use, and any route planned on it, as they were. Capacities:
//! `MAX_TILE_SIDE` 128 posts a side, `MAX_TILE_CELLS` 16 384 posts (64 KiB of `f32`), spacing
//! `MIN_TILE_RESOLUTION_M` 0.02 m .. `MAX_TILE_RESOLUTION_M` 5 m (`config::homotopy`); staging and tile together
//! 128 KiB of the navigator's planning storage.

use crate::config::homotopy::MAX_TILE_CELLS;
use crate::plan::homotopy::dem::{HeightTile, TileError};
use crate::protocol::TileHeader;

/// Staged and current terrain tile (all zero bytes when empty).
pub struct TileStorage {
    /// Heights of the tile being uploaded, row-major.
    staging: [f32; MAX_TILE_CELLS],
    /// The tile being uploaded and how many posts arrived; empty when none is in progress.
    staged: heapless::Vec<(TileHeader, usize), 1>,
    /// The tile in use (0 x 0 before the first upload).
    pub(crate) tile: HeightTile,
    /// The id of the tile in use (0 before the first).
    pub(crate) tile_id: u32,
}

impl TileStorage {
    /// Empty (const: part of the board's static planning storage).
    pub const fn new() -> Self {
        Self { staging: [0.0; MAX_TILE_CELLS], staged: heapless::Vec::new(), tile: HeightTile::new(), tile_id: 0 }
    }

    /// Stages one chunk's heights at `offset`. Returns the id of a staged tile this chunk 0 abandoned.
    pub fn part(&mut self, header: &TileHeader, offset: usize, heights: &[f32]) -> Option<u32> {
        let mut abandoned = None;
        if offset == 0 {
            abandoned = self.staged.pop().map(|(h, _)| h.tile_id);
            // Capacity 1, just emptied.
            let _ = self.staged.push((*header, 0));
        }
        let Some((h, got)) = self.staged.first_mut() else { return abandoned };
        if h != header || *got != offset {
            // The executive checked the order; a chunk that does not continue the staged tile is dropped whole.
            self.staged.clear();
            return abandoned;
        }
        let end = offset.checked_add(heights.len());
        let Some(dst) = end.and_then(|end| self.staging.get_mut(offset..end)) else {
            self.staged.clear();
            return abandoned;
        };
        for (d, h) in dst.iter_mut().zip(heights) {
            *d = *h;
        }
        *got = end.unwrap_or(offset);
        abandoned
    }

    /// Swaps the staged tile in when it is complete and valid; otherwise the tile in use stays.
    pub fn complete(&mut self, header: &TileHeader) -> Result<(), TileError> {
        let staged = self.staged.pop();
        let got = match staged {
            Some((h, got)) if h == *header => got,
            _ => 0,
        };
        let heights = self.staging.get(..got).unwrap_or(&[]);
        // `load` checks everything before it changes the tile: a short upload is a `Length` error.
        self.tile.load(
            [f64::from(header.origin[0]), f64::from(header.origin[1])],
            f64::from(header.resolution_m),
            usize::from(header.rows),
            usize::from(header.cols),
            heights,
        )?;
        self.tile_id = header.tile_id;
        Ok(())
    }

    /// The tile in use, if one was loaded.
    pub fn current(&self) -> Option<&HeightTile> {
        (self.tile.shape().0 > 0).then_some(&self.tile)
    }
}

impl Default for TileStorage {
    fn default() -> Self {
        Self::new()
    }
}
