//! The impact engine against closed forms (shared/notes/closed-forms.md).

use meid::impact::{
    Absorber, Contact, ContactLaw, Damper, DashpotKind, ImpactSystem, Release, Slider, Switch,
};
use meid::integrate::{self, Method, NoOutput, Options};
use meid::modal::ModalModel;
use std::f64::consts::PI;

/// A free rigid body of mass `m` as a one-mode modal model (ω = 0, ψ = 1/√m).
fn free_body(m: f64) -> ModalModel {
    let mut s = ModalModel::with_damping_ratios(vec![0.0], &[0.0]).unwrap();
    s.points.insert("b".into(), vec![1.0 / m.sqrt()]);
    s
}

fn linear(k: f64, c: f64, release: Release) -> Contact {
    Contact {
        law: ContactLaw::Linear {
            stiffness: k,
            damping: c,
        },
        release,
    }
}

/// The engines checked: `exact` as run by default (Taylor steps first, closed forms for long
/// stretches), `exact` with closed forms only, and `dopri5`.
#[derive(Debug, Clone, Copy)]
enum Engine {
    Taylor,
    ClosedForm,
    Dopri5,
}

fn opts(engine: Engine) -> Options {
    let (method, taylor) = match engine {
        Engine::Taylor => (Method::Exact, integrate::exact::TAYLOR_STEPS_PER_MODE),
        Engine::ClosedForm => (Method::Exact, 0),
        Engine::Dopri5 => (Method::Dopri5, 0),
    };
    Options {
        method,
        taylor_steps_per_mode: taylor,
        duration: 0.05,
        sample_rate: None,
        stop_at_collision_end: true,
        rtol: 1e-8,
        ..Options::default()
    }
}

/// The run used the form the engine names: Taylor steps, or closed forms only.
fn check_engine(engine: Engine, sol: &integrate::Solution) {
    match engine {
        Engine::Taylor => assert!(sol.taylor_steps > 0, "no Taylor step taken"),
        Engine::ClosedForm | Engine::Dopri5 => assert_eq!(sol.taylor_steps, 0),
    }
}

struct TwoBody {
    t: f64,
    v1: f64,
    v2: f64,
    peak: f64,
}

fn two_body(m1: f64, m2: f64, k: f64, c: f64, release: Release, method: Engine) -> TwoBody {
    two_body_with(m1, m2, 1.0, linear(k, c, release), method)
}

