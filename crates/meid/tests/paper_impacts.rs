//! The per-impact table of the paper's machine against closed forms: a two-body linear
//! contact (contact time, peak, restitution, impulse, dissipation), the slider's and a free
//! damper's momentum changes, and the same rows from the exact method and dopri5.

use meid::analysis::impacts::{impacts, totals};
use meid::impact::{Absorber, Contact, ContactLaw, ImpactSystem, Release, Slider, Switch};
use meid::integrate::network::ImpactRow;
use meid::integrate::{self, Method, NoOutput, Options, Solution};
use meid::modal::ModalModel;
use meid::model::{Case, Model};
use std::f64::consts::PI;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

fn run_opts(method: Method, duration: f64) -> Options {
    Options {
        method,
        duration,
        sample_rate: None,
        rtol: 1e-10,
        atol: 1e-16,
        ..Options::default()
    }
}

fn example(overrides: &[&str], case: Case) -> ImpactSystem {
    let ex =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml");
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Model::from_file(&ex, &o)
        .unwrap()
        .impact_system(case)
        .unwrap()
}

/// The state of the run's path at time `t` (a switch, to round-off).
fn state_at(sol: &Solution, t: f64) -> &[f64] {
    let p = sol
        .path
        .iter()
        .min_by(|a, b| (a.t - t).abs().total_cmp(&(b.t - t).abs()))
        .unwrap();
    assert!(
        (p.t - t).abs() <= 1e-15 * t.max(1e-3),
        "no path point at {t}"
    );
    &p.x
}

/// Slider `m1` at `v0` against a free body `m2` through a linear contact `(k, c)` released
/// at zero overlap.
fn two_body(m1: f64, m2: f64, v0: f64, k: f64, c: f64, method: Method) -> Vec<ImpactRow> {
    let law = ContactLaw::Linear {
        stiffness: k,
        damping: c,
    };
    two_body_law(m1, m2, v0, law, method)
}

fn two_body_law(m1: f64, m2: f64, v0: f64, law: ContactLaw, method: Method) -> Vec<ImpactRow> {
    let mut s = ModalModel::with_damping_ratios(vec![0.0], &[0.0]).unwrap();
    s.points.insert("b".into(), vec![1.0 / m2.sqrt()]);
    let contact = Contact {
        law,
        release: Release::Overlap,
    };
    let slider = Slider {
        mass: m1,
        velocity: v0,
    };
    let sys = ImpactSystem::new(&s, "b", None, "b", slider, contact, Absorber::None).unwrap();
    let sol = integrate::solve(&sys, &run_opts(method, 0.02), &mut NoOutput).unwrap();
    impacts(&sys, &sol).unwrap()
}

#[test]
fn a_two_body_linear_contact_gives_the_closed_form_row() {
    let (m1, m2, v0, k): (f64, f64, f64, f64) = (1.0, 3.0, 1.5, 1.0e6);
    let mu = m1 * m2 / (m1 + m2);
    for (zeta, method, tol) in [
        (0.0_f64, Method::Exact, 1e-9),
        (0.1, Method::Exact, 1e-9),
        (0.1, Method::Dopri5, 1e-6),
    ] {
        let c = 2.0 * zeta * (k * mu).sqrt();
        let rows = two_body(m1, m2, v0, k, c, method);
        assert_eq!(rows.len(), 1, "{rows:?}");
        let r = &rows[0];
        let wn = (k / mu).sqrt();
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        let e = (-zeta * PI / (1.0 - zeta * zeta).sqrt()).exp();
        assert_eq!(r.contact, "slider_bed");
        assert_eq!(r.start_s, 0.0);
        assert!(rel(r.approach_velocity_m_per_s, v0) < 1e-12, "{r:?}");
        assert!(rel(r.duration_s, PI / wd) < tol, "{zeta} {method:?} {r:?}");
        let exit = r.exit_velocity_m_per_s.unwrap();
        assert!(rel(exit, e * v0) < tol, "{zeta} {method:?} {r:?}");
        assert!(rel(r.restitution.unwrap(), e) < tol, "{r:?}");
        // The relative motion is that of a mass μ on k, c: the impulse is μ v₀ (1 + e).
        assert!(rel(r.impulse_n_s, mu * v0 * (1.0 + e)) < tol, "{r:?}");
        let lost = 0.5 * mu * v0 * v0 * (1.0 - e * e);
        if zeta == 0.0 {
            // Undamped: peak √(kμ) v₀ at a quarter of the contact, nothing dissipated.
            assert!(
                rel(r.peak_force_n.unwrap(), (k * mu).sqrt() * v0) < tol,
                "{r:?}"
            );
            assert!(rel(r.peak_time_s, PI / (2.0 * wn)) < 1e-9, "{r:?}");
            assert!(r.dissipated_j.abs() < 1e-12 * lost.max(1.0), "{r:?}");
        } else {
            assert!(rel(r.dissipated_j, lost) < tol, "{zeta} {method:?} {r:?}");
        }
    }
}

