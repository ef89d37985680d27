//! dopri5 on general machines (`integrate::network::dopri5`): against the exact engine with
//! linear laws, against the paper engine's dopri5 with a Hertz slider-bed contact, against
//! the free impact's restitution of Hunt-Crossley contacts and Hertz's closed-form contact
//! time (Johnson, *Contact Mechanics*, §11.4), and its refusals.
//!
//! Tolerances: the runs integrate at rtol = 1e-10, atol = 1e-14 (per component, SI). A
//! quantity of the run then carries a relative error of `rtol` times the error growth over its
//! steps; the comparisons of two engines on the same physics ask 1e-7 (1000 × rtol; measured
//! about 1e-9: energy ratio 5e-10 on the paper machine, 1e-8 with its Hertz slider-bed
//! contact, impact durations 1e-9), and the closed forms 1e-6 (their reference values carry
//! the quadrature and the free impact's restitution relation). Peaks and switching times on the
//! dense output carry its 4th-order interpolation error, of the same order.

use meid::analysis::energy;
use meid::impact::network::{End, Network};
use meid::impact::{restitution, Contact, ContactLaw, Release};
use meid::integrate::network::dopri5::residual_bound;
use meid::integrate::network::{self as engine, ChannelKind, ImpactRow, NetSolution};
use meid::integrate::{Method, Options};
use meid::model::network::NetworkModel;
use meid::model::{Case, Model};

use super::network_engine::{body, bystander, link, paper_model, paper_network, peak_of, rel};

/// dopri5 at rtol 1e-10 (module documentation).
fn dopri5(duration: f64) -> Options {
    Options {
        method: Method::Dopri5,
        duration,
        sample_rate: None,
        rtol: 1e-10,
        atol: 1e-14,
        ..Options::default()
    }
}

fn peak(sol: &NetSolution, kind: &ChannelKind) -> f64 {
    peak_of(sol, kind).0
}

/// The run of `net` with `o` (dopri5) and with the exact method.
fn both(net: &Network, o: &Options) -> (NetSolution, NetSolution) {
    let d = engine::solve(net, o).unwrap();
    let exact = Options {
        method: Method::Exact,
        ..*o
    };
    (d, engine::solve(net, &exact).unwrap())
}

/// The impact rows of two runs agree field by field within `tol` (relative to the row's
/// scale of each field).
fn same_rows(a: &[ImpactRow], b: &[ImpactRow], tol: f64) {
    assert_eq!(a.len(), b.len(), "{a:#?}\n{b:#?}");
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x.contact, y.contact);
        let dur = y.duration_s.max(1e-300);
        assert!(
            (x.start_s - y.start_s).abs() <= tol * dur.max(y.start_s),
            "{x:?} {y:?}"
        );
        assert!(rel(x.duration_s, y.duration_s) <= tol, "{x:?} {y:?}");
        let (px, py) = (x.peak_force_n.unwrap(), y.peak_force_n.unwrap());
        assert!(rel(px, py) <= tol, "{x:?} {y:?}");
        assert!(rel(x.impulse_n_s, y.impulse_n_s) <= tol, "{x:?} {y:?}");
        let v = y
            .approach_velocity_m_per_s
            .abs()
            .max(y.exit_velocity_m_per_s.unwrap_or(0.0).abs());
        assert!(
            (x.approach_velocity_m_per_s - y.approach_velocity_m_per_s).abs() <= tol * v,
            "{x:?} {y:?}"
        );
        if let (Some(ex), Some(ey)) = (x.exit_velocity_m_per_s, y.exit_velocity_m_per_s) {
            assert!((ex - ey).abs() <= tol * v, "{x:?} {y:?}");
        }
    }
}

/// Linear laws: the paper's lumped machine as a network, dopri5 against the exact engine:
/// energy ratio, peak contact forces and every impact row within 1e-7.
#[test]
fn linear_laws_match_the_exact_engine_on_the_paper_machine() {
    let net = paper_network(&paper_model(), 1);
    let o = dopri5(0.05);
    let (d, e) = both(&net, &o);
    let (rd, re) = (d.energy_ratio.unwrap(), e.energy_ratio.unwrap());
    assert!(rel(rd, re) < 1e-7, "{rd} vs {re}");
    for c in 0..2 {
        let k = ChannelKind::ContactForce(c);
        assert!(rel(peak(&d, &k), peak(&e, &k)) < 1e-7, "contact {c}");
    }
    same_rows(&d.impacts, &e.impacts, 1e-7);
    assert!(d.residual_run_end <= residual_bound(&o));
}

