//! Mode selection and truncation: the static flexibility the retained modes capture at the named
//! points, the "auto" rule that keeps every mode up to a cutoff, and the bounce-mode defect (a
//! plate on four corner springs whose 14 Hz bounce mode the old rule dropped).

use std::fmt::Write;
use std::path::PathBuf;

use meid::model::fem::{self, contact_omega, ReductionContext};
use meid::model::{ContactSpec, LawSpec, Model, ReleaseSpec};

/// A structured nx × ny quad mesh of [0, a] × [0, b] in Gmsh 4.1 ASCII with physical groups
/// "plate" (surface), "corners" (the four corner points) and "centre" (a point).
fn plate_msh(nx: usize, ny: usize, a: f64, b: f64) -> String {
    assert!(nx.is_multiple_of(2) && ny.is_multiple_of(2));
    let tag = |i: usize, j: usize| 1 + j * (nx + 1) + i;
    let mut s = String::new();
    s.push_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    s.push_str(
        "$PhysicalNames\n3\n0 1 \"corners\"\n0 2 \"centre\"\n2 3 \"plate\"\n$EndPhysicalNames\n",
    );
    // 5 points (4 corners + centre), 0 curves, 1 surface.
    s.push_str("$Entities\n5 0 1 0\n");
    let corners = [(0, 0), (nx, 0), (nx, ny), (0, ny)];
    for (k, &(i, j)) in corners.iter().enumerate() {
        let (x, y) = (a * i as f64 / nx as f64, b * j as f64 / ny as f64);
        writeln!(s, "{} {x} {y} 0 1 1", k + 1).unwrap();
    }
    writeln!(s, "5 {} {} 0 1 2", a / 2.0, b / 2.0).unwrap();
    writeln!(s, "1 0 0 0 {a} {b} 0 1 3 0").unwrap();
    s.push_str("$EndEntities\n");
    let total = (nx + 1) * (ny + 1);
    writeln!(s, "$Nodes\n1 {total} 1 {total}\n2 1 0 {total}").unwrap();
    for t in 1..=total {
        writeln!(s, "{t}").unwrap();
    }
    for j in 0..=ny {
        for i in 0..=nx {
            writeln!(
                s,
                "{:e} {:e} 0",
                a * i as f64 / nx as f64,
                b * j as f64 / ny as f64
            )
            .unwrap();
        }
    }
    s.push_str("$EndNodes\n");
    let mut blocks = Vec::new();
    let mut et = 1;
    for (k, &(i, j)) in corners.iter().enumerate() {
        blocks.push(format!("0 {} 15 1\n{et} {}\n", k + 1, tag(i, j)));
        et += 1;
    }
    blocks.push(format!("0 5 15 1\n{et} {}\n", tag(nx / 2, ny / 2)));
    et += 1;
    let mut q = format!("2 1 3 {}\n", nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            writeln!(
                q,
                "{et} {} {} {} {}",
                tag(i, j),
                tag(i + 1, j),
                tag(i + 1, j + 1),
                tag(i, j + 1)
            )
            .unwrap();
            et += 1;
        }
    }
    blocks.push(q);
    writeln!(s, "$Elements\n{} {} 1 {}", blocks.len(), et - 1, et - 1).unwrap();
    for b in blocks {
        s.push_str(&b);
    }
    s.push_str("$EndElements\n");
    s
}

const A: f64 = 0.40;
const B: f64 = 0.30;
const H: f64 = 0.010;
/// Steel plate mass ρ a b h (kg).
fn plate_mass() -> f64 {
    7850.0 * A * B * H
}
/// Vertical stiffness per corner spring giving a 14 Hz bounce: k = m (2π·14)² / 4.
fn corner_kz() -> f64 {
    plate_mass() * (2.0 * std::f64::consts::PI * 14.0).powi(2) / 4.0
}

