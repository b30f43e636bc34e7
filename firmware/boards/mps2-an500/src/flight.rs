//! The flight loop on the board: UART0 bytes in, the flight executive (`firmware::exec`), UART0 bytes out.
//!
//! ## Two clocks
//! - **Free-running** (default, as in flight): the executive reads the SysTick clock and is stepped continuously;
//!   when a step reports no work the core sleeps (`wfi`) until a UART byte or the 1 ms SysTick wakes it. Its first
//!   step sends the boot `Telemetry` frame, the protocol's ready frame (`firmware/PROTOCOL.md`).
//! - **Lockstep** (boot word `tetherbot.clock=lockstep`): the host steps the executive over the control port on
//!   the host's simulated clock, the way the in-process link does (one `step` per period, bytes delivered at step
//!   boundaries). Output bytes then depend only on input bytes and step times, so the same run gives the same
//!   bytes in-process and on the board: the equivalence test. The watchdog allows 30 s instead of 2 s here
//!   (`watchdog::LOCKSTEP_TIMEOUT_TICKS`: the emulator's clock follows a possibly loaded host's wall clock).
//!
//! ## Control port (UART1; test harness only, never the flight protocol). All integers little-endian.
//! - board -> host at boot: `H` (hello, 1 byte): the handshake; the host sends nothing before it.
//! - host -> board `R` (run, 22 bytes): `R`, `announced: u32` (protocol bytes the host wrote to UART0 since the
//!   last `R`), `t_start_us: u64`, `step_us: u32`, `max_steps: u32`, `until_quiet: u8`. The board runs at most
//!   `max_steps` steps at `t_start_us + k * step_us`, stopping early after a step that reports no work when
//!   `until_quiet` is 1, and answers
//! - board -> host `D` (done, 10 bytes): `D`, `steps: u32`, `busy: u8` (of the last step), `tx: u32` (protocol
//!   bytes written to UART0 during the run, which the host then reads).
//! - host -> board `Q` (quit, 1 byte, both clocks): the board prints its resource report over semihosting
//!   (`board: stack_high_water_bytes=... ...`) and exits QEMU with status 0.
//! - host -> board `B` (reboot, 1 byte, both clocks; between runs): the board requests a system reset
//!   (SYSRESETREQ), as a watchdog bite does; it boots again and says `H`. The tether checkpoint in `.uninit`
//!   (`storage::take_retained`, `firmware::nav::retained`) survives: the rebooted flight software recovers it.
//! - host -> board `W` (watchdog bite, 1 byte, both clocks, test builds only): the flight loop stops kicking the
//!   watchdog (`watchdog::stop_kicking`); its interrupt, then its reset output reboot the board, which prints
//!   `board: REBOOTED by the watchdog's reset output` and says `H`. The checkpoint survives as for `B`.
//!
//! In lockstep the executive's link behaves like the in-process byte queue: `read` returns exactly the announced
//! bytes not yet consumed (waiting for them to cross the emulated UART, they are already sent) and `write` takes
//! everything. Any control byte other than `R` / `Q` is a harness bug: reported, failure exit.

use cortex_m::peripheral::NVIC;
use cortex_m_semihosting::debug;
use firmware::config::map::{MapConfig, FLIGHT_BLOCKS, FLIGHT_INDEX};
use firmware::config::protocol::TEAM_SCAN_POINTS_CAPACITY;
use firmware::exec::{ExecStorage, Executive, TeamLend};
use firmware::geom::Vec3;
use firmware::plan::team::mission::DefaultTeamMission;
use firmware::map::Block;
use firmware::nav::{HomotopyStorage, NavPlanStorage, Navigator};
use hal::{ByteLink, Instant};

use crate::clock::{BoardClock, SysTickClock, INSTRUCTIONS_PER_TICK};
use crate::storage::{take_retained, Lent, EXEC_STORAGE, TEAM_DSTAR, TEAM_PLANNER};
use firmware::exec::Autonomy;
use firmware::nav::retained::RetainedBlock;
use crate::uart::{Uart, UART0_BASE, UART1_BASE, UART_IRQS};
use crate::watchdog::{CmsdkWatchdog, LOCKSTEP_TIMEOUT_TICKS, TIMEOUT_TICKS};

