//! `ncchannel soak merge REPORT...`: the campaign reports of all shards (`soak --shard I/N
//! --report FILE`, from however many machines) joined into one verdict, with the exit code of
//! a soak of the whole campaign.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use crate::soak::campaign::{merge, CampaignReport};

use super::exit;

/// Largest report file read: a campaign report of many runs, not an accident.
const MAX_REPORT_BYTES: u64 = 256 << 20;

#[derive(Debug, Clone, clap::Args)]
pub struct MergeArgs {
    /// Campaign reports of the shards (each shard exactly once).
    #[arg(required = true)]
    pub reports: Vec<PathBuf>,
    /// Write the merged campaign report here (- for standard output; the human report then
    /// goes to standard error).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Merge only reports of this campaign run (`soak --run-id`); without it, every report
    /// must be of the first one's run. A report of another run is stale: no verdict.
    #[arg(long, env = "NCCHANNEL_SOAK_RUN_ID", value_name = "ID")]
    pub run_id: Option<String>,
}

fn usage(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("ncchannel soak merge: {msg}");
    ExitCode::from(exit::USAGE)
}

/// Read one shard's campaign report.
fn read(path: &Path) -> Result<CampaignReport, String> {
    let bytes = crate::bounded::read_file(path, MAX_REPORT_BYTES)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_slice(&bytes).map_err(|e| {
        format!(
            "{}: not a campaign report ({e}); soak writes one with --shard, --seeds or several scenarios",
            path.display()
        )
    })
}

pub fn execute(args: MergeArgs) -> ExitCode {
    let mut reports = Vec::new();
    for p in &args.reports {
        match read(p) {
            Ok(r) => reports.push((p.display().to_string(), r)),
            Err(msg) => return usage(msg),
        }
    }
    let merged = match merge(reports, args.run_id.as_deref()) {
        Ok(m) => m,
        Err(e) => return usage(e),
    };
    let to_stderr = args
        .report
        .as_deref()
        .is_some_and(crate::destination::is_stdout);
    let _ = if to_stderr {
        merged.print_human(&mut std::io::stderr())
    } else {
        merged.print_human(&mut std::io::stdout())
    };
    if let Some(p) = &args.report {
        if !super::out::write_report("soak merge", p, &merged.to_json()) {
            return ExitCode::from(exit::USAGE);
        }
    }
    ExitCode::from(if merged.all_held {
        exit::OK
    } else {
        exit::CHANNEL_ERROR
    })
}
