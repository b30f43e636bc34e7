//! Seeded link-fault injection (issue 24, item 1): a [`FlightLink`] wrapper that damages the host -> flight
//! (uplink) and flight -> host (downlink) frames of any link (in-process or QEMU), after smoltcp's `phy::FaultInjector` (a wrapper around a device that
//! drops and corrupts packets at configured rates from a seeded generator), here on a COBS byte stream.
//!
//! **Faults** ([`FaultKind`], each at its own rate per byte and direction, [`FaultProfile`]; profile keys `KIND`
//! for the uplink as before, `down.KIND` for the downlink; each direction has its own generator, so downlink
//! faults leave a seed's uplink faults as they were): a frame of `n` encoded bytes meets
//! kind `k` with probability `1 - (1 - rate_k)^n`; the kinds are drawn in table order and at most one fault hits a
//! frame.
//!
//! | kind | what the frame suffers | parameter (default) |
//! |---|---|---|
//! | `bitflip` | one bit of one byte flipped (the delimiter excepted) | |
//! | `drop` | lost | |
//! | `duplicate` | delivered twice | |
//! | `reorder` | swapped with the next frame (delivered in order if none follows within the hold) | `reorder_hold_us` (200 ms) |
//! | `truncate` | cut after a random number of bytes, delimiter kept | |
//! | `delay` | held, later frames overtake it | `delay_us` (200 ms) |
//! | `stall` | the direction stops: this frame and all after it are held, then delivered in order | `stall_us` (500 ms) |
//!
//! The delays stay below the host session's retransmission timeout (1 s, `session::RetransmitPolicy`), so a
//! delayed frame is not also retransmitted.
//!
//! **Recording.** Put the field-log recorder *inside* the injector (`FaultLink<RecordingLink<L>>`): the log then
//! holds the bytes the flight software really received, when it received them, so `replay` reproduces a faulty
//! run byte for byte with no change, and every fault is written as a fault record ([`FlightLink::note_fault`],
//! `fieldlog` format 4: with its direction), which `inspect` lists. Downlink faults need nothing more for the
//! replay: the log holds what the flight software sent, and the host's answers to the damaged downlink are in its
//! recorded uplink bytes. Downlink frames are delivered to the host by the link call (`advance_to`,
//! `recv_until_quiet`) whose link time reaches their release.
//!
//! **Accounting** ([`FaultAccount`]): the injector knows what it did (injected; harmless = the frame reached the
//! flight software intact and in order: a delay no intact frame overtook, a stall, a reorder with no frame to swap
//! with or whose partner was lost or damaged).
//! The detection side is the flight software's own `Telemetry` (protocol v4), read from the downlink: a lost or
//! damaged frame is a gap in the host's sequence numbers (`seq_gaps` less `seq_late`, since a late frame first
//! shows as a gap), a duplicate is a `Nack(DuplicateFrame)`, a reordered or delayed frame is `seq_late`. Per group,
//! injected must equal detected plus harmless. The injector also reads every `Ack` on the downlink: an `Ack` for
//! the sequence number of a damaged frame would mean the flight software acted on it (it must be 0).
//!
//! On the downlink the detection side is the host's ([`crate::session::DownlinkCounts`]: its deframer and CRC
//! check, and the flight software's sequence numbers, with the same rules as the flight side's on the uplink), added
//! by [`FaultAccount::with_host`] with the flight sequence numbers of the frames whose drive commands the host took:
//! none may be one the injector damaged or dropped (`executed_damaged`, must be 0).

use std::collections::BTreeSet;

use firmware::protocol::{self, Deframer, Frame, Message, NackReason, Telemetry};
use rand_core::{Rng, SeedableRng};

use super::{FlightLink, LinkError};
pub use crate::session::DownlinkCounts;

/// A kind of link fault (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
pub enum FaultKind {
    /// One bit of one byte flipped.
    BitFlip,
    /// The frame lost.
    Drop,
    /// The frame delivered twice.
    Duplicate,
    /// The frame swapped with the next one.
    Reorder,
    /// The frame cut short.
    Truncate,
    /// The frame held while later ones pass.
    Delay,
    /// The uplink held, then delivered in order.
    Stall,
}

impl FaultKind {
    /// Every kind, in the order they are drawn.
    pub const ALL: [FaultKind; 7] = [
        FaultKind::BitFlip,
        FaultKind::Drop,
        FaultKind::Duplicate,
        FaultKind::Reorder,
        FaultKind::Truncate,
        FaultKind::Delay,
        FaultKind::Stall,
    ];

