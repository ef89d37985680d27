//! Checks of `analysis::compare` and `analysis::blows` against closed forms
//! (`/work/shared/notes/closed-forms.md`) and the paper's lumped example.

use meid::analysis::blows::{run_blows, BlowOptions};
use meid::analysis::compare::{record_spectrum, CaseName, CompareOptions, Comparison};
use meid::analysis::simulate;
use meid::analysis::spectrum::{level_db, parseval_energy, Window};
use meid::model::{Case, Model};

const M: f64 = 100.0; // mounted mass, kg
const K: f64 = 1.0e5; // mount stiffness, N/m
const MS: f64 = 0.01; // slider, kg (1e-4 M: the blow is an impulse)
const KS: f64 = 1.0e6; // contact, N/m: contact frequency sqrt(KS/MS) = 1e4 rad/s = 316 x the mount's
const VS: f64 = 1.0; // m/s

/// A rigid mass M on a spring k to the floor, struck by a light slider through a stiff
/// undamped contact; `[added_mass]` of `added` kg for the comparison.
fn mounted_mass(added: f64) -> Model {
    let text = format!(
        r#"
name = "spring-mounted mass"
[structure]
reference_mode = 1
[structure.lumped]
damping_ratios = [0.0]
masses = [{{ name = "bed", mass = {M} }}]
springs = [{{ name = "mount", nodes = ["bed", "ground"], stiffness = {K} }}]
floor = ["mount"]
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = {MS}
velocity = {VS}
[added_mass]
mass = {added}
[contact.slider_bed]
law = "linear"
stiffness = {KS}
damping = 0.0
release = "force"
[simulation]
method = "exact"
duration = 2.0
sample_rate = 20000.0
"#
    );
    Model::from_text("mounted.toml", text, &[]).unwrap()
}

fn paper() -> Model {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/paper-lumped.toml"
    );
    Model::from_file(path.as_ref(), &[]).unwrap()
}

fn flat_top() -> CompareOptions {
    CompareOptions {
        window: Window::FlatTop,
        ..CompareOptions::default()
    }
}

fn reduction(r: &meid::analysis::compare::ComparisonResult, case: CaseName, metric: &str) -> f64 {
    r.reductions
        .iter()
        .find(|x| x.case == case && x.metric == metric)
        .unwrap_or_else(|| panic!("no row {case} {metric}"))
        .reduction_db
}

/// Closed form: impulse J on a spring-mounted mass M gives a peak spring force J sqrt(k/M)
/// (= v sqrt(kM), v = J/M); a rigid added mass m lowers it by 10 log10(1 + m/M) dB
/// (0.79 dB for 20 %, 3.01 dB for 100 %) and the acceleration of the mode,
/// ω² (v/ω) = J sqrt(k)/M^1.5, by 30 log10(1 + m/M) dB. The blow here is an impulse to about
/// 1e-4 (slider 1e-4 M, contact 316x faster than the mount), so the reductions must match to
/// 0.05 dB (the flat-top window reads amplitudes to 0.004 dB).
#[test]
fn added_mass_matches_impulse_closed_form() {
    for ratio in [0.2, 1.0] {
        let r = Comparison::new(mounted_mass(ratio * M), flat_top())
            .run()
            .unwrap();
        let expect_force = 10.0 * (1.0 + ratio).log10();
        let expect_acc = 30.0 * (1.0 + ratio).log10();
        let time = reduction(&r, CaseName::AddedMass, "peak floor force (time)");
        let spec = reduction(&r, CaseName::AddedMass, "floor force at mode 1 (reference)");
        let acc = reduction(
            &r,
            CaseName::AddedMass,
            "bed acceleration at mode 1 (reference)",
        );
        eprintln!(
            "m/M = {ratio}: floor force {time:.4} dB (time), {spec:.4} dB (spectrum), expected {expect_force:.4}; acceleration at the mode {acc:.4} dB, expected {expect_acc:.4}"
        );
        assert!(
            (time - expect_force).abs() < 0.05,
            "{time} vs {expect_force}"
        );
        assert!(
            (spec - expect_force).abs() < 0.05,
            "{spec} vs {expect_force}"
        );
        assert!((acc - expect_acc).abs() < 0.05, "{acc} vs {expect_acc}");
    }
}

