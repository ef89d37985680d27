//! Calibration (`meid calibrate`): model values fitted to measured records by bounded
//! nonlinear least squares.
//!
//! # What is fitted
//!
//! Parameters `p = (p_1 … p_n)` are numeric model paths, as `--set` and `meid sweep --vary`
//! address them (`structure.lumped.damping_ratios[1]`, `contact.slider_bed.stiffness` (K_s),
//! `contact.bed_damper.stiffness` (K_d), a tabulated mode's frequency …), each within bounds
//! `lo_i ≤ p_i ≤ hi_i`. Every evaluation builds the model with the values set
//! (the model [`Model::with_fields`] gives, written through typed setters compiled once,
//! [`Model::with_values`]); a [`StructureCache`] keeps the structures built, so the structure
//! is solved once when only contact or damping values vary (for a lumped model K_s, K_d enter
//! the structural key through the contact frequency, and each new value builds its own
//! two-mode structure: microseconds).
//!
//! # Residuals
//!
//! Each measured case is processed as `meid validate` processes it ([`super::validate`]: the
//! same channel mapping, trigger rule, pre-trigger, record length, windows); the model of case
//! `c` is simulated at the measurement's sample rate, at rest for the pre-trigger, and its
//! record taken from the trigger found by the same rule on the same channel. Residuals of
//! mapped channel `k` (measured blow average `m_k`, each blow record less its baseline, the
//! median of its pre-trigger samples, as the simulated record `s_k(p)`, which starts at rest:
//! a transducer's bias or preload is not fitted as motion; [`super::process`], Baseline):
//!
//! ```text
//! time histories (default):  r_kj = (s_kj(p) − m_kj) / rms(m_k),      j = 1 … N samples
//! band-limited spectra:      r_kj = 10 log10((E^s_kj(p) + ε_k)/(E^m_kj + ε_k)),  f_lo ≤ f_j ≤ f_hi
//! ```
//!
//! (`E` the blow-averaged energy spectral densities, `ε_k` = 10⁻¹² max E^m_k keeps empty bins
//! finite), stacked into `r(p) ∈ R^m`; the cost is `S(p) = Σ r²`. Scaling by `rms(m_k)` makes
//! channels of different units (m/s², N) comparable and the time residual dimensionless.
//!
//! # Solver: projected Levenberg-Marquardt
//!
//! Written here rather than taken from a crate: the `levenberg-marquardt` crate has no
//! bounds and brings nalgebra (meid's linear algebra is faer), and the systems are n × n
//! with n a handful, so the dense solves are a few lines. Internally each parameter is
//! `θ_i = ln p_i` when `lo_i > 0` (stiffnesses and damping ratios span decades and stay
//! positive), else `θ_i = p_i / s_i` with `s_i = max(|p_i⁰|, hi_i − lo_i)`. With `J = ∂r/∂θ`
//! (central differences, step `h = 10⁻⁴`, one-sided at a bound), `A = JᵀJ`, `g = Jᵀr`,
//! each iteration solves
//!
//! ```text
//! (A_FF + μ diag(A_FF)) δ_F = −g_F,   θ' = clamp(θ + δ, θ_lo, θ_hi)
//! ```
//!
//! over the free set `F` (a parameter at a bound whose gradient points outward is held there,
//! so the projection never stalls the others). The step is accepted when the gain ratio
//! `ρ = (S(θ) − S(θ')) / (S(θ) − ‖r + Jδ‖²) > 0`; then `μ ← μ max(1/3, 1 − (2ρ − 1)³)`,
//! else `μ ← μν, ν ← 2ν` (Nielsen's update, μ⁰ = 10⁻³ max diag A). It stops when the relative
//! decrease of `S` over an accepted step is below `ftol`, the step below `xtol (‖θ‖ + xtol)`,
//! the projected gradient below `gtol`, after `max_iterations`, or when μ grows past 10¹⁶
//! with no acceptable step.
//!
//! # Confidence intervals
//!
//! At the estimate, with `J_p = ∂r/∂p` (the chain rule: `∂θ/∂p = 1/p` or `1/s`):
//!
//! ```text
//! s² = S(p̂) / (m − n),   Cov(p̂) ≈ s² (J_pᵀ J_p)⁻¹,   p̂_i ± t_{0.975, m−n} √Cov_ii
//! ```
//!
//! the linearised (Gauss-Newton) 95 % interval, widened by the solver's remaining step (below),
//! plus, for time-history residuals, the
//! uncertainty of the baselines removed from the measured records: each channel's blow average
//! lost `b̄_k = (1/B) Σ_b b_b`, medians of `P` pre-trigger samples whose error is one constant
//! over all of the channel's residuals (not white: with 100 pre-trigger samples and 10 blows
//! it weighs ten times the white noise on the direction of a constant). With `σ_k` the spread
//! of the pre-trigger samples about their baselines, `u_k` the indicator of channel `k`'s
//! residuals and `C = (J_pᵀ J_p)⁻¹`,
//!
//! ```text
//! var(b̄_k) ≈ (π/2) σ_k² / (P B)       (the variance of a median of P normal samples, over B blows)
//! Cov(p̂) ≈ s² C + C (Σ_k var(b̄_k)/rms(m_k)² · g_k g_kᵀ) C,   g_k = J_pᵀ u_k
//! ```
//!
//! It assumes independent residuals of equal
//! variance: exact for white measurement noise on the samples (the synthetic test), but the
//! residual of a real machine is also model error, correlated from sample to sample, and the
//! interval is then narrower than the true uncertainty. **The intervals are estimates**; a
//! parameter ending at a bound gets no interval (`at_bound`).
//!
//! The solver stops on a relative step or cost decrease (`xtol`, `ftol`: 1e-8), not at the
//! least-squares minimum itself; on data with little noise the statistical half-width
//! `t √Cov_ii` is far smaller than that (1e-12 relative on noise-free measurements). The
//! Gauss-Newton step still left at the estimate,
//!
//! ```text
//! δ = −(J_pᵀ J_p)⁻¹ J_pᵀ r(p̂)      (over the identifiable values)
//! ```
//!
//! estimates how far from the minimum the solver stopped (`solver_step = |δ_i|`; on the
//! noise-free test it is the actual distance to the known values within 10 %), and each
//! interval is `p̂_i ± (t √Cov_ii + |δ_i|)`.
//!
//! # Identifiability
//!
//! A value the residuals do not depend on (its column of `J` zero: a damper stiffness fitted
//! to the bare machine) or depend on only through the others (its column a combination of
//! theirs) makes `JᵀJ` singular. Such values are named **not identifiable**
//! ([`identifiability`]: Gram-Schmidt on the columns of `J`), get no interval, and the
//! intervals of the others come from their own block of `JᵀJ`.

use std::collections::BTreeMap;

use serde::Serialize;

use super::mapping::MeasurementSpec;
use super::process::{average_blows, blow_spectrum, Processing};
use super::validate::{measured_blows, simulated_blow, MeasuredCase};
use super::SimChannel;
use crate::model::{Case, CompiledFields, FieldValue, Model, StructureCache};
use crate::{Error, Result};

/// One fitted model value.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitParameter {
    /// Model path, e.g. `contact.slider_bed.stiffness`.
    pub path: String,
    /// The model's value (the start).
    pub start: f64,
    pub lower: f64,
    pub upper: f64,
}

