//! The SciPy peer (`bench/peer/impact_rk45.py`) run on one impact system: shared by the
//! benchmark examples (`#[path]`-included; not an example itself).

use std::path::Path;
use std::process::Command;

use meid::impact::ImpactSystem;

/// What the peer measured on one collision.
pub struct PeerRun {
    /// SciPy's version string.
    pub scipy: String,
    /// Every run's wall time (s).
    pub times_s: Vec<f64>,
    /// Its energy ratio E_p+/E_s-.
    pub energy_ratio: f64,
}

impl PeerRun {
    /// `(median, minimum)` of the runs' wall times (s).
    #[allow(dead_code)] // (`impact_bench` pools the times with its own rounds instead)
    pub fn median_min(&self) -> (f64, f64) {
        median_min(self.times_s.clone())
    }
}

/// `(median, minimum)` of `v` (not empty; the median of an even count is the mean of the two
/// middle values).
pub fn median_min(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    let median = if v.len().is_multiple_of(2) {
        0.5 * (v[m - 1] + v[m])
    } else {
        v[m]
    };
    (median, v[0])
}

/// `sys` as the peers' JSON spec (modal frequencies, damping matrix, mode-shape values at O_b
/// and O_f, slider, damper and contact data): what `bench/peer/*.py` read.
pub fn spec_json(sys: &ImpactSystem) -> Result<serde_json::Value, String> {
    let st = &sys.structure;
    let damper = sys
        .damper
        .ok_or("the peer needs a system with an impact damper")?;
    let bed_damper = sys
        .bed_damper
        .ok_or("the peer needs a bed-damper contact")?;
    let spec = serde_json::json!({
        "omega": st.omega_rad_per_s, "damping": st.damping,
        "phi_b": sys.points.bed_contact, "phi_f": sys.points.damper_anchor,
        "m_s": sys.slider.mass, "v_s": sys.slider.velocity,
        "m_d": damper.mass, "k_d": damper.stiffness, "c_d": damper.damping,
        "K_s": sys.slider_bed.law.stiffness(), "K_d": bed_damper.law.stiffness(),
    });
    Ok(spec)
}

/// Writes `sys` as the peer's JSON spec and runs the script `runs` times on it.
pub fn scipy_collision(sys: &ImpactSystem, root: &Path, runs: usize) -> Result<PeerRun, String> {
    let spec = spec_json(sys)?;
    let path = std::env::temp_dir().join(format!("meid_impact_peer_{}.json", std::process::id()));
    std::fs::write(&path, spec.to_string()).map_err(|e| e.to_string())?;
    let out = Command::new("python3")
        .arg(root.join("bench/peer/impact_rk45.py"))
        .arg(&path)
        .arg(runs.to_string())
        .output()
        .map_err(|e| format!("python3 not run: {e}"))?;
    let _ = std::fs::remove_file(&path);
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).map_err(|e| e.to_string())?;
    let num = |k: &str| v[k].as_f64().ok_or(format!("peer output has no {k}"));
    Ok(PeerRun {
        scipy: v["scipy"].as_str().unwrap_or("?").to_string(),
        times_s: v["times_s"]
            .as_array()
            .map(|a| a.iter().filter_map(|t| t.as_f64()).collect())
            .filter(|t: &Vec<f64>| !t.is_empty())
            .ok_or("peer output has no times_s")?,
        energy_ratio: num("energy_ratio")?,
    })
}
