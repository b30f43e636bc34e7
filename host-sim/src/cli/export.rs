//! `tetherbot export LOG --mcap out.mcap`.

use std::path::PathBuf;
use std::process::ExitCode;

use crate::fieldlog;
use crate::mcap_export;

/// Arguments of `export`.
#[derive(Debug, Clone, clap::Args)]
pub struct ExportArgs {
    /// The field log.
    pub log: PathBuf,
    /// Write an MCAP file here.
    #[arg(long, value_name = "OUT")]
    pub mcap: PathBuf,
}

/// `export` entry point.
pub fn main(args: &ExportArgs) -> ExitCode {
    let log = match fieldlog::read_file(&args.log) {
        Ok(l) => l,
        Err(e) => return super::fail(e),
    };
    let file = match std::fs::File::create(&args.mcap) {
        Ok(f) => f,
        Err(e) => return super::fail(format!("cannot create {}: {e}", args.mcap.display())),
    };
    match mcap_export::export(&log, std::io::BufWriter::new(file)) {
        Ok(s) => {
            println!(
                "{}: {} raw records, {} decoded frames ({} undecodable)",
                args.mcap.display(),
                s.raw_records,
                s.frames,
                s.bad_frames
            );
            if let Some(d) = log.damage {
                println!(
                    "note: log damaged at byte {} ({:?}); exported the records before it",
                    d.offset, d.reason
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => super::fail(format!("MCAP export failed: {e}")),
    }
}