/// What the residual compares.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum ResidualKind {
    /// Blow-averaged time histories, sample by sample.
    TimeHistory,
    /// ESD levels (dB) of the bins between the two frequencies.
    Spectrum { lower_hz: f64, upper_hz: f64 },
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Settings {
    pub residual: ResidualKind,
    pub max_iterations: usize,
    /// Relative decrease of the cost below which the fit has converged.
    pub ftol: f64,
    /// Relative step (in the internal coordinates) below which it has converged.
    pub xtol: f64,
    /// Largest projected gradient component `|Jᵀr|` (relative to the cost) below which it has
    /// converged.
    pub gtol: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            residual: ResidualKind::TimeHistory,
            max_iterations: 50,
            ftol: 1e-8,
            xtol: 1e-8,
            gtol: 1e-10,
        }
    }
}

/// `--fit` values: comma-separated paths, repeatable; each path once.
pub fn parse_fit(list: &[String]) -> Result<Vec<String>> {
    let mut out: Vec<String> = Vec::new();
    for item in list {
        for p in item.split(',') {
            let p = p.trim();
            if p.is_empty() {
                return Err(Error::invalid(
                    "--fit",
                    format!("empty path in '{item}': give PATH[,PATH…], e.g. contact.slider_bed.stiffness"),
                ));
            }
            if out.iter().any(|q| q == p) {
                return Err(Error::invalid("--fit", format!("'{p}' is given twice")));
            }
            out.push(p.to_string());
        }
    }
    if out.is_empty() {
        return Err(Error::invalid("--fit", "no path to fit"));
    }
    Ok(out)
}

/// `--bounds` values: `PATH=LO..HI` (or `PATH=LO:HI`, [`crate::analysis::study::parse_range`]),
/// comma-separated, repeatable.
pub fn parse_bounds(list: &[String]) -> Result<BTreeMap<String, (f64, f64)>> {
    let mut out = BTreeMap::new();
    for item in list {
        for b in item.split(',') {
            let b = b.trim();
            let bad = |why: &str| {
                Error::invalid(
                    "--bounds",
                    format!("'{b}': {why}; give PATH=LO..HI (or PATH=LO:HI) with LO < HI, e.g. contact.slider_bed.stiffness=1e7..1e8"),
                )
            };
            let (path, range) = b.split_once('=').ok_or_else(|| bad("no '='"))?;
            let (lo, hi) = crate::analysis::study::parse_range(range).map_err(|e| bad(&e))?;
            if !(lo.is_finite() && hi.is_finite()) {
                return Err(bad("the bounds must be finite"));
            }
            if lo >= hi {
                return Err(bad(&format!("LO = {lo} is not below HI = {hi}")));
            }
            if out.insert(path.trim().to_string(), (lo, hi)).is_some() {
                return Err(bad("the path has bounds twice"));
            }
        }
    }
    Ok(out)
}

