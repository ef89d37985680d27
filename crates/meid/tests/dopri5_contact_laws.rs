//! dopri5 with every contact law: the energy balance, the consistency of the modes with the
//! state, and the physics of the blow, over {linear, Hertz, Hunt-Crossley} on each contact ×
//! {one-way, two-way} dashpot × {force, overlap} release × the four example machines; the
//! exact method on the linear ones; exact peaks and path knots; the guards against runs that
//! make no progress.

use meid::analysis::simulate;
use meid::impact::{
    Channel, ContactLaw, DashpotKind, ImpactSystem, Mode, Release, Switch, CHANNELS,
};
use meid::integrate::{self, Method, NoOutput, Observer, Options};
use meid::model::{Case, Model};
use std::path::PathBuf;

const EXAMPLES: [&str; 4] = [
    "paper-lumped",
    "paper-no-base",
    "paper-soft-base",
    "paper-stiff-base",
];

fn load(name: &str, sets: &[&str]) -> Model {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(format!("{name}.toml"));
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Model::from_file(&path, &sets).unwrap()
}

fn system(name: &str, sets: &[&str]) -> ImpactSystem {
    load(name, sets).impact_system(Case::AsSpecified).unwrap()
}

fn opts(method: Method, duration: f64) -> Options {
    Options {
        method,
        duration,
        sample_rate: None,
        rtol: 1e-8,
        ..Options::default()
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Law {
    Linear,
    Hertz,
    HuntCrossley,
}

/// The law of kind `law` equivalent to the example's linear contact `(k, m)` (stiffness K in
/// N/m, the mass m it stops): a damped linear law with 5 % of critical damping
/// (`C = 0.1 √(K m)`); Hertz with `K_h = K / √δ_ref`, which has the linear law's stiffness
/// `dF/dδ ∝ K_h √δ` (so a comparable contact frequency) at the overlap
/// `δ_ref = v_s √(m_s / K_s)` of the slider on a rigid bed; Hunt-Crossley with the same `K_h`,
/// `n = 3/2` and `α = 0.2 s/m` (restitution about `1 − α v`).
fn law(kind: Law, k: f64, m: f64, delta_ref: f64) -> ContactLaw {
    match kind {
        Law::Linear => ContactLaw::Linear {
            stiffness: k,
            damping: 0.1 * (k * m).sqrt(),
        },
        Law::Hertz => ContactLaw::Hertz {
            stiffness: k / delta_ref.sqrt(),
        },
        Law::HuntCrossley => ContactLaw::HuntCrossley {
            stiffness: k / delta_ref.sqrt(),
            exponent: 1.5,
            alpha: 0.2,
        },
    }
}

/// `sys` with the given laws, dashpot and release rule (the example's linear stiffnesses set
/// the scale of the non-linear ones).
fn variant(
    base: &ImpactSystem,
    slider_bed: Law,
    bed_damper: Law,
    dashpot: DashpotKind,
    release: Release,
) -> ImpactSystem {
    let mut sys = base.clone();
    let ks = base.slider_bed.law.stiffness();
    let ms = base.slider.mass;
    let delta_ref = base.slider.velocity * (ms / ks).sqrt();
    sys.slider_bed.law = law(slider_bed, ks, ms, delta_ref);
    sys.slider_bed.release = release;
    if let (Some(d), Some(c)) = (sys.damper.as_mut(), sys.bed_damper.as_mut()) {
        d.dashpot = dashpot;
        c.law = law(bed_damper, c.law.stiffness(), d.mass, delta_ref);
        c.release = release;
    }
    sys
}

/// Checks at every output sample that the mode agrees with the state: an open contact does
/// not overlap (unless the force rule released it and its law would pull), a closed one does
/// not pull under the force rule nor separate, the one-way dashpot acts exactly while the
/// damper returns. Records the largest violations.
struct Consistency<'a> {
    sys: &'a ImpactSystem,
    /// Largest overlap of an open contact and largest separation of a closed one (m).
    overlap_open: f64,
    gap_closed: f64,
    /// Largest pull of a closed contact under the force rule (N).
    pull: f64,
    /// Largest relative velocity against the dashpot's state (m/s).
    dashpot: f64,
    samples: usize,
}

impl Observer for Consistency<'_> {
    fn sample(&mut self, _t: f64, x: &[f64], mode: Mode) {
        let sys = self.sys;
        self.samples += 1;
        let m = sys.motions(x);
        for (ci, s) in [Switch::SliderBed, Switch::BedDamper]
            .into_iter()
            .enumerate()
        {
            if s == Switch::BedDamper && sys.damper.is_none() {
                continue;
            }
            let (d, r) = m[ci];
            let c = sys.contact(s);
            let force_rule = c.release == Release::Force && c.law.is_damped();
            let f = c.law.force(d, r);
            if mode.on(s) {
                self.gap_closed = self.gap_closed.max(-d);
                if force_rule {
                    self.pull = self.pull.max(-f);
                }
            } else if force_rule && f <= 0.0 {
                // Released by the force rule: it may still overlap while it would pull.
            } else {
                self.overlap_open = self.overlap_open.max(d);
            }
        }
        if let Some(d) = &sys.damper {
            if d.dashpot == DashpotKind::OneWay && d.damping > 0.0 {
                let r = m[2].1;
                let wrong = if mode.on(Switch::Dashpot) { r } else { -r };
                self.dashpot = self.dashpot.max(wrong);
            }
        }
    }
}

