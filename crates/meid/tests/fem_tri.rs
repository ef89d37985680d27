//! Three-node shells (CST membrane + DKT bending, `meid::structure::tri3`) against closed forms.
//!
//! * Rigid bodies: a free distorted triangle mesh (and a free quad + triangle mesh) in a tilted
//!   plane has exactly six zero-energy modes.
//! * Patch tests: the MacNeal-Harder distorted patch (see fem_patch.rs) cut into ten triangles;
//!   the boundary nodes get an exact constant-strain or constant-curvature field, the interior
//!   nodes must reproduce it to round-off (1e-9 of the field's size).
//! * Thin simply supported (hard) plate, t/L = 1e-3: the lowest four frequencies converge to
//!   Kirchhoff's `f_mn = π/2 (m² + n²)/a² sqrt(D/(ρ t))` (no shear locking: DKT has no shear
//!   energy), within 1 % on a 24 × 24 × 2 mesh, structured and irregular.
//! * Mixed mesh: half quadrangles (MITC4), half triangles give the same frequencies as all
//!   quadrangles within the discretisation error of the two pure meshes.
//! * Gmsh 4.1 file with triangles read end to end from a model file (ss_plate_tri.toml), and
//!   bad triangles (degenerate, inverted, folded) refused with the file, line, element and nodes.

// Tests index nodes and modes by position, like the formulas they check.
#![allow(clippy::needless_range_loop)]

use std::path::PathBuf;

use faer::prelude::Solve;
use faer::Mat;
use meid::model::fem::from_file_with_analysis;
use meid::structure::{Dof, FeModel, Material, Mesh, ShellElement, TriShellElement};

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

/// Rows e1, e2, n of the tilted patch plane.
const ROT: [[f64; 3]; 3] = [[0.6, 0.8, 0.0], [-0.48, 0.36, 0.8], [0.64, -0.48, 0.6]];

fn to_global(v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| ROT[0][i] * v[0] + ROT[1][i] * v[1] + ROT[2][i] * v[2])
}

/// The patch as triangles of thickness `t` (each quad cut along its 1-3 diagonal) in the
/// tilted plane.
fn patch_mesh(t: f64) -> Mesh {
    let origin = [0.3, -0.2, 1.1];
    let mut mesh = Mesh::new();
    for p in LOCAL {
        let g = to_global([p[0], p[1], 0.0]);
        mesh.add_node([g[0] + origin[0], g[1] + origin[1], g[2] + origin[2]]);
    }
    for q in QUADS {
        for tr in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            mesh.add_triangle(TriShellElement::new(tr, Material::STEEL, t));
        }
    }
    mesh
}

/// Interior error of the patch with boundary nodes 0..4 prescribed by the local field.
fn patch_error(field: impl Fn(f64, f64) -> [f64; 6]) -> f64 {
    let model = FeModel::assemble(patch_mesh(0.001)).unwrap();
    let k = model.dense_stiffness();
    let exact: Vec<[f64; 6]> = LOCAL
        .iter()
        .map(|p| {
            let f = field(p[0], p[1]);
            let t = to_global([f[0], f[1], f[2]]);
            let o = to_global([f[3], f[4], f[5]]);
            [t[0], t[1], t[2], o[0], o[1], o[2]]
        })
        .collect();
    let idx = |node: usize, d: usize| model.dofs.reduced_index(node, d).unwrap();
    let pairs = |r: std::ops::Range<usize>| -> Vec<(usize, usize)> {
        r.flat_map(|n| (0..6).map(move |d| (n, d))).collect()
    };
    let interior = pairs(4..8);
    let boundary = pairs(0..4);
    let ni = interior.len();
    let mut kii = Mat::<f64>::zeros(ni, ni);
    let mut rhs = Mat::<f64>::zeros(ni, 1);
    for (a, &(n, d)) in interior.iter().enumerate() {
        for (b, &(m, e)) in interior.iter().enumerate() {
            kii[(a, b)] = k[(idx(n, d), idx(m, e))];
        }
        for &(m, e) in &boundary {
            rhs[(a, 0)] -= k[(idx(n, d), idx(m, e))] * exact[m][e];
        }
    }
    let u = kii.full_piv_lu().solve(&rhs);
    let scale = exact.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
    let mut err = 0.0_f64;
    for (a, &(n, d)) in interior.iter().enumerate() {
        err = err.max((u[(a, 0)] - exact[n][d]).abs());
    }
    err / scale
}

