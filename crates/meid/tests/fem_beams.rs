//! Frame elements against Euler-Bernoulli closed forms.
//!
//! Reference: f_n = (β_n L)² / (2π L²) · sqrt(E I / (ρ A)) (e.g. Blevins, *Formulas for Natural
//! Frequency and Mode Shape*, Table 8-1), β_n L for the cantilever 1.875104, 4.694091, 7.854757,
//! 10.995541 and free-free 4.730041, 7.853205, 10.995608, 14.137165.
//! Tolerance: 0.5 % for the first four bending modes on the fine mesh (brief), and the error must
//! fall as the mesh is refined.

// Tests index nodes and modes by position, like the formulas they check.
#![allow(clippy::needless_range_loop)]

use meid::structure::{Dof, FeModel, FrameElement, Material, Mesh, Section};

const CANTILEVER: [f64; 4] = [1.875104, 4.694091, 7.854757, 10.995541];
const FREE_FREE: [f64; 4] = [4.730041, 7.853205, 10.995608, 14.137165];
const L: f64 = 1.2;

fn section() -> Section {
    // 30 mm (global y) x 50 mm (global z)
    Section::solid_rectangle(0.03, 0.05).unwrap()
}

fn exact_hz(beta_l: f64, i_m4: f64) -> f64 {
    let m = Material::STEEL;
    let a = section().area_m2;
    beta_l * beta_l / (2.0 * std::f64::consts::PI * L * L)
        * (m.youngs_modulus_pa * i_m4 / (m.density_kg_per_m3 * a)).sqrt()
}

/// A beam along global x in `n` elements; `planar` keeps only w and θy (bending in the x-z plane).
fn beam(n: usize, clamp: bool, planar: bool) -> Mesh {
    let mut mesh = Mesh::new();
    let nodes: Vec<usize> = (0..=n)
        .map(|i| mesh.add_node([L * i as f64 / n as f64, 0.0, 0.0]))
        .collect();
    for w in nodes.windows(2) {
        let mut el = FrameElement::new([w[0], w[1]], Material::STEEL, section());
        // local y = global y, local z = global z: w bends about local y with Iy = b h^3 / 12.
        el.orientation = Some([0.0, 1.0, 0.0]);
        mesh.add_frame(el);
    }
    if planar {
        for &nd in &nodes {
            mesh.fix(nd, &[Dof::Ux, Dof::Uy, Dof::Rx, Dof::Rz]);
        }
    }
    if clamp {
        mesh.fix_all(nodes[0]);
    }
    mesh
}

fn hz(model: &FeModel) -> (Vec<f64>, usize) {
    let modes = model.solve_dense().unwrap();
    // The low modes used below are M-orthonormal (the dense solver favours them; see
    // modal::dense for the accuracy of the top of the spectrum).
    let nl = 12.min(modes.shapes.ncols());
    let phi = modes.shapes.subcols(0, nl);
    let gram = phi.transpose() * model.dense_mass() * phi;
    for j in 0..nl {
        for i in 0..nl {
            let t = if i == j { 1.0 } else { 0.0 };
            assert!(
                (gram[(i, j)] - t).abs() < 1e-8,
                "Gram ({i},{j}) = {}",
                gram[(i, j)]
            );
        }
    }
    (
        modes
            .omega_rad_per_s
            .iter()
            .map(|w| w / (2.0 * std::f64::consts::PI))
            .collect(),
        modes.rigid_body_modes,
    )
}

#[test]
fn cantilever_bending_converges_to_euler_bernoulli() {
    let iy = section().iy_m4;
    let mut prev_err = f64::INFINITY;
    for n in [2, 4, 8, 32] {
        let (f, rigid) = hz(&FeModel::assemble(beam(n, true, true)).unwrap());
        assert_eq!(rigid, 0);
        let err = (0..4)
            .filter(|&i| i < f.len())
            .map(|i| (f[i] / exact_hz(CANTILEVER[i], iy) - 1.0).abs())
            .fold(0.0, f64::max);
        // n = 2 has only 4 bending DOFs: all four modes exist but are poor.
        assert!(
            err < prev_err,
            "n = {n}: error {err} did not fall below {prev_err}"
        );
        prev_err = err;
        if n == 32 {
            for i in 0..4 {
                let e = exact_hz(CANTILEVER[i], iy);
                assert!(
                    (f[i] / e - 1.0).abs() < 0.005,
                    "cantilever mode {}: {} Hz vs {} Hz",
                    i + 1,
                    f[i],
                    e
                );
            }
        }
    }
}

#[test]
fn free_free_planar_bending_matches_and_has_two_rigid_modes() {
    let iy = section().iy_m4;
    let mut prev_err = f64::INFINITY;
    for n in [4, 8, 32] {
        let (f, rigid) = hz(&FeModel::assemble(beam(n, false, true)).unwrap());
        // planar: translation z and rotation about y
        assert_eq!(rigid, 2);
        let err = (0..4)
            .map(|i| (f[i + 2] / exact_hz(FREE_FREE[i], iy) - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(err < prev_err, "n = {n}: {err} vs {prev_err}");
        prev_err = err;
    }
    assert!(prev_err < 0.005, "{prev_err}");
}

/// The unconstrained 3-D beam has exactly six zero modes; the 7th is the first bending mode about
/// the weak axis (global z, Iz = h b³/12) and the lowest x-z bending mode matches too.
#[test]
fn free_free_3d_has_six_rigid_modes() {
    let (f, rigid) = hz(&FeModel::assemble(beam(32, false, false)).unwrap());
    assert_eq!(rigid, 6);
    assert!(f[..6].iter().all(|&x| x == 0.0));
    let weak = exact_hz(FREE_FREE[0], section().iz_m4);
    assert!((f[6] / weak - 1.0).abs() < 0.005, "{} vs {}", f[6], weak);
    let strong = exact_hz(FREE_FREE[0], section().iy_m4);
    assert!(
        f.iter().any(|&x| (x / strong - 1.0).abs() < 0.005),
        "no mode near {strong} Hz"
    );
    // Torsion of a free-free bar: f = n c_t / (2L), c_t = sqrt(G J / (ρ Ip)).
    let m = Material::STEEL;
    let s = section();
    let ft = (m.shear_modulus_pa() * s.torsion_constant_m4
        / (m.density_kg_per_m3 * s.polar_moment_m4()))
    .sqrt()
        / (2.0 * L);
    assert!(
        f.iter().any(|&x| (x / ft - 1.0).abs() < 0.005),
        "no torsion mode near {ft} Hz"
    );
}

/// Axial: a clamped-free bar, f_n = (2n-1) c / (4L), c = sqrt(E/ρ) (Blevins Table 8-16).
#[test]
fn clamped_free_axial_bar() {
    let n = 40;
    let mut mesh = beam(n, true, false);
    for nd in 1..=n {
        mesh.fix(nd, &[Dof::Uy, Dof::Uz, Dof::Rx, Dof::Ry, Dof::Rz]);
    }
    let (f, _) = hz(&FeModel::assemble(mesh).unwrap());
    let m = Material::STEEL;
    let c = (m.youngs_modulus_pa / m.density_kg_per_m3).sqrt();
    for k in 1..=3 {
        let e = (2 * k - 1) as f64 * c / (4.0 * L);
        assert!((f[k - 1] / e - 1.0).abs() < 0.005, "{} vs {e}", f[k - 1]);
    }
}
