//! A constant force on the slider (`slider.force`): the slider bounces on a spring-mounted,
//! damped bed with shrinking flights and comes to rest on it (issue 10, part 5: "a closed
//! form with an accumulation point").
//!
//! The system: a bed of mass `m_b` on a spring `k` to ground with modal damping ratio `ζ`, a
//! slider of mass `m` pushed towards the bed by `F`, a linear damped contact `(K, C)`. In flight
//! the two bodies are uncoupled and each motion is a closed form:
//!
//! ```text
//! z_s(s) = z₀ + v₀ s + F s²/(2m)                        (parabola)
//! u_b(s) = e^{−ζωs} (u₀ cos ω_d s + (v_b0 + ζω u₀)/ω_d sin ω_d s)   (damped free vibration)
//! ```
//!
//! so each landing time is the first root of `z_s − u_b`, found here by a scan and Newton on
//! these expressions from meid's state at the separation, and compared with meid's event.
//! With a damped contact there is a threshold landing speed (∝ F) below which the force never
//! returns to zero: the bounces end after finitely many, at a computable last landing, and the
//! system settles at the static state `f_bs = F`, `u_b = F/k`, `z_s = F/k + F/K`.

use meid::analysis::simulate;
use meid::impact::{Channel, ChannelMap, Mode, Switch};
use meid::integrate::{self, Method, NoOutput};
use meid::model::{Case, Model};

const M_BED: f64 = 10.0;
const K_BED: f64 = 1.0e6;
const ZETA: f64 = 0.02;
const M_S: f64 = 1.0;
const V_S: f64 = 0.5;
const FORCE: f64 = 50.0;
const K_C: f64 = 1.0e7;
const C_C: f64 = 60.0;

fn model(release: &str, overrides: &[String]) -> Model {
    let text = format!(
        r#"
name = "bouncing slider"
[structure.lumped]
damping_ratios = {ZETA}
masses = [{{ name = "bed", mass = {M_BED} }}]
springs = [{{ nodes = ["bed", "ground"], stiffness = {K_BED} }}]
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = {M_S}
velocity = {V_S}
force = {FORCE}
[contact.slider_bed]
stiffness = {K_C}
damping = {C_C}
release = "{release}"
[simulation]
duration = 3.0
sample_rate = 1000.0
"#
    );
    Model::from_text("bouncing.toml", text, overrides).expect("model")
}

/// The landing after a separation at state `(z0, v0, u0, vb0)`: the first `s > 0` with
/// `z_s(s) = u_b(s)` on the closed forms above (scan at 1/200 of the bed period for the first
/// sign change of `u_b − z_s` from positive, then bisection and Newton to round-off).
fn landing(z0: f64, v0: f64, u0: f64, vb0: f64) -> f64 {
    let w = (K_BED / M_BED).sqrt();
    let wd = w * (1.0 - ZETA * ZETA).sqrt();
    let a = F_ACC;
    let gap = |s: f64| -> (f64, f64) {
        let e = (-ZETA * w * s).exp();
        let (sn, cs) = (wd * s).sin_cos();
        let b = (vb0 + ZETA * w * u0) / wd;
        let u = e * (u0 * cs + b * sn);
        let du = e * ((-ZETA * w) * (u0 * cs + b * sn) + wd * (-u0 * sn + b * cs));
        let z = z0 + v0 * s + 0.5 * a * s * s;
        let dz = v0 + a * s;
        (u - z, du - dz)
    };
    let h = 2.0 * std::f64::consts::PI / w / 200.0;
    // Start just past the separation. Under the overlap rule the gap opens from zero; under
    // the force rule the contact lets go while still overlapping (K δ + C δ̇ = 0 at δ > 0), so
    // the flight starts with the gap closing to zero first: skip to where it is open.
    let mut lo = 1e-9 * h;
    while gap(lo).0 <= 0.0 {
        lo += h / 64.0;
        assert!(lo < h, "the gap does not open after the separation");
    }
    let mut hi = lo + h;
    while gap(hi).0 > 0.0 {
        lo = hi;
        hi += h;
        assert!(hi < 100.0, "no landing");
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if gap(mid).0 > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-15 * hi {
            break;
        }
    }
    let mut s = 0.5 * (lo + hi);
    for _ in 0..3 {
        let (g, d) = gap(s);
        s -= g / d;
    }
    s
}

const F_ACC: f64 = FORCE / M_S;

/// (separation time, landing time) pairs of a run, from its events.
fn flights(sol: &integrate::Solution) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut open_at = None;
    for (i, e) in sol.events.iter().enumerate() {
        let (was, is) = (e.from.on(Switch::SliderBed), e.to.on(Switch::SliderBed));
        if was && !is {
            open_at = Some(i);
        }
        if !was && is {
            if let Some(j) = open_at.take() {
                out.push((j, i));
            }
        }
    }
    out
}

