//! Fault campaigns (issue 24, item 1): missions over a faulted uplink or downlink (`link::faults`), one fault kind
//! at a time, at rates per byte from 1e-5 to 1e-2, and the table: how the missions ended (arrived, safe with the
//! reason, fell, anything else), the faults injected, detected (uplink: by the flight software's telemetry;
//! downlink: by the host's counters) and harmless, whether
//! injected = detected + harmless held in every mission, `Ack`s of damaged frames, the host's retransmissions and
//! the executive's cycle accounting (longest step, slips). `host-sim/doc/faults.md` has the figures.

use core::fmt::Write as _;
use std::collections::BTreeMap;

use firmware::protocol::Tracking;

use super::campaign::{run_one, run_parallel};
use super::run::{MissionReport, Verdict};
use crate::link::faults::{FaultAccount, FaultKind, FaultProfile, LinkDirection};
use crate::scenario::Scenario;

/// Default rates per byte of a fault campaign.
pub const DEFAULT_RATES: [f64; 4] = [1e-5, 1e-4, 1e-3, 1e-2];

/// The missions of one (rate, kind) cell.
#[derive(Debug, Clone)]
pub struct FaultCell {
    /// Rate per byte.
    pub rate: f64,
    /// The kind.
    pub kind: FaultKind,
    /// The faulted direction.
    pub direction: LinkDirection,
    /// Each mission (seed order): its report and accounting, or why it could not run.
    pub missions: Vec<Result<(MissionReport, FaultAccount), String>>,
}

/// The profile of one cell's mission: `kind` alone at `rate` in direction `d`, the other parameters from `base`.
pub fn cell_profile(base: &FaultProfile, kind: FaultKind, rate: f64, d: LinkDirection) -> FaultProfile {
    let mut p = FaultProfile::single(kind, rate, base.seed);
    if d == LinkDirection::Down {
        core::mem::swap(&mut p.rates, &mut p.down_rates);
    }
    p.delay_us = base.delay_us;
    p.stall_us = base.stall_us;
    p.reorder_hold_us = base.reorder_hold_us;
    p
}

/// Runs every (rate, kind, seed) mission on `threads` threads; `tick` after each.
#[allow(clippy::too_many_arguments)]
pub fn run(
    sc: &Scenario,
    seeds: &[u64],
    rates: &[f64],
    kinds: &[FaultKind],
    base: &FaultProfile,
    direction: LinkDirection,
    tracking: Tracking,
    threads: usize,
    charge_host_time: bool,
    tick: &(dyn Fn() + Sync),
) -> Vec<FaultCell> {
    let cells: Vec<(f64, FaultKind)> = rates
        .iter()
        .flat_map(|&r| kinds.iter().map(move |&k| (r, k)))
        .collect();
    let per = seeds.len().max(1);
    let results = run_parallel(cells.len() * seeds.len(), threads, &|i| {
        let (rate, kind) = cells
            .get(i / per)
            .copied()
            .unwrap_or((0.0, FaultKind::Drop));
        let seed = seeds.get(i % per).copied().unwrap_or_default();
        let profile = cell_profile(base, kind, rate, direction);
        let r =
            run_one(sc, seed, tracking, Some(&profile), charge_host_time).and_then(|(rep, acc)| {
                acc.map(|a| (rep, a))
                    .ok_or_else(|| "no fault accounting".to_string())
            });
        tick();
        r
    });
    let mut it = results.into_iter();
    cells
        .into_iter()
        .map(|(rate, kind)| FaultCell {
            rate,
            kind,
            direction,
            missions: it.by_ref().take(seeds.len()).collect(),
        })
        .collect()
}

/// Whether a mission ended as the issue requires: arrived, or stopped safe with a reason.
pub fn ended_well(v: &Verdict) -> bool {
    matches!(v, Verdict::Arrived | Verdict::SafeStop(_))
}

/// Totals of a cell.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CellSummary {
    /// Missions that ran.
    pub ran: usize,
    /// Missions that could not run.
    pub errors: usize,
    /// Arrived.
    pub arrived: usize,
    /// Safe stops by reason.
    pub safe: BTreeMap<String, usize>,
    /// Falls.
    pub fell: usize,
    /// Other endings (false arrival, time limit, flight quiet) by name.
    pub other: BTreeMap<String, usize>,
    /// Faults injected, detected by telemetry, harmless.
    pub injected: u64,
    /// Detected by the flight software's telemetry.
    pub detected: u64,
    /// Harmless.
    pub harmless: u64,
    /// Missions whose accounting did not balance (with the first reason).
    pub unbalanced: Vec<(u64, String)>,
    /// `Ack`s of damaged uplink frames, plus drive commands executed from damaged downlink frames.
    pub acked_damaged: u64,
    /// Drive commands received again and not executed again (the host's count).
    pub commands_repeated: u64,
    /// Resent requests the flight software answered without acting again (`Telemetry.requests_repeated`, v5).
    pub requests_repeated: u64,
    /// Drive commands the flight software sent again for want of a report (`Telemetry.drive_resends`, v5).
    pub drive_resends: u64,
    /// Frames retransmitted by the host.
    pub retransmits: u64,
    /// Scan chunks the host sent again.
    pub chunks_resent: u64,
    /// Longest executive step, microseconds.
    pub max_step_us: u32,
    /// Executive steps over budget.
    pub slips: u64,
}

