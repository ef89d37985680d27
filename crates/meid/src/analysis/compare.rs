//! The paper's comparison (section 4, Figs. 10, 11, 13, 14, 18, 19): one machine, one blow
//! (or a train of blows), three cases — no damper, the impact damper, a rigid added mass — and
//! by how many dB each case lowers the bed acceleration at B and the force to the floor.
//!
//! The added mass is [`Model::added_mass`]: `added_mass.mass` (default: the damper's mass m_d)
//! fixed at `added_mass.point` (default: the bed contact point O_b; the paper's Figs. 10-11 also
//! put it on the floating base, `point = "O_f"` or the lumped model's `"base"`).
//!
//! # Measures
//!
//! Each case is simulated over the same record (default 2 s, sampled at the model's rate: the
//! samples are the time histories written and plotted, nothing else). Every reduction says which
//! measure it is ([`Measure`]); with the default exact spectrum none depends on the sample rate
//! or on the record length:
//!
//! * **time peak** `20 log10(peak_none / peak_case)` of `max |a_B(t)|`, `max |F_floor(t)|`,
//!   located on the continuous solution ([`crate::integrate::peaks`]);
//! * **ESD peak** at each dominant mode: the maximum of the exact energy spectral density
//!   `E(f) = 2|G(f)|²` ([`super::esd`]) within ±10 % of **that case's own** mode frequency,
//!   located by refinement (Brent) rather than on a grid; `10 log10(E_none/E_case)`. Levels are
//!   dB re 1 (m/s²)²·s/Hz (or re (1e-6 m/s²)²·s/Hz, ISO 1683's reference squared) and
//!   re 1 N²·s/Hz;
//! * **band level**: the energy `∫E df` of the one-third-octave band (IEC 61260-1, base 10,
//!   [`super::octave`]) that contains that ESD peak, integrated by adaptive Gauss-Kronrod to
//!   1e-6 (4e-6 dB); dB re 1 (m/s²)²·s and re 1 N²·s;
//! * **signal energy** `∫g² dt` over the whole response (time domain, exact);
//! * **energy ratio**: `10 log10(η_none/η_case)` with `η = E_p+/E_s−` (paper Eq. 10), the share
//!   of the blow's energy left in the machine, which the paper calls vibration power.
//!
//! The exact spectrum is the Fourier transform of the simulated response including its free
//! decay after the record: the run is continued without samples until the decay left carries
//! less than [`DecayRule::tail_energy_fraction`] of each channel's energy (module docs of
//! [`super::esd`]). A model whose response does not decay (no damping) has no such spectrum:
//! the comparison says so; the windowed FFT of the record remains available.
//!
//! **Test-lab path** ([`SpectrumMethod::Fft`]): the windowed FFT of the sampled record,
//! [`super::spectrum::esd_fft`], zero-padded to 4× the record, with a rectangular, Hann or
//! exponential window on the responses (and the force window on the blow's force), as a
//! laboratory would process measurements. Its levels depend on the record, the window and the
//! rate, as a measurement's do; the reductions then carry the `fft-` measures.
//!
//! The dominant modes are the model's reference mode (the rigid-body mode, the paper's ω_6)
//! and, among the other modes with ω > 0, the one with the largest `|ψ(O_b)|·|ψ(B)|` (struck
//! at the bed and seen at B: the paper's first bed mode, 283 Hz), or frequencies the user
//! names (the band is then ±10 % around the named value in every case). The added mass lowers
//! the modes (Rayleigh-Ritz on the retained modes,
//! [`crate::modal::ModalModel::with_point_mass`]), so the band follows it.
//!
//! **Reductions** are `ΔL = L_none − L_case` dB: positive means the case is quieter. For a
//! spring-mounted mass `M` hit by an impulse `J` the peak spring force is `J √(k/M)`
//! (`= v √(kM)` with `v = J/M`), so a rigid added mass `m` gives `ΔL = 10 log10(1 + m/M)`
//! (0.79 dB for 20 %, 3.01 dB for 100 %) in the time peak — the baseline the damper must beat.
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
//!     println!("{} {} ({:?}): {:.2} dB", row.case, row.metric, row.measure, row.reduction_db);
//! }
//! # Ok::<(), meid::Error>(())
//! ```

use serde::Serialize;

use super::blows::{run_blows, BlowOptions};
use super::energy::{simulate, History};
use super::esd::{esd_level_db, Continuation, DecayRule, SpectrumBuilder, Trajectory};
use super::octave::{bands_covering, Band};
use super::spectrum::{
    amplitude_spectrum_padded, esd_fft, Esd, Padding, Spectrum, TransientWindow, Window,
    REF_ACCELERATION_M_PER_S2,
};
use crate::impact::{Channel, ImpactSystem};
use crate::integrate::Options;
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

/// How the comparison's spectra are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpectrumMethod {
    /// The exact transform of the simulated response with its free decay ([`super::esd`]).
    #[default]
    Exact,
    /// The windowed FFT of the sampled record (test-lab path).
    Fft,
}

impl std::str::FromStr for SpectrumMethod {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "exact" => Ok(SpectrumMethod::Exact),
            "fft" => Ok(SpectrumMethod::Fft),
            _ => Err(Error::invalid(
                "spectrum",
                format!("unknown spectrum '{s}'; valid: exact, fft"),
            )),
        }
    }
}

/// Settings of a comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct CompareOptions {
    /// Record length (s) for a single blow (default 2 s).
    pub duration_s: f64,
    /// Number of blows (1 = a single blow over `duration_s`).
    pub blows: usize,
    /// Stroke rate (blows per minute) when `blows > 1`; the record is then `blows · 60/rate`.
    pub rate_bpm: f64,
    /// Exact spectrum (default) or the windowed FFT of the record.
    pub spectrum: SpectrumMethod,
    /// Window of the FFT path on the responses (default rectangular); the blow's force gets the
    /// force window over the slider's contact.
    pub window: TransientWindow,
    /// Reference for acceleration levels (m/s²): 1 (default) or 1e-6 (ISO 1683); ESD levels
    /// are re its square·s/Hz.
    pub acceleration_reference_m_per_s2: f64,
    /// Mode frequencies (Hz) to read levels at instead of the model's dominant modes.
    pub mode_frequencies_hz: Option<Vec<f64>>,
    /// Half-width of the search band as a fraction of the mode frequency (default 0.10).
    pub band_fraction: f64,
    /// How long runs are continued for the exact spectrum.
    pub decay: DecayRule,
    /// Points of the exact ESD curve written and plotted (log-spaced; default 1500).
    pub curve_points: usize,
}