/// Every flight of the exact run lands where the closed forms say (1e-9 relative to the
/// flight time, from meid's state at the separation), the bounces stop after finitely many
/// (a resting contact from the last landing on), and the run ends at the static state to 1e-9.
#[test]
fn flights_land_on_the_closed_form_and_the_slider_comes_to_rest() {
    for release in ["force", "overlap"] {
        let m = model(release, &[]);
        let sys = m.impact_system(Case::AsSpecified).expect("system");
        let mut o = m.options();
        o.method = Method::Exact;
        o.duration = 8.0;
        o.sample_rate = None;
        let sol = integrate::solve(&sys, &o, &mut NoOutput).expect("run");
        assert!(
            (sol.t_final - 8.0).abs() < 1e-12,
            "{release}: ended at {}",
            sol.t_final
        );
        let fl = flights(&sol);
        assert!(fl.len() >= 3, "{release}: {} flights", fl.len());
        let nd = sys.dofs();
        let (zs, bed) = (sys.slider_index(), 0);
        let phi = sys.points.bed_contact[0];
        let mut worst = 0.0_f64;
        for &(j, i) in &fl {
            let p = sol
                .path
                .iter()
                .find(|p| p.t == sol.events[j].t && p.mode == sol.events[j].to)
                .expect("path point at the separation");
            let x = &p.x;
            let s = landing(x[zs], x[nd + zs], phi * x[bed], phi * x[nd + bed]);
            let meid_s = sol.events[i].t - sol.events[j].t;
            let rel = (meid_s - s).abs() / s;
            worst = worst.max(rel);
            assert!(
                rel <= 1e-9,
                "{release}: flight from {} s: meid {meid_s} s, closed form {s} s ({rel:e})",
                p.t
            );
        }
        // The last landing starts a resting contact: no separation after it.
        let last = sol.events.last().expect("events");
        assert!(last.to.on(Switch::SliderBed), "{release}: ends in flight");
        let t_rest = sol.events[fl.last().expect("a flight").1].t;
        println!(
            "{release}: {} flights, worst landing error {worst:.2e}, last landing (rest) at {t_rest:.9} s",
            fl.len()
        );
        assert!(t_rest < 1.0, "{release}: last landing at {t_rest}");
        // The static state (the slowest transient, the bed's, has decayed by
        // e^{−ζω(8 s − t_rest)} ≈ e^{−48} by 8 s).
        let v = ChannelMap::new(&sys).values(&sys, sol.mode_final, &sol.x_final);
        let f_bs = v[Channel::ContactSliderBed.index()];
        let u_b = v[Channel::BedDisplacement.index()];
        assert!(
            (f_bs - FORCE).abs() <= 1e-9 * FORCE,
            "{release}: contact force {f_bs}"
        );
        assert!(
            (u_b - FORCE / K_BED).abs() <= 1e-9 * FORCE / K_BED,
            "{release}: bed at {u_b}"
        );
        let z = sol.x_final[zs];
        let z_static = FORCE / K_BED + FORCE / K_C;
        assert!(
            (z - z_static).abs() <= 1e-9 * z_static,
            "{release}: slider at {z}"
        );
        assert_eq!(sol.mode_final, Mode(Mode::SLIDER_BED), "{release}");
    }
}

/// dopri5 reproduces the exact run's bounces (same number, landing times to 1e-6 s) and
/// both complete.
#[test]
fn dopri5_bounces_like_the_exact_run() {
    for release in ["force", "overlap"] {
        let m = model(release, &[]);
        let sys = m.impact_system(Case::AsSpecified).expect("system");
        let mut o = m.options();
        o.sample_rate = None;
        o.duration = 3.0;
        o.method = Method::Exact;
        let ex = integrate::solve(&sys, &o, &mut NoOutput).expect("exact");
        o.method = Method::Dopri5;
        let dp = integrate::solve(&sys, &o, &mut NoOutput).expect("dopri5");
        let (fe, fd) = (flights(&ex), flights(&dp));
        assert_eq!(fe.len(), fd.len(), "{release}: flights");
        for (a, b) in fe.iter().zip(&fd) {
            let (ta, tb) = (ex.events[a.1].t, dp.events[b.1].t);
            assert!((ta - tb).abs() < 1e-6, "{release}: landing {ta} vs {tb}");
        }
    }
}

