//! Static storage lent to the flight core.
//!
//! The core never allocates: every arena is owned by its caller and lent as `&mut`. On the board the owner is a
//! `static`, handed out exactly once as `&'static mut` by [`Lent::take`]. This is the only place the board
//! creates a mutable reference to a static, and the `taken` flag makes a second one impossible.

use core::cell::UnsafeCell;
use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicBool, Ordering};

use firmware::config::team::GLOBAL_GRID_MAX_CELLS;
use firmware::exec::ExecStorage;
use firmware::plan::team::dstar_lite::DStarArena;
use firmware::plan::team::DefaultLocalPlanner;
use firmware::nav::retained::{RetainedBlock, RETAINED_BYTES};

/// The executive's large buffers (scan reassembly, plan), lent once: to the flight loop, or in bench mode to the
/// executive benchmark. ~130 KiB of `.bss` in SRAM.
pub static EXEC_STORAGE: Lent<ExecStorage> = Lent::new(ExecStorage::new());

/// The climbing team's local planner (`DefaultLocalPlanner`, ~0.6 MiB) and D* Lite arena over the scenes
/// (`GLOBAL_GRID_MAX_CELLS` = 4096, ~190 KiB), in `.psram`, initialised in place when taken: the flight loop lends
/// them to the executive's team mission (`firmware::exec::TeamLend`), or in bench mode the planning workloads take
/// them. The mode is chosen at boot, so one memory serves both.
#[link_section = ".psram"]
pub static TEAM_PLANNER: UninitSlot<DefaultLocalPlanner> = UninitSlot::new();
#[link_section = ".psram"]
pub static TEAM_DSTAR: UninitSlot<DStarArena<GLOBAL_GRID_MAX_CELLS>> = UninitSlot::new();

impl ConstInit for DefaultLocalPlanner {
    const INIT: Self = DefaultLocalPlanner::new();
}
impl ConstInit for DStarArena<GLOBAL_GRID_MAX_CELLS> {
    const INIT: Self = DStarArena::new();
}

/// The tether checkpoint's block (`firmware::nav::retained`, ~1.6 KiB) in SRAM's `.uninit`: neither loaded nor
/// zeroed at boot, and not reloaded by QEMU's system reset (the watchdog-reset probe's mark shows it survives), so
/// what the flight software wrote before a reset is there after it. Power-on content is whatever the RAM holds
/// (zeros on the emulator); the checkpoint's magic and CRC tell it from a checkpoint.
#[link_section = ".uninit.tether_retained"]
static mut RETAINED: MaybeUninit<RetainedBlock> = MaybeUninit::uninit();
static RETAINED_TAKEN: AtomicBool = AtomicBool::new(false);

/// The retained block, lent once (`None` the second time).
pub fn take_retained() -> Option<&'static mut RetainedBlock> {
    if RETAINED_TAKEN.swap(true, Ordering::AcqRel) {
        return None;
    }
    let p = core::ptr::addr_of_mut!(RETAINED).cast::<u8>();
    // SAFETY: the flag makes this the only reference ever made to the static, which lives for the program. Each
    // byte is read and written back (volatile, so neither is elided) before the reference exists: the memory then
    // holds defined bytes (the last boot's checkpoint or power-on content), which any `[u8; N]` may.
    unsafe {
        for i in 0..RETAINED_BYTES {
            let b = core::ptr::read_volatile(p.add(i));
            core::ptr::write_volatile(p.add(i), b);
        }
        Some(&mut *core::ptr::addr_of_mut!(RETAINED).cast::<RetainedBlock>())
    }
}

/// A static value that can be borrowed mutably once, for the rest of the program.
pub struct Lent<T> {
    taken: AtomicBool,
    value: UnsafeCell<T>,
}

// SAFETY: the value is reachable only through the single `&'static mut` that `take` hands out (guarded by the
// atomic flag), so sharing the `Lent` itself between contexts cannot create aliasing access to `T`.
unsafe impl<T: Send> Sync for Lent<T> {}

impl<T> Lent<T> {
    /// Wraps the initial value (a `const` initialiser, so the value lives in `.bss` / `.data`, never on the stack).
    pub const fn new(value: T) -> Self {
        Self {
            taken: AtomicBool::new(false),
            value: UnsafeCell::new(value),
        }
    }

