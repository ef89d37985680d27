//! The general impact machine's exact engine (`impact::network`, `integrate::network`) against
//! closed forms, and against the paper's engine on the paper's machine.

use std::f64::consts::PI;

use meid::analysis::energy;
use meid::impact::network::{Body, End, Link, Network, Suspension};
use meid::impact::{restitution, Contact, ContactLaw, DashpotKind, Release};
use meid::integrate::network::{self as engine, ChannelKind, NetSolution};
use meid::integrate::Options;
use meid::modal::ModalModel;
use meid::model::{Case, Model};

/// A structure that takes no part: one mode at 1 Hz with a point "s" nothing touches.
pub(crate) fn bystander() -> ModalModel {
    let mut s = ModalModel::with_damping_ratios(vec![2.0 * PI], &[0.0]).unwrap();
    s.points.insert("s".into(), vec![1.0]);
    s
}

fn linear(k: f64, c: f64) -> Contact {
    Contact {
        law: ContactLaw::Linear {
            stiffness: k,
            damping: c,
        },
        release: Release::Force,
    }
}

pub(crate) fn body(name: &str, mass: f64, velocity: f64) -> Body {
    Body {
        name: name.into(),
        mass,
        velocity,
        force: 0.0,
    }
}

pub(crate) fn link(name: &str, a: End, b: End, gap: f64, contact: Contact) -> Link {
    Link {
        name: name.into(),
        ends: [a, b],
        gap,
        contact,
    }
}

pub(crate) fn opts(duration: f64) -> Options {
    Options {
        duration,
        sample_rate: None,
        ..Options::default()
    }
}

pub(crate) fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

fn body_velocity(net: &Network, sol: &NetSolution, b: usize) -> f64 {
    sol.x_final[net.dofs() + net.n_modes() + b]
}

/// A mass on a spring k1 (a damper's suspension to the ground) with a contact spring k2 to the
/// ground engaged at zero gap on its +z side: the bilinear oscillator returns to x = 0 moving
/// +z after π/ω1 + π/ω2, ω1 = √(k1/m), ω2 = √((k1 + k2)/m).
#[test]
fn bilinear_oscillator_period() {
    let (m, k1, k2) = (2.0, 3.0e4, 5.0e5);
    let net = Network::new(
        &bystander(),
        vec![body("mass", m, 0.7)],
        vec![Suspension {
            name: "spring".into(),
            body: 0,
            stiffness: k1,
            damping: 0.0,
            dashpot: DashpotKind::TwoWay,
            anchor: End::Ground,
        }],
        vec![link(
            "stop",
            End::Body(0),
            End::Ground,
            0.0,
            linear(k2, 0.0),
        )],
    )
    .unwrap();
    let sol = engine::solve(&net, &opts(0.05)).unwrap();
    let (w1, w2) = ((k1 / m).sqrt(), ((k1 + k2) / m).sqrt());
    let period = PI / w1 + PI / w2;
    // Closed at t = 0, opens after π/ω2, closes again one period after the start.
    assert!(sol.events.len() >= 2, "{:?}", sol.events);
    assert!(rel(sol.events[0].0, PI / w2) < 1e-12, "{}", sol.events[0].0);
    assert!(
        rel(sol.events[1].0, period) < 1e-12,
        "{} vs {period}",
        sol.events[1].0
    );
    // Each impact lasts π/ω2 and is elastic.
    let first = &sol.impacts[0];
    assert!(rel(first.duration_s, PI / w2) < 1e-12);
    assert!((first.restitution.unwrap() - 1.0).abs() < 1e-12);
    // The stop's peak force: k2 · v/ω2 (the overlap's amplitude).
    assert!(rel(first.peak_force_n.unwrap(), k2 * 0.7 / w2) < 1e-12);
}