    /// The name used in profiles and tables.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::BitFlip => "bitflip",
            FaultKind::Drop => "drop",
            FaultKind::Duplicate => "duplicate",
            FaultKind::Reorder => "reorder",
            FaultKind::Truncate => "truncate",
            FaultKind::Delay => "delay",
            FaultKind::Stall => "stall",
        }
    }

    fn index(self) -> usize {
        self as usize
    }

    fn from_u8(b: u8) -> Option<Self> {
        Self::ALL.get(usize::from(b)).copied()
    }

    /// How the flight software's telemetry shows this kind.
    pub fn group(self) -> DetectionGroup {
        match self {
            FaultKind::BitFlip | FaultKind::Drop | FaultKind::Truncate => DetectionGroup::Lost,
            FaultKind::Duplicate => DetectionGroup::Duplicate,
            FaultKind::Reorder | FaultKind::Delay | FaultKind::Stall => DetectionGroup::Late,
        }
    }
}

/// Which way a faulted frame was going.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
pub enum LinkDirection {
    /// Host -> flight.
    Up,
    /// Flight -> host.
    Down,
}

impl LinkDirection {
    /// "uplink" or "downlink".
    pub fn name(self) -> &'static str {
        match self {
            LinkDirection::Up => "uplink",
            LinkDirection::Down => "downlink",
        }
    }
}

/// The telemetry evidence of a fault (module docs, "Accounting").
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
pub enum DetectionGroup {
    /// A sequence gap not filled by a late frame (`seq_gaps - seq_late`).
    Lost,
    /// `frames_rejected[DuplicateFrame]`.
    Duplicate,
    /// `seq_late`.
    Late,
}

impl DetectionGroup {
    /// Every group.
    pub const ALL: [DetectionGroup; 3] = [
        DetectionGroup::Lost,
        DetectionGroup::Duplicate,
        DetectionGroup::Late,
    ];

    /// What the flight software counted for this group in `t`.
    pub fn detected(self, t: &Telemetry) -> u64 {
        match self {
            DetectionGroup::Lost => u64::from(t.seq_gaps).saturating_sub(u64::from(t.seq_late)),
            DetectionGroup::Duplicate => u64::from(
                t.frames_rejected
                    .get(NackReason::DuplicateFrame.index())
                    .copied()
                    .unwrap_or(0),
            ),
            DetectionGroup::Late => u64::from(t.seq_late),
        }
    }

    /// What the host counted for this group on the downlink ([`DownlinkCounts`]; the same evidence as the flight
    /// side's on the uplink).
    pub fn detected_down(self, h: &DownlinkCounts) -> u64 {
        match self {
            DetectionGroup::Lost => h.gaps.saturating_sub(h.late),
            DetectionGroup::Duplicate => h.duplicates,
            DetectionGroup::Late => h.late,
        }
    }
}

/// Rates (per byte) and parameters of the injected faults.
#[derive(Debug, Clone, PartialEq)]
pub struct FaultProfile {
    /// Rate per byte of each kind on the uplink (host -> flight), in [`FaultKind::ALL`] order.
    pub rates: [f64; 7],
    /// Rate per byte of each kind on the downlink (flight -> host), in [`FaultKind::ALL`] order.
    pub down_rates: [f64; 7],
    /// Hold of a delayed frame, microseconds (default 200 ms).
    pub delay_us: u64,
    /// Length of a stall, microseconds (default 500 ms).
    pub stall_us: u64,
    /// Longest hold of a frame waiting for one to swap with, microseconds (default 200 ms).
    pub reorder_hold_us: u64,
    /// Seed of the injector's generator.
    pub seed: u64,
}

impl Default for FaultProfile {
    fn default() -> Self {
        Self {
            rates: [0.0; 7],
            down_rates: [0.0; 7],
            delay_us: 200_000,
            stall_us: 500_000,
            reorder_hold_us: 200_000,
            seed: 0,
        }
    }
}

impl FaultProfile {
    /// One kind at `rate` per byte.
    pub fn single(kind: FaultKind, rate: f64, seed: u64) -> Self {
        let mut p = Self {
            seed,
            ..Self::default()
        };
        if let Some(r) = p.rates.get_mut(kind.index()) {
            *r = rate;
        }
        p
    }

    /// The uplink rate of `kind`.
    pub fn rate(&self, kind: FaultKind) -> f64 {
        self.rates.get(kind.index()).copied().unwrap_or(0.0)
    }

    /// The downlink rate of `kind`.
    pub fn down_rate(&self, kind: FaultKind) -> f64 {
        self.down_rates.get(kind.index()).copied().unwrap_or(0.0)
    }

    /// The rates of direction `d`.
    pub fn rates_of(&self, d: LinkDirection) -> &[f64; 7] {
        match d {
            LinkDirection::Up => &self.rates,
            LinkDirection::Down => &self.down_rates,
        }
    }

