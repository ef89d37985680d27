//! Frame end releases in `[structure.fem.model]` (issue 13, point 1), from model files in
//! crates/meid/tests/data, against Euler-Bernoulli closed forms.

use std::f64::consts::PI;
use std::path::PathBuf;

use meid::model::fem::from_file_with_analysis;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

// The beam of the three files: L = 2 m, E = 210 GPa, ρ = 7850 kg/m³, A = 1e-3 m²,
// Iy = 4e-7 m⁴, Iz = 1e-7 m⁴ (torsion and axial modes lie above 1 kHz).
const L: f64 = 2.0;
const E: f64 = 2.1e11;
const RHO: f64 = 7850.0;
const A: f64 = 1.0e-3;
const I_PLANES: [f64; 2] = [4.0e-7, 1.0e-7];

/// `f = (βL)² / (2π L²) sqrt(EI/(ρA))` for each βL and both bending planes, sorted.
fn bending(beta_l: &[f64]) -> Vec<f64> {
    let mut f: Vec<f64> = beta_l
        .iter()
        .flat_map(|bl| {
            I_PLANES
                .iter()
                .map(move |i| bl * bl / (2.0 * PI * L * L) * (E * i / (RHO * A)).sqrt())
        })
        .collect();
    f.sort_by(|a, b| a.partial_cmp(b).unwrap());
    f
}

fn modes(name: &str) -> (Vec<f64>, usize) {
    let (_, an) = from_file_with_analysis(&data(name), &[], None).unwrap();
    let an = an.unwrap();
    (an.table.frequency_hz.clone(), an.modes.rigid_body_modes)
}

fn assert_close(label: &str, f: &[f64], first: usize, want: &[f64], tol: f64) {
    for (k, w) in want.iter().enumerate() {
        let x = f[first + k];
        assert!(
            (x / w - 1.0).abs() <= tol,
            "{label} mode {}: {x} Hz vs closed form {w} Hz ({:+.2e})",
            first + k + 1,
            x / w - 1.0
        );
    }
}

/// Both end nodes clamped, both bending rotations released at both ends: a simply supported
/// beam, `f_n = n²π/(2L²) sqrt(EI/(ρA))` (βL = nπ) in each plane; the six lowest within 2e-4
/// (measured 4e-7, 4e-7, 7e-6, 7e-6, 3.4e-5, 1.1e-4: 20 cubic elements converge as h⁴; clamped,
/// the first would be (4.730/π)² = 2.27 times higher).
#[test]
fn fixed_fixed_beam_with_released_rotations_is_simply_supported() {
    let (f, rigid) = modes("frame_ss_by_releases.toml");
    eprintln!("simply supported by releases: {f:?}");
    assert_eq!(rigid, 0);
    let want = bending(&[PI, 2.0 * PI, 3.0 * PI, 4.0 * PI]);
    assert_close("simply supported", &f, 0, &want[..6], 2e-4);
}

/// Both end nodes clamped, the rotations released at x = L only: a propped cantilever,
/// tan βL = tanh βL, βL = 3.926602, 7.068583, 10.210176, 13.351768; the six lowest within
/// 2e-4 (measured 1.2e-6, 1.2e-6, 1.1e-5, 1.1e-5, 4.7e-5, 1.4e-4).
#[test]
fn released_rotation_at_one_end_gives_a_propped_cantilever() {
    let (f, rigid) = modes("frame_propped_by_releases.toml");
    eprintln!("propped cantilever by a release: {f:?}");
    assert_eq!(rigid, 0);
    let want = bending(&[3.926602, 7.068583, 10.210176, 13.351768]);
    assert_close("propped cantilever", &f, 0, &want[..6], 2e-4);
}

/// The rotations released at the clamped root of a cantilever leave a mechanism with mass (the
/// beam swings on a pin): the modal solver's rigid-body check finds the two swinging modes at
/// 0 Hz, and the elastic modes are those of a pinned-free beam, tan βL = tanh βL
/// (βL = 3.926602, 7.068583), within 2e-5 (measured 1.2e-6, 1.2e-6, 1.1e-5, 1.1e-5).
#[test]
fn released_root_rotation_is_a_zero_mode_found_by_the_rigid_body_check() {
    let (f, rigid) = modes("frame_pinned_free_by_release.toml");
    eprintln!("pinned-free by a release: {f:?}, rigid {rigid}");
    assert_eq!(rigid, 2);
    assert_eq!(f[0], 0.0);
    assert_eq!(f[1], 0.0);
    let want = bending(&[3.926602, 7.068583]);
    assert_close("pinned-free", &f, 2, &want, 2e-5);
}