/// The value at a dotted path of a TOML table (`a.b[1].c`), when it is a number.
fn number_at(table: &toml::Table, path: &str) -> Option<f64> {
    let mut cur: Option<&toml::Value> = None;
    for seg in path.split('.') {
        let (key, index) = match seg.find('[') {
            Some(i) => (
                &seg[..i],
                Some(seg[i + 1..].strip_suffix(']')?.parse::<usize>().ok()?),
            ),
            None => (seg, None),
        };
        let t = match cur {
            None => table,
            Some(toml::Value::Table(t)) => t,
            _ => return None,
        };
        let mut v = t.get(key)?;
        if let Some(i) = index {
            v = v.as_array()?.get(i)?;
        }
        cur = Some(v);
    }
    match cur? {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// The fitted parameters of `model`: each path must be a real-number field of the model with a
/// value (the start); bounds from `bounds`, else `[p⁰/10, 10 p⁰]` for a positive start (a start
/// ≤ 0 needs bounds). The start must lie within the bounds.
pub fn parameters(
    model: &Model,
    paths: &[String],
    bounds: &BTreeMap<String, (f64, f64)>,
) -> Result<Vec<FitParameter>> {
    for b in bounds.keys() {
        if !paths.iter().any(|p| p == b) {
            return Err(Error::invalid(
                "--bounds",
                format!(
                    "'{b}' is not fitted (--fit {}): bounds are for fitted paths",
                    paths.join(",")
                ),
            ));
        }
    }
    let table = toml::Table::try_from(&model.spec)
        .map_err(|e| Error::numerical("calibrate", format!("cannot serialise the model: {e}")))?;
    let mut out = Vec::new();
    for path in paths {
        match crate::analysis::sweep::field_kind(model, path) {
            Ok(crate::analysis::sweep::FieldKind::Real) => {}
            Ok(crate::analysis::sweep::FieldKind::Whole) => {
                return Err(Error::invalid(
                    "--fit",
                    format!("`{path}` takes a whole number (a count or an index); calibration fits real numbers"),
                ))
            }
            Err(e) => {
                let message = match e {
                    Error::Input { message, .. } => message,
                    other => other.to_string(),
                };
                return Err(Error::Input {
                    location: format!("--fit {path}"),
                    message: format!("{message} (fit numeric model paths as --set names them, e.g. contact.slider_bed.stiffness, structure.lumped.damping_ratios[0])"),
                });
            }
        }
        let start = number_at(&table, path).ok_or_else(|| Error::Input {
            location: format!("--fit {path}"),
            message: format!(
                "the model gives no value for `{path}` to start from: write one in the model file or give --set {path}=VALUE"
            ),
        })?;
        let (lower, upper) = match bounds.get(path) {
            Some(&b) => b,
            None if start > 0.0 => (start / 10.0, start * 10.0),
            None => {
                return Err(Error::invalid(
                    "--bounds",
                    format!(
                    "`{path}` starts at {start}, not > 0: give its bounds, --bounds {path}=LO:HI"
                ),
                ))
            }
        };
        if !(lower <= start && start <= upper) {
            return Err(Error::invalid(
                "--bounds",
                format!(
                    "the start of `{path}` (the model's value {start:e}) lies outside its bounds [{lower:e}, {upper:e}]: widen the bounds or set a start inside with --set {path}=VALUE"
                ),
            ));
        }
        out.push(FitParameter {
            path: path.clone(),
            start,
            lower,
            upper,
        });
    }
    Ok(out)
}

/// One mapped channel of one case: the measured target.
#[derive(Debug, Clone)]
struct ChannelTarget {
    channel: SimChannel,
    measured_name: String,
    unit: String,
    /// Blow-averaged measured record, each record less its baseline.
    average: Vec<f64>,
    rms: f64,
    /// `var(b̄)`: the variance of the mean baseline removed (module docs, Confidence
    /// intervals; 0 when none was removed).
    baseline_variance: f64,
    /// Measured ESD (spectrum residuals) and the bins used.
    spectrum: Vec<f64>,
    bins: std::ops::Range<usize>,
    floor: f64,
}

#[derive(Debug, Clone)]
struct CaseTarget {
    case: Case,
    fs: f64,
    n: usize,
    pre: usize,
    trigger: SimChannel,
    processing: Processing,
    channels: Vec<ChannelTarget>,
}

/// `var(b̄) ≈ (π/2) σ² / (P B)`: the variance of the mean over `B` blow records of their
/// baselines, each the median of `P` pre-trigger samples, `σ²` the pooled variance of those
/// samples about their records' means (module docs, Confidence intervals); 0 when no baseline
/// is removed (fewer than [`super::process::MIN_BASELINE_SAMPLES`] pre-trigger samples).
fn baseline_variance(x: &[f64], blows: &super::process::Blows) -> Result<f64> {
    let pre = blows.pretrigger;
    if pre < super::process::MIN_BASELINE_SAMPLES || pre > blows.length || blows.starts.is_empty() {
        return Ok(0.0);
    }
    let mut ss = 0.0;
    for &s in &blows.starts {
        let seg = x.get(s..s + pre).ok_or_else(|| {
            Error::invalid(
                "blows",
                format!("the record from sample {s} runs past the end"),
            )
        })?;
        let mean = seg.iter().sum::<f64>() / pre as f64;
        ss += seg.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>();
    }
    let b = blows.starts.len() as f64;
    let var = ss / (b * (pre as f64 - 1.0));
    Ok(std::f64::consts::FRAC_PI_2 * var / (pre as f64 * b))
}

/// The least-squares problem: the measured targets and how a model is evaluated against them.
pub struct Problem<'a> {
    model: &'a Model,
    params: Vec<FitParameter>,
    settings: Settings,
    cases: Vec<CaseTarget>,
    cache: StructureCache,
    /// The fitted paths compiled on the model ([`crate::model::setter`]).
    fields: CompiledFields,
}

/// Simulated blow averages of every case and channel (in the targets' order).
type Simulated = Vec<Vec<Vec<f64>>>;

impl<'a> Problem<'a> {
    /// Processes the measured cases as `meid validate` does (module docs).
    pub fn new(
        model: &'a Model,
        params: Vec<FitParameter>,
        measured: &[MeasuredCase],
        p: &Processing,
        flags: &BTreeMap<String, SimChannel>,
        settings: Settings,
    ) -> Result<Self> {
        if measured.is_empty() {
            return Err(Error::invalid("measured", "no measured file"));
        }
        if params.is_empty() {
            return Err(Error::invalid("--fit", "no path to fit"));
        }
        if let ResidualKind::Spectrum { lower_hz, upper_hz } = settings.residual {
            if !(lower_hz.is_finite()
                && upper_hz.is_finite()
                && 0.0 <= lower_hz
                && lower_hz < upper_hz)
            {
                return Err(Error::invalid(
                    "--spectrum",
                    format!(
                        "the band must be LO:HI Hz with 0 ≤ LO < HI (got {lower_hz}:{upper_hz})"
                    ),
                ));
            }
        }
        let section: Option<&MeasurementSpec> = model.spec.measurement.as_ref();
        let point = model.spec.points.measurement.clone();
        let mut cases = Vec::new();
        for m in measured {
            let mb = measured_blows(m, p, section, flags, &point)?;
            let n = mb.blows.length;
            let mut channels = Vec::new();
            for (&c, &i) in &mb.map {
                let r = &m.records[i];
                // Less each record's baseline, as the simulation's (at rest: 0).
                let average = average_blows(&r.values, &mb.blows)?;
                let baseline_variance = baseline_variance(&r.values, &mb.blows)?;
                let rms = (average.iter().map(|x| x * x).sum::<f64>() / n as f64).sqrt();
                if !(rms > 0.0 && rms.is_finite()) {
                    return Err(Error::Input {
                        location: r.origin.clone(),
                        message: format!(
                            "channel '{}': the blow-averaged record is zero or not finite: nothing to fit",
                            r.name
                        ),
                    });
                }
                let (spectrum, bins, floor) = match settings.residual {
                    ResidualKind::TimeHistory => (Vec::new(), 0..0, 0.0),
                    ResidualKind::Spectrum { lower_hz, upper_hz } => {
                        let s = blow_spectrum(&r.values, c.role(), mb.fs, &mb.blows, p, None)?;
                        let first = s.frequency_hz.iter().position(|f| *f >= lower_hz);
                        let last = s.frequency_hz.iter().rposition(|f| *f <= upper_hz);
                        let bins = match (first, last) {
                            (Some(a), Some(b)) if a <= b => a..b + 1,
                            _ => {
                                return Err(Error::invalid(
                                    "--spectrum",
                                    format!(
                                        "no spectral bin between {lower_hz} and {upper_hz} Hz (bins every {:.4} Hz up to {:.1} Hz)",
                                        s.bin_width_hz(),
                                        mb.fs / 2.0
                                    ),
                                ))
                            }
                        };
                        let Some(d) = s.density_si() else {
                            return Err(Error::Input {
                                location: r.origin.clone(),
                                message: format!(
                                    "channel '{}': its energy spectral density is beyond the range of doubles in ({})²·s/Hz: the spectral fit (--spectrum) cannot use it",
                                    r.name,
                                    r.unit()
                                ),
                            });
                        };
                        let top = d.iter().fold(0.0_f64, |a, b| a.max(*b));
                        (d.to_vec(), bins, 1e-12 * top)
                    }
                };
                channels.push(ChannelTarget {
                    channel: c,
                    measured_name: r.name.clone(),
                    unit: r.unit().to_string(),
                    average,
                    rms,
                    baseline_variance,
                    spectrum,
                    bins,
                    floor,
                });
            }
            cases.push(CaseTarget {
                case: m.case,
                fs: mb.fs,
                n,
                pre: mb.blows.pretrigger,
                trigger: mb.trigger,
                processing: p.clone(),
                channels,
            });
        }
        let paths: Vec<&str> = params.iter().map(|q| q.path.as_str()).collect();
        let fields = model.compile_fields(&paths);
        Ok(Problem {
            model,
            params,
            settings,
            cases,
            fields,
            cache: StructureCache::new(),
        })
    }

    /// The fitted parameters.
    pub fn parameters(&self) -> &[FitParameter] {
        &self.params
    }

    /// Structures built so far (the cache's count; 0 when only non-structural values vary).
    pub fn structures_built(&self) -> usize {
        self.cache.builds()
    }

    /// The model with `values` set: the model `--set PATH=VALUE` gives with each value written
    /// `{:e}` ([`Model::with_fields`]), through the typed setters ([`Model::with_values`]).
    pub fn model_with(&self, values: &[f64]) -> Result<Model> {
        let typed: Vec<FieldValue> = values.iter().map(|v| FieldValue::Real(*v)).collect();
        self.model
            .with_values(&self.fields, &typed, Some(&self.cache))
    }

    /// Simulated records (blow averages per case and channel) and the residual vector at
    /// `values`.
    fn evaluate(&self, values: &[f64]) -> Result<(Simulated, Vec<f64>)> {
        let m = self.model_with(values)?;
        let mut sims = Vec::with_capacity(self.cases.len());
        let mut r = Vec::new();
        for ct in &self.cases {
            let sys = m.impact_system(ct.case)?;
            let sim = simulated_blow(&m, &sys, ct.fs, ct.n, ct.pre, ct.trigger, &ct.processing)?;
            let mut per = Vec::with_capacity(ct.channels.len());
            for ch in &ct.channels {
                let s = sim.record(ch.channel)?;
                let sa = average_blows(&s.values, &sim.blows)?;
                match self.settings.residual {
                    ResidualKind::TimeHistory => {
                        r.extend(sa.iter().zip(&ch.average).map(|(s, m)| (s - m) / ch.rms));
                    }
                    ResidualKind::Spectrum { .. } => {
                        let ss = blow_spectrum(
                            &s.values,
                            ch.channel.role(),
                            ct.fs,
                            &sim.blows,
                            &sim.processing,
                            None,
                        )?;
                        let sd = ss.density_si().ok_or_else(|| {
                            Error::numerical(
                                "calibrate",
                                "the simulated energy spectral density is beyond the range of doubles",
                            )
                        })?;
                        for k in ch.bins.clone() {
                            let (es, em) = (sd[k], ch.spectrum[k]);
                            r.push(10.0 * ((es + ch.floor) / (em + ch.floor)).log10());
                        }
                    }
                }
                per.push(sa);
            }
            sims.push(per);
        }
        if let Some(bad) = r.iter().position(|x| !x.is_finite()) {
            return Err(Error::numerical(
                "calibrate",
                format!("residual {bad} is not finite at {values:?}"),
            ));
        }
        Ok((sims, r))
    }

    /// The residual vector `r(p)` (module docs).
    pub fn residuals(&self, values: &[f64]) -> Result<Vec<f64>> {
        Ok(self.evaluate(values)?.1)
    }
}

/// Why the solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Convergence {
    /// The cost decreased by less than `ftol` (relative) over a step.
    Cost,
    /// The step was below `xtol`.
    Step,
    /// The projected gradient vanished.
    Gradient,
    /// `max_iterations` reached: not converged.
    MaxIterations,
    /// No step decreased the cost (μ past 10¹⁶): not converged.
    NoProgress,
}