/// The energy balance with the force's work `W_F = F (z_s − z_s0)`: within 1e-9 (exact) and
/// 1e-6 (dopri5) over the bounces, and the summary states the work and the ratio's
/// denominator `E_s− + W_F+`.
#[test]
fn energy_balance_counts_the_work_of_the_force() {
    for release in ["force", "overlap"] {
        for method in [Method::Exact, Method::Dopri5] {
            let m = model(release, &[]);
            let sys = m.impact_system(Case::AsSpecified).expect("system");
            let mut o = m.options();
            o.method = method;
            let run = simulate(&sys, &o, true).expect("run");
            let s = &run.summary;
            let bound = if method == Method::Exact { 1e-9 } else { 1e-6 };
            assert!(
                s.energy_balance_residual_run_end <= bound,
                "{release} {method:?}: {}",
                s.energy_balance_residual_run_end
            );
            assert_eq!(s.slider_force_n, FORCE);
            let e_s = 0.5 * M_S * V_S * V_S;
            let w = s.force_work_after_j.expect("the first contact ends");
            assert_eq!(s.energy_input_j, Some(e_s + w));
            // At rest the force has done W_F = F z_s = F (F/k + F/K).
            let z_static = FORCE / K_BED + FORCE / K_C;
            assert!(
                (s.force_work_run_end_j - FORCE * z_static).abs() < 1e-6 * FORCE * z_static,
                "{release} {method:?}: W_F = {}",
                s.force_work_run_end_j
            );
            // The recorded dissipation history ends at E_s− + W_F − stored.
            let h = run.history.as_ref().expect("history");
            let d_end = *h.dissipated_j.last().expect("samples");
            assert!(
                (d_end - run.solution.totals.dissipated).abs() <= 10.0 * bound * (e_s + w.abs()),
                "{release} {method:?}: {d_end} vs {}",
                run.solution.totals.dissipated
            );
        }
    }
}

/// `slider.force` must be finite and ≥ 0: the error names the field.
#[test]
fn invalid_forces_are_refused_with_the_field() {
    for bad in ["-1", "nan", "inf"] {
        let e = Model::from_text("bouncing.toml", toml_with_force(bad), &[])
            .err()
            .unwrap_or_else(|| panic!("force = {bad} accepted"))
            .to_string();
        assert!(e.contains("slider.force"), "{bad}: {e}");
        assert!(e.contains(">= 0"), "{bad}: {e}");
    }
}

fn toml_with_force(f: &str) -> String {
    format!(
        r#"
[structure.lumped]
masses = [{{ name = "bed", mass = 10.0 }}]
springs = [{{ nodes = ["bed", "ground"], stiffness = 1e6 }}]
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = 1.0
velocity = 0.5
force = {f}
[contact.slider_bed]
stiffness = 1e7
"#
    )
}

/// A constant force with a free (0 Hz) structure is refused, naming the field; the exact
/// spectrum refuses a forced system, naming the field.
#[test]
fn forced_runs_refuse_what_they_cannot_represent() {
    let free = r#"
[structure.modal]
frequencies_hz = [0.0, 50.0]
shapes = { bed = [0.3, 0.2] }
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = 1.0
velocity = 0.5
force = 10.0
[contact.slider_bed]
stiffness = 1e7
"#;
    let e = Model::from_text("free.toml", free.to_string(), &[])
        .map(|_| ())
        .expect_err("refused")
        .to_string();
    assert!(
        e.contains("slider.force") && e.contains("rigid-body"),
        "{e}"
    );
    let m = model("force", &[]);
    let sys = m.impact_system(Case::AsSpecified).expect("system");
    let e = meid::analysis::esd::check_unforced(&sys)
        .map(|_| ())
        .expect_err("refused")
        .to_string();
    assert!(e.contains("slider.force"), "{e}");
}

/// The lumped example under a 100 N slider force runs 60 s with both methods: no chatter stop,
/// no zero-length loop, the energy balance (with the force's work) within its bound.
#[test]
fn sixty_seconds_of_the_lumped_example_under_a_force() {
    let path = format!(
        "{}/../../examples/paper-lumped.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let m = Model::from_file(path.as_ref(), &["slider.force=100".to_string()]).expect("example");
    let sys = m.impact_system(Case::Damper).expect("system");
    for method in [Method::Exact, Method::Dopri5] {
        let mut o = m.options();
        o.method = method;
        o.duration = 60.0;
        o.sample_rate = None;
        let run = simulate(&sys, &o, false).unwrap_or_else(|e| panic!("{method:?}: {e}"));
        let s = &run.summary;
        assert!((s.simulated_time_s - 60.0).abs() < 1e-9, "{method:?}");
        let bound = if method == Method::Exact { 1e-9 } else { 1e-6 };
        assert!(
            s.energy_balance_residual_run_end <= bound,
            "{method:?}: residual {}",
            s.energy_balance_residual_run_end
        );
        println!(
            "{method:?}: {} events, residual {:.2e}, W_F = {:.6} J",
            s.switching_events, s.energy_balance_residual_run_end, s.force_work_run_end_j
        );
    }
}
