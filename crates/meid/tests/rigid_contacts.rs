//! The rigid impact law (`law = "rigid"`: instantaneous impacts, Newton's restitution) of
//! general machines against closed forms: Newton's post-impact velocities and energy loss of
//! two free bodies, a body striking a modal structure, the accumulation time of a bouncing
//! ball, two contacts struck at one instant, and the stiff limit of a linear contact with the
//! same restitution.

use std::f64::consts::PI;

use meid::impact::network::{Body, End, Network};

use super::network_engine::{link, opts, rel};
use super::network_model::line_of;
use meid::impact::{restitution, Contact, ContactLaw, Release};
use meid::integrate::network::{self as engine, ChannelKind, NetSolution};
use meid::modal::ModalModel;

/// A structure that takes no part: one mode at 1 Hz with a point "s" nothing touches.
fn bystander() -> ModalModel {
    let mut s = ModalModel::with_damping_ratios(vec![2.0 * PI], &[0.0]).unwrap();
    s.points.insert("s".into(), vec![1.0]);
    s
}

fn rigid(e: f64) -> Contact {
    Contact {
        law: ContactLaw::Rigid { restitution: e },
        release: Release::Force,
    }
}

fn body(name: &str, mass: f64, velocity: f64, force: f64) -> Body {
    Body {
        name: name.into(),
        mass,
        velocity,
        force,
    }
}

fn body_velocity(net: &Network, x: &[f64], b: usize) -> f64 {
    x[net.dofs() + net.n_modes() + b]
}

/// Every run's energy balance closes to the exact bound.
fn balanced(sol: &NetSolution) {
    assert!(sol.residual_run_end <= 1e-9, "{}", sol.residual_run_end);
    if let Some(r) = sol.residual_collision_end {
        assert!(r <= 1e-9, "{r}");
    }
}

/// A hammer (m, v) striking point "P" of `s` through `contact`, run to the end of the
/// collision: the network and its solution (energy balance checked).
fn strike(s: &ModalModel, m: f64, v: f64, contact: Contact) -> (Network, NetSolution) {
    let net = Network::new(
        s,
        vec![body("hammer", m, v, 0.0)],
        vec![],
        vec![link(
            "blow",
            End::Body(0),
            End::Point("P".into()),
            0.0,
            contact,
        )],
    )
    .unwrap();
    let mut o = opts(1.0);
    o.stop_at_collision_end = true;
    let sol = engine::solve(&net, &o).unwrap();
    balanced(&sol);
    (net, sol)
}

const ES: [f64; 7] = [0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0];

/// Two free bodies, `a` (m1, v) striking `b` (m2, at rest) across a gap g: at t = g/v the
/// velocities become Newton's, `v1 = (m1 − e m2) v/(m1 + m2)`, `v2 = m1 (1 + e) v/(m1 + m2)`,
/// and the impact removes `½(1 − e²) m* v²` (m* = m1 m2/(m1 + m2)), booked as dissipated (run
/// total and impact row) to 1e-12; the row carries the impulse `(1 + e) m* v`, duration 0 and no
/// peak force.
#[test]
fn rigid_two_body_newton() {
    let (m1, m2, v) = (1.5, 4.0, 2.0);
    let ms = m1 * m2 / (m1 + m2);
    for gap in [0.0, 3.0e-3] {
        for e in ES {
            let net = Network::new(
                &bystander(),
                vec![body("a", m1, v, 0.0), body("b", m2, 0.0, 0.0)],
                vec![],
                vec![link("ab", End::Body(0), End::Body(1), gap, rigid(e))],
            )
            .unwrap();
            let sol = engine::solve(&net, &opts(0.01)).unwrap();
            balanced(&sol);
            assert_eq!(sol.impacts.len(), 1, "e = {e}: {:?}", sol.impacts);
            let r = &sol.impacts[0];
            assert!((r.start_s - gap / v).abs() <= 1e-15, "{r:?}");
            let (v1, v2) = (
                body_velocity(&net, &sol.x_final, 0),
                body_velocity(&net, &sol.x_final, 1),
            );
            let scale = v;
            assert!((v1 - (m1 - e * m2) * v / (m1 + m2)).abs() <= 1e-12 * scale);
            assert!((v2 - m1 * (1.0 + e) * v / (m1 + m2)).abs() <= 1e-12 * scale);
            let ke = 0.5 * m1 * v * v;
            let lost = 0.5 * (1.0 - e * e) * ms * v * v;
            assert!((sol.dissipated_j - lost).abs() <= 1e-12 * ke, "e = {e}");
            assert!((r.dissipated_j - lost).abs() <= 1e-12 * ke, "e = {e}");
            assert!(rel(r.impulse_n_s, (1.0 + e) * ms * v) <= 1e-12, "{r:?}");
            assert_eq!(r.peak_force_n, None);
            assert_eq!(r.duration_s, 0.0);
            assert!((r.restitution.unwrap() - e).abs() <= 1e-12, "{r:?}");
            // The collision ends at the impact: the energy ratio is the share lost.
            let ratio = sol.energy_ratio.unwrap();
            assert!(
                (ratio - lost / ke).abs() <= 1e-12,
                "{ratio} vs {}",
                lost / ke
            );
        }
    }
}

