//! Checks of the exact Fourier transform and energy spectral density of simulated responses
//! (`analysis::esd`) against closed forms, Parseval's theorem and independent quadrature of
//! finely sampled records.

use std::f64::consts::PI;

use faer::c64;
use meid::analysis::esd::{DecayRule, SpectrumBuilder, Stretch, Trajectory};
use meid::impact::{
    Absorber, Channel, ChannelMap, Contact, ContactLaw, ImpactSystem, Mode, Release, Slider,
};
use meid::integrate::{self, NoOutput, Observer, Options};
use meid::modal::ModalModel;
use meid::model::{Case, Model};

/// One structural mode (ω_n, ζ, mass-normalised, φ = 1 at the only point) and a slider 1 m
/// away at rest: the bed's free vibration never reaches it.
fn one_mode(wn: f64, zeta: f64) -> ImpactSystem {
    let mut m = ModalModel::with_damping_ratios(vec![wn], &[zeta]).unwrap();
    m.points.insert("p".into(), vec![1.0]);
    ImpactSystem::new(
        &m,
        "p",
        None,
        "p",
        Slider {
            mass: 1.0,
            velocity: 1.0,
        },
        Contact {
            law: ContactLaw::Linear {
                stiffness: 1e6,
                damping: 0.0,
            },
            release: Release::Force,
        },
        Absorber::None,
    )
    .unwrap()
}

/// The impulse response `q = e^{−σt} sin(ω_d t)/ω_d` as the state `[q, z_s; q̇, ż_s]`.
fn sdof_state(wn: f64, zeta: f64, t: f64) -> Vec<f64> {
    let s = zeta * wn;
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let e = (-s * t).exp();
    let q = e * (wd * t).sin() / wd;
    let v = e * ((wd * t).cos() - s * (wd * t).sin() / wd);
    vec![q, -1.0, v, 0.0]
}

/// The impulse response in three stretches of one mode ending at `t_end`.
fn sdof_trajectory(wn: f64, zeta: f64, t_end: f64) -> Trajectory {
    let cuts = [0.0, 0.13 * t_end, 0.61 * t_end, t_end];
    let stretches = cuts
        .windows(2)
        .map(|w| Stretch {
            t0: w[0],
            t1: w[1],
            mode: Mode(0),
            x0: sdof_state(wn, zeta, w[0]),
            x1: sdof_state(wn, zeta, w[1]),
        })
        .collect();
    Trajectory {
        stretches,
        end: Some((t_end, Mode(0), sdof_state(wn, zeta, t_end))),
    }
}

/// `|got − want| ≤ tol·max(|want|, floor)`.
fn close_to(got: c64, want: c64, tol: f64, floor: f64) -> bool {
    (got - want).norm() <= tol * want.norm().max(floor)
}

fn close(got: c64, want: c64, tol: f64) -> bool {
    close_to(got, want, tol, 0.0)
}