impl Convergence {
    /// Text for reports.
    pub fn describe(self) -> &'static str {
        match self {
            Convergence::Cost => "converged: relative cost decrease below ftol",
            Convergence::Step => "converged: step below xtol",
            Convergence::Gradient => "converged: projected gradient below gtol",
            Convergence::MaxIterations => "NOT converged: iteration limit reached",
            Convergence::NoProgress => "NOT converged: no step decreases the cost",
        }
    }

    /// True for the converged reasons.
    pub fn converged(self) -> bool {
        matches!(
            self,
            Convergence::Cost | Convergence::Step | Convergence::Gradient
        )
    }
}

/// The solver's outcome in the internal coordinates.
#[derive(Debug, Clone)]
pub struct LmOutcome {
    pub x: Vec<f64>,
    pub residuals: Vec<f64>,
    pub cost: f64,
    /// `∂r/∂x` at `x` (column-major: one column per parameter).
    pub jacobian: Vec<Vec<f64>>,
    pub iterations: usize,
    pub evaluations: usize,
    pub reason: Convergence,
}

/// Solves `A x = b` (A symmetric positive definite, n small) by Cholesky; `None` when A is not
/// positive definite.
fn cholesky_solve(a: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s.is_finite() && s > 0.0) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let s: f64 = (0..i).map(|k| l[i][k] * y[k]).sum();
        y[i] = (b[i] - s) / l[i][i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| l[k][i] * x[k]).sum();
        x[i] = (y[i] - s) / l[i][i];
    }
    Some(x)
}

/// The inverse of a small symmetric positive definite matrix (column by column).
pub(super) fn spd_inverse(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let mut inv = vec![vec![0.0; n]; n];
    for j in 0..n {
        let mut e = vec![0.0; n];
        e[j] = 1.0;
        let c = cholesky_solve(a, &e)?;
        for i in 0..n {
            inv[i][j] = c[i];
        }
    }
    Some(inv)
}

pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `∂r/∂x` by central differences, step `h = 10⁻⁴ (1 + |x_i|)`, one-sided at a bound.
fn fd_jacobian(
    f: &mut dyn FnMut(&[f64]) -> Result<Vec<f64>>,
    x: &[f64],
    r: &[f64],
    lo: &[f64],
    hi: &[f64],
    evals: &mut usize,
) -> Result<Vec<Vec<f64>>> {
    let h = 1e-4;
    let n = x.len();
    let mut cols = Vec::with_capacity(n);
    for i in 0..n {
        let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
        let step = h * (1.0 + x[i].abs());
        xp[i] = (x[i] + step).min(hi[i]);
        xm[i] = (x[i] - step).max(lo[i]);
        let (rp, rm) = if xp[i] > x[i] && xm[i] < x[i] {
            *evals += 2;
            (f(&xp)?, f(&xm)?)
        } else if xp[i] > x[i] {
            *evals += 1;
            xm[i] = x[i];
            (f(&xp)?, r.to_vec())
        } else {
            *evals += 1;
            xp[i] = x[i];
            (r.to_vec(), f(&xm)?)
        };
        let d = xp[i] - xm[i];
        if !(d.is_finite() && d > 0.0) {
            return Err(Error::invalid(
                "--bounds",
                "a parameter's bounds leave no room to vary it",
            ));
        }
        cols.push(rp.iter().zip(&rm).map(|(a, b)| (a - b) / d).collect());
    }
    Ok(cols)
}

/// Projected Levenberg-Marquardt (module docs) on `f: x ↦ r` within `[lo, hi]`, from `x0`.
/// An evaluation that fails at a trial point counts as a rejected step; one that fails at the
/// start (or in the Jacobian of an accepted point) is an error.
pub fn levenberg_marquardt(
    mut f: impl FnMut(&[f64]) -> Result<Vec<f64>>,
    x0: &[f64],
    lo: &[f64],
    hi: &[f64],
    s: &Settings,
) -> Result<LmOutcome> {
    let n = x0.len();
    let clamp = |x: &mut [f64]| {
        for i in 0..n {
            x[i] = x[i].clamp(lo[i], hi[i]);
        }
    };
    let mut x = x0.to_vec();
    clamp(&mut x);
    let mut evaluations = 0usize;
    let mut r = f(&x)?;
    evaluations += 1;
    let mut cost = dot(&r, &r);
    let mut jac = fd_jacobian(&mut f, &x, &r, lo, hi, &mut evaluations)?;
    let normal = |jac: &[Vec<f64>], r: &[f64]| {
        let a: Vec<Vec<f64>> = (0..n)
            .map(|i| (0..n).map(|j| dot(&jac[i], &jac[j])).collect())
            .collect();
        let g: Vec<f64> = (0..n).map(|i| dot(&jac[i], r)).collect();
        (a, g)
    };
    let (mut a, mut g) = normal(&jac, &r);
    let mut mu = 1e-3 * (0..n).map(|i| a[i][i]).fold(0.0_f64, f64::max);
    if !(mu.is_finite() && mu > 0.0) {
        mu = 1e-3;
    }
    let mut nu = 2.0;
    let mut iterations = 0;
    let reason = loop {
        // Free set: a parameter at a bound with the descent direction (−g) pointing out is held.
        let free: Vec<usize> = (0..n)
            .filter(|&i| !((x[i] <= lo[i] && g[i] > 0.0) || (x[i] >= hi[i] && g[i] < 0.0)))
            .collect();
        let gmax = free.iter().map(|&i| g[i].abs()).fold(0.0_f64, f64::max);
        if free.is_empty() || gmax <= s.gtol * cost.max(f64::MIN_POSITIVE) {
            break Convergence::Gradient;
        }
        if iterations >= s.max_iterations {
            break Convergence::MaxIterations;
        }
        iterations += 1;
        let mut accepted = None;
        while accepted.is_none() {
            if mu > 1e16 {
                break;
            }
            let af: Vec<Vec<f64>> = free
                .iter()
                .map(|&i| {
                    free.iter()
                        .map(|&j| {
                            let d = if i == j {
                                mu * a[i][i].max(1e-300)
                            } else {
                                0.0
                            };
                            a[i][j] + d
                        })
                        .collect()
                })
                .collect();
            let bf: Vec<f64> = free.iter().map(|&i| -g[i]).collect();
            let Some(df) = cholesky_solve(&af, &bf) else {
                mu *= nu;
                nu *= 2.0;
                continue;
            };
            let mut xn = x.clone();
            for (k, &i) in free.iter().enumerate() {
                xn[i] += df[k];
            }
            clamp(&mut xn);
            let step: Vec<f64> = (0..n).map(|i| xn[i] - x[i]).collect();
            let norm_x = dot(&x, &x).sqrt();
            if dot(&step, &step).sqrt() <= s.xtol * (norm_x + s.xtol) {
                accepted = Some(None);
                break;
            }
            // Predicted cost ‖r + Jδ‖² = S + 2δᵀg + δᵀAδ.
            let a_step: Vec<f64> = (0..n).map(|i| dot(&a[i], &step)).collect();
            let predicted = -(2.0 * dot(&step, &g) + dot(&step, &a_step));
            let trial = f(&xn);
            evaluations += 1;
            let rho = match &trial {
                Ok(rn) if predicted > 0.0 => (cost - dot(rn, rn)) / predicted,
                _ => -1.0,
            };
            if rho > 0.0 {
                if let Ok(rn) = trial {
                    accepted = Some(Some((xn, rn)));
                }
                mu *= (1.0_f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
            } else {
                mu *= nu;
                nu *= 2.0;
            }
        }
        match accepted {
            None => break Convergence::NoProgress,
            Some(None) => break Convergence::Step,
            Some(Some((xn, rn))) => {
                let new_cost = dot(&rn, &rn);
                let decrease = cost - new_cost;
                x = xn;
                r = rn;
                cost = new_cost;
                jac = fd_jacobian(&mut f, &x, &r, lo, hi, &mut evaluations)?;
                (a, g) = normal(&jac, &r);
                if decrease <= s.ftol * cost.max(f64::MIN_POSITIVE) {
                    break Convergence::Cost;
                }
            }
        }
    };
    Ok(LmOutcome {
        x,
        residuals: r,
        cost,
        jacobian: jac,
        iterations,
        evaluations,
        reason,
    })
}

/// `t_{0.975, ν}`, the two-sided 95 % quantile of Student's t with ν degrees of freedom.
pub fn student_t_975(dof: usize) -> f64 {
    const T: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match dof {
        0 => f64::INFINITY,
        d if d <= 30 => T[d - 1],
        // Cornish-Fisher expansion about the normal quantile z = 1.959964.
        d => {
            let z: f64 = 1.959_963_985;
            let v = d as f64;
            z + (z.powi(3) + z) / (4.0 * v)
                + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * v * v)
        }
    }
}

