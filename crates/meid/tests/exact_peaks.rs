//! Exact peaks (`integrate::peaks`) against a closed form, and their independence of the output
//! sample rate.
//!
//! A bed of mass `M` on a spring `k` to the floor is struck by a slider `m_s` at `v` through an
//! undamped linear contact `K`. While the contact is closed the two bodies form a 2-DOF system
//! with frequencies `m_s M ω⁴ − (m_s(K + k) + M K) ω² + K k = 0` and modes `φ = [K, K − ω²m_s]`;
//! from rest with `ż_s = v` the motion is `x(t) = Σ φ_i c_i sin(ω_i t)/ω_i`, `Σ φ_i c_i = [v, 0]`.
//! The contact opens when `z_s − u_b` returns to zero; then the bed oscillates freely at
//! `ω_b = √(k/M)` with amplitude `A = √(u² + (u̇/ω_b)²)`, so its peak acceleration is the larger of
//! the contact phase's maximum of `|ü_b|` and `ω_b² A`, and the peak floor force the larger of
//! the contact phase's `k|u_b|` and `k A`. The contact-phase extremes are found here on the
//! closed form by Newton's method on its analytic derivative, independently of meid.

use meid::analysis::simulate;
use meid::impact::Channel;
use meid::model::{Case, Model};

const MS: f64 = 1.0;
const V: f64 = 1.0;
const MB: f64 = 4.0;
const KC: f64 = 1.0e6;
const KB: f64 = 1.0e4;

fn model(rate: f64) -> Model {
    let text = format!(
        r#"
name = "spring-mounted bed"
[structure.lumped]
damping_ratios = [0.0]
masses = [{{ name = "bed", mass = {MB} }}]
springs = [{{ name = "mount", nodes = ["bed", "ground"], stiffness = {KB} }}]
floor = ["mount"]
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = {MS}
velocity = {V}
[contact.slider_bed]
law = "linear"
stiffness = {KC}
damping = 0.0
release = "force"
[simulation]
method = "exact"
duration = 0.2
sample_rate = {rate}
"#
    );
    Model::from_text("mounted.toml", text, &[]).expect("model")
}

/// The closed form of the contact phase: `(ω_i, c_i φ_i[0], c_i φ_i[1])` for both modes.
fn contact_modes() -> [(f64, f64, f64); 2] {
    let a = MS * MB;
    let b = -(MS * (KC + KB) + MB * KC);
    let c = KC * KB;
    let disc = (b * b - 4.0 * a * c).sqrt();
    let w2 = [(-b - disc) / (2.0 * a), (-b + disc) / (2.0 * a)];
    let phi = w2.map(|w| [KC, KC - w * MS]);
    // c_0 φ_0 + c_1 φ_1 = [V, 0].
    let det = phi[0][0] * phi[1][1] - phi[1][0] * phi[0][1];
    let c0 = (V * phi[1][1]) / det;
    let c1 = (-V * phi[0][1]) / det;
    [
        (w2[0].sqrt(), c0 * phi[0][0], c0 * phi[0][1]),
        (w2[1].sqrt(), c1 * phi[1][0], c1 * phi[1][1]),
    ]
}

/// `Σ_i b_i ω_i^{j−1} S_j(ω_i t)` with `S_0 = sin`, `S_1 = cos`, `S_2 = −sin`, `S_3 = −cos`:
/// the j-th derivative of `Σ b_i sin(ω_i t)/ω_i`.
fn deriv(
    modes: &[(f64, f64, f64); 2],
    pick: impl Fn(&(f64, f64, f64)) -> f64,
    j: i32,
    t: f64,
) -> f64 {
    modes
        .iter()
        .map(|m| {
            let (w, b) = (m.0, pick(m));
            let s = match j.rem_euclid(4) {
                0 => (w * t).sin(),
                1 => (w * t).cos(),
                2 => -(w * t).sin(),
                _ => -(w * t).cos(),
            };
            b * w.powi(j - 1) * s
        })
        .sum()
}

