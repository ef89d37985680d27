//! Test-lab processing of time histories: blows found by a trigger, records averaged over
//! blows, force and exponential windows, energy spectra, one-third-octave levels, the H1
//! frequency response and its coherence.
//!
//! Everything works on plain sampled channels (`&[f64]` at `f_s`), so the same
//! [`Processing`] applies to a measured [`super::Record`] and to a simulated history
//! ([`super::Record::from_history`]): same trigger, same record length, same windows — a
//! like-for-like comparison.
//!
//! # Blows
//!
//! A blow is triggered at the first sample `i` with `|x_i − x̃| ≥ L` on the trigger channel
//! (`x̃` the channel's median, its baseline: a DC offset or a transducer's preload neither hides
//! the blows nor triggers; `L` absolute, or a fraction of the channel's largest `|x − x̃|`), once
//! the detector is armed. After a trigger the detector ignores `hold-off` seconds, then re-arms
//! when `|x − x̃|` falls below `L`. Each blow's record starts `pre-trigger` seconds before its trigger and lasts the record
//! length (default: the shortest interval between triggers, or up to the end for a single
//! blow). A blow whose record would start before the first sample or end after the last is
//! counted but not averaged. When every blow triggers within the pre-trigger of the record's
//! start (a record that starts at the trigger, as many acquisition systems write it, or a
//! simulated history), `meid measure` keeps the pre-trigger the record has, the time before the
//! first trigger, and says so in a note ([`group_blows`]). When blows are found but none of their
//! records fits in the file even so, [`require_complete`] refuses with the range of pre-trigger
//! or record length that would fit (the same rule for `meid measure`, `validate` and
//! `calibrate`). A record must hold at least
//! [`MIN_RECORD_SAMPLES`] samples.
//!
//! # Scaling
//!
//! The spectra are computed from the record scaled by `2^−e`, `2^e` the power of two at or
//! below its largest `|x|` (an exact scaling: the result is bit for bit that of the unscaled
//! record whenever that neither overflows nor underflows). The energy spectral density is
//! restored in unit²·s/Hz when it is representable as a double; otherwise it is kept scaled
//! and [`BlowSpectrum::scale_db`] holds `10 log10` of the factor, so levels stay exact and
//! finite for any finite data (e.g. amplitudes of 1e300).
//!
//! # Baseline
//!
//! Before its window and FFT, each blow record loses its baseline: the median of its
//! pre-trigger samples when it has at least [`MIN_BASELINE_SAMPLES`] of them
//! ([`record_baseline`]; a simulated record, at rest before the blow, has 0). A DC offset (a
//! transducer's bias or preload, an amplifier's drift) would otherwise leak into the low bins
//! under a Hann or exponential window and could be the "dominant" line. The time averages and
//! the peaks are of the records less their baselines too, as a test lab reads them (a
//! simulated history starts at rest, baseline 0: measured and simulated compare like with
//! like):
//!
//! ```text
//! b_b = median(x_b[0 .. pre])            (pre ≥ 16 samples; else b_b = 0, nothing removed)
//! x̄_n = (1/B) Σ_b (x_b[n] − b_b)         the time average
//! peak = x_b[n] − b_b at the (b, n) of the largest |x_b[n] − b_b|, with its sign and time
//! ```
//!
//! The baselines removed are reported per channel ([`BaselineRemoved`]: their mean
//! `(1/B) Σ_b b_b`, which the time average lost, their range over the blows, and the number of
//! pre-trigger samples each is the median of). A peak read from samples is a **sample peak**:
//! the signal between samples may go higher; a sinusoid of frequency `f` sampled at `f_s` is
//! read at no less than `cos(π f/f_s)` of its amplitude.
//!
//! # Averaging
//!
//! * in time: `x̄_n = (1/B) Σ_b (x_b[n] − b_b)` over the B complete blow records (aligned on
//!   the trigger sample, each less its baseline `b_b`), for overlays;
//! * in frequency: the energy spectral density is the mean of the blows' ESDs,
//!   `Ē_k = (1/B) Σ_b E_{b,k}` with `E_{b,k} = 2|Δt Σ_n w_n x_b[n] e^{−2πikn/N}|²`
//!   ([`crate::analysis::spectrum::esd_fft`]'s scaling; unit²·s/Hz). Levels are
//!   `10 log10(Ē/E_ref)` dB re 1 (m/s²)²·s/Hz, 1 N²·s/Hz, 1 (m/s)²·s/Hz or 1 m²·s/Hz.
//! * the H1 estimate of the frequency response from force `f` to response `x`:
//!   `H1_k = Σ_b conj(F_{b,k}) X_{b,k} / Σ_b |F_{b,k}|²` and the coherence
//!   `γ²_k = |Σ_b conj(F) X|² / (Σ_b |F|² · Σ_b |X|²)` (1 for noise-free linear data; with one
//!   blow it is 1 by construction). Bendat & Piersol, *Random Data*, 4th ed., Eqs. (9.52), (9.60).
//!
//! # Windows and the added damping of the exponential window
//!
//! The windows are [`TransientWindow`]'s: the force window (1 over the pulse, a half-cosine
//! taper, 0 after) on the blow's force, the excitation ([`Role`]; never on a response such as
//! the force to the floor), and an exponential `w(t) = e^{−t/τ}` on the responses (and,
//! multiplied in, on the force, so that H1 stays the ratio of equally windowed signals). The
//! exponential window multiplies a mode's free decay `e^{−ζωt}` by `e^{−t/τ}`: the windowed
//! record is that of a mode with decay rate `ζω + 1/τ`, i.e. a damping ratio
//!
//! ```text
//! ζ_w = (ζω + 1/τ) / ω_w,   ω_w² = ω_d² + (ζω + 1/τ)²,   ω_d = ω √(1 − ζ²)
//! ζ_w ≈ ζ + 1/(ωτ)                  (ζ, 1/(ωτ) ≪ 1)
//! ```
//!
//! A damping ratio read from an exponentially windowed spectrum must be corrected by
//! `ζ = ζ_w − 1/(ωτ)` ([`crate::analysis::spectrum::exponential_window_correction`]); the
//! H1 of the windowed records *is* the FRF of that more damped mode
//! ([`windowed_sdof_damping`]), which the tests check.

use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use serde::Serialize;

use crate::analysis::esd::esd_level_db;
use crate::analysis::octave::{bands_covering, Band};
use crate::analysis::spectrum::{bin_band_energy, one_sided_factor, TransientWindow};
use crate::{Error, Result};

use super::{Quantity, Record};