/// A body (m, v) striking point P of an undamped three-mode structure at rest: the impulse
/// `J = (1 + e) v/(1/m + Σψ_i(P)²)` gives the modal velocities `q̇_i⁺ = J ψ_i(P)` (the point is
/// driven along +z, the blow's direction) and the body `v − J/m`, to 1e-12.
#[test]
fn rigid_strike_on_modal_structure() {
    let omega = vec![2.0 * PI * 40.0, 2.0 * PI * 130.0, 2.0 * PI * 410.0];
    let psi = vec![0.21, -0.13, 0.07];
    let mut s = ModalModel::with_damping_ratios(omega, &[0.0, 0.0, 0.0]).unwrap();
    s.points.insert("P".into(), psi.clone());
    let (m, v) = (3.0, 1.7);
    for e in [0.0, 0.5, 1.0] {
        let (net, sol) = strike(&s, m, v, rigid(e));
        let ce = sol.collision_end.as_ref().unwrap();
        assert_eq!(ce.t, 0.0);
        let s2: f64 = psi.iter().map(|p| p * p).sum();
        let j = (1.0 + e) * v / (1.0 / m + s2);
        let nd = net.dofs();
        for (i, p) in psi.iter().enumerate() {
            assert!(
                (ce.x[nd + i] - j * p).abs() <= 1e-12 * v,
                "mode {i}, e = {e}"
            );
        }
        assert!((body_velocity(&net, &ce.x, 0) - (v - j / m)).abs() <= 1e-12 * v);
        let lost = 0.5 * (1.0 - e * e) * v * v / (1.0 / m + s2);
        assert!((ce.dissipated_j - lost).abs() <= 1e-12 * 0.5 * m * v * v);
        assert!(rel(sol.impacts[0].impulse_n_s, j) <= 1e-12);
    }
}

/// A ball dropped from rest at height h onto a rigid floor under its weight m g bounces
/// infinitely often in finite time and rests from the accumulation time
/// `√(2h/g)(1 + e)/(1 − e)` (to 1e-9), after finitely many impacts; then it stays at the
/// floor with the contact force m g, having dissipated m g h.
#[test]
fn rigid_ball_accumulation_time() {
    let (m, g, h): (f64, f64, f64) = (0.2, 9.81, 0.8);
    for e in [0.0, 0.3, 0.5, 0.8] {
        let t_acc = (2.0 * h / g).sqrt() * (1.0 + e) / (1.0 - e);
        let net = Network::new(
            &bystander(),
            vec![body("ball", m, 0.0, m * g)],
            vec![],
            vec![link("floor", End::Body(0), End::Ground, h, rigid(e))],
        )
        .unwrap();
        let sol = engine::solve(&net, &opts(1.5 * t_acc)).unwrap();
        balanced(&sol);
        let resting: Vec<_> = sol.impacts.iter().filter(|r| r.duration_s > 0.0).collect();
        assert_eq!(resting.len(), 1, "e = {e}");
        let r = resting[0];
        assert!(
            rel(r.start_s, t_acc) <= 1e-9,
            "e = {e}: rest from {} s, accumulation time {t_acc} s ({} impacts)",
            r.start_s,
            sol.impacts.len()
        );
        assert!(sol.impacts.len() < 200, "e = {e}: {}", sol.impacts.len());
        assert_eq!(r.exit_velocity_m_per_s, None);
        let nd = net.dofs();
        let nm = net.n_modes();
        assert!((sol.x_final[nm] - h).abs() <= 1e-12 * h);
        assert!(sol.x_final[nd + nm].abs() <= 1e-12 * (2.0 * g * h).sqrt());
        assert!(rel(sol.dissipated_j, m * g * h) <= 1e-9);
        let f = sol
            .channels
            .iter()
            .find(|c| c.kind == ChannelKind::ContactForce(0))
            .unwrap();
        assert!(rel(f.extremes.max, m * g) <= 1e-12, "{:?}", f.extremes);
        // Each bounce's restitution is e.
        for b in sol.impacts.iter().filter(|r| r.duration_s == 0.0) {
            if let Some(re) = b.restitution {
                assert!(re == 0.0 || (re - e).abs() <= 1e-9, "{b:?}");
            }
        }
    }
}