impl Default for CompareOptions {
    fn default() -> Self {
        Self {
            duration_s: 2.0,
            blows: 1,
            rate_bpm: 60.0,
            spectrum: SpectrumMethod::Exact,
            window: TransientWindow::Rectangular,
            acceleration_reference_m_per_s2: REF_ACCELERATION_M_PER_S2,
            mode_frequencies_hz: None,
            band_fraction: 0.10,
            decay: DecayRule::default(),
            curve_points: 1500,
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

/// The channels whose spectra a comparison computes: the bed acceleration at B, the force to
/// the floor, and the blow itself (the slider-bed contact force).
pub const SPECTRUM_CHANNELS: [Channel; 3] = [
    Channel::BedAcceleration,
    Channel::FloorForce,
    Channel::ContactSliderBed,
];

/// The level at one dominant mode in one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeLevel {
    /// e.g. "mode 1 (reference)" or "6.35 Hz (named)".
    pub name: String,
    /// Centre of the search band in this case (Hz).
    pub centre_hz: f64,
    pub band_hz: [f64; 2],
    /// Where the acceleration / force ESD peaks are (Hz).
    pub acceleration_peak_hz: f64,
    pub floor_force_peak_hz: f64,
    /// ESD level at the peak, dB re (acceleration reference)²·s/Hz.
    pub acceleration_level_db: f64,
    /// ESD level at the peak, dB re 1 N²·s/Hz.
    pub floor_force_level_db: f64,
    /// The one-third-octave band containing the acceleration peak and its level
    /// (dB re (acceleration reference)²·s).
    pub acceleration_band: Band,
    pub acceleration_band_level_db: f64,
    /// The band containing the force peak and its level (dB re 1 N²·s).
    pub floor_force_band: Band,
    pub floor_force_band_level_db: f64,
    /// True when a maximum lies on the edge of the search band (no interior peak there).
    pub peak_at_band_edge: bool,
}

/// The spectrum of one channel in one case.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelSpectrum {
    pub channel: Channel,
    /// ESD on the comparison's frequencies ([`ComparisonResult::frequency_hz`]), unit²·s/Hz.
    pub esd: Vec<f64>,
    /// Energy of each band of [`ComparisonResult::bands`] (unit²·s).
    pub band_energy: Vec<f64>,
    /// `∫ g² dt` (unit²·s): exact over the response with its free decay (exact path), or the
    /// windowed record's (FFT path).
    pub energy: f64,
    /// Exact path: the refined ESD peaks `(f, E)` at the dominant modes, for plots.
    pub peaks: Vec<(f64, f64)>,
}

impl ChannelSpectrum {
    /// The curve to draw: the ESD on `frequency_hz` (the comparison's frequencies) with the
    /// refined peaks merged in, at `f > 0`, sorted by frequency, as levels in dB re
    /// `reference` ([`super::esd::esd_level_db`]).
    pub fn level_curve_db(&self, frequency_hz: &[f64], reference: f64) -> (Vec<f64>, Vec<f64>) {
        let mut pts: Vec<(f64, f64)> = frequency_hz
            .iter()
            .zip(&self.esd)
            .map(|(f, e)| (*f, *e))
            .chain(self.peaks.iter().copied())
            .filter(|(f, _)| *f > 0.0)
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        pts.into_iter()
            .map(|(f, e)| (f, super::esd::esd_level_db(e, reference)))
            .unzip()
    }
}

/// The results of one case.
#[derive(Debug, Clone)]
pub struct CaseResult {
    pub case: CaseName,
    pub history: History,
    pub peak_bed_acceleration_m_per_s2: f64,
    pub peak_floor_force_n: f64,
    pub modes: Vec<ModeLevel>,
    /// E_p+/E_s− of the (first) blow.
    pub energy_ratio: Option<f64>,
    /// In the order of [`SPECTRUM_CHANNELS`].
    pub spectra: Vec<ChannelSpectrum>,
    /// Exact path: how the run was continued for the spectrum.
    pub continuation: Option<Continuation>,
    /// True when part of the exact spectrum is interpolated between knots (non-linear contact
    /// laws): an estimate.
    pub spectrum_is_estimate: bool,
}

/// Which measure a reduction is (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Measure {
    /// Peak of the time history on the continuous solution, `20 log10`.
    TimePeak,
    /// Maximum of the exact ESD near the case's mode, `10 log10`.
    EsdPeak,
    /// Exact one-third-octave band energy, `10 log10`.
    BandLevel,
    /// `∫g² dt` of the whole response, `10 log10`.
    SignalEnergy,
    /// `E_p+/E_s−` (the paper's vibration power), `10 log10`.
    EnergyRatio,
    /// Largest bin of the windowed FFT ESD of the record.
    FftEsdPeak,
    /// One-third-octave band energy from the bins of the windowed FFT.
    FftBandLevel,
    /// Energy of the windowed record.
    FftSignalEnergy,
}

impl Measure {
    /// Short name (as in JSON).
    pub fn name(self) -> &'static str {
        match self {
            Measure::TimePeak => "time-peak",
            Measure::EsdPeak => "esd-peak",
            Measure::BandLevel => "band-level",
            Measure::SignalEnergy => "signal-energy",
            Measure::EnergyRatio => "energy-ratio",
            Measure::FftEsdPeak => "fft-esd-peak",
            Measure::FftBandLevel => "fft-band-level",
            Measure::FftSignalEnergy => "fft-signal-energy",
        }
    }
}

/// One row of the reduction table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Reduction {
    pub case: CaseName,
    /// e.g. "peak bed acceleration (time)", "floor force ESD at mode 1 (reference)".
    pub metric: String,
    /// Which measure it is.
    pub measure: Measure,
    /// Level in dB re `reference`.
    pub level_db: f64,
    pub no_damper_level_db: f64,
    /// The level's reference, e.g. "1 (m/s²)²·s/Hz".
    pub reference: String,
    /// `L_none − L_case` (positive: quieter than without damper).
    pub reduction_db: f64,
}