/// The trigger level.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Level {
    /// In the channel's SI unit, a deviation from its median (its baseline).
    Absolute(f64),
    /// A fraction of the channel's largest deviation from its median `|x − x̃|`, in (0, 1].
    FractionOfPeak(f64),
}

/// Settings shared by measured and simulated records.
#[derive(Debug, Clone, PartialEq)]
pub struct Processing {
    /// Trigger level (default 10 % of the trigger channel's peak).
    pub level: Level,
    /// Time kept before each trigger (s, default 0.01).
    pub pretrigger_s: f64,
    /// Length of each blow's record (s); `None`: the shortest interval between triggers (a
    /// single blow: to the end of the file).
    pub record_s: Option<f64>,
    /// Time after a trigger during which no other is taken (s, default 0.25).
    pub holdoff_s: f64,
    /// Window on responses (default rectangular).
    pub window: TransientWindow,
    /// Apply the force window to the blow's excitation ([`Role::Excitation`]; the pulse is
    /// found on the force itself: [`force_window_for`]).
    pub force_window: bool,
}

impl Default for Processing {
    fn default() -> Self {
        Processing {
            level: Level::FractionOfPeak(0.1),
            pretrigger_s: 0.01,
            record_s: None,
            holdoff_s: 0.25,
            window: TransientWindow::Rectangular,
            force_window: false,
        }
    }
}

impl Processing {
    fn check(&self) -> Result<()> {
        match self.level {
            Level::Absolute(l) if !(l.is_finite() && l > 0.0) => {
                return Err(Error::invalid(
                    "trigger level",
                    format!("must be > 0 (got {l})"),
                ))
            }
            Level::FractionOfPeak(f) if !(f > 0.0 && f <= 1.0) => {
                return Err(Error::invalid(
                    "trigger level",
                    format!("a fraction of the peak must lie in (0, 1] (got {f})"),
                ))
            }
            _ => {}
        }
        if !(self.pretrigger_s.is_finite() && self.pretrigger_s >= 0.0) {
            return Err(Error::invalid(
                "pre-trigger",
                format!("must be ≥ 0 s (got {})", self.pretrigger_s),
            ));
        }
        if !(self.holdoff_s.is_finite() && self.holdoff_s >= 0.0) {
            return Err(Error::invalid(
                "hold-off",
                format!("must be ≥ 0 s (got {})", self.holdoff_s),
            ));
        }
        if let Some(r) = self.record_s {
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::invalid(
                    "record length",
                    format!("must be > 0 s (got {r})"),
                ));
            }
        }
        Ok(())
    }
}

/// The fewest samples a blow record may hold: 16, i.e. 8 spectral lines above DC at the
/// spacing `1/T` (a shorter record resolves nothing worth reporting: a 2-sample record's one
/// line is the Nyquist frequency).
pub const MIN_RECORD_SAMPLES: usize = 16;

/// The blows found in a record.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Blows {
    /// Trigger samples.
    pub triggers: Vec<usize>,
    /// First sample of each complete blow record (trigger − pre-trigger).
    pub starts: Vec<usize>,
    /// Samples per blow record.
    pub length: usize,
    /// Samples before the trigger.
    pub pretrigger: usize,
    /// The absolute level used (SI), a deviation from the channel's median.
    pub level: f64,
    /// Set when the pre-trigger asked for was shortened to the time the record has before its
    /// first blow ([`group_blows`]): what was done, for the user.
    pub note: Option<String>,
}

/// Finds blows on `x` sampled at `fs` (module docs).
pub fn detect_blows(x: &[f64], fs: f64, p: &Processing) -> Result<Blows> {
    p.check()?;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(Error::invalid(
            "sample rate",
            format!("must be > 0 Hz (got {fs})"),
        ));
    }
    // Deviations from the channel's baseline (its median): a DC offset, a transducer's
    // bias or preload, neither hides the blows nor triggers on its own.
    let baseline = median(x);
    let dev = |v: f64| (v - baseline).abs();
    let peak = x.iter().fold(0.0_f64, |m, v| m.max(dev(*v)));
    let level = match p.level {
        Level::Absolute(l) => l,
        Level::FractionOfPeak(f) => f * peak,
    };
    let n = x.len();
    let pre = (p.pretrigger_s * fs).round() as usize;
    let hold = (p.holdoff_s * fs).round() as usize;
    let mut triggers = Vec::new();
    if level > 0.0 && n > 0 {
        let mut armed = dev(x[0]) < level;
        let mut i = 0;
        while i < n {
            let a = dev(x[i]);
            if armed && a >= level {
                triggers.push(i);
                armed = false;
                i = i.saturating_add(hold.max(1));
                continue;
            }
            if !armed && a < level {
                armed = true;
            }
            i += 1;
        }
    }
    let min_s = MIN_RECORD_SAMPLES as f64 / fs;
    let length = match p.record_s {
        Some(r) => {
            let l = (r * fs).round();
            if l < MIN_RECORD_SAMPLES as f64 {
                return Err(Error::invalid(
                    "record length",
                    format!(
                        "{r} s is {l} samples at {fs} Hz: a blow record needs at least {MIN_RECORD_SAMPLES} samples ({min_s:.6} s), 8 spectral lines above DC; give a longer record (--record or [measurement] record_s)"
                    ),
                ));
            }
            // Saturates for absurd lengths; the fit check below refuses them.
            l as usize
        }
        None => {
            let gaps = triggers.windows(2).map(|w| w[1] - w[0]).min();
            match (gaps, triggers.first()) {
                (Some(g), _) => {
                    if g < MIN_RECORD_SAMPLES {
                        return Err(Error::invalid(
                            "record length",
                            format!(
                                "the shortest interval between triggers is {g} samples ({:.6} s), and the record length defaults to it: a blow record needs at least {MIN_RECORD_SAMPLES} samples ({min_s:.6} s); give a longer hold-off (--holdoff) or a record length (--record)",
                                g as f64 / fs
                            ),
                        ));
                    }
                    g
                }
                (None, Some(&t)) => n - t.saturating_sub(pre),
                (None, None) => n,
            }
        }
    };
    if length < MIN_RECORD_SAMPLES && p.record_s.is_none() {
        return Err(Error::invalid(
            "record length",
            format!(
                "the record runs to the end of the file and holds {length} samples ({:.6} s): a blow record needs at least {MIN_RECORD_SAMPLES} samples ({min_s:.6} s); the file is too short",
                length as f64 / fs
            ),
        ));
    }
    let starts = triggers
        .iter()
        .filter(|&&t| t >= pre && (t - pre).checked_add(length).is_some_and(|e| e <= n))
        .map(|&t| t - pre)
        .collect();
    Ok(Blows {
        triggers,
        starts,
        length,
        pretrigger: pre,
        level,
        note: None,
    })
}