/// The whole matrix: every run's energy balance closes to 1e-6 of the blow's energy at the
/// end of the collision and at the end of the run (0.1 s: the collision, the damper's flight
/// and, on the lumped machines, its return), the modes agree with the state at 100 kHz
/// samples, the slider leaves no faster than it came, `0 ≤ E_p+/E_s− ≤ 1`, and the damper is
/// struck (its contact closes with a compressive force). The exact method does the linear
/// ones with the overlap rule to 1e-9 and agrees with dopri5 on the energy ratio to 1e-6.
#[test]
fn every_law_dashpot_and_release_balances_energy() {
    let laws = [Law::Linear, Law::Hertz, Law::HuntCrossley];
    let mut worst = (0.0f64, String::new());
    let mut runs = 0;
    for name in EXAMPLES {
        let base = system(name, &[]);
        assert!(base.damper.is_some(), "{name}: the examples have a damper");
        let vs = base.slider.velocity;
        let delta_ref = vs * (base.slider.mass / base.slider_bed.law.stiffness()).sqrt();
        for sb in laws {
            for bd in laws {
                for dashpot in [DashpotKind::OneWay, DashpotKind::TwoWay] {
                    for release in [Release::Force, Release::Overlap] {
                        let sys = variant(&base, sb, bd, dashpot, release);
                        let case = format!("{name}, {sb:?}/{bd:?}, {dashpot:?}, {release:?}");
                        let mut o = opts(Method::Dopri5, 0.1);
                        o.sample_rate = Some(1e5);
                        let mut obs = Consistency {
                            sys: &sys,
                            overlap_open: 0.0,
                            gap_closed: 0.0,
                            pull: 0.0,
                            dashpot: 0.0,
                            samples: 0,
                        };
                        let sol = integrate::solve(&sys, &o, &mut obs)
                            .unwrap_or_else(|e| panic!("{case}: {e}"));
                        assert_eq!(obs.samples, 10_001, "{case}");
                        let run = simulate(&sys, &opts(Method::Dopri5, 0.1), false)
                            .unwrap_or_else(|e| panic!("{case}: {e}"));
                        runs += 1;
                        let s = &run.summary;
                        let r_end = s.energy_balance_residual.expect("collision ends");
                        let r_run = s.energy_balance_residual_run_end;
                        assert!(
                            r_end <= 1e-6 && r_run <= 1e-6,
                            "{case}: {r_end:e} {r_run:e}"
                        );
                        if r_run > worst.0 {
                            worst = (r_run, case.clone());
                        }
                        // The same run with and without samples.
                        assert_eq!(sol.totals, run.solution.totals, "{case}");
                        // Physics of the blow.
                        let v_after = s.slider_rebound_velocity_m_per_s.unwrap();
                        assert!(v_after.abs() <= vs, "{case}: rebound {v_after} m/s");
                        let ratio = s.energy_ratio.unwrap();
                        assert!((0.0..=1.0).contains(&ratio), "{case}: E_p+/E_s- {ratio}");
                        assert!(
                            s.contact_time_bed_damper_s.unwrap() > 0.0
                                && s.peak_contact_force_bed_damper_n > 0.0,
                            "{case}: the damper was never struck"
                        );
                        // Modes consistent with the state (to round-off of the overlaps,
                        // 1e-6 of the peak contact force, 1e-9 of the strike speed).
                        let f_peak = s.peak_contact_force_slider_bed_n;
                        assert!(
                            obs.overlap_open <= 1e-6 * delta_ref,
                            "{case}: {}",
                            obs.overlap_open
                        );
                        assert!(
                            obs.gap_closed <= 1e-6 * delta_ref,
                            "{case}: {}",
                            obs.gap_closed
                        );
                        assert!(obs.pull <= 1e-6 * f_peak, "{case}: pull {} N", obs.pull);
                        assert!(obs.dashpot <= 1e-9 * vs, "{case}: dashpot {}", obs.dashpot);
                        // The exact method on the linear laws, both release rules (the
                        // elastic energy a contact released by the force rule takes with it
                        // counted as dissipated, `contact_energy_jump`).
                        if sb == Law::Linear && bd == Law::Linear {
                            let ex = simulate(&sys, &opts(Method::Exact, 0.1), false)
                                .unwrap_or_else(|e| panic!("{case} (exact): {e}"));
                            let e = &ex.summary;
                            assert!(
                                e.energy_balance_residual.unwrap() <= 1e-9
                                    && e.energy_balance_residual_run_end <= 1e-9,
                                "{case} (exact): {:e}",
                                e.energy_balance_residual_run_end
                            );
                            let d = (e.energy_ratio.unwrap() - ratio).abs();
                            assert!(d <= 1e-6, "{case}: exact vs dopri5 energy ratio {d:e}");
                        }
                    }
                }
            }
        }
    }
    assert_eq!(runs, 4 * 9 * 4);
    eprintln!("largest dopri5 residual {:e} ({})", worst.0, worst.1);
}

