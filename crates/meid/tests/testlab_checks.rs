//! Checks of the test-lab spectrum path (`analysis::spectrum::esd_fft` and the transient
//! windows) against Parseval's theorem and the closed form of a damped oscillator's impulse
//! response, and of the exponential window's damping correction.

use std::f64::consts::PI;

use meid::analysis::spectrum::{esd_fft, exponential_window_correction, Padding, TransientWindow};

/// `x(t) = e^{−σt} sin(ω_d t)/ω_d` sampled at `fs` for `n` samples.
fn impulse_response(wn: f64, zeta: f64, fs: f64, n: usize) -> Vec<f64> {
    let s = zeta * wn;
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    (0..n)
        .map(|j| {
            let t = j as f64 / fs;
            (-s * t).exp() * (wd * t).sin() / wd
        })
        .collect()
}

/// `2|T|²` for the sampled `x(t) = e^{−σt} sin(ω_d t)/ω_d`, `X(ω) = 1/((σ + iω)² + ω_d²)`: the
/// DFT of the samples (step `h`) is the trapezoid rule `T = h Σ_{n≥0} f(nh)` for
/// `f = x e^{−iωt}` (`x(0) = 0`), and Euler-Maclaurin gives
/// `T = X − h² f'(0)/12 + h⁴ f'''(0)/720 + O(h⁶)` with `f'(0) = x'(0) = 1` and
/// `f'''(0) = x'''(0) − 3iωx''(0) − 3ω²x'(0) = 4σ² − ω_n² − 3ω² + 6iσω` (by Poisson summation
/// these are the aliases `Σ_{k≠0} X(ω + kω_s)`).
fn esd_closed_form(sigma: f64, wd: f64, f: f64, h: f64) -> f64 {
    let w = 2.0 * PI * f;
    // (σ + iω)² + ω_d² = σ² − ω² + ω_d² + 2iσω
    let re = sigma * sigma - w * w + wd * wd;
    let im = 2.0 * sigma * w;
    let d = re * re + im * im;
    let wn2 = wd * wd + sigma * sigma;
    let h4 = h.powi(4) / 720.0;
    let xr = re / d - h * h / 12.0 + h4 * (4.0 * sigma * sigma - wn2 - 3.0 * w * w);
    let xi = -im / d + h4 * 6.0 * sigma * w;
    2.0 * (xr * xr + xi * xi)
}

/// Parseval for the windowed record, every window, with and without zero padding:
/// `Σ_k E_k Δf = Δt Σ_n (w_n x_n)²` to 1e-12 (the DFT's Parseval identity, scaled).
#[test]
fn esd_fft_parseval_for_every_window() {
    let fs = 1000.0;
    for n in [3001usize, 4096] {
        // A deterministic, broadband record: a chirp plus a decaying oscillation.
        let x: Vec<f64> = (0..n)
            .map(|j| {
                let t = j as f64 / fs;
                (2.0 * PI * (5.0 + 80.0 * t) * t).sin()
                    + 3.0 * (-2.0 * t).exp() * (2.0 * PI * 37.0 * t).cos()
            })
            .collect();
        for w in [
            TransientWindow::Rectangular,
            TransientWindow::Hann,
            TransientWindow::Exponential { tau_s: 0.5 },
            TransientWindow::Force {
                pulse_s: 0.2,
                taper_s: 0.1,
            },
        ] {
            let c = w.coefficients(n, fs).unwrap();
            let time: f64 = x.iter().zip(&c).map(|(a, b)| (a * b).powi(2)).sum::<f64>() / fs;
            for pad in [
                Padding::None,
                Padding::Length(4 * n),
                Padding::NextPowerOfTwo,
            ] {
                let e = esd_fft(&x, fs, w, pad).unwrap();
                let freq = e.energy();
                assert!(
                    ((freq - time) / time).abs() < 1e-12,
                    "{} {pad:?} n = {n}: {freq} vs {time}",
                    w.name()
                );
                // Bands add up to the whole.
                let f_top = e.frequency_hz.last().copied().unwrap() + 1.0;
                assert!(((e.band_energy(0.0, f_top) - freq) / freq).abs() < 1e-12);
            }
        }
    }
}

/// The force window: 1 over the pulse, ½(1 + cos(π(t − T_p)/T_c)) over the taper, 0 after;
/// invalid parameters are refused.
#[test]
fn force_and_exponential_window_shapes() {
    let fs = 1000.0;
    let w = TransientWindow::Force {
        pulse_s: 0.01,
        taper_s: 0.004,
    }
    .coefficients(30, fs)
    .unwrap();
    assert_eq!(&w[..11], &[1.0; 11]); // t = 0 … 10 ms
    assert!((w[12] - 0.5).abs() < 1e-12); // mid-taper
    assert!(w[14..].iter().all(|v| *v == 0.0));
    let e = TransientWindow::Exponential { tau_s: 0.02 }
        .coefficients(30, fs)
        .unwrap();
    assert!((e[20] - (-1.0f64).exp()).abs() < 1e-15);
    assert!(TransientWindow::Exponential { tau_s: 0.0 }
        .coefficients(4, fs)
        .is_err());
    assert!(TransientWindow::Force {
        pulse_s: -1.0,
        taper_s: 0.0
    }
    .coefficients(4, fs)
    .is_err());
}