/// One fitted value with its interval.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimate {
    pub path: String,
    pub start: f64,
    pub value: f64,
    pub lower_bound: f64,
    pub upper_bound: f64,
    /// `√Cov_ii` (estimated; module docs). NaN at a bound or when `JᵀJ` is singular.
    pub standard_error: f64,
    /// `|δ_i|`, the Gauss-Newton step `δ = −(J_pᵀJ_p)⁻¹J_pᵀr` still left at the estimate: how
    /// far the solver stopped from the least-squares minimum (estimated; module docs). NaN
    /// where the standard error is.
    pub solver_step: f64,
    /// The 95 % interval `value ± (t·standard_error + solver_step)` (estimated).
    pub ci95_low: f64,
    pub ci95_high: f64,
    /// `(t·standard_error + solver_step) / |value|`.
    pub relative_half_width: f64,
    /// The estimate sits on a bound: no interval.
    pub at_bound: bool,
    /// Whether the residuals determine the value ([`identifiability`]); the value of one
    /// that is not is the start (or wherever the others' steps left it) and has no interval.
    pub identifiability: Identifiability,
}

/// Whether the data determine a fitted value, from the Jacobian `J = ∂r/∂θ` at the estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Identifiability {
    /// Its column of `J` is independent of the others: it has an interval.
    Identifiable,
    /// The residuals do not depend on it: `‖J_i‖ ≤ 10⁻⁹ max_j ‖J_j‖` (a damper stiffness
    /// fitted to the bare machine, a damping ratio of a mode no channel sees).
    NoEffect,
    /// Its column is a combination of the identifiable ones' (to 10⁻⁶ of its norm, above the
    /// central differences' truncation error, 10⁻⁸ for smooth residuals): only a
    /// combination of these values is determined (e.g. a stiffness and a mass that enter
    /// through their ratio alone).
    Dependent,
}

impl Identifiability {
    /// Text for the report's interval column.
    pub fn describe(self) -> &'static str {
        match self {
            Identifiability::Identifiable => "identifiable",
            Identifiability::NoEffect => "not identifiable: no effect",
            Identifiability::Dependent => "not identifiable: dependent",
        }
    }
}

/// Classifies each fitted value ([`Identifiability`]) from the columns `J_i` (one per value,
/// internal coordinates) of the Jacobian: Gram-Schmidt in the given order keeps a column when
/// its part orthogonal to those kept has a norm above 10⁻⁶ of its own (a relative rank test
/// that the columns' units do not affect); a column of norm at most 10⁻⁹ of the largest has no
/// effect.
pub fn identifiability(jacobian: &[Vec<f64>]) -> Vec<Identifiability> {
    const TOL: f64 = 1e-9;
    const DEPENDENT: f64 = 1e-6;
    let norms: Vec<f64> = jacobian.iter().map(|c| dot(c, c).sqrt()).collect();
    let top = norms.iter().copied().fold(0.0_f64, f64::max);
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut out = Vec::with_capacity(jacobian.len());
    for (c, &norm) in jacobian.iter().zip(&norms) {
        if !(norm.is_finite() && norm > TOL * top) {
            out.push(Identifiability::NoEffect);
            continue;
        }
        let mut v = c.clone();
        // Twice (re-orthogonalisation keeps the test honest in floating point).
        for _ in 0..2 {
            for q in &basis {
                let d = dot(&v, q);
                v.iter_mut().zip(q).for_each(|(a, b)| *a -= d * b);
            }
        }
        let rest = dot(&v, &v).sqrt();
        if rest > DEPENDENT * norm {
            v.iter_mut().for_each(|a| *a /= rest);
            basis.push(v);
            out.push(Identifiability::Identifiable);
        } else {
            out.push(Identifiability::Dependent);
        }
    }
    out
}

/// Fit of one channel of one case, before (the model's values) and after.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelFit {
    pub case: String,
    pub channel: SimChannel,
    pub measured_name: String,
    pub unit: String,
    /// RMS of the measured blow average (SI).
    pub measured_rms: f64,
    /// RMS of simulated − measured (SI), time histories.
    pub rms_error_before: f64,
    pub rms_error_after: f64,
    /// `rms_error / measured_rms`.
    pub relative_error_before: f64,
    pub relative_error_after: f64,
    /// Blow averages for the overlay (from the record start).
    #[serde(skip)]
    pub measured: Vec<f64>,
    #[serde(skip)]
    pub before: Vec<f64>,
    #[serde(skip)]
    pub after: Vec<f64>,
    #[serde(skip)]
    pub sample_rate_hz: f64,
    #[serde(skip)]
    pub pretrigger_s: f64,
}

/// The calibration's result.
#[derive(Debug, Clone, Serialize)]
pub struct Calibration {
    pub parameters: Vec<Estimate>,
    pub residual: ResidualKind,
    /// Number of residuals `m`.
    pub residuals: usize,
    /// `√(S/m)` before and after (dimensionless for time histories: relative to each
    /// channel's measured RMS; dB for spectra).
    pub rms_residual_before: f64,
    pub rms_residual_after: f64,
    /// `s = √(S/(m − n))`.
    pub sigma: f64,
    /// Correlation matrix of the estimates (estimated, from `(JᵀJ)⁻¹`).
    pub correlation: Vec<Vec<f64>>,
    pub iterations: usize,
    pub evaluations: usize,
    pub convergence: Convergence,
    pub converged: bool,
    /// Structures solved during the fit (0: every evaluation reused the model's).
    pub structures_built: usize,
    pub channels: Vec<ChannelFit>,
}