/// The fewest pre-trigger samples a blow record's baseline is taken from ([`record_baseline`]).
pub const MIN_BASELINE_SAMPLES: usize = 16;

/// The baseline of a blow record `seg` whose first `pre` samples precede the trigger: the
/// median of those samples when there are at least [`MIN_BASELINE_SAMPLES`] (robust to the
/// few samples of a blow's rise before the trigger level), else 0 (module docs, Baseline).
pub fn record_baseline(seg: &[f64], pre: usize) -> f64 {
    if pre >= MIN_BASELINE_SAMPLES && pre <= seg.len() {
        median(&seg[..pre])
    } else {
        0.0
    }
}

/// The shortest run of equal samples at a record's extreme that counts as clipping.
pub const CLIP_RUN: usize = 3;

/// The samples of `x` in runs of at least [`CLIP_RUN`] consecutive samples equal to its
/// largest value, or to its smallest, of the extremes at least half the largest deviation from
/// the median `x̃` away from it (`|ext − x̃| ≥ ½ max|x − x̃|`: the rest level of a one-sided
/// record, a hammer's 0 between blows, is not a cut): a sampled transient does not stay at its
/// extreme for three samples unless the signal was cut there (a transducer, amplifier or
/// converter at its full scale). A constant record has no extreme to clip at (0). It can only
/// flag: a slow signal quantised coarsely may also repeat its extreme; the count is for a
/// warning.
pub fn clipped_samples(x: &[f64]) -> usize {
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if lo >= hi || lo.is_nan() || hi.is_nan() {
        return 0;
    }
    // Only an extreme far from the baseline is a cut: the rest level of a one-sided record (a
    // hammer's 0 between blows) is its smallest value and repeats by nature.
    let m = median(x);
    let reach = (hi - m).max(m - lo);
    let mut count = 0;
    for target in [lo, hi] {
        if (target - m).abs() < 0.5 * reach {
            continue;
        }
        let mut run = 0usize;
        for &v in x.iter().chain(std::iter::once(&f64::NAN)) {
            if v == target {
                run += 1;
            } else {
                if run >= CLIP_RUN {
                    count += run;
                }
                run = 0;
            }
        }
    }
    count
}

/// The median of `x` (0 for an empty record; the mean of the two middle values for an even
/// count).
pub fn median(x: &[f64]) -> f64 {
    let n = x.len();
    if n == 0 {
        return 0.0;
    }
    let mut v = x.to_vec();
    let (_, &mut hi, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        hi
    } else {
        let lo = v[..n / 2].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lo + hi)
    }
}

/// Refuses blows of which none has a complete record in a channel of `n` samples at `fs`,
/// naming the settings that would make one fit (`channel`, `origin`: the trigger channel's
/// name and where it came from). A blow `b` (trigger sample `t_b`) fits when
/// `pre ≤ t_b` and `t_b − pre + L ≤ n` (pre-trigger `pre`, record `L` samples). When no
/// blow has `t_b ≥ pre`, the pre-trigger must come down to at most the last trigger's time;
/// otherwise the record must shorten to at most `max_b (n − t_b + pre)` samples. No trigger
/// at all is not this function's concern (`Ok`).
pub fn require_complete(b: &Blows, n: usize, fs: f64, channel: &str, origin: &str) -> Result<()> {
    if !b.starts.is_empty() || b.triggers.is_empty() {
        return Ok(());
    }
    let pre = b.pretrigger;
    let secs = |k: usize| k as f64 / fs;
    let first = b.triggers[0];
    let last = *b.triggers.last().unwrap_or(&first);
    let message = match b.triggers.iter().filter(|&&t| t >= pre).map(|&t| n - (t - pre)).max()
    {
        None => {
            let latest = if b.triggers.len() > 1 {
                format!(" (the last of {} at {:.6} s)", b.triggers.len(), secs(last))
            } else {
                String::new()
            };
            format!(
                "the first blow on '{channel}' triggers at {:.6} s{latest}, less than the pre-trigger ({:.6} s) after the record's start, so no blow record fits: give a shorter pre-trigger, between 0 and {:.6} s (--pretrigger or [measurement] pretrigger_s; 0 for a simulated history, which starts with the blow)",
                secs(first),
                secs(pre),
                secs(last)
            )
        }
        Some(longest) if longest < MIN_RECORD_SAMPLES => format!(
            "the blows on '{channel}' ({} found) trigger so close to the end of the file ({} samples, {:.6} s) that the longest record from {:.6} s before a trigger holds {longest} samples, fewer than the {MIN_RECORD_SAMPLES} a record needs: give a longer pre-trigger (--pretrigger or [measurement] pretrigger_s)",
            b.triggers.len(),
            n,
            secs(n),
            secs(pre)
        ),
        Some(longest) => format!(
            "a record of {:.6} s ({} samples) from {:.6} s before each trigger runs past the end of the file ({} samples, {:.6} s) after every blow on '{channel}' ({} found): give a record length between {:.6} s ({MIN_RECORD_SAMPLES} samples) and {:.6} s (--record or [measurement] record_s)",
            secs(b.length),
            b.length,
            secs(pre),
            n,
            secs(n),
            b.triggers.len(),
            secs(MIN_RECORD_SAMPLES),
            secs(longest)
        ),
    };
    Err(Error::Input {
        location: origin.to_string(),
        message,
    })
}

/// The baselines removed from one channel's blow records (module docs, Baseline), in the
/// channel's SI unit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BaselineRemoved {
    /// `(1/B) Σ_b b_b`: the mean of the records' baselines, what the time average lost.
    pub mean: f64,
    /// The smallest and largest `b_b` over the records (their spread: drift between blows).
    pub min: f64,
    pub max: f64,
    /// Pre-trigger samples each `b_b` is the median of; 0 when the pre-trigger holds fewer than
    /// [`MIN_BASELINE_SAMPLES`] (nothing removed: the records are as measured).
    pub samples: usize,
}

impl BaselineRemoved {
    /// One line for reports, e.g. `+3.0000e0 m/s^2 (median of 100 pre-trigger samples)`, or
    /// why none was removed.
    pub fn describe(&self, unit: &str) -> String {
        if self.samples == 0 {
            format!("none removed (pre-trigger under {MIN_BASELINE_SAMPLES} samples: peaks and averages include any DC offset)")
        } else if self.min == self.max {
            format!(
                "{:+.4e} {unit} (median of {} pre-trigger samples)",
                self.mean, self.samples
            )
        } else {
            format!(
                "{:+.4e} {unit} on average, {:+.4e} … {:+.4e} over the blows (medians of {} pre-trigger samples)",
                self.mean, self.min, self.max, self.samples
            )
        }
    }
}