/// The onboard map's block pool (`FLIGHT_BLOCKS` blocks, ~14 MiB) and index, in PSRAM: the `.psram` section is
/// NOLOAD and zeroed at boot (`storage::zero_psram`), hence the all-zero initial values.
#[link_section = ".psram"]
static MAP_BLOCKS: Lent<[Block; FLIGHT_BLOCKS]> = Lent::new([Block::ZEROED; FLIGHT_BLOCKS]);
#[link_section = ".psram"]
static MAP_INDEX: Lent<[u32; FLIGHT_INDEX]> = Lent::new([0; FLIGHT_INDEX]);

/// The navigator's planning storage (the ABIT* arena, the suspended search, the best path, the terrain tile and its
/// staging copy; `NavPlanStorage::bytes()`, ~1.1 MiB) in SRAM: the PSRAM is nearly full with the map's pool and the
/// bench's arenas. Measured on the panic-never flight build of 2026-12-04 (`llvm-nm -S`): 1 163 336 B, in `.data`
/// (its empty state has 8 non-zero bytes, two 0xFFFFFFFF words, so it is not a `.bss` value).
static NAV_PLAN: Lent<NavPlanStorage> = Lent::new(NavPlanStorage::new());

/// The global planner's storage (homotopy goals on an uploaded tile, `HomotopyStorage`, ~0.66 MiB) in SRAM: its
/// empty BTM and A* arena are not all zero bytes, so it is in `.data` (its image in flash).
static NAV_HOMOTOPY: Lent<HomotopyStorage> = Lent::new(HomotopyStorage::new());

/// The climbing team's scan reassembly (all zero bytes when empty: `.psram`) and the team mission itself (~7 KiB;
/// its empty `Option` is not all zero bytes: SRAM). With `storage::TEAM_PLANNER` and `TEAM_DSTAR` they are the
/// executive's team storage (`firmware::exec::TeamLend`), lent once at boot; one lending serves mission after
/// mission.
#[link_section = ".psram"]
static TEAM_POINTS: Lent<[Vec3; TEAM_SCAN_POINTS_CAPACITY]> = Lent::new([Vec3::new(0.0, 0.0, 0.0); TEAM_SCAN_POINTS_CAPACITY]);
static TEAM_MISSION: Lent<Option<DefaultTeamMission<'static>>> = Lent::new(None);

/// The flight software's autonomy, the same as the host's in-process `FlightAutonomy` (so outputs are equal).
type BoardAutonomy =
    Navigator<&'static mut [Block], &'static mut [u32], &'static mut NavPlanStorage, &'static mut HomotopyStorage>;

/// Bytes of an `R` command after its tag.
const RUN_LEN: usize = 21;

#[derive(Clone, Copy)]
struct Irq(u16);
// SAFETY: the numbers are the mps2-an500's UART0/UART1 RX/TX lines, valid NVIC interrupt numbers (< 240).
unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

/// The executive's link: UART0, gated in lockstep (see the module docs).
pub struct BoardLink {
    uart: Uart,
    /// Lockstep only: announced protocol bytes not yet read by the executive.
    gate: Option<u64>,
    /// Bytes written since the last `R` (lockstep accounting).
    written: u64,
}

impl ByteLink for BoardLink {
    type Error = crate::uart::UartError;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        let Some(available) = self.gate else {
            return self.uart.read(buf);
        };
        let want = buf
            .len()
            .min(usize::try_from(available).unwrap_or(usize::MAX));
        let mut got = 0;
        // The announced bytes were written by the host before its `R`; they are crossing the emulated UART. The
        // watchdog bounds this wait: a byte that never comes is a harness fault and bites.
        while got < want {
            got += self.uart.read(buf.get_mut(got..want).unwrap_or(&mut []))?;
        }
        self.gate = Some(available - got as u64);
        Ok(got)
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        if self.gate.is_none() {
            let n = self.uart.write(buf)?;
            self.written += n as u64;
            return Ok(n);
        }
        let mut sent = 0;
        while sent < buf.len() {
            sent += self.uart.write(buf.get(sent..).unwrap_or(&[]))?;
        }
        self.written += sent as u64;
        Ok(sent)
    }

    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        match self.gate {
            Some(available) => Ok(available > 0),
            None => self.uart.read_ready(),
        }
    }

    fn write_ready(&mut self) -> Result<bool, Self::Error> {
        match self.gate {
            Some(_) => Ok(true),
            None => self.uart.write_ready(),
        }
    }
}

