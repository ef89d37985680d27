//! Gmsh `.msh` 4.1 ASCII reader: structure, physical groups, errors with file:line:col, and a
//! plate read from a file against Kirchhoff (simply supported square, a/h = 100, λ = 2π²,
//! 16×16 elements, tolerance 1 %; reference as in fem_plates.rs).

// Tests index nodes and modes by position, like the formulas they check.
#![allow(clippy::needless_range_loop)]

use std::fmt::Write;

use meid::structure::gmsh::{parse_msh, read_msh};
use meid::structure::{Dof, FeModel, Material, Mesh};
use meid::Error;

const A: f64 = 1.0;

/// A structured n×n quad mesh of [0, a]² written as Gmsh 4.1 would: physical curves
/// "x_edges" (x = 0, a), "y_edges" (y = 0, a), physical surface "plate", physical point
/// "centre". Node tags are non-contiguous; the bottom-edge nodes sit in a parametric curve block.
fn plate_msh(n: usize) -> String {
    let tag = |i: usize, j: usize| 1000 + 3 * (j * (n + 1) + i);
    let xy = |i: usize, j: usize| (A * i as f64 / n as f64, A * j as f64 / n as f64);
    let mut s = String::new();
    s.push_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    s.push_str("$PhysicalNames\n4\n1 1 \"x_edges\"\n1 2 \"y_edges\"\n2 3 \"plate\"\n0 4 \"centre\"\n$EndPhysicalNames\n");
    s.push_str("$Entities\n1 4 1 0\n");
    writeln!(s, "1 {} {} 0 1 4", A / 2.0, A / 2.0).unwrap();
    for (c, phys) in [(1, 2), (2, 1), (3, 2), (4, 1)] {
        writeln!(s, "{c} 0 0 0 {A} {A} 0 1 {phys} 2 1 -1").unwrap();
    }
    writeln!(s, "1 0 0 0 {A} {A} 0 1 3 4 1 2 -3 -4").unwrap();
    s.push_str("$EndEntities\n");
    // Nodes: block 1 = bottom edge (curve 1, parametric), block 2 = the rest (surface 1).
    let bottom: Vec<(usize, usize)> = (0..=n).map(|i| (i, 0)).collect();
    let rest: Vec<(usize, usize)> = (1..=n).flat_map(|j| (0..=n).map(move |i| (i, j))).collect();
    let total = (n + 1) * (n + 1);
    writeln!(s, "$Nodes\n2 {total} {} {}", tag(0, 0), tag(n, n)).unwrap();
    writeln!(s, "1 1 1 {}", bottom.len()).unwrap();
    for &(i, j) in &bottom {
        writeln!(s, "{}", tag(i, j)).unwrap();
    }
    for &(i, j) in &bottom {
        let (x, y) = xy(i, j);
        writeln!(s, "{x} {y} 0 {x}").unwrap();
    }
    writeln!(s, "2 1 0 {}", rest.len()).unwrap();
    for &(i, j) in &rest {
        writeln!(s, "{}", tag(i, j)).unwrap();
    }
    for &(i, j) in &rest {
        let (x, y) = xy(i, j);
        writeln!(s, "{x:e} {y:e} 0.0").unwrap();
    }
    s.push_str("$EndNodes\n");
    // Elements: point, four edges of lines, quads.
    let mut blocks = Vec::new();
    let mut et = 1;
    blocks.push(format!("0 1 15 1\n{et} {}\n", tag(n / 2, n / 2)));
    et += 1;
    let edges: [Vec<(usize, usize)>; 4] = [
        (0..=n).map(|i| (i, 0)).collect(),
        (0..=n).map(|j| (n, j)).collect(),
        (0..=n).rev().map(|i| (i, n)).collect(),
        (0..=n).rev().map(|j| (0, j)).collect(),
    ];
    for (c, e) in edges.iter().enumerate() {
        let mut b = format!("1 {} 1 {n}\n", c + 1);
        for w in e.windows(2) {
            writeln!(b, "{et} {} {}", tag(w[0].0, w[0].1), tag(w[1].0, w[1].1)).unwrap();
            et += 1;
        }
        blocks.push(b);
    }
    let mut b = format!("2 1 3 {}\n", n * n);
    for j in 0..n {
        for i in 0..n {
            writeln!(
                b,
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
    blocks.push(b);
    writeln!(s, "$Elements\n{} {} 1 {}", blocks.len(), et - 1, et - 1).unwrap();
    for b in blocks {
        s.push_str(&b);
    }
    s.push_str("$EndElements\n$Comment\nignored section\n$EndComment\n");
    s
}

#[test]
fn reads_structure_and_physical_groups() {
    let n = 4;
    let g = parse_msh(&plate_msh(n), "plate.msh").unwrap();
    assert_eq!(g.nodes.len(), (n + 1) * (n + 1));
    assert_eq!(g.quads.len(), n * n);
    assert_eq!(g.node_sets["x_edges"].len(), 2 * (n + 1));
    assert_eq!(g.node_sets["y_edges"].len(), 2 * (n + 1));
    assert_eq!(g.node_sets["plate"].len(), (n + 1) * (n + 1));
    assert_eq!(g.element_sets["plate"].len(), n * n);
    let c = g.node_sets["centre"][0];
    assert_eq!(g.nodes[c], [0.5, 0.5, 0.0]);
    assert_eq!(g.node_tags[c], 1000 + 3 * (2 * 5 + 2));
    // first quad: tags of (0,0), (1,0), (1,1), (0,1)
    let q = g.quads[0].map(|i| g.node_tags[i]);
    assert_eq!(q, [1000, 1003, 1018, 1015]);
}

#[test]
fn plate_from_file_matches_kirchhoff() {
    let n = 16;
    let path = std::env::temp_dir().join(format!("meid-fem-gmsh-{}.msh", std::process::id()));
    std::fs::write(&path, plate_msh(n)).unwrap();
    let g = read_msh(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    let h = A / 100.0;
    let mut mesh = Mesh::new();
    g.add_to_mesh(&mut mesh, Material::STEEL, h).unwrap();
    for nd in 0..mesh.nodes.len() {
        mesh.fix(nd, &[Dof::Ux, Dof::Uy, Dof::Rz]);
    }
    for nd in mesh.point("x_edges").unwrap().to_vec() {
        mesh.fix(nd, &[Dof::Uz, Dof::Rx]);
    }
    for nd in mesh.point("y_edges").unwrap().to_vec() {
        mesh.fix(nd, &[Dof::Uz, Dof::Ry]);
    }
    // only single nodes as points in the modal model: drop the big sets
    mesh.points.retain(|k, _| k == "centre");
    let model = FeModel::assemble(mesh).unwrap();
    let modes = model.solve_dense().unwrap();
    let m = Material::STEEL;
    let d = m.youngs_modulus_pa * h.powi(3) / (12.0 * (1.0 - m.poisson_ratio.powi(2)));
    let exact = 2.0 * std::f64::consts::PI.powi(2) / (2.0 * std::f64::consts::PI * A * A)
        * (d / (m.density_kg_per_m3 * h)).sqrt();
    let f = modes.omega_rad_per_s[0] / (2.0 * std::f64::consts::PI);
    assert!((f / exact - 1.0).abs() < 0.01, "{f} vs {exact}");
    // the centre is the antinode of mode 1: the largest |w| of that mode
    let mm = model.modal_model(&modes, &[0], &[0.0]).unwrap();
    assert!(mm.points["centre"][0].abs() > 0.0);
}

fn input_error(text: &str) -> (String, String) {
    match parse_msh(text, "bad.msh").unwrap_err() {
        Error::Input { location, message } => (location, message),
        e => panic!("expected an input error, got {e}"),
    }
}

#[test]
fn errors_carry_file_line_and_column() {
    let (loc, msg) = input_error("$MeshFormat\n3.0 0 8\n$EndMeshFormat\n");
    assert_eq!(loc, "bad.msh:2:1");
    assert!(msg.contains("4.1"), "{msg}");

    let good = plate_msh(2);
    // corrupt the first coordinate of the second node block: "0 0.5 0.0" style line
    let lines: Vec<&str> = good.lines().collect();
    let target = lines.iter().position(|l| l.starts_with("2 1 0 ")).unwrap() + 7; // 6 tags then coords
    let mut bad: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    bad[target] = "0 0.x 0".to_string();
    let (loc, msg) = input_error(&(bad.join("\n") + "\n"));
    assert_eq!(loc, format!("bad.msh:{}:3", target + 1));
    assert!(
        msg.contains("expected a finite number") && msg.contains("0.x"),
        "{msg}"
    );

    // A second-order surface element (type 9, 6-node triangle) is refused with the fix.
    let tri6 = good.replace("2 1 3 4\n", "2 1 9 4\n");
    let (_, msg) = input_error(&tri6);
    assert!(
        msg.contains("6-node triangle") && msg.contains("Mesh.ElementOrder = 1"),
        "{msg}"
    );

    let (loc, msg) = input_error(&good.replace("$EndNodes\n", ""));
    assert!(
        msg.contains("$Elements starts before $Nodes"),
        "{loc}: {msg}"
    );

    let missing = good.replace("0 1 15 1\n1 1012\n", "0 1 15 1\n1 9999\n");
    assert_ne!(missing, good);
    let (_, msg) = input_error(&missing);
    assert!(
        msg.contains("'9999'") && msg.contains("not in $Nodes"),
        "{msg}"
    );
}

#[test]
fn missing_file_is_an_io_error() {
    let e = read_msh("/nonexistent/meid/plate.msh").unwrap_err();
    assert!(matches!(e, Error::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/meid/plate.msh"));
}