/// The baseline `b_b` of each blow record `x[s_b .. s_b + L]` ([`record_baseline`]).
pub fn blow_baselines(x: &[f64], blows: &Blows) -> Result<Vec<f64>> {
    check_starts(x.len(), &blows.starts, blows.length)?;
    Ok(blows
        .starts
        .iter()
        .map(|&s| record_baseline(&x[s..s + blows.length], blows.pretrigger))
        .collect())
}

/// The blow records of one channel with their baselines `b_b` ([`record_baseline`], found
/// once): the time average, the sample peak and what was removed all use the same `b_b`.
#[derive(Debug, Clone)]
pub struct BlowRecords<'a> {
    x: &'a [f64],
    blows: &'a Blows,
    baselines: Vec<f64>,
}

impl<'a> BlowRecords<'a> {
    /// The records of `x` at `blows` (every record checked to lie in `x`).
    pub fn new(x: &'a [f64], blows: &'a Blows) -> Result<Self> {
        Ok(Self {
            x,
            blows,
            baselines: blow_baselines(x, blows)?,
        })
    }

    /// Record `b` with its baseline.
    fn records(&self) -> impl Iterator<Item = (usize, &'a [f64], f64)> + '_ {
        let len = self.blows.length;
        self.blows
            .starts
            .iter()
            .zip(&self.baselines)
            .map(move |(&s, &b)| (s, &self.x[s..s + len], b))
    }

    /// What the baselines remove from the channel, summed up.
    pub fn removed(&self) -> BaselineRemoved {
        let (blows, b) = (self.blows, &self.baselines);
        let samples =
            if blows.pretrigger >= MIN_BASELINE_SAMPLES && blows.pretrigger <= blows.length {
                blows.pretrigger
            } else {
                0
            };
        let (min, max) = b
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, c), &v| {
                (a.min(v), c.max(v))
            });
        let (min, max) = if b.is_empty() { (0.0, 0.0) } else { (min, max) };
        BaselineRemoved {
            mean: if b.is_empty() {
                0.0
            } else {
                b.iter().sum::<f64>() / b.len() as f64
            },
            min,
            max,
            samples,
        }
    }

    /// `x̄_n = (1/B) Σ_b (x[s_b + n] − b_b)`: the time average of the blow records, each less
    /// its baseline (module docs, Baseline).
    pub fn average(&self) -> Result<Vec<f64>> {
        if self.blows.starts.is_empty() {
            return Err(Error::invalid(
                "blows",
                "no complete blow record to average",
            ));
        }
        let mut acc = vec![0.0; self.blows.length];
        for (_, rec, b) in self.records() {
            for (a, v) in acc.iter_mut().zip(rec) {
                *a += v - b;
            }
        }
        let n = self.blows.starts.len() as f64;
        acc.iter_mut().for_each(|a| *a /= n);
        Ok(acc)
    }

    /// The sample peak of the records less their baselines: `x[i] − b_b` at the sample `i` of
    /// the largest `|x[s_b + n] − b_b|` over the records (the first such sample), with its
    /// sign (module docs, Baseline). Returns `(value, i)`.
    pub fn peak(&self) -> (f64, usize) {
        let mut best = (0.0_f64, self.blows.starts.first().copied().unwrap_or(0));
        for (s, rec, b) in self.records() {
            for (i, v) in rec.iter().enumerate() {
                let d = v - b;
                if d.abs() > best.0.abs() {
                    best = (d, s + i);
                }
            }
        }
        best
    }
}

/// The time average of the blow records, each less its baseline ([`BlowRecords::average`]).
pub fn average_blows(x: &[f64], blows: &Blows) -> Result<Vec<f64>> {
    BlowRecords::new(x, blows)?.average()
}

/// Every blow record `[s, s + len)` lies in a channel of `n` samples (checked before anything
/// of size `len` is allocated).
fn check_starts(n: usize, starts: &[usize], len: usize) -> Result<()> {
    if len < 2 {
        return Err(Error::invalid(
            "blows",
            format!("a blow record needs at least 2 samples, got {len}"),
        ));
    }
    for &s in starts {
        if s.checked_add(len).is_none_or(|e| e > n) {
            return Err(Error::invalid(
                "blows",
                format!(
                    "the record from sample {s} ({len} samples) runs past the end ({n} samples)"
                ),
            ));
        }
    }
    Ok(())
}

/// Windowed FFTs of blow records with one plan.
struct Transformer {
    fft: std::sync::Arc<dyn realfft::RealToComplex<f64>>,
    input: Vec<f64>,
    output: Vec<Complex<f64>>,
}

impl Transformer {
    fn new(n_fft: usize) -> Self {
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(n_fft);
        let input = fft.make_input_vec();
        let output = fft.make_output_vec();
        Transformer { fft, input, output }
    }
    /// `X_k = Σ_n w_n x_n e^{−2πikn/N_fft}` into `self.output`.
    fn run(&mut self, x: &[f64], w: &[f64]) -> Result<&[Complex<f64>]> {
        self.input.iter_mut().for_each(|v| *v = 0.0);
        for ((d, a), b) in self.input.iter_mut().zip(x).zip(w) {
            *d = a * b;
        }
        self.fft
            .process(&mut self.input, &mut self.output)
            .map_err(|e| Error::numerical("FFT", e.to_string()))?;
        Ok(&self.output)
    }
}

fn freqs(bins: usize, n_fft: usize, fs: f64) -> Vec<f64> {
    (0..bins).map(|k| k as f64 * fs / n_fft as f64).collect()
}

/// What a channel is to the blow: its excitation (the blow force: a hammer's, the slider's)
/// or a response (every other channel, the force to the floor included: a transmitted force
/// rings with the structure and is windowed like an acceleration). The force window applies to
/// the excitation only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Role {
    Excitation,
    Response,
}

impl super::SimChannel {
    /// The blow force is the excitation; the bed acceleration and the floor force respond.
    pub fn role(self) -> Role {
        match self {
            super::SimChannel::BlowForce => Role::Excitation,
            _ => Role::Response,
        }
    }
}