/// The reported failures: Hertz on the slider (K = 1e9 N/m^1.5) on the lumped machine
/// (residual 0.645) and on the machine without a base (the slider left at 47 m/s after a
/// 1.2 m/s strike), and Hertz on the damper only (the bed passed through the damper, whose
/// contact force read 0 N). Each now balances its energy over the example's 0.5 s.
#[test]
fn reported_hertz_cases_balance_energy() {
    let cases: [(&str, &[&str]); 3] = [
        (
            "paper-lumped",
            &[
                "contact.slider_bed.law=\"hertz\"",
                "contact.slider_bed.stiffness=1e9",
            ],
        ),
        (
            "paper-no-base",
            &[
                "contact.slider_bed.law=\"hertz\"",
                "contact.slider_bed.stiffness=1e9",
            ],
        ),
        (
            "paper-lumped",
            &[
                "contact.bed_damper.law=\"hertz\"",
                "contact.bed_damper.stiffness=5e10",
            ],
        ),
    ];
    for (name, sets) in cases {
        let sys = system(name, sets);
        let run = simulate(&sys, &opts(Method::Dopri5, 0.5), false)
            .unwrap_or_else(|e| panic!("{name} {sets:?}: {e}"));
        let s = &run.summary;
        assert!(
            s.energy_balance_residual_run_end <= 1e-6,
            "{name} {sets:?}: {:e}",
            s.energy_balance_residual_run_end
        );
        let v = s.slider_rebound_velocity_m_per_s.unwrap();
        assert!(v.abs() <= sys.slider.velocity, "{name} {sets:?}: {v}");
        assert!(s.peak_contact_force_bed_damper_n > 0.0, "{name} {sets:?}");
    }
}

