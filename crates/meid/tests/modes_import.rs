//! Modes imported from other tools (`[structure.modes]`, `meid::model::imported`):
//!
//! * a CalculiX `.frd` of a cantilever of 20-node bricks (`tests/data/ccx_cantilever`, written by
//!   ccx 2.20; the test does not need ccx) against the beam's closed forms: Euler-Bernoulli
//!   frequencies with the first-order Timoshenko correction, and the mass-normalised tip value
//!   `|ψ(L)| = 2/√(ρAL)`. Tolerances: the mesh's own discretisation error (0.003 % to 0.09 %
//!   on the four z-bending frequencies against a 40 × 2 × 2 mesh) plus the first-order
//!   Timoshenko formula's (≈ 0.1 % on the fourth: a converged mesh sits 0.11 % below it);
//!   shapes: shear deformation changes the tip value by up to 0.3 % on the fourth mode;
//! * UFF 2411 + 55 written by meid from a known modal model and read back; modal masses other
//!   than 1 rescale, a missing modal mass is refused unless stated, a contradiction is refused;
//!   a file in mm-t-s that says so in its dataset 164 is converted, a `units` that contradicts
//!   it is refused;
//! * every study runs on imported modes: a simulation with its energy balance, and the same
//!   results as the model the modes came from.

use std::path::{Path, PathBuf};

use meid::analysis::energy::simulate;
use meid::io::uff::{self, Mode, Node, Units};
use meid::model::{Case, Model};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(p)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("meid-modes-import-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

// The cantilever of ccx_cantilever.inp: steel, Poisson ratio 0, clamped at x = 0.
const L: f64 = 1.0;
const B: f64 = 0.04;
const H: f64 = 0.02;
const E: f64 = 2.1e11;
const RHO: f64 = 7850.0;

/// Euler-Bernoulli cantilever: roots of `1 + cos βL cosh βL = 0`, and the mode
/// `W(x) = cosh βx − cos βx − σ (sinh βx − sin βx)`, `σ = (cosh βL + cos βL)/(sinh βL + sin βL)`.
fn beta_l(k: usize) -> f64 {
    // Bisection on each bracket ((k − ½)π ± 0.5): exact to round-off.
    let f = |x: f64| 1.0 + x.cos() * x.cosh();
    let c = (k as f64 - 0.5) * std::f64::consts::PI;
    let (mut a, mut b) = (c - 0.5, c + 0.5);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if f(a) * f(m) <= 0.0 {
            b = m
        } else {
            a = m
        }
    }
    0.5 * (a + b)
}

fn w(bl: f64, x: f64) -> f64 {
    let s = (bl.cosh() + bl.cos()) / (bl.sinh() + bl.sin());
    let b = bl / L;
    (b * x).cosh() - (b * x).cos() - s * ((b * x).sinh() - (b * x).sin())
}

/// The mass-normalised shape `W(x)/√(ρA ∫W²)` (Simpson, 2000 intervals).
fn psi(bl: f64, x: f64) -> f64 {
    let n = 2000;
    let h = L / n as f64;
    let mut s = 0.0;
    for i in 0..=n {
        let c = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        s += c * w(bl, i as f64 * h).powi(2);
    }
    let int = s * h / 3.0;
    w(bl, x) / (RHO * B * H * int).sqrt()
}