pub(super) fn to_internal(p: &FitParameter, v: f64) -> f64 {
    if p.lower > 0.0 {
        v.ln()
    } else {
        v / scale(p)
    }
}

pub(super) fn from_internal(p: &FitParameter, x: f64) -> f64 {
    if p.lower > 0.0 {
        x.exp()
    } else {
        x * scale(p)
    }
}

/// `dp/dθ`.
pub(super) fn dp_dx(p: &FitParameter, v: f64) -> f64 {
    if p.lower > 0.0 {
        v
    } else {
        scale(p)
    }
}

fn scale(p: &FitParameter) -> f64 {
    p.start.abs().max(p.upper - p.lower)
}

/// What a bounded least-squares fit gives both calibrations (response and modal): the fitted
/// values, the solver's outcome in its internal (bounded) variables, the residuals before and
/// after, the Jacobian in the values (`J_p = J_θ · dθ/dp`), which values are identifiable and
/// `J_pᵀJ_p` over those (`free`), and the residual variance `s² = rᵀr / (m − n)`.
pub(super) struct BoundedFit<T> {
    pub values: Vec<f64>,
    pub out: LmOutcome,
    /// The bounds in the internal variables: a value on one is at its bound.
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
    pub before: T,
    pub r0: Vec<f64>,
    pub after: T,
    pub r1: Vec<f64>,
    pub jp: Vec<Vec<f64>>,
    pub identifiability: Vec<Identifiability>,
    pub free: Vec<usize>,
    pub jtj: Vec<Vec<f64>>,
    pub dof: usize,
    pub s2: f64,
    pub cost: f64,
}

impl<T> BoundedFit<T> {
    /// Levenberg-Marquardt over `params` from their starts within their bounds:
    /// `evaluate(values)` gives what the caller reports with the residuals, `residuals(values)`
    /// the residuals alone.
    pub fn run(
        params: &[FitParameter],
        settings: &Settings,
        evaluate: impl Fn(&[f64]) -> Result<(T, Vec<f64>)>,
        residuals: impl Fn(&[f64]) -> Result<Vec<f64>>,
    ) -> Result<Self> {
        let n = params.len();
        let x0: Vec<f64> = params.iter().map(|p| to_internal(p, p.start)).collect();
        let lo: Vec<f64> = params.iter().map(|p| to_internal(p, p.lower)).collect();
        let hi: Vec<f64> = params.iter().map(|p| to_internal(p, p.upper)).collect();
        let values_of = |x: &[f64]| -> Vec<f64> {
            params
                .iter()
                .zip(x)
                .map(|(p, &xi)| from_internal(p, xi).clamp(p.lower, p.upper))
                .collect()
        };
        let starts: Vec<f64> = params.iter().map(|p| p.start).collect();
        let (before, r0) = evaluate(&starts)?;
        let out = levenberg_marquardt(|x| residuals(&values_of(x)), &x0, &lo, &hi, settings)?;
        let values = values_of(&out.x);
        let (after, r1) = evaluate(&values)?;
        let cost = dot(&r1, &r1);
        let dof = r1.len().saturating_sub(n);
        let s2 = if dof > 0 { cost / dof as f64 } else { f64::NAN };
        // J_p = J_θ · dθ/dp.
        let jp: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                let d = dp_dx(&params[i], values[i]);
                out.jacobian[i].iter().map(|x| x / d).collect()
            })
            .collect();
        let identifiability = identifiability(&out.jacobian);
        // The covariance of the identifiable values (the others held: their columns are zero
        // or dependent, and would make JᵀJ singular for every value).
        let free: Vec<usize> = (0..n)
            .filter(|&i| identifiability[i] == Identifiability::Identifiable)
            .collect();
        let jtj: Vec<Vec<f64>> = free
            .iter()
            .map(|&i| free.iter().map(|&j| dot(&jp[i], &jp[j])).collect())
            .collect();
        Ok(Self {
            values,
            out,
            lo,
            hi,
            before,
            r0,
            after,
            r1,
            jp,
            identifiability,
            free,
            jtj,
            dof,
            s2,
            cost,
        })
    }

    /// Whether value `i` ended on one of its bounds.
    pub fn at_bound(&self, i: usize) -> bool {
        self.out.x[i] <= self.lo[i] || self.out.x[i] >= self.hi[i]
    }

    /// The Gauss-Newton step left at the estimate, `|δ_i|` with `δ = −C J_pᵀr` over the free
    /// values (`c_inv` = `(J_pᵀJ_p)⁻¹` over `free`), per value; NaN for a value that is not
    /// free or without `c_inv`. The solver stops on a relative step or cost decrease (xtol,
    /// ftol), which on data with little noise is far wider than the statistical interval.
    pub fn solver_steps(&self, c_inv: Option<&[Vec<f64>]>) -> Vec<f64> {
        let mut step = vec![f64::NAN; self.values.len()];
        if let Some(c) = c_inv {
            let g: Vec<f64> = self
                .free
                .iter()
                .map(|&i| dot(&self.jp[i], &self.r1))
                .collect();
            for (k, &i) in self.free.iter().enumerate() {
                step[i] = c[k].iter().zip(&g).map(|(c, g)| c * g).sum::<f64>().abs();
            }
        }
        step
    }

    /// The r.m.s. residual at the starts and at the estimate.
    pub fn rms_residuals(&self) -> (f64, f64) {
        (
            (dot(&self.r0, &self.r0) / self.r0.len() as f64).sqrt(),
            (self.cost / self.r1.len() as f64).sqrt(),
        )
    }
}

/// Runs the calibration (module docs).
pub fn calibrate(problem: &Problem<'_>) -> Result<Calibration> {
    let params = &problem.params;
    let n = params.len();
    let fit = BoundedFit::run(
        params,
        &problem.settings,
        |v| problem.evaluate(v),
        |v| problem.residuals(v),
    )?;
    let BoundedFit {
        ref values,
        ref out,
        ref before,
        ref after,
        ref r1,
        ref jp,
        ref identifiability,
        ref free,
        jtj: ref a,
        dof,
        s2,
        ..
    } = fit;
    let m = r1.len();
    let baseline = baseline_term(problem, free, jp);
    let c_inv = spd_inverse(a);
    let cov = covariance(c_inv.as_deref(), &baseline, free, n, s2);
    let solver_step = fit.solver_steps(c_inv.as_deref());
    let (rms_before, rms_after) = fit.rms_residuals();
    let t = student_t_975(dof);
    let mut estimates = Vec::new();
    for (i, p) in params.iter().enumerate() {
        let at_bound = fit.at_bound(i);
        let se = match &cov {
            Some(c) if !at_bound && c[i][i] >= 0.0 => c[i][i].sqrt(),
            _ => f64::NAN,
        };
        let step = if se.is_nan() {
            f64::NAN
        } else {
            solver_step[i]
        };
        estimates.push(estimate(
            p,
            values[i],
            se,
            step,
            t,
            at_bound,
            identifiability[i],
        ));
    }
    let correlation = match &cov {
        Some(c) => (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| c[i][j] / (c[i][i] * c[j][j]).sqrt())
                    .collect()
            })
            .collect(),
        None => vec![vec![f64::NAN; n]; n],
    };
    Ok(Calibration {
        parameters: estimates,
        residual: problem.settings.residual,
        residuals: m,
        rms_residual_before: rms_before,
        rms_residual_after: rms_after,
        sigma: s2.sqrt(),
        correlation,
        iterations: out.iterations,
        evaluations: out.evaluations + 2,
        convergence: out.reason,
        converged: out.reason.converged(),
        structures_built: problem.structures_built(),
        channels: channel_fits(problem, before, after),
    })
}