/// On the lumped example with linear laws every channel's extremes from dopri5 (on its dense
/// output) agree with the exact method's (on the closed forms) to 1e-6 of the channel's peak,
/// and their times to 1e-6 s relative (plus 1 ns), wherever the extreme is significant (above
/// 1e-6 of the peak; the dashpot force's "maximum" is round-off at its first switch). The
/// run's peaks are identical for output rates of 100 Hz and 2 MHz.
#[test]
fn dopri5_peaks_match_exact_and_ignore_the_sample_rate() {
    let sys = system("paper-lumped", &[]);
    let ex = integrate::solve(&sys, &opts(Method::Exact, 0.5), &mut NoOutput).unwrap();
    let dp = integrate::solve(&sys, &opts(Method::Dopri5, 0.5), &mut NoOutput).unwrap();
    for c in CHANNELS {
        let (a, b) = (ex.totals.peaks.get(c), dp.totals.peaks.get(c));
        let scale = a.abs_peak();
        assert!(scale > 0.0, "{c:?}");
        for (va, ta, vb, tb, what) in [
            (a.max, a.t_max, b.max, b.t_max, "max"),
            (a.min, a.t_min, b.min, b.t_min, "min"),
        ] {
            assert!(
                (va - vb).abs() <= 1e-6 * scale,
                "{c:?} {what}: {va} vs {vb}"
            );
            if va.abs() > 1e-6 * scale {
                assert!(
                    (ta - tb).abs() <= 1e-6 * ta + 1e-9,
                    "{c:?} {what} at {ta} vs {tb}"
                );
            }
        }
    }
    let with_rate = |rate: f64| {
        let mut o = opts(Method::Dopri5, 0.1);
        o.sample_rate = Some(rate);
        simulate(&sys, &o, true).unwrap()
    };
    let (slow, fast) = (with_rate(100.0), with_rate(2e6));
    assert_eq!(slow.history.as_ref().unwrap().time_s.len(), 11);
    assert_eq!(fast.history.as_ref().unwrap().time_s.len(), 200_001);
    assert_eq!(slow.solution.totals.peaks, fast.solution.totals.peaks);
    assert_eq!(slow.summary.peaks, fast.summary.peaks);
}

/// Non-linear laws: the peak contact force is where its slope vanishes on the dense output,
/// with the value of the law there. Hertz on a rigid bed conserves the slider's energy, so
/// the peak force is `K δ_max^{3/2}` with `K δ_max^{5/2}/(5/2) = ½ m v²` to the accuracy of
/// the run when the bed is far heavier; here the check is the law's own: the peak of the
/// slider-bed channel equals `K δ^{3/2}` at the largest overlap the samples see, up to the
/// samples' resolution, and the channel's maximum time lies inside the contact.
#[test]
fn nonlinear_peaks_are_the_laws_values_inside_the_contact() {
    let base = system("paper-lumped", &[]);
    let sys = variant(
        &base,
        Law::Hertz,
        Law::HuntCrossley,
        DashpotKind::OneWay,
        Release::Force,
    );
    let mut o = opts(Method::Dopri5, 0.01);
    o.sample_rate = Some(1e7);
    let run = simulate(&sys, &o, true).unwrap();
    let h = run.history.unwrap();
    let sampled = h
        .contact_force_slider_bed_n
        .iter()
        .copied()
        .fold(0.0, f64::max);
    let e = *run.solution.totals.peaks.get(Channel::ContactSliderBed);
    // The located peak is at least the sampled one and within the samples' resolution
    // (0.1 µs of a ~0.4 ms contact: `½ f'' δt²` ≪ 1e-6 relative).
    assert!(e.max >= sampled * (1.0 - 1e-12), "{} vs {sampled}", e.max);
    assert!(e.max <= sampled * (1.0 + 1e-6), "{} vs {sampled}", e.max);
    let end = run.summary.collision_end_s.unwrap();
    assert!(
        e.t_max > 0.0 && e.t_max < end,
        "{} not in (0, {end})",
        e.t_max
    );
}