#[test]
fn calculix_cantilever_matches_the_beam_closed_forms() {
    let m = Model::from_file(&data("ccx_cantilever/cantilever.toml"), &[]).unwrap();
    let s = &m.structure;
    assert_eq!(s.len(), 6, "{:?}", s.labels);
    assert!(s.notes[0].contains("6 modes"), "{:?}", s.notes);
    // Bending in z (the struck direction) moves the tip in z; bending in y does not.
    let tip = s.point("tip").unwrap();
    let mid = s.point("mid").unwrap();
    let z_modes: Vec<usize> = (0..s.len()).filter(|&i| tip[i].abs() > 0.1).collect();
    assert_eq!(z_modes, vec![0, 2, 4, 5], "{tip:?}");
    let i_z = B * H.powi(3) / 12.0;
    let a = B * H;
    let r2 = H * H / 12.0; // radius of gyration² of the section about y
    let shear = 1.0 + E / ((5.0 / 6.0) * (E / 2.0)); // 1 + E/(κG), ν = 0, κ = 5/6
    for (k, &i) in z_modes.iter().enumerate() {
        let bl = beta_l(k + 1);
        let f_eb = bl * bl / (2.0 * std::f64::consts::PI * L * L) * (E * i_z / (RHO * a)).sqrt();
        // First-order Timoshenko (shear + rotary inertia): f ≈ f_EB (1 − ½ (β r)² (1 + E/κG)).
        let f_t = f_eb * (1.0 - 0.5 * (bl / L).powi(2) * r2 * shear);
        let f = s.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI);
        let e_eb = f / f_eb - 1.0;
        let e_t = f / f_t - 1.0;
        eprintln!(
            "z mode {}: ccx {f:.5} Hz, Euler-Bernoulli {f_eb:.5} ({:+.3} %), Timoshenko {f_t:.5} ({:+.3} %)",
            k + 1,
            100.0 * e_eb,
            100.0 * e_t
        );
        // Euler-Bernoulli alone is off by the shear/rotary correction (0.02 % to 0.7 %); with
        // it the gap is the mesh's and the formula's (module docs).
        assert!(e_eb.abs() < 1e-2, "mode {k}: {e_eb:e}");
        assert!(e_t.abs() < 3e-3, "mode {k}: {e_t:e}");
        // Mass normalisation: the tip value of a mass-normalised cantilever mode is 2/√(ρAL)
        // (|W(L)| = 2 for ∫W² = L); the shear correction of the shape is of the same order as
        // that of the frequency.
        let tip_cf = psi(bl, L).abs();
        assert!((2.0 / (RHO * a * L).sqrt() / tip_cf - 1.0).abs() < 1e-9);
        let e_tip = tip[i].abs() / tip_cf - 1.0;
        let e_mid = mid[i].abs() / psi(bl, 0.5 * L).abs().max(1e-300) - 1.0;
        eprintln!(
            "  |ψ(tip)| {:.6} vs {tip_cf:.6} 1/√kg ({:+.3} %), |ψ(L/2)| {:.6} ({:+.3} %)",
            tip[i].abs(),
            100.0 * e_tip,
            mid[i].abs(),
            100.0 * e_mid
        );
        // Euler-Bernoulli's shape ignores shear: the tip value differs by about the size of the
        // frequency's shear correction c_k = ½(β r)²(1 + E/κG) (measured 0.014 %, 0.11 %,
        // 0.28 %, 0.53 % against c_k = 0.02 %, 0.13 %, 0.35 %, 0.69 %); 2e-4 for the mesh.
        let c_k = 0.5 * (bl / L).powi(2) * r2 * shear;
        assert!(
            e_tip.abs() < c_k + 2e-4,
            "mode {k}: tip {e_tip:e} (c_k {c_k:e})"
        );
        // The same sign pattern as the closed form (tip and mid-span in or out of phase).
        assert_eq!(
            (tip[i] * mid[i]).signum(),
            (psi(bl, L) * psi(bl, 0.5 * L)).signum()
        );
    }
    // The first mode's mid-span value (the others have a node near mid-span).
    let e_mid = mid[0].abs() / psi(beta_l(1), 0.5 * L).abs() - 1.0;
    assert!(e_mid.abs() < 5e-3, "{e_mid:e}");
}

#[test]
fn a_study_runs_on_calculix_modes() {
    let m = Model::from_file(&data("ccx_cantilever/cantilever.toml"), &[]).unwrap();
    let sys = m.impact_system(Case::AsSpecified).unwrap();
    let run = simulate(&sys, &m.options(), true).unwrap();
    let s = &run.summary;
    let res = s.energy_balance_residual.unwrap();
    assert!(res < 1e-9, "energy balance residual {res:e}");
    assert!(s.peak_contact_force_slider_bed_n > 0.0);
    assert!(s.peak_bed_acceleration_m_per_s2 > 0.0);
}

const LUMPED_TAIL: &str = r#"
[points]
bed_contact = "bed"
damper_anchor = "base"
measurement = "bed"

[slider]
mass = 1.2
velocity = 1.2

[damper]
mass = 3.5
stiffness = 1.8e3
damping = 7.0e2

[contact.slider_bed]
stiffness = 4.2980449e7

[contact.bed_damper]
stiffness = 1.2535964e8

[simulation]
duration = 0.05
"#;

