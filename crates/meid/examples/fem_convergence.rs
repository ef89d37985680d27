//! NAFEMS free-vibration benchmarks as meid model files: mesh generator and convergence table.
//!
//! ```text
//! cargo run --release -p meid --example fem_convergence                 # the table (docs/explanations/fem.md)
//! cargo run --release -p meid --example fem_convergence -- --write-data crates/meid/tests/data
//! ```
//!
//! Every benchmark is a `[structure.fem.model]` model file (plus a Gmsh 4.1 ASCII mesh for the
//! plates), written here for several meshes into a temporary directory and run through
//! `meid::model::fem::from_file_with_analysis`, the path `meid modes` takes. `--write-data DIR`
//! writes the mesh each test in `crates/meid/tests/fem_general.rs` uses (the last mesh of each
//! row of the table) into DIR; the files in `crates/meid/tests/data` were made so.
//!
//! References (NAFEMS, *Selected Benchmarks for Natural Frequency Analysis*, publication R0015,
//! Abbassian, Dawswell and Knowles, 1987; values as tabulated in the Altair OptiStruct
//! Verification Problems manual, OS-V: 0400, 0420, 0425, 0430, 0440, 0470, and, for FV32, the
//! ENERCALC 3D verification example F-03, which cites NAFEMS Test No. 32):
//!
//! | test | structure | reference (Hz) |
//! |---|---|---|
//! | FV2 | pin-ended double cross, 8 arms of 5 m, 0.125 m square section, in-plane | 11.336, 17.709 (×7), 45.345, 57.390 (×7) |
//! | FV12 | free square plate 10 × 10 × 0.05 m | 6 rigid, 1.622, 2.360, 2.922, 4.233, 4.233, 7.416 |
//! | FV15 | clamped rhombic plate, sides 10 m, 45° skew, 0.05 m | 7.938, 12.835, 17.941, 19.133, 24.009, 27.922 |
//! | FV16 | square plate 10 × 10 × 0.05 m clamped on one edge | 0.421, 1.029, 2.582, 3.306, 3.753, 6.555 |
//! | FV32 | tapered membrane 10 m long, 5 m → 1 m wide, 0.05 m, clamped at the wide end | 44.623, 130.03, 162.70, 246.05, 379.90, 391.44 |
//! | Test 21 | simply supported thick square plate 10 × 10 × 1 m (hard support) | 45.897, 109.44 (×2), 167.89, 204.51 (×2), 256.50 (×2) |
//!
//! Material throughout: E = 200 GPa, ν = 0.3, ρ = 8000 kg/m³.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use meid::model::fem::from_file_with_analysis;

