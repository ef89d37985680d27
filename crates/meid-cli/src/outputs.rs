//! Output sets and disk budgets shared by the subcommands that write `-o DIR`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use meid::io::OutputSet;
use meid::limits::format_bytes;

/// Starts the output set of `-o DIR` ([`OutputSet`]: staged, then swapped in as a whole with
/// `manifest.json` written last). Refuses a DIR that is an existing file, and a DIR another
/// meid process is writing into ([`lock_dir`]).
pub fn begin(dir: &Path) -> Result<OutputSet> {
    if !dir.exists() || dir.is_dir() {
        std::fs::create_dir_all(dir).map_err(|e| {
            anyhow::anyhow!("-o {}: cannot create the directory: {e}", dir.display())
        })?;
        lock_dir(dir)?;
    }
    Ok(OutputSet::begin(dir)?)
}

/// The output directories this process holds locked, with the open directory that holds each
/// lock (kept open until the process ends, which releases the lock, on a signal too).
static LOCKED: std::sync::Mutex<Vec<(PathBuf, std::fs::File)>> = std::sync::Mutex::new(Vec::new());

/// Takes an exclusive advisory lock (`flock`) on the directory `dir` for the rest of this
/// process, so that two runs never write one output set or one sweep journal at once (two
/// `sweep --resume` into one DIR would interleave its rows). A DIR another process holds is
/// refused. Where `flock` is not available (not Unix), nothing is locked.
pub fn lock_dir(dir: &Path) -> Result<()> {
    #[cfg(unix)]
    {
        let key = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
        let mut held = LOCKED
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if held.iter().any(|(p, _)| *p == key) {
            return Ok(());
        }
        let f = std::fs::File::open(dir)
            .map_err(|e| anyhow::anyhow!("-o {}: cannot open the directory: {e}", dir.display()))?;
        match rustix::fs::flock(&f, rustix::fs::FlockOperation::NonBlockingLockExclusive) {
            Ok(()) => held.push((key, f)),
            Err(e) if e == rustix::io::Errno::WOULDBLOCK => bail!(
                "-o {}: another meid run is writing into this directory (it holds the directory's lock); wait for it to end, or give another -o DIR",
                dir.display()
            ),
            // A file system without flock (some network mounts): go on unlocked.
            Err(_) => {}
        }
    }
    #[cfg(not(unix))]
    let _ = dir;
    Ok(())
}

/// Ends the process on SIGINT (exit 130) or SIGTERM (exit 143) after removing the staging
/// directories of unfinished output sets ([`meid::io::remove_live_staging`]); a sweep's
/// journal stays, for `--resume`. Installed once at start; where signals cannot be caught,
/// the default action (and the next run's removal of dead staging directories) remains.
pub fn on_signal_clean_up() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGINT, SIGTERM};
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
            return;
        };
        let _ = std::thread::Builder::new()
            .name("meid-signals".into())
            .spawn(move || {
                if let Some(sig) = signals.forever().next() {
                    meid::io::remove_live_staging();
                    std::process::exit(128 + sig);
                }
            });
    }
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

/// Writes `table` as the Parquet file `path` beside its CSV (docs/reference/outputs.md,
/// "Parquet"). A meid built without the `parquet` feature (the README's first command leaves it
/// out to build faster) writes no Parquet file and says so on standard error.
pub fn write_parquet_table(path: &Path, table: &meid::io::table::Table) -> Result<()> {
    #[cfg(feature = "parquet")]
    meid::io::parquet::write_parquet(path, table)?;
    #[cfg(not(feature = "parquet"))]
    {
        let _ = table;
        crate::ui::warning(format_args!(
            "{} not written: this meid was built without the `parquet` feature \
             (`cargo install --locked --path crates/meid-cli` has it)",
            path.file_name()
                .map(|n| n.to_string_lossy())
                .unwrap_or_default()
        ));
    }
    Ok(())
}