/// `X(ω) = 1/(ω_n² − ω² + 2iζω_nω)` for the impulse response, with `iωX` for the velocity and
/// `−1 − ω²X` for the acceleration (`q̈ = −ω_n²q − 2ζω_n q̇`): the transform of the response
/// continued by its free decay matches to 1e-9 from 0 Hz to 100 kHz, through the resonance.
/// Over the record only, the closed form subtracts the free decay from `(q(T), q̇(T))`:
/// `G_T = X − e^{−iωT}((iω + 2ζω_n) q(T) + q̇(T)) X`.
#[test]
fn sdof_impulse_response_matches_closed_form() {
    let (wn, zeta, t_end) = (2.0 * PI * 10.0, 0.02, 0.7);
    let sys = one_mode(wn, zeta);
    let traj = sdof_trajectory(wn, zeta, t_end);
    let ch = [
        Channel::BedDisplacement,
        Channel::BedVelocity,
        Channel::BedAcceleration,
    ];
    let mut b = SpectrumBuilder::new(&sys, &ch);
    let full = b.build(&traj, true).unwrap();
    let rec = b.build(&traj, false).unwrap();
    let end = sdof_state(wn, zeta, t_end);
    let mut worst = 0.0_f64;
    // Each channel's |G| at the resonance: the scale of "relative" where G vanishes (the
    // velocity at 0 Hz).
    let peak = full.transform(10.0);
    for f in [
        0.0, 1e-6, 1e-3, 0.5, 9.9, 9.98, 9.995_999, 10.0, 10.02, 37.0, 1e3, 1e5,
    ] {
        let w = 2.0 * PI * f;
        let iw = c64::new(0.0, w);
        let x = 1.0 / (c64::new(wn * wn - w * w, 2.0 * zeta * wn * w));
        let want = [x, iw * x, -1.0 - x * (w * w)];
        let g = full.transform(f);
        let decay =
            ((iw + 2.0 * zeta * wn) * end[0] + end[2]) * x * c64::new(0.0, -w * t_end).exp();
        let want_rec = [
            x - decay,
            iw * (x - decay) + end[0] * c64::new(0.0, -w * t_end).exp(),
        ];
        for k in 0..3 {
            let e = (g[k] - want[k]).norm() / want[k].norm().max(peak[k].norm());
            worst = worst.max(e);
            assert!(
                close_to(g[k], want[k], 1e-9, 1e-3 * peak[k].norm()),
                "f = {f} Hz, {:?}: {} vs {}",
                ch[k],
                g[k],
                want[k]
            );
        }
        let gr = rec.transform(f);
        for k in 0..2 {
            assert!(
                close_to(gr[k], want_rec[k], 1e-9, 1e-3 * peak[k].norm()),
                "record only, f = {f} Hz, {:?}: {} vs {}",
                ch[k],
                gr[k],
                want_rec[k]
            );
        }
        // ESD = 2|G|².
        assert!((full.esd(f)[0] - 2.0 * x.norm_sqr()).abs() <= 1e-9 * 2.0 * x.norm_sqr());
    }
    eprintln!("largest relative error {worst:.2e}");
    // Energies in the time domain: ∫q² = 1/(4ζω_n³), ∫q̇² = 1/(4ζω_n).
    let e = full.energy();
    assert!(
        (e[0] * 4.0 * zeta * wn.powi(3) - 1.0).abs() < 1e-12,
        "{e:?}"
    );
    assert!((e[1] * 4.0 * zeta * wn - 1.0).abs() < 1e-12, "{e:?}");
}

/// The same response produced by the exact integrator (one path point at t = 0, run end at
/// 0.7 s): identical transform. An undamped mode has no transform with its free decay (the
/// builder refuses, naming the pole), while its record `[0, T]` does: at ω = ω_n exactly,
/// `∫₀^T sin(ω_n t)/ω_n e^{−iω_n t} dt = (T − (1 − e^{−2iω_nT})/(2iω_n))/(2iω_n)`.
#[test]
fn integrator_path_and_undamped_modes() {
    let (wn, zeta) = (2.0 * PI * 10.0, 0.02);
    let sys = one_mode(wn, zeta);
    let opts = Options {
        duration: 0.7,
        sample_rate: None,
        ..Options::default()
    };
    let sol =
        integrate::solve_from(&sys, &sdof_state(wn, zeta, 0.0), &opts, &mut NoOutput).unwrap();
    assert!(sol.events.is_empty());
    let traj = Trajectory::from_solution(&sol);
    let mut b = SpectrumBuilder::new(&sys, &[Channel::BedDisplacement]);
    let spec = b.build(&traj, true).unwrap();
    for f in [3.0, 10.0, 55.0] {
        let w = 2.0 * PI * f;
        let x = 1.0 / (c64::new(wn * wn - w * w, 2.0 * zeta * wn * w));
        assert!(close(spec.transform(f)[0], x, 1e-9), "{f} Hz");
    }
    // Undamped.
    let sys0 = one_mode(wn, 0.0);
    let t_end = 0.7;
    let traj0 = sdof_trajectory(wn, 0.0, t_end);
    let mut b0 = SpectrumBuilder::new(&sys0, &[Channel::BedDisplacement]);
    let err = b0.build(&traj0, true).unwrap_err().to_string();
    assert!(
        err.contains("does not decay") && err.contains("10.0000"),
        "{err}"
    );
    let rec = b0.build(&traj0, false).unwrap();
    let i2w = c64::new(0.0, 2.0 * wn);
    let want = (t_end - (1.0 - (-i2w * t_end).exp()) / i2w) / i2w;
    let got = rec.transform(10.0)[0];
    assert!(close(got, want, 1e-9), "{got} vs {want}");
    // And the continuation gives up with the same diagnosis within its cost limit.
    let mut b0 = SpectrumBuilder::new(&sys0, &[Channel::BedDisplacement]);
    let mut t = Trajectory::from_solution(
        &integrate::solve_from(&sys0, &sdof_state(wn, 0.0, 0.0), &opts, &mut NoOutput).unwrap(),
    );
    let rule = DecayRule {
        max_continuation_s: 20.0,
        ..DecayRule::default()
    };
    let err = b0
        .continue_until_decayed(&opts, &mut t, &rule)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("does not decay") && err.contains("--spectrum fft"),
        "{err}"
    );
}

