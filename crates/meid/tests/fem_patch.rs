//! Patch tests and rigid-body checks.
//!
//! Patch: the MacNeal-Harder distorted five-element patch (MacNeal & Harder, *Finite Elements in
//! Analysis and Design* 1 (1985) 3-20): a 0.24 × 0.12 rectangle with interior nodes (0.04, 0.02),
//! (0.18, 0.03), (0.16, 0.08), (0.08, 0.08). The boundary nodes get the exact field; the interior
//! nodes, free of load, must reproduce it (tolerance 1e-9 relative to the field's size, i.e.
//! round-off). Fields: a constant membrane strain with an in-plane rotation (θz = ω), and a
//! constant-curvature bending state w = ½(a x² + b y²) + c x y with θx = ∂w/∂y, θy = -∂w/∂x.
//! The patch is placed in a tilted plane so that the 3-D transformation is exercised.
//!
//! Rigid bodies: a free frame + plate assembly joined by a rigid spider has exactly six
//! zero-frequency modes and no other mode below them.

// Tests index nodes and modes by position, like the formulas they check.
#![allow(clippy::needless_range_loop)]

use faer::prelude::Solve;
use faer::Mat;
use meid::structure::{
    Dof, FeModel, FrameElement, Material, Mesh, PointMass, RigidLink, Section, ShellElement, Spring,
};

const LOCAL: [[f64; 2]; 8] = [
    [0.0, 0.0],
    [0.24, 0.0],
    [0.24, 0.12],
    [0.0, 0.12],
    [0.04, 0.02],
    [0.18, 0.03],
    [0.16, 0.08],
    [0.08, 0.08],
];
const QUADS: [[usize; 4]; 5] = [
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
    [4, 5, 6, 7],
];

/// Orthonormal frame (columns e1, e2, n) of the tilted patch plane.
fn rotation() -> [[f64; 3]; 3] {
    // rows are e1, e2, n
    let e1 = [0.6, 0.8, 0.0];
    let e2 = [-0.48, 0.36, 0.8];
    let n = [0.64, -0.48, 0.6];
    [e1, e2, n]
}

fn to_global(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| r[0][i] * v[0] + r[1][i] * v[1] + r[2][i] * v[2])
}

/// Solves the patch with the boundary nodes (0..4) prescribed by `field(x, y)` = local
/// `[u, v, w, θx, θy, θz]` and returns the max interior error relative to the field's size.
fn patch_error(field: impl Fn(f64, f64) -> [f64; 6]) -> f64 {
    let r = rotation();
    let origin = [0.3, -0.2, 1.1];
    let mut mesh = Mesh::new();
    for p in LOCAL {
        let g = to_global(&r, [p[0], p[1], 0.0]);
        mesh.add_node([g[0] + origin[0], g[1] + origin[1], g[2] + origin[2]]);
    }
    for q in QUADS {
        mesh.add_shell(ShellElement::new(q, Material::STEEL, 0.001));
    }
    let model = FeModel::assemble(mesh).unwrap();
    let k = model.dense_stiffness();
    let exact: Vec<[f64; 6]> = LOCAL
        .iter()
        .map(|p| {
            let f = field(p[0], p[1]);
            let t = to_global(&r, [f[0], f[1], f[2]]);
            let o = to_global(&r, [f[3], f[4], f[5]]);
            [t[0], t[1], t[2], o[0], o[1], o[2]]
        })
        .collect();
    let idx = |node: usize, d: usize| model.dofs.reduced_index(node, d).unwrap();
    let interior: Vec<usize> = (4..8)
        .flat_map(|n| (0..6).map(move |d| (n, d)))
        .map(|(n, d)| idx(n, d))
        .collect();
    let boundary: Vec<(usize, f64)> = (0..4)
        .flat_map(|n| (0..6).map(move |d| (n, d)))
        .map(|(n, d)| (idx(n, d), exact[n][d]))
        .collect();
    let ni = interior.len();
    let mut kii = Mat::<f64>::zeros(ni, ni);
    let mut rhs = Mat::<f64>::zeros(ni, 1);
    for (a, &i) in interior.iter().enumerate() {
        for (b, &j) in interior.iter().enumerate() {
            kii[(a, b)] = k[(i, j)];
        }
        for &(j, ub) in &boundary {
            rhs[(a, 0)] -= k[(i, j)] * ub;
        }
    }
    let u = kii.full_piv_lu().solve(&rhs);
    let scale = exact.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
    let mut err = 0.0_f64;
    for (a, (n, d)) in (4..8).flat_map(|n| (0..6).map(move |d| (n, d))).enumerate() {
        err = err.max((u[(a, 0)] - exact[n][d]).abs());
    }
    err / scale
}

#[test]
fn constant_membrane_strain_patch() {
    // u = 1e-3 (x + 0.3 y), v = 1e-3 (-0.1 x + 0.7 y): ε = (1e-3, 0.7e-3, 0.2e-3), ω = -0.2e-3.
    let err = patch_error(|x, y| {
        let omega = 0.5 * (-0.1e-3 - 0.3e-3);
        [
            1e-3 * (x + 0.3 * y),
            1e-3 * (-0.1 * x + 0.7 * y),
            0.0,
            0.0,
            0.0,
            omega,
        ]
    });
    assert!(err < 1e-9, "membrane patch error {err}");
}

#[test]
fn constant_curvature_bending_patch() {
    let (a, b, c) = (2e-3, -1e-3, 1.5e-3);
    let err = patch_error(|x, y| {
        let w = 0.5 * (a * x * x + b * y * y) + c * x * y;
        [0.0, 0.0, w, b * y + c * x, -(a * x + c * y), 0.0]
    });
    assert!(err < 1e-9, "bending patch error {err}");
}