/// A plate on four corner springs (x, y, z), struck at its centre by a 1.2 kg slider through a
/// 4.3e7 N/m contact (ω_s = 5985 rad/s, 952.5 Hz): `select` and extra `[structure.fem]` lines.
fn bounce_model(tag: &str, fem_extra: &str) -> (PathBuf, String) {
    let dir = std::env::temp_dir().join(format!("meid-bounce-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("plate.msh"), plate_msh(8, 6, A, B)).unwrap();
    let kz = corner_kz();
    let text = format!(
        r#"
[structure.fem]
damping_ratios = 0.01
count = 30
{fem_extra}

[structure.fem.mesh]
file = "plate.msh"
thickness = {H}
points = {{ O_b = "centre", B = "centre" }}
springs = [{{ group = "corners", stiffness = [{kxy}, {kxy}, {kz}] }}]

[points]
bed_contact = "O_b"
measurement = "B"

[slider]
mass = 1.2
velocity = 1.2

[contact.slider_bed]
law = "linear"
stiffness = 4.3e7

[simulation]
duration = 0.02
"#,
        kxy = 0.2 * kz
    );
    (dir.join("model.toml"), text)
}

fn load(tag: &str, fem_extra: &str) -> Model {
    let (path, text) = bounce_model(tag, fem_extra);
    Model::from_text(&path.display().to_string(), text, &[]).unwrap()
}

/// The defect: the old rule (now `select = "participation"`, 2 modes by ψ(O_b)²) keeps two
/// plate-bending modes and drops the 14 Hz bounce mode, which carries almost all of the contact
/// point's static flexibility (the springs are ~100 times softer than the plate). The new
/// default keeps it, captures ≥ 95 % at O_b, and the old selection reports its loss.
#[test]
fn auto_keeps_the_bounce_mode_the_old_rule_dropped() {
    // Without the static correction, which would restore the share (see
    // `static_correction_restores_the_share_and_silences_the_warning`).
    let old = load(
        "old",
        "select = \"participation\"\nauto_count = 2\nstatic_correction = false",
    );
    let f0 = old.structure.omega_rad_per_s[0] / (2.0 * std::f64::consts::PI);
    assert!(
        f0 > 100.0,
        "the old rule kept a {f0} Hz mode: the defect is not reproduced"
    );
    let d_old = old.diagnostics();
    let ob_old = d_old.truncation.iter().find(|r| r.point == "O_b").unwrap();
    assert!(ob_old.captured_share < 0.05, "{ob_old:?}");
    assert!(
        d_old
            .warnings
            .iter()
            .any(|w| w.contains("'O_b'") && w.contains("static flexibility")),
        "{:?}",
        d_old.warnings
    );

    let new = load("new", "");
    let st = &new.structure;
    let f: Vec<f64> = (0..st.len())
        .filter(|&i| !st.is_pseudo(i))
        .map(|i| st.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI))
        .collect();
    // The bounce: a rigid plate on 4 kz: sqrt(4 kz / m)/2π = 14 Hz (the plate's bending lowers
    // it a little).
    let bounce = f.iter().position(|&x| (x - 14.0).abs() < 0.3);
    assert!(bounce.is_some(), "no bounce mode kept: {f:?}");
    let d = new.diagnostics();
    let ob = d.truncation.iter().find(|r| r.point == "O_b").unwrap();
    eprintln!(
        "old rule: {:?} Hz, share {:.4}; auto: {} modes {:.2}..{:.2} Hz, share {:.6}",
        old.structure
            .omega_rad_per_s
            .iter()
            .map(|w| w / (2.0 * std::f64::consts::PI))
            .collect::<Vec<_>>(),
        ob_old.captured_share,
        f.len(),
        f[0],
        f[f.len() - 1],
        ob.captured_share
    );
    assert!(ob.captured_share >= 0.95, "{ob:?}");
    assert!(ob.captured_share <= 1.0 + 1e-12, "{ob:?}");
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    // G_PP is the springs in series with the plate: at least the four springs in parallel.
    assert!(ob.static_flexibility_m_per_n > 1.0 / (4.0 * corner_kz()));
    assert!(ob.static_flexibility_m_per_n < 1.1 / (4.0 * corner_kz()));
}

/// "Auto" never drops a low mode in favour of a higher one: every kept mode above the cutoff
/// comes after all participating modes below it, and the cutoff is 3 ω_s / 2π.
#[test]
fn auto_keeps_every_participating_mode_below_the_cutoff() {
    let (path, text) = bounce_model("cutoff", "");
    let spec: meid::model::ModelSpec = toml::from_str(&text).unwrap();
    let ctx = ReductionContext::of(&spec);
    let ws = (4.3e7_f64 / 1.2).sqrt();
    assert!((ctx.contact_omega_rad_per_s - ws).abs() <= 1e-12 * ws);
    let src = meid::model::Source {
        name: path.display().to_string(),
        text: text.clone(),
        overrides: Vec::new(),
    };
    let a = fem::analyse(spec.structure.fem.as_ref().unwrap(), &src, &ctx).unwrap();
    let cutoff = 3.0 * ws / (2.0 * std::f64::consts::PI);
    let fmax_kept_below = a
        .selected
        .iter()
        .map(|&i| a.table.frequency_hz[i])
        .filter(|&f| f <= cutoff)
        .fold(0.0, f64::max);
    for i in 0..a.table.frequency_hz.len() {
        let f = a.table.frequency_hz[i];
        let moves = a.scores[i] > 1e-12 * a.scores.iter().fold(0.0_f64, |x, &y| x.max(y));
        if f <= cutoff && moves {
            assert!(a.selected.contains(&i), "mode {} ({f} Hz) dropped", i + 1);
        }
        if !a.selected.contains(&i) && moves {
            assert!(
                f > fmax_kept_below,
                "mode {} ({f} Hz) dropped below a kept one",
                i + 1
            );
        }
    }
}

/// A deliberately truncated selection (only the 6th mode, a plate mode) keeps a small share and
/// is warned about, in the diagnostics and on the CLI's stderr.
#[test]
fn truncated_selection_reports_a_small_share_and_a_warning() {
    let m = load("trunc", "select = [7]\nstatic_correction = false");
    let d = m.diagnostics();
    // O_b and B name the same node: two rows, two warnings.
    assert_eq!(d.truncation.len(), 2);
    for (r, (point, role)) in d
        .truncation
        .iter()
        .zip([("O_b", "bed_contact"), ("B", "measurement")])
    {
        assert_eq!(
            (r.point.as_str(), r.roles.clone()),
            (point, vec![role.to_string()])
        );
        assert!(r.captured_share < 0.95, "{r:?}");
    }
    // B is O_b's node: its static response to the blow is its own flexibility, so the share
    // of the blow's response equals the captured share; O_b (the struck point) has none.
    assert_eq!(d.truncation[0].blow_response_share, None);
    let b = &d.truncation[1];
    let share = b
        .blow_response_share
        .expect("B's share of the blow's response");
    assert!((share - b.captured_share).abs() <= 1e-9, "{b:?}");
    assert_eq!(d.warnings.len(), 2, "{:?}", d.warnings);
    for w in &d.warnings {
        assert!(w.contains("static flexibility at point"), "{w}");
    }
    assert!(
        d.warnings[1].contains("of its static response to the blow"),
        "{:?}",
        d.warnings
    );
}

/// A lumped model keeps all its modes: the share is 1 to 1e-12 at every point (the static
/// flexibility comes from the Cholesky factor of K, the modal sum from the eigenvectors).
/// Here a free-free three-mass chain (one rigid-body mode: the elastic convention) and the
/// paper's grounded two-mass model.
#[test]
fn lumped_models_capture_everything() {
    let free = r#"
[structure.lumped]
masses = [ { name = "a", mass = 2.0 }, { name = "b", mass = 5.0 }, { name = "c", mass = 1.5 } ]
springs = [ { nodes = ["a", "b"], stiffness = 3.0e5 }, { nodes = ["b", "c"], stiffness = 8.0e4 } ]
[points]
bed_contact = "a"
damper_anchor = "b"
measurement = "c"
[slider]
mass = 0.5
velocity = 1.0
[contact.slider_bed]
stiffness = 1e7
"#;
    let m = Model::from_text("free.toml", free.to_string(), &[]).unwrap();
    assert_eq!(m.structure.omega_rad_per_s[0], 0.0);
    let d = m.diagnostics();
    assert_eq!(d.truncation.len(), 3);
    for r in &d.truncation {
        assert!((r.captured_share - 1.0).abs() <= 1e-12, "{r:?}");
    }
    // Closed form at the free end c of a free chain: with the load made self-equilibrated, the
    // elastic flexibility is Σ over springs of (share of the total mass beyond the spring,
    // seen from c)² / k: spring b-c carries (m_a + m_b)/M of the load, a-b carries m_a/M.
    let mt: f64 = 8.5;
    let gc = ((2.0 + 5.0) / mt).powi(2) / 8.0e4 + (2.0 / mt).powi(2) / 3.0e5;
    let rc = d.truncation.iter().find(|r| r.point == "c").unwrap();
    assert!(
        (rc.static_flexibility_m_per_n - gc).abs() <= 1e-12 * gc,
        "{} vs {gc}",
        rc.static_flexibility_m_per_n
    );

    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/paper-lumped.toml"
    );
    let m = Model::from_file(std::path::Path::new(path), &[]).unwrap();
    let d = m.diagnostics();
    for r in &d.truncation {
        assert!((r.captured_share - 1.0).abs() <= 1e-12, "{r:?}");
    }
    // Grounded chain: G(base) = 1/k_f, G(bed) = 1/k_f + 1/k_c.
    let (kc, kf) = (2.5415164e7, 8.1195270e4);
    let bed = d.truncation.iter().find(|r| r.point == "bed").unwrap();
    let base = d.truncation.iter().find(|r| r.point == "base").unwrap();
    assert!((bed.static_flexibility_m_per_n - (1.0 / kf + 1.0 / kc)).abs() <= 1e-13 / kf);
    assert!((base.static_flexibility_m_per_n - 1.0 / kf).abs() <= 1e-13 / kf);
    assert!(d.warnings.is_empty(), "{d:?}");
    // The one note: the damper (3.5 kg) against the 10 kg the bed opposes to the blow.
    assert!(
        d.notes.len() == 1
            && d.notes[0].starts_with("at O_b ('bed') the structure meets a blow as m_eff = 10 kg")
            && d.notes[0].ends_with("m_d/m_eff = 0.35"),
        "{d:?}"
    );
    // With every mode retained, Σ ψ_i(P)² = (M⁻¹)_PP: the effective mass at a point is the
    // mass lumped there (10 kg bed, 41 kg base), and no single mode carries less.
    for (r, mass) in [(bed, 10.0), (base, 41.0)] {
        let m_eff = r.effective_mass_kg.unwrap();
        assert!((m_eff - mass).abs() <= 1e-12 * mass, "{r:?}");
        assert!(r.dominant_mode_effective_mass_kg.unwrap() >= m_eff, "{r:?}");
    }
    // The bed moves most in the bed mode (mode 2, 283 Hz), the base in the rigid-body mode.
    assert_eq!(bed.dominant_mode, Some(2));
    assert_eq!(base.dominant_mode, Some(1));
    // Closed form of the two-mass chain: λ² m_b m_f − λ (m_b (k_c + k_f) + m_f k_c) + k_c k_f
    // = 0; in mode λ the base moves r = (k_c − m_b λ)/k_c times the bed, and mass
    // normalisation gives 1/ψ(bed)² = m_b + m_f r².
    let (mb, mf) = (10.0, 41.0);
    let (a, b, c) = (mb * mf, -(mb * (kc + kf) + mf * kc), kc * kf);
    let lam2 = (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
    let r = (kc - mb * lam2) / kc;
    let want = mb + mf * r * r;
    let got = bed.dominant_mode_effective_mass_kg.unwrap();
    assert!((got - want).abs() <= 1e-9 * want, "{got} vs {want}");
}

/// Contact frequencies: linear √(K/m) whatever v; Hertz T_c = 2.9432 δ_max / v (the classical
/// constant, 2 √π Γ(7/5)/Γ(9/10)), so ω_c = π v / (2.9432 δ_max).
#[test]
fn contact_frequencies_match_closed_forms() {
    let mut c = ContactSpec {
        law: LawSpec::Linear,
        stiffness: 4.3e7,
        damping: None,
        exponent: None,
        alpha: None,
        restitution: None,
        release: ReleaseSpec::Force,
    };
    let w = contact_omega(&c, 1.2, 3.0).unwrap();
    assert!((w - (4.3e7_f64 / 1.2).sqrt()).abs() <= 1e-12 * w);
    c.law = LawSpec::Hertz;
    c.stiffness = 1.0e10;
    let (m, v) = (1.2, 1.5);
    let d_max = (5.0 * m * v * v / (4.0 * c.stiffness)).powf(0.4);
    // 2 √π Γ(1.4) / Γ(0.9) with Γ(1.4) = 0.887263817503075, Γ(0.9) = 1.068628702119319.
    let k = 2.0 * std::f64::consts::PI.sqrt() * 0.887263817503075 / 1.068628702119319;
    let exact = std::f64::consts::PI * v / (k * d_max);
    let got = contact_omega(&c, m, v).unwrap();
    assert!((got - exact).abs() <= 1e-9 * exact, "{got} vs {exact}");
    assert!((k - 2.9432).abs() < 1e-4, "{k}");
    assert!(contact_omega(&c, m, 0.0).is_none());
}

/// The elastic (inertia-relief) convention on a structure with rigid-body modes, checked against
/// an independent computation. A free plate (no springs: six rigid-body modes, three of which
/// move the centre and the corners along z) with every mode kept: the modal sum over all
/// elastic modes of the dense eigen-decomposition must equal the static flexibility from the
/// factorisation of K + σM with the rigid-body projection, at the centre and at the corners.
/// And on the plate on z-only springs (three in-plane rigid-body modes that do not move the
/// points along z) G_PP equals that with in-plane springs (flat shells: in-plane and bending
/// decouple).
#[test]
fn elastic_convention_matches_the_full_modal_sum() {
    let (path, text) = bounce_model("free", "");
    let text = text
        .replace(
            "springs = [{ group = \"corners\", stiffness",
            "#springs = [{ group = \"corners\", stiffness",
        )
        .replace(
            "points = { O_b = \"centre\", B = \"centre\" }",
            "points = { O_b = \"centre\", B = \"corners\" }",
        );
    let spec: meid::model::ModelSpec = toml::from_str(&text).unwrap();
    let src = meid::model::Source {
        name: path.display().to_string(),
        text: text.clone(),
        overrides: Vec::new(),
    };
    let ctx = ReductionContext::of(&spec);
    let a = fem::analyse(spec.structure.fem.as_ref().unwrap(), &src, &ctx).unwrap();
    assert_eq!(a.modes.rigid_body_modes, 6);
    // Every mode, from the dense solver directly (`meid` refuses the top of a full dense
    // spectrum, whose residuals exceed the solution check's bound; their ψ²/ω² is negligible).
    let all = meid::modal::dense::solve_shift_invert(
        a.model.dense_stiffness().as_ref(),
        a.model.dense_mass().as_ref(),
        None,
    )
    .unwrap();
    assert_eq!(all.rigid_body_modes, 6);
    for p in ["O_b", "B"] {
        let f = a.model.point_functional(p).unwrap();
        let sum: f64 = (0..all.eigenvalues.len())
            .filter(|&i| all.omega_rad_per_s[i] > 0.0)
            .map(|i| {
                let psi: f64 = (0..f.len()).map(|j| f[j] * all.shapes[(j, i)]).sum();
                psi * psi / all.eigenvalues[i]
            })
            .sum();
        let g = a.modal.static_flexibility[p];
        eprintln!("{p}: full modal sum {sum:e}, G_PP {g:e}");
        assert!((sum / g - 1.0).abs() <= 1e-11, "{p}: {sum} vs {g}");
    }

    // z-only springs: three in-plane rigid-body modes, same G_PP as with in-plane springs.
    let g = |fem_extra: &str, kxy: &str| {
        let (path, text) = bounce_model("zonly", fem_extra);
        let text = text.replace(
            &format!("stiffness = [{}, {}", 0.2 * corner_kz(), 0.2 * corner_kz()),
            &format!("stiffness = [{kxy}, {kxy}"),
        );
        assert!(
            text.contains(&format!("stiffness = [{kxy}, {kxy}, ")),
            "{text}"
        );
        let spec: meid::model::ModelSpec = toml::from_str(&text).unwrap();
        let src = meid::model::Source {
            name: path.display().to_string(),
            text: text.clone(),
            overrides: Vec::new(),
        };
        let ctx = ReductionContext::of(&spec);
        let a = fem::analyse(spec.structure.fem.as_ref().unwrap(), &src, &ctx).unwrap();
        (a.modes.rigid_body_modes, a.modal.static_flexibility["O_b"])
    };
    let ((r0, g0), (r1, g1)) = (g("", "0.0"), g("", &format!("{}", 0.2 * corner_kz())));
    assert_eq!((r0, r1), (3, 0));
    assert!((g0 - g1).abs() <= 1e-10 * g1, "{g0} vs {g1}");
}

/// `select = "auto"` on a square-section cantilever (`tests/data/eb_cantilever.toml`, 20 modes):
/// every bending eigenvalue is a pair (y and z bending), whose basis each solver picks its own
/// way. Before: the dense solver kept modes [2, 3, 4, 6, 7, 8, 10, 13, 14] (one of a pair moving
/// the tip's z, its partner by 2.4e-5 or nothing) and Lanczos [1, 2, 3, 4, 5, 6, 7, 8, 10, 11,
/// 13, 14]: the modes kept depended on the solver. Now each pair is kept whole, by both solvers
/// alike; the captured flexibility is the same (the tip's L³/3EI = 1.190476e-4 m/N, exact).
#[test]
fn auto_keeps_a_repeated_eigenvalue_whole_whatever_the_solver() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/eb_cantilever.toml");
    let run = |solver: &str| {
        let over = vec![
            "structure.fem.select=\"auto\"".to_string(),
            format!("structure.fem.solver=\"{solver}\""),
        ];
        let (_, an) = fem::from_file_with_analysis(&path, &over, Some(20)).unwrap();
        an.unwrap()
    };
    let (d, l) = (run("dense"), run("lanczos"));
    assert_eq!(d.selected, l.selected);
    // Whole pairs: the bending modes 1-8 (four pairs) and the 10/11 pair, 13/14 pair.
    assert_eq!(d.selected, vec![0, 1, 2, 3, 4, 5, 6, 7, 9, 10, 12, 13]);
    let (e, i, len) = (2.1e11_f64, 1.3333333333333333e-8_f64, 1.0_f64);
    let g = len.powi(3) / (3.0 * e * i);
    for an in [&d, &l] {
        let row = &an.modal.truncation(&[("O_b".into(), vec![])])[0];
        assert!(
            (row.static_flexibility_m_per_n - g).abs() <= 1e-9 * g,
            "{row:?}"
        );
        assert!(row.captured_share > 0.999, "{row:?}");
    }
    let (rd, rl) = (
        &d.modal.truncation(&[("O_b".into(), vec![])])[0],
        &l.modal.truncation(&[("O_b".into(), vec![])])[0],
    );
    assert!(
        (rd.modal_flexibility_m_per_n - rl.modal_flexibility_m_per_n).abs()
            <= 1e-9 * rd.modal_flexibility_m_per_n,
        "{rd:?} {rl:?}"
    );
}