/// Simpson's rule on the fly over a fine uniform grid (the sample count must be odd): `∫g²dt`
/// and `∫g e^{−iωt}dt` of each channel at the frequencies `f`.
struct Simpson<'a> {
    sys: &'a ImpactSystem,
    map: ChannelMap,
    channels: Vec<Channel>,
    f: Vec<f64>,
    h: f64,
    n: usize,
    first: Option<(f64, Vec<f64>)>,
    last: (f64, Vec<f64>),
    energy: Vec<f64>,
    fourier: Vec<Vec<c64>>,
}

impl Simpson<'_> {
    fn add(&mut self, t: f64, v: &[f64], w: f64) {
        for (k, g) in v.iter().enumerate() {
            self.energy[k] += w * g * g;
            for (j, f) in self.f.iter().enumerate() {
                self.fourier[k][j] += c64::new(0.0, -2.0 * PI * f * t).exp() * (w * g);
            }
        }
    }
    /// (∫g², ∫g e^{−iωt}) per channel, after the last sample.
    fn finish(mut self) -> (Vec<f64>, Vec<Vec<c64>>) {
        // Samples were weighted 2 (even) and 4 (odd); the two ends need 1.
        if let Some((t0, v0)) = self.first.take() {
            self.add(t0, &v0, -1.0);
        }
        let (t1, v1) = self.last.clone();
        self.add(t1, &v1, -1.0);
        let s = self.h / 3.0;
        (
            self.energy.iter().map(|e| e * s).collect(),
            self.fourier
                .iter()
                .map(|r| r.iter().map(|g| g * s).collect())
                .collect(),
        )
    }
}

impl Observer for Simpson<'_> {
    fn sample(&mut self, t: f64, x: &[f64], mode: Mode) {
        let all = self.map.values(self.sys, mode, x);
        let v: Vec<f64> = self.channels.iter().map(|c| all[c.index()]).collect();
        let w = if self.n % 2 == 1 { 4.0 } else { 2.0 };
        self.add(t, &v, w);
        if self.first.is_none() {
            self.first = Some((t, v.clone()));
        }
        self.last = (t, v);
        self.n += 1;
    }
}