type BoardExecutive =
    Executive<BoardLink, BoardClock, CmsdkWatchdog, BoardAutonomy, &'static mut ExecStorage>;

/// Reads exactly `buf.len()` control bytes, kicking the watchdog and sleeping between bytes. The host sends each
/// command in one write, so this waits only while it crosses the UART.
fn read_control(ctl: &mut Uart, buf: &mut [u8]) {
    let mut got = 0;
    while got < buf.len() {
        crate::watchdog::kick();
        got += ctl.read(buf.get_mut(got..).unwrap_or(&mut [])).unwrap_or(0);
        if got < buf.len() {
            idle(ctl);
        }
    }
}

fn write_control(ctl: &mut Uart, bytes: &[u8]) {
    let mut sent = 0;
    while sent < bytes.len() {
        sent += ctl.write(bytes.get(sent..).unwrap_or(&[])).unwrap_or(0);
    }
}

/// Sleeps until an interrupt (UART byte, transmitter free, SysTick) unless a byte is already waiting on `uart`.
fn idle(uart: &mut Uart) {
    cortex_m::interrupt::free(|_| {
        if !uart.read_ready().unwrap_or(true) {
            cortex_m::asm::wfi();
        }
    });
}

fn le_u32(b: &[u8], at: usize) -> u32 {
    let mut w = [0u8; 4];
    if let Some(s) = b.get(at..at + 4) {
        w.copy_from_slice(s);
    }
    u32::from_le_bytes(w)
}

fn le_u64(b: &[u8], at: usize) -> u64 {
    let mut w = [0u8; 8];
    if let Some(s) = b.get(at..at + 8) {
        w.copy_from_slice(s);
    }
    u64::from_le_bytes(w)
}

/// What the lockstep executive steps cost in core-clock ticks (SysTick): under QEMU's `-icount shift=0` one tick
/// is [`INSTRUCTIONS_PER_TICK`] instructions, so these are instruction counts of the flight code's work (a team
/// mission's local plans, a navigator's planning) on the emulated board; without icount they follow the host's
/// wall clock and mean little. A step includes the wait for its announced bytes to cross the emulated UART.
#[derive(Default)]
struct StepCost {
    steps: u64,
    total_ticks: u64,
    max_ticks: u64,
}

impl StepCost {
    fn step(&mut self, exec: &mut BoardExecutive) -> firmware::exec::StepReport {
        let t0 = exec.clock_mut().systick.ticks();
        let report = exec.step();
        let dt = exec.clock_mut().systick.ticks().saturating_sub(t0);
        self.steps += 1;
        self.total_ticks = self.total_ticks.saturating_add(dt);
        self.max_ticks = self.max_ticks.max(dt);
        report
    }
}

