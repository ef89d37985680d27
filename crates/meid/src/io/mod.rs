//! Files out: atomic writes, CSV time histories with units in the header, JSON.
//!
//! Every file is written to a temporary file in the target directory and renamed into place,
//! so an interrupted run never leaves a half-written output.

pub mod matrix_market;
pub mod vtk;

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::analysis::History;
use crate::{Error, Result};

/// Writes `bytes` to `path` atomically (temporary file in the same directory, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let file_name = path
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_else(|| "out".into());
    let tmp: PathBuf = dir.join(format!(".{file_name}.{}.tmp", std::process::id()));
    {
        let mut f = std::fs::File::create(&tmp).map_err(|e| Error::io(&tmp, e))?;
        f.write_all(bytes).map_err(|e| Error::io(&tmp, e))?;
        f.sync_all().map_err(|e| Error::io(&tmp, e))?;
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })
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

/// Time histories as CSV text: one header row of `quantity_unit` names, then one row per
/// sample. `machine_energy_j` is Eq. (24): `KE_p + PE_p + dissipated`.
pub fn history_csv(h: &History) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let err = |e: csv::Error| Error::numerical("csv", e.to_string());
    w.write_record(HISTORY_COLUMNS).map_err(err)?;
    let mut row: Vec<String> = Vec::with_capacity(HISTORY_COLUMNS.len());
    for i in 0..h.time_s.len() {
        let e = &h.energy[i];
        let vals = [
            h.time_s[i],
            h.bed_displacement_m[i],
            h.bed_velocity_m_per_s[i],
            h.bed_acceleration_m_per_s2[i],
            h.floor_force_n[i],
            h.contact_force_slider_bed_n[i],
            h.contact_force_bed_damper_n[i],
            h.damper_force_n[i],
            h.slider_displacement_m[i],
            h.slider_velocity_m_per_s[i],
            h.damper_displacement_m[i],
            h.damper_velocity_m_per_s[i],
            e.ke_slider,
            e.pe_slider_contact,
            e.ke_machine,
            e.pe_machine,
            e.ke_damper,
            e.pe_damper_spring,
            e.pe_damper_contact,
            h.dissipated_j[i],
            e.ke_machine + e.pe_machine + h.dissipated_j[i],
        ];
        row.clear();
        row.extend(vals.iter().map(|v| format!("{v:.12e}")));
        w.write_record(&row).map_err(err)?;
    }
    w.into_inner()
        .map_err(|e| Error::numerical("csv", e.to_string()))
}