/// The IS 2974-2 hammer foundation (examples/hammer-rigid.toml) with a stiff linear tup-anvil
/// contact of restitution 0.5: dopri5 against the exact engine, as above.
#[test]
fn linear_laws_match_the_exact_engine_on_the_hammer_foundation() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/hammer-rigid.toml");
    let sets = [
        "contact.tup_anvil.law=\"linear\"".to_string(),
        "contact.tup_anvil.stiffness=1e11".to_string(),
    ];
    let m = NetworkModel::from_file(&path, &sets).unwrap();
    let o = dopri5(0.02);
    let (d, e) = both(&m.network, &o);
    let (rd, re) = (d.energy_ratio.unwrap(), e.energy_ratio.unwrap());
    assert!(rel(rd, re) < 1e-7, "{rd} vs {re}");
    same_rows(&d.impacts, &e.impacts, 1e-7);
    for p in ["anvil", "block"] {
        let k = ChannelKind::PointDisplacement(p.into());
        assert!(rel(peak(&d, &k), peak(&e, &k)) < 1e-7, "{p}");
        let k = ChannelKind::PointAcceleration(p.into());
        assert!(rel(peak(&d, &k), peak(&e, &k)) < 1e-7, "{p}");
    }
}

/// A Hertz slider-bed contact (K = 1e9 N/m^1.5) on the paper's lumped machine: the general
/// engine's dopri5 on the machine written as a network against the paper engine's dopri5 on
/// the paper's form (the same physics): energy ratio and peak contact forces within 1e-7.
#[test]
fn hertz_paper_machine_matches_the_paper_engine() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml");
    let sets = [
        "contact.slider_bed.law=\"hertz\"".to_string(),
        "contact.slider_bed.stiffness=1e9".to_string(),
        "simulation.method=\"dopri5\"".to_string(),
    ];
    let model = Model::from_file(&path, &sets).unwrap();
    let sys = model.impact_system(Case::AsSpecified).unwrap();
    let o = Options {
        sample_rate: None,
        duration: 0.05,
        ..dopri5(0.05)
    };
    let (summary, _) = energy::simulate_observed(&sys, &o, None).unwrap();
    let net = paper_network(&model, 1);
    assert!(matches!(
        net.contacts[0].contact.law,
        ContactLaw::Hertz { .. }
    ));
    let sol = engine::solve(&net, &o).unwrap();
    let (r, pr) = (sol.energy_ratio.unwrap(), summary.energy_ratio.unwrap());
    assert!(rel(r, pr) < 1e-7, "{r} vs {pr}");
    let fs = peak(&sol, &ChannelKind::ContactForce(0));
    assert!(
        rel(fs, summary.peak_contact_force_slider_bed_n) < 1e-7,
        "{fs} vs {}",
        summary.peak_contact_force_slider_bed_n
    );
    let fd = peak(&sol, &ChannelKind::ContactForce(1));
    assert!(
        rel(fd, summary.peak_contact_force_bed_damper_n) < 1e-7,
        "{fd} vs {}",
        summary.peak_contact_force_bed_damper_n
    );
}

/// Two free bodies, `m1` at `v` onto `m2` at rest, in a general file through a Hunt-Crossley
/// contact `f = K δ^1.5 (1 + 3/2 α δ̇)` with `restitution = e` (α from the closing speed at
/// t = 0, `impact::restitution`): they separate at `e v` (the row's restitution to 1e-6) and
/// the impact dissipates `½ m* v² (1 − e²)` (to 1e-6 of the energy put in).
#[test]
fn hunt_crossley_free_impact_rebounds_with_its_restitution() {
    let (m1, m2, v) = (2.0, 3.0f64, 1.5);
    for e in [0.3, 0.5, 0.9] {
        let text = format!(
            r#"name = "two free bodies"
[structure.modal]
frequencies_hz = [0.0]
damping_ratios = [0.0]
shapes = {{ anvil = [{psi}] }}

[[impactor]]
name = "tup"
mass = {m1}
velocity = {v}

[[contact]]
name = "tup_anvil"
between = ["tup", "anvil"]
law = "hunt-crossley"
stiffness = 1e9
restitution = {e}

[simulation]
method = "dopri5"
duration = 0.01
rtol = 1e-10
"#,
            psi = 1.0 / m2.sqrt()
        );
        let m = NetworkModel::from_text("two.toml", text, &[]).unwrap();
        let sol = m.solve(&m.options().unwrap()).unwrap();
        assert_eq!(sol.impacts.len(), 1, "{:?}", sol.impacts);
        let row = &sol.impacts[0];
        let got = row.restitution.unwrap();
        assert!((got - e).abs() < 1e-6, "e = {e}: {got}");
        let m_red = m1 * m2 / (m1 + m2);
        let lost = 0.5 * m_red * v * v * (1.0 - e * e);
        let e_in = 0.5 * m1 * v * v;
        assert!(
            (sol.dissipated_j - lost).abs() < 1e-6 * e_in,
            "{}",
            sol.dissipated_j
        );
        assert!((row.dissipated_j - lost).abs() < 1e-6 * e_in, "{row:?}");
        assert!(sol.residual_run_end < 1e-6);
    }
}