/// The paper's lumped machine with the impact damper (and 10 %/5 % modal damping, so that the
/// response decays within seconds): switches of every kind (slider and damper contacts, the
/// one-way dashpot). Checks, per channel (bed acceleration, floor force, slider-bed force):
/// 1. the continuation rule: the run is continued until the free decay carries < 1e-12 of
///    every channel's energy;
/// 2. Parseval for the exact path: `∫₀^∞ E(f) df` (adaptive Gauss-Kronrod) equals the energy
///    `∫g²dt` computed in the time domain, to 1e-7;
/// 3. over a record `[0, T]`, that energy equals Simpson's rule on the response sampled at
///    1 MHz (independent of the transform), and the transform equals Simpson's rule for
///    `∫g e^{−iωt}dt` at 5 frequencies, to 1e-5: Simpson's rule is O(h²) across the jumps of
///    slope at the switches (a contact closing at `δ̇ ≠ 0` steps `ḟ` by `K δ̇`), about 1e-6
///    relative at h = 1 µs here (measured: 8e-7 for the energy of the bed acceleration).
#[test]
fn impact_run_parseval_and_sampled_quadrature() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/paper-lumped.toml"
    );
    let model = Model::from_file(
        path.as_ref(),
        &["structure.lumped.damping_ratios=[0.1, 0.05]".to_string()],
    )
    .unwrap();
    let sys = model.impact_system(Case::Damper).unwrap();
    let ch = [
        Channel::BedAcceleration,
        Channel::FloorForce,
        Channel::ContactSliderBed,
    ];
    let mut opts = model.options();
    opts.duration = 0.05;
    opts.sample_rate = None;
    let sol = integrate::solve(&sys, &opts, &mut NoOutput).unwrap();
    let mut traj = Trajectory::from_solution(&sol);
    let mut b = SpectrumBuilder::new(&sys, &ch);
    let cont = b
        .continue_until_decayed(&opts, &mut traj, &DecayRule::default())
        .unwrap();
    eprintln!("{cont:?}, {} stretches", traj.stretches.len());
    assert!(cont.tail_energy_fraction.iter().all(|f| *f <= 1e-12));
    assert!(cont.switches > 0 && cont.end_s > 0.05);
    let spec = b.build(&traj, true).unwrap();
    // 2. Parseval.
    for (k, c) in ch.iter().enumerate() {
        let q = spec.esd_integral(k, 1e-10);
        let e = spec.energy()[k];
        eprintln!(
            "{c:?}: ∫E df = {:.12e} (±{:.1e}, {} evaluations), ∫g² dt = {e:.12e}",
            q.value, q.error, q.evaluations
        );
        assert!(q.converged && ((q.value - e) / e).abs() < 1e-7, "{c:?}");
    }
    // 3. A record of 1.5 s sampled at 1 MHz against the exact transform of the same record.
    let fs = 1.0e6;
    let n = 1_500_000; // intervals (even)
    let freqs = vec![6.0, 95.0, 283.0, 1200.0, 5000.0];
    let mut s = Simpson {
        sys: &sys,
        map: ChannelMap::new(&sys),
        channels: ch.to_vec(),
        f: freqs.clone(),
        h: 1.0 / fs,
        n: 0,
        first: None,
        last: (0.0, Vec::new()),
        energy: vec![0.0; 3],
        fourier: vec![vec![c64::new(0.0, 0.0); freqs.len()]; 3],
    };
    let mut o = opts;
    o.duration = n as f64 / fs;
    o.sample_rate = Some(fs);
    let sol = integrate::solve(&sys, &o, &mut s).unwrap();
    assert_eq!(s.n, n + 1);
    let (e_samp, g_samp) = s.finish();
    let rec = b.build(&Trajectory::from_solution(&sol), false).unwrap();
    for (k, c) in ch.iter().enumerate() {
        let e = rec.energy()[k];
        eprintln!("{c:?}: sampled ∫g² = {:.12e}, exact {e:.12e}", e_samp[k]);
        assert!(((e_samp[k] - e) / e).abs() < 1e-5, "{c:?}");
        // Simpson's errors at the slope jumps are absolute (~2e-7 m/s²·s here at every
        // frequency): relative to the largest |G| among the frequencies checked.
        let scale = freqs
            .iter()
            .map(|f| rec.transform(*f)[k].norm())
            .fold(0.0, f64::max);
        for (j, f) in freqs.iter().enumerate() {
            let g = rec.transform(*f)[k];
            eprintln!("  {f} Hz: {g:.9e} vs sampled {:.9e}", g_samp[k][j]);
            assert!((g - g_samp[k][j]).norm() < 1e-5 * scale, "{c:?} {f} Hz");
        }
    }
}

