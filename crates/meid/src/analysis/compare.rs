//! The paper's comparison (section 4, Figs. 10, 11, 13, 14, 18, 19): one machine, one blow
//! (or a train of blows), three cases — no damper, the impact damper, a rigid added mass — and
//! by how many dB each case lowers the bed acceleration at B and the force to the floor.
//!
//! The added mass is [`Model::added_mass`]: `added_mass.mass` (default: the damper's mass m_d)
//! fixed at `added_mass.point` (default: the bed contact point O_b; the paper's Figs. 10-11 also
//! put it on the floating base, `point = "O_f"` or the lumped model's `"base"`).
//!
//! # Formulation
//!
//! Each case is simulated over the same record (default 2 s, sampled at the model's rate).
//! Levels are taken two ways:
//!
//! * **Time-domain peaks** `max |a_B(t)|`, `max |F_floor(t)|`, as dB ratios
//!   `20 log10(peak_case / peak_none)`.
//! * **Spectral peaks at the dominant modes**: the whole record's one-sided amplitude spectrum
//!   ([`super::spectrum::amplitude_spectrum_padded`], zero-padded to 4× the record length,
//!   which interpolates the spectrum between the `1/T` bins) with a chosen window and its
//!   coherent-gain correction, `A_k = 2|X_k|/Σw`, so a sinusoid of peak amplitude `A` reads
//!   `A` (within the window's scalloping loss: rectangular 3.92 dB, Hann 1.42 dB, flat-top
//!   0.004 dB at most — with 4× padding the worst case shrinks to ~0.2 dB rectangular,
//!   0.1 dB Hann). Levels are RMS, `L = 20 log10((A/√2)/A_ref)` dB re 1 m/s² (or ISO 1683's
//!   1e-6 m/s²) and re 1 N (Heinzel et al. 2002; ISO 1683:2015). The default is the
//!   **rectangular** window: the blow's transient starts at t = 0, where a Hann or flat-top
//!   taper is zero, so those windows weight the response by where it sits in the record
//!   (on the paper example Hann reads the 283 Hz bed mode, which decays in ~0.06 s, 30 dB
//!   low). Rectangular is exact for a transient that has decayed inside the record; for a
//!   lightly damped mode that still rings at the end of the record it leaks, and Hann or
//!   flat-top (which reads steady sinusoids best) can be chosen.
//!
//! The dominant modes are the model's reference mode (the rigid-body mode, the paper's ω_6)
//! and, among the other modes with ω > 0, the one with the largest `|ψ(O_b)|·|ψ(B)|` (struck
//! at the bed and seen at B: the paper's first bed mode, 283 Hz), or frequencies the user
//! names. Each level is the largest spectral line within ±10 % of **that case's own** mode
//! frequency: the added mass lowers the modes (Rayleigh-Ritz on the retained modes,
//! [`crate::modal::ModalModel::with_point_mass`]), so the band follows it. For user-named
//! frequencies the band is ±10 % around the named value in every case.
//!
//! **Reductions** are `ΔL = L_none − L_case` dB: positive means the case is quieter. For a
//! spring-mounted mass `M` hit by an impulse `J` the peak spring force is `J √(k/M)`
//! (`= v √(kM)` with `v = J/M`), so a rigid added mass `m` gives `ΔL = 10 log10(1 + m/M)`
//! (0.79 dB for 20 %, 3.01 dB for 100 %) — the baseline the damper must beat.
//!
//! The paper's own figures are carried as [`PAPER_FIGURES`] to print beside ours.
//!
//! # Example
//!
//! ```no_run
//! use meid::analysis::compare::{CompareOptions, Comparison};
//! use meid::model::Model;
//!
//! let model = Model::from_file("examples/paper-lumped.toml".as_ref(), &[])?;
//! let result = Comparison::new(model, CompareOptions::default()).run()?;
//! for row in &result.reductions {
//!     println!("{} {}: {:.2} dB", row.case, row.metric, row.reduction_db);
//! }
//! # Ok::<(), meid::Error>(())
//! ```

use serde::Serialize;