/// `2 ∫₀¹ dx / √(1 − x^{5/2})` by composite Simpson on `x = 1 − u²` (which removes the
/// endpoint singularity: the integrand becomes `2u / √(1 − (1 − u²)^{5/2})`, smooth, → 2/√2.5
/// at u = 0).
fn hertz_constant() -> f64 {
    let g = |u: f64| {
        if u == 0.0 {
            2.0 / 2.5f64.sqrt()
        } else {
            2.0 * u / (1.0 - (1.0 - u * u).powf(2.5)).sqrt()
        }
    };
    let simpson = |n: usize| {
        let h = 1.0 / n as f64;
        let mut s = g(0.0) + g(1.0);
        for i in 1..n {
            s += if i % 2 == 1 { 4.0 } else { 2.0 } * g(i as f64 * h);
        }
        2.0 * s * h / 3.0
    };
    let (a, b) = (simpson(4000), simpson(8000));
    assert!((a - b).abs() < 1e-10, "{a} {b}");
    b
}

/// Two free bodies through an undamped Hertz contact `f = K δ^{3/2}`: the contact lasts
/// `t_c = c δ_max / v` with `δ_max = (5 m* v² / (4K))^{2/5}` and `c = 2∫₀¹ dx/√(1 − x^{5/2})
/// = 2.9432` (Johnson, *Contact Mechanics*, §11.4; `c` by quadrature), the peak force is
/// `K δ_max^{3/2}`, and the velocities after are those of the elastic collision; all to 1e-6.
#[test]
fn hertz_two_body_contact_time_is_johnsons() {
    let c = hertz_constant();
    assert!((c - 2.9432).abs() < 1e-4, "{c}");
    let (m1, m2, v, k) = (1.5, 4.0, 2.0, 3.0e9);
    let law = Contact {
        law: ContactLaw::Hertz { stiffness: k },
        release: Release::Force,
    };
    let net = Network::new(
        &bystander(),
        vec![body("a", m1, v), body("b", m2, 0.0)],
        vec![],
        vec![link("ab", End::Body(0), End::Body(1), 1e-3, law)],
    )
    .unwrap();
    let sol = engine::solve(&net, &dopri5(0.01)).unwrap();
    assert_eq!(sol.impacts.len(), 1, "{:?}", sol.impacts);
    let row = &sol.impacts[0];
    let m_red = m1 * m2 / (m1 + m2);
    let d_max = (5.0 * m_red * v * v / (4.0 * k)).powf(0.4);
    let t_c = c * d_max / v;
    assert!(
        rel(row.duration_s, t_c) < 1e-6,
        "{} vs {t_c}",
        row.duration_s
    );
    assert!(rel(row.start_s, 1e-3 / v) < 1e-6, "{}", row.start_s);
    let f_max = k * d_max.powf(1.5);
    assert!(rel(row.peak_force_n.unwrap(), f_max) < 1e-6, "{row:?}");
    let nd = net.dofs();
    let nm = net.n_modes();
    let (v1, v2) = (sol.x_final[nd + nm], sol.x_final[nd + nm + 1]);
    assert!((v1 - (m1 - m2) / (m1 + m2) * v).abs() < 1e-6 * v, "{v1}");
    assert!((v2 - 2.0 * m1 / (m1 + m2) * v).abs() < 1e-6 * v, "{v2}");
    assert!(sol.dissipated_j.abs() < 1e-6 * 0.5 * m1 * v * v);
    // Impulse: the momentum the second body took.
    assert!(rel(row.impulse_n_s, m2 * v2) < 1e-6, "{row:?}");
}

/// The free impact of a Hunt-Crossley contact through the engine directly: α from
/// `restitution::x_of_e` at the approach velocity gives e (the model's conversion checked
/// independently of the file reader).
#[test]
fn hunt_crossley_alpha_of_e_through_the_engine() {
    let (m1, m2, v, e) = (1.0, 1.0, 0.8, 0.5);
    let x = restitution::x_of_e(e).unwrap();
    let law = Contact {
        law: ContactLaw::HuntCrossley {
            stiffness: 5e8,
            exponent: 1.5,
            alpha: 2.0 * x / (3.0 * v),
        },
        release: Release::Force,
    };
    let net = Network::new(
        &bystander(),
        vec![body("a", m1, v), body("b", m2, 0.0)],
        vec![],
        vec![link("ab", End::Body(0), End::Body(1), 0.0, law)],
    )
    .unwrap();
    let sol = engine::solve(&net, &dopri5(0.01)).unwrap();
    let got = sol.impacts[0].restitution.unwrap();
    assert!((got - e).abs() < 1e-6, "{got}");
}

