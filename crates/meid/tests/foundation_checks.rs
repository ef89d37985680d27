//! `[foundation]` and `[[receiver]]` against closed forms and published numbers: a rigid block on
//! the Lysmer analog after a blow (damped frequency and D_z = 0.425/√B_z), the IS 2974-2 worked
//! example's two frequencies, the Bornitz law at the receivers, DIN 4150-3's table at its corner
//! frequencies, the zero-crossing frequency and the W_m weighting.

use std::path::PathBuf;

use meid::foundation::{self, standards};
use meid::model::{Case, Model};

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// A one-mass lumped model: a block of `m` kg on a half-space (G, ν, ρ) under a plan of area π
/// (r0 = 1 m), struck by a 100 kg slider at 1 m/s.
fn block_on_half_space(m: f64, g: f64, nu: f64, rho: f64) -> String {
    let side = std::f64::consts::PI.sqrt();
    format!(
        r#"
[structure.lumped]
masses = [{{ name = "block", mass = {m:e} }}]

[foundation]
mass = "block"
length = {side:e}
width = {side:e}
soil = {{ shear_modulus = {g:e}, poisson = {nu:e}, density = {rho:e} }}

[points]
bed_contact = "block"
measurement = "block"

[slider]
mass = 100.0
velocity = 1.0

[contact.slider_bed]
stiffness = 1.0e9

[simulation]
duration = 2.0
sample_rate = 20000.0
"#
    )
}

/// The root in [t0, t1] of the cubic Hermite interpolant of (f, f') at both ends (bisection).
fn hermite_root(t0: f64, t1: f64, f: [f64; 2], d: [f64; 2]) -> f64 {
    let h = t1 - t0;
    let at = |s: f64| {
        let (h00, h10, h01, h11) = (
            2.0 * s.powi(3) - 3.0 * s * s + 1.0,
            s.powi(3) - 2.0 * s * s + s,
            -2.0 * s.powi(3) + 3.0 * s * s,
            s.powi(3) - s * s,
        );
        h00 * f[0] + h10 * h * d[0] + h01 * f[1] + h11 * h * d[1]
    };
    let (mut a, mut b) = (0.0, 1.0);
    for _ in 0..200 {
        let c = 0.5 * (a + b);
        if at(a) * at(c) <= 0.0 {
            b = c;
        } else {
            a = c;
        }
    }
    t0 + 0.5 * (a + b) * h
}

/// Rigid block on the Lysmer analog after an impulse: the free vibration after the blow has
/// the damped frequency √(k_z/m) √(1 − D_z²) and the damping ratio D_z = 0.425/√B_z,
/// B_z = (1 − ν) m/(4 ρ r0³), measured on meid's exact history (zero crossings of the
/// displacement for the period, its extremes for the decay) to 1e-6.
#[test]
fn block_on_lysmer_analog_rings_at_the_closed_form() {
    let (m, g, nu, rho) = (6.912e5, 5.0e7, 0.25, 1800.0);
    let model = Model::from_text("block.toml", block_on_half_space(m, g, nu, rho), &[]).unwrap();
    let r0 = 1.0;
    let k = 4.0 * g * r0 / (1.0 - nu);
    let bz = (1.0 - nu) * m / (4.0 * rho * r0.powi(3));
    let dz = 0.425 / bz.sqrt();
    let wd = (k / m).sqrt() * (1.0 - dz * dz).sqrt();
    let sys = model.impact_system(Case::AsSpecified).unwrap();
    let run = meid::analysis::energy::simulate(&sys, &model.options(), true).unwrap();
    let end = run.summary.collision_end_s.unwrap();
    let h = run.history.unwrap();
    let (t, u, v, a) = (
        &h.time_s,
        &h.bed_displacement_m,
        &h.bed_velocity_m_per_s,
        &h.bed_acceleration_m_per_s2,
    );
    let mut zeros = Vec::new();
    let mut extremes = Vec::new();
    for i in 1..t.len() {
        if t[i - 1] <= end {
            continue;
        }
        if u[i - 1] * u[i] < 0.0 {
            zeros.push(hermite_root(
                t[i - 1],
                t[i],
                [u[i - 1], u[i]],
                [v[i - 1], v[i]],
            ));
        }
        if v[i - 1] * v[i] < 0.0 {
            let te = hermite_root(t[i - 1], t[i], [v[i - 1], v[i]], [a[i - 1], a[i]]);
            // The displacement there, from the Hermite interpolant of (u, u̇) on the interval.
            let s = (te - t[i - 1]) / (t[i] - t[i - 1]);
            let dt = t[i] - t[i - 1];
            let ue = (2.0 * s.powi(3) - 3.0 * s * s + 1.0) * u[i - 1]
                + (s.powi(3) - 2.0 * s * s + s) * dt * v[i - 1]
                + (-2.0 * s.powi(3) + 3.0 * s * s) * u[i]
                + (s.powi(3) - s * s) * dt * v[i];
            extremes.push(ue);
        }
    }
    assert!(
        zeros.len() >= 3 && extremes.len() >= 3,
        "{zeros:?} {extremes:?}"
    );
    let half = (zeros[2] - zeros[0]) / 2.0;
    let wd_meid = std::f64::consts::PI / half;
    assert!(
        (wd_meid / wd - 1.0).abs() < 1e-6,
        "ω_d {wd_meid} vs closed form {wd}"
    );
    // Successive extremes (opposite signs) shrink by exp(−D π/√(1 − D²)).
    let ratio = (extremes[1] / extremes[0]).abs();
    let l = -ratio.ln() / std::f64::consts::PI;
    let d_meid = l / (1.0 + l * l).sqrt();
    assert!(
        (d_meid / dz - 1.0).abs() < 1e-6,
        "D_z {d_meid} vs 0.425/√B_z = {dz}"
    );
    // The analog's dashpot is the model's physical dashpot: c_z = 3.4 r0² √(ρG)/(1 − ν).
    let f = model.foundation().unwrap().unwrap();
    let cz = 3.4 * (rho * g).sqrt() / (1.0 - nu);
    assert!((f.c_z_n_s_per_m / cz - 1.0).abs() < 1e-12);
}