/// A structured quadrilateral mesh of the unit square mapped by `map(u, v) -> (x, y)`, z = 0,
/// as Gmsh 4.1 ASCII: physical surface "plate" (all quads, and so all nodes), physical curves
/// "x0" (u = 0), "x1" (u = 1), "y0" (v = 0), "y1" (v = 1) of 2-node lines (node sets).
fn grid_msh(nx: usize, ny: usize, map: impl Fn(f64, f64) -> (f64, f64)) -> String {
    let id = |i: usize, j: usize| j * (nx + 1) + i + 1;
    let mut pts = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            pts.push(map(i as f64 / nx as f64, j as f64 / ny as f64));
        }
    }
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    for &(x, y) in &pts {
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    let mut s = String::new();
    s.push_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    s.push_str("$PhysicalNames\n5\n2 1 \"plate\"\n1 2 \"x0\"\n1 3 \"x1\"\n1 4 \"y0\"\n1 5 \"y1\"\n$EndPhysicalNames\n");
    s.push_str("$Entities\n0 4 1 0\n");
    for c in 1..=4 {
        let _ = writeln!(
            s,
            "{c} {} {} 0 {} {} 0 1 {} 0",
            lo.0,
            lo.1,
            hi.0,
            hi.1,
            c + 1
        );
    }
    let _ = writeln!(s, "1 {} {} 0 {} {} 0 1 1 0", lo.0, lo.1, hi.0, hi.1);
    s.push_str("$EndEntities\n");
    let n = pts.len();
    let _ = writeln!(s, "$Nodes\n1 {n} 1 {n}\n2 1 0 {n}");
    for k in 1..=n {
        let _ = writeln!(s, "{k}");
    }
    for (x, y) in &pts {
        let _ = writeln!(s, "{x:.15e} {y:.15e} 0");
    }
    s.push_str("$EndNodes\n");
    let edges: [Vec<[usize; 2]>; 4] = [
        (0..ny).map(|j| [id(0, j), id(0, j + 1)]).collect(),
        (0..ny).map(|j| [id(nx, j), id(nx, j + 1)]).collect(),
        (0..nx).map(|i| [id(i, 0), id(i + 1, 0)]).collect(),
        (0..nx).map(|i| [id(i, ny), id(i + 1, ny)]).collect(),
    ];
    let nq = nx * ny;
    let ne = nq + 2 * (nx + ny);
    let _ = writeln!(s, "$Elements\n5 {ne} 1 {ne}");
    let mut tag = 0;
    for (c, lines) in edges.iter().enumerate() {
        let _ = writeln!(s, "1 {} 1 {}", c + 1, lines.len());
        for l in lines {
            tag += 1;
            let _ = writeln!(s, "{tag} {} {}", l[0], l[1]);
        }
    }
    let _ = writeln!(s, "2 1 3 {nq}");
    for j in 0..ny {
        for i in 0..nx {
            tag += 1;
            let _ = writeln!(
                s,
                "{tag} {} {} {} {}",
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            );
        }
    }
    s.push_str("$EndElements\n");
    s
}

/// What follows `[structure.fem.model]` in every benchmark file: meid needs an impact model to
/// build a `Model`; it plays no part in the frequencies.
const TAIL: &str = r#"
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
"#;

const MATERIAL: &str =
    "material = { youngs_modulus = 2.0e11, poisson_ratio = 0.3, density = 8000.0 }";

fn header(title: &str, comment: &str, select: usize, count: usize, solver: &str) -> String {
    let mut s = String::new();
    for l in comment.lines() {
        let _ = writeln!(s, "# {l}");
    }
    let _ = writeln!(
        s,
        "name = \"{title}\"\n\n[structure]\nreference_mode = 1\n\n[structure.fem]\nselect = [{select}]\ncount = {count}\nsolver = \"{solver}\"\n\n[structure.fem.model]"
    );
    s
}

/// One benchmark: its files for a mesh parameter `n`, its reference and how many rigid-body
/// modes precede the elastic ones.
struct Case {
    /// File stem in tests/data.
    stem: &'static str,
    label: &'static str,
    reference: Vec<f64>,
    rigid: usize,
    /// Mesh parameters of the table; the last one is the tests' mesh.
    meshes: Vec<usize>,
    /// (model file text, optional mesh text) for mesh parameter n.
    files: fn(usize) -> (String, Option<String>),
    mesh_label: fn(usize) -> String,
}

