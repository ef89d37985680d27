//! Spectra of sampled records: windows, window-corrected amplitude spectra, Welch power
//! spectral densities, levels in dB, band peaks and a Parseval check.
//!
//! # Conventions
//!
//! The discrete Fourier transform of a record `x_n`, `n = 0..N-1`, sampled at `f_s` is
//! `X_k = Σ_n w_n x_n e^{-2πi k n / N}` with a window `w_n`; bin `k` sits at
//! `f_k = k f_s / N_fft` (`N_fft ≥ N` when the record is zero-padded). The FFT itself is
//! `realfft` (a real-to-complex wrapper around `rustfft`); only the scaling, windows and
//! averaging are written here, because they are where the units are decided and they are a
//! few lines each (no crate in the workspace documents the corrections we need).
//!
//! * **Amplitude spectrum** (sinusoid-calibrated): `A_k = 2 |X_k| / Σ_n w_n`
//!   (`|X_k| / Σ w_n` at DC and Nyquist). A sinusoid `A cos(2π f t + φ)` lying on a bin
//!   reads exactly `A` at that bin for every window; between bins it reads low by the
//!   window's scalloping loss (rectangular 3.92 dB, Hann 1.42 dB, flat-top HFT90D
//!   0.0039 dB at most). Dividing by `Σ w_n = N · CG` is the coherent-gain (amplitude)
//!   correction. Reference: G. Heinzel, A. Rüdiger, R. Schilling, *Spectrum and spectral
//!   density estimation by the Discrete Fourier transform (DFT), including a comprehensive
//!   list of window functions and some new flat-top windows*, Max-Planck-Institut für
//!   Gravitationsphysik, 2002 (hereafter Heinzel 2002), Eqs. (13)-(19).
//! * **Power spectral density** (Welch 1967, one-sided): for each segment
//!   `G_k = 2 |X_k|² / (f_s Σ_n w_n²)` (no factor 2 at DC and Nyquist), averaged over
//!   segments. Units (signal unit)²/Hz; `Σ_k G_k Δf` equals the variance of a zero-mean
//!   record. `f_s Σ w² / (Σ w)² = ENBW` is the power (noise-bandwidth) correction
//!   (Heinzel 2002, Eqs. (20)-(24)). P. D. Welch, IEEE Trans. Audio Electroacoust. 15 (1967) 70-73.
//! * **Levels**: `L = 20 log10(A_rms / A_ref)` dB with `A_rms = A / √2`, the RMS of the
//!   sinusoid whose peak amplitude is `A` (the amplitude spectrum holds peak amplitudes;
//!   levels are quoted as RMS as in ISO 1683). References: 1 m/s² (default for
//!   acceleration), 1e-6 m/s² (ISO 1683:2015), 1 N for force.
//!   PSD levels are `10 log10(G / A_ref²)` dB re A_ref²/Hz.

use realfft::num_complex::Complex;
use realfft::RealFftPlanner;

use crate::{Error, Result};

/// Reference acceleration 1 m/s² for levels in dB (the crate's default for acceleration).
pub const REF_ACCELERATION_M_PER_S2: f64 = 1.0;
/// Reference acceleration 1 µm/s² = 1e-6 m/s² (ISO 1683:2015, preferred reference values).
pub const REF_ACCELERATION_ISO1683_M_PER_S2: f64 = 1.0e-6;
/// Reference force 1 N for force levels in dB.
pub const REF_FORCE_N: f64 = 1.0;

/// Coefficients `c_k` of the HFT90D flat-top window, `w_j = Σ_k (-1)^k c_k cos(k z_j)`,
/// `z_j = 2π j / N` (Heinzel 2002, Sec. D.3.3: NENBW 3.8832 bins, largest amplitude
/// error -0.0039 dB, highest side lobe -90.2 dB).
const HFT90D: [f64; 5] = [1.0, 1.942604, 1.340318, 0.440811, 0.043097];
/// Coefficients of the Hann window in the same form: `w_j = 0.5 - 0.5 cos(z_j)`.
const HANN: [f64; 2] = [0.5, 0.5];