/// A repeated eigenvalue's modes do not depend on the eigen-solver: on the square cantilever
/// (bending pairs in y and z), every one of the 20 computed mode shapes, the effective masses,
/// the participation at the tip and a one-mode simulation are the same from the dense solver
/// and Lanczos. Before, each solver returned its own rotation of each pair: the shapes of a pair
/// differed by O(1), `select = [1]` kept a mode moving the tip along the impact with one solver
/// and a different mix with the other, and `select = "participation"` could keep different
/// members. Now the first mode of a pair is the one that moves the impact point (O_b) along the
/// impact, positively, the second does not move it; "participation" ranks and keeps the pair
/// whole; keeping one member warns, naming the pair.
#[test]
fn a_repeated_eigenvalue_gives_the_same_modes_whatever_the_solver() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/eb_cantilever.toml");
    let run = |solver: &str, select: &str| {
        let over = vec![
            format!("structure.fem.select={select}"),
            format!("structure.fem.solver=\"{solver}\""),
            "structure.fem.auto_count=1".to_string(),
            "structure.fem.auto_max_hz=3000".to_string(),
        ];
        // reference_mode names a retained mode by the structure's number: the participation
        // selection keeps the pair 18/19, not mode 1.
        let mut over = over;
        if select.contains("participation") {
            over.push("structure.reference_mode=18".to_string());
        }
        fem::from_file_with_analysis(&path, &over, Some(20)).unwrap()
    };
    let ((md, d), (ml, l)) = (run("dense", "[1]"), run("lanczos", "[1]"));
    let (d, l) = (d.unwrap(), l.unwrap());
    let (sd, sl) = (&d.modes.shapes, &l.modes.shapes);
    assert_eq!(sd.ncols(), 20);
    for j in 0..20 {
        let max = (0..sd.nrows()).fold(0.0_f64, |a, r| a.max(sd[(r, j)].abs()));
        for r in 0..sd.nrows() {
            assert!(
                (sd[(r, j)] - sl[(r, j)]).abs() <= 1e-7 * max,
                "mode {} DOF {r}: dense {} lanczos {}",
                j + 1,
                sd[(r, j)],
                sl[(r, j)]
            );
        }
        let (ed, el) = (&d.table.effective_mass[j], &l.table.effective_mass[j]);
        let total: f64 = d.table.total_mass.iter().sum();
        for k in 0..6 {
            assert!(
                (ed[k] - el[k]).abs() <= 1e-7 * total,
                "mode {} effective mass",
                j + 1
            );
        }
    }
    // Mode 1 moves the tip along the impact; its partner (mode 2) does not.
    let (pd, pl) = (d.modal.point("O_b").unwrap(), l.modal.point("O_b").unwrap());
    assert!(
        pd[0] > 0.0 && (pd[0] - pl[0]).abs() <= 1e-9 * pd[0],
        "{pd:?} {pl:?}"
    );
    let psi2: f64 = {
        let f = d.model.point_functional("O_b").unwrap();
        (0..f.len()).map(|r| f[r] * sd[(r, 1)]).sum()
    };
    assert!(psi2.abs() <= 1e-9 * pd[0], "mode 2 moves O_b: {psi2}");
    for an in [&d, &l] {
        assert!(
            an.modal
                .warnings
                .iter()
                .any(|w| w.contains("keeps mode(s) 1 of the modes 1, 2 that share one eigenvalue")),
            "{:?}",
            an.modal.warnings
        );
    }
    // The same one-mode simulation from either solver.
    let peaks = |m: &Model| {
        let sys = m.impact_system(meid::model::Case::AsSpecified).unwrap();
        meid::analysis::simulate(&sys, &m.options(), false)
            .unwrap()
            .summary
            .peaks
    };
    for (a, b) in peaks(&md).iter().zip(&peaks(&ml)) {
        assert!(
            (a.peak - b.peak).abs() <= 1e-7 * a.peak.abs().max(1e-300),
            "{a:?} {b:?}"
        );
    }
    // "participation" with one mode asked, up to 3000 Hz: the pair with the largest ψ² at the
    // tip (every bending pair has ψ_tip² ≈ 1.27, rising slowly with the mode; 2641.84 Hz is the
    // highest), whole, from either solver.
    let (pd, pl) = (
        run("dense", "\"participation\"").1.unwrap(),
        run("lanczos", "\"participation\"").1.unwrap(),
    );
    assert_eq!(pd.selected, vec![17, 18]);
    assert_eq!(pl.selected, vec![17, 18]);
    // The last computed mode, one of a pair cut by `count`: the member moving O_b, whichever
    // solver (the solve computes one mode more for it).
    let psi20 = |an: &fem::FemAnalysis| {
        let f = an.model.point_functional("O_b").unwrap();
        (0..f.len())
            .map(|r| f[r] * an.modes.shapes[(r, 19)])
            .sum::<f64>()
    };
    // It bends in z alone (no effective mass in y), as the pairs' first modes do: 1.1331 against
    // 1.1287 for mode 1 (ψ_tip rises slowly with the mode).
    for an in [&d, &l] {
        let total: f64 = an.table.total_mass.iter().sum();
        assert!(an.table.effective_mass[19][1] <= 1e-9 * total);
        assert!(psi20(an) > 1.13, "{}", psi20(an));
    }
}