/// The force window of an excitation record, found on the record itself (so that the level
/// is in its own unit, whatever channel the blows were triggered on): in the first blow record
/// `x[s .. s + len]`, the pulse is the run of samples around the largest `|x|` with
/// `|x| ≥ L_F`, `L_F = f · max|x|` (`f` the trigger fraction, 0.1 for an absolute trigger
/// level, which is in the trigger channel's unit). The window is 1 from the record start to
/// the pulse's end `T_p`, then a half-cosine taper over half the pulse's duration `T_c`
/// (at least one sample), then 0.
pub fn force_window_for(x: &[f64], blows: &Blows, fs: f64, p: &Processing) -> TransientWindow {
    let s = blows.starts.first().copied().unwrap_or(0).min(x.len());
    let raw = &x[s..(s + blows.length).min(x.len())];
    let base = record_baseline(raw, blows.pretrigger);
    let rec: Vec<f64> = raw.iter().map(|v| v - base).collect();
    let (k_max, top) =
        rec.iter().enumerate().fold(
            (0, 0.0_f64),
            |b, (i, v)| {
                if v.abs() > b.1 {
                    (i, v.abs())
                } else {
                    b
                }
            },
        );
    let f = match p.level {
        Level::FractionOfPeak(f) => f,
        Level::Absolute(_) => 0.1,
    };
    let l = f * top;
    let end = (k_max..rec.len())
        .find(|&i| rec[i].abs() < l)
        .unwrap_or(rec.len());
    let begin = (0..=k_max)
        .rev()
        .find(|&i| rec[i].abs() < l)
        .map_or(0, |i| i + 1);
    let dt = 1.0 / fs;
    let pulse = end.max(1) as f64 * dt;
    let taper = (0.5 * (end - begin) as f64 * dt).max(dt);
    TransientWindow::Force {
        pulse_s: pulse,
        taper_s: taper,
    }
}

/// The windows of one channel: the response window, times the force window for the
/// excitation when asked ([`Processing::force_window`]).
fn window_for(role: Role, x: &[f64], blows: &Blows, fs: f64, p: &Processing) -> Result<Vec<f64>> {
    let mut w = p.window.coefficients(blows.length, fs)?;
    if p.force_window && role == Role::Excitation {
        let f = force_window_for(x, blows, fs, p).coefficients(blows.length, fs)?;
        w.iter_mut().zip(f).for_each(|(a, b)| *a *= b);
    }
    Ok(w)
}

/// The mean energy spectral density of the blow records (module docs), unit²·s/Hz.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BlowSpectrum {
    pub frequency_hz: Vec<f64>,
    /// The mean ESD, in unit²·s/Hz when [`Self::scale_db`] is 0; otherwise divided by
    /// `10^(scale_db/10)` (module docs, Scaling).
    pub density: Vec<f64>,
    /// Number of blow records averaged (0: the whole record, no blow found).
    pub averages: usize,
    /// `10 log10` of the factor from [`Self::density`] to unit²·s/Hz: 0 unless the ESD in
    /// unit²·s/Hz is beyond the range of doubles.
    pub scale_db: f64,
    /// The sample rate (Hz): the bins stand for `[0, f_s/2]`.
    pub sample_rate_hz: f64,
}

impl BlowSpectrum {
    /// The level of a [`Self::density`] value (or a band energy from [`Self::third_octaves`])
    /// `e`: `10 log10(e/E_ref) + scale_db` dB re `E_ref`; −∞ for `e = 0`.
    pub fn level_db(&self, e: f64, reference: f64) -> f64 {
        esd_level_db(e, reference) + self.scale_db
    }
    /// The densities in unit²·s/Hz, when they are representable as doubles.
    pub fn density_si(&self) -> Option<&[f64]> {
        (self.scale_db == 0.0).then_some(&self.density[..])
    }
    /// Bin spacing (Hz).
    pub fn bin_width_hz(&self) -> f64 {
        self.frequency_hz.get(1).copied().unwrap_or(0.0)
    }
    /// `∫_{f_lo}^{f_hi} Ē df` (unit²·s; scaled as [`Self::density`]), each bin's energy
    /// `Ē_k Δf` spread over the frequencies it stands for
    /// ([`crate::analysis::spectrum::bin_band_energy`]): a bin across a band edge counts in
    /// proportion, so a band level does not depend on where the bins fall (the record length,
    /// the padding), and bands that tile the spectrum add up to `Σ Ē_k Δf`.
    pub fn band_energy(&self, f_lo: f64, f_hi: f64) -> f64 {
        bin_band_energy(
            &self.frequency_hz,
            &self.density,
            self.sample_rate_hz,
            f_lo,
            f_hi,
        )
    }
    /// The largest bin above DC: (frequency, density).
    pub fn dominant(&self) -> Option<(f64, f64)> {
        self.frequency_hz.iter().zip(&self.density).skip(1).fold(
            None,
            |b: Option<(f64, f64)>, (&f, &e)| match b {
                Some(x) if x.1 >= e => Some(x),
                _ => Some((f, e)),
            },
        )
    }
    /// The largest bin in `[f_lo, f_hi]`.
    pub fn peak_in_band(&self, f_lo: f64, f_hi: f64) -> Option<(f64, f64)> {
        self.frequency_hz
            .iter()
            .zip(&self.density)
            .filter(|(f, _)| **f >= f_lo && **f <= f_hi)
            .fold(None, |b: Option<(f64, f64)>, (&f, &e)| match b {
                Some(x) if x.1 >= e => Some(x),
                _ => Some((f, e)),
            })
    }
    /// One-third-octave bands (IEC 61260-1) from the first bin above DC to the Nyquist
    /// frequency, each with its energy (unit²·s); bands not wholly inside are left out.
    pub fn third_octaves(&self) -> Vec<(Band, f64)> {
        let df = self.bin_width_hz();
        let top = self.frequency_hz.last().copied().unwrap_or(0.0);
        if df.is_nan() || df <= 0.0 {
            return Vec::new();
        }
        bands_covering(df, top)
            .into_iter()
            .filter(|b| b.lower_hz >= df && b.upper_hz <= top)
            .map(|b| (b, self.band_energy(b.lower_hz, b.upper_hz)))
            .collect()
    }
}