/// Data windows (tapers) applied to a record before the FFT. All are the periodic
/// ("DFT-even") forms, the right ones for spectral analysis (Heinzel 2002, Sec. 6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Window {
    /// No taper, `w = 1`. Coherent gain 1, ENBW 1 bin, scalloping loss up to 3.92 dB.
    /// Exact for transients that decay inside the record and for bin-centred sinusoids.
    Rectangular,
    /// Hann, `w_j = 0.5 - 0.5 cos(2π j / N)`. Coherent gain 0.5, ENBW 1.5 bins,
    /// scalloping loss up to 1.42 dB (half-bin offset).
    #[default]
    Hann,
    /// Flat-top HFT90D (Heinzel 2002):
    /// `w_j = 1 - 1.942604 cos z + 1.340318 cos 2z - 0.440811 cos 3z + 0.043097 cos 4z`,
    /// `z = 2π j / N`. ENBW 3.8832 bins, amplitude error at most
    /// 0.0039 dB anywhere between bins: the window for reading amplitudes.
    FlatTop,
}

impl Window {
    /// The window's `n` samples (periodic form).
    pub fn coefficients(self, n: usize) -> Vec<f64> {
        let cosine_sum = |c: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|j| {
                    let z = 2.0 * std::f64::consts::PI * j as f64 / n as f64;
                    c.iter()
                        .enumerate()
                        .map(|(k, ck)| {
                            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                            sign * ck * (k as f64 * z).cos()
                        })
                        .sum()
                })
                .collect()
        };
        match self {
            Window::Rectangular => vec![1.0; n],
            Window::Hann => cosine_sum(&HANN),
            Window::FlatTop => cosine_sum(&HFT90D),
        }
    }

    /// Coherent gain `CG = Σ w_j / N` (the amplitude correction divides by `N · CG`).
    pub fn coherent_gain(self, n: usize) -> f64 {
        if n == 0 {
            return f64::NAN;
        }
        self.coefficients(n).iter().sum::<f64>() / n as f64
    }

    /// Equivalent noise bandwidth in bins, `NENBW = N Σ w_j² / (Σ w_j)²`
    /// (Heinzel 2002, Eq. 21). Multiply by `f_s / N` for hertz.
    pub fn enbw_bins(self, n: usize) -> f64 {
        let w = self.coefficients(n);
        let s1: f64 = w.iter().sum();
        let s2: f64 = w.iter().map(|v| v * v).sum();
        n as f64 * s2 / (s1 * s1)
    }

    /// A short name for labels and files.
    pub fn name(self) -> &'static str {
        match self {
            Window::Rectangular => "rectangular",
            Window::Hann => "hann",
            Window::FlatTop => "flat-top (HFT90D)",
        }
    }
}

/// Zero-padding of a record before the FFT. Padding interpolates the spectrum (finer bin
/// spacing); it does not improve the resolution, which stays `f_s / N`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Padding {
    /// FFT length = record length.
    #[default]
    None,
    /// FFT length = the next power of two ≥ record length.
    NextPowerOfTwo,
    /// FFT length = the given length (must be ≥ record length).
    Length(usize),
}

impl Padding {
    fn fft_length(self, n: usize) -> Result<usize> {
        match self {
            Padding::None => Ok(n),
            Padding::NextPowerOfTwo => n.checked_next_power_of_two().ok_or_else(|| {
                Error::invalid("padding", format!("no power of two ≥ {n} fits in usize"))
            }),
            Padding::Length(m) if m >= n => Ok(m),
            Padding::Length(m) => Err(Error::invalid(
                "padding",
                format!("padded length {m} is shorter than the record ({n} samples)"),
            )),
        }
    }
}

/// A one-sided amplitude spectrum.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrum {
    /// Bin frequencies `k f_s / N_fft` (Hz), `k = 0..=N_fft/2`.
    pub frequency_hz: Vec<f64>,
    /// Peak amplitude of a sinusoid at each bin, window-corrected (signal unit).
    pub amplitude: Vec<f64>,
}