/// The selection of `truncated_selection_reports_a_small_share_and_a_warning` (one plate mode
/// of the sprung plate, < 95 % at O_b) with the static correction on (the default): the
/// pseudo-modes restore the full static flexibility, so the share at O_b and B is 1 up to
/// round-off, the rows say `static_correction` with the modes' own share below 95 %, and no
/// truncation warning is left; the pseudo-modes are labelled "static correction", numbered 0.
#[test]
fn static_correction_restores_the_share_and_silences_the_warning() {
    let m = load("corrected", "select = [7]");
    let d = m.diagnostics();
    assert_eq!(d.truncation.len(), 2);
    for r in &d.truncation {
        assert!(r.static_correction, "{r:?}");
        assert!((r.captured_share - 1.0).abs() <= 1e-9, "{r:?}");
        assert!(r.modes_share.is_some_and(|s| s < 0.95), "{r:?}");
        assert_eq!(r.dominant_mode, Some(7), "{r:?}");
    }
    assert!(
        !d.warnings.iter().any(|w| w.contains("static flexibility")),
        "{:?}",
        d.warnings
    );
    let st = &m.structure;
    assert!(st.len() > 1 && !st.is_pseudo(0));
    for i in 1..st.len() {
        assert!(st.is_pseudo(i), "{:?}", st.labels);
        assert_eq!(st.mode_numbers[i], 0);
        assert!(
            st.labels[i].starts_with("static correction"),
            "{}",
            st.labels[i]
        );
    }
}