/// Mean ESD over the blow records `starts` of `x` (length `blows.length`, windowed as `p`
/// says for a channel of that `role`), zero-padded to `n_fft ≥ length` (None: no padding).
pub fn blow_spectrum(
    x: &[f64],
    role: Role,
    fs: f64,
    blows: &Blows,
    p: &Processing,
    n_fft: Option<usize>,
) -> Result<BlowSpectrum> {
    if blows.starts.is_empty() {
        return Err(Error::invalid("blows", "no complete blow record: lower the trigger level, the pre-trigger or the record length"));
    }
    let len = blows.length;
    check_starts(x.len(), &blows.starts, len)?;
    let n_fft = n_fft.unwrap_or(len).max(len);
    let w = window_for(role, x, blows, fs, p)?;
    let mut tr = Transformer::new(n_fft);
    let dt = 1.0 / fs;
    // The scale 2^e at or below the largest |x| of the records (module docs, Scaling).
    let mut top = 0.0_f64;
    for &s in &blows.starts {
        for v in &x[s..s + len] {
            if !v.is_finite() {
                return Err(Error::invalid(
                    "blows",
                    format!("sample value {v} is not finite: no spectrum"),
                ));
            }
            top = top.max(v.abs());
        }
    }
    // Clamped so that 2^e and 2^−e are both normal doubles.
    let e = if top > 0.0 {
        binary_exponent(top).clamp(-1022, 1022)
    } else {
        0
    };
    let down = pow2(-e);
    let mut scaled = vec![0.0; len];
    let mut acc = vec![0.0; n_fft / 2 + 1];
    for &s in &blows.starts {
        // (In range: `check_starts` above.)
        let seg = &x[s..s + len];
        // The record less its baseline (module docs, Baseline), scaled: (v − b)·2^−e exactly.
        let b = record_baseline(seg, blows.pretrigger) * down;
        scaled
            .iter_mut()
            .zip(seg)
            .for_each(|(d, v)| *d = v * down - b);
        let bins = tr.run(&scaled, &w)?;
        for (k, (a, c)) in acc.iter_mut().zip(bins).enumerate() {
            *a += one_sided_factor(k, n_fft) * c.norm_sqr() * dt * dt;
        }
    }
    let b = blows.starts.len();
    acc.iter_mut().for_each(|a| *a /= b as f64);
    // Back to unit²·s/Hz (× 2^e × 2^e, exact) when every bin stays a finite normal double.
    let up = pow2(e);
    let representable = acc.iter().all(|a| {
        let r = a * up * up;
        r.is_finite() && (*a == 0.0 || r.is_normal())
    });
    let scale_db = if representable {
        acc.iter_mut().for_each(|a| *a = *a * up * up);
        0.0
    } else {
        20.0 * e as f64 * std::f64::consts::LOG10_2
    };
    let density = acc;
    Ok(BlowSpectrum {
        frequency_hz: freqs(density.len(), n_fft, fs),
        density,
        averages: b,
        scale_db,
        sample_rate_hz: fs,
    })
}

/// `e` with `2^e ≤ |v| < 2^(e+1)` for a finite `v ≠ 0` (subnormals: −1023 or below).
fn binary_exponent(v: f64) -> i32 {
    let bits = ((v.abs().to_bits() >> 52) & 0x7ff) as i32;
    if bits == 0 {
        // Subnormal: 2^−1074 · mantissa.
        let m = v.abs().to_bits() & ((1u64 << 52) - 1);
        -1074 + 63 - m.leading_zeros() as i32
    } else {
        bits - 1023
    }
}

/// `2^k` for `k` in −1022..=1023 (exact), clamped to that range.
fn pow2(k: i32) -> f64 {
    f64::from_bits(((k.clamp(-1022, 1023) + 1023) as u64) << 52)
}

/// The H1 frequency response estimate and its coherence.
#[derive(Debug, Clone, PartialEq)]
pub struct Frf {
    pub frequency_hz: Vec<f64>,
    /// `H1_k` (response unit per force unit).
    pub h1: Vec<Complex<f64>>,
    /// `γ²_k` in [0, 1].
    pub coherence: Vec<f64>,
    pub averages: usize,
}

/// The blow-summed auto and cross spectra of a force `f` and a response `x` sampled together:
/// `G_ff = Σ_b |F_b|²`, `G_xx = Σ_b |X_b|²`, `G_fx = Σ_b conj(F_b) X_b` per line (the one-sided
/// lines `0 … N/2` of the record, `N` its samples), each record less its baseline, the force
/// with the force window (when `p.force_window`) times the response window, the response with
/// the response window (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct CrossSpectra {
    pub frequency_hz: Vec<f64>,
    pub gff: Vec<f64>,
    pub gxx: Vec<f64>,
    pub gfx: Vec<Complex<f64>>,
    pub averages: usize,
}

/// [`CrossSpectra`] of `force` and `response` over the complete blow records of `blows`.
pub fn cross_spectra(
    force: &[f64],
    response: &[f64],
    fs: f64,
    blows: &Blows,
    p: &Processing,
) -> Result<CrossSpectra> {
    if force.len() != response.len() {
        return Err(Error::invalid(
            "H1",
            format!(
                "force and response differ in length ({} and {} samples)",
                force.len(),
                response.len()
            ),
        ));
    }
    if blows.starts.is_empty() {
        return Err(Error::invalid("blows", "no complete blow record for H1"));
    }
    let len = blows.length;
    check_starts(force.len(), &blows.starts, len)?;
    let wf = window_for(Role::Excitation, force, blows, fs, p)?;
    let wx = p.window.coefficients(len, fs)?;
    let mut tf = Transformer::new(len);
    let mut tx = Transformer::new(len);
    let bins = len / 2 + 1;
    let (mut gfx, mut gff, mut gxx) = (
        vec![Complex::new(0.0, 0.0); bins],
        vec![0.0; bins],
        vec![0.0; bins],
    );
    let less_baseline = |seg: &[f64]| -> Vec<f64> {
        let b = record_baseline(seg, blows.pretrigger);
        seg.iter().map(|v| v - b).collect()
    };
    for &s in &blows.starts {
        let f = tf.run(&less_baseline(&force[s..s + len]), &wf)?;
        let x = tx.run(&less_baseline(&response[s..s + len]), &wx)?;
        for k in 0..bins {
            gfx[k] += f[k].conj() * x[k];
            gff[k] += f[k].norm_sqr();
            gxx[k] += x[k].norm_sqr();
        }
    }
    Ok(CrossSpectra {
        frequency_hz: freqs(bins, len, fs),
        gff,
        gxx,
        gfx,
        averages: blows.starts.len(),
    })
}

/// H1 and coherence from a force and a response sampled together (module docs). The force
/// gets the force window (when `p.force_window`) times the response window, the response the
/// response window.
pub fn h1(force: &[f64], response: &[f64], fs: f64, blows: &Blows, p: &Processing) -> Result<Frf> {
    let g = cross_spectra(force, response, fs, blows, p)?;
    let h1 = g
        .gfx
        .iter()
        .zip(&g.gff)
        .map(|(c, f)| {
            if *f > 0.0 {
                c / f
            } else {
                Complex::new(f64::NAN, f64::NAN)
            }
        })
        .collect();
    let coherence = (0..g.gff.len())
        .map(|k| {
            let d = g.gff[k] * g.gxx[k];
            if d > 0.0 {
                (g.gfx[k].norm_sqr() / d).min(1.0)
            } else {
                f64::NAN
            }
        })
        .collect();
    Ok(Frf {
        frequency_hz: g.frequency_hz,
        h1,
        coherence,
        averages: g.averages,
    })
}