use super::blows::{run_blows, BlowOptions};
use super::energy::{simulate, History};
use super::spectrum::{
    amplitude_spectrum_padded, level_db, Padding, Spectrum, Window, REF_ACCELERATION_M_PER_S2,
    REF_FORCE_N,
};
use crate::impact::ImpactSystem;
use crate::model::{Case, Model};
use crate::{Error, Result};

/// Figures reported in the paper (Ahmadi-style MEID study), to print beside ours.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PaperFigure {
    pub what: &'static str,
    pub reduction_db: f64,
}

/// The paper's reductions in dB (positive = quieter than without damper).
pub const PAPER_FIGURES: [PaperFigure; 6] = [
    PaperFigure {
        what: "impact damper, vibration power (conclusion)",
        reduction_db: 3.0,
    },
    PaperFigure {
        what: "added mass, vibration power (conclusion)",
        reduction_db: 2.0,
    },
    PaperFigure {
        what: "impact damper, bed acceleration, experiment (soft support, Fig. 21)",
        reduction_db: 3.2,
    },
    PaperFigure {
        what: "impact damper, floor force, experiment (soft support, Fig. 22)",
        reduction_db: 3.3,
    },
    PaperFigure {
        what: "impact damper, bed acceleration, no floating base (Fig. 18)",
        reduction_db: 2.3,
    },
    PaperFigure {
        what: "impact damper, floor force, no floating base (Fig. 19)",
        reduction_db: 2.4,
    },
];

/// Settings of a comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct CompareOptions {
    /// Record length (s) for a single blow (default 2 s).
    pub duration_s: f64,
    /// Number of blows (1 = a single blow over `duration_s`).
    pub blows: usize,
    /// Stroke rate (blows per minute) when `blows > 1`; the record is then `blows · 60/rate`.
    pub rate_bpm: f64,
    /// Window of the spectra (default rectangular, see the module docs).
    pub window: Window,
    /// Reference for acceleration levels (m/s²): 1 (default) or 1e-6 (ISO 1683).
    pub acceleration_reference_m_per_s2: f64,
    /// Mode frequencies (Hz) to read levels at instead of the model's dominant modes.
    pub mode_frequencies_hz: Option<Vec<f64>>,
    /// Half-width of the search band as a fraction of the mode frequency (default 0.10).
    pub band_fraction: f64,
}

impl Default for CompareOptions {
    fn default() -> Self {
        Self {
            duration_s: 2.0,
            blows: 1,
            rate_bpm: 60.0,
            window: Window::Rectangular,
            acceleration_reference_m_per_s2: REF_ACCELERATION_M_PER_S2,
            mode_frequencies_hz: None,
            band_fraction: 0.10,
        }
    }
}

/// One of the three cases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CaseName {
    NoDamper,
    Damper,
    AddedMass,
}

impl CaseName {
    /// Short name for files and tables.
    pub fn name(self) -> &'static str {
        match self {
            CaseName::NoDamper => "no-damper",
            CaseName::Damper => "damper",
            CaseName::AddedMass => "added-mass",
        }
    }
    /// Legend text.
    pub fn label(self) -> &'static str {
        match self {
            CaseName::NoDamper => "without damper",
            CaseName::Damper => "impact damper",
            CaseName::AddedMass => "added mass",
        }
    }
    fn case(self) -> Case {
        match self {
            CaseName::NoDamper => Case::NoDamper,
            CaseName::Damper => Case::Damper,
            CaseName::AddedMass => Case::AddedMass,
        }
    }
}

impl std::fmt::Display for CaseName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The level at one dominant mode in one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeLevel {
    /// e.g. "mode 1 (reference)" or "6.35 Hz (named)".
    pub name: String,
    /// Centre of the search band in this case (Hz).
    pub centre_hz: f64,
    pub band_hz: [f64; 2],
    /// Where the acceleration / force peaks were found (Hz).
    pub acceleration_peak_hz: f64,
    pub floor_force_peak_hz: f64,
    /// dB re the acceleration reference (RMS).
    pub acceleration_level_db: f64,
    /// dB re 1 N (RMS).
    pub floor_force_level_db: f64,
}