fn lumped() -> Model {
    let text = format!(
        r#"
[structure.lumped]
damping_ratios = [0.01, 0.02]
masses = [{{ name = "bed", mass = 10.0 }}, {{ name = "base", mass = 41.0 }}]
springs = [
  {{ name = "columns", nodes = ["bed", "base"], stiffness = 2.5415164e7 }},
  {{ name = "supports", nodes = ["base", "ground"], stiffness = 8.1195270e4 }},
]
{LUMPED_TAIL}"#
    );
    Model::from_text("lumped.toml", text, &[]).unwrap()
}

/// A model in `dir` whose structure is `[structure.modes]` with the given body.
fn imported(dir: &Path, body: &str) -> meid::Result<Model> {
    let text = format!("[structure.modes]\n{body}\n{LUMPED_TAIL}");
    Model::from_text(&dir.join("model.toml").display().to_string(), text, &[])
}

/// The error of [`imported`], which must refuse.
fn refused(dir: &Path, body: &str) -> String {
    imported(dir, body).unwrap_err().to_string()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs())
}

#[test]
fn uff_written_by_meid_reads_back_and_runs_the_same_study() {
    let src = lumped();
    let dir = tmp("roundtrip");
    std::fs::write(
        dir.join("lumped.uff"),
        uff::modes_uff_points(&src.structure).unwrap(),
    )
    .unwrap();
    // modes_uff_points: point k in name order is node k (base = 1, bed = 2), +z = meid's z.
    let m = imported(
        &dir,
        "file = \"lumped.uff\"\npoints = { bed = 2, base = 1 }\nimpact_direction = [0, 0, 1]",
    )
    .unwrap();
    let (a, b) = (&src.structure, &m.structure);
    assert_eq!(a.len(), b.len());
    // Dataset 55 prints %13.5e: 6 significant digits.
    for i in 0..a.len() {
        assert!(rel(a.omega_rad_per_s[i], b.omega_rad_per_s[i]) < 5e-6);
        let n = a.len();
        let za = a.damping[i * n + i] / (2.0 * a.omega_rad_per_s[i]);
        let zb = b.damping[i * n + i] / (2.0 * b.omega_rad_per_s[i]);
        assert!(rel(za, zb) < 5e-6, "{za} vs {zb}");
        for p in ["bed", "base"] {
            let (x, y) = (a.point(p).unwrap()[i], b.point(p).unwrap()[i]);
            assert!(rel(x, y) < 5e-6, "{p} mode {i}: {x} vs {y}");
        }
    }
    assert!(
        b.notes.iter().any(|n| n.contains("damping ratios from")),
        "{:?}",
        b.notes
    );
    // The same study on both: peaks agree to the precision of the file.
    for case in [Case::NoDamper, Case::Damper] {
        let ra = simulate(&src.impact_system(case).unwrap(), &src.options(), false).unwrap();
        let rb = simulate(&m.impact_system(case).unwrap(), &m.options(), false).unwrap();
        for (x, y) in [
            (
                ra.summary.peak_bed_acceleration_m_per_s2,
                rb.summary.peak_bed_acceleration_m_per_s2,
            ),
            (
                ra.summary.peak_contact_force_slider_bed_n,
                rb.summary.peak_contact_force_slider_bed_n,
            ),
        ] {
            assert!(rel(x, y) < 1e-4, "{case:?}: {x} vs {y}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

fn write_modes(path: &Path, modal_mass: f64, shape_scale: f64) {
    write_uff(
        path,
        &[(6.25, 0.125, 0.5), (240.0, -0.25, 0.0625)],
        modal_mass,
        shape_scale,
    );
}

/// A UFF file of nodes 7 and 9 and one dataset 55 per `(frequency Hz, ψ_7, ψ_9)` (z only, times
/// `shape_scale`), numbered from 1.
fn write_uff(path: &Path, modes: &[(f64, f64, f64)], modal_mass: f64, shape_scale: f64) {
    let modes: Vec<[f64; 4]> = modes
        .iter()
        .map(|(f, a, b)| [*f, 0.0, a * shape_scale, b * shape_scale])
        .collect();
    write_nodes_7_9(path, &modes, modal_mass, &[]);
}

/// A UFF file of nodes 7 and 9 and one dataset 55 per `[frequency Hz, damping ratio, z at 7,
/// z at 9]`, numbered from 1, mode k after a dataset 164 `units[k]` when there is one.
fn write_nodes_7_9(path: &Path, modes: &[[f64; 4]], modal_mass: f64, units: &[Units]) {
    let mut out = Vec::new();
    uff::write_2411(
        &mut out,
        &[
            Node {
                label: 7,
                xyz: [0.0; 3],
            },
            Node {
                label: 9,
                xyz: [1.0, 0.0, 0.0],
            },
        ],
    )
    .unwrap();
    for (k, [f, zeta, a, b]) in modes.iter().enumerate() {
        if let Some(u) = units.get(k) {
            uff::write_164(&mut out, u).unwrap();
        }
        uff::write_55(
            &mut out,
            &Mode {
                number: k as i64 + 1,
                frequency_hz: *f,
                modal_mass,
                damping_ratio: *zeta,
                name: format!("mode {}", k + 1),
                id_lines: Vec::new(),
                shapes: vec![(7, [0.0, 0.0, *a]), (9, [0.0, 0.0, *b])],
                units: None,
            },
        )
        .unwrap();
    }
    std::fs::write(path, out).unwrap();
}

const POINTS: &str = "points = { bed = 7, base = 9 }\nimpact_direction = [0, 0, 1]";

#[test]
fn modal_masses_other_than_one_rescale_the_shapes() {
    let dir = tmp("rescale");
    // Shapes twice the mass-normalised ones, modal mass 4: ψ = φ/√4.
    write_modes(&dir.join("m.uff"), 4.0, 2.0);
    let m = imported(&dir, &format!("file = \"m.uff\"\n{POINTS}")).unwrap();
    assert_eq!(m.structure.point("bed").unwrap(), &[0.125, -0.25]);
    assert_eq!(m.structure.point("base").unwrap(), &[0.5, 0.0625]);
    assert!(
        m.structure
            .notes
            .iter()
            .any(|n| n.contains("divided by √(modal mass)") && n.contains("4e0")),
        "{:?}",
        m.structure.notes
    );
    // mm-t-s: a shape in mm/√t is 1e-3/√1e3 of it in m/√kg.
    let m = imported(
        &dir,
        &format!("file = \"m.uff\"\n{POINTS}\nunits = \"mm-t-s\""),
    )
    .unwrap();
    let want = 0.125 * 1e-3 / 1e3f64.sqrt();
    assert!(rel(m.structure.point("bed").unwrap()[0], want) < 1e-15);
    // The file says 4, the model says 1: refused, naming the field.
    let e = refused(
        &dir,
        &format!("file = \"m.uff\"\n{POINTS}\nmass_normalised = true"),
    );
    assert!(
        e.contains("structure.modes.mass_normalised = true") && e.contains("4e0"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_missing_modal_mass_is_refused_unless_stated() {
    let dir = tmp("nomass");
    write_modes(&dir.join("m.uff"), 0.0, 1.0);
    let e = refused(&dir, &format!("file = \"m.uff\"\n{POINTS}"));
    assert!(
        e.contains("model.toml")
            && e.contains("m.uff: mode 1 has no modal mass")
            && e.contains("mass_normalised = true"),
        "{e}"
    );
    let m = imported(
        &dir,
        &format!("file = \"m.uff\"\n{POINTS}\nmass_normalised = true"),
    )
    .unwrap();
    assert_eq!(m.structure.point("bed").unwrap(), &[0.125, -0.25]);
    assert!(
        m.structure
            .notes
            .iter()
            .any(|n| n.contains("taken as mass-normalised")),
        "{:?}",
        m.structure.notes
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn frd_generalised_mass_rescales_and_a_missing_one_is_refused() {
    let dir = tmp("frd");
    let text = std::fs::read_to_string(data("ccx_cantilever/ccx_cantilever.frd")).unwrap();
    let base = "file = \"c.frd\"\npoints = { bed = 62, base = 52 }";
    std::fs::write(dir.join("c.frd"), &text).unwrap();
    let a = imported(&dir, base).unwrap();
    // 1PGM 4: the shapes are halved.
    std::fs::write(
        dir.join("c.frd"),
        text.replace(
            "1PGM                1.000000E+00",
            "1PGM                4.000000E+00",
        ),
    )
    .unwrap();
    let b = imported(&dir, base).unwrap();
    for (x, y) in a
        .structure
        .point("bed")
        .unwrap()
        .iter()
        .zip(b.structure.point("bed").unwrap())
    {
        assert_eq!(*y, 0.5 * x);
    }
    // No 1PGM: refused unless mass_normalised = true.
    let no_gm: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("1PGM"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(dir.join("c.frd"), no_gm).unwrap();
    let e = refused(&dir, base);
    assert!(e.contains("no modal mass") && e.contains("1PGM"), "{e}");
    let c = imported(&dir, &format!("{base}\nmass_normalised = true")).unwrap();
    assert_eq!(
        c.structure.point("bed").unwrap(),
        a.structure.point("bed").unwrap()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_mappings_are_clear_errors() {
    let dir = tmp("bad");
    write_modes(&dir.join("m.uff"), 1.0, 1.0);
    let cases: &[(&str, &[&str])] = &[
        (
            "file = \"m.uff\"\npoints = { bed = 7, base = 12 }",
            &[
                "structure.modes.points.base",
                "node 12",
                "2 nodes",
                "labels 7 to 9",
            ],
        ),
        (
            "file = \"m.uff\"\npoints = { bed = 7, base = 9 }\nselect = [1, 3]",
            &["structure.modes.select", "no mode 3", "its modes: 1, 2"],
        ),
        (
            "file = \"nowhere.uff\"\npoints = { bed = 7, base = 9 }",
            &["structure.modes.file", "nowhere.uff", "not a file"],
        ),
        (
            "file = \"m.txt\"\npoints = { bed = 7, base = 9 }",
            &["cannot tell the format", "format = \"uff\""],
        ),
        (
            "file = \"m.uff\"\npoints = { bed = 7, base = 9 }\nimpact_direction = [0, 0, 0]",
            &["structure.modes.impact_direction", "nonzero"],
        ),
        (
            "file = \"m.uff\"\npoints = { bed = 7, base = 9 }\nunits = \"inch\"",
            &["structure.modes.units", "mm-t-s"],
        ),
        (
            "file = \"m.uff\"\npoints = { bed = 7, base = 9 }\nmax_hz = 1",
            &["no mode", "select/max_hz"],
        ),
        (
            "file = \"m.uff\"\npoints = { bed = 7, base = 9 }\nmass_normalized = true",
            &["unknown field", "mass_normalised"],
        ),
    ];
    for (body, want) in cases {
        let e = refused(&dir, body);
        for w in *want {
            assert!(e.contains(w), "{body}: {e} (wanted '{w}')");
        }
    }
    // select and max_hz keep what they say.
    let m = imported(
        &dir,
        "file = \"m.uff\"\npoints = { bed = 7, base = 9 }\nselect = [2]\nmass_normalised = true",
    )
    .unwrap();
    assert_eq!(m.structure.len(), 1);
    assert_eq!(m.structure.labels, vec!["mode 2 (240.0000 Hz)".to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// An imported mode kept without its partner of the same frequency (a repeated eigenvalue, in
/// the basis the FE program chose) is warned about, naming both; keeping both, or a file
/// without such a pair, warns of nothing. Before, nothing was said, and the direction kept was
/// the FE program's arbitrary choice.
#[test]
fn keeping_one_mode_of_a_repeated_pair_is_warned_about() {
    let dir = tmp("pair");
    write_uff(
        &dir.join("m.uff"),
        &[
            (6.25, 0.125, 0.5),
            (240.0, -0.25, 0.0625),
            (240.0, 0.3, -0.1),
        ],
        1.0,
        1.0,
    );
    let m = imported(
        &dir,
        &format!("file = \"m.uff\"\n{POINTS}\nselect = [1, 2]"),
    )
    .unwrap();
    assert!(
        m.structure
            .warnings
            .iter()
            .any(|w| w.contains("keeps mode 2 of")
                && w.contains("not mode(s) 3 at the same frequency")),
        "{:?}",
        m.structure.warnings
    );
    for sel in ["select = [1, 2, 3]", "select = [1]"] {
        let m = imported(&dir, &format!("file = \"m.uff\"\n{POINTS}\n{sel}")).unwrap();
        assert!(
            m.structure.warnings.is_empty(),
            "{sel}: {:?}",
            m.structure.warnings
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The lumped machine's modes written in mm, tonne, s, N with a dataset 164 that says so
/// (length factor 1000, force factor 1: the mass factor is 1e-3 per kg), each shape at twice
/// its mass-normalised value with modal mass 4 t·mm²/mm²: `ψ_file = 2 ψ_SI · 1000 / √1e-3`.
fn write_mm_t_s(path: &Path, src: &Model, units: &[Units]) {
    let s = &src.structure;
    let to_file = 2.0 * 1e3 / 1e-3f64.sqrt();
    let n = s.len();
    let modes: Vec<[f64; 4]> = (0..n)
        .map(|i| {
            let w = s.omega_rad_per_s[i];
            [
                w / (2.0 * std::f64::consts::PI),
                s.damping[i * n + i] / (2.0 * w),
                s.point("bed").unwrap()[i] * to_file,
                s.point("base").unwrap()[i] * to_file,
            ]
        })
        .collect();
    write_nodes_7_9(path, &modes, 4.0, units);
}

fn mm_t_s() -> Units {
    Units {
        code: 9,
        description: "mm t s N".into(),
        length: 1000.0,
        force: 1.0,
    }
}

/// A UFF file that declares mm-t-s in its dataset 164 is converted without being told: the
/// same ψ (to dataset 55's 6 digits) and the same study as the SI model. Before, it was read
/// as SI: ψ 6.3e4 times too large, a bed of 2.5e-9 kg effective mass.
#[test]
fn a_uff_unit_dataset_converts_the_modes_it_declares() {
    let src = lumped();
    let dir = tmp("units164");
    write_mm_t_s(&dir.join("mm.uff"), &src, &[mm_t_s()]);
    let body = "file = \"mm.uff\"\npoints = { bed = 7, base = 9 }\nimpact_direction = [0, 0, 1]";
    let m = imported(&dir, body).unwrap();
    let (a, b) = (&src.structure, &m.structure);
    for i in 0..a.len() {
        for p in ["bed", "base"] {
            let (x, y) = (a.point(p).unwrap()[i], b.point(p).unwrap()[i]);
            assert!(rel(x, y) < 5e-6, "{p} mode {i}: {x} vs {y}");
        }
    }
    assert!(
        b.notes
            .iter()
            .any(|n| n.contains("converted from the file's units")
                && n.contains("unit code 9")
                && n.contains("length factor 1000")),
        "{:?}",
        b.notes
    );
    let ra = simulate(
        &src.impact_system(Case::Damper).unwrap(),
        &src.options(),
        false,
    )
    .unwrap();
    let rb = simulate(&m.impact_system(Case::Damper).unwrap(), &m.options(), false).unwrap();
    assert!(
        rel(
            ra.summary.energy_ratio.unwrap(),
            rb.summary.energy_ratio.unwrap()
        ) < 1e-4
    );
    assert!(
        rel(
            ra.summary.peak_bed_acceleration_m_per_s2,
            rb.summary.peak_bed_acceleration_m_per_s2
        ) < 1e-4
    );
    // `units` that agree with the file are accepted; one that contradicts it is refused.
    let same = imported(&dir, &format!("{body}\nunits = \"mm-t-s\"")).unwrap();
    assert_eq!(
        same.structure.point("bed").unwrap(),
        b.point("bed").unwrap()
    );
    let e = refused(&dir, &format!("{body}\nunits = \"m-kg-s\""));
    assert!(
        e.contains("structure.modes.units")
            && e.contains("contradicts")
            && e.contains("unit code 9"),
        "{e}"
    );
    // meid's own export declares SI: `units = "mm-t-s"` on it is refused too.
    std::fs::write(
        dir.join("si.uff"),
        uff::modes_uff_points(&src.structure).unwrap(),
    )
    .unwrap();
    let e = refused(
        &dir,
        "file = \"si.uff\"\npoints = { bed = 2, base = 1 }\nimpact_direction = [0, 0, 1]\nunits = \"mm-t-s\"",
    );
    assert!(
        e.contains("contradicts") && e.contains("unit code 1"),
        "{e}"
    );
    // Modes of one file under two unit systems: refused, naming both.
    write_mm_t_s(&dir.join("mixed.uff"), &src, &[mm_t_s(), Units::si()]);
    let e = refused(&dir, &body.replace("mm.uff", "mixed.uff"));
    assert!(
        e.contains("mode 1") && e.contains("mode 2") && e.contains("one unit system"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A file in mm-t-s that does not say so (no dataset 164, as a CalculiX `.frd` never does) read
/// as SI makes the bed 1e9 times too light: a warning names the struck point's effective mass,
/// its ratio to the slider's and `units = "mm-t-s"`; with `units` given, or on the SI file,
/// there is none.
#[test]
fn modes_in_undeclared_mm_t_s_are_warned_about() {
    let src = lumped();
    let dir = tmp("undeclared");
    write_mm_t_s(&dir.join("mm.uff"), &src, &[]);
    let body = "file = \"mm.uff\"\npoints = { bed = 7, base = 9 }\nimpact_direction = [0, 0, 1]";
    let suspicion = |m: &Model| -> Vec<String> {
        m.diagnostics()
            .warnings
            .into_iter()
            .filter(|w| w.contains("units = \"mm-t-s\""))
            .collect()
    };
    let m = imported(&dir, body).unwrap();
    let w = suspicion(&m);
    assert_eq!(w.len(), 1, "{w:?}");
    // 1/Σψ² at the bed read as SI: 1e-9 of the SI model's (the file's modal mass 4 divided
    // back out), quoted to 5 digits.
    let s2: f64 = src
        .structure
        .point("bed")
        .unwrap()
        .iter()
        .map(|v| v * v)
        .sum();
    let quoted: f64 = w[0]
        .split("1/Σψ² = ")
        .nth(1)
        .and_then(|t| t.split(" kg").next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no effective mass in: {}", w[0]));
    assert!(
        rel(quoted, 1e-9 / s2) < 1e-4,
        "{quoted:e} vs {:e}",
        1e-9 / s2
    );
    assert!(
        w[0].contains("'bed'") && w[0].contains("1.2 kg slider"),
        "{}",
        w[0]
    );
    // The check reads the slider of the model at hand: a 1e-3 kg slider is no longer 1e6
    // times heavier than the (wrong) bed.
    let light = Model::from_text(
        &dir.join("model.toml").display().to_string(),
        format!("[structure.modes]\n{body}\n{LUMPED_TAIL}").replace("mass = 1.2", "mass = 1e-3"),
        &[],
    )
    .unwrap();
    assert!(suspicion(&light).is_empty(), "{:?}", suspicion(&light));
    // Units stated by the model: converted, no warning.
    let ok = imported(&dir, &format!("{body}\nunits = \"mm-t-s\"")).unwrap();
    assert!(suspicion(&ok).is_empty());
    for (a, b) in ok
        .structure
        .point("bed")
        .unwrap()
        .iter()
        .zip(src.structure.point("bed").unwrap())
    {
        assert!(rel(*a, *b) < 5e-6);
    }
    // The same modes in SI without a dataset 164: unstated, but plausible.
    let n = src.structure.len();
    let si: Vec<[f64; 4]> = (0..n)
        .map(|i| {
            let s = &src.structure;
            [
                s.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI),
                0.01,
                s.point("bed").unwrap()[i],
                s.point("base").unwrap()[i],
            ]
        })
        .collect();
    write_nodes_7_9(&dir.join("si.uff"), &si, 1.0, &[]);
    let m = imported(&dir, &body.replace("mm.uff", "si.uff")).unwrap();
    assert!(m.structure.unstated_units.is_some());
    assert!(suspicion(&m).is_empty(), "{:?}", suspicion(&m));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Modes after a dataset 164 meid cannot read have unknown units: the import is refused,
/// naming the dataset, rather than read as SI.
#[test]
fn modes_after_an_unreadable_unit_dataset_are_refused() {
    let dir = tmp("bad164");
    let mut text = String::from(
        "    -1\n   164\n         9            mm t s N         1\n   1.0D+03\n    -1\n",
    );
    write_modes(&dir.join("m.uff"), 1.0, 1.0);
    text.push_str(&std::fs::read_to_string(dir.join("m.uff")).unwrap());
    std::fs::write(dir.join("bad.uff"), text).unwrap();
    let e = refused(&dir, &format!("file = \"bad.uff\"\n{POINTS}"));
    assert!(
        e.contains("model.toml:2")
            && e.contains("follows the dataset 164 at line 1, which meid could not read"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