/// Largest |f| over [0, t_end] of `f = d^j u_b/dt^j`, by a fine scan and Newton on `f'`.
fn max_abs(modes: &[(f64, f64, f64); 2], j: i32, t_end: f64) -> f64 {
    let f = |t: f64| deriv(modes, |m| m.2, j, t);
    let df = |t: f64| deriv(modes, |m| m.2, j + 1, t);
    let ddf = |t: f64| deriv(modes, |m| m.2, j + 2, t);
    let n = 20_000;
    let mut best = f(0.0).abs().max(f(t_end).abs());
    for k in 0..n {
        let (a, b) = (
            t_end * k as f64 / n as f64,
            t_end * (k + 1) as f64 / n as f64,
        );
        if df(a).signum() != df(b).signum() {
            let mut t = 0.5 * (a + b);
            for _ in 0..50 {
                let step = df(t) / ddf(t);
                t = (t - step).clamp(a, b);
                if step.abs() < 1e-16 * t_end {
                    break;
                }
            }
            best = best.max(f(t).abs());
        }
    }
    best
}

fn closed_form_peaks() -> (f64, f64) {
    let modes = contact_modes();
    // Release: the overlap z_s − u_b = Σ (φ0 − φ1) c sin(ωt)/ω returns to zero.
    let overlap = |t: f64| deriv(&modes, |m| m.1 - m.2, 0, t);
    let rate = |t: f64| deriv(&modes, |m| m.1 - m.2, 1, t);
    let mut t = 1e-6;
    while overlap(t + 1e-6) > 0.0 {
        t += 1e-6;
    }
    for _ in 0..60 {
        t -= overlap(t) / rate(t);
    }
    let t_rel = t;
    let u = deriv(&modes, |m| m.2, 0, t_rel);
    let du = deriv(&modes, |m| m.2, 1, t_rel);
    let wb = (KB / MB).sqrt();
    let amp = (u * u + (du / wb).powi(2)).sqrt();
    let acc_contact = max_abs(&modes, 2, t_rel);
    let disp_contact = max_abs(&modes, 0, t_rel);
    (
        acc_contact.max(wb * wb * amp),
        (KB * disp_contact).max(KB * amp),
    )
}

/// The four shipped examples.
const EXAMPLES: [&str; 4] = [
    "paper-lumped",
    "paper-soft-base",
    "paper-stiff-base",
    "paper-no-base",
];