/// The results of one case.
#[derive(Debug, Clone)]
pub struct CaseResult {
    pub case: CaseName,
    pub history: History,
    pub acceleration_spectrum: Spectrum,
    pub floor_force_spectrum: Spectrum,
    pub peak_bed_acceleration_m_per_s2: f64,
    pub peak_floor_force_n: f64,
    pub modes: Vec<ModeLevel>,
    /// E_p+/E_s− of the (first) blow.
    pub energy_ratio: Option<f64>,
}

/// One row of the reduction table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Reduction {
    pub case: CaseName,
    /// e.g. "peak bed acceleration", "floor force at mode 1 (reference)".
    pub metric: String,
    /// dB re the metric's reference: time peaks as `20 log10(peak/ref)`, spectral as RMS levels.
    pub level_db: f64,
    pub no_damper_level_db: f64,
    /// `L_none − L_case` (positive: quieter than without damper).
    pub reduction_db: f64,
}

/// The finished comparison.
#[derive(Debug, Clone)]
pub struct ComparisonResult {
    pub sample_rate_hz: f64,
    /// The added-mass case's mass (kg) and point, when that case ran.
    pub added_mass: Option<(f64, String)>,
    pub window: Window,
    pub acceleration_reference_m_per_s2: f64,
    pub cases: Vec<CaseResult>,
    pub reductions: Vec<Reduction>,
}

/// A comparison you build from a model and run. See the module docs.
#[derive(Debug, Clone)]
pub struct Comparison {
    pub model: Model,
    pub options: CompareOptions,
}

/// A mode to read levels at: name and, per case, the band centre.
enum ModeSpec {
    Index(usize, String),
    Frequency(f64),
}

impl Comparison {
    pub fn new(model: Model, options: CompareOptions) -> Self {
        Self { model, options }
    }

    /// The cases this model can run: always no damper; the damper when the model has one;
    /// the added mass ([`Model::added_mass`]) when it has a damper (its mass) or an
    /// `[added_mass]`.
    pub fn cases(&self) -> Vec<CaseName> {
        let s = &self.model.spec;
        let mut c = vec![CaseName::NoDamper];
        if s.damper.is_some() {
            c.push(CaseName::Damper);
        }
        if s.damper.is_some() || s.added_mass.is_some() {
            c.push(CaseName::AddedMass);
        }
        c
    }