fn fv2(n: usize) -> (String, Option<String>) {
    let comment = format!(
        "NAFEMS FV2, pin-ended double cross (in-plane vibration): eight arms of L = 5 m at 45°\n\
         from the centre, square section 0.125 m x 0.125 m (A = 0.015625 m², I = 2.0345e-5 m⁴),\n\
         E = 200 GPa, ρ = 8000 kg/m³, {n} frame elements per arm. Pinned ends: ux = uy = 0 at the\n\
         arm ends; in-plane only: uz = rx = ry = 0 at every node.\n\
         Reference (NAFEMS, \"Selected Benchmarks for Natural Frequency Analysis\", FV2, as\n\
         tabulated in the Altair OptiStruct Verification Problems, OS-V: 0400 Pin-ended Double\n\
         Cross): 11.336, 17.709 (modes 2-8), 45.345, 57.390 (modes 10-16) Hz.\n\
         Written by crates/meid/examples/fem_convergence.rs; used by tests/fem_general.rs."
    );
    let mut s = header(
        "NAFEMS FV2 pin-ended double cross",
        &comment,
        1,
        16,
        "dense",
    );
    let mut nodes = vec![[0.0, 0.0]];
    let mut frames = Vec::new();
    let mut ends = Vec::new();
    for arm in 0..8 {
        let a = arm as f64 * std::f64::consts::FRAC_PI_4;
        let mut prev = 0;
        for k in 1..=n {
            let r = 5.0 * k as f64 / n as f64;
            nodes.push([r * a.cos(), r * a.sin()]);
            let cur = nodes.len() - 1;
            frames.push([prev, cur]);
            prev = cur;
        }
        ends.push(prev);
    }
    s.push_str("nodes = [\n");
    for p in &nodes {
        let _ = writeln!(s, "  [{:.15e}, {:.15e}, 0.0],", p[0], p[1]);
    }
    s.push_str("]\n");
    let all: Vec<String> = (0..nodes.len()).map(|i| i.to_string()).collect();
    let ends: Vec<String> = ends.iter().map(|i| i.to_string()).collect();
    let _ = writeln!(
        s,
        "sets = {{ centre = [0], pins = [{}], all = [{}] }}",
        ends.join(", "),
        all.join(", ")
    );
    let _ = writeln!(s, "{MATERIAL}");
    let i = 0.125_f64.powi(4) / 12.0;
    // Torsion constant of a square, 0.1406 a⁴ (Roark); it plays no part in-plane.
    let j = 0.1406 * 0.125_f64.powi(4);
    s.push_str("frames = [\n");
    for f in &frames {
        let _ = writeln!(
            s,
            "  {{ nodes = [{}, {}], area = 0.015625, iy = {i:e}, iz = {i:e}, j = {j:e} }},",
            f[0], f[1]
        );
    }
    s.push_str("]\n");
    s.push_str("constraints = [\n  { set = \"pins\", dofs = [\"ux\", \"uy\"] },\n  { set = \"all\", dofs = [\"uz\", \"rx\", \"ry\"] },\n]\n");
    s.push_str("points = { O_b = \"centre\", B = \"centre\" }\n");
    s.push_str(TAIL);
    (s, None)
}

fn plate_model(
    title: &str,
    comment: &str,
    stem: &str,
    select: usize,
    count: usize,
    body: &str,
) -> String {
    let mut s = header(title, comment, select, count, "lanczos");
    let _ = writeln!(s, "mesh = \"{stem}.msh\"\n{MATERIAL}\n{body}");
    s.push_str("points = { O_b = \"plate\", B = \"plate\" }\n");
    s.push_str(TAIL);
    s
}

fn fv12(n: usize) -> (String, Option<String>) {
    let c = format!(
        "NAFEMS FV12, free thin square plate: 10 m x 10 m x 0.05 m, E = 200 GPa, ν = 0.3,\n\
         ρ = 8000 kg/m³, no supports at all, {n} x {n} MITC4 shells (square_plate_10m.msh, shared by FV12, FV16 and Test 21).\n\
         Reference (NAFEMS, \"Selected Benchmarks for Natural Frequency Analysis\", FV12, as\n\
         tabulated in the Altair OptiStruct Verification Problems, OS-V: 0420 Free Thin Square\n\
         Plate, and the CATIA V5 Analysis verification \"Free Thin Square Plate\"): six rigid-body\n\
         modes, then 1.622, 2.360, 2.922, 4.233, 4.233, 7.416 Hz.\n\
         Written by crates/meid/examples/fem_convergence.rs; used by tests/fem_general.rs."
    );
    let m = plate_model(
        "NAFEMS FV12 free square plate",
        &c,
        "square_plate_10m",
        7,
        12,
        "shells = [{ set = \"plate\", thickness = 0.05 }]",
    );
    (m, Some(grid_msh(n, n, |u, v| (10.0 * u, 10.0 * v))))
}