/// The damping ratio and natural frequency of the mode an exponential window `e^{−t/τ}` makes
/// of a mode `(ω, ζ)`: `σ_w = ζω + 1/τ`, `ω_w = √(ω_d² + σ_w²)`, `ζ_w = σ_w/ω_w` (module docs).
pub fn windowed_sdof_damping(omega_rad_per_s: f64, zeta: f64, tau_s: f64) -> (f64, f64) {
    let wd2 = omega_rad_per_s * omega_rad_per_s * (1.0 - zeta * zeta);
    let sigma = zeta * omega_rad_per_s + 1.0 / tau_s;
    let ww = (wd2 + sigma * sigma).sqrt();
    (ww, sigma / ww)
}

/// The dB reference of a quantity's ESD levels (SI unit squared · s/Hz) and its text.
pub fn esd_reference(q: Quantity) -> (f64, String) {
    (1.0, format!("1 ({})²·s/Hz", q.si_unit()))
}

/// What `meid measure` reports for one channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelSummary {
    pub name: String,
    /// SI unit of the values (after conversion).
    pub unit: String,
    pub samples: usize,
    pub sample_rate_hz: f64,
    /// The sample peak of the averaged blow records less their baselines, with its sign:
    /// `x_i − b_b` at the sample of the largest `|x_i − b_b|` ([`BlowRecords::peak`]; the signal between
    /// samples may go higher). With no blow found, of the whole record as measured.
    pub peak: f64,
    /// The time of that sample in the file (s).
    pub peak_time_s: f64,
    /// The baselines removed from the blow records before peaks, averages and spectra.
    pub baseline: BaselineRemoved,
    /// Blows detected on the trigger channel of the file.
    pub blows: usize,
    /// Blows whose records were averaged (0: no blow was found, the spectrum is the whole
    /// record's).
    pub blows_averaged: usize,
    /// Length of each record (s) and the time it starts before its trigger (s).
    pub record_s: f64,
    pub pretrigger_s: f64,
    /// Frequency of the largest bin of the blow-averaged ESD above DC (Hz); `None` when the
    /// ESD is zero above DC.
    pub dominant_frequency_hz: Option<f64>,
    /// Its level, dB re 1 (SI unit)²·s/Hz (finite for any finite data: module docs, Scaling).
    pub dominant_level_db: Option<f64>,
    /// Samples in runs of [`CLIP_RUN`] or more consecutive samples at the record's largest or
    /// smallest value ([`clipped_samples`]): a flat top where a transient peaks is the mark of
    /// an overloaded transducer or amplifier (0: none).
    pub clipped_samples: usize,
    /// The window the spectrum was computed with, e.g. "rectangular", or "rectangular × force
    /// (pulse 0.0112 s, taper 0.0005 s)" on the blow's excitation with `--force-window`.
    pub window: String,
    /// Set when the records keep a shorter pre-trigger than asked for: the first blow comes
    /// sooner after the record's start ([`group_blows`]); says so, with both times. Left out of
    /// the JSON when there is none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pretrigger_note: Option<String>,
}

/// A processed channel: the summary, the blow-averaged record and spectrum, the bands.
#[derive(Debug, Clone)]
pub struct ProcessedChannel {
    pub summary: ChannelSummary,
    pub quantity: Quantity,
    /// Where the record came from ([`Record::origin`]).
    pub origin: String,
    /// Time average of the complete blow records (the whole record when no blow was found).
    pub average: Vec<f64>,
    pub spectrum: BlowSpectrum,
    pub bands: Vec<(Band, f64)>,
}

/// The trigger channel of a set of records sampled together: the blow force when a channel
/// is one by name ([`super::mapping`]), else the bed acceleration at B, else the first force,
/// else the first acceleration, else the first record.
pub fn trigger_channel(records: &[&Record], measurement_point: &str) -> usize {
    use super::SimChannel;
    let named = |c: SimChannel| {
        records
            .iter()
            .position(|r| super::by_name(r, measurement_point) == Some(c))
    };
    named(SimChannel::BlowForce)
        .or_else(|| named(SimChannel::BedAcceleration))
        .or_else(|| records.iter().position(|r| r.quantity == Quantity::Force))
        .or_else(|| {
            records
                .iter()
                .position(|r| r.quantity == Quantity::Acceleration)
        })
        .unwrap_or(0)
}

/// The blows of a group of records sampled together, found on `records[trigger]`. When no
/// blow record fits because the first blow triggers sooner after the record's start than the
/// pre-trigger, the records keep the pre-trigger the file has, the time before that first
/// trigger, and [`Blows::note`] says so (a record that starts at the trigger, a simulated
/// history). Blows found of which none fits even so are refused ([`require_complete`]); when no
/// blow is found at all, the whole record counts as one (no trigger: `triggers` empty, and
/// [`process_channel`] reports 0 blows averaged).
pub fn group_blows(records: &[&Record], trigger: usize, p: &Processing) -> Result<(Blows, usize)> {
    let r = records
        .get(trigger)
        .ok_or_else(|| Error::invalid("trigger", "no such channel"))?;
    let fs = r.sample_rate_hz()?;
    let b = detect_blows(&r.values, fs, p)?;
    let found = b.triggers.len();
    let n = records.iter().map(|r| r.values.len()).min().unwrap_or(0);
    if b.triggers.is_empty() {
        return Ok((
            Blows {
                triggers: Vec::new(),
                starts: vec![0],
                length: n,
                pretrigger: 0,
                level: b.level,
                note: None,
            },
            found,
        ));
    }
    let fits = |b: Blows| {
        let starts = b
            .starts
            .iter()
            .copied()
            .filter(|&s| s.checked_add(b.length).is_some_and(|e| e <= n))
            .collect();
        Blows { starts, ..b }
    };
    let mut b = fits(b);
    // Every blow triggers within the pre-trigger of the record's start (a record that starts
    // at the trigger, a simulated history): the pre-trigger the record has, the time before its
    // first trigger, instead of no blow at all.
    let first = b.triggers[0];
    if b.starts.is_empty() && first < b.pretrigger {
        let asked = b.pretrigger;
        let shorter = Processing {
            pretrigger_s: first as f64 / fs,
            ..p.clone()
        };
        let c = fits(detect_blows(&r.values, fs, &shorter)?);
        if !c.starts.is_empty() {
            b = Blows {
                note: Some(format!(
                    "{}: the first blow on '{}' triggers {:.6} s after the record's start, within \
                     the pre-trigger of {:.6} s: its records keep the {:.6} s the file has before \
                     it (a pre-trigger under {MIN_BASELINE_SAMPLES} samples removes no baseline; \
                     --pretrigger or [measurement] pretrigger_s sets it)",
                    r.origin,
                    r.name,
                    first as f64 / fs,
                    asked as f64 / fs,
                    c.pretrigger as f64 / fs
                )),
                ..c
            };
        }
    }
    require_complete(&b, n, fs, &r.name, &r.origin)?;
    Ok((b, found))
}