/// Two free bodies through an undamped linear contact: after the contact the velocities are
/// those of an elastic collision, and it lasts π√(m*/k), m* = m1 m2/(m1 + m2); with a gap g the
/// first contact is at g/v.
#[test]
fn two_body_elastic_collision() {
    let (m1, m2, v, k) = (1.5, 4.0, 2.0, 1.0e6);
    for gap in [0.0, 3.0e-3] {
        let net = Network::new(
            &bystander(),
            vec![body("a", m1, v), body("b", m2, 0.0)],
            vec![],
            vec![link("ab", End::Body(0), End::Body(1), gap, linear(k, 0.0))],
        )
        .unwrap();
        let sol = engine::solve(&net, &opts(0.01)).unwrap();
        let m_red = m1 * m2 / (m1 + m2);
        assert_eq!(sol.impacts.len(), 1, "{:?}", sol.impacts);
        let row = &sol.impacts[0];
        assert!(
            rel(row.start_s + 1e-300, gap / v + 1e-300) < 1e-12
                || (gap == 0.0 && row.start_s == 0.0)
        );
        assert!(
            rel(row.duration_s, PI * (m_red / k).sqrt()) < 1e-12,
            "{}",
            row.duration_s
        );
        let va = body_velocity(&net, &sol, 0);
        let vb = body_velocity(&net, &sol, 1);
        assert!(rel(va, (m1 - m2) / (m1 + m2) * v) < 1e-12, "{va}");
        assert!(rel(vb, 2.0 * m1 / (m1 + m2) * v) < 1e-12, "{vb}");
        assert!(rel(row.impulse_n_s, m2 * vb) < 1e-12);
        assert!(rel(row.approach_velocity_m_per_s, v) < 1e-12);
        assert!(rel(row.exit_velocity_m_per_s.unwrap(), v) < 1e-12);
        // Energy ratio: the bodies keep all of it (no structure involved).
        assert!(sol.energy_ratio.unwrap().abs() < 1e-12);
    }
}

/// One body striking two identical bodies through identical contacts with the same gap: both
/// close at the same instant, in one event, and the result is the collision with one body of
/// twice the mass through a contact twice as stiff.
#[test]
fn two_contacts_closing_at_the_same_instant() {
    let (m1, m2, v, k, gap) = (3.0, 1.0, 1.5, 2.0e6, 1.0e-3);
    let net = Network::new(
        &bystander(),
        vec![body("a", m1, v), body("b", m2, 0.0), body("c", m2, 0.0)],
        vec![],
        vec![
            link("ab", End::Body(0), End::Body(1), gap, linear(k, 0.0)),
            link("ac", End::Body(0), End::Body(2), gap, linear(k, 0.0)),
        ],
    )
    .unwrap();
    let sol = engine::solve(&net, &opts(0.01)).unwrap();
    let (t0, from, to) = sol.events[0];
    assert!(rel(t0, gap / v) < 1e-12);
    assert_eq!((from.0, to.0), (0, 0b11), "both close in one event");
    let mb = 2.0 * m2;
    let m_red = m1 * mb / (m1 + mb);
    for row in &sol.impacts {
        assert!(rel(row.start_s, gap / v) < 1e-12);
        assert!(rel(row.duration_s, PI * (m_red / (2.0 * k)).sqrt()) < 1e-12);
    }
    let va = body_velocity(&net, &sol, 0);
    assert!(rel(va, (m1 - mb) / (m1 + mb) * v) < 1e-12, "{va}");
    for b in [1, 2] {
        assert!(rel(body_velocity(&net, &sol, b), 2.0 * m1 / (m1 + mb) * v) < 1e-12);
    }
}

