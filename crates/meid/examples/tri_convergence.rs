//! Three-node shells (CST + DKT) from model files: mesh generator and convergence table.
//!
//! ```text
//! cargo run --release -p meid --example tri_convergence                 # the table (docs/explanations/fem.md)
//! cargo run --release -p meid --example tri_convergence -- --write-data crates/meid/tests/data
//! ```
//!
//! Each case is a `[structure.fem.model]` model file with a Gmsh 4.1 ASCII mesh of 3-node
//! triangles (element type 2), run through `meid::model::fem::from_file_with_analysis`, the path
//! `meid modes` takes. Meshes: the unit square cut into n × n cells, each split into two
//! triangles along a diagonal; "structured" uses the same diagonal everywhere, "irregular"
//! alternates the diagonal from cell to cell and moves every interior node by up to ±0.2 of a
//! cell in x and y (a fixed pseudo-random pattern), so no two triangles are alike.
//!
//! References:
//! * `ss_plate_tri`: simply supported (hard) square steel plate 1 m × 1 m × 0.01 m,
//!   E = 210 GPa, ν = 0.3, ρ = 7850 kg/m³; Kirchhoff closed form
//!   `f_mn = π/2 (m² + n²)/a² sqrt(D/(ρ t))`, `D = E t³/(12(1-ν²))`: 49.1724, 122.931 (×2),
//!   196.690, 245.862 (×2) Hz.
//! * FV16 and Test 21 as in `fem_convergence.rs` (NAFEMS R0015, values as tabulated in the Altair
//!   OptiStruct Verification Problems OS-V: 0430 and 0470). DKT is a Kirchhoff element: the
//!   thick plate of Test 21 (t/ℓ = 1/10) shows the missing shear deformation (about +1.4 % ×
//!   (m² + n²) on mode (m, n)); mesh it with quadrangles.
//!
//! `--write-data DIR` writes `ss_plate_tri.toml` and `ss_plate_tri.msh` (irregular 32 × 32 × 2)
//! for `crates/meid/tests/fem_tri.rs`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use meid::model::fem::from_file_with_analysis;

/// Deterministic value in [-1, 1) for grid node (i, j) (a 64-bit mix, not a statistical RNG).
fn jitter(i: usize, j: usize, salt: u64) -> f64 {
    let mut z = (i as u64) << 32 ^ (j as u64) ^ salt.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// A triangle mesh of the unit square mapped by `map(u, v) -> (x, y)`, z = 0, as Gmsh 4.1 ASCII:
/// physical surface "plate" (all triangles), physical curves "x0" (u = 0), "x1" (u = 1),
/// "y0" (v = 0), "y1" (v = 1) of 2-node lines (node sets). `irregular` as in the module doc.
fn tri_msh(n: usize, irregular: bool, map: impl Fn(f64, f64) -> (f64, f64)) -> String {
    let id = |i: usize, j: usize| j * (n + 1) + i + 1;
    let mut pts = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (mut u, mut v) = (i as f64 / n as f64, j as f64 / n as f64);
            if irregular && i > 0 && i < n && j > 0 && j < n {
                u += 0.2 * jitter(i, j, 1) / n as f64;
                v += 0.2 * jitter(i, j, 2) / n as f64;
            }
            pts.push(map(u, v));
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
    let np = pts.len();
    let _ = writeln!(s, "$Nodes\n1 {np} 1 {np}\n2 1 0 {np}");
    for k in 1..=np {
        let _ = writeln!(s, "{k}");
    }
    for (x, y) in &pts {
        let _ = writeln!(s, "{x:.15e} {y:.15e} 0");
    }
    s.push_str("$EndNodes\n");
    let edges: [Vec<[usize; 2]>; 4] = [
        (0..n).map(|j| [id(0, j), id(0, j + 1)]).collect(),
        (0..n).map(|j| [id(n, j), id(n, j + 1)]).collect(),
        (0..n).map(|i| [id(i, 0), id(i + 1, 0)]).collect(),
        (0..n).map(|i| [id(i, n), id(i + 1, n)]).collect(),
    ];
    let nt = 2 * n * n;
    let ne = nt + 4 * n;
    let _ = writeln!(s, "$Elements\n5 {ne} 1 {ne}");
    let mut tag = 0;
    for (c, lines) in edges.iter().enumerate() {
        let _ = writeln!(s, "1 {} 1 {}", c + 1, lines.len());
        for l in lines {
            tag += 1;
            let _ = writeln!(s, "{tag} {} {}", l[0], l[1]);
        }
    }
    let _ = writeln!(s, "2 1 2 {nt}");
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            let tris = if irregular && (i + j) % 2 == 1 {
                [[a, b, d], [b, c, d]]
            } else {
                [[a, b, c], [a, c, d]]
            };
            for t in tris {
                tag += 1;
                let _ = writeln!(s, "{tag} {} {} {}", t[0], t[1], t[2]);
            }
        }
    }
    s.push_str("$EndElements\n");
    s
}

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