    /// Parses `KIND=RATE,...` (`all=RATE` sets every kind) for the uplink, `down.KIND=RATE` (`down.all=RATE`) for
    /// the downlink, `delay_us=`, `stall_us=`, `reorder_hold_us=`, `seed=` (both directions); `none` is no fault.
    /// Rates are per byte, in [0, 1].
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut p = Self::default();
        for item in text
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty() && *s != "none")
        {
            let (key, value) = item.split_once('=').ok_or_else(|| {
                format!("fault profile item `{item}` is not KEY=VALUE (e.g. bitflip=1e-4)")
            })?;
            let key = key.trim();
            let value = value.trim();
            let int = || {
                value
                    .parse::<u64>()
                    .map_err(|e| format!("fault profile `{key}={value}`: {e}"))
            };
            match key {
                "delay_us" => p.delay_us = int()?,
                "stall_us" => p.stall_us = int()?,
                "reorder_hold_us" => p.reorder_hold_us = int()?,
                "seed" => p.seed = int()?,
                _ => {
                    let rate: f64 = value
                        .parse()
                        .map_err(|e| format!("fault profile `{key}={value}`: {e}"))?;
                    if !(0.0..=1.0).contains(&rate) {
                        return Err(format!(
                            "fault profile `{key}={value}`: a rate per byte must be in [0, 1]"
                        ));
                    }
                    let (rates, name) = match key.strip_prefix("down.") {
                        Some(name) => (&mut p.down_rates, name),
                        None => (&mut p.rates, key),
                    };
                    if name == "all" {
                        *rates = [rate; 7];
                    } else {
                        let kind = FaultKind::ALL.iter().find(|k| k.name() == name).ok_or_else(|| {
                            let names: Vec<&str> = FaultKind::ALL.iter().map(|k| k.name()).collect();
                            format!("fault profile: unknown key `{key}` (kinds: {}, all, each alone for the uplink or after `down.` for the downlink; delay_us, stall_us, reorder_hold_us, seed)", names.join(", "))
                        })?;
                        rates[kind.index()] = rate;
                    }
                }
            }
        }
        Ok(p)
    }

    /// Whether any rate is non-zero.
    pub fn any(&self) -> bool {
        self.rates.iter().chain(&self.down_rates).any(|&r| r > 0.0)
    }
}

impl core::fmt::Display for FaultProfile {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for k in FaultKind::ALL {
            if self.rate(k) > 0.0 {
                write!(f, "{}={:e},", k.name(), self.rate(k))?;
            }
        }
        for k in FaultKind::ALL {
            if self.down_rate(k) > 0.0 {
                write!(f, "down.{}={:e},", k.name(), self.down_rate(k))?;
            }
        }
        write!(
            f,
            "delay_us={},stall_us={},reorder_hold_us={},seed={}",
            self.delay_us, self.stall_us, self.reorder_hold_us, self.seed
        )
    }
}

/// One injected fault, as the field log keeps it (a fault record's payload, [`FaultEvent::to_bytes`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct FaultEvent {
    /// Link time of the injection, microseconds.
    pub t_us: u64,
    /// The direction of the faulted frame.
    pub direction: LinkDirection,
    /// The kind.
    pub kind: FaultKind,
    /// Index of the frame in its direction (0 = the first frame that went through the injector that way).
    pub frame: u64,
    /// The frame's sequence number (its sender's; 0 if its header could not be read).
    pub seq: u32,
    /// The frame's encoded length, bytes.
    pub frame_len: u32,
    /// Bit flipped (byte * 8 + bit), bytes kept by a truncation, or the hold in microseconds; 0 otherwise.
    pub detail: u64,
}

/// Bytes of an encoded [`FaultEvent`] (without its time, which is the record's): field-log format 4.
pub const FAULT_EVENT_LEN: usize = 1 + 8 + 4 + 4 + 8 + 1;
/// Bytes of a format-3 fault record's payload (no direction byte: every fault was on the uplink).
pub const FAULT_EVENT_LEN_V3: usize = FAULT_EVENT_LEN - 1;

impl FaultEvent {
    /// The payload of a fault record: `kind u8 | frame u64 | seq u32 | frame_len u32 | detail u64 | direction u8`
    /// (0 uplink, 1 downlink), little-endian (field-log format 4; format 3 had no direction byte).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(FAULT_EVENT_LEN);
        b.push(self.kind as u8);
        b.extend_from_slice(&self.frame.to_le_bytes());
        b.extend_from_slice(&self.seq.to_le_bytes());
        b.extend_from_slice(&self.frame_len.to_le_bytes());
        b.extend_from_slice(&self.detail.to_le_bytes());
        b.push(match self.direction {
            LinkDirection::Up => 0,
            LinkDirection::Down => 1,
        });
        b
    }

    /// Reads a fault record's payload (`None` if it is not one); a format-3 payload (25 bytes) is an uplink fault.
    pub fn from_bytes(t_us: u64, b: &[u8]) -> Option<Self> {
        let direction = match (b.len(), b.get(FAULT_EVENT_LEN_V3)) {
            (FAULT_EVENT_LEN_V3, _) | (FAULT_EVENT_LEN, Some(0)) => LinkDirection::Up,
            (FAULT_EVENT_LEN, Some(1)) => LinkDirection::Down,
            _ => return None,
        };
        let u64_at = |at: usize| {
            b.get(at..at + 8)
                .and_then(|s| s.try_into().ok())
                .map(u64::from_le_bytes)
        };
        let u32_at = |at: usize| {
            b.get(at..at + 4)
                .and_then(|s| s.try_into().ok())
                .map(u32::from_le_bytes)
        };
        Some(Self {
            t_us,
            direction,
            kind: FaultKind::from_u8(*b.first()?)?,
            frame: u64_at(1)?,
            seq: u32_at(9)?,
            frame_len: u32_at(13)?,
            detail: u64_at(17)?,
        })
    }
}

