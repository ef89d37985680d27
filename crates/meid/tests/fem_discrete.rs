//! Springs, dashpots and point masses against single- and two-DOF closed forms, and the
//! modal-model helper's damping and floor-force terms.
//!
//! * mass m on a spring k and dashpot c to the ground: ω = sqrt(k/m); with the mass-normalised
//!   shape φ = ±1/sqrt(m): modal damping D = 2ζω + c/m, floor force k φ and c φ ;
//! * two masses joined by a spring: ω² = k (1/m1 + 1/m2) plus one rigid mode;
//! * rotary inertia I on a torsion spring k_t: ω = sqrt(k_t / I).
//!
//! Tolerance 1e-10 relative: the round-off of the dense shift-invert solver
//! (`ε κ (λ + σ)²/(σ λ)`, see `modal::dense`).

use meid::structure::{Dashpot, Dof, FeModel, Mesh, PointMass, Spring};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-10 * b.abs().max(1e-300)
}

#[test]
fn spring_dashpot_mass_to_ground() {
    let (m, k, c, zeta) = (4.0, 2.5e5, 120.0, 0.03);
    let mut mesh = Mesh::new();
    let n = mesh.add_node([0.1, 0.2, 0.3]);
    mesh.add_mass(PointMass {
        node: n,
        mass_kg: m,
        inertia_kg_m2: [0.0; 3],
    });
    mesh.add_spring(Spring {
        node: n,
        other: None,
        stiffness: [0.0, 0.0, k, 0.0, 0.0, 0.0],
    });
    mesh.add_dashpot(Dashpot {
        node: n,
        other: None,
        damping: [0.0, 0.0, c, 0.0, 0.0, 0.0],
    });
    mesh.fix(n, &[Dof::Ux, Dof::Uy, Dof::Rx, Dof::Ry, Dof::Rz]);
    mesh.name_point("P", vec![n]);
    let model = FeModel::assemble(mesh).unwrap();
    let modes = model.solve_dense().unwrap();
    let w = (k / m).sqrt();
    assert!(close(modes.omega_rad_per_s[0], w));
    let mm = model.modal_model(&modes, &[0], &[zeta]).unwrap();
    assert!(
        close(mm.damping[0], 2.0 * zeta * w + c / m),
        "{}",
        mm.damping[0]
    );
    let phi = mm.points["P"][0];
    assert!(close(phi.abs(), 1.0 / m.sqrt()));
    let ff = mm.floor_force.unwrap();
    assert!(close(ff.stiffness[0], k * phi));
    assert!(close(ff.damping[0], c * phi));
}

#[test]
fn two_masses_on_a_spring() {
    let (m1, m2, k) = (2.0, 3.0, 1.0e4);
    let mut mesh = Mesh::new();
    let a = mesh.add_node([0.0, 0.0, 0.0]);
    let b = mesh.add_node([0.0, 0.0, 0.1]);
    mesh.add_mass(PointMass {
        node: a,
        mass_kg: m1,
        inertia_kg_m2: [0.0; 3],
    });
    mesh.add_mass(PointMass {
        node: b,
        mass_kg: m2,
        inertia_kg_m2: [0.0; 3],
    });
    mesh.add_spring(Spring {
        node: a,
        other: Some(b),
        stiffness: [0.0, 0.0, k, 0.0, 0.0, 0.0],
    });
    for n in [a, b] {
        mesh.fix(n, &[Dof::Ux, Dof::Uy, Dof::Rx, Dof::Ry, Dof::Rz]);
    }
    let model = FeModel::assemble(mesh).unwrap();
    let modes = model.solve_dense().unwrap();
    assert_eq!(modes.rigid_body_modes, 1);
    // Only x, y and rotations are supported: nothing carries force to the floor along z.
    let (gk, gc) = model.floor_force_functional().unwrap();
    assert!(gk.iter().chain(gc).all(|&g| g == 0.0));
    let w = (k * (1.0 / m1 + 1.0 / m2)).sqrt();
    assert!(
        (modes.omega_rad_per_s[1] / w - 1.0).abs() < 1e-10,
        "{:?} vs {w}",
        modes.omega_rad_per_s
    );
}