fn model_file(comment: &str, title: &str, stem: &str, count: usize, body: &str) -> String {
    let mut s = String::new();
    for l in comment.lines() {
        let _ = writeln!(s, "# {l}");
    }
    let _ = writeln!(
        s,
        "name = \"{title}\"\n\n[structure]\nreference_mode = 1\n\n[structure.fem]\nselect = [1]\ncount = {count}\nsolver = \"lanczos\"\n\n[structure.fem.model]\nmesh = \"{stem}.msh\"\n{body}\npoints = {{ O_b = \"plate\", B = \"plate\" }}"
    );
    s.push_str(TAIL);
    s
}

const SS: &str = "constraints = [\n  { set = \"x0\", dofs = [\"uz\", \"rx\"] },\n  { set = \"x1\", dofs = [\"uz\", \"rx\"] },\n  \
                  { set = \"y0\", dofs = [\"uz\", \"ry\"] },\n  { set = \"y1\", dofs = [\"uz\", \"ry\"] },\n  \
                  { set = \"plate\", dofs = [\"ux\", \"uy\", \"rz\"] },\n]";

/// Kirchhoff simply supported square plate, a = 1 m, t = 0.01 m, steel (module doc).
fn ss_kirchhoff_hz(m: usize, n: usize) -> f64 {
    let (e, nu, rho, t, a) = (2.1e11_f64, 0.3_f64, 7850.0_f64, 0.01_f64, 1.0_f64);
    let d = e * t.powi(3) / (12.0 * (1.0 - nu * nu));
    std::f64::consts::PI / 2.0 * ((m * m + n * n) as f64) / (a * a) * (d / (rho * t)).sqrt()
}

fn ss_plate(n: usize, irregular: bool) -> (String, String) {
    let kind = if irregular { "irregular" } else { "structured" };
    let c = format!(
        "Simply supported (hard) square steel plate 1 m x 1 m x 0.01 m, E = 210 GPa, ν = 0.3,\n\
         ρ = 7850 kg/m³, {n} x {n} cells of two 3-node (CST + DKT) shells, {kind} mesh\n\
         (alternating diagonals, interior nodes moved by up to ±0.2 cell).\n\
         Kirchhoff closed form f_mn = π/2 (m² + n²)/a² sqrt(D/(ρ t)): 49.1724, 122.931 (x2),\n\
         196.690, 245.862 (x2) Hz.\n\
         Written by crates/meid/examples/tri_convergence.rs; used by tests/fem_tri.rs."
    );
    let m = model_file(
        &c,
        "simply supported square plate, triangles",
        "ss_plate_tri",
        6,
        &format!(
            "material = {{ youngs_modulus = 2.1e11, poisson_ratio = 0.3, density = 7850.0 }}\n\
             shells = [{{ set = \"plate\", thickness = 0.01 }}]\n{SS}"
        ),
    );
    (m, tri_msh(n, irregular, |u, v| (u, v)))
}

const NAFEMS_MATERIAL: &str =
    "material = { youngs_modulus = 2.0e11, poisson_ratio = 0.3, density = 8000.0 }";

fn fv16(n: usize, irregular: bool) -> (String, String) {
    let m = model_file(
        "NAFEMS FV16 with 3-node shells (see fem_convergence.rs)",
        "NAFEMS FV16, triangles",
        "plate_tri",
        6,
        &format!(
            "{NAFEMS_MATERIAL}\nshells = [{{ set = \"plate\", thickness = 0.05 }}]\n\
             constraints = [{{ set = \"x0\", dofs = [\"all\"] }}]"
        ),
    );
    (m, tri_msh(n, irregular, |u, v| (10.0 * u, 10.0 * v)))
}

