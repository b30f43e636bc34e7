//! The stack guard: an overflow of the flight stack faults on the instruction that overflows, with a report.
//!
//! ARMv7-M has no stack-limit register (ARMv8-M's `MSPLIM` / `PSPLIM`), so the Cortex-M7's MPU (PMSAv7, 8
//! regions on the M7 and in QEMU's model) does it: one region, [`_stack_guard_start`, `_stack_end`) right below
//! the painted stack (`memory.x`; default 128 KiB), is no-access and execute-never for all code. Every other
//! address keeps the default memory map (`PRIVDEFENA`; the board runs privileged). A push, a spill or an
//! exception frame that lands in the guard raises MemManage (`SCB.SHCSR.MEMFAULTENA`, enabled here) before a
//! byte of `.bss` or `.uninit` is corrupted.
//!
//! **Two stacks.** A fault handler needs a stack of its own: on an overflow the thread's stack pointer already
//! points into the guard, and a handler that pushed there would fault again (a lockup). So thread mode (the
//! flight loop, the executive, the benchmarks) runs on the process stack (PSP) in the painted 256 KiB region, and
//! exceptions run on the main stack (MSP): a separate 16 KiB region below the guard (`_handler_stack_start`, also
//! painted, its high-water mark reported at quit). [`run_on_process_stack`] makes the switch once, first thing in
//! `main`. When an overflow hits the guard the MemManage handler (`fault.rs`) runs on the handler stack and prints
//! `board: STACK OVERFLOW ...`; if the fault escalated to HardFault (it does while `PRIMASK` is set, as in the
//! idle loop's critical section), the HardFault handler recognises it from the same status registers and prints
//! the same report. Either way the run ends with exit status 1.
//!
//! **Why 128 KiB.** A function whose frame is larger than the guard could move the stack pointer past the guard
//! in one step and write below it without touching it. The largest frame in the binary (the sum of the `sub sp`
//! immediates of one function in the disassembly) is `firmware::stability::check_stability`'s, 65 956 B,
//! measured 2026-12-02 in the flight and the test build: a 64 KiB guard would not do. `.ci/run` fails when a
//! frame reaches the guard's size (`tools/max-frame.sh`; no function sets `sp` from a register, which that
//! check would miss, and it reports any that does). The guard costs 128 KiB of the ~1.2 MiB of SRAM left
//! between `.uninit` and the stacks. The MPU requires a region's base to be aligned to its size (power of two,
//! at least 32 B); `memory.x` asserts both.
//!
//! The stack paint (`stack.rs`, cortex-m-rt's `paint-stack`) covers [`_stack_end`, `_stack_start`) only, so the
//! high-water scan never reads the guard; the paint is written at reset, before the MPU is on.
//!
//! What it does not cover: an overflow of the handler stack itself (handlers are small: the reports, SysTick,
//! the UART wake-up; its high-water mark is reported with the flight stack's), and a single frame larger than
//! the guard (none in this binary).

use core::ptr::addr_of;

use cortex_m::peripheral::{scb::Exception, MPU, SCB};

extern "C" {
    static _stack_start: u32;
    static _stack_end: u32;
    static _stack_guard_start: u32;
    static _handler_stack_start: u32;
    static _handler_stack_end: u32;
}

/// MPU_RASR: execute-never.
const RASR_XN: u32 = 1 << 28;
/// MPU_RASR.AP = 0b000: no access, privileged or not.
const RASR_AP_NO_ACCESS: u32 = 0b000 << 24;
/// MPU_RASR: region enabled.
const RASR_ENABLE: u32 = 1;
/// MPU_CTRL: MPU on, default memory map for privileged accesses outside the regions; off in HardFault and NMI
/// (`HFNMIENA` = 0) so the fault reports can read anything.
const CTRL_ENABLE_PRIVDEFENA: u32 = 0b101;
/// The MPU region number of the guard.
const GUARD_REGION: u32 = 0;
/// MemManage fault status bits (CFSR[7:0]).
const MMFSR_DACCVIOL: u32 = 1 << 1;
const MMFSR_MSTKERR: u32 = 1 << 4;
const MMFSR_MLSPERR: u32 = 1 << 5;
const MMFSR_MMARVALID: u32 = 1 << 7;

/// The guard region `[start, end)`: the bytes right below the flight stack.
pub fn guard() -> (usize, usize) {
    // Only the addresses of the linker symbols are taken (memory.x).
    (
        addr_of!(_stack_guard_start) as usize,
        addr_of!(_stack_end) as usize,
    )
}

/// The handler (main) stack `[end, start)`: below the guard, painted at boot by [`run_on_process_stack`].
pub fn handler_stack() -> (usize, usize) {
    (
        addr_of!(_handler_stack_end) as usize,
        addr_of!(_handler_stack_start) as usize,
    )
}

/// Why the guard could not be enabled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GuardError {
    /// MPU_TYPE reports no data regions: no MPU on this core.
    NoMpu,
    /// The linker symbols do not describe a region the MPU can hold (size not a power of two >= 32 B, or base not
    /// aligned to it); memory.x asserts this, so only a changed linker script gets here.
    BadRegion {
        /// Guard base.
        start: usize,
        /// Guard end.
        end: usize,
    },
}

