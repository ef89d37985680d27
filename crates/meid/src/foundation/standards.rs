//! The formulas of the foundation checks: the Bornitz attenuation law, DIN 4150-3's guideline
//! values, the dominant frequency of a velocity record, and ISO 2631-2's W_m weighting.

use std::f64::consts::PI;

/// Bornitz's attenuation `v(r)/v(r1) = (r1/r)^n e^{−α (r − r1)}` (Bornitz 1931): geometric
/// spreading with exponent `n` (0.5 surface waves, 1 body waves, 2 body waves along the
/// surface) and material damping `α` (1/m).
pub fn bornitz_factor(r1_m: f64, r_m: f64, n: f64, alpha_per_m: f64) -> f64 {
    (r1_m / r_m).powf(n) * (-alpha_per_m * (r_m - r1_m)).exp()
}

/// DIN 4150-3 (1999-02) Table 1, short-term vibration, foundation, guideline value of the peak
/// velocity (m/s) for building line `line` (1 industrial, 2 residential, 3 sensitive) at the
/// dominant frequency `f_hz`: constant up to 10 Hz, linear from 10 to 50 Hz and from 50 to
/// 100 Hz, and the 100 Hz value above (the table's note). Table 1's corner values (mm/s):
/// line 1 20/40/50, line 2 5/15/20, line 3 3/8/10 at 10/50/100 Hz.
pub fn din4150_3_short_term_m_per_s(line: usize, f_hz: f64) -> f64 {
    let [v10, v50, v100] = match line {
        1 => [20.0, 40.0, 50.0],
        2 => [5.0, 15.0, 20.0],
        _ => [3.0, 8.0, 10.0],
    };
    let mm = if f_hz <= 10.0 {
        v10
    } else if f_hz <= 50.0 {
        v10 + (v50 - v10) * (f_hz - 10.0) / 40.0
    } else if f_hz <= 100.0 {
        v50 + (v100 - v50) * (f_hz - 50.0) / 50.0
    } else {
        v100
    };
    mm * 1e-3
}

/// DIN 4150-3 (1999-02) Table 3, long-term vibration: guideline value (m/s) of the horizontal
/// peak velocity in the plane of the highest floor, at all frequencies: 10, 5 and 2.5 mm/s for
/// lines 1, 2, 3.
pub fn din4150_3_long_term_m_per_s(line: usize) -> f64 {
    match line {
        1 => 10e-3,
        2 => 5e-3,
        _ => 2.5e-3,
    }
}

/// The dominant frequency (Hz) of a sampled record by the zero-crossing method (DIN 4150-3,
/// 5.4 / ISO 4866): `1/(2 Δt)` with Δt the time between the zero crossings on either side of
/// sample `i_peak`, each located by linear interpolation between samples. `None` when the
/// record does not cross zero on both sides.
pub fn zero_crossing_hz(t: &[f64], v: &[f64], i_peak: usize) -> Option<f64> {
    if i_peak >= v.len() || v[i_peak] == 0.0 {
        return None;
    }
    let s = v[i_peak].signum();
    let cross = |a: usize, b: usize| t[a] + (t[b] - t[a]) * v[a] / (v[a] - v[b]);
    let before = (1..=i_peak)
        .rev()
        .find(|&i| v[i - 1] * s <= 0.0)
        .map(|i| cross(i - 1, i))?;
    let after = (i_peak + 1..v.len())
        .find(|&i| v[i] * s <= 0.0)
        .map(|i| cross(i - 1, i))?;
    let dt = after - before;
    (dt > 0.0).then(|| 1.0 / (2.0 * dt))
}