fn fv15(n: usize) -> (String, Option<String>) {
    let c = format!(
        "NAFEMS FV15, clamped thin rhombic plate: sides 10 m, skew angle 45°, thickness 0.05 m,\n\
         E = 200 GPa, ν = 0.3, ρ = 8000 kg/m³, all four edges clamped, {n} x {n} skewed MITC4\n\
         shells (fv15_plate.msh, a Gmsh mesh).\n\
         Reference (NAFEMS, \"Selected Benchmarks for Natural Frequency Analysis\", FV15, as\n\
         tabulated in the Altair OptiStruct Verification Problems, OS-V: 0425 Clamped Thin\n\
         Rhombic Plate): 7.938, 12.835, 17.941, 19.133, 24.009, 27.922 Hz.\n\
         Written by crates/meid/examples/fem_convergence.rs; used by tests/fem_general.rs."
    );
    let m = plate_model(
        "NAFEMS FV15 clamped rhombic plate",
        &c,
        "fv15_plate",
        1,
        6,
        "shells = [{ set = \"plate\", thickness = 0.05 }]\n\
         constraints = [\n  { set = \"x0\", dofs = [\"all\"] },\n  { set = \"x1\", dofs = [\"all\"] },\n  \
         { set = \"y0\", dofs = [\"all\"] },\n  { set = \"y1\", dofs = [\"all\"] },\n]",
    );
    let s45 = std::f64::consts::FRAC_1_SQRT_2;
    (
        m,
        Some(grid_msh(n, n, |u, v| {
            (10.0 * u + 10.0 * v * s45, 10.0 * v * s45)
        })),
    )
}

fn fv16(n: usize) -> (String, Option<String>) {
    let c = format!(
        "NAFEMS FV16, cantilevered thin square plate: 10 m x 10 m x 0.05 m, E = 200 GPa, ν = 0.3,\n\
         ρ = 8000 kg/m³, the edge x = 0 clamped, {n} x {n} MITC4 shells (square_plate_10m.msh, shared by FV12, FV16 and Test 21).\n\
         Reference (NAFEMS, \"Selected Benchmarks for Natural Frequency Analysis\", FV16, as\n\
         tabulated in the Altair OptiStruct Verification Problems, OS-V: 0430 Cantilevered Thin\n\
         Square Plate): 0.421, 1.029, 2.582, 3.306, 3.753, 6.555 Hz.\n\
         Written by crates/meid/examples/fem_convergence.rs; used by tests/fem_general.rs."
    );
    let m = plate_model(
        "NAFEMS FV16 cantilevered square plate",
        &c,
        "square_plate_10m",
        1,
        6,
        "shells = [{ set = \"plate\", thickness = 0.05 }]\n\
         constraints = [{ set = \"x0\", dofs = [\"all\"] }]",
    );
    (m, Some(grid_msh(n, n, |u, v| (10.0 * u, 10.0 * v))))
}