impl core::fmt::Display for FaultEvent {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "t {:.6} s  {:<9} {} frame #{} (seq {}, {} bytes), detail {}",
            self.t_us as f64 / 1e6,
            self.kind.name(),
            self.direction.name(),
            self.frame,
            self.seq,
            self.frame_len,
            self.detail
        )
    }
}

/// What the injector did and what each receiver saw (module docs, "Accounting").
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct FaultAccount {
    /// Uplink faults injected, per kind ([`FaultKind::ALL`] order).
    pub injected: [u64; 7],
    /// Uplink faults that left their frame intact and in order, per kind.
    pub harmless: [u64; 7],
    /// Downlink faults injected, per kind.
    pub down_injected: [u64; 7],
    /// Downlink faults that left their frame intact and in order, per kind.
    pub down_harmless: [u64; 7],
    /// `Ack`s the flight software sent for the sequence number of a frame the injector damaged (must be 0).
    pub acked_damaged: u64,
    /// Drive commands the host executed from a downlink frame the injector damaged or dropped (must be 0;
    /// [`Self::with_host`]).
    pub executed_damaged: u64,
    /// The last `Telemetry` seen on the downlink.
    #[serde(skip)]
    pub telemetry: Option<Telemetry>,
    /// The host's own detection on the downlink ([`Self::with_host`]).
    pub host: Option<DownlinkCounts>,
    /// Flight sequence numbers of the downlink frames damaged or lost.
    #[serde(skip)]
    pub damaged_down_seqs: BTreeSet<u32>,
}

impl FaultAccount {
    /// Injected faults of a kind.
    pub fn injected(&self, k: FaultKind) -> u64 {
        self.injected.get(k.index()).copied().unwrap_or(0)
    }

    /// Harmless faults of a kind.
    pub fn harmless(&self, k: FaultKind) -> u64 {
        self.harmless.get(k.index()).copied().unwrap_or(0)
    }

    /// Injected downlink faults of a kind.
    pub fn down_injected(&self, k: FaultKind) -> u64 {
        self.down_injected.get(k.index()).copied().unwrap_or(0)
    }

    /// Harmless downlink faults of a kind.
    pub fn down_harmless(&self, k: FaultKind) -> u64 {
        self.down_harmless.get(k.index()).copied().unwrap_or(0)
    }

    /// What the host counted on the downlink for a group (`None` without the host's counts).
    pub fn down_detected(&self, g: DetectionGroup) -> Option<u64> {
        self.host.as_ref().map(|h| g.detected_down(h))
    }

    /// Injected and harmless downlink faults of the kinds of a group.
    pub fn down_group_totals(&self, g: DetectionGroup) -> (u64, u64) {
        self.totals_in(LinkDirection::Down, g)
    }

    /// Injected and harmless faults of the kinds of a group in direction `d`.
    pub fn totals_in(&self, d: LinkDirection, g: DetectionGroup) -> (u64, u64) {
        let (injected, harmless) = match d {
            LinkDirection::Up => (&self.injected, &self.harmless),
            LinkDirection::Down => (&self.down_injected, &self.down_harmless),
        };
        FaultKind::ALL
            .iter()
            .filter(|k| k.group() == g)
            .fold((0, 0), |(i, h), &k| {
                let at = |a: &[u64; 7]| a.get(k.index()).copied().unwrap_or(0);
                (i + at(injected), h + at(harmless))
            })
    }

    /// Adds the host's side: its downlink counts (`HostSession::downlink`) and the flight sequence numbers of the
    /// frames whose drive commands it executed (any of them damaged on the way is counted in `executed_damaged`).
    pub fn with_host(mut self, host: DownlinkCounts, executed_seqs: &[u32]) -> Self {
        self.host = Some(host);
        self.executed_damaged = executed_seqs
            .iter()
            .filter(|s| self.damaged_down_seqs.contains(s))
            .count() as u64;
        self
    }

    /// What the last telemetry counted for a group (`None` without telemetry).
    pub fn detected(&self, g: DetectionGroup) -> Option<u64> {
        self.telemetry.as_ref().map(|t| g.detected(t))
    }