/// A one-sided power spectral density from Welch's method.
#[derive(Debug, Clone, PartialEq)]
pub struct Psd {
    /// Bin frequencies `k f_s / L` (Hz), `L` the segment length.
    pub frequency_hz: Vec<f64>,
    /// Power spectral density, (signal unit)²/Hz.
    pub density: Vec<f64>,
    /// Number of averaged segments.
    pub segments: usize,
    /// Equivalent noise bandwidth of the window, Hz.
    pub enbw_hz: f64,
}

/// The largest value of a spectrum inside a frequency band.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Peak {
    /// Bin index in the spectrum.
    pub index: usize,
    /// Bin frequency (Hz); the true peak frequency is within half a bin of it.
    pub frequency_hz: f64,
    /// Value at the bin (amplitude, or density for a PSD).
    pub value: f64,
}

/// Options for [`welch_psd`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WelchOptions {
    /// Samples per segment `L` (≥ 2); the frequency resolution is `f_s / L`.
    pub segment_length: usize,
    /// Overlap of consecutive segments as a fraction of `L`, in `[0, 1)` (0.5 is usual for Hann).
    pub overlap_fraction: f64,
    /// Window applied to each segment.
    pub window: Window,
    /// Subtract each segment's mean before the FFT (removes the DC bin's leakage).
    pub detrend_mean: bool,
}

impl Default for WelchOptions {
    fn default() -> Self {
        WelchOptions {
            segment_length: 4096,
            overlap_fraction: 0.5,
            window: Window::Hann,
            detrend_mean: true,
        }
    }
}

/// Energy of a record computed in time and in frequency (rectangular window, no padding).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parseval {
    /// `Σ_n x_n² Δt` ((signal unit)²·s).
    pub time_domain: f64,
    /// `Σ_k |X_k Δt|² Δf` over all `N` two-sided bins, `Δf = f_s / N` ((signal unit)²·s).
    pub frequency_domain: f64,
}

impl Parseval {
    /// `|time - frequency| / time` (0 when both are 0).
    pub fn relative_difference(&self) -> f64 {
        let d = (self.time_domain - self.frequency_domain).abs();
        if d == 0.0 {
            0.0
        } else {
            d / self.time_domain.abs().max(self.frequency_domain.abs())
        }
    }
}

fn check_record(x: &[f64], sample_rate_hz: f64) -> Result<()> {
    if x.len() < 2 {
        return Err(Error::invalid(
            "record",
            format!("needs at least 2 samples, got {}", x.len()),
        ));
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(
            "record",
            format!("sample {i} is not finite ({})", x[i]),
        ));
    }
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(Error::invalid(
            "sample_rate_hz",
            format!("must be a positive finite number, got {sample_rate_hz}"),
        ));
    }
    Ok(())
}

/// FFT of `x` (already windowed) zero-padded to `n_fft`; returns the `n_fft/2 + 1` bins.
pub(crate) fn real_fft(x: &[f64], n_fft: usize) -> Result<Vec<Complex<f64>>> {
    let mut planner = RealFftPlanner::<f64>::new();
    let r2c = planner.plan_fft_forward(n_fft);
    let mut input = r2c.make_input_vec();
    input[..x.len()].copy_from_slice(x);
    let mut output = r2c.make_output_vec();
    r2c.process(&mut input, &mut output)
        .map_err(|e| Error::numerical("FFT", e.to_string()))?;
    Ok(output)
}

/// The one-sided weight of bin `k` of an `n_fft`-point real FFT: bins `1..n_fft/2` (the
/// Nyquist bin of an even length excluded) stand for themselves and their mirror image (2),
/// the DC and Nyquist bins for themselves only (1).
pub(crate) fn one_sided_factor(k: usize, n_fft: usize) -> f64 {
    if k == 0 || (n_fft.is_multiple_of(2) && k == n_fft / 2) {
        1.0
    } else {
        2.0
    }
}