/// The baselines' share of the covariance (module docs): B = Σ_k var(b̄_k)/rms_k² g_k g_kᵀ over
/// the `free` values, g_k the sums of J_p's rows of channel k (time-history residuals only: a
/// constant leaves the ESD above DC as it is).
fn baseline_term(problem: &Problem<'_>, free: &[usize], jp: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut baseline_term = vec![vec![0.0; free.len()]; free.len()];
    if problem.settings.residual == ResidualKind::TimeHistory {
        let mut row = 0;
        for ct in &problem.cases {
            for ch in &ct.channels {
                let rows = row..row + ct.n;
                row += ct.n;
                if ch.baseline_variance <= 0.0 {
                    continue;
                }
                let w = ch.baseline_variance / (ch.rms * ch.rms);
                let g: Vec<f64> = free
                    .iter()
                    .map(|&i| jp[i].get(rows.clone()).map_or(0.0, |r| r.iter().sum()))
                    .collect();
                for (a, ga) in g.iter().enumerate() {
                    for (b, gb) in g.iter().enumerate() {
                        baseline_term[a][b] += w * ga * gb;
                    }
                }
            }
        }
    }
    baseline_term
}

/// Cov = s² C + C B C over the `free` values (C = (J_pᵀ J_p)⁻¹, `c_inv`; B the baselines'
/// share), in an n × n matrix with NaN for the held values; `None` without C.
fn covariance(
    c_inv: Option<&[Vec<f64>]>,
    baseline_term: &[Vec<f64>],
    free: &[usize],
    n: usize,
    s2: f64,
) -> Option<Vec<Vec<f64>>> {
    c_inv.map(|c| {
        let k = free.len();
        let cb: Vec<Vec<f64>> = (0..k)
            .map(|a| {
                (0..k)
                    .map(|b| (0..k).map(|l| c[a][l] * baseline_term[l][b]).sum())
                    .collect()
            })
            .collect();
        let mut full = vec![vec![f64::NAN; n]; n];
        for (a, &i) in free.iter().enumerate() {
            for (b, &j) in free.iter().enumerate() {
                let cbc: f64 = (0..k).map(|l| cb[a][l] * c[l][b]).sum();
                full[i][j] = s2 * c[a][b] + cbc;
            }
        }
        full
    })
}

/// One parameter's estimate `v` with its 95 % interval `v ± (t se + step)` (`t` Student's
/// 97.5 % quantile, `se` the standard error, `step` the Gauss-Newton step left).
pub(super) fn estimate(
    p: &FitParameter,
    v: f64,
    se: f64,
    step: f64,
    t: f64,
    at_bound: bool,
    identifiability: Identifiability,
) -> Estimate {
    let half = t * se + step;
    Estimate {
        path: p.path.clone(),
        start: p.start,
        value: v,
        lower_bound: p.lower,
        upper_bound: p.upper,
        standard_error: se,
        solver_step: step,
        ci95_low: v - half,
        ci95_high: v + half,
        relative_half_width: half / v.abs(),
        at_bound,
        identifiability,
    }
}

/// Each measured channel against the simulation before and after the fit: the RMS errors
/// `√(Σ (s − m)²/n)` and the blow-averaged records.
fn channel_fits(problem: &Problem<'_>, before: &Simulated, after: &Simulated) -> Vec<ChannelFit> {
    let mut channels = Vec::new();
    for (ci, ct) in problem.cases.iter().enumerate() {
        for (k, ch) in ct.channels.iter().enumerate() {
            let rms_err = |s: &[f64]| {
                (s.iter()
                    .zip(&ch.average)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    / ct.n as f64)
                    .sqrt()
            };
            let (eb, ea) = (rms_err(&before[ci][k]), rms_err(&after[ci][k]));
            channels.push(ChannelFit {
                case: super::validate::case_name(ct.case).into(),
                channel: ch.channel,
                measured_name: ch.measured_name.clone(),
                unit: ch.unit.clone(),
                measured_rms: ch.rms,
                rms_error_before: eb,
                rms_error_after: ea,
                relative_error_before: eb / ch.rms,
                relative_error_after: ea / ch.rms,
                measured: ch.average.clone(),
                before: before[ci][k].clone(),
                after: after[ci][k].clone(),
                sample_rate_hz: ct.fs,
                pretrigger_s: ct.pre as f64 / ct.fs,
            });
        }
    }
    channels
}

/// The calibrated model file: the model's own text with each fitted value replaced in place
/// (comments and layout kept) when the file writes every fitted value and no `--set` changed
/// the model; otherwise the whole calibrated model serialised, under a comment saying so.
/// Either text reads back ([`Model::from_text`]) to the calibrated model.
pub fn calibrated_model_text(
    model: &Model,
    params: &[FitParameter],
    values: &[f64],
) -> Result<String> {
    calibrated_model_text_by(model, params, values, "meid calibrate")
}

/// [`calibrated_model_text`] with the command that calibrated named in its header
/// (`meid report --fit` writes the same file as `meid calibrate --modal`).
pub fn calibrated_model_text_by(
    model: &Model,
    params: &[FitParameter],
    values: &[f64],
    command: &str,
) -> Result<String> {
    let src = &model.source;
    let spans: Option<Vec<_>> = params.iter().map(|p| src.value_span(&p.path)).collect();
    let header = {
        let mut h = format!("# Calibrated by `{command}`:\n");
        for (p, v) in params.iter().zip(values) {
            h.push_str(&format!("#   {} = {v:e} (was {:e})\n", p.path, p.start));
        }
        h
    };
    if let (true, Some(mut spans)) = (src.overrides.is_empty(), spans) {
        let mut order: Vec<usize> = (0..params.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(spans[i].start));
        let mut text = src.text.clone();
        for i in order {
            let span = std::mem::replace(&mut spans[i], 0..0);
            text.replace_range(span, &format!("{:e}", values[i]));
        }
        return Ok(format!("{header}{text}"));
    }
    let m = model.with_fields(
        &params
            .iter()
            .zip(values)
            .map(|(p, v)| format!("{}={v:e}", p.path))
            .collect::<Vec<_>>(),
        None,
    )?;
    let body = toml::to_string(&m.spec)
        .map_err(|e| Error::numerical("calibrate", format!("cannot serialise the model: {e}")))?;
    Ok(format!(
        "{header}# (written from the model as read, with its --set overrides: the original layout and comments are not kept)\n{body}"
    ))
}

impl Calibration {
    /// The fitted values in the parameters' order.
    pub fn values(&self) -> Vec<f64> {
        self.parameters.iter().map(|e| e.value).collect()
    }