    fn check(&self) -> Result<f64> {
        let o = &self.options;
        if !(o.duration_s.is_finite() && o.duration_s > 0.0) {
            return Err(Error::invalid(
                "duration",
                format!("must be > 0 s (got {})", o.duration_s),
            ));
        }
        if o.blows == 0 {
            return Err(Error::invalid("blows", "needs at least one blow"));
        }
        if !(o.band_fraction > 0.0 && o.band_fraction < 1.0) {
            return Err(Error::invalid(
                "band_fraction",
                format!("must be in (0, 1) (got {})", o.band_fraction),
            ));
        }
        if !(o.acceleration_reference_m_per_s2.is_finite()
            && o.acceleration_reference_m_per_s2 > 0.0)
        {
            return Err(Error::invalid("acceleration reference", "must be > 0 m/s²"));
        }
        if let Some(f) = &o.mode_frequencies_hz {
            if f.is_empty() || f.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(Error::invalid(
                    "mode frequencies",
                    "give one or more frequencies > 0 Hz",
                ));
            }
        }
        let fs = self.model.spec.simulation.sample_rate;
        if !(fs.is_finite() && fs > 0.0) {
            return Err(Error::invalid(
                "simulation.sample_rate",
                "the comparison needs an output sample rate > 0 Hz",
            ));
        }
        Ok(fs)
    }

    /// The modes levels are read at: the reference mode and the elastic mode with the largest
    /// `|ψ(O_b)|·|ψ(B)|`, or the user's frequencies.
    fn mode_specs(&self, bare: &ImpactSystem) -> Vec<ModeSpec> {
        if let Some(f) = &self.options.mode_frequencies_hz {
            return f.iter().map(|&v| ModeSpec::Frequency(v)).collect();
        }
        let st = &bare.structure;
        let n = st.len();
        let reference = self
            .model
            .spec
            .structure
            .reference_mode
            .map(|r| r - 1)
            .or_else(|| (0..n).find(|&i| st.omega_rad_per_s[i] > 0.0));
        let mut out = Vec::new();
        if let Some(r) = reference {
            if st.omega_rad_per_s[r] > 0.0 {
                out.push(ModeSpec::Index(r, format!("mode {} (reference)", r + 1)));
            }
        }
        let pb = &bare.points.bed_contact;
        let pm = &bare.points.measurement;
        let mut best: Option<(usize, f64)> = None;
        for i in 0..n {
            if Some(i) == reference || st.omega_rad_per_s[i] <= 0.0 {
                continue;
            }
            let w = pb[i].abs() * pm[i].abs();
            if best.is_none_or(|b| w > b.1) {
                best = Some((i, w));
            }
        }
        if let Some((i, _)) = best {
            out.push(ModeSpec::Index(i, format!("mode {} (bed)", i + 1)));
        }
        out
    }

    /// Runs the cases and builds the table.
    pub fn run(&self) -> Result<ComparisonResult> {
        let fs = self.check()?;
        let o = &self.options;
        if self.cases().len() < 2 {
            return Err(Error::invalid(
                "damper",
                "the model has neither [damper] nor [added_mass]: nothing to compare with",
            ));
        }
        let bare = self.model.impact_system(Case::NoDamper)?;
        let specs = self.mode_specs(&bare);
        if specs.is_empty() {
            return Err(Error::invalid(
                "modes",
                "the model has no mode with ω > 0 to read levels at; name frequencies",
            ));
        }
        let mut opts = self.model.options();
        opts.duration = o.duration_s;
        opts.sample_rate = Some(fs);
        let mut cases = Vec::new();
        for c in self.cases() {
            let sys = self.model.impact_system(c.case())?;
            // Peaks on the continuous solution (not the samples): (bed acceleration, floor force).
            let (history, energy_ratio, peaks) = if o.blows > 1 {
                let b = BlowOptions {
                    blows: o.blows,
                    rate_bpm: o.rate_bpm,
                    ..BlowOptions::default()
                };
                let r = run_blows(&sys, &opts, &b, true)?;
                let e = r.blows.first().and_then(|b| b.energy_ratio);
                let peaks = r.blows.iter().fold((0.0_f64, 0.0_f64), |p, b| {
                    (
                        p.0.max(b.peak_bed_acceleration_m_per_s2),
                        p.1.max(b.peak_floor_force_n),
                    )
                });
                (r.history, e, peaks)
            } else {
                let r = simulate(&sys, &opts, true)?;
                let s = &r.summary;
                let peaks = (s.peak_bed_acceleration_m_per_s2, s.peak_floor_force_n);
                (r.history, s.energy_ratio, peaks)
            };
            let history = history
                .ok_or_else(|| Error::numerical("compare", "the run recorded no history"))?;
            cases.push(self.analyse(c, &sys, history, energy_ratio, peaks, &specs, fs)?);
        }
        let reductions = reductions(&cases);
        let added_mass = if cases.iter().any(|c| c.case == CaseName::AddedMass) {
            self.model.added_mass()
        } else {
            None
        };
        Ok(ComparisonResult {
            sample_rate_hz: fs,
            added_mass,
            window: o.window,
            acceleration_reference_m_per_s2: o.acceleration_reference_m_per_s2,
            cases,
            reductions,
        })
    }

    fn analyse(
        &self,
        case: CaseName,
        sys: &ImpactSystem,
        history: History,
        energy_ratio: Option<f64>,
        peaks: (f64, f64),
        specs: &[ModeSpec],
        fs: f64,
    ) -> Result<CaseResult> {
        let o = &self.options;
        let a = &history.bed_acceleration_m_per_s2;
        let f = &history.floor_force_n;
        let acc = record_spectrum(a, fs, o.window)?;
        let force = record_spectrum(f, fs, o.window)?;
        let mut modes = Vec::new();
        for s in specs {
            let (name, centre) = match s {
                ModeSpec::Index(i, name) => (
                    name.clone(),
                    sys.structure.omega_rad_per_s[*i] / (2.0 * std::f64::consts::PI),
                ),
                ModeSpec::Frequency(v) => (format!("{v} Hz (named)"), *v),
            };
            let lo = centre * (1.0 - o.band_fraction);
            let hi = centre * (1.0 + o.band_fraction);
            let pa = acc.peak_in_band(lo, hi)?;
            let pf = force.peak_in_band(lo, hi)?;
            modes.push(ModeLevel {
                name,
                centre_hz: centre,
                band_hz: [lo, hi],
                acceleration_peak_hz: pa.frequency_hz,
                floor_force_peak_hz: pf.frequency_hz,
                acceleration_level_db: level_db(pa.value, o.acceleration_reference_m_per_s2)?,
                floor_force_level_db: level_db(pf.value, REF_FORCE_N)?,
            });
        }
        Ok(CaseResult {
            case,
            peak_bed_acceleration_m_per_s2: peaks.0,
            peak_floor_force_n: peaks.1,
            acceleration_spectrum: acc,
            floor_force_spectrum: force,
            history,
            modes,
            energy_ratio,
        })
    }
}