#[test]
fn triangle_membrane_patch_constant_strain() {
    // ε = (1e-3, 0.7e-3, 0.2e-3), ω = ½(v,x - u,y) = -0.2e-3 carried by θz.
    let err = patch_error(|x, y| {
        [
            1e-3 * (x + 0.3 * y),
            1e-3 * (-0.1 * x + 0.7 * y),
            0.0,
            0.0,
            0.0,
            0.5 * (-0.1e-3 - 0.3e-3),
        ]
    });
    eprintln!("membrane patch error {err:e}");
    assert!(err < 1e-9, "membrane patch error {err}");
}

#[test]
fn triangle_bending_patch_constant_curvature() {
    // w = ½(a x² + b y²) + c x y, θx = ∂w/∂y, θy = -∂w/∂x.
    let (a, b, c) = (2e-3, -1e-3, 1.5e-3);
    let err = patch_error(|x, y| {
        let w = 0.5 * (a * x * x + b * y * y) + c * x * y;
        [0.0, 0.0, w, b * y + c * x, -(a * x + c * y), 0.0]
    });
    eprintln!("bending patch error {err:e}");
    assert!(err < 1e-9, "bending patch error {err}");
}

/// Number of eigenvalues of K below 1e-12 of the largest (round-off), the largest of those and
/// the smallest one above, both relative to the largest.
fn zero_modes(model: &FeModel) -> (usize, f64, f64) {
    let k = model.dense_stiffness();
    let evd = k.self_adjoint_eigen(faer::Side::Lower).unwrap();
    let ev: Vec<f64> = (0..k.nrows()).map(|i| evd.S()[i]).collect();
    let max = ev.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
    let zeros = ev.iter().filter(|v| v.abs() < 1e-12 * max).count();
    let top_zero = ev
        .iter()
        .filter(|v| v.abs() < 1e-12 * max)
        .fold(0.0_f64, |a, b| a.max(b.abs()));
    let next = ev
        .iter()
        .filter(|v| v.abs() >= 1e-12 * max)
        .fold(f64::INFINITY, |a, b| a.min(*b));
    (zeros, top_zero / max, next / max)
}

/// Free patches (t = 20 mm on the 0.24 × 0.12 m patch): exactly six eigenvalues of K below
/// 1e-12 of the largest (round-off), the seventh above 1e-9 (the softest elastic mode sits at
/// about 2e-8: bending ∝ t³ against membrane ∝ t); at t = 1 mm the modal solver finds exactly
/// six rigid-body modes from K and M and the seventh mode above 1 Hz.
#[test]
fn free_triangle_meshes_have_six_rigid_modes() {
    let mixed = |t: f64| {
        // two quads of the patch kept as quads, the rest triangles
        let mut mesh = patch_mesh(t);
        mesh.triangles
            .retain(|e| ![[0, 1, 5], [0, 5, 4], [4, 5, 6], [4, 6, 7]].contains(&e.nodes));
        for q in [QUADS[0], QUADS[4]] {
            mesh.add_shell(ShellElement::new(q, Material::STEEL, t));
        }
        assert_eq!(mesh.triangles.len(), 6);
        mesh
    };
    for (label, mesh) in [("triangles", patch_mesh(0.02)), ("mixed", mixed(0.02))] {
        let (z, top, next) = zero_modes(&FeModel::assemble(mesh).unwrap());
        eprintln!(
            "free {label} patch: {z} zero modes (largest {top:e} of max), next/max = {next:e}"
        );
        assert_eq!(z, 6, "{label}");
        assert!(next > 1e-9, "{label}: {next}");
    }
    for (label, mesh) in [("triangles", patch_mesh(0.001)), ("mixed", mixed(0.001))] {
        let modes = FeModel::assemble(mesh).unwrap().solve_dense().unwrap();
        let f7 = modes.omega_rad_per_s[6] / (2.0 * std::f64::consts::PI);
        eprintln!(
            "free {label} patch t = 1 mm: {} rigid-body modes, 7th {f7} Hz",
            modes.rigid_body_modes
        );
        assert_eq!(modes.rigid_body_modes, 6, "{label}");
        assert!(f7 > 1.0, "{label}: {f7}");
    }
}