    /// The report as text.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{:<40} {:>13} {:>13} {:>29} {:>9}",
            "parameter", "start", "estimate", "95 % interval (estimated)", "± %"
        );
        for e in &self.parameters {
            if e.identifiability != Identifiability::Identifiable {
                let _ = writeln!(
                    s,
                    "{:<40} {:>13.6e} {:>13.6e} {:>29} {:>9}",
                    e.path,
                    e.start,
                    e.value,
                    e.identifiability.describe(),
                    "-"
                );
            } else if e.at_bound {
                let _ = writeln!(
                    s,
                    "{:<40} {:>13.6e} {:>13.6e} {:>29} {:>9}",
                    e.path, e.start, e.value, "at its bound: no interval", "-"
                );
            } else {
                let _ = writeln!(
                    s,
                    "{:<40} {:>13.6e} {:>13.6e} [{:>13.6e}, {:>13.6e}] {:>8.3}",
                    e.path,
                    e.start,
                    e.value,
                    e.ci95_low,
                    e.ci95_high,
                    100.0 * e.relative_half_width
                );
            }
        }
        let unit = match self.residual {
            ResidualKind::TimeHistory => "(relative to each channel's measured RMS)".to_string(),
            ResidualKind::Spectrum { lower_hz, upper_hz } => {
                format!("dB (ESD levels, {lower_hz}–{upper_hz} Hz)")
            }
        };
        let _ = writeln!(
            s,
            "residual RMS {unit}: {:.5e} before, {:.5e} after ({} residuals)",
            self.rms_residual_before, self.rms_residual_after, self.residuals
        );
        for c in &self.channels {
            let _ = writeln!(
                s,
                "  {} {} ('{}'): RMS error {:.4e} → {:.4e} {u} ({:.3} % → {:.3} % of the measured RMS {:.4e} {u})",
                c.case,
                c.channel.label(),
                c.measured_name,
                c.rms_error_before,
                c.rms_error_after,
                100.0 * c.relative_error_before,
                100.0 * c.relative_error_after,
                c.measured_rms,
                u = c.unit
            );
        }
        let _ = writeln!(
            s,
            "{} after {} iterations ({} model evaluations, {} structures solved)",
            self.convergence.describe(),
            self.iterations,
            self.evaluations,
            self.structures_built
        );
        let _ = writeln!(s, "intervals: linearised, s²(JᵀJ)⁻¹ with independent residuals assumed, plus the solver's remaining Gauss-Newton step; correlated model error makes the true uncertainty larger");
        let lost: Vec<&Estimate> = self
            .parameters
            .iter()
            .filter(|e| e.identifiability != Identifiability::Identifiable)
            .collect();
        if !lost.is_empty() {
            let names: Vec<&str> = lost.iter().map(|e| e.path.as_str()).collect();
            let _ = writeln!(
                s,
                "not identifiable from these measurements: {} — the residuals do not depend on {} (no effect) or only through the other values (dependent); its value is not an estimate: fix it (leave it out of --fit) or measure a case it acts in",
                names.join(", "),
                if lost.len() == 1 { "it" } else { "them" }
            );
        }
        s
    }

    /// Pictures: per case and channel, `calibration_<case>_<channel>` (PNG, SVG): the measured
    /// blow average, the simulation before (the model's values) and after (the estimates).
    pub fn plots(&self, dir: &std::path::Path) -> Result<()> {
        use crate::plot::{LinePlot, Series};
        for c in &self.channels {
            let dt = 1.0 / c.sample_rate_hz;
            let t: Vec<f64> = (0..c.measured.len())
                .map(|i| i as f64 * dt - c.pretrigger_s)
                .collect();
            let series = |label: String, y: &[f64]| Series {
                label,
                x: t.clone(),
                y: y.to_vec(),
                ..Default::default()
            };
            crate::plot::line_plot(
                dir.join(format!("calibration_{}_{}", c.case, c.channel.target())),
                &LinePlot {
                    title: format!(
                        "{} ({}): before and after calibration",
                        c.channel.label(),
                        c.case
                    ),
                    x_label: "time from the trigger (s)".into(),
                    y_label: format!("{} ({})", c.channel.quantity().name(), c.unit),
                    series: vec![
                        series(format!("measured ({})", c.measured_name), &c.measured),
                        series("simulated, before".into(), &c.before),
                        series("simulated, calibrated".into(), &c.after),
                    ],
                    ..LinePlot::default()
                },
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lm_fits_an_exponential_decay_and_respects_bounds() {
        // r_j = a e^{−b t_j} − y_j with y from a = 2, b = 3: exact fit from a poor start.
        let t: Vec<f64> = (0..50).map(|j| j as f64 * 0.02).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-3.0 * t).exp()).collect();
        let f = |x: &[f64]| -> Result<Vec<f64>> {
            Ok(t.iter()
                .zip(&y)
                .map(|(t, y)| x[0] * (-x[1] * t).exp() - y)
                .collect())
        };
        let s = Settings::default();
        let o = levenberg_marquardt(f, &[1.0, 1.0], &[0.0, 0.0], &[10.0, 10.0], &s).unwrap();
        assert!(
            (o.x[0] - 2.0).abs() < 1e-6 && (o.x[1] - 3.0).abs() < 1e-6,
            "{:?}",
            o.x
        );
        assert!(o.reason.converged(), "{:?}", o.reason);
        // With b ≤ 2.5 the optimum is on the bound b = 2.5.
        let o = levenberg_marquardt(f, &[1.0, 1.0], &[0.0, 0.0], &[10.0, 2.5], &s).unwrap();
        assert_eq!(o.x[1], 2.5);
        assert!(o.reason.converged(), "{:?}", o.reason);
    }

    #[test]
    fn identifiability_of_jacobian_columns() {
        let a = vec![1.0, 2.0, -1.0, 0.5];
        let b = vec![0.3, -1.0, 2.0, 4.0];
        let twice_a: Vec<f64> = a.iter().map(|x| 2.0 * x).collect();
        let a_plus_b: Vec<f64> = a.iter().zip(&b).map(|(x, y)| 1e8 * (x + y)).collect();
        use Identifiability::*;
        assert_eq!(
            identifiability(&[a.clone(), b.clone()]),
            vec![Identifiable, Identifiable]
        );
        assert_eq!(
            identifiability(&[a.clone(), vec![0.0; 4], twice_a]),
            vec![Identifiable, NoEffect, Dependent]
        );
        // Scale does not matter: a column 1e8 times larger, a combination of the others.
        assert_eq!(
            identifiability(&[a, b, a_plus_b]),
            vec![Identifiable, Identifiable, Dependent]
        );
        // Round-off below 1e-6 of a column is still dependence.
        let c = vec![1.0, 1.0 + 1e-9, 1.0, 1.0];
        assert_eq!(
            identifiability(&[vec![1.0; 4], c]),
            vec![Identifiable, Dependent]
        );
    }

    #[test]
    fn cholesky_inverse_of_a_known_matrix() {
        let a = vec![vec![4.0, 2.0], vec![2.0, 3.0]];
        let inv = spd_inverse(&a).unwrap();
        // det = 8: inverse = [[3, −2], [−2, 4]]/8.
        let want = [[0.375, -0.25], [-0.25, 0.5]];
        for i in 0..2 {
            for j in 0..2 {
                assert!((inv[i][j] - want[i][j]).abs() < 1e-15);
            }
        }
        assert!(spd_inverse(&[vec![1.0, 2.0], vec![2.0, 1.0]]).is_none());
    }

    #[test]
    fn student_t_quantiles() {
        assert_eq!(student_t_975(1), 12.706);
        assert!((student_t_975(60) - 2.000).abs() < 2e-3);
        assert!((student_t_975(1_000_000) - 1.959964).abs() < 1e-5);
    }

    #[test]
    fn bounds_and_fit_lists_parse_and_refuse() {
        let b = parse_bounds(&["a.b=1:2,c[0]=-1e3:5e3".into()]).unwrap();
        assert_eq!(b["a.b"], (1.0, 2.0));
        assert_eq!(b["c[0]"], (-1e3, 5e3));
        let e = parse_bounds(&["a=2:1".into()]).unwrap_err().to_string();
        assert!(e.contains("LO = 2 is not below HI = 1"), "{e}");
        assert!(parse_bounds(&["a=1".into()]).is_err());
        assert_eq!(
            parse_fit(&["a, b".into(), "c".into()]).unwrap(),
            ["a", "b", "c"]
        );
        assert!(parse_fit(&["a,,b".into()]).is_err());
        assert!(parse_fit(&["a,a".into()]).is_err());
    }
}
