//! Fuzz target: the retained tether checkpoint's reader (`firmware::nav::retained::read`), fed the block a boot
//! finds (power-on noise, a torn write, a corrupted slot). Must never panic; a checkpoint it accepts must be finite,
//! hold at least the root anchor, and come back unchanged when written to a fresh block and read again.
#![no_main]

use firmware::nav::retained::{read, write, Recovered, RETAINED_BYTES};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut block = [0u8; RETAINED_BYTES];
    let n = data.len().min(RETAINED_BYTES);
    block[..n].copy_from_slice(&data[..n]);
    if let Recovered::Valid(cp) = read(&block) {
        assert!(!cp.anchors.is_empty());
        assert!(cp.root.iter().all(|v| v.is_finite()) && cp.payout_m.is_finite());
        let mut again = [0u8; RETAINED_BYTES];
        write(&mut again, &cp);
        assert_eq!(read(&again), Recovered::Valid(cp));
    }
});