/// ISO 2631-2:2003's W_m weighting (people in buildings, any direction) as ISO 8041 defines it:
/// `W_m(s) = H_h(s) H_l(s) H_t(s)` with the band limits
/// `H_h = s²/(s² + ω1 s/Q1 + ω1²)`, `H_l = ω2²/(s² + ω2 s/Q2 + ω2²)` (f1 = 10^−0.1 Hz,
/// f2 = 100 Hz, Q1 = Q2 = 1/√2) and the acceleration-velocity transition
/// `H_t = (1 + s/ω3)/(1 + s/(Q4 ω4) + s²/ω4²)` (f3 = f4 = 1/(2π·0.028 s) = 5.684 Hz, Q4 = 0.5),
/// gain K = 1. Returns |W_m(j 2π f)|.
pub fn wm_gain(f_hz: f64) -> f64 {
    let [h, l, t] = wm_sections();
    let s = num_complex::Complex64::new(0.0, 2.0 * PI * f_hz);
    let eval = |c: &Analog| {
        (c.b[0] * s * s + c.b[1] * s + c.b[2]) / (c.a[0] * s * s + c.a[1] * s + c.a[2])
    };
    (eval(&h) * eval(&l) * eval(&t)).norm()
}

/// A second-order analog section `(b0 s² + b1 s + b2)/(a0 s² + a1 s + a2)`.
struct Analog {
    b: [f64; 3],
    a: [f64; 3],
}

fn wm_sections() -> [Analog; 3] {
    let q = std::f64::consts::FRAC_1_SQRT_2;
    let w1 = 2.0 * PI * 10f64.powf(-0.1);
    let w2 = 2.0 * PI * 100.0;
    let w34 = 1.0 / 0.028;
    let q4 = 0.5;
    [
        Analog {
            b: [1.0, 0.0, 0.0],
            a: [1.0, w1 / q, w1 * w1],
        },
        Analog {
            b: [0.0, 0.0, w2 * w2],
            a: [1.0, w2 / q, w2 * w2],
        },
        Analog {
            b: [0.0, 1.0 / w34, 1.0],
            a: [1.0 / (w34 * w34), 1.0 / (q4 * w34), 1.0],
        },
    ]
}

/// The W_m-weighted record of acceleration samples `a` at `fs_hz`: each section discretised by
/// the bilinear transform `s = 2 f_s (1 − z⁻¹)/(1 + z⁻¹)` (frequency warping below 1e-4 at
/// 100 Hz for f_s ≥ 20 kHz).
pub fn wm_filter(a: &[f64], fs_hz: f64) -> Vec<f64> {
    let mut y = a.to_vec();
    let k = 2.0 * fs_hz;
    for c in wm_sections() {
        // (b0 s² + b1 s + b2) with s = k (1 − z⁻¹)/(1 + z⁻¹), times (1 + z⁻¹)².
        let poly = |p: [f64; 3]| {
            [
                p[0] * k * k + p[1] * k + p[2],
                -2.0 * p[0] * k * k + 2.0 * p[2],
                p[0] * k * k - p[1] * k + p[2],
            ]
        };
        let bz = poly(c.b);
        let az = poly(c.a);
        let (mut x1, mut x2, mut y1, mut y2) = (0.0, 0.0, 0.0, 0.0);
        for v in y.iter_mut() {
            let x0 = *v;
            let y0 = (bz[0] * x0 + bz[1] * x1 + bz[2] * x2 - az[1] * y1 - az[2] * y2) / az[0];
            x2 = x1;
            x1 = x0;
            y2 = y1;
            y1 = y0;
            *v = y0;
        }
    }
    y
}

/// The largest running r.m.s. over `tau_s` (linear integration, ISO 2631-1:1997 Eq. 3, the
/// maximum transient vibration value MTVV with τ = 1 s) of samples `x` at `fs_hz`; a record
/// shorter than τ is taken with zeros after it (the blow has ended).
pub fn max_running_rms(x: &[f64], fs_hz: f64, tau_s: f64) -> f64 {
    let w = ((tau_s * fs_hz).round() as usize).max(1);
    let mut sum = 0.0;
    let mut best: f64 = 0.0;
    for i in 0..x.len() {
        sum += x[i] * x[i];
        if i >= w {
            sum -= x[i - w] * x[i - w];
        }
        best = best.max(sum.max(0.0));
    }
    (best / w as f64).sqrt()
}