fn bin_frequencies(n_bins: usize, n_fft: usize, sample_rate_hz: f64) -> Vec<f64> {
    (0..n_bins)
        .map(|k| k as f64 * sample_rate_hz / n_fft as f64)
        .collect()
}

/// Single-block amplitude spectrum of a record without padding; see
/// [`amplitude_spectrum_padded`].
pub fn amplitude_spectrum(x: &[f64], sample_rate_hz: f64, window: Window) -> Result<Spectrum> {
    amplitude_spectrum_padded(x, sample_rate_hz, window, Padding::None)
}

/// Single-block, sinusoid-calibrated amplitude spectrum:
/// `A_k = 2 |Σ_n w_n x_n e^{-2πi k n / N_fft}| / Σ_n w_n` (halved at DC and at the Nyquist
/// bin of an even `N_fft`). The window spans the `N` recorded samples; the zeros of the
/// padding are not windowed. Heinzel 2002, Eq. (17).
pub fn amplitude_spectrum_padded(
    x: &[f64],
    sample_rate_hz: f64,
    window: Window,
    padding: Padding,
) -> Result<Spectrum> {
    check_record(x, sample_rate_hz)?;
    let n = x.len();
    let n_fft = padding.fft_length(n)?;
    let w = window.coefficients(n);
    let sum_w: f64 = w.iter().sum();
    let xw: Vec<f64> = x.iter().zip(&w).map(|(a, b)| a * b).collect();
    let bins = real_fft(&xw, n_fft)?;
    let amplitude = bins
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let one_sided = one_sided_factor(k, n_fft);
            one_sided * c.norm() / sum_w
        })
        .collect();
    Ok(Spectrum {
        frequency_hz: bin_frequencies(bins.len(), n_fft, sample_rate_hz),
        amplitude,
    })
}

/// One-sided power spectral density by Welch's method of averaged modified periodograms:
/// `G_k = (1/S) Σ_s 2 |X_{s,k}|² / (f_s Σ_n w_n²)` over `S` segments of length `L`
/// starting every `L - round(overlap·L)` samples (trailing samples that do not fill a
/// segment are not used). No factor 2 at DC and at the Nyquist bin of an even `L`.
/// Welch (1967); Heinzel 2002, Eq. (24).
pub fn welch_psd(x: &[f64], sample_rate_hz: f64, options: &WelchOptions) -> Result<Psd> {
    check_record(x, sample_rate_hz)?;
    let l = options.segment_length;
    if l < 2 {
        return Err(Error::invalid(
            "segment_length",
            format!("must be at least 2 samples, got {l}"),
        ));
    }
    if l > x.len() {
        return Err(Error::invalid(
            "segment_length",
            format!(
                "{l} samples is longer than the record ({} samples)",
                x.len()
            ),
        ));
    }
    let ov = options.overlap_fraction;
    if !(ov.is_finite() && (0.0..1.0).contains(&ov)) {
        return Err(Error::invalid(
            "overlap_fraction",
            format!("must lie in [0, 1), got {ov}"),
        ));
    }
    let step = (l - ((ov * l as f64).round() as usize).min(l - 1)).max(1);
    let w = options.window.coefficients(l);
    let sum_w2: f64 = w.iter().map(|v| v * v).sum();
    let sum_w: f64 = w.iter().sum();

    let mut planner = RealFftPlanner::<f64>::new();
    let r2c = planner.plan_fft_forward(l);
    let mut input = r2c.make_input_vec();
    let mut output = r2c.make_output_vec();
    let mut acc = vec![0.0; output.len()];
    let mut segments = 0usize;
    let mut start = 0usize;
    while start + l <= x.len() {
        let seg = &x[start..start + l];
        let mean = if options.detrend_mean {
            seg.iter().sum::<f64>() / l as f64
        } else {
            0.0
        };
        for ((dst, v), wj) in input.iter_mut().zip(seg).zip(&w) {
            *dst = (v - mean) * wj;
        }
        r2c.process(&mut input, &mut output)
            .map_err(|e| Error::numerical("FFT", e.to_string()))?;
        for (a, c) in acc.iter_mut().zip(&output) {
            *a += c.norm_sqr();
        }
        segments += 1;
        start += step;
    }
    let scale = 1.0 / (sample_rate_hz * sum_w2 * segments as f64);
    let density = acc
        .iter()
        .enumerate()
        .map(|(k, a)| {
            let one_sided = one_sided_factor(k, l);
            one_sided * a * scale
        })
        .collect();
    Ok(Psd {
        frequency_hz: bin_frequencies(acc.len(), l, sample_rate_hz),
        density,
        segments,
        enbw_hz: sample_rate_hz * sum_w2 / (sum_w * sum_w),
    })
}