/// Mesh pattern of a square plate.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Pattern {
    /// All quadrangles.
    Quads,
    /// Every cell cut along the same diagonal.
    Structured,
    /// Alternating diagonals, interior nodes moved by up to ±0.2 cell (fixed pattern).
    Irregular,
    /// Quadrangles for x < a/2, structured triangles for x > a/2.
    Mixed,
}

/// Deterministic value in [-1, 1) for grid node (i, j).
fn jitter(i: usize, j: usize, salt: u64) -> f64 {
    let mut z = (i as u64) << 32 ^ (j as u64) ^ salt.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

const E: f64 = 2.1e11;
const NU: f64 = 0.3;
const RHO: f64 = 7850.0;

/// Hard simply supported unit square plate of thickness `t`, n × n cells, bending only
/// (ux = uy = θz = 0 everywhere).
fn ss_plate(n: usize, t: f64, pattern: Pattern) -> FeModel {
    let mat = Material {
        youngs_modulus_pa: E,
        poisson_ratio: NU,
        density_kg_per_m3: RHO,
    };
    let mut mesh = Mesh::new();
    let h = 1.0 / n as f64;
    let mut id = vec![vec![0; n + 1]; n + 1];
    for i in 0..=n {
        for j in 0..=n {
            let (mut x, mut y) = (i as f64 * h, j as f64 * h);
            if pattern == Pattern::Irregular && i > 0 && i < n && j > 0 && j < n {
                x += 0.2 * h * jitter(i, j, 1);
                y += 0.2 * h * jitter(i, j, 2);
            }
            id[i][j] = mesh.add_node([x, y, 0.0]);
        }
    }
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (id[i][j], id[i + 1][j], id[i + 1][j + 1], id[i][j + 1]);
            let quad = match pattern {
                Pattern::Quads => true,
                Pattern::Mixed => 2 * i < n,
                _ => false,
            };
            if quad {
                let mut el = ShellElement::new([a, b, c, d], mat, t);
                el.shear_factor = 5.0 / 6.0;
                mesh.add_shell(el);
            } else {
                let tris = if pattern == Pattern::Irregular && (i + j) % 2 == 1 {
                    [[a, b, d], [b, c, d]]
                } else {
                    [[a, b, c], [a, c, d]]
                };
                for tr in tris {
                    mesh.add_triangle(TriShellElement::new(tr, mat, t));
                }
            }
        }
    }
    for i in 0..=n {
        for j in 0..=n {
            let nd = id[i][j];
            mesh.fix(nd, &[Dof::Ux, Dof::Uy, Dof::Rz]);
            if i == 0 || i == n {
                mesh.fix(nd, &[Dof::Uz, Dof::Rx]);
            }
            if j == 0 || j == n {
                mesh.fix(nd, &[Dof::Uz, Dof::Ry]);
            }
        }
    }
    FeModel::assemble(mesh).unwrap()
}

fn kirchhoff_hz(m: usize, n: usize, t: f64) -> f64 {
    let d = E * t.powi(3) / (12.0 * (1.0 - NU * NU));
    std::f64::consts::PI / 2.0 * ((m * m + n * n) as f64) * (d / (RHO * t)).sqrt()
}