/// The paper's machine (examples/paper-lumped.toml) as a network with its damper split into
/// `split` identical dampers at O_b, each with 1/split of m_d, k_d, c_d and K_d (the same
/// contact frequency).
pub(crate) fn paper_network(model: &Model, split: usize) -> Network {
    let s = &model.spec;
    let d = s.damper.as_ref().unwrap();
    let cs = model.slider_bed_setting().unwrap().contact;
    let cd = model
        .contact_setting(meid::model::ContactName::BedDamper)
        .unwrap()
        .unwrap()
        .contact;
    let f = split as f64;
    let ContactLaw::Linear { stiffness, damping } = cd.law else {
        panic!("linear")
    };
    let bed = End::Point(s.points.bed_contact.clone());
    let anchor = match s.points.damper_anchor.as_deref() {
        None | Some("ground") => End::Ground,
        Some(p) => End::Point(p.into()),
    };
    let mut bodies = vec![Body {
        name: "slider".into(),
        mass: s.slider.mass,
        velocity: s.slider.velocity,
        force: s.slider.force,
    }];
    let mut susp = Vec::new();
    let mut links = vec![link("slider_bed", End::Body(0), bed.clone(), 0.0, cs)];
    for i in 0..split {
        bodies.push(body(&format!("damper{i}"), d.mass / f, 0.0));
        susp.push(Suspension {
            name: format!("damper{i}"),
            body: i + 1,
            stiffness: d.stiffness / f,
            damping: d.damping / f,
            dashpot: DashpotKind::OneWay,
            anchor: anchor.clone(),
        });
        links.push(link(
            &format!("bed_damper{i}"),
            bed.clone(),
            End::Body(i + 1),
            0.0,
            Contact {
                law: ContactLaw::Linear {
                    stiffness: stiffness / f,
                    damping: damping / f,
                },
                release: cd.release,
            },
        ));
    }
    Network::new(&model.structure, bodies, susp, links).unwrap()
}

pub(crate) fn paper_model() -> Model {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml");
    Model::from_file(&path, &[]).unwrap()
}

pub(crate) fn peak_of(sol: &NetSolution, kind: &ChannelKind) -> (f64, f64) {
    sol.channels
        .iter()
        .find(|c| &c.kind == kind)
        .unwrap()
        .extremes
        .peak()
}

/// The general engine on the paper's configuration, and with the damper split into four
/// identical quarters at the same point, against the paper's engine: energy ratio, peak
/// contact forces, peak bed acceleration and floor force to 1e-12 (relative).
#[test]
fn paper_machine_and_four_quarter_dampers_match_the_paper_engine() {
    let model = paper_model();
    let sys = model.impact_system(Case::AsSpecified).unwrap();
    let mut o = model.options();
    o.sample_rate = None;
    let (summary, _) = energy::simulate_observed(&sys, &o, None).unwrap();
    let paper_ratio = summary.energy_ratio.unwrap();
    let peak = |name: &str| {
        let p = summary.peaks.iter().find(|p| p.channel == name).unwrap();
        (p.peak, p.time_s)
    };
    for split in [1, 4] {
        let net = paper_network(&model, split);
        let sol = engine::solve(&net, &o).unwrap();
        let ratio = sol.energy_ratio.unwrap();
        assert!(
            rel(ratio, paper_ratio) < 1e-12,
            "split {split}: {ratio} vs {paper_ratio}"
        );
        let (fs, _) = peak_of(&sol, &ChannelKind::ContactForce(0));
        assert!(
            rel(fs, summary.peak_contact_force_slider_bed_n) < 1e-12,
            "{fs}"
        );
        let fd: f64 = (1..=split)
            .map(|c| peak_of(&sol, &ChannelKind::ContactForce(c)).0)
            .sum();
        assert!(
            rel(fd, summary.peak_contact_force_bed_damper_n) < 1e-12,
            "{fd}"
        );
        let (acc, t_acc) = peak_of(&sol, &ChannelKind::PointAcceleration("bed".into()));
        let (pacc, pt_acc) = peak("bed_acceleration_m_per_s2");
        assert!(rel(acc, pacc) < 1e-12, "split {split}: {acc} vs {pacc}");
        assert!((t_acc - pt_acc).abs() < 1e-12, "{t_acc} vs {pt_acc}");
        let (ff, _) = peak_of(&sol, &ChannelKind::FloorForce);
        let (pff, _) = peak("floor_force_n");
        assert!(rel(ff, pff) < 1e-12, "split {split}: {ff} vs {pff}");
    }
}