/// The shipped example `name` (`examples/{name}.toml`) with `--set` overrides.
fn example(name: &str, sets: &[String]) -> Model {
    let path = format!("{}/../../examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    Model::from_file(path.as_ref(), sets).expect("example")
}

#[test]
fn peaks_match_the_closed_form_at_any_output_rate() {
    let (acc, force) = closed_form_peaks();
    for rate in [10.0, 1e3, 2e4, 1e6, 1e7] {
        let m = model(rate);
        let sys = m.impact_system(Case::NoDamper).expect("system");
        let run = simulate(&sys, &m.options(), rate <= 1e6).expect("run");
        let s = &run.summary;
        assert_eq!(
            run.solution.events.len(),
            1,
            "one contact (closed from t = 0), then open"
        );
        let a = s.peak_bed_acceleration_m_per_s2;
        let f = s.peak_floor_force_n;
        assert!(
            (a / acc - 1.0).abs() < 1e-9,
            "rate {rate}: acceleration {a} vs {acc}"
        );
        assert!(
            (f / force - 1.0).abs() < 1e-9,
            "rate {rate}: floor force {f} vs {force}"
        );
        // The acceleration peak is in the contact (it is the contact force over the masses).
        assert!(s.peak_bed_acceleration_time_s < run.solution.events[0].t + 1e-12);
    }
}

/// Every summary peak of the four examples is the same at 100 Hz and at 2 MHz output.
#[test]
fn example_peaks_do_not_depend_on_the_output_rate() {
    for name in EXAMPLES {
        let mut peaks = Vec::new();
        for rate in [100.0, 2e6] {
            let m = example(name, &[]);
            let sys = m.impact_system(Case::Damper).expect("system");
            let mut o = m.options();
            o.sample_rate = Some(rate);
            o.duration = 0.05;
            let run = simulate(&sys, &o, true).expect("run");
            peaks.push(run.summary.peaks.clone());
        }
        assert_eq!(peaks[0].len(), 8, "{name}: all channels");
        for (p, q) in peaks[0].iter().zip(&peaks[1]) {
            let scale = p.peak.abs().max(1e-300);
            assert!(
                (p.peak - q.peak).abs() <= 1e-9 * scale && (p.time_s - q.time_s).abs() <= 1e-12,
                "{name} {}: {} at {} s vs {} at {} s",
                p.channel,
                p.peak,
                p.time_s,
                q.peak,
                q.time_s
            );
        }
        let acc = peaks[0]
            .iter()
            .find(|p| p.channel == Channel::BedAcceleration.key())
            .expect("acceleration");
        assert!(acc.peak > 0.0);
    }
}

/// `dopri5` locates the same extremes on its dense output: they are estimates, as accurate as
/// the integration, and the summary says so (`peak_accuracy`) while `exact` says exact. Against
/// the closed form above (rtol 1e-8 and 1e-10) and against `exact` on the four examples (rtol
/// 1e-8), every peak is within 1e-6 of its value, and the tighter tolerance is closer.
#[test]
fn dopri5_peaks_are_estimates_within_the_integration_tolerance() {
    use meid::integrate::Method;
    let (acc, force) = closed_form_peaks();
    let m = model(2e4);
    let sys = m.impact_system(Case::NoDamper).expect("system");
    let mut errs = Vec::new();
    for rtol in [1e-8, 1e-10] {
        let mut o = m.options();
        o.method = Method::Dopri5;
        o.rtol = rtol;
        let s = simulate(&sys, &o, false).expect("dopri5 run").summary;
        assert!(
            s.peak_accuracy.starts_with("estimates") && s.peak_accuracy.contains("dopri5"),
            "{}",
            s.peak_accuracy
        );
        let e = (s.peak_bed_acceleration_m_per_s2 / acc - 1.0)
            .abs()
            .max((s.peak_floor_force_n / force - 1.0).abs());
        assert!(e < 1e-6, "rtol {rtol}: relative error {e}");
        errs.push(e);
    }
    assert!(errs[1] < errs[0], "a tighter tolerance is closer: {errs:?}");
    let exact = simulate(&sys, &m.options(), false)
        .expect("exact run")
        .summary;
    assert_eq!(exact.peak_accuracy, "exact, on the continuous solution");

    for name in EXAMPLES {
        let m = example(name, &[]);
        let sys = m.impact_system(Case::Damper).expect("system");
        let mut o = m.options();
        o.sample_rate = None;
        let a = simulate(&sys, &o, false).expect("exact").summary;
        o.method = Method::Dopri5;
        let b = simulate(&sys, &o, false).expect("dopri5").summary;
        for (p, q) in a.peaks.iter().zip(&b.peaks) {
            let rel = (p.peak - q.peak).abs() / p.peak.abs();
            assert!(
                rel < 1e-6,
                "{name} {}: exact {} vs dopri5 {} ({rel:.2e})",
                p.channel,
                p.peak,
                q.peak
            );
        }
    }
}

/// A dopri5 run whose absolute tolerance is not small against the motion (a blow at 1e-12 m/s
/// moves the bed by 8e-16 m, below the default atol 1e-14) fails its energy check, and the error
/// names `simulation.atol` first with a value that works; that value does work.
#[test]
fn a_dopri5_tolerance_too_large_for_the_motion_is_named() {
    use meid::integrate::Method;
    let m = example("paper-lumped", &["slider.velocity=1e-12".to_string()]);
    let sys = m.impact_system(Case::Damper).expect("system");
    let mut o = m.options();
    o.method = Method::Dopri5;
    let e = simulate(&sys, &o, false)
        .expect_err("atol 1e-14 against 1e-16 m")
        .to_string();
    let hint = "Likely cause: simulation.atol = 1e-14 is not small against the motion";
    assert!(e.contains(hint), "{e}");
    let given: f64 = e
        .split("): give ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no suggested atol in {e}"));
    o.atol = given;
    let s = simulate(&sys, &o, false)
        .expect("the suggested atol")
        .summary;
    o.method = Method::Exact;
    let x = simulate(&sys, &o, false).expect("exact").summary;
    let (a, b) = (
        s.energy_ratio.expect("ratio"),
        x.energy_ratio.expect("ratio"),
    );
    assert!((a / b - 1.0).abs() < 1e-6, "dopri5 {a} vs exact {b}");
}
