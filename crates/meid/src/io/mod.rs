//! Files out: atomic writes, CSV time histories with units in the header, JSON.
//!
//! Every file is written to a temporary file in the target directory and renamed into place,
//! so an interrupted run never leaves a half-written output.

pub mod csv_records;
pub mod frd;
pub mod matrix_market;
#[cfg(feature = "parquet")]
pub mod parquet;
pub mod table;
pub mod uff;
pub mod vtk;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::{Error, Result};

/// A file written through a temporary beside it and renamed into place by [`Self::commit`].
/// Dropped without a commit (any error path, a panic), it removes its temporary: a failed write
/// leaves neither a half-written target nor a `.NAME.PID.N.tmp` behind.
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    file: Option<std::io::BufWriter<std::fs::File>>,
}

impl AtomicFile {
    /// Creates the temporary `.NAME.PID.N.tmp` in `path`'s directory (created if missing).
    pub fn create(path: &Path) -> Result<Self> {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let file_name = path
            .file_name()
            .map(|f| f.to_string_lossy().to_string())
            .unwrap_or_else(|| "out".into());
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(".{file_name}.{}.{n}.tmp", std::process::id()));
        let f = std::fs::File::create(&tmp).map_err(|e| Error::io(&tmp, e))?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp,
            file: Some(std::io::BufWriter::new(f)),
        })
    }

    /// The temporary's path (removed on drop unless committed).
    pub fn temporary_path(&self) -> &Path {
        &self.tmp
    }

    /// Appends `bytes`; an error names the target.
    pub fn write_all(&mut self, bytes: &[u8]) -> Result<()> {
        match self.file.as_mut() {
            Some(f) => f.write_all(bytes).map_err(|e| Error::io(&self.path, e)),
            None => Err(Error::io(
                &self.path,
                std::io::Error::other("already committed"),
            )),
        }
    }

    /// Flushes, syncs and renames the temporary onto the target.
    pub fn commit(mut self) -> Result<()> {
        let Some(f) = self.file.take() else {
            return Ok(());
        };
        let f = f
            .into_inner()
            .map_err(|e| Error::io(&self.path, e.into_error()))?;
        f.sync_all().map_err(|e| Error::io(&self.path, e))?;
        drop(f);
        std::fs::rename(&self.tmp, &self.path).map_err(|e| Error::io(&self.path, e))?;
        self.tmp = PathBuf::new();
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self.file.as_mut() {
            Some(f) => f.write(buf),
            None => Err(std::io::Error::other("already committed")),
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        match self.file.as_mut() {
            Some(f) => f.flush(),
            None => Ok(()),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        self.file = None;
        if !self.tmp.as_os_str().is_empty() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Writes `bytes` to `path` atomically (temporary file in the same directory, then rename;
/// the temporary is removed on every error path, see [`AtomicFile`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut f = AtomicFile::create(path)?;
    f.write_all(bytes)?;
    f.commit()
}

/// Serialises `value` as pretty JSON to `path`, atomically.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut s = serde_json::to_string_pretty(value)
        .map_err(|e| Error::numerical("json", format!("cannot serialise: {e}")))?;
    s.push('\n');
    write_atomic(path, s.as_bytes())
}

/// Column names (with units) of [`history_csv`].
pub const HISTORY_COLUMNS: [&str; 21] = [
    "time_s",
    "bed_displacement_m",
    "bed_velocity_m_per_s",
    "bed_acceleration_m_per_s2",
    "floor_force_n",
    "contact_force_slider_bed_n",
    "contact_force_bed_damper_n",
    "damper_force_n",
    "slider_displacement_m",
    "slider_velocity_m_per_s",
    "damper_displacement_m",
    "damper_velocity_m_per_s",
    "ke_slider_j",
    "pe_slider_contact_j",
    "ke_machine_j",
    "pe_machine_j",
    "ke_damper_j",
    "pe_damper_spring_j",
    "pe_damper_contact_j",
    "dissipated_j",
    "machine_energy_j",
];

/// Bytes per row of [`history_csv`] used for estimates: 21 values of at most 19 characters
/// (`-1.234567890123e-10`) and their separators.
pub const HISTORY_ROW_BYTES: u64 = 21 * 20;

/// Writes the rows of [`history_csv`] one at a time to any writer (a file, for histories too
/// long to hold): the header on creation, then [`Self::row`] per sample.
pub struct HistoryWriter<W: Write> {
    out: W,
    line: String,
    rows: u64,
}

impl<W: Write> HistoryWriter<W> {
    /// Writes the header ([`HISTORY_COLUMNS`]).
    pub fn new(mut out: W) -> std::io::Result<Self> {
        let mut line = HISTORY_COLUMNS.join(",");
        line.push('\n');
        out.write_all(line.as_bytes())?;
        Ok(HistoryWriter { out, line, rows: 0 })
    }

    /// Writes one sample: the values in [`HISTORY_COLUMNS`] order, `{:.12e}`.
    pub fn row(&mut self, values: &[f64; 21]) -> std::io::Result<()> {
        use std::fmt::Write as _;
        self.line.clear();
        for (k, v) in values.iter().enumerate() {
            if k > 0 {
                self.line.push(',');
            }
            let _ = write!(self.line, "{v:.12e}");
        }
        self.line.push('\n');
        self.rows += 1;
        self.out.write_all(self.line.as_bytes())
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// The writer back (flushed).
    pub fn into_inner(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// A time history as [`history_csv`] writes it: its samples, each the values of
/// [`HISTORY_COLUMNS`] in order (the simulation's `analysis::History` is one). This module
/// knows the file format; the history knows its quantities.
pub trait HistoryRows {
    /// Number of samples.
    fn samples(&self) -> usize;
    /// Sample `i` in [`HISTORY_COLUMNS`] order.
    fn row(&self, i: usize) -> [f64; 21];
}

/// Time histories as CSV text: one header row of `quantity_unit` names, then one row per
/// sample. `machine_energy_j` is Eq. (24): `KE_p + PE_p + dissipated`.
pub fn history_csv<H: HistoryRows + ?Sized>(h: &H) -> Result<Vec<u8>> {
    let err = |e: std::io::Error| Error::numerical("csv", e.to_string());
    let mut w = HistoryWriter::new(Vec::new()).map_err(err)?;
    for i in 0..h.samples() {
        w.row(&h.row(i)).map_err(err)?;
    }
    w.into_inner().map_err(err)
}

/// Writes [`history_csv`] of `h` to `path` atomically, row by row (no copy of the text in
/// memory).
pub fn write_history_csv<H: HistoryRows + ?Sized>(path: &Path, h: &H) -> Result<()> {
    let mut f = AtomicFile::create(path)?;
    {
        let mut w = HistoryWriter::new(&mut f).map_err(|e| Error::io(path, e))?;
        for i in 0..h.samples() {
            w.row(&h.row(i)).map_err(|e| Error::io(path, e))?;
        }
        w.into_inner().map_err(|e| Error::io(path, e))?;
    }
    f.commit()
}

/// Name of the manifest an [`OutputSet`] writes last.
pub const MANIFEST: &str = "manifest.json";

/// A run's output files, replaced **as a set**.
///
/// Files are written into a private staging directory `DIR/.meid-staging.PID.N` (use
/// [`Self::staging`] / [`Self::path`]); the files of the previous run stay untouched until
/// [`Self::commit`]. The commit removes `DIR/manifest.json` (from then on the directory is
/// marked as being replaced), moves the staged files into `DIR` by rename, deletes the files
/// the previous manifest listed that the new set does not have (e.g. a picture of another
/// metric), and writes the new `manifest.json` last. So `manifest.json` present ⇒ the files
/// it lists are one run's complete set. A run that fails before the commit drops the set:
/// its staging directory is removed and the previous set, manifest included, is left as it
/// was. Files not listed in a manifest (a sweep's journal, the user's own files) are never
/// touched.
pub struct OutputSet {
    dir: PathBuf,
    staging: PathBuf,
}

/// One file of a [`MANIFEST`].
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ManifestFile {
    pub name: String,
    pub bytes: u64,
}

/// The content of [`MANIFEST`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Manifest {
    /// The command that wrote the set (`simulate`, `sweep`, ...).
    pub command: String,
    pub meid_version: String,
    /// The files of the set, sorted by name (the manifest itself not included).
    pub files: Vec<ManifestFile>,
}

impl OutputSet {
    /// Creates `dir` if needed and a fresh staging directory in it. Refuses a `dir` that exists
    /// and is not a directory.
    pub fn begin(dir: &Path) -> Result<Self> {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        if dir.exists() && !dir.is_dir() {
            return Err(Error::Input {
                location: format!("-o {}", dir.display()),
                message: "exists and is not a directory".into(),
            });
        }
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        remove_dead_staging(dir);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let staging = dir.join(format!(".meid-staging.{}.{n}", std::process::id()));
        std::fs::create_dir(&staging).map_err(|e| Error::io(&staging, e))?;
        live_staging(|l| l.push(staging.clone()));
        Ok(OutputSet {
            dir: dir.to_path_buf(),
            staging,
        })
    }

    /// The output directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The staging directory: write the set's files here.
    pub fn staging(&self) -> &Path {
        &self.staging
    }

    /// `staging/name`.
    pub fn path(&self, name: &str) -> PathBuf {
        self.staging.join(name)
    }

    /// Moves the staged files into place, removes the previous set's leftovers and writes the
    /// manifest (see the type's docs). Returns the final paths, sorted.
    pub fn commit(mut self, command: &str) -> Result<Vec<PathBuf>> {
        let staging = std::mem::take(&mut self.staging);
        let result = commit_set(&self.dir, &staging, command);
        let _ = std::fs::remove_dir_all(&staging);
        live_staging(|l| l.retain(|p| *p != staging));
        result
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if !self.staging.as_os_str().is_empty() {
            let _ = std::fs::remove_dir_all(&self.staging);
            live_staging(|l| l.retain(|p| *p != self.staging));
        }
    }
}

/// The staging directories of this process's output sets not yet committed or dropped.
static LIVE_STAGING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn live_staging<T>(f: impl FnOnce(&mut Vec<PathBuf>) -> T) -> T {
    let mut g = LIVE_STAGING
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    f(&mut g)
}

/// Removes the staging directories of every output set of this process not yet committed
/// (for a process about to end on a signal, whose destructors will not run: an interrupted
/// run leaves no `.meid-staging.PID.N` behind). Returns the directories removed.
pub fn remove_live_staging() -> Vec<PathBuf> {
    let dirs = live_staging(std::mem::take);
    for d in &dirs {
        // Worker threads may still create files in it: a few attempts.
        for _ in 0..5 {
            if std::fs::remove_dir_all(d).is_ok() || !d.exists() {
                break;
            }
        }
    }
    dirs
}

/// Removes the staging directories `.meid-staging.PID.N` in `dir` left by killed runs: those
/// whose process is gone (Linux: no `/proc/PID`). Elsewhere, or for a live process, nothing is
/// removed.
fn remove_dead_staging(dir: &Path) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let Some(rest) = name.strip_prefix(".meid-staging.") else {
            continue;
        };
        let Some(pid) = rest.split('.').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// Reads `DIR/manifest.json`, if there is a readable one.
pub fn read_manifest(dir: &Path) -> Option<Manifest> {
    let text = std::fs::read_to_string(dir.join(MANIFEST)).ok()?;
    serde_json::from_str(&text).ok()
}

fn commit_set(dir: &Path, staging: &Path, command: &str) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(staging).map_err(|e| Error::io(staging, e))? {
        let entry = entry.map_err(|e| Error::io(staging, e))?;
        let meta = entry.metadata().map_err(|e| Error::io(entry.path(), e))?;
        let name = entry.file_name().to_string_lossy().to_string();
        // Temporaries of an atomic write inside the staging directory are not part of the set.
        if meta.is_file() && !name.starts_with('.') && name != MANIFEST {
            files.push(ManifestFile {
                name,
                bytes: meta.len(),
            });
        }
    }
    files.sort_by(|a, b| a.name.cmp(&b.name));
    let old = read_manifest(dir);
    let manifest_path = dir.join(MANIFEST);
    match std::fs::remove_file(&manifest_path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(Error::io(&manifest_path, e)),
    }
    let mut out = Vec::with_capacity(files.len());
    for f in &files {
        let to = dir.join(&f.name);
        std::fs::rename(staging.join(&f.name), &to).map_err(|e| Error::io(&to, e))?;
        out.push(to);
    }
    if let Some(old) = old {
        for f in old.files {
            // Plain names only: a manifest never reaches outside its directory.
            let plain = !f.name.is_empty()
                && Path::new(&f.name).file_name() == Some(std::ffi::OsStr::new(&f.name))
                && f.name != MANIFEST;
            if plain && !files.iter().any(|n| n.name == f.name) {
                let _ = std::fs::remove_file(dir.join(&f.name));
            }
        }
    }
    write_json(
        &manifest_path,
        &Manifest {
            command: command.to_string(),
            meid_version: env!("CARGO_PKG_VERSION").to_string(),
            files,
        },
    )?;
    Ok(out)
}