/// The IS 2974-2 worked example (two-mass model after Barkan): ω = 260.335 and 125.164 rad/s
/// to 1e-4; on the half-space whose Lysmer k_z is the example's k1, the same with the soil's
/// dashpot switched off.
#[test]
fn hammer_foundation_reproduces_the_worked_example_frequencies() {
    let published = [125.164, 260.335];
    let spring = Model::from_file(&example("hammer-foundation.toml"), &[]).unwrap();
    let soil = Model::from_file(
        &example("hammer-on-soil.toml"),
        &["foundation.soil.radiation_damping=false".into()],
    )
    .unwrap();
    for model in [&spring, &soil] {
        let mut w = model.structure.omega_rad_per_s.clone();
        w.sort_by(f64::total_cmp);
        assert_eq!(w.len(), 2);
        for (a, b) in w.iter().zip(published) {
            assert!((a / b - 1.0).abs() < 1e-4, "{a} vs published {b}");
        }
    }
    // The soil's Lysmer stiffness is k1 = 73.2e5 kN/m.
    let f = soil.foundation().unwrap().unwrap();
    assert!((f.k_z_n_per_m / 7.32e9 - 1.0).abs() < 1e-9);
    assert_eq!(f.c_z_n_s_per_m, 0.0);
}

/// The worked example's amplitudes and meid's exact peaks. After an instantaneous impact with
/// restitution e the anvil leaves at V_a = (1 + e) m0 v/(m0 + m2), the block at rest; the free
/// vibration is Σ A_i φ_i sin(ω_i t). The code's 1.54 mm (anvil), 1.00 mm (block) and
/// 452 kN/m² (pad) are the lower mode's amplitudes; meid's exact peaks through the stiff
/// restitution contact are those of the whole free vibration, to 1e-3 (the contact lasts 0.6 ms).
#[test]
fn hammer_amplitudes_are_the_lower_mode_and_meid_peaks_the_whole_vibration() {
    let g: f64 = 9.81;
    let (m0, m2, m1) = (50e3 / g, 1000e3 / g, 3052e3 / g);
    let (k1, k2, area): (f64, f64, f64) = (7.32e9, 4.6e9, 5.5);
    let va = 1.5 * m0 * 6.2 / (m0 + m2);
    let a = (k1 + k2) / m1 + k2 / m2;
    let b = k1 * k2 / (m1 * m2);
    let w: Vec<f64> = [-1.0_f64, 1.0]
        .iter()
        .map(|s| ((a + s * (a * a - 4.0 * b).sqrt()) / 2.0).sqrt())
        .collect();
    // Mode shapes (anvil 1, block (k2 − m2 ω²)/k2); velocities [V_a, 0] at t = 0.
    let q: Vec<f64> = w.iter().map(|w| (k2 - m2 * w * w) / k2).collect();
    let det = w[0] * w[1] * (q[1] - q[0]);
    let c = [va * w[1] * q[1] / det, -va * w[0] * q[0] / det];
    // The lower mode: the code's numbers.
    let (anvil_lo, block_lo) = ((c[0]).abs(), (c[0] * q[0]).abs());
    assert_eq!(format!("{:.2}", anvil_lo * 1e3), "1.54");
    assert_eq!(format!("{:.2}", block_lo * 1e3), "1.00");
    let code_pad = k2 * (1.54e-3 - 1.00e-3) / area / 1e3;
    assert_eq!(format!("{code_pad:.0}"), "452");
    // The whole free vibration's peaks, on a fine grid over 1 s.
    let (mut pa, mut pb, mut pr) = (0.0_f64, 0.0_f64, 0.0_f64);
    for i in 0..2_000_000 {
        let t = i as f64 * 5e-7;
        let (s0, s1) = ((w[0] * t).sin(), (w[1] * t).sin());
        let xa = c[0] * s0 + c[1] * s1;
        let xb = c[0] * q[0] * s0 + c[1] * q[1] * s1;
        pa = pa.max(xa.abs());
        pb = pb.max(xb.abs());
        pr = pr.max((xa - xb).abs());
    }
    let model = Model::from_file(
        &example("hammer-foundation.toml"),
        &["simulation.duration=1.0".into()],
    )
    .unwrap();
    let f = foundation::assess(&model, Case::AsSpecified)
        .unwrap()
        .unwrap()
        .foundation;
    let close = |got: f64, want: f64, what: &str| {
        assert!(
            (got / want - 1.0).abs() < 1e-3,
            "{what}: meid {got} vs free vibration {want}"
        );
    };
    close(f.peak_anvil_displacement_m.unwrap(), pa, "anvil");
    close(f.peak_block_displacement_m, pb, "block");
    close(f.peak_pad_stress_pa.unwrap(), k2 * pr / area, "pad stress");
}