#[test]
fn the_slider_bed_impulse_is_the_slider_momentum_change() {
    // The bare lumped machine: the slider's only force is the contact's, so each closing's
    // impulse is m_s (v_in − v_out), from the slider's velocities at the two switches.
    let sys = example(&[], Case::NoDamper);
    let sol = integrate::solve(&sys, &run_opts(Method::Exact, 0.05), &mut NoOutput).unwrap();
    let rows = impacts(&sys, &sol).unwrap();
    let r = &rows[0];
    assert_eq!(r.contact, "slider_bed");
    let nd = sys.dofs();
    let vs = |x: &[f64]| x[nd + sys.slider_index()];
    let end = r.start_s + r.duration_s;
    let (x_in, x_out) = (state_at(&sol, r.start_s), state_at(&sol, end));
    let m_s = sys.slider.mass;
    let dp = m_s * (vs(x_in) - vs(x_out));
    assert!(rel(r.impulse_n_s, dp) < 1e-9, "{} vs {dp}", r.impulse_n_s);
    // The bed is at rest at the strike: the approach velocity is the slider's.
    assert!(rel(r.approach_velocity_m_per_s, sys.slider.velocity) < 1e-12);
    let v_rel = |x: &[f64]| sys.relative_motion(Switch::SliderBed, x).1;
    let e = -v_rel(x_out) / v_rel(x_in);
    assert!(rel(r.restitution.unwrap(), e) < 1e-12, "{r:?} vs {e}");
    assert_eq!(r.dissipated_j, 0.0);
    // The collision's contact time and peak are the first closing's.
    let end_totals = sol.collision_end.as_ref().unwrap().totals;
    assert!(rel(r.duration_s, end_totals.closed_time[0]) < 1e-12);
    assert!(
        rel(r.peak_force_n.unwrap(), end_totals.peak_force(0)) < 1e-9,
        "{r:?}"
    );
}

#[test]
fn a_free_damper_takes_the_bed_damper_impulses_as_momentum() {
    // Without its spring and dashpot the damper is a free mass: the bed-damper impulses add
    // up to its momentum change m_d Δż_d, closing by closing and over the run.
    let sys = example(
        &["damper.stiffness=0.0", "damper.damping=0.0"],
        Case::Damper,
    );
    let sol = integrate::solve(&sys, &run_opts(Method::Exact, 0.02), &mut NoOutput).unwrap();
    let rows = impacts(&sys, &sol).unwrap();
    let nd = sys.dofs();
    let m_d = sys.damper.unwrap().mass;
    let vd = |x: &[f64]| x[nd + sys.damper_index()];
    let bd: Vec<&ImpactRow> = rows.iter().filter(|r| r.contact == "bed_damper").collect();
    assert!(!bd.is_empty());
    let mut sum = 0.0;
    for r in &bd {
        let x_in = state_at(&sol, r.start_s);
        let x_out = state_at(&sol, r.start_s + r.duration_s);
        let dp = m_d * (vd(x_out) - vd(x_in));
        assert!(rel(r.impulse_n_s, dp) < 1e-9, "{r:?} vs {dp}");
        sum += dp;
    }
    let t = totals(&sys, &rows);
    assert_eq!(t[1].contact, "bed_damper");
    assert_eq!(t[1].impacts, bd.len());
    assert!(rel(t[1].impulse_n_s, sum) < 1e-9);
    // The damper started at rest and flies off after its last closing.
    assert!(rel(t[1].impulse_n_s, m_d * vd(&sol.x_final)) < 1e-9);
}

#[test]
fn exact_and_dopri5_give_the_same_rows() {
    let sys = example(&[], Case::Damper);
    let rows = |method| {
        let sol = integrate::solve(&sys, &run_opts(method, 0.05), &mut NoOutput).unwrap();
        impacts(&sys, &sol).unwrap()
    };
    let (a, b) = (rows(Method::Exact), rows(Method::Dopri5));
    assert_eq!(a.len(), b.len(), "{a:?}\n{b:?}");
    assert!(a.iter().any(|r| r.contact == "bed_damper"));
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.contact, y.contact);
        let close = |p: f64, q: f64, scale: f64| (p - q).abs() <= 1e-6 * scale;
        assert!(close(x.start_s, y.start_s, 1e-3), "{x:?}\n{y:?}");
        assert!(close(x.duration_s, y.duration_s, 1e-3), "{x:?}\n{y:?}");
        assert!(
            close(x.impulse_n_s, y.impulse_n_s, x.impulse_n_s.abs()),
            "{x:?}\n{y:?}"
        );
        assert!(
            close(
                x.peak_force_n.unwrap(),
                y.peak_force_n.unwrap(),
                x.peak_force_n.unwrap()
            ),
            "{x:?}\n{y:?}"
        );
        let e = |r: &ImpactRow| r.restitution.unwrap_or(0.0);
        assert!(close(e(x), e(y), 1.0), "{x:?}\n{y:?}");
    }
}

#[test]
fn a_hertz_contact_row_comes_from_the_interpolated_path() {
    // dopri5 on a Hertz contact (f = k δ^{3/2}): elastic, so the exit speed is v₀, the impulse
    // 2 μ v₀ and the peak k δ_max^{3/2} with ½ μ v₀² = (2/5) k δ_max^{5/2}; the impulse and peak
    // come from the interpolant between dopri5's steps (the peak at its quadrature nodes).
    let (m1, m2, v0, k): (f64, f64, f64, f64) = (1.0, 3.0, 1.5, 1.0e9);
    let mu = m1 * m2 / (m1 + m2);
    let rows = two_body_law(
        m1,
        m2,
        v0,
        ContactLaw::Hertz { stiffness: k },
        Method::Dopri5,
    );
    assert_eq!(rows.len(), 1, "{rows:?}");
    let r = &rows[0];
    let d_max = (5.0 * mu * v0 * v0 / (4.0 * k)).powf(0.4);
    assert!(rel(r.exit_velocity_m_per_s.unwrap(), v0) < 1e-6, "{r:?}");
    assert!(rel(r.impulse_n_s, 2.0 * mu * v0) < 1e-5, "{r:?}");
    assert!(
        rel(r.peak_force_n.unwrap(), k * d_max.powf(1.5)) < 1e-3,
        "{r:?}"
    );
    assert!(r.dissipated_j.abs() < 1e-9, "{r:?}");
}