/// Two contacts struck at the same instant: bodies A and B (m each) meet a body C (m, at rest)
/// from both sides at speed v across equal gaps. By symmetry C stays at rest and each contact
/// rebounds with its restitution: A leaves at −e v, B at +e v, and the impacts remove
/// `2 · ½ m v² (1 − e²)`; both impacts start at g/v.
#[test]
fn rigid_two_contacts_at_once() {
    let (m, v, gap) = (2.0, 1.3, 2.0e-3);
    for e in [0.0, 0.5, 1.0] {
        let net = Network::new(
            &bystander(),
            vec![
                body("A", m, v, 0.0),
                body("C", m, 0.0, 0.0),
                body("B", m, -v, 0.0),
            ],
            vec![],
            vec![
                link("AC", End::Body(0), End::Body(1), gap, rigid(e)),
                link("CB", End::Body(1), End::Body(2), gap, rigid(e)),
            ],
        )
        .unwrap();
        let sol = engine::solve(&net, &opts(0.01)).unwrap();
        balanced(&sol);
        assert_eq!(sol.impacts.len(), 2, "e = {e}: {:?}", sol.impacts);
        for r in &sol.impacts {
            assert!(rel(r.start_s, gap / v) <= 1e-12, "{r:?}");
        }
        let x = &sol.x_final;
        assert!((body_velocity(&net, x, 0) + e * v).abs() <= 1e-12 * v);
        assert!(body_velocity(&net, x, 1).abs() <= 1e-12 * v);
        assert!((body_velocity(&net, x, 2) - e * v).abs() <= 1e-12 * v);
        let lost = m * v * v * (1.0 - e * e);
        assert!((sol.dissipated_j - lost).abs() <= 1e-12 * m * v * v);
    }
}

/// The stiff limit: a body striking a one-mode structure through a linear contact whose
/// damping gives restitution e (`C = 2ζ(e)√(K m*)`, force release) converges, as K grows, to
/// the rigid law's result: the body's velocity after the contact and the energy ratio. The
/// error falls as `O(1/K)`, not `O(1/√K)`: the contact lasts `t_c = π√(m*/K)`, and what the
/// structure's own stiffness adds to the contact's impulse over it is of order `ω² t_c²`.
/// Measured (m = 1 kg, modal mass 10 kg at 50 Hz, e = 0.5): |Δv|/v = 8.14e-5, 8.14e-6,
/// 8.14e-7, 8.14e-8 and |Δratio| = 5.92e-5 … 5.92e-8 for K = 1e8 … 1e11 N/m; each decade of K
/// divides both by 10 (exponent 1 within 0.01).
#[test]
fn rigid_stiff_limit_of_linear_contacts() {
    let (m, v, e) = (1.0, 1.0, 0.5);
    let psi = 1.0 / 10.0_f64.sqrt();
    let mut s = ModalModel::with_damping_ratios(vec![2.0 * PI * 50.0], &[0.0]).unwrap();
    s.points.insert("P".into(), vec![psi]);
    let run = |contact: Contact| {
        let (net, sol) = strike(&s, m, v, contact);
        let ce = sol.collision_end.as_ref().unwrap();
        (body_velocity(&net, &ce.x, 0), sol.energy_ratio.unwrap())
    };
    let (v_rigid, ratio_rigid) = run(rigid(e));
    let m_red = 1.0 / (1.0 / m + psi * psi);
    assert!((v_rigid - (v - (1.0 + e) * v * m_red / m)).abs() <= 1e-12);
    let zeta = restitution::zeta_of_e(e, Release::Force).unwrap();
    let mut errs = Vec::new();
    for k in [1e8, 1e9, 1e10, 1e11] {
        let c = 2.0 * zeta * (k * m_red).sqrt();
        let (vb, ratio) = run(Contact {
            law: ContactLaw::Linear {
                stiffness: k,
                damping: c,
            },
            release: Release::Force,
        });
        let (ev, er) = ((vb - v_rigid).abs() / v, (ratio - ratio_rigid).abs());
        errs.push((ev, er));
    }
    for w in errs.windows(2) {
        for (a, b) in [(w[0].0, w[1].0), (w[0].1, w[1].1)] {
            let p = (a / b).log10();
            assert!((p - 1.0).abs() <= 0.01, "{a:e} → {b:e}: exponent {p}");
        }
    }
}