/// Programs the guard region and turns the MPU and the MemManage exception on.
pub fn enable(mpu: &mut MPU, scb: &mut SCB) -> Result<(), GuardError> {
    if (mpu._type.read() >> 8) & 0xFF == 0 {
        return Err(GuardError::NoMpu);
    }
    let (start, end) = guard();
    let size = end.saturating_sub(start);
    if size < 32 || !size.is_power_of_two() || start % size != 0 {
        return Err(GuardError::BadRegion { start, end });
    }
    // RASR.SIZE: the region is 2^(SIZE + 1) bytes.
    let size_field = size.trailing_zeros().saturating_sub(1);
    // SAFETY: region 0 becomes a no-access region over the guard, memory nothing else uses (memory.x reserves
    // it between `.uninit` and the handler stack on one side and the flight stack on the other); all other
    // addresses keep the default map. The barriers make the new map take effect before the next access.
    unsafe {
        mpu.ctrl.write(0);
        mpu.rnr.write(GUARD_REGION);
        mpu.rbar.write(start as u32);
        mpu.rasr
            .write(RASR_XN | RASR_AP_NO_ACCESS | (size_field << 1) | RASR_ENABLE);
        mpu.ctrl.write(CTRL_ENABLE_PRIVDEFENA);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
    scb.enable(Exception::MemoryManagement);
    Ok(())
}

/// The fault status that shows a stack overflow into the guard: a data access in the guard (MMFAR valid and in
/// it), or an exception entry that could not push its frame onto the process stack (MSTKERR, or MLSPERR for
/// the lazily stacked FPU registers) while the stack pointer is in or below the guard.
pub fn is_overflow(cfsr: u32, mmfar: u32, psp: u32) -> bool {
    let (start, end) = guard();
    let in_guard = |a: u32| (start..end).contains(&(a as usize));
    let data = cfsr & (MMFSR_MMARVALID | MMFSR_DACCVIOL) == (MMFSR_MMARVALID | MMFSR_DACCVIOL)
        && in_guard(mmfar);
    let stacking = cfsr & (MMFSR_MSTKERR | MMFSR_MLSPERR) != 0 && (psp as usize) < end;
    data || stacking
}

/// The paint of the handler stack (cortex-m-rt paints only the flight stack).
const PAINT: u32 = 0xCCCC_CCCC;

/// Paints the handler stack, then moves thread mode to the process stack at the top of the flight stack region,
/// points the main (handler) stack at its own region, and jumps to `entry`.
///
/// # Safety
/// Call once, first thing in `main`, with no data on the current stack that anyone needs later: the process
/// stack starts at `_stack_start`, where cortex-m-rt's reset code and `main` have their (abandoned) frames.
pub unsafe fn run_on_process_stack(entry: extern "C" fn() -> !) -> ! {
    let (low, high) = handler_stack();
    let mut addr = low;
    while addr < high {
        // SAFETY: [low, high) is the handler stack reserved by memory.x, 4-aligned, unused until the switch
        // below (exceptions still run on the reset stack at the top of the flight stack region).
        unsafe { core::ptr::write_volatile(addr as *mut u32, PAINT) };
        addr += 4;
    }
    let psp = addr_of!(_stack_start) as usize;
    let control = cortex_m::register::control::read().bits() | 0b10; // SPSEL: thread mode uses PSP
    // SAFETY: `psp` and `high` are 8-aligned stack tops (memory.x); after `msr CONTROL` + `isb` thread mode runs
    // on PSP, so writing MSP moves only the stack exceptions use, which holds no frame at this point (no
    // exception is active in thread mode). `entry` never returns.
    unsafe {
        core::arch::asm!(
            "msr PSP, {psp}",
            "msr CONTROL, {control}",
            "isb",
            "msr MSP, {msp}",
            "blx {entry}",
            psp = in(reg) psp,
            control = in(reg) control,
            msp = in(reg) high,
            entry = in(reg) entry,
            options(noreturn),
        )
    }
}

/// Recurses with a 1 KiB frame until the stack runs into the guard (the boot probe `tetherbot.probe=stack`).
/// Returns only if nothing trapped the overflow within `(stack + guard) / 1 KiB + 16` frames: the caller
/// reports that as a failure.
#[cfg(feature = "test-probes")]
pub fn overflow_probe() -> u32 {
    let (start, _) = guard();
    let top = addr_of!(_stack_start) as usize;
    let limit = u32::try_from(top.saturating_sub(start) / 1024 + 16).unwrap_or(u32::MAX);
    recurse(0, limit)
}

#[cfg(feature = "test-probes")]
#[inline(never)]
fn recurse(depth: u32, limit: u32) -> u32 {
    // A 1 KiB local the optimiser must keep (black_box), and work after the call, so no tail call.
    let frame = core::hint::black_box([depth as u8; 1024]);
    if depth >= limit {
        return depth;
    }
    let deeper = recurse(depth.saturating_add(1), limit);
    let frame = core::hint::black_box(frame);
    deeper.max(u32::from(frame.first().copied().unwrap_or(0)))
}