/// Energy of a record in time and in frequency for the rectangular window (Parseval's
/// theorem for the DFT: `Σ_n |x_n|² = (1/N) Σ_k |X_k|²`, scaled by `Δt` to the continuous
/// form `∫ x² dt = ∫ |X(f)|² df` with `X(f_k) ≈ X_k Δt`).
pub fn parseval_energy(x: &[f64], sample_rate_hz: f64) -> Result<Parseval> {
    check_record(x, sample_rate_hz)?;
    let n = x.len();
    let dt = 1.0 / sample_rate_hz;
    let df = sample_rate_hz / n as f64;
    let bins = real_fft(x, n)?;
    let frequency_domain: f64 = bins
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let count = one_sided_factor(k, n);
            count * c.norm_sqr() * dt * dt * df
        })
        .sum();
    let time_domain: f64 = x.iter().map(|v| v * v).sum::<f64>() * dt;
    Ok(Parseval {
        time_domain,
        frequency_domain,
    })
}

fn check_reference(reference: f64) -> Result<()> {
    if reference.is_finite() && reference > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(
            "reference",
            format!("a dB reference must be positive and finite, got {reference}"),
        ))
    }
}

/// Level in dB of a sinusoid of peak amplitude `amplitude`: `20 log10((A / √2) / A_ref)`
/// (RMS of the sinusoid against the reference, ISO 1683 convention). A zero amplitude gives
/// `-inf`. Example: `A = √2 m/s²` re 1 m/s² is 0 dB; re 1e-6 m/s² it is 120 dB.
pub fn level_db(amplitude: f64, reference: f64) -> Result<f64> {
    check_reference(reference)?;
    if !(amplitude.is_finite() && amplitude >= 0.0) {
        return Err(Error::invalid(
            "amplitude",
            format!("must be a finite non-negative number, got {amplitude}"),
        ));
    }
    Ok(20.0 * (amplitude / std::f64::consts::SQRT_2 / reference).log10())
}

/// Level in dB of a power spectral density: `10 log10(G / A_ref²)` (dB re A_ref²/Hz).
pub fn psd_level_db(density: f64, reference: f64) -> Result<f64> {
    check_reference(reference)?;
    if !(density.is_finite() && density >= 0.0) {
        return Err(Error::invalid(
            "density",
            format!("must be a finite non-negative number, got {density}"),
        ));
    }
    Ok(10.0 * (density / (reference * reference)).log10())
}

/// The largest value in the closed band `[f_lo, f_hi]` (Hz) of a sampled spectrum.
pub fn peak_in_band(frequency_hz: &[f64], values: &[f64], f_lo: f64, f_hi: f64) -> Result<Peak> {
    if frequency_hz.len() != values.len() {
        return Err(Error::invalid(
            "spectrum",
            format!(
                "{} frequencies but {} values",
                frequency_hz.len(),
                values.len()
            ),
        ));
    }
    if !(f_lo.is_finite() && f_hi.is_finite() && f_lo <= f_hi) {
        return Err(Error::invalid(
            "band",
            format!("needs finite f_lo ≤ f_hi, got [{f_lo}, {f_hi}] Hz"),
        ));
    }
    let mut best: Option<Peak> = None;
    for (k, (&f, &v)) in frequency_hz.iter().zip(values).enumerate() {
        if f < f_lo || f > f_hi || v.is_nan() {
            continue;
        }
        if best.is_none_or(|b| v > b.value) {
            best = Some(Peak {
                index: k,
                frequency_hz: f,
                value: v,
            });
        }
    }
    best.ok_or_else(|| {
        Error::invalid(
            "band",
            format!("no spectral line lies in [{f_lo}, {f_hi}] Hz"),
        )
    })
}