/// A critically damped oscillator (ζ = 1: a defective double pole, so the mode goes to the
/// dense fallback: complex solves per frequency, Van Loan's exponential for the energy):
/// `q = t e^{−ω_n t}`, `X = 1/(ω_n + iω)²`, `∫q² = 1/(4ω_n³)`, `∫q̇² = 1/(4ω_n)`, to 1e-9.
#[test]
fn critically_damped_mode_uses_the_dense_fallback() {
    let wn = 2.0 * PI * 10.0;
    let sys = one_mode(wn, 1.0);
    let state = |t: f64| {
        let e = (-wn * t).exp();
        vec![t * e, -1.0, e * (1.0 - wn * t), 0.0]
    };
    let cuts = [0.0, 0.01, 0.05, 0.2];
    let traj = Trajectory {
        stretches: cuts
            .windows(2)
            .map(|w| Stretch {
                t0: w[0],
                t1: w[1],
                mode: Mode(0),
                x0: state(w[0]),
                x1: state(w[1]),
            })
            .collect(),
        end: Some((0.2, Mode(0), state(0.2))),
    };
    let mut b = SpectrumBuilder::new(&sys, &[Channel::BedDisplacement, Channel::BedVelocity]);
    let spec = b.build(&traj, true).unwrap();
    assert_eq!(spec.fallback_modes(), 1);
    for f in [0.1, 3.0, 10.0, 70.0, 2000.0] {
        let w = 2.0 * PI * f;
        let x = 1.0 / (c64::new(wn, w) * c64::new(wn, w));
        let g = spec.transform(f);
        assert!(close(g[0], x, 1e-9), "{f} Hz: {} vs {x}", g[0]);
        assert!(close(g[1], c64::new(0.0, w) * x, 1e-9), "{f} Hz");
    }
    let e = spec.energy();
    assert!((e[0] * 4.0 * wn.powi(3) - 1.0).abs() < 1e-9, "{e:?}");
    assert!((e[1] * 4.0 * wn - 1.0).abs() < 1e-9, "{e:?}");
}

/// A free-free structure (a rigid-body mode ω = 0 and a 10 Hz mode, φ = 1 in both) drifting at
/// `v` while ringing: the bed displacement sees the rigid motion, whose stretches are integrated
/// as polynomials, `∫₀^T v t e^{−iωt} dt = e^{aT}(T/a − 1/a²) + 1/a²` (a = −iω), plus the
/// oscillator's record transform; its free decay does not exist (refused, naming the 0 Hz
/// pole), while the acceleration, which does not see the drift, has `−1 − ω²X` exactly.
#[test]
fn rigid_body_motion_is_integrated_and_refused_as_a_tail() {
    let (wn, zeta, v, t_end) = (2.0 * PI * 10.0, 0.02, 0.3, 0.7);
    let mut m = ModalModel::with_damping_ratios(vec![0.0, wn], &[0.0, zeta]).unwrap();
    m.points.insert("p".into(), vec![1.0, 1.0]);
    let sys = ImpactSystem::new(
        &m,
        "p",
        None,
        "p",
        Slider {
            mass: 1.0,
            velocity: 1.0,
        },
        Contact {
            law: ContactLaw::Linear {
                stiffness: 1e6,
                damping: 0.0,
            },
            release: Release::Force,
        },
        Absorber::None,
    )
    .unwrap();
    let state = |t: f64| {
        let s = sdof_state(wn, zeta, t);
        // [q1, q2, z_s; q̇1, q̇2, ż_s]
        vec![v * t, s[0], -1.0, v, s[2], 0.0]
    };
    let cuts = [0.0, 0.2, t_end];
    let traj = Trajectory {
        stretches: cuts
            .windows(2)
            .map(|w| Stretch {
                t0: w[0],
                t1: w[1],
                mode: Mode(0),
                x0: state(w[0]),
                x1: state(w[1]),
            })
            .collect(),
        end: Some((t_end, Mode(0), state(t_end))),
    };
    let mut b = SpectrumBuilder::new(&sys, &[Channel::BedDisplacement]);
    let rec = b.build(&traj, false).unwrap();
    let err = b.build(&traj, true).unwrap_err().to_string();
    assert!(
        err.contains("does not decay") && err.contains("(0.000000 Hz)"),
        "{err}"
    );
    let end = sdof_state(wn, zeta, t_end);
    for f in [0.05, 1.0, 10.0, 123.0] {
        let w = 2.0 * PI * f;
        let a = c64::new(0.0, -w);
        let drift = (a * t_end).exp() * (t_end / a - 1.0 / (a * a)) + 1.0 / (a * a);
        let x = 1.0 / (c64::new(wn * wn - w * w, 2.0 * zeta * wn * w));
        let decay =
            ((c64::new(0.0, w) + 2.0 * zeta * wn) * end[0] + end[2]) * x * (a * t_end).exp();
        let want = drift * v + x - decay;
        let got = rec.transform(f)[0];
        assert!(close(got, want, 1e-9), "{f} Hz: {got} vs {want}");
    }
    let mut b = SpectrumBuilder::new(&sys, &[Channel::BedAcceleration]);
    let acc = b.build(&traj, true).unwrap();
    for f in [0.05, 10.0, 123.0] {
        let w = 2.0 * PI * f;
        let x = 1.0 / (c64::new(wn * wn - w * w, 2.0 * zeta * wn * w));
        assert!(
            close(acc.transform(f)[0], -1.0 - x * (w * w), 1e-9),
            "{f} Hz"
        );
    }
}