/// `Solution::path`: a knot at t = 0, at every mode change, and, on stretches where a closed
/// contact has a non-linear law, at every accepted step, all with the mode of the stretch
/// they start and the state there.
#[test]
fn path_has_knots_on_nonlinear_stretches() {
    let base = system("paper-lumped", &[]);
    for (sb, bd) in [(Law::Linear, Law::Linear), (Law::Hertz, Law::Linear)] {
        let sys = variant(&base, sb, bd, DashpotKind::OneWay, Release::Force);
        let sol = integrate::solve(&sys, &opts(Method::Dopri5, 0.01), &mut NoOutput).unwrap();
        let p = &sol.path;
        assert_eq!(p[0].t, 0.0);
        assert!(p.windows(2).all(|w| w[0].t <= w[1].t));
        let changes = p.windows(2).filter(|w| w[0].mode != w[1].mode).count();
        assert_eq!(changes, sol.events.len(), "{sb:?}");
        for e in &sol.events {
            assert!(
                p.iter().any(|k| k.t == e.t && k.mode == e.to),
                "{sb:?} {e:?}"
            );
        }
        let nonlinear_closed = |m: Mode| sb == Law::Hertz && m.on(Switch::SliderBed);
        let extra = p.windows(2).filter(|w| w[0].mode == w[1].mode).count();
        if sb == Law::Linear {
            assert_eq!(extra, 0, "linear stretches have no knots between switches");
            assert_eq!(p.len(), sol.events.len() + 1);
        } else {
            // Every knot inside a stretch belongs to one whose slider contact is Hertzian.
            assert!(extra > 10, "{extra}");
            assert!(p
                .windows(2)
                .filter(|w| w[0].mode == w[1].mode)
                .all(|w| nonlinear_closed(w[1].mode)));
        }
        // The knots are states of the run: the last one integrates to the final state
        // within the run (same mode), and each knot's state is finite.
        assert!(p.iter().all(|k| k.x.iter().all(|v| v.is_finite())));
    }
}

/// Long runs finish: 60 s of each example with dopri5 (the lumped machine's damper comes to
/// rest against its bed near 23.8 s; the run used to spin there forever), with the energy
/// balance closed to 1e-6.
#[test]
fn sixty_second_runs_finish() {
    for name in EXAMPLES {
        let sys = system(name, &[]);
        let run = simulate(&sys, &opts(Method::Dopri5, 60.0), false)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(run.solution.t_final, 60.0, "{name}");
        assert!(
            run.summary.energy_balance_residual_run_end <= 1e-6,
            "{name}: {:e}",
            run.summary.energy_balance_residual_run_end
        );
    }
}

/// A stiff bed-damper contact (1e10 N/m, a contact period of 0.12 ms against the slider's
/// 1 ms) used to leave dopri5 at t = 0 forever; it now runs with a balanced energy.
#[test]
fn stiff_contact_finishes() {
    for k in ["1e10", "1e11"] {
        let sys = system(
            "paper-lumped",
            &[&format!("contact.bed_damper.stiffness={k}")],
        );
        let run = simulate(&sys, &opts(Method::Dopri5, 0.5), false)
            .unwrap_or_else(|e| panic!("{k}: {e}"));
        assert!(
            run.summary.energy_balance_residual_run_end <= 1e-6,
            "{k}: {:e}",
            run.summary.energy_balance_residual_run_end
        );
        assert!(run.summary.peak_contact_force_bed_damper_n > 0.0);
    }
}