impl Spectrum {
    /// Levels of every bin, `20 log10((A_k/√2)/A_ref)` dB; see [`level_db`].
    pub fn levels_db(&self, reference: f64) -> Result<Vec<f64>> {
        self.amplitude
            .iter()
            .map(|&a| level_db(a, reference))
            .collect()
    }

    /// The largest amplitude in `[f_lo, f_hi]` Hz; see [`peak_in_band`].
    pub fn peak_in_band(&self, f_lo: f64, f_hi: f64) -> Result<Peak> {
        peak_in_band(&self.frequency_hz, &self.amplitude, f_lo, f_hi)
    }

    /// Level in dB (RMS re `reference`) of the largest amplitude in `[f_lo, f_hi]` Hz:
    /// "the peak at a dominant mode".
    pub fn peak_level_db(&self, f_lo: f64, f_hi: f64, reference: f64) -> Result<f64> {
        level_db(self.peak_in_band(f_lo, f_hi)?.value, reference)
    }
}

impl Psd {
    /// `Σ_k G_k Δf` over the bins in `[f_lo, f_hi]` Hz ((signal unit)²): the mean square
    /// of the signal in that band. Over all bins it is the record's variance.
    pub fn band_power(&self, f_lo: f64, f_hi: f64) -> f64 {
        let df = if self.frequency_hz.len() > 1 {
            self.frequency_hz[1] - self.frequency_hz[0]
        } else {
            0.0
        };
        self.frequency_hz
            .iter()
            .zip(&self.density)
            .filter(|(f, _)| **f >= f_lo && **f <= f_hi)
            .map(|(_, g)| g * df)
            .sum()
    }

    /// Levels of every bin, `10 log10(G_k / A_ref²)` dB re A_ref²/Hz.
    pub fn levels_db(&self, reference: f64) -> Result<Vec<f64>> {
        self.density
            .iter()
            .map(|&g| psd_level_db(g, reference))
            .collect()
    }
}

// ---------------------------------------------------------------- transient (energy) records

/// Windows for transient records: the test-lab practice for impact tests, kept for comparing
/// simulated and measured spectra like for like (the exact spectrum of a simulated response,
/// [`super::esd`], needs no window).
///
/// * **Exponential** `w(t) = e^{−t/τ}` (t from the first sample) forces a lightly damped
///   response to decay inside the record, at a known cost: it multiplies a mode
///   `e^{−ζωt}` by `e^{−t/τ}`, i.e. it adds `1/τ` to the decay rate `σ = ζω`. A damping ratio
///   identified from the windowed spectrum is therefore `ζ_m = ζ + 1/(τω)` (for `ζ ≪ 1`), and the
///   structure's own is `ζ = ζ_m − 1/(τω)` ([`exponential_window_correction`]).
/// * **Force** window for the excitation record (a hammer's or the slider's force): 1 over the
///   pulse `[0, T_p]`, a half-cosine taper `½(1 + cos(π(t − T_p)/T_c))` over `[T_p, T_p + T_c]`,
///   0 after, so that the noise after the pulse does not enter the force spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TransientWindow {
    /// `w = 1` over the record.
    Rectangular,
    /// Hann over the record (periodic form): zero at the start, where a blow's transient is.
    Hann,
    /// `w(t) = e^{−t/τ}`.
    Exponential { tau_s: f64 },
    /// 1 over the pulse, cosine taper, 0 after.
    Force { pulse_s: f64, taper_s: f64 },
}

