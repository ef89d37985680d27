//! Bad input gives errors that name the element or node and what would be valid.

// Tests index nodes and modes by position, like the formulas they check.
#![allow(clippy::needless_range_loop)]

use meid::structure::{FeModel, FrameElement, Material, Mesh, Section, ShellElement};

fn square(mesh: &mut Mesh, p: [[f64; 2]; 4]) -> [usize; 4] {
    p.map(|q| mesh.add_node([q[0], q[1], 0.0]))
}

fn err_of(mesh: Mesh) -> String {
    FeModel::assemble(mesh).unwrap_err().to_string()
}

#[test]
fn degenerate_shell_is_rejected() {
    let mut mesh = Mesh::new();
    let n = square(&mut mesh, [[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    mesh.add_shell(ShellElement::new(n, Material::STEEL, 0.01));
    let e = err_of(mesh);
    assert!(
        e.contains("shell element 0") && e.contains("degenerate"),
        "{e}"
    );
}

#[test]
fn repeated_node_shell_is_rejected() {
    let mut mesh = Mesh::new();
    let n = square(&mut mesh, [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    mesh.add_shell(ShellElement::new(
        [n[0], n[1], n[2], n[2]],
        Material::STEEL,
        0.01,
    ));
    mesh.add_shell(ShellElement::new(n, Material::STEEL, 0.01));
    let e = err_of(mesh);
    assert!(
        e.contains("shell element 0") && e.contains("repeated"),
        "{e}"
    );
}

#[test]
fn inverted_shell_is_rejected() {
    let mut mesh = Mesh::new();
    let n = square(&mut mesh, [[0.0, 0.0], [1.0, 0.0], [0.3, 0.3], [0.0, 1.0]]);
    mesh.add_shell(ShellElement::new(n, Material::STEEL, 0.01));
    let e = err_of(mesh);
    assert!(
        e.contains("shell element 0") && e.contains("inverted"),
        "{e}"
    );
}

#[test]
fn zero_length_frame_is_rejected() {
    let mut mesh = Mesh::new();
    let a = mesh.add_node([0.0, 0.0, 0.0]);
    let b = mesh.add_node([0.0, 0.0, 0.0]);
    let sec = Section::solid_circle(0.01).unwrap();
    mesh.add_frame(FrameElement::new([a, b], Material::STEEL, sec));
    let e = err_of(mesh);
    assert!(
        e.contains("frame element 0") && e.contains("zero length"),
        "{e}"
    );
}

#[test]
fn unused_node_is_rejected() {
    let mut mesh = Mesh::new();
    let n = square(&mut mesh, [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    mesh.add_shell(ShellElement::new(n, Material::STEEL, 0.01));
    mesh.add_node([5.0, 5.0, 5.0]);
    let e = err_of(mesh);
    assert!(
        e.contains("node 4") && e.contains("used by no element"),
        "{e}"
    );
}

#[test]
fn non_positive_thickness_and_modulus_are_rejected() {
    let mut mesh = Mesh::new();
    let n = square(&mut mesh, [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    mesh.add_shell(ShellElement::new(n, Material::STEEL, 0.0));
    let e = err_of(mesh.clone());
    assert!(
        e.contains("shell element 0") && e.contains("thickness") && e.contains("> 0"),
        "{e}"
    );
    mesh.shells[0].thickness_m = 0.01;
    mesh.shells[0].material.youngs_modulus_pa = -1.0;
    let e = err_of(mesh);
    assert!(e.contains("Young's modulus") && e.contains("> 0 Pa"), "{e}");
}

#[test]
fn bad_sections_are_rejected() {
    let e = Section::tube(0.02, 0.015).unwrap_err().to_string();
    assert!(e.contains("tube wall"), "{e}");
    let e = Section::new(1e-4, 0.0, 1e-8, 1e-8).unwrap_err().to_string();
    assert!(e.contains("Iy"), "{e}");
}

#[test]
fn unknown_point_name_lists_known_names() {
    let mut mesh = Mesh::new();
    let n = square(&mut mesh, [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    mesh.add_shell(ShellElement::new(n, Material::STEEL, 0.01));
    mesh.name_point("O_b", vec![n[2]]);
    mesh.name_point("B", vec![n[1]]);
    let model = FeModel::assemble(mesh).unwrap();
    let e = model.point_functional("O_d").unwrap_err().to_string();
    assert!(
        e.contains("unknown point name 'O_d'") && e.contains("did you mean 'O_b'"),
        "{e}"
    );
    assert!(e.contains("known points: B, O_b"), "{e}");
}

#[test]
fn node_out_of_range_is_rejected() {
    let mut mesh = Mesh::new();
    let n = square(&mut mesh, [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    mesh.add_shell(ShellElement::new(
        [n[0], n[1], n[2], 9],
        Material::STEEL,
        0.01,
    ));
    let e = err_of(mesh);
    assert!(e.contains("shell element 0") && e.contains("node 9"), "{e}");
}