fn t21(n: usize, irregular: bool) -> (String, String) {
    let m = model_file(
        "NAFEMS Test 21 with 3-node (Kirchhoff) shells (see fem_convergence.rs)",
        "NAFEMS Test 21, triangles",
        "plate_tri",
        8,
        &format!("{NAFEMS_MATERIAL}\nshells = [{{ set = \"plate\", thickness = 1.0 }}]\n{SS}"),
    );
    (m, tri_msh(n, irregular, |u, v| (10.0 * u, 10.0 * v)))
}

fn run(dir: &Path, stem: &str, files: (String, String)) -> Result<(Vec<f64>, usize), String> {
    let path = dir.join(format!("{stem}.toml"));
    std::fs::write(&path, &files.0).map_err(|e| e.to_string())?;
    let msh = files
        .0
        .lines()
        .find_map(|l| l.strip_prefix("mesh = \""))
        .and_then(|l| l.strip_suffix('"'))
        .unwrap_or("plate_tri.msh")
        .to_string();
    std::fs::write(dir.join(msh), files.1).map_err(|e| e.to_string())?;
    let (_, an) = from_file_with_analysis(&path, &[], None).map_err(|e| e.to_string())?;
    let an = an.ok_or("no FE analysis")?;
    Ok((an.table.frequency_hz.clone(), an.model.n_dofs()))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--write-data") {
        let dir = PathBuf::from(args.get(i + 1).expect("--write-data DIR"));
        let (m, msh) = ss_plate(32, true);
        std::fs::write(dir.join("ss_plate_tri.toml"), m).expect("write model");
        std::fs::write(dir.join("ss_plate_tri.msh"), msh).expect("write mesh");
        println!(
            "wrote ss_plate_tri.toml, ss_plate_tri.msh in {}",
            dir.display()
        );
        return;
    }
    let dir = std::env::temp_dir().join(format!("meid-tri-convergence-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let ss_ref: Vec<f64> = [(1, 1), (1, 2), (2, 1), (2, 2), (1, 3), (3, 1)]
        .iter()
        .map(|&(m, n)| ss_kirchhoff_hz(m, n))
        .collect();
    type Files = fn(usize, bool) -> (String, String);
    let cases: Vec<(&str, Files, Vec<f64>, Vec<usize>)> = vec![
        (
            "SS plate 1 m × 10 mm (Kirchhoff)",
            ss_plate,
            ss_ref,
            vec![8, 16, 24, 32],
        ),
        (
            "FV16 cantilevered plate",
            fv16,
            vec![0.421, 1.029, 2.582, 3.306, 3.753, 6.555],
            vec![8, 16, 32, 48],
        ),
        (
            "Test 21 thick SS plate",
            t21,
            vec![
                45.897, 109.44, 109.44, 167.89, 204.51, 204.51, 256.50, 256.50,
            ],
            vec![16, 32],
        ),
    ];
    println!(
        "| benchmark (triangles) | mesh | DOFs | frequencies (Hz), error vs reference (%) | largest error, absolute (%) |"
    );
    println!("|---|---|---|---|---|");
    for (label, files, reference, meshes) in cases {
        for irregular in [false, true] {
            for &n in &meshes {
                let mesh = format!(
                    "{n}×{n}×2 {}",
                    if irregular { "irregular" } else { "structured" }
                );
                match run(&dir, "case", files(n, irregular)) {
                    Ok((f, dofs)) => {
                        let mut cells = Vec::new();
                        let mut worst: f64 = 0.0;
                        for (k, r) in reference.iter().enumerate() {
                            match f.get(k) {
                                Some(x) => {
                                    let e = 100.0 * (x / r - 1.0);
                                    worst = worst.max(e.abs());
                                    cells.push(format!("{x:.4} ({e:+.2})"));
                                }
                                None => cells.push("(missing)".into()),
                            }
                        }
                        println!(
                            "| {label} | {mesh} | {dofs} | {} | {worst:.2} |",
                            cells.join(", ")
                        );
                    }
                    Err(e) => println!("| {label} | {mesh} | | error: {e} | |"),
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