/// Each receiver's PPV is the block's exact peak velocity times (r1/r)^n e^{−α (r − r1)}, at
/// three distances.
#[test]
fn receivers_follow_the_bornitz_law() {
    for r in [15.0, 40.0, 120.0] {
        let model = Model::from_file(
            &example("hammer-on-soil.toml"),
            &[format!("receiver[0].distance={r}")],
        )
        .unwrap();
        let a = foundation::assess(&model, Case::AsSpecified)
            .unwrap()
            .unwrap();
        let r1 = (7.5_f64 * 6.5 / std::f64::consts::PI).sqrt();
        let expected =
            a.foundation.peak_block_velocity_m_per_s * (r1 / r).sqrt() * (-0.005 * (r - r1)).exp();
        let got = a.receivers[0].ppv_m_per_s;
        assert!(
            (got / expected - 1.0).abs() < 1e-12,
            "r = {r}: {got} vs {expected}"
        );
        assert!(a.foundation.peak_block_velocity_m_per_s > 0.0);
    }
}

/// DIN 4150-3 Table 1 at its corner frequencies and between them (mm/s).
#[test]
fn din4150_3_table_1_at_its_corners() {
    let table = [
        (
            1,
            [
                (5.0, 20.0),
                (10.0, 20.0),
                (30.0, 30.0),
                (50.0, 40.0),
                (75.0, 45.0),
                (100.0, 50.0),
                (200.0, 50.0),
            ],
        ),
        (
            2,
            [
                (5.0, 5.0),
                (10.0, 5.0),
                (30.0, 10.0),
                (50.0, 15.0),
                (75.0, 17.5),
                (100.0, 20.0),
                (200.0, 20.0),
            ],
        ),
        (
            3,
            [
                (5.0, 3.0),
                (10.0, 3.0),
                (30.0, 5.5),
                (50.0, 8.0),
                (75.0, 9.0),
                (100.0, 10.0),
                (200.0, 10.0),
            ],
        ),
    ];
    for (line, points) in table {
        for (f, mm) in points {
            let v = standards::din4150_3_short_term_m_per_s(line, f);
            assert!((v * 1e3 - mm).abs() < 1e-12, "line {line} at {f} Hz: {v}");
        }
    }
    assert_eq!(standards::din4150_3_long_term_m_per_s(1), 10e-3);
    assert_eq!(standards::din4150_3_long_term_m_per_s(2), 5e-3);
    assert_eq!(standards::din4150_3_long_term_m_per_s(3), 2.5e-3);
}