/// A Hertz slider contact (`dopri5`): the stretches with the contact closed are interpolated
/// (cubic Hermite state between path points, the force on it) and the spectrum says it is an
/// estimate. Parseval holds for the interpolated response (1e-7). Against Simpson's rule on the
/// dopri5 solution sampled at 1 MHz, the slider-bed force (whose whole content is the
/// interpolated pulse) at 6-1200 Hz is within 1e-6 of its largest |G| (measured 4e-8) once
/// the contact has 48 knots ([`SpectrumBuilder::refine_nonlinear`]); with one Hermite stretch per contact (the
/// path points of a dopri5 run without knots) it is off by a third.
#[test]
fn nonlinear_contact_stretches_are_an_estimate() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/paper-lumped.toml"
    );
    let model = Model::from_file(
        path.as_ref(),
        &[
            "structure.lumped.damping_ratios=[0.1, 0.05]".to_string(),
            "simulation.method=\"dopri5\"".to_string(),
            "contact.slider_bed.law=\"hertz\"".to_string(),
            "contact.slider_bed.stiffness=2.0e9".to_string(),
        ],
    )
    .unwrap();
    let sys = model.impact_system(Case::NoDamper).unwrap();
    let ch = [Channel::BedAcceleration, Channel::ContactSliderBed];
    let mut opts = model.options();
    opts.duration = 0.02;
    opts.sample_rate = None;
    let sol = integrate::solve(&sys, &opts, &mut NoOutput).unwrap();
    let mut traj = Trajectory::from_solution(&sol);
    let mut b = SpectrumBuilder::new(&sys, &ch);
    b.continue_until_decayed(&opts, &mut traj, &DecayRule::default())
        .unwrap();
    let coarse = b.build(&traj, true).unwrap();
    let added = b.refine_nonlinear(&opts, &mut traj).unwrap();
    assert!(added > 0);
    let spec = b.build(&traj, true).unwrap();
    assert!(spec.is_estimate() && coarse.is_estimate());
    for (k, c) in ch.iter().enumerate() {
        let q = spec.esd_integral(k, 1e-10);
        let e = spec.energy()[k];
        assert!(((q.value - e) / e).abs() < 1e-7, "{c:?}: {q:?} vs {e}");
    }
    let fs = 1.0e6;
    let n = 20_000;
    let freqs = vec![6.0, 95.0, 283.0, 1200.0];
    let mut s = Simpson {
        sys: &sys,
        map: ChannelMap::new(&sys),
        channels: ch.to_vec(),
        f: freqs.clone(),
        h: 1.0 / fs,
        n: 0,
        first: None,
        last: (0.0, Vec::new()),
        energy: vec![0.0; 2],
        fourier: vec![vec![c64::new(0.0, 0.0); freqs.len()]; 2],
    };
    let mut o = opts;
    o.duration = n as f64 / fs;
    o.sample_rate = Some(fs);
    let sol = integrate::solve(&sys, &o, &mut s).unwrap();
    let (_, g_samp) = s.finish();
    let mut t = Trajectory::from_solution(&sol);
    let coarse = b.build(&t, false).unwrap();
    b.refine_nonlinear(&o, &mut t).unwrap();
    let rec = b.build(&t, false).unwrap();
    let scale = g_samp[1].iter().map(|g| g.norm()).fold(0.0, f64::max);
    let (mut worst, mut worst_coarse) = (0.0_f64, 0.0_f64);
    for (j, f) in freqs.iter().enumerate() {
        let g = rec.transform(*f)[1];
        let err = (g - g_samp[1][j]).norm() / scale;
        let err_coarse = (coarse.transform(*f)[1] - g_samp[1][j]).norm() / scale;
        eprintln!(
            "slider-bed force at {f} Hz: estimate {g:.6e}, sampled {:.6e}: {err:.2e} (one Hermite stretch per contact: {err_coarse:.2e})",
            g_samp[1][j]
        );
        worst = worst.max(err);
        worst_coarse = worst_coarse.max(err_coarse);
    }
    assert!(worst < 1e-6, "{worst}");
    // dopri5 itself now leaves a knot at every accepted step of a non-linear contact
    // (`PathPoint`), so the path before refinement is already accurate.
    assert!(worst_coarse < 1e-6, "{worst_coarse}");
}