/// A free 4×4-element plate with a column hung from its centre by a rigid spider over the
/// surrounding element ring: six zero modes exactly, the seventh well above zero.
#[test]
fn free_frame_plate_assembly_has_six_rigid_modes() {
    let mut mesh = Mesh::new();
    let xs: Vec<f64> = (0..=4).map(|i| -0.2 + 0.1 * i as f64).collect();
    let grid = mesh
        .add_plate_grid(&xs, &xs, 0.0, Material::STEEL, 0.01)
        .unwrap();
    let centre = grid[2][2];
    let foot = mesh.add_node([0.0, 0.0, -0.3]);
    let mid = mesh.add_node([0.0, 0.0, -0.15]);
    let sec = Section::solid_circle(0.03).unwrap();
    mesh.add_frame(FrameElement::new([centre, mid], Material::STEEL, sec));
    mesh.add_frame(FrameElement::new([mid, foot], Material::STEEL, sec));
    let ring: Vec<usize> = (1..=3)
        .flat_map(|i| (1..=3).map(move |j| (i, j)))
        .filter(|&(i, j)| (i, j) != (2, 2))
        .map(|(i, j)| grid[i][j])
        .collect();
    mesh.add_rigid_link(RigidLink {
        master: centre,
        slaves: ring,
    });
    let model = FeModel::assemble(mesh).unwrap();
    let modes = model.solve_dense().unwrap();
    assert_eq!(modes.rigid_body_modes, 6);
    let f7 = modes.omega_rad_per_s[6] / (2.0 * std::f64::consts::PI);
    assert!(f7 > 1.0, "7th mode {f7} Hz");
    // The mode table's total mass equals the physical mass (plate + column) in each translation.
    let table = model.mode_table(&modes).unwrap();
    let mass = 0.4 * 0.4 * 0.01 * 7850.0 + 0.3 * sec.area_m2 * 7850.0;
    for d in 0..3 {
        assert!(
            (table.total_mass[d] / mass - 1.0).abs() < 1e-12,
            "{:?}",
            table.total_mass
        );
        let sum: f64 = table.effective_mass.iter().map(|e| e[d]).sum();
        assert!(
            (sum / mass - 1.0).abs() < 1e-8,
            "sum of effective masses {sum} vs {mass}"
        );
    }
}

/// Rigid-link elimination against a two-DOF closed form: master node (mass m0, inertia I0 about y)
/// on a vertical spring k and a rotational spring kr about y; a slave at x = L carries mass m.
/// With q = (uz, θy) of the master: M = [[m0 + m, -m L], [-m L, I0 + m L²]], K = diag(k, kr)
/// (the slave moves uz - θy L). ω² are the roots of det(K - ω² M) = 0.
#[test]
fn rigid_link_matches_two_dof_closed_form() {
    let (m0, i0, m, l, k, kr) = (2.0, 0.05, 3.0, 0.4, 1.0e5, 2.0e4);
    let mut mesh = Mesh::new();
    let master = mesh.add_node([0.0, 0.0, 0.0]);
    let slave = mesh.add_node([l, 0.0, 0.0]);
    mesh.add_mass(PointMass {
        node: master,
        mass_kg: m0,
        inertia_kg_m2: [0.0, i0, 0.0],
    });
    mesh.add_mass(PointMass {
        node: slave,
        mass_kg: m,
        inertia_kg_m2: [0.0; 3],
    });
    mesh.add_spring(Spring {
        node: master,
        other: None,
        stiffness: [0.0, 0.0, k, 0.0, kr, 0.0],
    });
    mesh.add_rigid_link(RigidLink {
        master,
        slaves: vec![slave],
    });
    mesh.fix(master, &[Dof::Ux, Dof::Uy, Dof::Rx, Dof::Rz]);
    mesh.name_point("tip", vec![slave]);
    let model = FeModel::assemble(mesh).unwrap();
    assert_eq!(model.n_dofs(), 2);
    let modes = model.solve_dense().unwrap();
    // det([[k - x(m0+m), x m L], [x m L, kr - x(I0 + m L²)]]) = 0
    let (a11, a12, a22) = (m0 + m, -m * l, i0 + m * l * l);
    let qa = a11 * a22 - a12 * a12;
    let qb = -(k * a22 + kr * a11);
    let qc = k * kr;
    let disc = (qb * qb - 4.0 * qa * qc).sqrt();
    let x = [(-qb - disc) / (2.0 * qa), (-qb + disc) / (2.0 * qa)];
    for (i, xi) in x.iter().enumerate() {
        let w = xi.sqrt();
        assert!(
            (modes.omega_rad_per_s[i] / w - 1.0).abs() < 1e-10,
            "{:?} vs {w}",
            modes.omega_rad_per_s
        );
    }
    // The point functional follows the slave (uz - θy L); the floor force is k uz of the master.
    let mm = model.modal_model(&modes, &[0, 1], &[0.0, 0.0]).unwrap();
    let ff = mm.floor_force.as_ref().unwrap();
    for i in 0..2 {
        let phi = |d: usize| modes.shapes[(model.dofs.reduced_index(master, d).unwrap(), i)];
        let tip = phi(2) - phi(4) * l;
        assert!((mm.points["tip"][i] - tip).abs() < 1e-12 * tip.abs().max(1.0));
        assert!((ff.stiffness[i] - k * phi(2)).abs() < 1e-9 * (k * phi(2)).abs());
    }
}