/// The rectangular-window ESD of a fully decayed impulse response (f_n = 10 Hz, ζ = 5 %,
/// 20 s at 2 kHz, decayed to e^{−63}) equals the closed form at the bins from 1 to 30 Hz, to
/// 1e-8 (see [`esd_closed_form`]; without its sampling terms the error would be 1.3e-3 at
/// 30 Hz).
#[test]
fn rectangular_esd_of_a_decayed_response_is_the_continuous_esd() {
    let (fn_hz, zeta, fs): (f64, f64, f64) = (10.0, 0.05, 2000.0);
    let wn = 2.0 * PI * fn_hz;
    let x = impulse_response(wn, zeta, fs, 40_000);
    let e = esd_fft(&x, fs, TransientWindow::Rectangular, Padding::None).unwrap();
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let mut worst = 0.0_f64;
    for (f, v) in e.frequency_hz.iter().zip(&e.density) {
        if *f < 1.0 || *f > 30.0 {
            continue;
        }
        let want = esd_closed_form(zeta * wn, wd, *f, 1.0 / fs);
        worst = worst.max((v / want - 1.0).abs());
    }
    eprintln!("largest relative ESD error 1-30 Hz: {worst:.2e}");
    assert!(worst < 1e-8);
}

/// An exponential window `e^{−t/τ}` adds `1/τ` to the decay rate: the windowed record of a
/// lightly damped response (ζ = 0.5 %, f_n = 10 Hz, cut at 16 s with 0.7 % of its amplitude
/// left) has exactly the ESD of an oscillator with `σ' = ζω + 1/τ` (checked to 1e-7 at
/// 2-30 Hz, with the sampling terms of [`esd_closed_form`]; `O(h⁶)` is 3e-8 at 1 kHz), so
/// the half-power bandwidth gives `ζ_m = (ω₂ − ω₁)/(2ω_n)`, `ω_n = √(ω₁ω₂)`, about 4× the
/// structure's ζ for τ = 1 s, and `ζ = ζ_m − 1/(τω_n)` recovers it to 1 %.
#[test]
fn exponential_window_adds_one_over_tau_to_the_decay_rate() {
    let (fn_hz, zeta, fs, tau): (f64, f64, f64, f64) = (10.0, 0.005, 1000.0, 1.0);
    let wn = 2.0 * PI * fn_hz;
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let x = impulse_response(wn, zeta, fs, 16_000);
    let e = esd_fft(
        &x,
        fs,
        TransientWindow::Exponential { tau_s: tau },
        Padding::Length(32 * 16_000),
    )
    .unwrap();
    let sigma_w = zeta * wn + 1.0 / tau;
    for (f, v) in e.frequency_hz.iter().zip(&e.density) {
        if *f >= 2.0 && *f <= 30.0 {
            let want = esd_closed_form(sigma_w, wd, *f, 1.0 / fs);
            assert!((v / want - 1.0).abs() < 1e-7, "{f} Hz: {v} vs {want}");
        }
    }
    // Half-power points around the peak, linear interpolation between the bins.
    let (ip, peak) =
        e.density
            .iter()
            .enumerate()
            .fold((0, 0.0), |b, (i, v)| if *v > b.1 { (i, *v) } else { b });
    let half = 0.5 * peak;
    let cross = |range: &mut dyn Iterator<Item = usize>| -> f64 {
        let mut prev = ip;
        for i in range {
            if e.density[i] < half {
                let (f0, f1) = (e.frequency_hz[prev], e.frequency_hz[i]);
                let (v0, v1) = (e.density[prev], e.density[i]);
                return f0 + (half - v0) * (f1 - f0) / (v1 - v0);
            }
            prev = i;
        }
        f64::NAN
    };
    let f1 = cross(&mut (0..ip).rev());
    let f2 = cross(&mut (ip + 1..e.density.len()));
    let w_n = 2.0 * PI * (f1 * f2).sqrt();
    let zeta_m = 2.0 * PI * (f2 - f1) / (2.0 * w_n);
    let corrected = exponential_window_correction(zeta_m, tau, w_n);
    eprintln!("ζ_m = {zeta_m:.6}, corrected {corrected:.6}, true {zeta}");
    assert!(zeta_m > 3.0 * zeta);
    assert!((corrected / zeta - 1.0).abs() < 0.01, "{corrected}");
}