    /// Injected and harmless faults of the kinds of a group.
    pub fn group_totals(&self, g: DetectionGroup) -> (u64, u64) {
        self.totals_in(LinkDirection::Up, g)
    }

    /// Checks injected = detected + harmless for every group and no `Ack` for a damaged frame; the reason if not.
    pub fn check(&self) -> Result<(), String> {
        let Some(t) = &self.telemetry else {
            return Err("no telemetry from the flight software".into());
        };
        let mut bad = Vec::new();
        // per group of a direction: injected = detected + harmless
        let mut balance = |d: LinkDirection, detected: &dyn Fn(DetectionGroup) -> u64| {
            for g in DetectionGroup::ALL {
                let (inj, harmless) = self.totals_in(d, g);
                let det = detected(g);
                if inj != det + harmless {
                    let side = if d == LinkDirection::Down { "downlink " } else { "" };
                    bad.push(format!(
                        "{side}{g:?}: injected {inj} != detected {det} + harmless {harmless}"
                    ));
                }
            }
        };
        balance(LinkDirection::Up, &|g| g.detected(t));
        let down_faults = self.down_injected.iter().any(|&n| n > 0);
        match &self.host {
            None if down_faults => bad.push("downlink faults but no host downlink counts".into()),
            None => {}
            Some(h) => balance(LinkDirection::Down, &|g| g.detected_down(h)),
        }
        if self.acked_damaged > 0 {
            bad.push(format!(
                "{} damaged frame(s) acknowledged",
                self.acked_damaged
            ));
        }
        if self.executed_damaged > 0 {
            bad.push(format!(
                "{} drive command(s) executed from a damaged downlink frame",
                self.executed_damaged
            ));
        }
        if bad.is_empty() {
            Ok(())
        } else {
            Err(bad.join("; "))
        }
    }
}

/// A frame waiting to be delivered.
#[derive(Debug, Clone)]
struct Held {
    at_us: u64,
    frame: u64,
    bytes: Vec<u8>,
}

/// One direction's injector state: its generator, the frame being cut out of the byte stream, the held frames and
/// what it knows of delivery order.
struct Lane {
    rng: rand_pcg::Pcg64,
    /// Bytes of a frame not yet ended by its delimiter.
    partial: Vec<u8>,
    frames: u64,
    /// Delayed frames, released at their times.
    delayed: Vec<Held>,
    /// A frame waiting for the next one to swap with.
    reordered: Option<Held>,
    /// Frames held by a stall, released in order at `stall_until_us`.
    stalled: Vec<Held>,
    stall_until_us: u64,
    /// Highest frame index delivered so far; frames delivered behind it are late.
    delivered_max: Option<u64>,
    /// Frames delivered behind a later one.
    late: BTreeSet<u64>,
    /// Sequence numbers of frames damaged or lost (never delivered intact).
    damaged_seqs: BTreeSet<u32>,
    /// Frame indices delivered damaged: the receiver never reads them, so they make nothing late.
    damaged_frames: BTreeSet<u64>,
}

impl Lane {
    fn new(seed: u64) -> Self {
        Self {
            rng: rand_pcg::Pcg64::seed_from_u64(seed),
            partial: Vec::new(),
            frames: 0,
            delayed: Vec::new(),
            reordered: None,
            stalled: Vec::new(),
            stall_until_us: 0,
            delivered_max: None,
            late: BTreeSet::new(),
            damaged_seqs: BTreeSet::new(),
            damaged_frames: BTreeSet::new(),
        }
    }

    fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    fn below(&mut self, n: u64) -> u64 {
        self.rng.next_u64() % n.max(1)
    }

    /// Notes that `frame` reaches the receiver now (a damaged frame is never read, so it makes nothing late).
    fn note_delivery(&mut self, frame: u64) {
        if self.damaged_frames.contains(&frame) {
            return;
        }
        match self.delivered_max {
            Some(m) if frame < m => {
                self.late.insert(frame);
            }
            _ => self.delivered_max = Some(frame),
        }
    }

    /// The next time something held falls due.
    fn next_release(&self) -> Option<u64> {
        let stall = (!self.stalled.is_empty()).then_some(self.stall_until_us);
        let reorder = self.reordered.as_ref().map(|h| h.at_us);
        let delayed = self.delayed.iter().map(|h| h.at_us).min();
        [stall, reorder, delayed].into_iter().flatten().min()
    }

    /// Takes the whole frames (each up to and with its delimiter) out of `partial` after appending `bytes`.
    fn frames_of(&mut self, bytes: &[u8]) -> Vec<Vec<u8>> {
        self.partial.extend_from_slice(bytes);
        let mut out = Vec::new();
        // Each pass takes one whole frame out of `partial`.
        while let Some(end) = self.partial.iter().position(|&b| b == 0) {
            let rest = self.partial.split_off(end + 1);
            out.push(core::mem::replace(&mut self.partial, rest));
        }
        out
    }
}