/// End to end: the no-damper floor force is the sinusoid F sin(ω t) with
/// F = J sqrt(k/M), J = 2 μ v_s (undamped contact, e = 1; μ = m_s M/(m_s + M)). Its level
/// at the mode must be 20 log10(F/√2) dB re 1 N within the flat-top's 0.004 dB plus the
/// 1e-4 impulse approximation (0.01 dB); the time peak must be F within 1e-3; and Parseval
/// must hold for the recorded force to 1e-9.
#[test]
fn spectrum_level_of_mounted_mass_matches_closed_form() {
    let r = Comparison::new(mounted_mass(20.0), flat_top())
        .run()
        .unwrap();
    let none = &r.cases[0];
    assert_eq!(none.case, CaseName::NoDamper);
    let mu = MS * M / (MS + M);
    let f_peak = 2.0 * mu * VS * (K / M).sqrt();
    let expect = level_db(f_peak, 1.0).unwrap();
    let got = none.modes[0].floor_force_level_db;
    eprintln!(
        "floor force level {got:.5} dB re 1 N, closed form {expect:.5} dB; peak {} N vs {f_peak} N",
        none.peak_floor_force_n
    );
    assert!((got - expect).abs() < 0.01, "{got} vs {expect}");
    assert!((none.peak_floor_force_n / f_peak - 1.0).abs() < 1e-3);
    let p = parseval_energy(&none.history.floor_force_n, r.sample_rate_hz).unwrap();
    assert!(p.relative_difference() < 1e-9, "{p:?}");
}

/// The compare spectrum path (window, coherent-gain correction, 4x zero padding): a sinusoid
/// of amplitude A reads 20 log10(A/√2) dB. On a bin the rectangular and Hann windows are exact
/// (1e-9 dB) and the flat-top within its ripple (0.0039 dB: the padded lines around the bin
/// sit on the ripple); off the bins the worst scalloping loss with 4x padding (1/8 bin) is sinc(1/8) = -0.224 dB
/// (rectangular), -0.087 dB (Hann), and 0.004 dB for the flat-top (Heinzel 2002).
#[test]
fn record_spectrum_reads_sine_levels() {
    let fs = 1000.0;
    let n = 2000;
    let a = 3.7;
    for (f0, window, tol) in [
        (50.0, Window::Rectangular, 1e-9),
        (50.0, Window::Hann, 1e-9),
        (50.0, Window::FlatTop, 0.004),
        (50.23, Window::Rectangular, 0.23),
        (50.23, Window::Hann, 0.09),
        (50.23, Window::FlatTop, 0.004),
    ] {
        let x: Vec<f64> = (0..n)
            .map(|j| a * (2.0 * std::f64::consts::PI * f0 * j as f64 / fs + 0.3).cos())
            .collect();
        let s = record_spectrum(&x, fs, window).unwrap();
        let got = s.peak_level_db(0.9 * f0, 1.1 * f0, 1.0).unwrap();
        let expect = level_db(a, 1.0).unwrap();
        assert!(
            (got - expect).abs() <= tol,
            "{window:?} at {f0} Hz: {got} vs {expect} (tol {tol})"
        );
    }
}

/// The paper's lumped machine: the impact damper must lower the bed acceleration at the bed
/// mode and the floor force at the rigid-body mode (the paper reports about 3 dB; the exact
/// numbers are reported, not tested).
#[test]
fn paper_damper_reduces_levels() {
    let r = Comparison::new(paper(), CompareOptions::default())
        .run()
        .unwrap();
    eprintln!("{}", r.table_text());
    let acc = reduction(&r, CaseName::Damper, "bed acceleration at mode 2 (bed)");
    let force = reduction(&r, CaseName::Damper, "floor force at mode 1 (reference)");
    assert!(acc > 0.0, "bed acceleration reduction {acc} dB");
    assert!(force > 0.0, "floor force reduction {force} dB");
    assert!(reduction(&r, CaseName::Damper, "peak floor force (time)") > 0.0);
}