/// The spectrum the comparison reads levels from: the whole record, windowed, zero-padded to
/// exactly 4× its length (so the record's own bins `k/T` stay bins, and three interpolated
/// lines lie between them), amplitude-corrected by the window's coherent gain
/// (`A_k = 2|X_k|/Σw`, see [`super::spectrum`]).
pub fn record_spectrum(x: &[f64], sample_rate_hz: f64, window: Window) -> Result<Spectrum> {
    let pad = Padding::Length(x.len().saturating_mul(4));
    amplitude_spectrum_padded(x, sample_rate_hz, window, pad)
}

/// `20 log10(x)`, `-inf` for 0.
fn db20(x: f64) -> f64 {
    20.0 * x.log10()
}

fn reductions(cases: &[CaseResult]) -> Vec<Reduction> {
    let metrics = |c: &CaseResult| -> Vec<(String, f64)> {
        let mut m = vec![
            (
                "peak bed acceleration (time)".to_string(),
                db20(c.peak_bed_acceleration_m_per_s2),
            ),
            (
                "peak floor force (time)".to_string(),
                db20(c.peak_floor_force_n),
            ),
        ];
        for l in &c.modes {
            m.push((
                format!("bed acceleration at {}", l.name),
                l.acceleration_level_db,
            ));
            m.push((format!("floor force at {}", l.name), l.floor_force_level_db));
        }
        m
    };
    let Some(none) = cases.iter().find(|c| c.case == CaseName::NoDamper) else {
        return Vec::new();
    };
    let base = metrics(none);
    let mut out = Vec::new();
    for c in cases {
        for ((metric, l), (_, l0)) in metrics(c).into_iter().zip(&base) {
            out.push(Reduction {
                case: c.case,
                metric,
                level_db: l,
                no_damper_level_db: *l0,
                reduction_db: l0 - l,
            });
        }
    }
    out
}

impl ComparisonResult {
    /// The reduction table as aligned text, with the paper's figures beside it.
    pub fn table_text(&self) -> String {
        let mut s = String::new();
        s.push_str(&format!(
            "window {}, levels dB re {} m/s² and re 1 N (RMS); reduction = L(no damper) − L(case), positive = quieter\n",
            self.window.name(),
            self.acceleration_reference_m_per_s2
        ));
        s.push_str(&format!(
            "{:<12} {:<44} {:>10} {:>12} {:>11}\n",
            "case", "metric", "level dB", "no damper dB", "reduction"
        ));
        for r in &self.reductions {
            if r.case == CaseName::NoDamper {
                continue;
            }
            s.push_str(&format!(
                "{:<12} {:<44} {:>10.2} {:>12.2} {:>8.2} dB\n",
                r.case.name(),
                r.metric,
                r.level_db,
                r.no_damper_level_db,
                r.reduction_db
            ));
        }
        if let Some((m, p)) = &self.added_mass {
            s.push_str(&format!("added mass: {m} kg fixed at point {p}\n"));
        }
        s.push_str("paper's figures:\n");
        for p in PAPER_FIGURES {
            s.push_str(&format!("  {:<70} {:>5.1} dB\n", p.what, p.reduction_db));
        }
        s
    }

