//! Resource figures of the board binary: flash and RAM by section (read from the ELF's section headers, no
//! external tool needed), and on-target instruction counts from the board's benchmark mode.
//!
//! Memory regions of the mps2-an500 (see the board's `memory.x`): flash (code, 4 MiB at 0x0), SRAM (4 MiB at
//! 0x2000_0000: `.data`, `.bss`, the 256 KiB stack), PSRAM (16 MiB at 0x6000_0000: `.psram` arenas). A section
//! with file contents that is loaded into RAM (`.data`) also occupies flash for its initial values.

use core::time::Duration;
use std::path::Path;

use super::{run_to_exit, QemuConfig, QemuError};

const SHF_ALLOC: u32 = 0x2;
const SHT_NOBITS: u32 = 8;

/// Which memory a section occupies at run time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Region {
    /// Code memory (0x0000_0000 .. 0x0040_0000).
    Flash,
    /// SRAM (0x2000_0000 .. 0x2040_0000).
    Sram,
    /// PSRAM (0x6000_0000 .. 0x6100_0000).
    Psram,
    /// Anything else.
    Other,
}

impl Region {
    fn of(addr: u32) -> Self {
        match addr {
            0x0000_0000..=0x003F_FFFF => Self::Flash,
            0x2000_0000..=0x203F_FFFF => Self::Sram,
            0x6000_0000..=0x60FF_FFFF => Self::Psram,
            _ => Self::Other,
        }
    }
}

/// One allocated section of the ELF.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Section {
    /// Section name.
    pub name: String,
    /// Run-time address.
    pub addr: u32,
    /// Size in bytes.
    pub size: u32,
    /// True if the file holds contents for it (it is loaded: counts against flash even when it runs from RAM).
    pub has_contents: bool,
    /// Where it lives at run time.
    pub region: Region,
}

fn u16_at(b: &[u8], at: usize) -> Result<u16, String> {
    b.get(at..at + 2)
        .map(|s| u16::from_le_bytes([s[0], s[1]]))
        .ok_or_else(|| format!("ELF truncated at {at}"))
}
fn u32_at(b: &[u8], at: usize) -> Result<u32, String> {
    b.get(at..at + 4)
        .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
        .ok_or_else(|| format!("ELF truncated at {at}"))
}

/// The allocated (non-empty) sections of a 32-bit little-endian ELF.
pub fn elf_sections(path: &Path) -> Result<Vec<Section>, String> {
    let b = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if b.get(..4) != Some(b"\x7fELF".as_slice()) || b.get(4) != Some(&1) || b.get(5) != Some(&1) {
        return Err(format!(
            "{}: not a 32-bit little-endian ELF",
            path.display()
        ));
    }
    let shoff = u32_at(&b, 0x20)? as usize;
    let shentsize = u16_at(&b, 0x2E)? as usize;
    let shnum = u16_at(&b, 0x30)? as usize;
    let shstrndx = u16_at(&b, 0x32)? as usize;
    let header = |i: usize| shoff + i * shentsize;
    let strtab = u32_at(&b, header(shstrndx) + 0x10)? as usize;
    let mut out = Vec::new();
    for i in 0..shnum {
        let h = header(i);
        let (name_off, kind, flags) = (
            u32_at(&b, h)? as usize,
            u32_at(&b, h + 4)?,
            u32_at(&b, h + 8)?,
        );
        let (addr, size) = (u32_at(&b, h + 0x0C)?, u32_at(&b, h + 0x14)?);
        if flags & SHF_ALLOC == 0 || size == 0 {
            continue;
        }
        let name_bytes = b.get(strtab + name_off..).unwrap_or(&[]);
        let end = name_bytes
            .iter()
            .position(|&c| c == 0)
            .unwrap_or(name_bytes.len());
        out.push(Section {
            name: String::from_utf8_lossy(&name_bytes[..end]).into_owned(),
            addr,
            size,
            has_contents: kind != SHT_NOBITS,
            region: Region::of(addr),
        });
    }
    Ok(out)
}