/// The finished comparison.
#[derive(Debug, Clone)]
pub struct ComparisonResult {
    pub sample_rate_hz: f64,
    /// The added-mass case's mass (kg) and point, when that case ran.
    pub added_mass: Option<(f64, String)>,
    pub spectrum: SpectrumMethod,
    /// The FFT path's window on the responses.
    pub window: TransientWindow,
    pub acceleration_reference_m_per_s2: f64,
    /// Frequencies of the ESD curves (Hz): log-spaced (exact) or the FFT bins in range.
    pub frequency_hz: Vec<f64>,
    /// The one-third-octave bands of the band table.
    pub bands: Vec<Band>,
    pub cases: Vec<CaseResult>,
    pub reductions: Vec<Reduction>,
    /// How exact the time peaks are ([`crate::analysis::energy::peak_accuracy`]).
    pub peak_accuracy: String,
    /// Blows in the simulated record (1: one blow from rest) and their stroke rate
    /// (blows/min, used only when `blows > 1`).
    pub blows: usize,
    pub rate_bpm: f64,
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

    /// The record the comparison simulates (s): `duration_s` for one blow, `blows · 60/rate`
    /// for a train.
    fn record_s(&self) -> f64 {
        let o = &self.options;
        if o.blows > 1 {
            o.blows as f64 * 60.0 / o.rate_bpm
        } else {
            o.duration_s
        }
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
            // The lowest frequency a record of T_record seconds resolves is its frequency
            // resolution Δf = 1/T_record (one period in the record): below it a level, and the
            // one-third-octave bands around it, describe nothing a measurement of that record
            // could show (and the bands would crowd towards 0 Hz).
            let record_s = self.record_s();
            let lowest = 1.0 / record_s;
            if let Some(v) = f.iter().find(|v| **v < lowest) {
                return Err(Error::invalid(
                    "mode frequencies (--frequencies)",
                    format!(
                        "{} Hz is below {} Hz, the frequency resolution 1/T of the {} s record \
                         (one period must fit in the record). Name frequencies of at least {} \
                         Hz, or lengthen the record (--duration, or --blows × 60/--rate-bpm)",
                        crate::num(*v),
                        crate::num(lowest),
                        crate::num(record_s),
                        crate::num(lowest)
                    ),
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
        // A record shorter than one sampling interval holds a single sample: no spectrum, no
        // level (the dB values would be -inf or NaN).
        let record_s = self.record_s();
        if record_s * fs < 1.0 {
            return Err(Error::invalid(
                if o.blows > 1 { "blows" } else { "duration" },
                format!(
                    "the {} s record is shorter than one sampling interval 1/f_s = {} s \
                     (simulation.sample_rate = {} Hz): lengthen the record (--duration, or \
                     --blows × 60/--rate-bpm) to at least {} s, or raise the rate (--rate)",
                    crate::num(record_s),
                    crate::num(1.0 / fs),
                    crate::num(fs),
                    crate::num(1.0 / fs)
                ),
            ));
        }
        Ok(fs)
    }

    /// Refuses a comparison whose histories would not fit [`crate::limits::max_memory`]:
    /// every case holds its record, `samples = ⌊T_record · f_s⌋ + 1` samples of
    /// [`super::energy::HISTORY_SAMPLE_BYTES`] (`T_record = duration_s`, or `blows · 60/rate`),
    /// plus, on the FFT path, the zero-padded complex transforms of two channels (≤ 4 × 16 B
    /// per sample each).
    fn check_memory(&self, fs: f64) -> Result<()> {
        let o = &self.options;
        let record_s = self.record_s();
        let samples = super::energy::sample_count(record_s, Some(fs));
        let per_sample = super::energy::HISTORY_SAMPLE_BYTES
            + if o.spectrum == SpectrumMethod::Fft {
                2.0 * 4.0 * 16.0
            } else {
                0.0
            };
        let cases = self.cases().len();
        crate::limits::check_memory(
            &format!("the records of {cases} cases ({samples:.3e} samples × {per_sample} B each)"),
            cases as f64 * samples * per_sample,
            if o.blows > 1 { "blows" } else { "duration" },
            "the record length (--duration, or --blows at --rate-bpm) or \
             simulation.sample_rate (--rate)",
        )
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
            .reference_mode()
            .map(|r| (r.index, r.number))
            .or_else(|| {
                (0..n)
                    .find(|&i| st.omega_rad_per_s[i] > 0.0 && !st.is_pseudo(i))
                    .map(|i| {
                        (
                            i,
                            self.model
                                .structure
                                .mode_numbers
                                .get(i)
                                .copied()
                                .unwrap_or(i + 1),
                        )
                    })
            });
        let mut out = Vec::new();
        if let Some((r, number)) = reference {
            if st.omega_rad_per_s[r] > 0.0 {
                out.push(ModeSpec::Index(r, format!("mode {number} (reference)")));
            }
        }
        let pb = &bare.points.bed_contact;
        let pm = &bare.points.measurement;
        let mut best: Option<(usize, f64)> = None;
        for i in 0..n {
            if Some(i) == reference.map(|r| r.0) || st.omega_rad_per_s[i] <= 0.0 || st.is_pseudo(i)
            {
                continue;
            }
            let w = pb[i].abs() * pm[i].abs();
            if best.is_none_or(|b| w > b.1) {
                best = Some((i, w));
            }
        }
        if let Some((i, _)) = best {
            let number = self
                .model
                .structure
                .mode_numbers
                .get(i)
                .copied()
                .unwrap_or(i + 1);
            out.push(ModeSpec::Index(i, format!("mode {number} (bed)")));
        }
        out
    }

    /// Runs the cases and builds the table.
    pub fn run(&self) -> Result<ComparisonResult> {
        self.run_with_progress(&|_, _| {})
    }

    /// [`Comparison::run`] calling `progress(cases done, cases)` after each case.
    pub fn run_with_progress(&self, progress: &dyn Fn(usize, usize)) -> Result<ComparisonResult> {
        let fs = self.check()?;
        let o = &self.options;
        if o.curve_points < 2 {
            return Err(Error::invalid(
                "curve_points",
                format!("needs at least 2 points (got {})", o.curve_points),
            ));
        }
        if self.cases().len() < 2 {
            return Err(Error::invalid(
                "damper",
                "the model has neither [damper] nor [added_mass]: nothing to compare with",
            ));
        }
        self.check_memory(fs)?;
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
        let systems = self
            .cases()
            .into_iter()
            .map(|c| Ok((c, self.model.impact_system(c.case())?)))
            .collect::<Result<Vec<_>>>()?;
        let centres: Vec<Vec<(String, f64)>> = systems
            .iter()
            .map(|(_, sys)| mode_centres(sys, &specs))
            .collect();
        let all = centres.iter().flatten().map(|c| c.1);
        let f_min = all.clone().fold(f64::INFINITY, f64::min);
        let f_max = all.fold(0.0, f64::max);
        let mut bands = bands_covering(0.5 * f_min, 4.0 * f_max);
        if o.spectrum == SpectrumMethod::Fft {
            bands.retain(|b| b.upper_hz <= 0.5 * fs);
        }
        let (Some(first), Some(last)) = (bands.first(), bands.last()) else {
            return Err(Error::invalid(
                "simulation.sample_rate",
                format!("no one-third-octave band around {f_min}-{f_max} Hz lies below the Nyquist frequency {} Hz", 0.5 * fs),
            ));
        };
        let (f_lo, f_hi) = (first.lower_hz, last.upper_hz);
        let mut grid: Vec<f64> = (0..o.curve_points)
            .map(|i| f_lo * (f_hi / f_lo).powf(i as f64 / (o.curve_points - 1) as f64))
            .collect();
        let mut cases = Vec::new();
        for (done, ((c, sys), centres)) in systems.iter().zip(&centres).enumerate() {
            progress(done, systems.len());
            let c = *c;
            // Peaks on the continuous solution (not the samples): (bed acceleration, floor force).
            let (history, energy_ratio, peaks, traj) = if o.blows > 1 {
                let b = BlowOptions {
                    blows: o.blows,
                    rate_bpm: o.rate_bpm,
                    ..BlowOptions::default()
                };
                let r = run_blows(sys, &opts, &b, true)?;
                let e = r.blows.first().and_then(|b| b.energy_ratio);
                let peaks = r.blows.iter().fold((0.0_f64, 0.0_f64), |p, b| {
                    (
                        p.0.max(b.peak_bed_acceleration_m_per_s2),
                        p.1.max(b.peak_floor_force_n),
                    )
                });
                let mut traj = Trajectory::default();
                for (rep, sol) in r.blows.iter().zip(&r.solutions) {
                    traj.append(sol, rep.start_s);
                }
                (r.history, e, peaks, traj)
            } else {
                let r = simulate(sys, &opts, true)?;
                let s = &r.summary;
                let peaks = (s.peak_bed_acceleration_m_per_s2, s.peak_floor_force_n);
                let traj = Trajectory::from_solution(&r.solution);
                (r.history, s.energy_ratio, peaks, traj)
            };
            let history = history
                .ok_or_else(|| Error::numerical("compare", "the run recorded no history"))?;
            let case = match o.spectrum {
                SpectrumMethod::Exact => {
                    self.analyse_exact(c, sys, traj, &opts, centres, &grid, &bands)
                }
                SpectrumMethod::Fft => {
                    let (case, bins) =
                        self.analyse_fft(c, &history, fs, centres, &bands, f_lo, f_hi)?;
                    grid = bins;
                    Ok(case)
                }
            }
            .map_err(|e| match e {
                Error::Numerical { context, message } => Error::Numerical {
                    context,
                    message: format!("{} case: {message}", c.label()),
                },
                other => other,
            })?;
            cases.push(CaseResult {
                energy_ratio,
                peak_bed_acceleration_m_per_s2: peaks.0,
                peak_floor_force_n: peaks.1,
                history,
                ..case
            });
        }
        let reductions = reductions(&cases, o.spectrum, o.acceleration_reference_m_per_s2);
        let added_mass = if cases.iter().any(|c| c.case == CaseName::AddedMass) {
            self.model.added_mass()
        } else {
            None
        };
        Ok(ComparisonResult {
            sample_rate_hz: fs,
            added_mass,
            spectrum: o.spectrum,
            window: o.window,
            acceleration_reference_m_per_s2: o.acceleration_reference_m_per_s2,
            frequency_hz: grid,
            bands,
            cases,
            reductions,
            peak_accuracy: crate::analysis::energy::peak_accuracy(&opts),
            blows: o.blows,
            rate_bpm: o.rate_bpm,
        })
    }

    /// The exact spectra of one case: the run continued until its free decay is negligible,
    /// the transform with the free decay, levels at the modes, band energies.
    #[allow(clippy::too_many_arguments)]
    fn analyse_exact(
        &self,
        case: CaseName,
        sys: &ImpactSystem,
        mut traj: Trajectory,
        opts: &Options,
        centres: &[(String, f64)],
        grid: &[f64],
        bands: &[Band],
    ) -> Result<CaseResult> {
        let o = &self.options;
        let mut builder = SpectrumBuilder::new(sys, &SPECTRUM_CHANNELS);
        let cont = builder.continue_until_decayed(opts, &mut traj, &o.decay)?;
        builder.refine_nonlinear(opts, &mut traj)?;
        let spec = builder.build(&traj, true)?;
        let nch = SPECTRUM_CHANNELS.len();
        let mut esd = vec![Vec::with_capacity(grid.len()); nch];
        for &f in grid {
            for (v, e) in esd.iter_mut().zip(spec.esd(f)) {
                v.push(e);
            }
        }
        let mut band_energy = vec![Vec::with_capacity(bands.len()); nch];
        for b in bands {
            for (v, q) in band_energy
                .iter_mut()
                .zip(spec.band_energies(b.lower_hz, b.upper_hz, BAND_RTOL))
            {
                v.push(q.value);
            }
        }
        let band_level = |ch: usize, f: f64, reference: f64| -> (Band, f64) {
            let b = Band::containing(f);
            let e = match bands.iter().position(|x| x.index == b.index) {
                Some(i) => band_energy[ch][i],
                None => spec.band_energies(b.lower_hz, b.upper_hz, BAND_RTOL)[ch].value,
            };
            (b, esd_level_db(e, reference))
        };
        let a2 = o.acceleration_reference_m_per_s2.powi(2);
        let mut modes = Vec::new();
        let mut peaks = vec![Vec::new(); nch];
        for (name, centre) in centres {
            let lo = centre * (1.0 - o.band_fraction);
            let hi = centre * (1.0 + o.band_fraction);
            let pa = spec.peak(0, lo, hi)?;
            let pf = spec.peak(1, lo, hi)?;
            peaks[0].push((pa.frequency_hz, pa.esd));
            peaks[1].push((pf.frequency_hz, pf.esd));
            let (ab, al) = band_level(0, pa.frequency_hz, a2);
            let (fb, fl) = band_level(1, pf.frequency_hz, 1.0);
            modes.push(ModeLevel {
                name: name.clone(),
                centre_hz: *centre,
                band_hz: [lo, hi],
                acceleration_peak_hz: pa.frequency_hz,
                floor_force_peak_hz: pf.frequency_hz,
                acceleration_level_db: esd_level_db(pa.esd, a2),
                floor_force_level_db: esd_level_db(pf.esd, 1.0),
                acceleration_band: ab,
                acceleration_band_level_db: al,
                floor_force_band: fb,
                floor_force_band_level_db: fl,
                peak_at_band_edge: pa.at_band_edge || pf.at_band_edge,
            });
        }
        let spectra = (0..nch)
            .map(|ch| ChannelSpectrum {
                channel: SPECTRUM_CHANNELS[ch],
                esd: std::mem::take(&mut esd[ch]),
                band_energy: std::mem::take(&mut band_energy[ch]),
                energy: spec.energy()[ch],
                peaks: std::mem::take(&mut peaks[ch]),
            })
            .collect();
        Ok(CaseResult {
            case,
            history: History::default(),
            peak_bed_acceleration_m_per_s2: 0.0,
            peak_floor_force_n: 0.0,
            modes,
            energy_ratio: None,
            spectra,
            continuation: Some(cont),
            spectrum_is_estimate: spec.is_estimate(),
        })
    }

    /// The test-lab spectra of one case: windowed FFT ESDs of the record, zero-padded to 4×
    /// its length; returns the case and the bins in `[f_lo, f_hi]`.
    #[allow(clippy::too_many_arguments)]
    fn analyse_fft(
        &self,
        case: CaseName,
        history: &History,
        fs: f64,
        centres: &[(String, f64)],
        bands: &[Band],
        f_lo: f64,
        f_hi: f64,
    ) -> Result<(CaseResult, Vec<f64>)> {
        let o = &self.options;
        let n = history.time_s.len();
        let pad = Padding::Length(n.saturating_mul(4));
        // The blow's force: force window over the first contact (rectangular for a train).
        let f = &history.contact_force_slider_bed_n;
        let blow_window = match f.iter().position(|v| *v > 0.0) {
            Some(i0) if o.blows == 1 => {
                let i1 = (i0..n).find(|&i| f[i] <= 0.0).unwrap_or(n);
                let pulse = i1 as f64 / fs;
                TransientWindow::Force {
                    pulse_s: pulse,
                    taper_s: 0.5 * pulse,
                }
            }
            _ => TransientWindow::Rectangular,
        };
        let esds: Vec<Esd> = vec![
            esd_fft(&history.bed_acceleration_m_per_s2, fs, o.window, pad)?,
            esd_fft(&history.floor_force_n, fs, o.window, pad)?,
            esd_fft(f, fs, blow_window, pad)?,
        ];
        let keep: Vec<usize> = (0..esds[0].frequency_hz.len())
            .filter(|&k| {
                let v = esds[0].frequency_hz[k];
                v >= f_lo && v <= f_hi
            })
            .collect();
        let bins: Vec<f64> = keep.iter().map(|&k| esds[0].frequency_hz[k]).collect();
        let a2 = o.acceleration_reference_m_per_s2.powi(2);
        let mut modes = Vec::new();
        for (name, centre) in centres {
            let lo = centre * (1.0 - o.band_fraction);
            let hi = centre * (1.0 + o.band_fraction);
            let pa = esds[0].peak_in_band(lo, hi)?;
            let pf = esds[1].peak_in_band(lo, hi)?;
            let (ab, fb) = (
                Band::containing(pa.frequency_hz),
                Band::containing(pf.frequency_hz),
            );
            modes.push(ModeLevel {
                name: name.clone(),
                centre_hz: *centre,
                band_hz: [lo, hi],
                acceleration_peak_hz: pa.frequency_hz,
                floor_force_peak_hz: pf.frequency_hz,
                acceleration_level_db: esd_level_db(pa.value, a2),
                floor_force_level_db: esd_level_db(pf.value, 1.0),
                acceleration_band: ab,
                acceleration_band_level_db: esd_level_db(
                    esds[0].band_energy(ab.lower_hz, ab.upper_hz),
                    a2,
                ),
                floor_force_band: fb,
                floor_force_band_level_db: esd_level_db(
                    esds[1].band_energy(fb.lower_hz, fb.upper_hz),
                    1.0,
                ),
                peak_at_band_edge: false,
            });
        }
        let spectra = esds
            .iter()
            .zip(SPECTRUM_CHANNELS)
            .map(|(e, channel)| ChannelSpectrum {
                channel,
                esd: keep.iter().map(|&k| e.density[k]).collect(),
                band_energy: bands
                    .iter()
                    .map(|b| e.band_energy(b.lower_hz, b.upper_hz))
                    .collect(),
                energy: e.energy(),
                peaks: Vec::new(),
            })
            .collect();
        Ok((
            CaseResult {
                case,
                history: History::default(),
                peak_bed_acceleration_m_per_s2: 0.0,
                peak_floor_force_n: 0.0,
                modes,
                energy_ratio: None,
                spectra,
                continuation: None,
                spectrum_is_estimate: false,
            },
            bins,
        ))
    }
}

/// Relative accuracy of the band energies (adaptive Gauss-Kronrod, see [`super::quadrature`]):
/// 1e-6, 4e-6 dB.
pub const BAND_RTOL: f64 = 1e-6;

/// Each mode spec's name and band centre in one case's system.
fn mode_centres(sys: &ImpactSystem, specs: &[ModeSpec]) -> Vec<(String, f64)> {
    specs
        .iter()
        .map(|s| match s {
            ModeSpec::Index(i, name) => (
                name.clone(),
                sys.structure.omega_rad_per_s[*i] / (2.0 * std::f64::consts::PI),
            ),
            ModeSpec::Frequency(v) => (format!("{v} Hz (named)"), *v),
        })
        .collect()
}

/// The spectrum the former comparison read levels from: the whole record, windowed,
/// zero-padded to exactly 4× its length, amplitude-corrected by the window's coherent gain
/// (`A_k = 2|X_k|/Σw`, see [`super::spectrum`]). Kept for amplitude readings of sampled records.
pub fn record_spectrum(x: &[f64], sample_rate_hz: f64, window: Window) -> Result<Spectrum> {
    let pad = Padding::Length(x.len().saturating_mul(4));
    amplitude_spectrum_padded(x, sample_rate_hz, window, pad)
}

/// A band edge for the band table: one decimal from 1 Hz up (`281.8`), two significant
/// digits below (`0.89`, `0.045`), so that no band of a low frequency prints as `0.0`.
fn band_edge(f_hz: f64) -> String {
    if !(f_hz > 0.0 && f_hz < 1.0) {
        format!("{f_hz:.1}")
    } else {
        let decimals = (1 - f_hz.log10().floor() as i32).max(1) as usize;
        format!("{f_hz:.decimals$}")
    }
}

/// `20 log10(x/r)`.
fn db20(x: f64, r: f64) -> f64 {
    20.0 * (x / r).log10()
}

/// "1 m/s²" or "1e-6 m/s²".
fn acc_ref_text(a_ref: f64) -> String {
    if a_ref == 1.0 {
        "1 m/s²".into()
    } else {
        format!("{a_ref:e} m/s²")
    }
}

fn reductions(cases: &[CaseResult], method: SpectrumMethod, a_ref: f64) -> Vec<Reduction> {
    let a2 = a_ref * a_ref;
    let ar = acc_ref_text(a_ref);
    let (esd_m, band_m, energy_m) = match method {
        SpectrumMethod::Exact => (Measure::EsdPeak, Measure::BandLevel, Measure::SignalEnergy),
        SpectrumMethod::Fft => (
            Measure::FftEsdPeak,
            Measure::FftBandLevel,
            Measure::FftSignalEnergy,
        ),
    };
    let Some(none) = cases.iter().find(|c| c.case == CaseName::NoDamper) else {
        return Vec::new();
    };
    let floor = none.spectra.get(1).is_some_and(|s| s.energy > 0.0);
    let metrics = |c: &CaseResult| -> Vec<(String, Measure, f64, String)> {
        let mut m = vec![(
            "peak bed acceleration (time)".to_string(),
            Measure::TimePeak,
            db20(c.peak_bed_acceleration_m_per_s2, a_ref),
            ar.clone(),
        )];
        if floor {
            m.push((
                "peak floor force (time)".to_string(),
                Measure::TimePeak,
                db20(c.peak_floor_force_n, 1.0),
                "1 N".into(),
            ));
        }
        for l in &c.modes {
            m.push((
                format!("bed acceleration ESD at {}", l.name),
                esd_m,
                l.acceleration_level_db,
                format!("({ar})²·s/Hz"),
            ));
            if floor {
                m.push((
                    format!("floor force ESD at {}", l.name),
                    esd_m,
                    l.floor_force_level_db,
                    "1 N²·s/Hz".into(),
                ));
            }
            m.push((
                format!("bed acceleration 1/3-octave band at {}", l.name),
                band_m,
                l.acceleration_band_level_db,
                format!("({ar})²·s"),
            ));
            if floor {
                m.push((
                    format!("floor force 1/3-octave band at {}", l.name),
                    band_m,
                    l.floor_force_band_level_db,
                    "1 N²·s".into(),
                ));
            }
        }
        if let Some(s) = c.spectra.first() {
            m.push((
                "bed acceleration energy ∫a²dt".to_string(),
                energy_m,
                esd_level_db(s.energy, a2),
                format!("({ar})²·s"),
            ));
        }
        if let (true, Some(s)) = (floor, c.spectra.get(1)) {
            m.push((
                "floor force energy ∫F²dt".to_string(),
                energy_m,
                esd_level_db(s.energy, 1.0),
                "1 N²·s".into(),
            ));
        }
        if let Some(e) = c.energy_ratio {
            m.push((
                "energy left in the machine E_p+/E_s− (vibration power)".to_string(),
                Measure::EnergyRatio,
                10.0 * e.log10(),
                "1".into(),
            ));
        }
        m
    };
    let base = metrics(none);
    let mut out = Vec::new();
    for c in cases {
        for (metric, measure, l, reference) in metrics(c) {
            let Some((_, _, l0, _)) = base.iter().find(|b| b.0 == metric && b.1 == measure) else {
                continue;
            };
            out.push(Reduction {
                case: c.case,
                metric,
                measure,
                level_db: l,
                no_damper_level_db: *l0,
                reference,
                reduction_db: l0 - l,
            });
        }
    }
    out
}

impl ComparisonResult {
    /// The ESD references as text: (acceleration, force).
    pub fn esd_references(&self) -> (String, String) {
        (
            format!(
                "({})²·s/Hz",
                acc_ref_text(self.acceleration_reference_m_per_s2)
            ),
            "1 N²·s/Hz".into(),
        )
    }

    /// What the spectra are, in one line.
    pub fn spectrum_text(&self) -> String {
        match self.spectrum {
            SpectrumMethod::Exact => {
                let ends: Vec<f64> = self
                    .cases
                    .iter()
                    .filter_map(|c| c.continuation.as_ref().map(|k| k.end_s))
                    .collect();
                let (lo, hi) = ends
                    .iter()
                    .fold((f64::INFINITY, 0.0_f64), |(a, b), &v| (a.min(v), b.max(v)));
                let estimate = if self.cases.iter().any(|c| c.spectrum_is_estimate) {
                    "; ESTIMATE: stretches with a non-linear contact closed are interpolated between knots"
                } else {
                    ""
                };
                format!(
                    "spectrum: exact Fourier transform of the simulated response and its free decay (runs continued to {lo:.2}-{hi:.2} s until the decay left carries < {:e} of each channel's energy); independent of the sample rate and the record length{estimate}",
                    DecayRule::default().tail_energy_fraction
                )
            }
            SpectrumMethod::Fft => format!(
                "spectrum: windowed FFT of the sampled record ({} window on the responses, zero-padded 4x): a test-lab estimate that depends on the record, the window and the rate",
                self.window.name()
            ),
        }
    }

    /// The reduction table as aligned text, with the paper's figures and the band table.
    pub fn table_text(&self) -> String {
        let (ea, ef) = self.esd_references();
        let mut s = String::new();
        s.push_str(&self.spectrum_text());
        s.push('\n');
        s.push_str(&format!(
            "ESD levels dB re {ea} and re {ef}; band levels and energies dB re {} and re 1 N²·s; reduction = L(no damper) − L(case), positive = quieter\n",
            ea.trim_end_matches("/Hz")
        ));
        s.push_str(&format!(
            "{:<11} {:<17} {:<54} {:>9} {:>12} {:>11}\n",
            "case", "measure", "metric", "level dB", "no damper dB", "reduction"
        ));
        for r in &self.reductions {
            if r.case == CaseName::NoDamper {
                continue;
            }
            s.push_str(&format!(
                "{:<11} {:<17} {:<54} {:>9.2} {:>12.2} {:>8.2} dB\n",
                r.case.name(),
                r.measure.name(),
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
        s.push_str(&format!(
            "one-third-octave bands (IEC 61260-1, base 10): band energy levels, bed acceleration dB re {} / floor force dB re 1 N²·s\n",
            ea.trim_end_matches("/Hz")
        ));
        s.push_str(&format!("{:>9} {:>19}", "band", "edges (Hz)"));
        for c in &self.cases {
            s.push_str(&format!(" {:>21}", c.case.name()));
        }
        s.push('\n');
        let a2 = self.acceleration_reference_m_per_s2.powi(2);
        for (i, b) in self.bands.iter().enumerate() {
            s.push_str(&format!(
                "{:>9} {:>8}-{:<10}",
                b.label(),
                band_edge(b.lower_hz),
                band_edge(b.upper_hz)
            ));
            for c in &self.cases {
                let l = |ch: usize, r: f64| {
                    c.spectra
                        .get(ch)
                        .and_then(|s| s.band_energy.get(i))
                        .map_or(f64::NAN, |e| esd_level_db(*e, r))
                };
                s.push_str(&format!(" {:>10.2} {:>10.2}", l(0, a2), l(1, 1.0)));
            }
            s.push('\n');
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
            "measure",
            "reference",
        ])
        .map_err(err)?;
        for r in &self.reductions {
            w.write_record([
                r.case.name().to_string(),
                r.metric.clone(),
                format!("{:.6}", r.level_db),
                format!("{:.6}", r.no_damper_level_db),
                format!("{:.6}", r.reduction_db),
                r.measure.name().to_string(),
                r.reference.clone(),
            ])
            .map_err(err)?;
        }
        w.into_inner()
            .map_err(|e| Error::numerical("csv", e.to_string()))
    }

    /// A JSON-ready summary: settings, per-case peaks, mode levels and energies, the band
    /// table, reductions, paper.
    /// The verdict of one blow from rest, in words: each case's exact peak floor force and bed
    /// acceleration against the machine without a damper (dB of the time peaks, negative:
    /// lower), which case is lowest at the floor and at the bed, and that production needs the
    /// steady blow at the stroke rate (`meid blows`).
    pub fn verdict(&self) -> Vec<String> {
        let get = |c: CaseName| self.cases.iter().find(|x| x.case == c);
        let db = |a: f64, b: f64| 20.0 * (a / b).log10();
        let mut out = Vec::new();
        let Some(none) = get(CaseName::NoDamper) else {
            return out;
        };
        let what = if self.blows > 1 {
            format!(
                "Over a train of {} blows from rest at {} /min (the train's largest peaks)",
                self.blows,
                crate::num(self.rate_bpm)
            )
        } else {
            "For one blow from rest".to_string()
        };
        for c in [CaseName::Damper, CaseName::AddedMass] {
            let Some(x) = get(c) else { continue };
            out.push(format!(
                "{what}, {} changes the peak floor force by {:+.1} dB ({} N against {} N without a damper) and the peak bed acceleration by {:+.1} dB ({} against {} m/s²).",
                if c == CaseName::Damper { "the impact damper" } else { "the same mass added rigidly" },
                db(x.peak_floor_force_n, none.peak_floor_force_n),
                crate::num(round_sig(x.peak_floor_force_n, 4)),
                crate::num(round_sig(none.peak_floor_force_n, 4)),
                db(x.peak_bed_acceleration_m_per_s2, none.peak_bed_acceleration_m_per_s2),
                crate::num(round_sig(x.peak_bed_acceleration_m_per_s2, 4)),
                crate::num(round_sig(none.peak_bed_acceleration_m_per_s2, 4)),
            ));
        }
        if self.cases.len() > 1 {
            let best = |f: fn(&CaseResult) -> f64| {
                self.cases
                    .iter()
                    .min_by(|a, b| f(a).total_cmp(&f(b)))
                    .map_or("—", |c| c.case.label())
            };
            out.push(format!(
                "Lowest peak floor force: {}; lowest peak bed acceleration: {}. {}",
                best(|c| c.peak_floor_force_n),
                best(|c| c.peak_bed_acceleration_m_per_s2),
                if self.blows > 1 {
                    "The first blows of a train from rest are not yet production: the periodic steady blow at the stroke rate is `meid blows --steady`'s (or compare's with a stroke rate: --rate-bpm or the model's [production] rate_bpm)."
                } else {
                    "One blow from rest is the paper's study, not production: give the stroke rate (--rate-bpm, or [production] rate_bpm in the model) for the steady blow at the machine's stroke rate."
                }
            ));
        }
        out
    }

    pub fn summary(&self) -> ComparisonSummary {
        let (ea, ef) = self.esd_references();
        let a2 = self.acceleration_reference_m_per_s2.powi(2);
        ComparisonSummary {
            verdict: self.verdict(),
            sample_rate_hz: self.sample_rate_hz,
            added_mass_kg: self.added_mass.as_ref().map(|a| a.0),
            added_mass_point: self.added_mass.as_ref().map(|a| a.1.clone()),
            spectrum: self.spectrum,
            spectrum_description: self.spectrum_text(),
            window: self.window.name(),
            acceleration_reference_m_per_s2: self.acceleration_reference_m_per_s2,
            acceleration_esd_reference: ea,
            force_esd_reference: ef,
            cases: self
                .cases
                .iter()
                .map(|c| CaseSummary {
                    case: c.case,
                    energy_ratio: c.energy_ratio,
                    peak_bed_acceleration_m_per_s2: c.peak_bed_acceleration_m_per_s2,
                    peak_floor_force_n: c.peak_floor_force_n,
                    bed_acceleration_energy_m2_per_s3: c.spectra.first().map_or(0.0, |s| s.energy),
                    floor_force_energy_n2_s: c.spectra.get(1).map_or(0.0, |s| s.energy),
                    modes: c.modes.clone(),
                    continuation: c.continuation.clone(),
                    spectrum_is_estimate: c.spectrum_is_estimate,
                })
                .collect(),
            bands: self
                .bands
                .iter()
                .enumerate()
                .map(|(i, b)| BandRow {
                    band: *b,
                    levels: self
                        .cases
                        .iter()
                        .map(|c| {
                            let e = |ch: usize| {
                                c.spectra
                                    .get(ch)
                                    .and_then(|s| s.band_energy.get(i))
                                    .copied()
                                    .unwrap_or(f64::NAN)
                            };
                            CaseBand {
                                case: c.case,
                                bed_acceleration_db: esd_level_db(e(0), a2),
                                floor_force_db: esd_level_db(e(1), 1.0),
                            }
                        })
                        .collect(),
                })
                .collect(),
            reductions: self.reductions.clone(),
            paper: PAPER_FIGURES.to_vec(),
            peak_accuracy: self.peak_accuracy.clone(),
        }
    }

    /// ESDs of every case as CSV: `frequency_hz`, then per case the bed acceleration, floor
    /// force and blow (slider-bed contact force) ESD levels in dB, the reference in the header.
    pub fn spectra_csv(&self) -> Result<Vec<u8>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let err = |e: csv::Error| Error::numerical("csv", e.to_string());
        let ar = if self.acceleration_reference_m_per_s2 == 1.0 {
            "1_(m/s^2)^2*s/Hz".to_string()
        } else {
            format!("({:e}_m/s^2)^2*s/Hz", self.acceleration_reference_m_per_s2)
        };
        let mut head = vec!["frequency_hz".to_string()];
        for c in &self.cases {
            head.push(format!("{}_bed_acceleration_esd_db_re_{ar}", c.case.name()));
            head.push(format!(
                "{}_floor_force_esd_db_re_1_N^2*s/Hz",
                c.case.name()
            ));
            head.push(format!("{}_blow_force_esd_db_re_1_N^2*s/Hz", c.case.name()));
        }
        w.write_record(&head).map_err(err)?;
        let a2 = self.acceleration_reference_m_per_s2.powi(2);
        for (k, f) in self.frequency_hz.iter().enumerate() {
            let mut row = vec![format!("{f:.6e}")];
            for c in &self.cases {
                for (ch, r) in [(0, a2), (1, 1.0), (2, 1.0)] {
                    let v = c
                        .spectra
                        .get(ch)
                        .and_then(|s| s.esd.get(k))
                        .map_or(f64::NAN, |e| esd_level_db(*e, r));
                    row.push(format!("{v:.6}"));
                }
            }
            w.write_record(&row).map_err(err)?;
        }
        w.into_inner()
            .map_err(|e| Error::numerical("csv", e.to_string()))
    }

    /// The one-third-octave band table as CSV: the band, then per case the band energies
    /// ((m/s²)²·s, N²·s) and levels (dB re the acceleration reference²·s and re 1 N²·s).
    pub fn bands_csv(&self) -> Result<Vec<u8>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let err = |e: csv::Error| Error::numerical("csv", e.to_string());
        let mut head: Vec<String> = ["band", "nominal_hz", "centre_hz", "lower_hz", "upper_hz"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        for c in &self.cases {
            let n = c.case.name();
            head.push(format!("{n}_bed_acceleration_energy_m2_per_s3"));
            head.push(format!("{n}_bed_acceleration_db"));
            head.push(format!("{n}_floor_force_energy_n2_s"));
            head.push(format!("{n}_floor_force_db"));
        }
        w.write_record(&head).map_err(err)?;
        let a2 = self.acceleration_reference_m_per_s2.powi(2);
        for (i, b) in self.bands.iter().enumerate() {
            let mut row = vec![
                b.index.to_string(),
                format!("{}", b.nominal_hz),
                format!("{:.6}", b.centre_hz),
                format!("{:.6}", b.lower_hz),
                format!("{:.6}", b.upper_hz),
            ];
            for c in &self.cases {
                for (ch, r) in [(0, a2), (1, 1.0)] {
                    let e = c
                        .spectra
                        .get(ch)
                        .and_then(|s| s.band_energy.get(i))
                        .copied()
                        .unwrap_or(f64::NAN);
                    row.push(format!("{e:.9e}"));
                    row.push(format!("{:.6}", esd_level_db(e, r)));
                }
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
    /// `∫a²dt`, (m/s²)²·s = m²/s³.
    pub bed_acceleration_energy_m2_per_s3: f64,
    /// `∫F²dt`, N²·s.
    pub floor_force_energy_n2_s: f64,
    pub modes: Vec<ModeLevel>,
    pub continuation: Option<Continuation>,
    pub spectrum_is_estimate: bool,
}

/// One band's levels in one case (dB re the acceleration reference²·s, re 1 N²·s).
#[derive(Debug, Clone, Serialize)]
pub struct CaseBand {
    pub case: CaseName,
    pub bed_acceleration_db: f64,
    pub floor_force_db: f64,
}

/// One row of the band table.
#[derive(Debug, Clone, Serialize)]
pub struct BandRow {
    pub band: Band,
    pub levels: Vec<CaseBand>,
}

/// The comparison for JSON output.
#[derive(Debug, Clone, Serialize)]
pub struct ComparisonSummary {
    /// The verdict of the single blow in words ([`ComparisonResult::verdict`]).
    pub verdict: Vec<String>,
    pub sample_rate_hz: f64,
    /// The added-mass case's mass (kg) and point (`added_mass.point`, default O_b).
    pub added_mass_kg: Option<f64>,
    pub added_mass_point: Option<String>,
    pub spectrum: SpectrumMethod,
    pub spectrum_description: String,
    pub window: String,
    pub acceleration_reference_m_per_s2: f64,
    pub acceleration_esd_reference: String,
    pub force_esd_reference: String,
    pub cases: Vec<CaseSummary>,
    pub bands: Vec<BandRow>,
    pub reductions: Vec<Reduction>,
    pub paper: Vec<PaperFigure>,
    /// How exact the time peaks are: `exact` to round-off, `dopri5` to its tolerance.
    pub peak_accuracy: String,
}

/// `v` rounded to `d` significant digits.
fn round_sig(v: f64, d: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(d - 1 - v.abs().log10().floor() as i32);
    (v * scale).round() / scale
}
