//! dopri5's persistent ("held") contact against a closed form (issue 10, point 5).
//!
//! A slider of mass `m` pushed by a constant force `F` rides on a bed of mass `m_b` on a spring
//! `k` (no structural damping), through a stiff damped linear contact `(K, C)`. The pair starts
//! at the static state with a common velocity `v₀`. Once the contact is held the two move as
//! one rigid body: `(m + m_b) ü = F − k u`, `Ω² = k/(m + m_b)`, so from the state `(u_e, u̇_e)`
//! at the hold
//!
//! ```text
//! u(τ) − F/k = (u_e − F/k) cos Ωτ + (u̇_e/Ω) sin Ωτ,
//! λ(τ) = F − m ü = F + m Ω² (u(τ) − F/k),
//! ```
//!
//! and the contact would pull (`λ = 0`) at the first `τ` with
//! `R cos(Ωτ − φ) = −F/(m Ω²)`, `R cos φ = u_e − F/k`, `R sin φ = u̇_e/Ω`: there the hold must
//! end, and the slider must leave the bed within a quarter of the contact's period after it
//! (the law's force at the frozen gap pushes it off).

use meid::analysis::EnergyTerms;
use meid::impact::{Channel, ChannelMap, Mode, Switch};
use meid::integrate::{self, NoOutput};
use meid::model::{Case, Model};

const M_BED: f64 = 10.0;
const K_BED: f64 = 1.0e6;
const M_S: f64 = 1.0;
const FORCE: f64 = 50.0;
const K_C: f64 = 1.0e12;
/// About 5 % of critical damping of the contact (ω_c ≈ 1.05e6 rad/s): an oscillation left
/// by the start decays within 0.1 ms.
const C_C: f64 = 9.5e4;
/// Common velocity at the start (m/s): an amplitude of 1 mm, so that `m Ω² A ≈ 91 N > F`.
const V0: f64 = 0.3015;

fn model() -> Model {
    let text = format!(
        r#"
name = "slider riding on a sprung bed"
[structure.lumped]
damping_ratios = 0.0
masses = [{{ name = "bed", mass = {M_BED} }}]
springs = [{{ nodes = ["bed", "ground"], stiffness = {K_BED} }}]
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = {M_S}
velocity = 1.0
force = {FORCE}
[contact.slider_bed]
stiffness = {K_C}
damping = {C_C}
[simulation]
method = "dopri5"
duration = 0.03
sample_rate = 10000.0
"#
    );
    Model::from_text("riding.toml", text, &[]).expect("model")
}

#[test]
fn a_held_contact_releases_where_the_rigid_closed_form_pulls() {
    let m = model();
    let sys = m.impact_system(Case::AsSpecified).expect("system");
    let nd = sys.dofs();
    let si = sys.slider_index();
    // Static state with a common velocity: u = F/k, δ = F/K.
    let psi = sys.points.bed_contact[0];
    let mut x0 = vec![0.0; 2 * nd];
    let u0 = FORCE / K_BED;
    x0[0] = u0 / psi;
    x0[si] = u0 + FORCE / K_C;
    x0[nd] = V0 / psi;
    x0[nd + si] = V0;
    let mut o = m.options();
    o.sample_rate = None;
    let sol = integrate::solve_from(&sys, &x0, &o, &mut NoOutput).expect("run");
    let held = |mo: meid::impact::Mode| mo.held(Switch::SliderBed);
    let entry = sol
        .events
        .iter()
        .position(|e| !held(e.from) && held(e.to))
        .expect("the contact is held");
    let release = sol
        .events
        .iter()
        .position(|e| held(e.from) && !held(e.to))
        .expect("the hold ends");
    let open = sol
        .events
        .iter()
        .position(|e| e.from.on(Switch::SliderBed) && !e.to.on(Switch::SliderBed))
        .expect("the slider leaves");
    assert!(entry < release && release < open);
    // The state at the hold (the path point of the entry event).
    let te = sol.events[entry].t;
    let pe = sol
        .path
        .iter()
        .find(|p| p.t == te && held(p.mode))
        .expect("path point at the hold");
    let (d, r) = sys.relative_motion(Switch::SliderBed, &pe.x);
    assert!(r.abs() < 1e-15, "held gap moves at {r} m/s");
    let (ue, ve) = (pe.x[si] - d, pe.x[nd + si]);
    let omega = (K_BED / (M_S + M_BED)).sqrt();
    let (a, b) = (ue - FORCE / K_BED, ve / omega);
    let (rr, phi) = (a.hypot(b), b.atan2(a));
    let c = -FORCE / (M_S * omega * omega * rr);
    assert!(c.abs() < 1.0, "the closed form never pulls");
    // First τ > 0 with cos(Ωτ − φ) = c.
    let base = c.acos();
    let tau = [phi + base, phi - base]
        .iter()
        .map(|th| {
            let two_pi = 2.0 * std::f64::consts::PI;
            th.rem_euclid(two_pi) / omega
        })
        .fold(f64::INFINITY, f64::min);
    let t_star = te + tau;
    let t_rel = sol.events[release].t;
    let t_open = sol.events[open].t;
    // The release is located on dense output at rtol 1e-8: λ is off by about rtol of its
    // size (≈ 100 N) and crosses zero at |λ̇| ≈ 2e4 N/s, a few 1e-11 s; plus the release
    // threshold (rtol/10)·λ_entry ≈ 5e-9 N, 2.5e-13 s. Bound: 1e-9 s (5e-8 of the period).
    assert!(
        (t_rel - t_star).abs() <= 1e-9,
        "released at {t_rel} s, closed form {t_star} s (diff {:e})",
        t_rel - t_star
    );
    // After the release the frozen gap's force pushes the slider off: it leaves within a
    // quarter of the contact's period π/(2 ω_c), ω_c² = K (1/m + 1/m_b).
    let wc = (K_C * (1.0 / M_S + 1.0 / M_BED)).sqrt();
    assert!(
        t_open > t_rel && t_open - t_rel <= std::f64::consts::FRAC_PI_2 / wc,
        "left {:e} s after the release (quarter period {:e} s)",
        t_open - t_rel,
        std::f64::consts::FRAC_PI_2 / wc
    );
}

