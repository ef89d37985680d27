//! Checks of `analysis::spectrum` against closed forms.
//!
//! References: Heinzel, Rüdiger, Schilling, "Spectrum and spectral density estimation by
//! the DFT" (MPI Gravitationsphysik, 2002) for window figures (Hann: CG 0.5, NENBW 1.5;
//! HFT90D: NENBW 3.8832 bins, max amplitude error 0.0039 dB); Parseval's theorem for the
//! DFT; the variance of white noise; the Hann scalloping loss from the Dirichlet kernel.

use std::f64::consts::PI;

use meid::analysis::spectrum::{
    amplitude_spectrum, amplitude_spectrum_padded, level_db, parseval_energy, peak_in_band,
    psd_level_db, welch_psd, Padding, WelchOptions, Window, REF_ACCELERATION_ISO1683_M_PER_S2,
    REF_ACCELERATION_M_PER_S2, REF_FORCE_N,
};

/// SplitMix64 (Steele, Lea, Flood 2014) and Box-Muller normals: a deterministic test source.
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

fn sine(n: usize, fs: f64, f: f64, amplitude: f64, phase: f64) -> Vec<f64> {
    (0..n)
        .map(|j| amplitude * (2.0 * PI * f * j as f64 / fs + phase).cos())
        .collect()
}

/// dB error of the amplitude read at the bin nearest to `f`.
fn peak_error_db(window: Window, n: usize, fs: f64, f: f64, amplitude: f64) -> f64 {
    let x = sine(n, fs, f, amplitude, 0.3);
    let s = amplitude_spectrum(&x, fs, window).unwrap();
    let k = (f * n as f64 / fs).round() as usize;
    20.0 * (s.amplitude[k] / amplitude).log10()
}

/// Normalised Dirichlet kernel for large N: sin(πδ)/(πδ).
fn sinc(d: f64) -> f64 {
    if d == 0.0 {
        1.0
    } else {
        (PI * d).sin() / (PI * d)
    }
}

/// Hann response at an offset of `d` bins relative to its on-bin value (large-N closed form):
/// W(d) = [0.5 D(d) + 0.25 (D(d-1) + D(d+1))] / 0.5.
fn hann_response(d: f64) -> f64 {
    (0.5 * sinc(d) + 0.25 * (sinc(d - 1.0) + sinc(d + 1.0))) / 0.5
}

#[test]
fn window_gains_match_closed_forms() {
    // Exact for the periodic forms: Σ cos(2πkj/N) = 0 for 0 < k < N.
    for n in [16, 1000, 4096] {
        assert!((Window::Rectangular.coherent_gain(n) - 1.0).abs() < 1e-14);
        assert!((Window::Rectangular.enbw_bins(n) - 1.0).abs() < 1e-14);
        assert!((Window::Hann.coherent_gain(n) - 0.5).abs() < 1e-14);
        assert!((Window::Hann.enbw_bins(n) - 1.5).abs() < 1e-12);
        // HFT90D in Heinzel's normalisation (c0 = 1): CG = 1; NENBW tabulated 3.8832 (4 decimals).
        assert!((Window::FlatTop.coherent_gain(n) - 1.0).abs() < 1e-13);
        assert!(
            (Window::FlatTop.enbw_bins(n) - 3.8832).abs() < 1e-4,
            "{}",
            Window::FlatTop.enbw_bins(n)
        );
    }
}

#[test]
fn on_bin_sine_reads_its_amplitude_for_every_window() {
    // A = 3.7 at bin 123 of N = 4096: exact for all windows (up to rounding, 1e-9 dB).
    let (n, fs) = (4096, 2048.0);
    let f = 123.0 * fs / n as f64;
    for w in [Window::Rectangular, Window::Hann, Window::FlatTop] {
        let e = peak_error_db(w, n, fs, f, 3.7);
        assert!(e.abs() < 1e-9, "{w:?}: {e} dB");
    }
}

#[test]
fn flat_top_reads_amplitude_within_0_01_db_between_bins() {
    // Heinzel 2002: HFT90D amplitude error ≤ 0.0039 dB; the brief asks ≤ 0.01 dB.
    let (n, fs) = (4096, 2048.0);
    let mut worst: f64 = 0.0;
    for i in 0..=20 {
        let offset = i as f64 / 40.0; // 0 .. 0.5 bin
        let f = (300.0 + offset) * fs / n as f64;
        let e = peak_error_db(Window::FlatTop, n, fs, f, 2.5);
        worst = worst.max(e.abs());
    }
    assert!(worst < 0.01, "worst flat-top error {worst} dB");
    assert!(
        worst < 0.0045,
        "worst flat-top error {worst} dB vs 0.0039 dB"
    );
}