/// The zero-crossing frequency of a sampled decaying sine is its frequency; the W_m filter's
/// steady gain is |W_m(j2πf)|, and W_m at f4 = 5.684 Hz is the a-v transition's 1/√2 times the
/// band limits.
#[test]
fn zero_crossing_and_wm_weighting() {
    let fs = 20_000.0;
    let f0 = 23.7;
    let t: Vec<f64> = (0..20_000).map(|i| i as f64 / fs).collect();
    let x: Vec<f64> = t
        .iter()
        .map(|t| (-3.0 * t).exp() * (2.0 * std::f64::consts::PI * f0 * t).sin())
        .collect();
    let i = (0.3 * fs) as usize;
    let fz = standards::zero_crossing_hz(&t, &x, i).unwrap();
    assert!((fz / f0 - 1.0).abs() < 1e-6, "{fz}");

    // W_m at f4: |H_t| = |1 + j|/|j/Q4| = √2/2, times the band limits' gains.
    let f4 = 1.0 / (0.028 * 2.0 * std::f64::consts::PI);
    let w = |f: f64, fc: f64| f / fc;
    let hp = {
        let r = w(f4, 10f64.powf(-0.1));
        r * r / ((1.0 - r * r).powi(2) + 2.0 * r * r).sqrt()
    };
    let lp = {
        let r = w(f4, 100.0);
        1.0 / ((1.0 - r * r).powi(2) + 2.0 * r * r).sqrt()
    };
    assert!((standards::wm_gain(f4) / (0.5f64.sqrt() * hp * lp) - 1.0).abs() < 1e-12);
    // The digital filter on a 16 Hz sine: steady amplitude ratio = |W_m(j 2π 16)| to 1e-4.
    let f = 16.0;
    let n = (4.0 * fs) as usize;
    let s: Vec<f64> = (0..n)
        .map(|i| (2.0 * std::f64::consts::PI * f * i as f64 / fs).sin())
        .collect();
    let y = standards::wm_filter(&s, fs);
    let tail = &y[n / 2..];
    let amp = tail.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    assert!((amp / standards::wm_gain(f) - 1.0).abs() < 1e-4, "{amp}");
}

/// The report's DIN 4150-3 chart: its limit lines pass through Table 1's values at the corner
/// frequencies (and hold them below 10 Hz and above 100 Hz); long-term, Table 3's constants.
#[test]
fn din_chart_lines_hold_the_table_values_at_the_corners() {
    use meid::model::foundation::Excitation;
    use meid::report::foundation::din_limit_lines;
    // DIN 4150-3 (1999-02) Table 1, foundation, mm/s at 10, 50, 100 Hz.
    let table1 = [[20.0, 40.0, 50.0], [5.0, 15.0, 20.0], [3.0, 8.0, 10.0]];
    let lines = din_limit_lines(Excitation::ShortTerm, 150.0);
    assert_eq!(lines.len(), 3);
    for (line, f, v) in &lines {
        let row = table1[line - 1];
        for (corner, want) in [10.0, 50.0, 100.0].into_iter().zip(row) {
            let k = f
                .iter()
                .position(|&x| x == corner)
                .unwrap_or_else(|| panic!("line {line}: no point at {corner} Hz"));
            assert!(
                (v[k] - want).abs() < 1e-12,
                "line {line} at {corner} Hz: {}",
                v[k]
            );
        }
        // Below 10 Hz the 10 Hz value, above 100 Hz the 100 Hz value; 30 Hz halfway.
        assert_eq!(f[0], 1.0);
        assert!((v[0] - row[0]).abs() < 1e-12);
        assert!(*f.last().unwrap() >= 200.0);
        assert!((v.last().unwrap() - row[2]).abs() < 1e-12);
        let k30 = f.iter().position(|&x| x > 29.0 && x < 31.0).unwrap();
        let want30 = row[0] + (row[1] - row[0]) * (f[k30] - 10.0) / 40.0;
        assert!(
            (v[k30] - want30).abs() < 1e-9,
            "line {line} at {} Hz",
            f[k30]
        );
    }
    // Table 3: 10, 5, 2.5 mm/s at all frequencies.
    for (line, _, v) in din_limit_lines(Excitation::LongTerm, 150.0) {
        let want = [10.0, 5.0, 2.5][line - 1];
        assert!(v.iter().all(|&x| (x - want).abs() < 1e-12), "line {line}");
    }
}