    /// The one mutable borrow; `None` if it was already taken.
    // `mut_from_ref` is the point of this type: the atomic flag makes the returned borrow unique.
    #[allow(clippy::mut_from_ref)]
    pub fn take(&'static self) -> Option<&'static mut T> {
        if self.taken.swap(true, Ordering::AcqRel) {
            return None;
        }
        // SAFETY: the flag was false, so no other reference to the value exists, and it is now true forever, so
        // none will be created later. The static lives for the whole program.
        Some(unsafe { &mut *self.value.get() })
    }
}

/// A value with a compile-time initial state (the empty arena), copied into an [`UninitSlot`] on first use.
pub trait ConstInit: Sized {
    /// The initial value.
    const INIT: Self;
}

/// A static that starts uninitialised and is lent once, initialised in place when taken, so a boot pays only for the
/// arenas its mode takes (the flight loop's or the benchmarks'):
/// - in `.psram` (NOLOAD, zeroed at boot) for a value whose initial state is not all zero bytes:
///   [`UninitSlot::take_init`] writes `T::INIT` into it from its `const` image in flash (`.rodata`) — a `memcpy`,
///   not a stack temporary (checked by the bench run's stack high-water mark);
/// - in SRAM's `.uninit` (NOLOAD: neither loaded nor zeroed at boot) for an arena too big for what `.psram` has
///   left: [`UninitSlot::take_zeroed`] zeroes it in place (`write_bytes`: no stack temporary, no flash image).
pub struct UninitSlot<T> {
    taken: AtomicBool,
    value: UnsafeCell<MaybeUninit<T>>,
}

// SAFETY: as for `Lent`: the memory is reachable only through the single `&'static mut` handed out by `claim`.
unsafe impl<T: Send> Sync for UninitSlot<T> {}

impl<T> UninitSlot<T> {
    /// An unused slot (all-zero bytes, as `.psram` requires).
    pub const fn new() -> Self {
        Self {
            taken: AtomicBool::new(false),
            value: UnsafeCell::new(MaybeUninit::uninit()),
        }
    }

    /// The slot's memory, once; `None` if it was already claimed.
    #[allow(clippy::mut_from_ref)]
    fn claim(&'static self) -> Option<&'static mut MaybeUninit<T>> {
        if self.taken.swap(true, Ordering::AcqRel) {
            return None;
        }
        // SAFETY: the flag was false, so no reference to the memory exists, and it is now true forever, so none
        // will be created later. The static lives for the whole program.
        Some(unsafe { &mut *self.value.get() })
    }

    /// The one mutable borrow, initialised to `T::INIT`; `None` if it was already taken.
    #[allow(clippy::mut_from_ref)] // unique: `claim`
    pub fn take_init(&'static self) -> Option<&'static mut T>
    where
        T: ConstInit,
    {
        let slot = self.claim()?;
        // SAFETY: the slot is valid, aligned memory for a `T` (a static of `MaybeUninit<T>`); after the write it
        // holds an initialised `T`. (A raw write of the constant: no stack temporary of a large `T`.)
        unsafe {
            slot.as_mut_ptr().write(T::INIT);
            Some(slot.assume_init_mut())
        }
    }

    /// The one mutable borrow, zeroed (the empty `T`); `None` if it was already taken.
    #[cfg(feature = "bench")]
    #[allow(clippy::mut_from_ref)] // unique: `claim`
    pub fn take_zeroed(&'static self) -> Option<&'static mut T>
    where
        T: ZeroIsEmpty,
    {
        let slot = self.claim()?;
        // SAFETY: the slot is valid, aligned memory for a `T`; `write_bytes` zeroes all of it, and
        // `T: ZeroIsEmpty` promises that all-zero bytes are a valid `T`.
        unsafe {
            core::ptr::write_bytes(slot.as_mut_ptr(), 0, 1);
            Some(slot.assume_init_mut())
        }
    }
}

extern "C" {
    static mut __spsram: u64;
    static mut __epsram: u64;
}

/// Zeroes the `.psram` section (see `memory.x`): statics placed there with `#[link_section = ".psram"]` must have
/// an all-zero initial value (or be an [`UninitSlot`]). Called once at boot, before anything in `.psram` is used.
/// Holds the benchmark's planning arenas (`bench/planning.rs`); the executive's storage (132 KiB) stays in SRAM.
pub fn zero_psram() {
    let start = core::ptr::addr_of_mut!(__spsram);
    let end = core::ptr::addr_of_mut!(__epsram);
    let mut p = start;
    while p < end {
        // SAFETY: [__spsram, __epsram) is the 8-aligned `.psram` output section in PSRAM (memory.x), which no
        // code has touched yet at boot; writing zeros there is what the section's contract promises.
        unsafe {
            core::ptr::write_volatile(p, 0);
            p = p.add(1);
        }
    }
}

#[cfg(feature = "bench")]
/// A type whose all-zero bit pattern is a valid (empty) value: empty `heapless` containers and the arenas made of
/// them. Implementing it is a promise that [`UninitSlot::take_zeroed`] may zero the bytes and use them as a `T`.
///
/// # Safety
/// Every field of the type (recursively) must accept all-zero bytes as a valid value.
pub unsafe trait ZeroIsEmpty {}
