//! Shell elements (MITC4 bending) against plate closed forms.
//!
//! * Kirchhoff thin square plate (a/h = 100): f = λ/(2π a²) sqrt(D/(ρh)), D = E h³/(12(1-ν²));
//!   simply supported λ = π²(m² + n²) (exact), clamped λ = 35.985 (doubly symmetric),
//!   73.394 (antisymmetric-symmetric), 108.22 (doubly antisymmetric) (Leissa, *Vibration of
//!   Plates*, NASA SP-160, 1969, Table 4.23).
//!   Tolerance 1 % on the fine mesh (brief).
//! * Mindlin thick plate (a/h = 10), hard simple supports, shear factor κ = π²/12: for mode (m, n)
//!   with k² = (m² + n²) π²/a² the flexural frequency is the smaller root of
//!   `(κGh k² - ρh ω²)(D k² + κGh - ρh³/12 ω²) - (κGh)² k² = 0` (Mindlin, *J. Appl. Mech.* 18
//!   (1951) 31-38). Tolerance 1 %.
//!
//! The in-plane DOFs (u, v, θz) are fixed so that only bending modes appear. Coarse-to-fine
//! checks use the whole plate; the fine-mesh checks use a quarter plate (16×16 elements, i.e. a
//! 32×32 whole plate) with symmetric (θ normal to the line fixed) or antisymmetric (w and the
//! tangential rotation fixed) conditions on the two mid-lines, so that each symmetry class of
//! modes is checked separately.

// Tests index nodes and modes by position, like the formulas they check.
#![allow(clippy::needless_range_loop)]

use meid::structure::{Dof, FeModel, Material, Mesh};

const A: f64 = 1.0;

#[derive(Clone, Copy, PartialEq)]
enum Edge {
    SimplySupported,
    Clamped,
}

#[derive(Clone, Copy, PartialEq)]
enum Mid {
    Symmetric,
    Antisymmetric,
}

/// Support of a node on an outer edge; `normal_x` = the edge is a line x = const.
fn outer_edge(mesh: &mut Mesh, nd: usize, edge: Edge, normal_x: bool) {
    mesh.fix(nd, &[Dof::Uz]);
    match edge {
        Edge::Clamped => mesh.fix(nd, &[Dof::Rx, Dof::Ry]),
        // hard support: the rotation about the edge normal (slope along the edge) is zero
        Edge::SimplySupported => mesh.fix(nd, &[if normal_x { Dof::Rx } else { Dof::Ry }]),
    }
}

/// Condition on a mid-line; `normal_x` = the line is x = const.
fn mid_line(mesh: &mut Mesh, nd: usize, mid: Mid, normal_x: bool) {
    match mid {
        // zero slope across the line: rotation about the line's direction
        Mid::Symmetric => mesh.fix(nd, &[if normal_x { Dof::Ry } else { Dof::Rx }]),
        Mid::Antisymmetric => mesh.fix(nd, &[Dof::Uz, if normal_x { Dof::Rx } else { Dof::Ry }]),
    }
}

/// Whole plate (`quarter = None`, n×n elements) or the quarter [0, a/2]² with mid-line
/// conditions `(at x = a/2, at y = a/2)`.
fn plate(n: usize, h: f64, edge: Edge, quarter: Option<(Mid, Mid)>, kappa: Option<f64>) -> FeModel {
    let mut mesh = Mesh::new();
    let len = if quarter.is_some() { A / 2.0 } else { A };
    let xs: Vec<f64> = (0..=n).map(|i| len * i as f64 / n as f64).collect();
    let grid = mesh
        .add_plate_grid(&xs, &xs, 0.0, Material::STEEL, h)
        .unwrap();
    if let Some(k) = kappa {
        for s in &mut mesh.shells {
            s.shear_factor = k;
        }
    }
    for i in 0..=n {
        for j in 0..=n {
            let nd = grid[i][j];
            mesh.fix(nd, &[Dof::Ux, Dof::Uy, Dof::Rz]);
            if i == 0 {
                outer_edge(&mut mesh, nd, edge, true);
            }
            if j == 0 {
                outer_edge(&mut mesh, nd, edge, false);
            }
            match quarter {
                None => {
                    if i == n {
                        outer_edge(&mut mesh, nd, edge, true);
                    }
                    if j == n {
                        outer_edge(&mut mesh, nd, edge, false);
                    }
                }
                Some((mx, my)) => {
                    if i == n {
                        mid_line(&mut mesh, nd, mx, true);
                    }
                    if j == n {
                        mid_line(&mut mesh, nd, my, false);
                    }
                }
            }
        }
    }
    FeModel::assemble(mesh).unwrap()
}

fn frequencies_hz(model: &FeModel) -> Vec<f64> {
    let modes = model.solve_dense().unwrap();
    assert_eq!(modes.rigid_body_modes, 0);
    modes
        .omega_rad_per_s
        .iter()
        .map(|w| w / (2.0 * std::f64::consts::PI))
        .collect()
}

fn kirchhoff_hz(lambda: f64, h: f64) -> f64 {
    let m = Material::STEEL;
    let d = m.youngs_modulus_pa * h.powi(3) / (12.0 * (1.0 - m.poisson_ratio.powi(2)));
    lambda / (2.0 * std::f64::consts::PI * A * A) * (d / (m.density_kg_per_m3 * h)).sqrt()
}