/// Writes a model file with the given `[structure.fem.model]` frames/constraints into a fresh
/// temporary directory and returns the error of reading it.
fn error_of(nodes: &str, frames: &str, constraints: &str) -> String {
    let text = std::fs::read_to_string(data("frame_ss_by_releases.toml")).unwrap();
    let start = text.find("nodes = [[").unwrap();
    let end = text.find("points = {").unwrap();
    let body = format!(
        "nodes = {nodes}\nsets = {{ ends = [0, 1], mid = [2] }}\nframes = [{frames}]\nconstraints = {constraints}\n"
    );
    let text = format!("{}{}{}", &text[..start], body, &text[end..]);
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("meid-releases-{}-{k}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("model.toml");
    std::fs::write(&path, text).unwrap();
    let e = from_file_with_analysis(&path, &[], None)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    let _ = std::fs::remove_dir_all(&dir);
    e
}

/// Releases that leave a mechanism with no inertia are errors naming what to change:
/// the axial DOF released at both ends of one element; a hinge node whose two frame ends both
/// release the bending rotations (nothing holds the node's rotation); a shear release; an
/// unknown name; a node that is not an end of the member.
#[test]
fn mechanism_releases_are_refused_from_model_files() {
    let nodes = "[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 0.0, 0.0]]";
    let sec = "area = 1.0e-3, iy = 4.0e-7, iz = 1.0e-7, j = 1.0e-5";
    let fixed = r#"[{ set = "ends", dofs = ["all"] }]"#;
    let e = error_of(
        nodes,
        &format!(
            r#"{{ nodes = [0, 2], {sec}, releases = [{{ node = "ends", dofs = ["ux"] }}, {{ node = 2, dofs = ["ux"] }}] }}, {{ nodes = [2, 1], {sec} }}"#
        ),
        fixed,
    );
    assert!(
        e.contains("frames[0].releases") && e.contains("mechanism"),
        "{e}"
    );
    let e = error_of(
        nodes,
        &format!(
            r#"{{ nodes = [0, 2], {sec}, releases = [{{ node = 2, dofs = ["ry", "rz"] }}] }}, {{ nodes = [2, 1], {sec}, releases = [{{ node = 2, dofs = ["ry", "rz"] }}] }}"#
        ),
        fixed,
    );
    assert!(
        e.contains("node 2") && e.contains("mechanism") && e.contains("constraints"),
        "{e}"
    );
    let e = error_of(
        nodes,
        &format!(
            r#"{{ nodes = [0, 2], {sec}, releases = [{{ node = 0, dofs = ["uy"] }}] }}, {{ nodes = [2, 1], {sec} }}"#
        ),
        fixed,
    );
    assert!(
        e.contains("frames[0].releases[0].dofs") && e.contains("'uy'"),
        "{e}"
    );
    let e = error_of(
        nodes,
        &format!(
            r#"{{ nodes = [0, 2], {sec}, releases = [{{ node = 1, dofs = ["ry"] }}] }}, {{ nodes = [2, 1], {sec} }}"#
        ),
        fixed,
    );
    assert!(
        e.contains("frames[0].releases[0].node") && e.contains("not an end"),
        "{e}"
    );
}

/// The same simply supported beam from a Gmsh 4.1 mesh (frame_ss_gmsh.toml/.msh): the frames
/// are the 2-node lines of the physical curve `beam`, released at the physical point `ends`;
/// the same six frequencies to 2e-4 of the closed form and to 1e-9 of the inline model.
#[test]
fn releases_on_a_gmsh_curve_give_the_same_simply_supported_beam() {
    let (f, rigid) = modes("frame_ss_gmsh.toml");
    let (g, _) = modes("frame_ss_by_releases.toml");
    eprintln!("simply supported from Gmsh: {f:?}");
    assert_eq!(rigid, 0);
    let want = bending(&[PI, 2.0 * PI, 3.0 * PI, 4.0 * PI]);
    assert_close("simply supported (Gmsh)", &f, 0, &want[..6], 2e-4);
    for k in 0..6 {
        assert!(
            (f[k] / g[k] - 1.0).abs() < 1e-9,
            "mode {}: {} vs {}",
            k + 1,
            f[k],
            g[k]
        );
    }
}