impl TransientWindow {
    /// The window's value at each of `n` samples at `t_j = j/f_s`.
    pub fn coefficients(&self, n: usize, sample_rate_hz: f64) -> Result<Vec<f64>> {
        let dt = 1.0 / sample_rate_hz;
        Ok(match *self {
            TransientWindow::Rectangular => vec![1.0; n],
            TransientWindow::Hann => Window::Hann.coefficients(n),
            TransientWindow::Exponential { tau_s } => {
                if !(tau_s.is_finite() && tau_s > 0.0) {
                    return Err(Error::invalid(
                        "window.tau_s",
                        format!(
                            "the exponential window's time constant must be > 0 s (got {tau_s})"
                        ),
                    ));
                }
                (0..n).map(|j| (-(j as f64) * dt / tau_s).exp()).collect()
            }
            TransientWindow::Force { pulse_s, taper_s } => {
                if !(pulse_s.is_finite() && pulse_s > 0.0 && taper_s.is_finite() && taper_s >= 0.0)
                {
                    return Err(Error::invalid(
                        "window",
                        format!(
                            "the force window needs a pulse > 0 s and a taper ≥ 0 s (got {pulse_s}, {taper_s})"
                        ),
                    ));
                }
                (0..n)
                    .map(|j| {
                        let t = j as f64 * dt;
                        if t <= pulse_s {
                            1.0
                        } else if t < pulse_s + taper_s {
                            0.5 * (1.0 + (std::f64::consts::PI * (t - pulse_s) / taper_s).cos())
                        } else {
                            0.0
                        }
                    })
                    .collect()
            }
        })
    }

    /// A short name for labels.
    pub fn name(&self) -> String {
        match *self {
            TransientWindow::Rectangular => "rectangular".into(),
            TransientWindow::Hann => "hann".into(),
            TransientWindow::Exponential { tau_s } => format!("exponential (τ = {tau_s} s)"),
            TransientWindow::Force { pulse_s, taper_s } => {
                format!("force (pulse {pulse_s} s, taper {taper_s} s)")
            }
        }
    }
}

/// The damping ratio of a mode from the one identified through an exponential window
/// `e^{−t/τ}`: `ζ = ζ_m − 1/(τω)` (the window adds `1/τ` to the decay rate `ζω`).
pub fn exponential_window_correction(zeta_measured: f64, tau_s: f64, omega_rad_per_s: f64) -> f64 {
    zeta_measured - 1.0 / (tau_s * omega_rad_per_s)
}

/// A one-sided energy spectral density of a windowed record.
#[derive(Debug, Clone, PartialEq)]
pub struct Esd {
    /// Bin frequencies `k f_s / N_fft` (Hz).
    pub frequency_hz: Vec<f64>,
    /// `E_k` (unit²·s/Hz).
    pub density: Vec<f64>,
    /// The sample rate `f_s` (Hz): the bins stand for `[0, f_s/2]`.
    pub sample_rate_hz: f64,
}

/// `∫_{f_lo}^{f_hi} E(f) df` (unit²·s) of a one-sided density given on the bins
/// `f_k = k Δf` of a DFT at `f_s = sample_rate_hz`, each bin's energy `E_k Δf` spread evenly
/// over the frequencies it stands for, `I_k = [f_k − Δf/2, f_k + Δf/2] ∩ [0, f_s/2]` (DC:
/// `[0, Δf/2]`; the Nyquist bin of an even length: `[f_s/2 − Δf/2, f_s/2]`):
///
/// ```text
/// E_band = Σ_k E_k Δf · |I_k ∩ [f_lo, f_hi]| / |I_k|
/// ```
///
/// A bin wholly inside the band counts whole and one across an edge in proportion, so bands
/// that tile `[0, f_s/2]` add up to `Σ_k E_k Δf` exactly, and a band narrower than a bin gets
/// its share of it. (Counting the bins whose centre lies in the band instead gives such a band
/// nothing or a whole bin: a band level that depends on the record length, 20 % on the 10 Hz
/// band of a decayed 100 Hz transient between 0.5 s and 1 s records.) Without a positive
/// `f_s` the last bin's interval is not clipped.
pub fn bin_band_energy(
    frequency_hz: &[f64],
    density: &[f64],
    sample_rate_hz: f64,
    f_lo: f64,
    f_hi: f64,
) -> f64 {
    let n = frequency_hz.len().min(density.len());
    if n < 2 || f_hi.is_nan() || f_lo.is_nan() || f_hi <= f_lo {
        return 0.0;
    }
    let df = frequency_hz[1] - frequency_hz[0];
    if !(df > 0.0 && df.is_finite()) {
        return 0.0;
    }
    let top = if sample_rate_hz > 0.0 {
        0.5 * sample_rate_hz
    } else {
        f64::INFINITY
    };
    // Only the bins whose interval can meet [f_lo, f_hi].
    let first = ((f_lo / df).floor() - 1.0).max(0.0);
    let first = if first < n as f64 { first as usize } else { n };
    let mut sum = 0.0;
    for k in first..n {
        let f = frequency_hz[k];
        let (a, b) = ((f - 0.5 * df).max(0.0), (f + 0.5 * df).min(top));
        if a >= f_hi {
            break;
        }
        let width = b - a;
        let overlap = b.min(f_hi) - a.max(f_lo);
        if width > 0.0 && overlap > 0.0 {
            sum += density[k] * (overlap / width).min(1.0);
        }
    }
    sum * df
}