/// Processes one channel with the group's blows (summary, average, spectrum, bands); `role`
/// says whether it is the blow's excitation (the only channel the force window applies to).
pub fn process_channel(
    r: &Record,
    role: Role,
    blows: &Blows,
    found: usize,
    p: &Processing,
) -> Result<ProcessedChannel> {
    let fs = r.sample_rate_hz()?;
    if r.values.len() < 2 {
        return Err(Error::Input {
            location: r.origin.clone(),
            message: format!("channel '{}': needs at least 2 samples", r.name),
        });
    }
    let records = BlowRecords::new(&r.values, blows)?;
    let (peak, k) = records.peak();
    let baseline = records.removed();
    let average = records.average()?;
    let mut spectrum = blow_spectrum(&r.values, role, fs, blows, p, None)?;
    let window = if p.force_window && role == Role::Excitation {
        format!(
            "{} × {}",
            p.window.name(),
            force_window_for(&r.values, blows, fs, p).name()
        )
    } else {
        p.window.name()
    };
    // No trigger: the whole record, not a blow.
    let averaged = if blows.triggers.is_empty() {
        0
    } else {
        blows.starts.len()
    };
    spectrum.averages = averaged;
    let (ref_e, _) = esd_reference(r.quantity);
    // A line only where there is energy (a channel zero throughout has none).
    let (df, de) = match spectrum.dominant() {
        Some((f, e)) if e > 0.0 => (Some(f), Some(spectrum.level_db(e, ref_e))),
        _ => (None, None),
    };
    let bands = spectrum.third_octaves();
    Ok(ProcessedChannel {
        summary: ChannelSummary {
            name: r.name.clone(),
            unit: r.unit().to_string(),
            samples: r.values.len(),
            sample_rate_hz: fs,
            peak,
            peak_time_s: r.time_at(k),
            baseline,
            blows: found,
            blows_averaged: averaged,
            record_s: blows.length as f64 / fs,
            pretrigger_s: blows.pretrigger as f64 / fs,
            dominant_frequency_hz: df,
            dominant_level_db: de,
            clipped_samples: clipped_samples(&r.values),
            window,
            pretrigger_note: blows.note.clone(),
        },
        quantity: r.quantity,
        origin: r.origin.clone(),
        average,
        spectrum,
        bands,
    })
}

/// Groups records by sampling (same file origin prefix, start, step and length): channels
/// recorded together share their blows.
pub fn groups(records: &[Record]) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = Vec::new();
    let key = |r: &Record| {
        let file = r.origin.split(", ").next().unwrap_or("").to_string();
        let (s, d) = r.even().unwrap_or((f64::NAN, f64::NAN));
        (file, s.to_bits(), d.to_bits(), r.values.len())
    };
    for (i, r) in records.iter().enumerate() {
        let k = key(r);
        match out.iter_mut().find(|g| key(&records[g[0]]) == k) {
            Some(g) => g.push(i),
            None => out.push(vec![i]),
        }
    }
    out
}

/// Processes every record; blows are found per group on the channel named `trigger` when the
/// group has it, else on its [`trigger_channel`] (`point`: the model's measurement point name,
/// for finding B by name). The excitation of a group (the one channel the force window applies
/// to) is the force named as the blow ([`super::by_name`]: `blow`, `hammer`,
/// `slider` …), else the `trigger` channel when it is a force; every other channel is a
/// response.
pub fn process_all(
    records: &[Record],
    p: &Processing,
    trigger: Option<&str>,
    point: &str,
) -> Result<Vec<ProcessedChannel>> {
    if let Some(name) = trigger {
        if !records.iter().any(|r| r.name == name) {
            let names: Vec<&str> = records.iter().map(|r| r.name.as_str()).collect();
            return Err(Error::invalid(
                "trigger",
                format!(
                    "no channel is named '{name}'; the channels are: {}",
                    names.join(", ")
                ),
            ));
        }
    }
    let mut out: Vec<Option<ProcessedChannel>> = vec![None; records.len()];
    for g in groups(records) {
        let members: Vec<&Record> = g.iter().map(|&i| &records[i]).collect();
        let t = match trigger {
            Some(name) => members
                .iter()
                .position(|r| r.name == name)
                .unwrap_or(trigger_channel(&members, point)),
            None => trigger_channel(&members, point),
        };
        let (blows, found) = group_blows(&members, t, p)?;
        let excitation = members
            .iter()
            .position(|r| super::by_name(r, point) == Some(super::SimChannel::BlowForce))
            .or_else(|| {
                (trigger.is_some_and(|name| members[t].name == name)
                    && members[t].quantity == Quantity::Force)
                    .then_some(t)
            });
        for (k, &i) in g.iter().enumerate() {
            let role = if excitation == Some(k) {
                Role::Excitation
            } else {
                Role::Response
            };
            out[i] = Some(process_channel(&records[i], role, &blows, found, p)?);
        }
    }
    Ok(out.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triggers_with_pretrigger_and_holdoff() {
        let fs = 1000.0;
        let mut x = vec![0.0; 3000];
        for &t in &[500usize, 1500, 2500] {
            for k in 0..20 {
                x[t + k] = 10.0 * (-(k as f64) / 5.0).exp() * if k % 2 == 0 { 1.0 } else { -1.0 };
            }
        }
        let p = Processing {
            pretrigger_s: 0.01,
            ..Processing::default()
        };
        let b = detect_blows(&x, fs, &p).unwrap();
        assert_eq!(b.triggers, vec![500, 1500, 2500]);
        assert_eq!(b.length, 1000);
        // The last blow's record (2490..3490) runs past the end: counted, not averaged.
        assert_eq!(b.starts, vec![490, 1490]);
        let avg = average_blows(&x, &b).unwrap();
        assert_eq!(avg[10], 10.0);
        let p = Processing {
            record_s: Some(0.4),
            ..p
        };
        let b = detect_blows(&x, fs, &p).unwrap();
        assert_eq!(b.starts, vec![490, 1490, 2490]);
        // An absolute level above every sample: none.
        let p = Processing {
            level: Level::Absolute(11.0),
            ..p
        };
        assert!(detect_blows(&x, fs, &p).unwrap().triggers.is_empty());
    }
}
