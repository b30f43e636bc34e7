//! Fuzz target: the terrain-tile reader on board (protocol v7): arbitrary bytes into the deframer and the decoder,
//! and every `TileChunk` that decodes through what the executive does with it: validation (`Validate`), in-order
//! reassembly (`protocol::TileAssembler`), staging in the navigator (`Autonomy::tile_part`) and, at the last chunk,
//! the load (`Autonomy::tile_complete`, `HeightTile::load`). Must never panic; a completed tile the load accepts is
//! the tile in use, and one it refuses leaves the tile in use (its id) as it was.
#![no_main]

use firmware::config::map::MapConfig;
use firmware::exec::Autonomy;
use firmware::map::Block;
use firmware::nav::Navigator;
use firmware::protocol::{decode_frame, Deframer, Message, TileAssembler, Validate};
use hal::Instant;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(mut nav) = Navigator::new(MapConfig::with_voxel_size(0.1), vec![Block::EMPTY; 16], vec![0u32; 64], Box::default())
    else {
        return;
    };
    let mut assembler = TileAssembler::new();
    let mut d = Deframer::new();
    let now = Instant::from_micros(0);
    let mut rest = data;
    while !rest.is_empty() {
        let (n, ev) = d.push(rest);
        rest = &rest[n..];
        let Some(Ok(frame)) = ev else { continue };
        let Ok((_, Message::TileChunk(c))) = decode_frame(frame) else { continue };
        if c.validate().is_err() {
            continue;
        }
        let Ok(a) = assembler.accept(&c) else { continue };
        nav.tile_part(&a.header, a.offset, &c.heights, now);
        if a.complete {
            let before = nav.map_status().tile_id;
            match nav.tile_complete(&a.header, now) {
                Ok(()) => assert_eq!(nav.map_status().tile_id, a.header.tile_id),
                Err(_) => assert_eq!(nav.map_status().tile_id, before, "a refused tile changed the tile in use"),
            }
        }
    }
});