/// Prints the resource report and ends the run successfully.
fn quit(exec: &BoardExecutive, cost: &StepCost) -> ! {
    let stack = crate::stack::usage();
    let handler_stack = crate::stack::handler_usage();
    let t = exec.telemetry();
    let hw = t.high_water;
    host_println!(
        "board: stack_high_water_bytes={} stack_size_bytes={} handler_stack_high_water_bytes={} \
         handler_stack_size_bytes={} exec_storage_bytes={} scan_points_peak={} \
         scan_points_capacity={} tx_queue_peak={} tx_queue_capacity={} rx_staging_peak={} frame_len_peak={} \
         log_queue_peak={} map_blocks_peak={} map_blocks_capacity={} map_storage_bytes={} nav_plan_storage_bytes={} \
         steps={} frames_accepted={} frames_sent={} lockstep_steps={} lockstep_step_ticks_total={} \
         lockstep_step_ticks_max={} instructions_per_tick_under_icount={}",
        stack.high_water_bytes,
        stack.size_bytes,
        handler_stack.high_water_bytes,
        handler_stack.size_bytes,
        core::mem::size_of::<ExecStorage>(),
        hw.scan_points,
        firmware::config::protocol::SCAN_POINTS_CAPACITY,
        hw.tx_queue,
        firmware::config::exec::TX_QUEUE_LEN,
        hw.rx_staging,
        hw.frame_len,
        hw.log_queue,
        t.map.blocks_used, // blocks are never freed: in use = peak
        t.map.blocks_capacity,
        core::mem::size_of::<[Block; FLIGHT_BLOCKS]>() + core::mem::size_of::<[u32; FLIGHT_INDEX]>(),
        NavPlanStorage::bytes(),
        t.steps,
        t.frames_accepted,
        t.frames_sent,
        cost.steps,
        cost.total_ticks,
        cost.max_ticks,
        INSTRUCTIONS_PER_TICK
    );
    if stack.high_water_bytes >= stack.size_bytes
        || handler_stack.high_water_bytes >= handler_stack.size_bytes
    {
        // The paint is gone down to the bottom of a region. The flight stack cannot pass its limit (the MPU guard
        // faults first, `stack_guard.rs`) but has used all of it; the handler stack has no guard of its own.
        host_eprintln!(
            "board: STACK region exhausted: flight {} of {} bytes, handler {} of {} bytes",
            stack.high_water_bytes,
            stack.size_bytes,
            handler_stack.high_water_bytes,
            handler_stack.size_bytes
        );
        crate::fault::fail()
    }
    debug::exit(debug::EXIT_SUCCESS);
    crate::fault::fail()
}

/// The flight loop. Never returns: the run ends with `Q` (success) or a fault (failure).
pub fn run(systick: SysTickClock, lockstep: bool) -> ! {
    // SAFETY: called once from `main`; from here on these values own UART0, UART1 and the watchdog.
    let (uart0, mut ctl, wdog) = unsafe {
        (
            Uart::take(UART0_BASE),
            Uart::take(UART1_BASE),
            CmsdkWatchdog::start(if lockstep { LOCKSTEP_TIMEOUT_TICKS } else { TIMEOUT_TICKS }),
        )
    };
    for irq in UART_IRQS {
        // SAFETY: the UART interrupts' handler (DefaultHandler in fault.rs) only clears UART interrupt status and
        // shares no data with thread mode.
        unsafe { NVIC::unmask(Irq(irq as u16)) };
    }
    let Some(storage) = EXEC_STORAGE.take() else {
        host_eprintln!("board: executive storage lent twice");
        crate::fault::fail()
    };
    let link = BoardLink {
        uart: uart0,
        gate: lockstep.then_some(0),
        written: 0,
    };
    let clock = BoardClock {
        systick,
        lockstep_now: lockstep.then_some(Instant::from_micros(0)),
    };
    let (Some(blocks), Some(index)) = (MAP_BLOCKS.take(), MAP_INDEX.take()) else {
        host_eprintln!("board: map storage lent twice");
        crate::fault::fail()
    };
    let Some(planning) = NAV_PLAN.take() else {
        host_eprintln!("board: planning storage lent twice");
        crate::fault::fail()
    };
    let Some(global) = NAV_HOMOTOPY.take() else {
        host_eprintln!("board: global planner storage lent twice");
        crate::fault::fail()
    };
    let Some(retained) = take_retained() else {
        host_eprintln!("board: retained memory lent twice");
        crate::fault::fail()
    };
    let mut autonomy = match Navigator::new(MapConfig::DEFAULT, &mut blocks[..], &mut index[..], planning) {
        Ok(nav) => nav.with_homotopy(global),
        Err(e) => {
            let why = match e {
                firmware::map::MapError::Config(_) => "invalid configuration",
                firmware::map::MapError::BadStorage => "bad storage",
                firmware::map::MapError::PoolFull => "pool full",
                firmware::map::MapError::IndexProbeExhausted => "index probe exhausted",
            };
            host_eprintln!("board: onboard map refused its storage: {}", why);
            crate::fault::fail()
        }
    };
    #[cfg(feature = "test-probes")]
    if crate::watchdog::take_reset_mark() {
        host_eprintln!("board: REBOOTED by the watchdog's reset output");
    }
    // before the first step: what a reset left (the flight software comes back Safe with its tether state)
    autonomy.recover_retained(retained);
    let mut exec: BoardExecutive = Executive::new(link, clock, wdog, autonomy, storage);
    if let (Some(dstar), Some(planner), Some(points), Some(mission)) =
        (TEAM_DSTAR.take_init(), TEAM_PLANNER.take_init(), TEAM_POINTS.take(), TEAM_MISSION.take())
    {
        // a new executive has no team storage, so it takes this
        let _ = exec.lend_team(TeamLend { dstar: dstar.storage(), planner, points, mission });
    }
    // The harness handshake; in free-running mode the executive's first step also sends the boot Telemetry.
    write_control(&mut ctl, b"H");
    if lockstep {
        run_lockstep(&mut exec, &mut ctl, retained)
    }
    loop {
        let report = exec.step();
        exec.autonomy_mut().keep_retained(retained);
        if ctl.read_ready().unwrap_or(false) {
            let mut tag = [0u8; 1];
            let _ = ctl.read(&mut tag);
            if tag == *b"Q" {
                quit(&exec, &StepCost::default());
            }
            if tag == *b"B" {
                cortex_m::peripheral::SCB::sys_reset();
            }
            #[cfg(feature = "test-probes")]
            if tag == *b"W" {
                watchdog_bite()
            }
            host_eprintln!(
                "board: bad control byte 0x{:02x} in free-running mode",
                tag[0]
            );
            crate::fault::fail()
        }
        if !report.busy {
            let link = &mut exec.link_mut().uart;
            cortex_m::interrupt::free(|_| {
                if !link.read_ready().unwrap_or(true) && !ctl.read_ready().unwrap_or(true) {
                    cortex_m::asm::wfi();
                }
            });
        }
    }
}