/// The damper settling against the bed without preload (where the exact integrator used to stop
/// at 23.77 s with "switches chatter"): asked for a decay of 1e-30 of the energy, the
/// continuation now runs through it, some 760 switches, and reaches that decay well within its
/// limit, and the spectrum is the same as with the regular rule to 1e-6 dB.
#[test]
fn continuation_runs_through_the_settling_damper() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/paper-lumped.toml"
    );
    let model = Model::from_file(path.as_ref(), &[]).unwrap();
    let sys = model.impact_system(Case::Damper).unwrap();
    let mut opts = model.options();
    opts.duration = 2.0;
    opts.sample_rate = None;
    let sol = integrate::solve(&sys, &opts, &mut NoOutput).unwrap();
    let mut traj = Trajectory::from_solution(&sol);
    let mut b = SpectrumBuilder::new(&sys, &[Channel::BedAcceleration, Channel::FloorForce]);
    let rule = DecayRule {
        tail_energy_fraction: 1e-30,
        max_continuation_s: 120.0,
        accept_energy_fraction: 1e-8,
    };
    let cont = b.continue_until_decayed(&opts, &mut traj, &rule).unwrap();
    eprintln!("{cont:?}");
    assert!(cont.stopped_early.is_none(), "{cont:?}");
    assert!(cont.end_s > 23.77 && cont.end_s < 120.0, "{cont:?}");
    assert!(
        cont.tail_energy_fraction.iter().all(|f| *f <= 1e-30),
        "{cont:?}"
    );
    // The spectrum from there is the same as from the regular rule's end, to 1e-6 dB.
    let spec = b.build(&traj, true).unwrap();
    let mut t2 = Trajectory::from_solution(&sol);
    let mut b2 = SpectrumBuilder::new(&sys, &[Channel::BedAcceleration, Channel::FloorForce]);
    b2.continue_until_decayed(&opts, &mut t2, &DecayRule::default())
        .unwrap();
    let spec2 = b2.build(&t2, true).unwrap();
    for f in [6.3, 100.0, 283.0] {
        let (e1, e2) = (spec.esd(f), spec2.esd(f));
        for k in 0..2 {
            assert!(
                (10.0 * (e1[k] / e2[k]).log10()).abs() < 1e-6,
                "{f} Hz: {e1:?} vs {e2:?}"
            );
        }
    }
}
