//! Stack high-water marks from the paint: the flight stack's, left by cortex-m-rt's `paint-stack` feature, and
//! the handler stack's, painted by `stack_guard::run_on_process_stack` at boot.
//!
//! At reset, before `main`, the runtime fills `[_stack_end, _stack_start)` (the top `_stack_size` bytes of RAM,
//! see `memory.x`) with `0xCCCC_CCCC`. The stack grows down from `_stack_start`; the lowest word that no longer
//! holds the paint marks the deepest the stack has been. A frame that happens to store `0xCCCC_CCCC` at its
//! deepest word would hide 4 bytes: the figure is exact to within that. The guard region below `_stack_end`
//! (`stack_guard.rs`) is not painted and never read here: reading it would fault.
//!
//! Thread mode runs on the flight stack; exceptions run on the handler stack (`stack_guard.rs`), but each
//! exception entry in thread mode still pushes its frame (up to 104 bytes with the FPU state) onto the flight
//! stack, so the flight figure includes the deepest interrupt frame.

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

/// The flight (thread-mode) stack.
pub fn usage() -> StackUsage {
    // Only the addresses of the linker symbols are taken; their contents are never read through them.
    scan(addr_of!(_stack_end) as usize, addr_of!(_stack_start) as usize)
}

/// The handler (exception) stack.
pub fn handler_usage() -> StackUsage {
    let (low, high) = crate::stack_guard::handler_stack();
    scan(low, high)
}

/// Scans a painted region `[low, high)` from its low end (a bounded loop: `(high - low) / 4` words).
fn scan(low: usize, high: usize) -> StackUsage {
    let size_bytes = high.saturating_sub(low);
    let mut untouched_words = 0usize;
    let mut addr = low;
    while addr < high {
        // SAFETY: `addr` lies in one of the two stack regions memory.x reserves ([_stack_end, _stack_start) or
        // [_handler_stack_end, _handler_stack_start)), 4-aligned (memory.x and cortex-m-rt align them), outside
        // the MPU guard. Reading stack memory below a stack pointer is harmless.
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