/// The downlink generator's seed is the profile's seed with this mixed in, so adding downlink faults leaves the
/// uplink's faults of a seed as they were.
const DOWNLINK_SEED_SALT: u64 = 0x646f_776e_6c69_6e6b;

/// The fault-injecting wrapper (module docs).
pub struct FaultLink<L: FlightLink> {
    inner: L,
    profile: FaultProfile,
    enabled: bool,
    up: Lane,
    down: Lane,
    /// Downlink bytes delivered to the host, handed over by the current link call.
    to_host: Vec<u8>,
    events: Vec<FaultEvent>,
    /// Reads the flight software's true output (before downlink faults).
    watcher: Deframer,
    acked_damaged: u64,
    telemetry: Option<Telemetry>,
}

impl<L: FlightLink> FaultLink<L> {
    /// Wraps `inner` with `profile` (seeded by `profile.seed`).
    pub fn new(inner: L, profile: FaultProfile) -> Self {
        Self {
            inner,
            up: Lane::new(profile.seed),
            down: Lane::new(profile.seed ^ DOWNLINK_SEED_SALT),
            profile,
            enabled: true,
            to_host: Vec::new(),
            events: Vec::new(),
            watcher: Deframer::new(),
            acked_damaged: 0,
            telemetry: None,
        }
    }

    /// The wrapped link.
    pub fn inner(&self) -> &L {
        &self.inner
    }

    /// The wrapped link, mutably.
    pub fn inner_mut(&mut self) -> &mut L {
        &mut self.inner
    }

    /// Gives the wrapped link back (frames still held are lost; call [`FlightLink::end_faults`] first).
    pub fn into_inner(self) -> L {
        self.inner
    }

    /// The faults injected so far.
    pub fn events(&self) -> &[FaultEvent] {
        &self.events
    }

    /// The flight sequence numbers of the downlink frames damaged or lost so far (the host must never act on one).
    pub fn damaged_downlink_seqs(&self) -> &BTreeSet<u32> {
        &self.down.damaged_seqs
    }

    /// The accounting so far (module docs); the host's side of the downlink is added with
    /// [`FaultAccount::with_host`].
    pub fn account(&self) -> FaultAccount {
        let mut a = FaultAccount {
            acked_damaged: self.acked_damaged,
            telemetry: self.telemetry,
            damaged_down_seqs: self.down.damaged_seqs.clone(),
            ..FaultAccount::default()
        };
        for e in &self.events {
            let k = e.kind.index();
            let lane = self.lane_ref(e.direction);
            let intact_in_order = match e.kind {
                FaultKind::Delay | FaultKind::Stall | FaultKind::Reorder => !lane.late.contains(&e.frame),
                _ => false,
            };
            let (injected, harmless) = match e.direction {
                LinkDirection::Up => (&mut a.injected, &mut a.harmless),
                LinkDirection::Down => (&mut a.down_injected, &mut a.down_harmless),
            };
            injected[k] += 1;
            if intact_in_order {
                harmless[k] += 1;
            }
        }
        a
    }

    fn lane_ref(&self, d: LinkDirection) -> &Lane {
        match d {
            LinkDirection::Up => &self.up,
            LinkDirection::Down => &self.down,
        }
    }

    fn lane(&mut self, d: LinkDirection) -> &mut Lane {
        match d {
            LinkDirection::Up => &mut self.up,
            LinkDirection::Down => &mut self.down,
        }
    }

    /// Hands `bytes` of frame `frame` to the receiver now (through a stall if one is on).
    fn emit(&mut self, d: LinkDirection, frame: u64, bytes: Vec<u8>) -> Result<(), LinkError> {
        let now = self.inner.now_us();
        let lane = self.lane(d);
        if now < lane.stall_until_us || !lane.stalled.is_empty() {
            let at_us = lane.stall_until_us;
            lane.stalled.push(Held { at_us, frame, bytes });
            return Ok(());
        }
        self.deliver(d, frame, &bytes)
    }

    fn deliver(&mut self, d: LinkDirection, frame: u64, bytes: &[u8]) -> Result<(), LinkError> {
        self.lane(d).note_delivery(frame);
        match d {
            LinkDirection::Up => self.inner.send(bytes),
            LinkDirection::Down => {
                self.to_host.extend_from_slice(bytes);
                Ok(())
            }
        }
    }