fn fv32(n: usize) -> (String, Option<String>) {
    let c = format!(
        "NAFEMS FV32, cantilevered tapered membrane: 10 m long (x), 5 m wide at x = 0 tapering\n\
         linearly to 1 m at x = 10 m, symmetric about y = 0, thickness 0.05 m, E = 200 GPa,\n\
         ν = 0.3, ρ = 8000 kg/m³, ux = uy = 0 on the edge x = 0; membrane only: uz = rx = ry = 0\n\
         at every node. {} x {} shells (Q4 membrane, fv32_membrane.msh).\n\
         Reference (NAFEMS, \"Selected Benchmarks for Natural Frequency Analysis\", Test No. 32,\n\
         as tabulated in the ENERCALC 3D verification example F-03 \"Cantilevered Tapered\n\
         Membrane Vibration\"): 44.623, 130.03, 162.70, 246.05, 379.90, 391.44 Hz.\n\
         Written by crates/meid/examples/fem_convergence.rs; used by tests/fem_general.rs.",
        2 * n,
        n
    );
    let m = plate_model(
        "NAFEMS FV32 tapered membrane",
        &c,
        "fv32_membrane",
        1,
        6,
        "shells = [{ set = \"plate\", thickness = 0.05 }]\n\
         constraints = [\n  { set = \"x0\", dofs = [\"ux\", \"uy\"] },\n  \
         { set = \"plate\", dofs = [\"uz\", \"rx\", \"ry\"] },\n]",
    );
    (
        m,
        Some(grid_msh(2 * n, n, |u, v| {
            (10.0 * u, (v - 0.5) * (5.0 - 4.0 * u))
        })),
    )
}

fn t21(n: usize) -> (String, Option<String>) {
    let c = format!(
        "NAFEMS Test 21, simply supported thick square plate: 10 m x 10 m x 1 m, E = 200 GPa,\n\
         ν = 0.3, ρ = 8000 kg/m³, {n} x {n} MITC4 shells with shear factor π²/12 (Mindlin's).\n\
         Hard simple support by per-DOF constraints: uz = rx = 0 on x = 0 and x = 10 m,\n\
         uz = ry = 0 on y = 0 and y = 10 m; ux = uy = rz = 0 at every node (as the benchmark).\n\
         Reference (NAFEMS, \"Selected Benchmarks for Natural Frequency Analysis\", Test 21, as\n\
         tabulated in the Altair OptiStruct Verification Problems, OS-V: 0470 Simply-Supported\n\
         Thick Square Plate): 45.897, 109.44, 109.44, 167.89, 204.51, 204.51, 256.50, 256.50 Hz;\n\
         Mindlin's closed form with κ = π²/12 gives 45.895, 109.444, 167.886, 204.513, 256.502.\n\
         Written by crates/meid/examples/fem_convergence.rs; used by tests/fem_general.rs."
    );
    let m = plate_model(
        "NAFEMS Test 21 simply supported thick plate",
        &c,
        "square_plate_10m",
        1,
        8,
        "shells = [{ set = \"plate\", thickness = 1.0, shear_factor = 0.8224670334241132 }]\n\
         constraints = [\n  { set = \"x0\", dofs = [\"uz\", \"rx\"] },\n  { set = \"x1\", dofs = [\"uz\", \"rx\"] },\n  \
         { set = \"y0\", dofs = [\"uz\", \"ry\"] },\n  { set = \"y1\", dofs = [\"uz\", \"ry\"] },\n  \
         { set = \"plate\", dofs = [\"ux\", \"uy\", \"rz\"] },\n]",
    );
    (m, Some(grid_msh(n, n, |u, v| (10.0 * u, 10.0 * v))))
}