/// Totals: (flash bytes, SRAM bytes excluding the stack, PSRAM bytes).
pub fn totals(sections: &[Section]) -> (u64, u64, u64) {
    let mut t = (0u64, 0u64, 0u64);
    for s in sections {
        let size = u64::from(s.size);
        match s.region {
            Region::Flash => t.0 += size,
            Region::Sram => {
                t.1 += size;
                if s.has_contents {
                    t.0 += size;
                }
            }
            Region::Psram => t.2 += size,
            Region::Other => {}
        }
    }
    t
}

/// The section table as text.
pub fn format_sections(sections: &[Section]) -> String {
    let mut s = format!(
        "{:<16} {:>10} {:>10}  {}\n",
        "section", "address", "bytes", "region"
    );
    for sec in sections {
        let region = match (sec.region, sec.has_contents) {
            (Region::Flash, _) => "flash",
            (Region::Sram, true) => "sram (+ flash for initial values)",
            (Region::Sram, false) => "sram",
            (Region::Psram, _) => "psram",
            (Region::Other, _) => "other",
        };
        s.push_str(&format!(
            "{:<16} 0x{:08x} {:>10}  {}\n",
            sec.name, sec.addr, sec.size, region
        ));
    }
    let (flash, sram, psram) = totals(sections);
    s.push_str(&format!(
        "total: flash {flash} B, sram {sram} B (+ stack), psram {psram} B\n"
    ));
    s
}

/// Instructions per SysTick tick under `-icount shift=0` (1 ns per instruction, 25 MHz core clock: the board's
/// `clock::INSTRUCTIONS_PER_TICK`).
pub const INSTRUCTIONS_PER_TICK: u64 = 40;

/// One workload's cost on target.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BenchResult {
    /// Workload name.
    pub name: String,
    /// Iterations run.
    pub iterations: u64,
    /// Instructions for all iterations (SysTick ticks x 40 under `-icount shift=0`).
    pub instructions: u64,
}

/// Boots the board in benchmark mode under `-icount shift=0` and parses its `bench:` lines.
pub fn run_bench(elf: &Path, timeout: Duration) -> Result<(Vec<BenchResult>, String), QemuError> {
    run_bench_with(elf, "tetherbot.mode=bench", timeout)
}

/// The value of `key=value` among the whitespace-separated words of `text` (the board's report and bench lines).
pub fn field<'a>(text: &'a str, key: &str) -> Option<&'a str> {
    text.split_whitespace().find_map(|w| w.strip_prefix(key)?.strip_prefix('='))
}

/// [`run_bench`] with other boot words (e.g. `tetherbot.mode=bench tetherbot.workload=tethered_test3`).
pub fn run_bench_with(
    elf: &Path,
    boot_words: &str,
    timeout: Duration,
) -> Result<(Vec<BenchResult>, String), QemuError> {
    let mut cfg = QemuConfig::new(elf.to_path_buf());
    cfg.icount = true;
    cfg.boot_words = Some(boot_words.into());
    let exit = run_to_exit(&cfg, timeout)?;
    let text = exit.output.both();
    if !exit.status.success() {
        return Err(QemuError::Exited(exit.status.code(), text));
    }
    let mut results = Vec::new();
    for line in text.lines().filter(|l| l.starts_with("bench: name=")) {
        let (Some(name), Some(it), Some(ins)) =
            (field(line, "name"), field(line, "iterations"), field(line, "instructions"))
        else {
            continue;
        };
        results.push(BenchResult {
            name: name.to_owned(),
            iterations: it.parse().unwrap_or(0),
            instructions: ins.parse().unwrap_or(0),
        });
    }
    Ok((results, text))
}

/// The bench results as a table.
pub fn format_bench(results: &[BenchResult]) -> String {
    let mut s = format!(
        "{:<28} {:>10} {:>14} {:>14}\n",
        "workload", "iterations", "instructions", "per iteration"
    );
    for r in results {
        s.push_str(&format!(
            "{:<28} {:>10} {:>14} {:>14}\n",
            r.name,
            r.iterations,
            r.instructions,
            r.instructions / r.iterations.max(1)
        ));
    }
    s
}