/// The totals of `cell`.
pub fn summarise(cell: &FaultCell) -> CellSummary {
    let mut s = CellSummary::default();
    for m in &cell.missions {
        let Ok((rep, acc)) = m else {
            s.errors += 1;
            continue;
        };
        s.ran += 1;
        match rep.verdict {
            Verdict::Arrived => s.arrived += 1,
            Verdict::SafeStop(r) => *s.safe.entry(format!("{r:?}")).or_default() += 1,
            Verdict::Fell => s.fell += 1,
            // The link is down and the rover never commanded: safe, the reason given by the ground.
            Verdict::Undelivered => *s.safe.entry("Undelivered(ground)".into()).or_default() += 1,
            v => *s.other.entry(v.name()).or_default() += 1,
        }
        match cell.direction {
            LinkDirection::Up => {
                s.injected += acc.injected(cell.kind);
                s.harmless += acc.harmless(cell.kind);
                s.detected += acc.detected(cell.kind.group()).unwrap_or(0);
            }
            LinkDirection::Down => {
                s.injected += acc.down_injected(cell.kind);
                s.harmless += acc.down_harmless(cell.kind);
                s.detected += acc.down_detected(cell.kind.group()).unwrap_or(0);
            }
        }
        if let Err(e) = acc.check() {
            s.unbalanced.push((rep.seed, e));
        }
        s.acked_damaged += acc.acked_damaged + acc.executed_damaged;
        s.commands_repeated += rep.commands_repeated;
        if let Some(t) = &acc.telemetry {
            s.requests_repeated += u64::from(t.requests_repeated);
            s.drive_resends += u64::from(t.drive_resends);
        }
        s.retransmits += rep.retransmits;
        s.chunks_resent += rep.chunks_resent;
        s.max_step_us = s.max_step_us.max(rep.max_step_us);
        s.slips += u64::from(rep.step_slips);
    }
    s
}

fn join(m: &BTreeMap<String, usize>) -> String {
    if m.is_empty() {
        "-".into()
    } else {
        m.iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The fault campaign table (Markdown) and its closing verdict lines.
pub fn table(name: &str, seeds: &[u64], cells: &[FaultCell]) -> String {
    let mut out = String::new();
    let dir = cells.first().map_or("uplink", |c| c.direction.name());
    let _ = writeln!(
        out,
        "fault campaign: {name}, seeds {seeds:?}, {dir} faults, one kind per mission (acked damaged: uplink frames acknowledged, or downlink frames whose drive command was executed; repeats: drive commands received again, not executed; flight resends: requests answered without acting again / drive commands sent again)"
    );
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "| rate/byte | kind | arrived | safe (reason) | fell | other | injected | detected | harmless | balanced | acked damaged | retransmits (frames / chunks) | repeats | flight resends | max step s | slips |"
    );
    let _ = writeln!(
        out,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    let (mut all, mut fell, mut other, mut unbalanced, mut acked, mut errors) = (0, 0, 0, 0, 0, 0);
    for c in cells {
        let s = summarise(c);
        all += s.ran;
        fell += s.fell;
        other += s.other.values().sum::<usize>();
        unbalanced += s.unbalanced.len();
        acked += s.acked_damaged;
        errors += s.errors;
        let _ = writeln!(
            out,
            "| {:e} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} / {} | {} | {} / {} | {:.3} | {} |",
            c.rate,
            c.kind.name(),
            s.arrived,
            join(&s.safe),
            s.fell,
            join(&s.other),
            s.injected,
            s.detected,
            s.harmless,
            if s.unbalanced.is_empty() {
                format!("{}/{}", s.ran, s.ran)
            } else {
                format!("{}/{}", s.ran - s.unbalanced.len(), s.ran)
            },
            s.acked_damaged,
            s.retransmits,
            s.chunks_resent,
            s.commands_repeated,
            s.requests_repeated,
            s.drive_resends,
            f64::from(s.max_step_us) * 1e-6,
            s.slips
        );
        for (seed, why) in &s.unbalanced {
            let _ = writeln!(out, "|  | seed {seed}: {why} | | | | | | | | | | | | | | |");
        }
    }
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "{all} missions: {fell} fell, {other} ended neither arrived nor safe, {unbalanced} with unbalanced accounting, {acked} damaged frames acknowledged, {errors} could not run"
    );
    out
}

/// Whether the campaign meets the bar: every mission ran and ended arrived or safe, balanced, no damaged
/// frame acknowledged.
pub fn passed(cells: &[FaultCell]) -> bool {
    cells.iter().all(|c| {
        c.missions.iter().all(|m| {
            m.as_ref()
                .is_ok_and(|(rep, acc)| ended_well(&rep.verdict) && acc.check().is_ok())
        })
    })
}