fn lowest_hz(model: &FeModel, count: usize) -> Vec<f64> {
    let modes = model.solve_dense_lowest(count).unwrap();
    assert_eq!(modes.rigid_body_modes, 0);
    modes
        .omega_rad_per_s
        .iter()
        .take(count)
        .map(|w| w / (2.0 * std::f64::consts::PI))
        .collect()
}

fn max_rel_err(f: &[f64], exact: &[f64]) -> f64 {
    f.iter()
        .zip(exact)
        .map(|(g, e)| (g / e - 1.0).abs())
        .fold(0.0, f64::max)
}

fn exact4(t: f64) -> Vec<f64> {
    [(1, 1), (1, 2), (2, 1), (2, 2)]
        .iter()
        .map(|&(m, n)| kirchhoff_hz(m, n, t))
        .collect()
}

/// t/L = 1e-3: errors of the lowest four modes fall with refinement (8, 16, 32 cells per side)
/// and are below 1 % at 32 × 32 × 2 on both the structured and the irregular mesh.
#[test]
fn thin_plate_triangles_converge_without_shear_locking() {
    let t = 1e-3;
    let exact = exact4(t);
    for pattern in [Pattern::Structured, Pattern::Irregular] {
        let mut prev = f64::INFINITY;
        for n in [8, 16, 32] {
            let f = lowest_hz(&ss_plate(n, t, pattern), 4);
            let err = max_rel_err(&f, &exact);
            eprintln!(
                "{pattern:?} {n}x{n}x2 t/L = 1e-3: {f:?} Hz, exact {exact:?}, max err {:.3} %",
                100.0 * err
            );
            assert!(
                err < prev,
                "{pattern:?} n = {n}: error {err} did not fall below {prev}"
            );
            prev = err;
        }
        assert!(prev < 0.01, "{pattern:?}: {prev}");
    }
}

/// The ratio f / f_Kirchhoff does not depend on the thickness from t/L = 1e-2 to 1e-4 (a locking
/// element stiffens as t falls): the 12 × 12 × 2 irregular mesh gives the same ratio to 1e-4.
#[test]
fn triangle_frequency_ratio_is_thickness_independent() {
    let ratio =
        |t: f64| lowest_hz(&ss_plate(12, t, Pattern::Irregular), 1)[0] / kirchhoff_hz(1, 1, t);
    let (a, b) = (ratio(1e-2), ratio(1e-4));
    eprintln!("f/f_K: t/L = 1e-2: {a}, 1e-4: {b}");
    assert!((a / b - 1.0).abs() < 1e-4, "{a} vs {b}");
}