    /// Releases everything due at the current time in direction `d`: the stall's frames, delayed frames, an
    /// expired reorder hold.
    fn release_due(&mut self, d: LinkDirection) -> Result<(), LinkError> {
        let now = self.inner.now_us();
        let lane = self.lane(d);
        if now >= lane.stall_until_us && !lane.stalled.is_empty() {
            for h in core::mem::take(&mut self.lane(d).stalled) {
                self.deliver(d, h.frame, &h.bytes)?;
            }
        }
        let lane = self.lane(d);
        if lane.reordered.as_ref().is_some_and(|h| h.at_us <= now) {
            if let Some(h) = lane.reordered.take() {
                self.emit(d, h.frame, h.bytes)?;
            }
        }
        let lane = self.lane(d);
        let (due, rest): (Vec<Held>, Vec<Held>) = core::mem::take(&mut lane.delayed)
            .into_iter()
            .partition(|h| h.at_us <= now);
        lane.delayed = rest;
        for h in due {
            self.emit(d, h.frame, h.bytes)?;
        }
        Ok(())
    }

    fn release_all_due(&mut self) -> Result<(), LinkError> {
        self.release_due(LinkDirection::Up)?;
        self.release_due(LinkDirection::Down)
    }

    /// The next time something held (either way) falls due.
    fn next_release(&self) -> Option<u64> {
        [self.up.next_release(), self.down.next_release()].into_iter().flatten().min()
    }

    /// Whether downlink frames go through the injector (else the flight's bytes pass as they come).
    fn downlink_faulted(&self) -> bool {
        self.enabled && self.profile.down_rates.iter().any(|&r| r > 0.0)
    }

    /// Takes the flight software's output of one inner link call: watched for the accounting, then faulted frame by
    /// frame on its way to the host.
    fn take_down(&mut self, got: Vec<u8>) -> Result<(), LinkError> {
        self.watch(&got);
        if !self.downlink_faulted() {
            let partial = core::mem::take(&mut self.down.partial);
            self.to_host.extend(partial);
            self.to_host.extend(got);
            return Ok(());
        }
        for frame in self.down.frames_of(&got) {
            self.inject(LinkDirection::Down, frame)?;
        }
        Ok(())
    }

    /// Runs the inner link to `t_us`, releasing held frames at their times on the way.
    fn run_to(&mut self, t_us: u64) -> Result<(), LinkError> {
        // Each pass releases at least one held frame (or a stall); at most as many passes as frames held.
        while let Some(at) = self.next_release().filter(|&at| at <= t_us) {
            let got = self.inner.advance_to(at)?;
            self.take_down(got)?;
            self.release_all_due()?;
        }
        let got = self.inner.advance_to(t_us)?;
        self.take_down(got)?;
        self.release_due(LinkDirection::Down)
    }

    /// Reads the flight software's true output: `Ack`s of damaged uplink frames and the latest `Telemetry`.
    fn watch(&mut self, bytes: &[u8]) {
        let mut rest = bytes;
        // Each pass consumes at least one byte.
        while !rest.is_empty() {
            let (used, ev) = self.watcher.push(rest);
            rest = rest.get(used.max(1)..).unwrap_or(&[]);
            let Some(Ok(frame)) = ev else { continue };
            match protocol::decode_frame(frame) {
                Ok((_, Message::Ack(a))) if self.up.damaged_seqs.contains(&a.seq) => {
                    self.acked_damaged += 1
                }
                Ok((_, Message::Telemetry(t))) => self.telemetry = Some(t),
                _ => {}
            }
        }
    }