/// One-sided energy spectral density of a windowed transient record:
/// `E_k = 2|Δt Σ_n w_n x_n e^{−2πikn/N_fft}|²` (unit²·s/Hz; not doubled at DC and at the Nyquist
/// bin), the discrete form of `E(f) = 2|G(f)|²` of [`super::esd`] for the windowed record
/// `w(t)x(t)`. Parseval holds exactly, with or without zero padding:
/// `Σ_k E_k Δf = Δt Σ_n (w_n x_n)²`, `Δf = f_s/N_fft` ([`Esd::energy`]). For a stationary
/// signal the PSD is the ESD divided by the record's `Δt Σ w_n²` (cf. [`welch_psd`]).
pub fn esd_fft(
    x: &[f64],
    sample_rate_hz: f64,
    window: TransientWindow,
    padding: Padding,
) -> Result<Esd> {
    check_record(x, sample_rate_hz)?;
    let n = x.len();
    let n_fft = padding.fft_length(n)?;
    let w = window.coefficients(n, sample_rate_hz)?;
    let xw: Vec<f64> = x.iter().zip(&w).map(|(a, b)| a * b).collect();
    let bins = real_fft(&xw, n_fft)?;
    let dt = 1.0 / sample_rate_hz;
    let density = bins
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let one_sided = one_sided_factor(k, n_fft);
            one_sided * c.norm_sqr() * dt * dt
        })
        .collect();
    Ok(Esd {
        frequency_hz: bin_frequencies(bins.len(), n_fft, sample_rate_hz),
        density,
        sample_rate_hz,
    })
}

impl Esd {
    /// Bin spacing `Δf` (Hz).
    pub fn bin_width_hz(&self) -> f64 {
        if self.frequency_hz.len() > 1 {
            self.frequency_hz[1] - self.frequency_hz[0]
        } else {
            0.0
        }
    }

    /// `Σ_k E_k Δf` (unit²·s): the windowed record's energy `Δt Σ (w x)²`.
    pub fn energy(&self) -> f64 {
        self.density.iter().sum::<f64>() * self.bin_width_hz()
    }

    /// `∫_{f_lo}^{f_hi} E df` (unit²·s), each bin's energy spread over the frequencies it
    /// stands for ([`bin_band_energy`]): bands that tile the spectrum add up to [`Self::energy`].
    pub fn band_energy(&self, f_lo: f64, f_hi: f64) -> f64 {
        bin_band_energy(
            &self.frequency_hz,
            &self.density,
            self.sample_rate_hz,
            f_lo,
            f_hi,
        )
    }

    /// The largest bin in `[f_lo, f_hi]`.
    pub fn peak_in_band(&self, f_lo: f64, f_hi: f64) -> Result<Peak> {
        peak_in_band(&self.frequency_hz, &self.density, f_lo, f_hi)
    }
}
