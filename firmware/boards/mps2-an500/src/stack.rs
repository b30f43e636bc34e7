//! Stack high-water mark from the paint left by cortex-m-rt's `paint-stack` feature.
//!
//! At reset, before `main`, the runtime fills `[_stack_end, _stack_start)` (the top `_stack_size` bytes of RAM,
//! see `memory.x`) with `0xCCCC_CCCC`. The stack grows down from `_stack_start`; the lowest word that no longer
//! holds the paint marks the deepest the stack has been. A frame that happens to store `0xCCCC_CCCC` at its
//! deepest word would hide 4 bytes: the figure is exact to within that.

use core::ptr::{addr_of, read_volatile};

const PAINT: u32 = 0xCCCC_CCCC;

extern "C" {
    static _stack_start: u32;
    static _stack_end: u32;
}

/// Stack use measured from the paint.
#[derive(Debug, Clone, Copy)]
pub struct StackUsage {
    /// Deepest use since reset, bytes.
    pub high_water_bytes: usize,
    /// Size of the stack region, bytes.
    pub size_bytes: usize,
}

/// Scans the painted region from its low end (a bounded loop: `size_bytes / 4` words).
pub fn usage() -> StackUsage {
    // Only the addresses of the linker symbols are taken; their contents are never read through them.
    let (low, high) = (
        addr_of!(_stack_end) as usize,
        addr_of!(_stack_start) as usize,
    );
    let size_bytes = high.saturating_sub(low);
    let mut untouched_words = 0usize;
    let mut addr = low;
    while addr < high {
        // SAFETY: `addr` lies in [_stack_end, _stack_start), RAM reserved for the stack by memory.x, 4-aligned
        // (both symbols are aligned by cortex-m-rt's linker script). Reading stack memory below the current
        // stack pointer is harmless.
        let word = unsafe { read_volatile(addr as *const u32) };
        if word != PAINT {
            break;
        }
        untouched_words += 1;
        addr += 4;
    }
    StackUsage {
        high_water_bytes: size_bytes.saturating_sub(untouched_words * 4),
        size_bytes,
    }
}
