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