/// Control byte `W`: the watchdog bites (`watchdog::stop_kicking`); reaching the end means it did not reset.
#[cfg(feature = "test-probes")]
fn watchdog_bite() -> ! {
    crate::watchdog::stop_kicking();
    host_eprintln!("board: the watchdog did not reset the board after a bite");
    crate::fault::fail()
}

fn run_lockstep(exec: &mut BoardExecutive, ctl: &mut Uart, retained: &mut RetainedBlock) -> ! {
    let mut cost = StepCost::default();
    loop {
        let mut tag = [0u8; 1];
        read_control(ctl, &mut tag);
        match &tag {
            b"Q" => quit(exec, &cost),
            b"B" => cortex_m::peripheral::SCB::sys_reset(),
            #[cfg(feature = "test-probes")]
            b"W" => watchdog_bite(),
            b"R" => {}
            _ => {
                host_eprintln!("board: bad control byte 0x{:02x} in lockstep mode", tag[0]);
                crate::fault::fail()
            }
        }
        let mut cmd = [0u8; RUN_LEN];
        read_control(ctl, &mut cmd);
        let announced = u64::from(le_u32(&cmd, 0));
        let t_start = le_u64(&cmd, 4);
        let step_us = u64::from(le_u32(&cmd, 12));
        let max_steps = le_u32(&cmd, 16);
        let until_quiet = cmd.get(20).copied().unwrap_or(0) != 0;
        {
            let link = exec.link_mut();
            link.gate = Some(link.gate.unwrap_or(0) + announced);
            link.written = 0;
        }
        let mut steps = 0u32;
        let mut busy = false;
        let mut t = t_start;
        for _ in 0..max_steps {
            exec.clock_mut().lockstep_now = Some(Instant::from_micros(t));
            let report = cost.step(exec);
            exec.autonomy_mut().keep_retained(retained);
            steps += 1;
            busy = report.busy;
            t += step_us;
            if until_quiet && !busy {
                break;
            }
        }
        let mut done = [0u8; 10];
        done[0] = b'D';
        done[1..5].copy_from_slice(&steps.to_le_bytes());
        done[5] = u8::from(busy);
        let written = u32::try_from(exec.link_mut().written).unwrap_or(u32::MAX);
        done[6..10].copy_from_slice(&written.to_le_bytes());
        write_control(ctl, &done);
    }
}