#[test]
fn rotary_inertia_on_torsion_spring() {
    let (izz, kt) = (0.02, 500.0);
    let mut mesh = Mesh::new();
    let n = mesh.add_node([0.0; 3]);
    mesh.add_mass(PointMass {
        node: n,
        mass_kg: 1.0,
        inertia_kg_m2: [0.0, 0.0, izz],
    });
    mesh.add_spring(Spring {
        node: n,
        other: None,
        stiffness: [0.0, 0.0, 0.0, 0.0, 0.0, kt],
    });
    mesh.fix(n, &[Dof::Ux, Dof::Uy, Dof::Uz, Dof::Rx, Dof::Ry]);
    let modes = FeModel::assemble(mesh).unwrap().solve_dense().unwrap();
    assert!(((modes.omega_rad_per_s[0] / (kt / izz).sqrt()) - 1.0).abs() < 1e-10);
}

/// A chain of N = 3 equal point masses m on springs k (ground–1–2–3, z only) as a model file:
/// the fixed-free chain's closed form `ω_j = 2 sqrt(k/m) sin((2j−1)π/(2(2N+1)))` and the static
/// flexibilities `G_33 = N/k` (the tip), `G_11 = 1/k`, all modes retained (share 1).
///
/// Before: a note said the five spring ends "are inf to inf times the stiffness the elements
/// give those DOFs ... they act as constraints; constrain those DOFs instead" (the springs are
/// the structure: constraining them leaves nothing), and with `count` ≥ the 3 DOFs a warning
/// said "the 3 computed modes stop at 28.6787 Hz, below the auto cutoff: modes in between may
/// be missing; raise structure.fem.count" (every mode of the structure was computed).
#[test]
fn spring_mass_chain_from_a_model_file_is_exact_and_unflagged() {
    let (m, k) = (1.0_f64, 1.0e4_f64);
    let dir = std::env::temp_dir().join(format!("meid-chain-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("chain.toml");
    let lateral = r#"dofs = ["ux", "uy", "rx", "ry", "rz"]"#;
    std::fs::write(
        &path,
        format!(
            r#"name = "chain"
[structure]
reference_mode = 1
[structure.fem]
select = "auto"
count = 10
[structure.fem.model]
nodes = [[0, 0, 0], [0, 0, 1], [0, 0, 2]]
sets = {{ a = [0], b = [1], c = [2] }}
springs = [{{ node = 0, stiffness = [0, 0, {k:e}, 0, 0, 0] }}, {{ node = 0, to = 1, stiffness = [0, 0, {k:e}, 0, 0, 0] }}, {{ node = 1, to = 2, stiffness = [0, 0, {k:e}, 0, 0, 0] }}]
masses = [{{ node = 0, mass = {m:e} }}, {{ node = 1, mass = {m:e} }}, {{ node = 2, mass = {m:e} }}]
constraints = [{{ set = "a", {lateral} }}, {{ set = "b", {lateral} }}, {{ set = "c", {lateral} }}]
points = {{ O_b = "c", B = "a" }}
[points]
bed_contact = "O_b"
measurement = "B"
[slider]
mass = 0.1
velocity = 0.1
[contact.slider_bed]
law = "linear"
stiffness = 1.0e6
damping = 0.0
release = "force"
[simulation]
method = "exact"
duration = 0.02
sample_rate = 20000.0
"#
        ),
    )
    .unwrap();
    let (_, an) = meid::model::fem::from_file_with_analysis(&path, &[], None).unwrap();
    let an = an.unwrap();
    let n = 3.0;
    for (j, f) in an.table.frequency_hz.iter().enumerate() {
        let w = 2.0
            * (k / m).sqrt()
            * ((2.0 * (j as f64 + 1.0) - 1.0) * std::f64::consts::PI / (2.0 * (2.0 * n + 1.0)))
                .sin();
        let fe = w / (2.0 * std::f64::consts::PI);
        assert!(close(*f, fe), "mode {}: {f} Hz vs {fe} Hz", j + 1);
    }
    assert_eq!(an.table.frequency_hz.len(), 3);
    assert_eq!(an.selected, vec![0, 1, 2]);
    let g = &an.modal.static_flexibility;
    assert!(close(g["O_b"], n / k), "{g:?}");
    assert!(close(g["B"], 1.0 / k), "{g:?}");
    assert!(
        an.modal
            .notes
            .iter()
            .all(|s| !s.contains("act as constraints")),
        "{:?}",
        an.modal.notes
    );
    assert!(an.modal.warnings.is_empty(), "{:?}", an.modal.warnings);
    std::fs::remove_dir_all(&dir).ok();
}