    /// The reduction table as CSV (every case, including the no-damper rows with 0 dB).
    pub fn table_csv(&self) -> Result<Vec<u8>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let err = |e: csv::Error| Error::numerical("csv", e.to_string());
        w.write_record([
            "case",
            "metric",
            "level_db",
            "no_damper_level_db",
            "reduction_db",
        ])
        .map_err(err)?;
        for r in &self.reductions {
            w.write_record([
                r.case.name().to_string(),
                r.metric.clone(),
                format!("{:.6}", r.level_db),
                format!("{:.6}", r.no_damper_level_db),
                format!("{:.6}", r.reduction_db),
            ])
            .map_err(err)?;
        }
        w.into_inner()
            .map_err(|e| Error::numerical("csv", e.to_string()))
    }

    /// A JSON-ready summary: settings, per-case peaks and mode levels, reductions, paper.
    pub fn summary(&self) -> ComparisonSummary {
        ComparisonSummary {
            sample_rate_hz: self.sample_rate_hz,
            added_mass_kg: self.added_mass.as_ref().map(|a| a.0),
            added_mass_point: self.added_mass.as_ref().map(|a| a.1.clone()),
            window: self.window.name(),
            acceleration_reference_m_per_s2: self.acceleration_reference_m_per_s2,
            cases: self
                .cases
                .iter()
                .map(|c| CaseSummary {
                    case: c.case,
                    energy_ratio: c.energy_ratio,
                    peak_bed_acceleration_m_per_s2: c.peak_bed_acceleration_m_per_s2,
                    peak_floor_force_n: c.peak_floor_force_n,
                    modes: c.modes.clone(),
                })
                .collect(),
            reductions: self.reductions.clone(),
            paper: PAPER_FIGURES.to_vec(),
        }
    }

    /// Spectra of every case as CSV: `frequency_hz` then, per case, acceleration and force
    /// levels (dB) — all cases share the bins (same record length).
    pub fn spectra_csv(&self) -> Result<Vec<u8>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let err = |e: csv::Error| Error::numerical("csv", e.to_string());
        let mut head = vec!["frequency_hz".to_string()];
        for c in &self.cases {
            head.push(format!("{}_acceleration_db", c.case.name()));
            head.push(format!("{}_floor_force_db", c.case.name()));
        }
        w.write_record(&head).map_err(err)?;
        let Some(first) = self.cases.first() else {
            return Ok(Vec::new());
        };
        let levels: Vec<(Vec<f64>, Vec<f64>)> = self
            .cases
            .iter()
            .map(|c| {
                Ok((
                    c.acceleration_spectrum
                        .levels_db(self.acceleration_reference_m_per_s2)?,
                    c.floor_force_spectrum.levels_db(REF_FORCE_N)?,
                ))
            })
            .collect::<Result<_>>()?;
        for (k, f) in first.acceleration_spectrum.frequency_hz.iter().enumerate() {
            let mut row = vec![format!("{f:.6e}")];
            for (a, fl) in &levels {
                row.push(format!("{:.6}", a.get(k).copied().unwrap_or(f64::NAN)));
                row.push(format!("{:.6}", fl.get(k).copied().unwrap_or(f64::NAN)));
            }
            w.write_record(&row).map_err(err)?;
        }
        w.into_inner()
            .map_err(|e| Error::numerical("csv", e.to_string()))
    }
}

/// Per-case numbers for JSON.
#[derive(Debug, Clone, Serialize)]
pub struct CaseSummary {
    pub case: CaseName,
    pub energy_ratio: Option<f64>,
    pub peak_bed_acceleration_m_per_s2: f64,
    pub peak_floor_force_n: f64,
    pub modes: Vec<ModeLevel>,
}

/// The comparison for JSON output.
#[derive(Debug, Clone, Serialize)]
pub struct ComparisonSummary {
    pub sample_rate_hz: f64,
    /// The added-mass case's mass (kg) and point (`added_mass.point`, default O_b).
    pub added_mass_kg: Option<f64>,
    pub added_mass_point: Option<String>,
    pub window: &'static str,
    pub acceleration_reference_m_per_s2: f64,
    pub cases: Vec<CaseSummary>,
    pub reductions: Vec<Reduction>,
    pub paper: Vec<PaperFigure>,
}