#[test]
fn hann_scalloping_matches_closed_form() {
    // Large-N closed form at half a bin: 20 log10(W(0.5)) = -1.4236 dB. Leakage of the
    // negative-frequency image at bin 300 is below 1e-7 relative for Hann (side lobes ∝ 1/k³).
    let expected_half = 20.0 * hann_response(0.5).log10();
    assert!((expected_half + 1.4236).abs() < 1e-4);
    let (n, fs) = (4096, 2048.0);
    for offset in [0.1, 0.25, 0.4, 0.5] {
        let f = (300.0 + offset) * fs / n as f64;
        let e = peak_error_db(Window::Hann, n, fs, f, 1.0);
        let expected = 20.0 * hann_response(offset).log10();
        assert!(
            (e - expected).abs() < 1e-3,
            "offset {offset}: {e} dB vs closed form {expected} dB"
        );
    }
}

#[test]
fn rectangular_scalloping_at_half_bin() {
    // 20 log10(2/π) = -3.9224 dB for large N; the negative-frequency image adds a relative
    // term ≈ 1/(2·600) (rectangular side lobes ∝ 1/k), hence a 0.01 dB tolerance.
    let (n, fs) = (4096, 2048.0);
    let f = 600.5 * fs / n as f64;
    let e = peak_error_db(Window::Rectangular, n, fs, f, 1.0);
    let expected = 20.0 * (2.0 / PI).log10();
    assert!((e - expected).abs() < 0.01, "{e} vs {expected}");
}

#[test]
fn zero_padding_interpolates_the_spectrum() {
    // N = 1000 padded to 1024 (next power of two) and to 4000 (4x).
    let (n, fs) = (1000, 1000.0);
    let f = 123.37; // off the original bins by 0.37 bin
    let x = sine(n, fs, f, 1.0, 0.0);
    let s = amplitude_spectrum_padded(&x, fs, Window::FlatTop, Padding::NextPowerOfTwo).unwrap();
    assert_eq!(s.frequency_hz.len(), 513);
    assert!((s.frequency_hz[1] - fs / 1024.0).abs() < 1e-12);
    let p = s.peak_in_band(100.0, 150.0).unwrap();
    assert!(level_db(p.value, 1.0).unwrap() - level_db(1.0, 1.0).unwrap() > -0.01);
    assert!((p.frequency_hz - f).abs() <= 0.5 * fs / 1024.0 + 1e-12);

    // Hann with 4x padding: the nearest padded bin is ≤ 1/8 original bin away; the error is
    // the Hann response there (closed form), here at δ = |123.37 - 123.25| = 0.12 bin.
    let s4 = amplitude_spectrum_padded(&x, fs, Window::Hann, Padding::Length(4 * n)).unwrap();
    let p4 = s4.peak_in_band(100.0, 150.0).unwrap();
    let delta_bins = (p4.frequency_hz - f).abs() * n as f64 / fs;
    assert!(delta_bins <= 0.125 + 1e-9);
    let expected = hann_response(delta_bins);
    assert!(
        (p4.value - expected).abs() < 2e-4,
        "{} vs {}",
        p4.value,
        expected
    );
    assert!(amplitude_spectrum_padded(&x, fs, Window::Hann, Padding::Length(999)).is_err());
}

#[test]
fn parseval_holds_to_1e_12() {
    let mut rng = Rng(7);
    for n in [1024usize, 1001] {
        let x: Vec<f64> = (0..n).map(|_| rng.normal() * 3.0 + 0.5).collect();
        let p = parseval_energy(&x, 512.0).unwrap();
        assert!(p.time_domain > 0.0);
        assert!(
            p.relative_difference() < 1e-12,
            "n = {n}: {}",
            p.relative_difference()
        );
    }
}

#[test]
fn white_noise_psd_integrates_to_variance() {
    // Gaussian noise σ = 2 (variance 4) at 1 kHz, 2^18 samples. The sample variance has a
    // relative standard error √(2/N) ≈ 0.3 %; the Welch estimate of the total power averages
    // 511 segments. Tolerance 2 % on the total, 10 % on the flat level of each 50 Hz band.
    let (n, fs, sigma) = (1usize << 18, 1000.0, 2.0);
    let mut rng = Rng(2024);
    let x: Vec<f64> = (0..n).map(|_| sigma * rng.normal()).collect();
    let opts = WelchOptions {
        segment_length: 1024,
        ..WelchOptions::default()
    };
    let psd = welch_psd(&x, fs, &opts).unwrap();
    assert_eq!(psd.segments, 511);
    assert!((psd.enbw_hz - 1.5 * fs / 1024.0).abs() < 1e-9);
    let total = psd.band_power(0.0, fs / 2.0);
    assert!(
        (total / (sigma * sigma) - 1.0).abs() < 0.02,
        "total {total}"
    );
    // One-sided white density σ²/(f_s/2) = 0.008 /Hz.
    let level = sigma * sigma / (fs / 2.0);
    for band in 1..9 {
        let (lo, hi) = (band as f64 * 50.0, band as f64 * 50.0 + 50.0);
        let mean = psd.band_power(lo, hi) / (hi - lo);
        assert!((mean / level - 1.0).abs() < 0.1, "band {lo}-{hi}: {mean}");
    }
}