/// Half quadrangles, half triangles (16 × 16 cells, t/L = 1e-2): every one of the lowest four
/// frequencies lies within the closed form ± the larger error of the pure meshes (+0.05 %), and
/// differs from the all-quad value by no more than that error.
#[test]
fn mixed_quad_triangle_mesh_matches_all_quad() {
    let t = 1e-2;
    let exact = exact4(t);
    let fq = lowest_hz(&ss_plate(16, t, Pattern::Quads), 4);
    let ft = lowest_hz(&ss_plate(16, t, Pattern::Structured), 4);
    let fm = lowest_hz(&ss_plate(16, t, Pattern::Mixed), 4);
    eprintln!("quads {fq:?}\ntris {ft:?}\nmixed {fm:?}\nexact {exact:?}");
    for k in 0..4 {
        let eq = (fq[k] / exact[k] - 1.0).abs();
        let et = (ft[k] / exact[k] - 1.0).abs();
        let bound = eq.max(et) + 5e-4;
        assert!(
            (fm[k] / exact[k] - 1.0).abs() <= bound,
            "mode {k}: {} vs {}",
            fm[k],
            exact[k]
        );
        assert!(
            (fm[k] / fq[k] - 1.0).abs() <= bound,
            "mode {k}: {} vs quads {}",
            fm[k],
            fq[k]
        );
    }
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// ss_plate_tri.toml: a Gmsh 4.1 mesh of 32 × 32 × 2 irregular triangles, 1 m × 1 m × 10 mm
/// steel, hard simple support from per-DOF constraints on the physical curves: the six lowest
/// frequencies within 1 % of Kirchhoff's closed form, and the (1,2)/(2,1) and (1,3)/(3,1) pairs
/// within 1 % of each other.
#[test]
fn gmsh_triangle_plate_from_model_file() {
    let (_, an) = from_file_with_analysis(&data("ss_plate_tri.toml"), &[], None).unwrap();
    let an = an.unwrap();
    let f = &an.table.frequency_hz;
    assert_eq!(an.modes.rigid_body_modes, 0);
    assert_eq!(an.model.mesh.triangles.len(), 2 * 32 * 32);
    assert!(an.model.mesh.shells.is_empty());
    let exact: Vec<f64> = [(1, 1), (1, 2), (2, 1), (2, 2), (1, 3), (3, 1)]
        .iter()
        .map(|&(m, n)| kirchhoff_hz(m, n, 0.01))
        .collect();
    eprintln!("ss_plate_tri: {f:?} Hz; exact {exact:?}");
    for k in 0..6 {
        assert!(
            (f[k] / exact[k] - 1.0).abs() <= 0.01,
            "mode {}: {} vs {}",
            k + 1,
            f[k],
            exact[k]
        );
    }
    // total mass ρ t a²
    let m = an.model.mesh.total_mass_kg();
    assert!((m / (7850.0 * 0.01) - 1.0).abs() < 1e-12, "{m}");
}

/// A minimal Gmsh 4.1 file: nodes of the unit square plus a fifth, the triangles given.
fn msh(nodes: &[[f64; 3]], tris: &[[usize; 3]]) -> String {
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    s.push_str("$PhysicalNames\n1\n2 1 \"plate\"\n$EndPhysicalNames\n");
    s.push_str("$Entities\n0 0 1 0\n1 0 0 0 1 1 0 1 1 0\n$EndEntities\n");
    let n = nodes.len();
    s.push_str(&format!("$Nodes\n1 {n} 1 {n}\n2 1 0 {n}\n"));
    for k in 1..=n {
        s.push_str(&format!("{k}\n"));
    }
    for p in nodes {
        s.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
    }
    s.push_str("$EndNodes\n");
    let m = tris.len();
    s.push_str(&format!("$Elements\n1 {m} 1 {m}\n2 1 2 {m}\n"));
    for (k, t) in tris.iter().enumerate() {
        s.push_str(&format!("{} {} {} {}\n", k + 1, t[0], t[1], t[2]));
    }
    s.push_str("$EndElements\n");
    s
}

fn read_err(name: &str, text: &str) -> String {
    let dir = std::env::temp_dir().join(format!("meid-fem-tri-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    let r = meid::structure::gmsh::read_msh(&p);
    let _ = std::fs::remove_file(&p);
    r.err().map(|e| e.to_string()).unwrap_or_default()
}

/// Degenerate (repeated node, collinear nodes), inverted (node order against the neighbour's)
/// and folded (consistent order, but lying back over the neighbour) triangles are refused with
/// the file, its line, the triangle tag and its node tags; the good mesh is read.
#[test]
fn bad_gmsh_triangles_are_refused() {
    let nodes = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 0.2, 0.0],
    ];
    let good = meid::structure::gmsh::read_msh({
        let dir = std::env::temp_dir().join(format!("meid-fem-tri-good-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("good.msh");
        std::fs::write(&p, msh(&nodes[..4], &[[1, 2, 3], [1, 3, 4]])).unwrap();
        p
    })
    .unwrap();
    assert_eq!(good.triangles.len(), 2);
    assert_eq!(good.triangle_sets["plate"], vec![0, 1]);

    let e = read_err("rep.msh", &msh(&nodes[..4], &[[1, 2, 3], [1, 3, 3]]));
    assert!(
        e.contains("rep.msh:")
            && e.contains("triangle 2")
            && e.contains("[1, 3, 3]")
            && e.contains("degenerate"),
        "{e}"
    );
    let line_nodes = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let e = read_err("col.msh", &msh(&line_nodes, &[[1, 2, 3], [1, 3, 4]]));
    assert!(
        e.contains("col.msh:")
            && e.contains("triangle 1")
            && e.contains("[1, 2, 3]")
            && e.contains("degenerate"),
        "{e}"
    );
    let e = read_err("inv.msh", &msh(&nodes[..4], &[[1, 2, 3], [1, 4, 3]]));
    assert!(
        e.contains("inv.msh:")
            && e.contains("triangle 2")
            && e.contains("[1, 4, 3]")
            && e.contains("inverted"),
        "{e}"
    );
    let e = read_err("fold.msh", &msh(&nodes, &[[1, 2, 3], [1, 3, 5]]));
    assert!(
        e.contains("fold.msh:")
            && e.contains("triangle 2")
            && e.contains("[1, 3, 5]")
            && e.contains("folded"),
        "{e}"
    );
}

/// A model file with inline nodes, `shells[].triangles` and per-DOF constraints on inline sets:
/// the 4 × 4 × 2 structured simply supported plate (t = 10 mm). Its lowest four frequencies
/// equal those of the same mesh built through the library (`ss_plate`) to 1e-9, and an inline
/// triangle ordered against its neighbour is refused naming the field and both triangles.
#[test]
fn inline_triangles_in_the_general_model() {
    let n = 4;
    let id = |i: usize, j: usize| i * (n + 1) + j;
    let mut nodes = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            nodes.push(format!(
                "[{}, {}, 0]",
                i as f64 / n as f64,
                j as f64 / n as f64
            ));
        }
    }
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            tris.push(format!("[{a}, {b}, {c}]"));
            tris.push(format!("[{a}, {c}, {d}]"));
        }
    }
    let set = |f: &dyn Fn(usize, usize) -> bool| -> String {
        let v: Vec<String> = (0..=n)
            .flat_map(|i| (0..=n).map(move |j| (i, j)))
            .filter(|&(i, j)| f(i, j))
            .map(|(i, j)| id(i, j).to_string())
            .collect();
        format!("[{}]", v.join(", "))
    };
    let model = |tris: &[String]| {
        format!(
            r#"name = "inline triangles"
[structure]
reference_mode = 1
[structure.fem]
select = [1]
count = 4
solver = "dense"
[structure.fem.model]
nodes = [{}]
sets = {{ x0 = {}, x1 = {}, y0 = {}, y1 = {}, all = {} }}
material = {{ youngs_modulus = 2.1e11, poisson_ratio = 0.3, density = 7850.0 }}
shells = [{{ thickness = 0.01, triangles = [{}] }}]
constraints = [
  {{ set = "x0", dofs = ["uz", "rx"] }}, {{ set = "x1", dofs = ["uz", "rx"] }},
  {{ set = "y0", dofs = ["uz", "ry"] }}, {{ set = "y1", dofs = ["uz", "ry"] }},
  {{ set = "all", dofs = ["ux", "uy", "rz"] }},
]
points = {{ O_b = "all", B = "all" }}
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
"#,
            nodes.join(", "),
            set(&|i, _| i == 0),
            set(&|i, _| i == n),
            set(&|_, j| j == 0),
            set(&|_, j| j == n),
            set(&|_, _| true),
            tris.join(", ")
        )
    };
    let dir = std::env::temp_dir().join(format!("meid-fem-tri-inline-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("inline.toml");
    std::fs::write(&p, model(&tris)).unwrap();
    let (_, an) = from_file_with_analysis(&p, &[], None).unwrap();
    let f = an.unwrap().table.frequency_hz.clone();
    let lib = lowest_hz(&ss_plate(n, 0.01, Pattern::Structured), 4);
    eprintln!("inline {f:?} vs library {lib:?}");
    for k in 0..4 {
        assert!((f[k] / lib[k] - 1.0).abs() < 1e-9, "{f:?} vs {lib:?}");
    }
    // reverse the second triangle: [0, 6, 1] → [0, 1, 6]
    let mut bad = tris.clone();
    let b = id(1, 1);
    let d = id(0, 1);
    bad[1] = format!("[0, {d}, {b}]");
    let p = dir.join("inverted.toml");
    std::fs::write(&p, model(&bad)).unwrap();
    let e = from_file_with_analysis(&p, &[], None)
        .err()
        .unwrap()
        .to_string();
    eprintln!("{e}");
    assert!(
        e.contains("shells[0].triangles[1]")
            && e.contains("inverted")
            && e.contains("triangles[0]"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `part = "bed"` on a Gmsh surface's shells: the model's bed mass m_b (for `md/mb`) is
/// ρ t A of its triangles, 7850 · 0.01 · 1 m² = 78.5 kg (the irregular triangles tile the
/// square exactly, to round-off), and `None` without the label.
#[test]
fn bed_part_on_a_gmsh_surface_gives_the_bed_mass() {
    let path = data("ss_plate_tri.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let name = path.display().to_string();
    let plain = meid::model::Model::from_text(&name, text.clone(), &[]).unwrap();
    assert_eq!(plain.bed_mass(), None);
    let labelled = text.replace(
        r#"shells = [{ set = "plate", thickness = 0.01 }]"#,
        r#"shells = [{ set = "plate", thickness = 0.01, part = "bed" }]"#,
    );
    assert_ne!(labelled, text);
    let m = meid::model::Model::from_text(&name, labelled, &[]).unwrap();
    let m_b = m.bed_mass().unwrap();
    assert!((m_b / 78.5 - 1.0).abs() < 1e-12, "m_b = {m_b} kg");
}

/// m_b comes from the mesh the modes came from: rewriting the Gmsh file with every x doubled
/// and reading the model again doubles it (157 kg), in the same process.
#[test]
fn bed_mass_follows_the_mesh_file() {
    let dir = std::env::temp_dir().join(format!("meid-bed-mesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(data("ss_plate_tri.toml"))
        .unwrap()
        .replace(
            r#"shells = [{ set = "plate", thickness = 0.01 }]"#,
            r#"shells = [{ set = "plate", thickness = 0.01, part = "bed" }]"#,
        );
    let model = dir.join("plate.toml");
    std::fs::write(&model, &text).unwrap();
    let msh = std::fs::read_to_string(data("ss_plate_tri.msh")).unwrap();
    std::fs::write(dir.join("ss_plate_tri.msh"), &msh).unwrap();
    let m_b = |p: &std::path::Path| meid::model::Model::from_file(p, &[]).unwrap().bed_mass();
    let one = m_b(&model).unwrap();
    assert!((one / 78.5 - 1.0).abs() < 1e-12, "{one} kg");
    // $Nodes of Gmsh 4.1: after each entity block header, `tag` lines then `x y z` lines.
    let mut stretched = String::new();
    let mut in_nodes = false;
    for line in msh.lines() {
        match line {
            "$Nodes" => in_nodes = true,
            "$EndNodes" => in_nodes = false,
            _ => {}
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        if in_nodes && f.len() == 3 && (f[0].contains('.') || f[0].contains('e')) {
            let x: f64 = f[0].parse().unwrap();
            stretched.push_str(&format!("{} {} {}\n", 2.0 * x, f[1], f[2]));
        } else {
            stretched.push_str(line);
            stretched.push('\n');
        }
    }
    assert_ne!(stretched.trim_end(), msh.trim_end());
    std::fs::write(dir.join("ss_plate_tri.msh"), &stretched).unwrap();
    let two = m_b(&model).unwrap();
    assert!((two / 157.0 - 1.0).abs() < 1e-12, "{two} kg");
    let _ = std::fs::remove_dir_all(&dir);
}