fn mindlin_hz(mm: usize, nn: usize, h: f64, kappa: f64) -> f64 {
    let m = Material::STEEL;
    let rho = m.density_kg_per_m3;
    let d = m.youngs_modulus_pa * h.powi(3) / (12.0 * (1.0 - m.poisson_ratio.powi(2)));
    let kgh = kappa * m.shear_modulus_pa() * h;
    let k2 = ((mm * mm + nn * nn) as f64) * std::f64::consts::PI.powi(2) / (A * A);
    let (a, b, c) = (kgh * k2, d * k2 + kgh, kgh * kgh * k2);
    let (rh, ri) = (rho * h, rho * h.powi(3) / 12.0);
    // rh ri x² - (rh b + ri a) x + (a b - c) = 0, smaller root (stable form)
    let p = rh * b + ri * a;
    let q = a * b - c;
    let x = 2.0 * q / (p + (p * p - 4.0 * rh * ri * q).sqrt());
    x.sqrt() / (2.0 * std::f64::consts::PI)
}

fn rel(got: f64, exact: f64) -> f64 {
    (got / exact - 1.0).abs()
}

fn max_rel_err(f: &[f64], exact: &[f64]) -> f64 {
    exact
        .iter()
        .zip(f)
        .map(|(e, g)| rel(*g, *e))
        .fold(0.0, f64::max)
}

/// Whole plates 4×4, 8×8, 16×16: the error of the first four modes falls with refinement
/// and the (1,2)/(2,1) pair is degenerate as the square's symmetry demands.
fn check_convergence(edge: Edge, exact: &[f64], h: f64) {
    let mut prev = f64::INFINITY;
    for n in [4, 8, 16] {
        let f = frequencies_hz(&plate(n, h, edge, None, None));
        let err = max_rel_err(&f, exact);
        assert!(err < prev, "n = {n}: error {err} did not fall below {prev}");
        assert!(
            rel(f[1], f[2]) < 1e-8,
            "pair not degenerate: {} {}",
            f[1],
            f[2]
        );
        prev = err;
    }
}

#[test]
fn thin_simply_supported_plate_matches_kirchhoff() {
    let h = A / 100.0;
    let pi2 = std::f64::consts::PI.powi(2);
    let ex = |l: f64| kirchhoff_hz(l * pi2, h);
    check_convergence(
        Edge::SimplySupported,
        &[ex(2.0), ex(5.0), ex(5.0), ex(8.0)],
        h,
    );
    use Mid::*;
    let ss = Edge::SimplySupported;
    let f = frequencies_hz(&plate(16, h, ss, Some((Symmetric, Symmetric)), None));
    assert!(rel(f[0], ex(2.0)) < 0.01, "(1,1): {} vs {}", f[0], ex(2.0));
    assert!(
        rel(f[1], ex(10.0)) < 0.01,
        "(1,3): {} vs {}",
        f[1],
        ex(10.0)
    );
    let f = frequencies_hz(&plate(16, h, ss, Some((Antisymmetric, Symmetric)), None));
    assert!(rel(f[0], ex(5.0)) < 0.01, "(2,1): {} vs {}", f[0], ex(5.0));
    let f = frequencies_hz(&plate(
        16,
        h,
        ss,
        Some((Antisymmetric, Antisymmetric)),
        None,
    ));
    assert!(rel(f[0], ex(8.0)) < 0.01, "(2,2): {} vs {}", f[0], ex(8.0));
}

#[test]
fn thin_clamped_plate_matches_leissa() {
    let h = A / 100.0;
    let ex = |l: f64| kirchhoff_hz(l, h);
    check_convergence(
        Edge::Clamped,
        &[ex(35.985), ex(73.394), ex(73.394), ex(108.22)],
        h,
    );
    use Mid::*;
    let c = Edge::Clamped;
    let f = frequencies_hz(&plate(16, h, c, Some((Symmetric, Symmetric)), None));
    assert!(rel(f[0], ex(35.985)) < 0.01, "{} vs {}", f[0], ex(35.985));
    let f = frequencies_hz(&plate(16, h, c, Some((Antisymmetric, Symmetric)), None));
    assert!(rel(f[0], ex(73.394)) < 0.01, "{} vs {}", f[0], ex(73.394));
    let f = frequencies_hz(&plate(16, h, c, Some((Antisymmetric, Antisymmetric)), None));
    assert!(rel(f[0], ex(108.22)) < 0.01, "{} vs {}", f[0], ex(108.22));
}

#[test]
fn thick_simply_supported_plate_matches_mindlin() {
    let h = A / 10.0;
    let kappa = std::f64::consts::PI.powi(2) / 12.0;
    // Mindlin is a few per cent below Kirchhoff at a/h = 10: the check can tell them apart.
    let kirch = kirchhoff_hz(2.0 * std::f64::consts::PI.powi(2), h);
    assert!(mindlin_hz(1, 1, h, kappa) < 0.97 * kirch);
    use Mid::*;
    let ss = Edge::SimplySupported;
    for (sym, (m, n)) in [
        ((Symmetric, Symmetric), (1, 1)),
        ((Antisymmetric, Symmetric), (2, 1)),
        ((Antisymmetric, Antisymmetric), (2, 2)),
    ] {
        let f = frequencies_hz(&plate(16, h, ss, Some(sym), Some(kappa)));
        let e = mindlin_hz(m, n, h, kappa);
        assert!(rel(f[0], e) < 0.01, "({m},{n}): {} vs {}", f[0], e);
    }
}