#[test]
fn welch_sine_power_is_half_amplitude_squared() {
    // A sinusoid of amplitude A carries mean square A²/2; the Hann-window lobe is ±2 bins.
    let (n, fs, a) = (65536usize, 4096.0, 2.0);
    let f = 437.3;
    let x = sine(n, fs, f, a, 1.0);
    for overlap in [0.0, 0.5, 0.75] {
        let opts = WelchOptions {
            segment_length: 2048,
            overlap_fraction: overlap,
            window: Window::Hann,
            detrend_mean: true,
        };
        let psd = welch_psd(&x, fs, &opts).unwrap();
        let df = fs / 2048.0;
        let p = psd.band_power(f - 6.0 * df, f + 6.0 * df);
        assert!(
            (p / (a * a / 2.0) - 1.0).abs() < 1e-3,
            "overlap {overlap}: {p}"
        );
    }
}

#[test]
fn levels_match_hand_computation() {
    // √2 peak = 1 RMS: 0 dB re 1 m/s², 120 dB re 1e-6 m/s².
    let a = std::f64::consts::SQRT_2;
    assert!(level_db(a, REF_ACCELERATION_M_PER_S2).unwrap().abs() < 1e-12);
    assert!((level_db(a, REF_ACCELERATION_ISO1683_M_PER_S2).unwrap() - 120.0).abs() < 1e-10);
    // 10 N peak: 20 log10(10/√2) = 16.9897 dB re 1 N.
    assert!((level_db(10.0, REF_FORCE_N).unwrap() - 16.989_700_043).abs() < 1e-8);
    // 1 m/s² peak: -3.0103 dB.
    assert!((level_db(1.0, 1.0).unwrap() + 3.010_299_957).abs() < 1e-8);
    assert_eq!(level_db(0.0, 1.0).unwrap(), f64::NEG_INFINITY);
    // PSD: 1e-4 (m/s²)²/Hz re (1 m/s²)²/Hz = -40 dB.
    assert!((psd_level_db(1e-4, 1.0).unwrap() + 40.0).abs() < 1e-12);
    assert!(level_db(1.0, 0.0).is_err());
    assert!(level_db(-1.0, 1.0).is_err());
    assert!(level_db(f64::NAN, 1.0).is_err());
    assert!(psd_level_db(1.0, -2.0).is_err());
}

#[test]
fn band_peaks_find_each_mode() {
    // Two "modes": 3 m/s² at 52.1 Hz and 0.4 m/s² at 187.8 Hz; flat-top reads both within 0.01 dB.
    let (n, fs) = (8192usize, 1024.0);
    let x: Vec<f64> = sine(n, fs, 52.1, 3.0, 0.2)
        .iter()
        .zip(sine(n, fs, 187.8, 0.4, 1.1))
        .map(|(a, b)| a + b)
        .collect();
    let s = amplitude_spectrum(&x, fs, Window::FlatTop).unwrap();
    let resolution = fs / n as f64;
    for (lo, hi, f, a) in [(40.0, 70.0, 52.1, 3.0), (150.0, 250.0, 187.8, 0.4)] {
        let p = s.peak_in_band(lo, hi).unwrap();
        assert!((p.frequency_hz - f).abs() <= 0.5 * resolution + 1e-12);
        let l = s.peak_level_db(lo, hi, 1.0).unwrap();
        assert!((l - level_db(a, 1.0).unwrap()).abs() < 0.01, "{f} Hz: {l}");
    }
    assert!(s.peak_in_band(600.0, 700.0).is_err());
    assert!(peak_in_band(&[1.0, 2.0], &[1.0], 0.0, 3.0).is_err());
}

#[test]
fn bad_inputs_are_errors() {
    assert!(amplitude_spectrum(&[], 1.0, Window::Hann).is_err());
    assert!(amplitude_spectrum(&[1.0, f64::NAN, 2.0], 1.0, Window::Hann).is_err());
    assert!(amplitude_spectrum(&[1.0, 2.0, 3.0], 0.0, Window::Hann).is_err());
    let x = vec![0.0; 100];
    let long = WelchOptions {
        segment_length: 200,
        ..WelchOptions::default()
    };
    assert!(welch_psd(&x, 10.0, &long).is_err());
    let bad_overlap = WelchOptions {
        segment_length: 50,
        overlap_fraction: 1.0,
        ..WelchOptions::default()
    };
    assert!(welch_psd(&x, 10.0, &bad_overlap).is_err());
}
