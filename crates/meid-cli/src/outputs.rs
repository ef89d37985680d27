//! Output sets and disk budgets shared by the subcommands that write `-o DIR`.

use std::path::Path;

use anyhow::{bail, Result};

use meid::io::OutputSet;
use meid::limits::format_bytes;

/// Starts the output set of `-o DIR` ([`OutputSet`]: staged, then swapped in as a whole with
/// `manifest.json` written last). Refuses a DIR that is an existing file.
pub fn begin(dir: &Path) -> Result<OutputSet> {
    Ok(OutputSet::begin(dir)?)
}

/// Bytes free for an unprivileged user on the file system holding `dir`, where it can be read.
pub fn available_bytes(dir: &Path) -> Option<u64> {
    #[cfg(unix)]
    {
        let s = rustix::fs::statvfs(dir).ok()?;
        Some(s.f_bavail.saturating_mul(s.f_frsize))
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        None
    }
}

/// Refuses to write an estimated `bytes` into `dir` when the file system has less free space:
/// the run would fail with a full disk after all its work.
pub fn check_disk(dir: &Path, what: &str, bytes: f64, reduce: &str) -> Result<()> {
    if let Some(free) = available_bytes(dir) {
        if bytes.is_nan() || bytes > free as f64 {
            bail!(
                "{what} would take about {} on disk, more than the {} free in {}. Reduce {reduce}",
                format_bytes(bytes),
                format_bytes(free as f64),
                dir.display()
            );
        }
    }
    Ok(())
}