/// A ball of mass `m` dropped from rest at height `h` under its weight `m g` onto the ground
/// (end B) through a linear contact of stiffness `m ω²` whose damping gives restitution `e`
/// under `release` (a free impact's, [`restitution::zeta_of_e`]), beside a structure that
/// takes no part.
fn ball(omega: f64, e: f64, release: Release, h: f64, duration: f64) -> meid::Result<NetSolution> {
    let (m, g) = (1.0, 9.81);
    let k = m * omega * omega;
    let zeta = restitution::zeta_of_e(e, release).unwrap();
    let c = 2.0 * zeta * (k * m).sqrt();
    let net = Network::new(
        &bystander(),
        vec![Body {
            name: "ball".into(),
            mass: m,
            velocity: 0.0,
            force: m * g,
        }],
        vec![],
        vec![link(
            "ground",
            End::Body(0),
            End::Ground,
            h,
            Contact {
                law: ContactLaw::Linear {
                    stiffness: k,
                    damping: c,
                },
                release,
            },
        )],
    )
    .unwrap();
    engine::solve(&net, &opts(duration))
}

/// The ball comes to rest at the accumulation time of the rigid limit. A ball dropped from
/// rest at height `h` first lands at `√(2h/g)` (exact: free fall); with restitution `e` each
/// flight is `e` times the one before, so the landings accumulate at
/// `t∞ = √(2h/g)(1 + e)/(1 − e)`. With a contact of finite stiffness each impact lasts about
/// `π/ω` and gravity acting during it changes the exit speed by `O(g/ω)`, hence the next
/// flight by `O(1/ω)`: the last landing is within `N π/ω` of `t∞` for `N` impacts (the
/// measured deviations are at most 0.45 of that), a bound that vanishes in the stiff limit
/// (`N` grows like `ln ω`). The landing speeds fall by `e` per bounce from `v₀ = √(2gh)` and
/// bouncing stops below a speed of order `g/ω`, so `N ≤ ln(v₀ω/g)/ln(1/e) + 3`: finitely many
/// events, then the ball rests on the contact at its static overlap `m g/K` for the rest of
/// the run (one stretch, no events). Both release rules; the energy balance holds throughout
/// (a force-release contact that closes again at a positive overlap gets its elastic energy
/// back).
#[test]
fn a_bouncing_ball_comes_to_rest_at_the_accumulation_time() {
    let (g, h): (f64, f64) = (9.81, 0.05);
    let v0 = (2.0 * g * h).sqrt();
    for release in [Release::Force, Release::Overlap] {
        for e in [0.3, 0.5, 0.8] {
            let t_inf = (2.0 * h / g).sqrt() * (1.0 + e) / (1.0 - e);
            for omega in [1e3, 1e4, 1e5] {
                let what = format!("{release:?}, e = {e}, ω = {omega:e}");
                let sol = ball(omega, e, release, h, 2.0 * t_inf)
                    .unwrap_or_else(|err| panic!("{what}: {err}"));
                let n = sol.impacts.len();
                let n_max = (v0 * omega / g).ln() / (1.0 / e).ln() + 3.0;
                assert!((n as f64) <= n_max, "{what}: {n} impacts > {n_max}");
                assert!(sol.events.len() <= 2 * n, "{what}: {:?}", sol.events);
                let first = &sol.impacts[0];
                assert!(rel(first.start_s, (2.0 * h / g).sqrt()) < 1e-12, "{what}");
                let last = sol.impacts.last().unwrap();
                assert!(last.exit_velocity_m_per_s.is_none(), "{what}: {last:?}");
                let tol = n as f64 * PI / omega;
                assert!(
                    (last.start_s - t_inf).abs() <= tol,
                    "{what}: rests from {} s, t∞ = {t_inf} s, tolerance {tol:e} s",
                    last.start_s
                );
                // At rest on the contact: overlap m g/K (m = 1 kg; to the round-off of z ≈ h),
                // no velocity.
                let z = sol.x_final[1];
                let overlap = g / (omega * omega);
                assert!(
                    (z - h - overlap).abs() <= 1e-14 * h + 1e-9 * overlap,
                    "{what}: {z}"
                );
                assert!(sol.x_final[3].abs() < 1e-9 * v0, "{what}");
                assert!(sol.residual_run_end <= 1e-9);
            }
        }
    }
}
