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
    /// Write an MCAP file here (refused if it exists, unless `--force`; never the log itself).
    #[arg(long, value_name = "OUT")]
    pub mcap: PathBuf,
    /// Overwrite an existing output file.
    #[arg(long)]
    pub force: bool,
}

/// `export` entry point.
pub fn main(args: &ExportArgs) -> ExitCode {
    let log = match fieldlog::read_file(&args.log) {
        Ok(l) => l,
        Err(e) => return super::fail(e),
    };
    if let Err(e) = super::check_output(&args.mcap, args.force, &[&args.log]) {
        return super::fail(e);
    }
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
            for d in &log.damaged {
                println!(
                    "note: log damaged at byte {} ({:?}); {} bytes skipped, the valid records around it exported",
                    d.offset, d.reason, d.unread_bytes
                );
            }
            if log.completeness() != fieldlog::Completeness::Complete {
                println!("note: log incomplete: {}", log.completeness());
            }
            ExitCode::SUCCESS
        }
        Err(e) => super::fail(format!("MCAP export failed: {e}")),
    }
}