fn general_error(sets: &[&str]) -> String {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let text = include_str!("data/paper_lumped_general.toml").to_string();
    NetworkModel::from_text("paper-general.toml", text, &sets)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default()
}

/// A non-linear law with the exact method, a rigid law with dopri5, and the Hertz law with a
/// restitution are refused naming the file and field and saying what is valid.
#[test]
fn bad_laws_and_methods_are_refused_naming_the_field() {
    let text = include_str!("data/paper_lumped_general.toml").replacen(
        "law = \"linear\"",
        "law = \"hertz\"",
        1,
    );
    let e = NetworkModel::from_text("paper-general.toml", text, &[])
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        e.contains("paper-general.toml") && e.contains("contact[0].law") && e.contains("dopri5"),
        "{e}"
    );
    let e = general_error(&[
        "contact.slider_bed.law=\"hertz\"",
        "simulation.method=\"dopri5\"",
        "contact.slider_bed.restitution=0.5",
    ]);
    assert!(
        e.contains("contact[0].restitution") && e.contains("hunt-crossley"),
        "{e}"
    );
    let e = general_error(&[
        "contact.slider_bed.law=\"rigid\"",
        "contact.slider_bed.restitution=0.5",
        "simulation.method=\"dopri5\"",
    ]);
    assert!(e.contains("contact[0].law") && e.contains("exact"), "{e}");
    // A Hunt-Crossley restitution on a contact that does not close at t = 0.
    let e = general_error(&[
        "contact.bed_damper.law=\"hunt-crossley\"",
        "contact.bed_damper.restitution=0.5",
        "simulation.method=\"dopri5\"",
    ]);
    assert!(
        e.contains("contact[1].restitution") && e.contains("alpha"),
        "{e}"
    );
    // Accepted with dopri5, and it runs.
    let sets: Vec<String> = [
        "contact.slider_bed.law=\"hertz\"",
        "contact.slider_bed.stiffness=1e9",
        "simulation.method=\"dopri5\"",
        "simulation.duration=0.01",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let text = include_str!("data/paper_lumped_general.toml").to_string();
    let m = NetworkModel::from_text("paper-general.toml", text, &sets).unwrap();
    let sol = m.solve(&m.options().unwrap()).unwrap();
    assert!(sol.energy_ratio.is_some());
}

/// A preloaded linear contact next to a Hertz contact runs with dopri5: the static state under
/// the preload is the linear equilibrium (the damper's contact closed, its force the preload's
/// `K·|g|` less what the damper's spring and the bed's supports take), and the run keeps its
/// energy balance. A preload on a Hertz contact is refused naming its gap: its static state is
/// not linear.
#[test]
fn a_preload_next_to_a_hertz_contact_runs_and_a_hertz_preload_is_refused() {
    let sets = |extra: &[&str]| -> Vec<String> {
        [
            "contact.slider_bed.law=\"hertz\"",
            "contact.slider_bed.stiffness=1e9",
            "simulation.method=\"dopri5\"",
            "simulation.duration=0.02",
        ]
        .iter()
        .chain(extra)
        .map(|s| s.to_string())
        .collect()
    };
    let text = include_str!("data/paper_lumped_general.toml").to_string();
    let m = NetworkModel::from_text(
        "paper-general.toml",
        text.clone(),
        // The preload pushes the bed towards the slider: the slider stands off by 1 µm.
        &sets(&[
            "contact.bed_damper.gap=-1e-5",
            "contact.slider_bed.gap=1e-6",
        ]),
    )
    .unwrap();
    let x0 = engine::initial_state(&m.network).unwrap();
    let c = m
        .network
        .contacts
        .iter()
        .position(|l| l.name == "bed_damper")
        .unwrap();
    let (delta, _) = m.network.overlap(c, &x0);
    assert!(delta > 0.0 && delta < 1e-5, "overlap at the start {delta}");
    let sol = m.solve(&m.options().unwrap()).unwrap();
    assert!(sol.energy_ratio.is_some_and(|r| r > 0.0 && r < 1.0));
    let e = NetworkModel::from_text(
        "paper-general.toml",
        text,
        &sets(&[
            "contact.bed_damper.law=\"hertz\"",
            "contact.bed_damper.stiffness=1e9",
            "contact.bed_damper.gap=-1e-5",
        ]),
    )
    .and_then(|m| engine::initial_state(&m.network))
    .err()
    .map(|e| e.to_string())
    .unwrap_or_default();
    assert!(
        e.contains("contact[1].gap (bed_damper)") && e.contains("linear contact law"),
        "{e}"
    );
}