/// Slider `m1` at `v0` against a free body `m2` through `contact`, to the end of the collision.
fn two_body_with(m1: f64, m2: f64, v0: f64, contact: Contact, method: Engine) -> TwoBody {
    let s = free_body(m2);
    let sys = ImpactSystem::new(
        &s,
        "b",
        None,
        "b",
        Slider {
            mass: m1,
            velocity: v0,
        },
        contact,
        Absorber::None,
    )
    .unwrap();
    let sol = integrate::solve(&sys, &opts(method), &mut NoOutput).unwrap();
    check_engine(method, &sol);
    let end = sol.collision_end.expect("collision must end");
    let nd = sys.dofs();
    let v1 = end.x[nd + sys.slider_index()];
    let v2 = end.x[nd] / m2.sqrt();
    TwoBody {
        t: end.t,
        v1,
        v2,
        peak: end.totals.peak_force(0),
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn two_bodies_undamped_exact() {
    // m1 = 1 kg, m2 = 3 kg, k = 1e6 N/m, v0 = 1 m/s: T = 2.7207 ms, F_max = 866.0 N, share 0.75.
    let (m1, m2, k) = (1.0, 3.0, 1.0e6);
    let mu = m1 * m2 / (m1 + m2);
    for engine in [Engine::Taylor, Engine::ClosedForm] {
        let r = two_body(m1, m2, k, 0.0, Release::Overlap, engine);
        let t_exact = PI / (k / mu).sqrt();
        assert!(
            rel(r.t, t_exact) < 1e-9,
            "contact time {} vs {}",
            r.t,
            t_exact
        );
        assert!(
            rel(r.peak, (k * mu).sqrt()) < 1e-9,
            "peak {} vs {}",
            r.peak,
            (k * mu).sqrt()
        );
        // Elastic: v1 = (m1 − m2)/(m1 + m2), v2 = 2 m1/(m1 + m2); share to m2 = 4 m1 m2/(m1+m2)².
        assert!(rel(r.v1, (m1 - m2) / (m1 + m2)) < 1e-9, "v1 {}", r.v1);
        let share = m2 * r.v2 * r.v2 / m1;
        assert!(rel(share, 0.75) < 1e-9, "share {share}");
    }
}

#[test]
fn two_bodies_damped_overlap_release() {
    let (m1, m2, k, zeta): (f64, f64, f64, f64) = (1.0, 3.0, 1.0e6, 0.1);
    let mu = m1 * m2 / (m1 + m2);
    let c = 2.0 * zeta * (k * mu).sqrt();
    let wd = (k / mu).sqrt() * (1.0 - zeta * zeta).sqrt();
    let e_exact = (-zeta * PI / (1.0 - zeta * zeta).sqrt()).exp();
    for (method, tol) in [
        (Engine::Taylor, 1e-9),
        (Engine::ClosedForm, 1e-9),
        (Engine::Dopri5, 1e-6),
    ] {
        let r = two_body(m1, m2, k, c, Release::Overlap, method);
        assert!(
            rel(r.t, PI / wd) < tol,
            "{method:?}: T {} vs {}",
            r.t,
            PI / wd
        );
        let e = (r.v2 - r.v1) / 1.0;
        assert!(rel(e, e_exact) < tol, "{method:?}: e {e} vs {e_exact}");
        let share = m2 * r.v2 * r.v2 / m1;
        let share_exact = (1.0 + e_exact).powi(2) * m1 * m2 / (m1 + m2).powi(2);
        assert!(
            rel(share, share_exact) < tol,
            "{method:?}: share {share} vs {share_exact}"
        );
    }
}

#[test]
fn two_bodies_damped_force_release() {
    // Release at zero force: w_d t_F = π − atan2(2ζ√(1−ζ²), 1 − 2ζ²).
    let (m1, m2, k, zeta): (f64, f64, f64, f64) = (1.0, 3.0, 1.0e6, 0.1);
    let mu = m1 * m2 / (m1 + m2);
    let c = 2.0 * zeta * (k * mu).sqrt();
    let wn = (k / mu).sqrt();
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let tf = (PI - (2.0 * zeta * (1.0 - zeta * zeta).sqrt()).atan2(1.0 - 2.0 * zeta * zeta)) / wd;
    // Relative velocity at t_F from the damped free response δ = (v0/ω_d) e^{−ζω_n t} sin ω_d t.
    let dv = (-zeta * wn * tf).exp() * ((wd * tf).cos() - zeta * wn / wd * (wd * tf).sin());
    let e_exact = -dv;
    for (method, tol) in [
        (Engine::Taylor, 1e-9),
        (Engine::ClosedForm, 1e-9),
        (Engine::Dopri5, 1e-6),
    ] {
        let r = two_body(m1, m2, k, c, Release::Force, method);
        assert!(rel(r.t, tf) < tol, "{method:?}: T {} vs {}", r.t, tf);
        let e = r.v2 - r.v1;
        assert!(rel(e, e_exact) < tol, "{method:?}: e {e} vs {e_exact}");
    }
    assert!(
        (e_exact - 0.744).abs() < 1e-3,
        "closed-form note says about 0.744, got {e_exact}"
    );
}

#[test]
fn two_bodies_dopri5_undamped() {
    let (m1, m2, k) = (1.0, 3.0, 1.0e6);
    let mu = m1 * m2 / (m1 + m2);
    let r = two_body(m1, m2, k, 0.0, Release::Overlap, Engine::Dopri5);
    assert!(rel(r.t, PI / (k / mu).sqrt()) < 1e-6);
    assert!(rel(r.peak, (k * mu).sqrt()) < 1e-6, "peak {}", r.peak);
    assert!(rel(r.v1, -0.5) < 1e-6);
}

/// m1 = m3 = m, m2 = 2m/3, equal contact stiffness: complete momentum exchange,
/// final velocities (0, 0, v0), both contacts open at t = π √(m/k).
#[test]
fn three_body_chain_complete_exchange() {
    let (m, k, v0) = (2.0, 5.0e5, 1.3);
    let s = free_body(2.0 * m / 3.0);
    let damper = Damper {
        mass: m,
        stiffness: 0.0,
        damping: 0.0,
        dashpot: DashpotKind::OneWay,
    };
    for (method, tol) in [
        (Engine::Taylor, 1e-9),
        (Engine::ClosedForm, 1e-9),
        (Engine::Dopri5, 1e-6),
    ] {
        let sys = ImpactSystem::new(
            &s,
            "b",
            None,
            "b",
            Slider {
                mass: m,
                velocity: v0,
            },
            linear(k, 0.0, Release::Overlap),
            Absorber::Damper(damper, linear(k, 0.0, Release::Overlap)),
        )
        .unwrap();
        let sol = integrate::solve(&sys, &opts(method), &mut NoOutput).unwrap();
        check_engine(method, &sol);
        let end = sol.collision_end.expect("collision must end");
        let t_exact = PI * (m / k).sqrt();
        assert!(
            rel(end.t, t_exact) < tol,
            "{method:?}: t {} vs {}",
            end.t,
            t_exact
        );
        let nd = sys.dofs();
        let v1 = end.x[nd + sys.slider_index()];
        let v2 = end.x[nd] / (2.0 * m / 3.0_f64).sqrt();
        let v3 = end.x[nd + sys.damper_index()];
        assert!(
            v1.abs() < tol * v0 && v2.abs() < tol * v0,
            "{method:?}: v1 {v1} v2 {v2}"
        );
        assert!(rel(v3, v0) < tol, "{method:?}: v3 {v3}");
        // Both contacts open at the same instant: one event with both switching.
        let last = sol.events.last().unwrap();
        assert!(last.from.on(Switch::SliderBed) && last.from.on(Switch::BedDamper));
    }
}

/// Hertz contact `f = K δ^{3/2}` between two free bodies (dopri5): energy
/// `½ μ v₀² = (2/5) K δ_max^{5/2}` gives `δ_max = (5 μ v₀² / (4K))^{2/5}`, the peak force
/// `K δ_max^{3/2}`, the contact time `2.9432 δ_max / v₀` (`2 ∫₀¹ dx / √(1 − x^{5/2})`; Johnson,
/// Contact Mechanics §11.4) and an elastic exchange (v₂ = 2 m₁ v₀ /(m₁ + m₂)).
#[test]
fn two_bodies_hertz_dopri5() {
    let (m1, m2, k, v0) = (1.0, 3.0, 1.0e9, 1.0);
    let r = two_body_with(
        m1,
        m2,
        v0,
        Contact {
            law: ContactLaw::Hertz { stiffness: k },
            release: Release::Force,
        },
        Engine::Dopri5,
    );
    let mu = m1 * m2 / (m1 + m2);
    let d_max = (5.0 * mu * v0 * v0 / (4.0 * k)).powf(0.4);
    // ∫₀¹ (1 − x^{5/2})^{-1/2} dx = Γ(7/5) Γ(1/2) / Γ(9/10) = 1.4716375921623.
    let t_c = 2.0 * 1.471_637_592_162_3 * d_max / v0;
    let f_max = k * d_max.powf(1.5);
    assert!(rel(r.peak, f_max) < 1e-6, "peak {} vs {f_max}", r.peak);
    assert!(rel(r.t, t_c) < 1e-6, "contact time {} vs {t_c}", r.t);
    let v2 = 2.0 * m1 * v0 / (m1 + m2);
    assert!(rel(r.v2, v2) < 1e-6, "v2 {} vs {v2}", r.v2);
}