/// A general machine with a rigid contact: a tup striking a lumped anvil.
const RIGID: &str = r#"name = "rigid"
[structure.lumped]
masses = [ { name = "anvil", mass = 100.0 } ]
springs = [ { nodes = ["anvil", "ground"], stiffness = 1.0e7 } ]
damping_ratios = [0.0]

[[impactor]]
name = "tup"
mass = 5.0
velocity = 3.0

[[contact]]
name = "blow"
between = ["tup", "anvil"]
law = "rigid"
restitution = 0.5

[simulation]
duration = 0.05
"#;

/// The file runs: one impact, Newton's anvil velocity, and the energy balance closes.
#[test]
fn rigid_model_file_runs() {
    let m = meid::model::network::NetworkModel::from_text("m.toml", RIGID.into(), &[]).unwrap();
    let sol = m.solve(&m.options().unwrap()).unwrap();
    balanced(&sol);
    let r = &sol.impacts[0];
    let ms = 1.0 / (1.0 / 5.0 + 1.0 / 100.0);
    assert!(rel(r.impulse_n_s, 1.5 * ms * 3.0) <= 1e-12, "{r:?}");
    assert_eq!(r.peak_force_n, None);
}

/// Bad rigid contacts are refused naming the file, line and field and what is valid: a
/// missing restitution, one outside [0, 1] or NaN, a stiffness or damping given with the law,
/// a preload; and the paper's form refuses the law, saying how to write a general machine.
#[test]
fn rigid_bad_input_names_file_line_and_field() {
    for (to, field, says) in [
        (
            "law = \"rigid\"",
            "contact[0].restitution",
            "needs restitution",
        ),
        (
            "law = \"rigid\"\nrestitution = 1.5",
            "contact[0].restitution",
            "[0, 1]",
        ),
        (
            "law = \"rigid\"\nrestitution = -0.1",
            "contact[0].restitution",
            "[0, 1]",
        ),
        (
            "law = \"rigid\"\nrestitution = nan",
            "contact[0].restitution",
            "[0, 1]",
        ),
        (
            "law = \"rigid\"\nrestitution = 0.5\nstiffness = 1e9",
            "contact[0].stiffness",
            "no stiffness or damping",
        ),
        (
            "law = \"rigid\"\nrestitution = 0.5\ndamping = 10.0",
            "contact[0].damping",
            "no stiffness or damping",
        ),
        (
            "law = \"rigid\"\nrestitution = 0.5\ngap = -1e-3",
            "contact[0].gap",
            "cannot be preloaded",
        ),
        (
            "law = \"linear\"\nrestitution = 0.5",
            "contact[0].stiffness",
            "needs a contact stiffness",
        ),
    ] {
        let text = RIGID.replacen("law = \"rigid\"\nrestitution = 0.5", to, 1);
        let e = match meid::model::network::NetworkModel::from_text("m.toml", text.clone(), &[]) {
            Ok(_) => panic!("loaded:\n{text}"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(field) && e.contains(says), "{field}: {e}");
        // A field written in the file is located at its line; a missing one at its entry.
        let key = format!("{} =", field.rsplit('.').next().unwrap());
        let at = match to.lines().find(|l| l.starts_with(&key)) {
            Some(l) => format!("m.toml:{}", line_of(&text, l)),
            None => "m.toml:".to_string(),
        };
        assert!(e.contains(&at), "{field}: not located at {at}: {e}");
    }
    // The paper's form.
    let paper = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/hammer-foundation.toml"
    ))
    .unwrap();
    let text = paper.replacen(
        "law = \"linear\"\nstiffness = 1.0e11             # N/m: a stiff tup-anvil contact (the code's impact is instantaneous)",
        "law = \"rigid\"",
        1,
    );
    assert_ne!(text, paper);
    let e = meid::model::Model::from_text("h.toml", text.clone(), &[])
        .unwrap_err()
        .to_string();
    let line = line_of(&text, "law = \"rigid\"");
    assert!(
        e.contains(&format!("h.toml:{line}"))
            && e.contains("contact.slider_bed.law")
            && e.contains("general machines only")
            && e.contains("[[contact]]"),
        "{e}"
    );
}