/// One blow of length T is the single simulation with duration T, bit for bit.
#[test]
fn one_blow_equals_simulate() {
    let model = paper();
    let sys = model.impact_system(Case::Damper).unwrap();
    let mut opts = model.options();
    opts.duration = 0.5;
    let run = simulate(&sys, &opts, true).unwrap();
    let b = BlowOptions {
        blows: 1,
        rate_bpm: 120.0, // T = 0.5 s
        ..BlowOptions::default()
    };
    let blows = run_blows(&sys, &opts, &b, true).unwrap();
    assert_eq!(blows.interval_s, 0.5);
    assert_eq!(
        blows.history.as_ref().unwrap(),
        run.history.as_ref().unwrap()
    );
    let r = &blows.blows[0];
    assert_eq!(r.energy_ratio, run.summary.energy_ratio);
    assert_eq!(r.peak_floor_force_n, run.summary.peak_floor_force_n);
    assert_eq!(
        r.peak_bed_acceleration_m_per_s2,
        run.summary.peak_bed_acceleration_m_per_s2
    );
}

/// A linear machine (no damper, the mounted mass with 2 % damping) struck periodically
/// reaches a periodic steady state: the residual vibration at each strike is a geometric
/// series with ratio exp(-ζ ω T) (here exp(-0.02·31.6·1) = 0.53 per blow), so the blow-to-blow
/// change of the peak floor force falls below 1 % within about 8 blows; and the first blow's
/// energy ratio is that of a single run.
#[test]
fn blows_reach_steady_state() {
    let model = Model::from_text(
        "m.toml",
        mounted_mass(20.0).source.text.clone(),
        &["structure.lumped.damping_ratios=[0.02]".to_string()],
    )
    .unwrap();
    let sys = model.impact_system(Case::NoDamper).unwrap();
    let opts = model.options();
    let b = BlowOptions {
        blows: 15,
        rate_bpm: 60.0,
        steady_tolerance: 0.01,
    };
    let r = run_blows(&sys, &opts, &b, true).unwrap();
    for x in &r.blows {
        eprintln!(
            "blow {:2}: floor {:.4} N, acc {:.4} m/s², η {:?}, machine energy at strike {:.3e} J",
            x.blow,
            x.peak_floor_force_n,
            x.peak_bed_acceleration_m_per_s2,
            x.energy_ratio,
            x.machine_energy_at_strike_j
        );
    }
    assert!(r.steady.converged, "{:?}", r.steady);
    assert!(r.steady.from_blow.unwrap() <= 10, "{:?}", r.steady);
    let h = r.history.unwrap();
    assert_eq!(h.time_s.len(), 15 * 20000 + 1);
    // uniform grid across the joins
    let dt = 1.0 / 20000.0;
    assert!(h
        .time_s
        .windows(2)
        .all(|w| ((w[1] - w[0]) / dt - 1.0).abs() < 1e-6));
}

/// Energy bookkeeping across blow joins: with no damping anywhere (undamped mount, undamped
/// contact) nothing is dissipated, so the concatenated `dissipated_j` (E_s− − Σ stored, shifted
/// by what was stored at each strike; the rebounding slider leaves with its energy) must stay
/// at 0 to round-off (1e-9 E_s−) over 5 blows, while the machine's energy at the strike grows.
#[test]
fn blow_train_energy_bookkeeping() {
    let e_s = 0.5 * MS * VS * VS;
    let b = BlowOptions {
        blows: 5,
        rate_bpm: 240.0,
        steady_tolerance: 0.01,
    };
    let model = mounted_mass(20.0);
    let sys = model.impact_system(Case::NoDamper).unwrap();
    let r = run_blows(&sys, &model.options(), &b, true).unwrap();
    let worst = r
        .history
        .unwrap()
        .dissipated_j
        .iter()
        .fold(0.0_f64, |m, d| m.max(d.abs()));
    assert!(worst < 1e-9 * e_s, "undamped train dissipated {worst} J");
    assert!(r.blows[4].machine_energy_at_strike_j > 0.0);
}