/// The excitation class: given, it wins; not given, long-term, with the reason in
/// `excitation_basis` naming the stroke rate when the model has one, and the conservative
/// choice when it has none.
#[test]
fn excitation_default_follows_the_stroke_rate() {
    use meid::model::foundation::Excitation;
    let path = example("hammer-foundation.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let found = |t: String| {
        Model::from_text("h.toml", t, &[])
            .unwrap()
            .foundation()
            .unwrap()
            .unwrap()
    };
    // No excitation, no [production]: long-term, and why.
    let f = found(text.clone());
    assert_eq!(f.excitation, Excitation::LongTerm);
    let basis = f.excitation_basis.unwrap();
    assert!(
        basis.contains("no [production] rate_bpm") && basis.contains("conservative"),
        "{basis}"
    );
    // A stroke rate: long-term because the blow repeats.
    let with_rate = format!("{text}\n[production]\nrate_bpm = 40.0\n");
    let f = found(with_rate.clone());
    assert_eq!(f.excitation, Excitation::LongTerm);
    let basis = f.excitation_basis.unwrap();
    assert!(
        basis.contains("rate_bpm = 40") && basis.contains("repeats"),
        "{basis}"
    );
    // The user's word wins, with or without a rate; then no default is explained.
    let short = with_rate.replace(
        "[foundation]\n",
        "[foundation]\nexcitation = \"short-term\"\n",
    );
    let f = found(short);
    assert_eq!(f.excitation, Excitation::ShortTerm);
    assert_eq!(f.excitation_basis, None);
    let long = text.replace(
        "[foundation]\n",
        "[foundation]\nexcitation = \"long-term\"\n",
    );
    assert_eq!(found(long).excitation_basis, None);
    // --set reaches it too.
    let m = Model::from_text(
        "h.toml",
        with_rate,
        &["foundation.excitation=\"short-term\"".into()],
    )
    .unwrap();
    assert_eq!(
        m.foundation().unwrap().unwrap().excitation,
        Excitation::ShortTerm
    );
}

/// With a stroke rate the checks judge the periodic steady blow: found directly (Newton on the
/// blow map) and replayed at the block, it equals the last blow of a train marched from rest
/// for 40 blows (an independent route to the same periodic regime). At 20 /min the paper's
/// damper returns to the bed before every strike (period-1).
#[test]
fn steady_basis_equals_the_marched_train_at_the_block() {
    use meid::analysis::blows::{run_blows, BlowOptions};
    use meid::analysis::steady::SteadyOptions;
    let text = std::fs::read_to_string(example("paper-on-soil.toml")).unwrap();
    // Measure the train at the base, which is the block on the soil.
    let m = Model::from_text(
        "paper-on-soil.toml",
        text,
        &["points.measurement=\"base\"".into()],
    )
    .unwrap();
    let basis = foundation::Basis::Steady(SteadyOptions {
        rate_bpm: 20.0,
        ..SteadyOptions::default()
    });
    let a = foundation::assess_with(&m, Case::Damper, &basis)
        .unwrap()
        .unwrap();
    let b = &a.foundation.blow_basis;
    assert_eq!(b.blow, "steady blow of the train");
    assert_eq!(b.regime.as_deref(), Some("period-1"));
    assert_eq!(
        (b.converged, b.damper_touches_bed),
        (Some(true), Some(true))
    );
    let sys = m.impact_system(Case::Damper).unwrap();
    let train = run_blows(
        &sys,
        &m.options(),
        &BlowOptions {
            blows: 40,
            rate_bpm: 20.0,
            ..BlowOptions::default()
        },
        false,
    )
    .unwrap();
    let last = train.blows.last().unwrap();
    let peak = |key: &str| {
        a.foundation
            .block_peaks
            .iter()
            .find(|p| p.channel == key)
            .unwrap()
            .peak
    };
    for (key, marched) in [
        ("floor_force_n", last.peak_floor_force_n),
        (
            "bed_acceleration_m_per_s2",
            last.peak_bed_acceleration_m_per_s2,
        ),
    ] {
        let rel = (peak(key) / marched - 1.0).abs();
        assert!(
            rel < 1e-8,
            "{key}: steady {} vs marched {marched}",
            peak(key)
        );
    }
    // The steady blow differs from the first blow from rest (the damper does not start at
    // rest against the bed): the basis matters.
    let rest = foundation::assess_with(&m, Case::Damper, &foundation::Basis::FromRest)
        .unwrap()
        .unwrap();
    assert_eq!(rest.foundation.blow_basis.blow, "one blow from rest");
    let (vs, vr) = (
        a.foundation.peak_block_velocity_m_per_s,
        rest.foundation.peak_block_velocity_m_per_s,
    );
    assert!((vs / vr - 1.0).abs() > 1e-3, "{vs} vs {vr}");
}