fn cases() -> Vec<Case> {
    let sq = |n: usize| format!("{n}×{n}");
    vec![
        Case {
            stem: "fv2",
            label: "FV2 double cross (frames)",
            reference: [11.336]
                .into_iter()
                .chain([17.709; 7])
                .chain([45.345])
                .chain([57.390; 7])
                .collect(),
            rigid: 0,
            meshes: vec![2, 4, 8, 16],
            files: fv2,
            mesh_label: |n| format!("{n}/arm"),
        },
        Case {
            stem: "fv12",
            label: "FV12 free plate",
            reference: vec![1.622, 2.360, 2.922, 4.233, 4.233, 7.416],
            rigid: 6,
            meshes: vec![8, 16, 24, 32, 48],
            files: fv12,
            mesh_label: sq,
        },
        Case {
            stem: "fv15",
            label: "FV15 clamped skew plate",
            reference: vec![7.938, 12.835, 17.941, 19.133, 24.009, 27.922],
            rigid: 0,
            meshes: vec![16, 32, 48, 64],
            files: fv15,
            mesh_label: sq,
        },
        Case {
            stem: "fv16",
            label: "FV16 cantilevered plate",
            reference: vec![0.421, 1.029, 2.582, 3.306, 3.753, 6.555],
            rigid: 0,
            meshes: vec![8, 16, 32, 48],
            files: fv16,
            mesh_label: sq,
        },
        Case {
            stem: "fv32",
            label: "FV32 tapered membrane",
            reference: vec![44.623, 130.03, 162.70, 246.05, 379.90, 391.44],
            rigid: 0,
            meshes: vec![4, 8, 16, 32],
            files: fv32,
            mesh_label: |n| format!("{}×{n}", 2 * n),
        },
        Case {
            stem: "nafems_t21",
            label: "Test 21 thick SS plate",
            reference: vec![
                45.897, 109.44, 109.44, 167.89, 204.51, 204.51, 256.50, 256.50,
            ],
            rigid: 0,
            meshes: vec![8, 16, 32, 48],
            files: t21,
            mesh_label: sq,
        },
    ]
}

fn mesh_file_name(stem: &str) -> &'static str {
    match stem {
        "fv12" | "fv16" | "nafems_t21" => "square_plate_10m.msh",
        "fv15" => "fv15_plate.msh",
        "fv32" => "fv32_membrane.msh",
        _ => "unused.msh",
    }
}

fn write_case(dir: &Path, case: &Case, n: usize) -> PathBuf {
    let (model, mesh) = (case.files)(n);
    let path = dir.join(format!("{}.toml", case.stem));
    std::fs::write(&path, model).expect("write model file");
    if let Some(m) = mesh {
        std::fs::write(dir.join(mesh_file_name(case.stem)), m).expect("write mesh");
    }
    path
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--write-data") {
        let dir = PathBuf::from(args.get(i + 1).expect("--write-data DIR"));
        for case in cases() {
            let n = *case.meshes.last().expect("meshes");
            let p = write_case(&dir, &case, n);
            println!("wrote {}", p.display());
        }
        return;
    }
    // `fem_convergence [STEM [n1,n2,...]]`: one benchmark, optionally other meshes.
    let only: Option<&String> = args.get(1);
    let custom: Option<Vec<usize>> = args
        .get(2)
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect());
    let dir = std::env::temp_dir().join(format!("meid-fem-convergence-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    println!(
        "| benchmark | mesh | DOFs | frequencies (Hz), error vs reference (%) | largest error, absolute (%) |"
    );
    println!("|---|---|---|---|---|");
    for case in cases() {
        if only.is_some_and(|o| o != case.stem) {
            continue;
        }
        let meshes = custom.clone().unwrap_or_else(|| case.meshes.clone());
        for &n in &meshes {
            let path = write_case(&dir, &case, n);
            let (_, an) = match from_file_with_analysis(&path, &[], None) {
                Ok(x) => x,
                Err(e) => {
                    println!(
                        "| {} | {} | | error: {e} | |",
                        case.label,
                        (case.mesh_label)(n)
                    );
                    continue;
                }
            };
            let an = an.expect("FE analysis");
            let f = &an.table.frequency_hz;
            let mut cells = Vec::new();
            let mut worst: f64 = 0.0;
            for (k, r) in case.reference.iter().enumerate() {
                let Some(x) = f.get(case.rigid + k) else {
                    cells.push("(missing)".to_string());
                    continue;
                };
                let e = 100.0 * (x / r - 1.0);
                worst = worst.max(e.abs());
                cells.push(format!("{x:.4} ({e:+.2})"));
            }
            println!(
                "| {} | {} | {} | {} | {:.2} |",
                case.label,
                (case.mesh_label)(n),
                an.model.n_dofs(),
                cells.join(", "),
                worst
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