    /// Draws the fault of one frame going in direction `d` and applies it.
    fn inject(&mut self, d: LinkDirection, bytes: Vec<u8>) -> Result<(), LinkError> {
        let enabled = self.enabled;
        let rates = match d {
            LinkDirection::Up => self.profile.rates,
            LinkDirection::Down => self.profile.down_rates,
        };
        let lane = self.lane(d);
        let frame = lane.frames;
        lane.frames += 1;
        let n = bytes.len() as u64;
        let mut chosen = None;
        if enabled && n >= 3 {
            for k in FaultKind::ALL {
                let rate = rates.get(k.index()).copied().unwrap_or(0.0);
                if rate <= 0.0 {
                    continue;
                }
                let p = 1.0 - (1.0 - rate).powf(n as f64);
                if lane.uniform() < p && chosen.is_none() {
                    chosen = Some(k);
                }
            }
        }
        // A frame held for a swap goes out right after this one (or this one is the swap's first frame).
        let swap = lane.reordered.take();
        let Some(kind) = chosen else {
            self.emit(d, frame, bytes)?;
            if let Some(h) = swap {
                self.emit(d, h.frame, h.bytes)?;
            }
            return Ok(());
        };
        let now = self.inner.now_us();
        let seq = frame_seq(&bytes);
        let mut event = FaultEvent {
            t_us: now,
            direction: d,
            kind,
            frame,
            seq,
            frame_len: n as u32,
            detail: 0,
        };
        let (delay_us, stall_us, reorder_hold_us) =
            (self.profile.delay_us, self.profile.stall_us, self.profile.reorder_hold_us);
        let lane = self.lane(d);
        let mut out = bytes;
        match kind {
            FaultKind::BitFlip => {
                let at = lane.below(n - 1);
                let bit = lane.below(8);
                if let Some(b) = out.get_mut(at as usize) {
                    *b ^= 1 << bit;
                }
                event.detail = at * 8 + bit;
                lane.damaged_seqs.insert(seq);
                lane.damaged_frames.insert(frame);
            }
            FaultKind::Truncate => {
                let keep = 1 + lane.below(n - 2);
                out.truncate(keep as usize);
                out.push(0);
                event.detail = keep;
                lane.damaged_seqs.insert(seq);
                lane.damaged_frames.insert(frame);
            }
            FaultKind::Drop => {
                lane.damaged_seqs.insert(seq);
            }
            FaultKind::Delay => event.detail = delay_us,
            FaultKind::Stall => {
                event.detail = stall_us;
                lane.stall_until_us = lane.stall_until_us.max(now + stall_us);
            }
            FaultKind::Reorder => event.detail = reorder_hold_us,
            FaultKind::Duplicate => {}
        }
        self.inner.note_fault(&event)?;
        self.events.push(event);
        match kind {
            FaultKind::Drop => {}
            FaultKind::Duplicate => {
                self.emit(d, frame, out.clone())?;
                self.emit(d, frame, out)?;
            }
            FaultKind::Delay => self.lane(d).delayed.push(Held {
                at_us: now + delay_us,
                frame,
                bytes: out,
            }),
            FaultKind::Reorder if swap.is_none() => {
                self.lane(d).reordered = Some(Held {
                    at_us: now + reorder_hold_us,
                    frame,
                    bytes: out,
                });
                return Ok(());
            }
            _ => self.emit(d, frame, out)?,
        }
        if let Some(h) = swap {
            self.emit(d, h.frame, h.bytes)?;
        }
        Ok(())
    }

    /// Delivers every frame held in direction `d`, in the order they would have come.
    fn flush(&mut self, d: LinkDirection) -> Result<(), LinkError> {
        let lane = self.lane(d);
        lane.stall_until_us = 0;
        let stalled = core::mem::take(&mut lane.stalled);
        let reordered = lane.reordered.take();
        let mut delayed = core::mem::take(&mut lane.delayed);
        for h in stalled {
            self.deliver(d, h.frame, &h.bytes)?;
        }
        if let Some(h) = reordered {
            self.deliver(d, h.frame, &h.bytes)?;
        }
        delayed.sort_by_key(|h| (h.at_us, h.frame));
        for h in delayed {
            self.deliver(d, h.frame, &h.bytes)?;
        }
        Ok(())
    }
}

/// The sequence number in an encoded frame's header (0 if it does not deframe).
fn frame_seq(wire: &[u8]) -> u32 {
    let mut d = Deframer::new();
    match d.push(wire) {
        (_, Some(Ok(f))) if f.len() >= firmware::config::protocol::HEADER_LEN => {
            Frame::new_unchecked(f).seq()
        }
        _ => 0,
    }
}

impl<L: FlightLink> FlightLink for FaultLink<L> {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn now_us(&self) -> u64 {
        self.inner.now_us()
    }

    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.release_all_due()?;
        for frame in self.up.frames_of(bytes) {
            self.inject(LinkDirection::Up, frame)?;
        }
        Ok(())
    }

    fn recv_until_quiet(&mut self, max_wait_us: u64) -> Result<Vec<u8>, LinkError> {
        let start = self.inner.now_us();
        let deadline = start.saturating_add(max_wait_us);
        if let Some(at) = self.next_release().filter(|&at| at <= deadline) {
            self.run_to(at)?;
        }
        let left = deadline.saturating_sub(self.inner.now_us());
        let got = self.inner.recv_until_quiet(left.max(1))?;
        self.take_down(got)?;
        self.release_all_due()?;
        Ok(core::mem::take(&mut self.to_host))
    }

    fn advance_to(&mut self, t_us: u64) -> Result<Vec<u8>, LinkError> {
        self.run_to(t_us)?;
        Ok(core::mem::take(&mut self.to_host))
    }

    fn note_fault(&mut self, event: &FaultEvent) -> Result<(), LinkError> {
        self.inner.note_fault(event)
    }

    fn end_faults(&mut self) -> Result<(), LinkError> {
        self.enabled = false;
        self.flush(LinkDirection::Up)?;
        // the downlink's held frames reach the host with the next receive
        self.flush(LinkDirection::Down)?;
        self.inner.end_faults()
    }

    fn reset_flight(&mut self, cause: super::ResetCause) -> Result<(), LinkError> {
        // frames held on the way (delayed, stalled, reordered) are in the radio path, not the flight computer:
        // they still arrive (uplink: at the rebooted software)
        self.inner.reset_flight(cause)
    }
}