/// Across the hold, its entry impulse and its release the energy balance
/// `E(0) + F (z_s − z_s0) = Σ stored + dissipated` holds within dopri5's bound (1e-6), and the
/// contact force reported while held is the multiplier: on the rigid pair
/// `λ = (F/m + k u/m_b)/(1/m + 1/m_b) = F + m Ω² (u − F/k)` exactly, not the law's force at
/// the frozen gap.
#[test]
fn a_held_contact_keeps_the_energy_balance_and_reports_its_multiplier() {
    let m = model();
    let sys = m.impact_system(Case::AsSpecified).expect("system");
    let nd = sys.dofs();
    let si = sys.slider_index();
    let psi = sys.points.bed_contact[0];
    let mut x0 = vec![0.0; 2 * nd];
    let u0 = FORCE / K_BED;
    x0[0] = u0 / psi;
    x0[si] = u0 + FORCE / K_C;
    x0[nd] = V0 / psi;
    x0[nd + si] = V0;
    let mut o = m.options();
    o.sample_rate = None;
    let sol = integrate::solve_from(&sys, &x0, &o, &mut NoOutput).expect("run");
    let e0 = EnergyTerms::at(&sys, Mode(Mode::SLIDER_BED), &x0).total();
    let x1 = &sol.x_final;
    let w_f = FORCE * (x1[si] - x0[si]);
    let e1 = EnergyTerms::at(&sys, sol.mode_final, x1).total() + sol.totals.dissipated;
    let residual = (e0 + w_f - e1).abs() / (e0 + w_f.abs());
    assert!(residual <= 1e-6, "energy residual {residual:e}");
    let map = ChannelMap::new(&sys);
    let omega2 = K_BED / (M_S + M_BED);
    let (mut checked, mut moved) = (0, 0.0f64);
    for p in sol.path.iter().filter(|p| p.mode.held(Switch::SliderBed)) {
        let (d, _) = sys.relative_motion(Switch::SliderBed, &p.x);
        let u = p.x[si] - d;
        let expected = FORCE + M_S * omega2 * (u - FORCE / K_BED);
        let f = map.values(&sys, p.mode, &p.x)[Channel::ContactSliderBed.index()];
        assert!(
            (f - expected).abs() <= 1e-9 * FORCE,
            "t = {}: reported {f} N, multiplier {expected} N",
            p.t
        );
        // The law's force at the frozen gap stays at its entry value while λ follows the motion.
        moved = moved.max((f - K_C * d).abs());
        checked += 1;
    }
    assert!(checked > 10, "{checked} held path points");
    assert!(
        moved > 10.0,
        "λ departs from the frozen gap's force by {moved} N at most"
    );
}
