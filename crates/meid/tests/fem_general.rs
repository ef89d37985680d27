//! The general FE model section `[structure.fem.model]`, validated from model files
//! (crates/meid/tests/data) against published references (issue 13, point 5).

use std::path::PathBuf;

use meid::model::fem::from_file_with_analysis;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// Euler-Bernoulli cantilever of 20 frame elements (eb_cantilever.toml):
/// `f_n = (β_n L)² / (2π L²) sqrt(EI/(ρA))`, β₁L = 1.875104, β₂L = 4.694091; the square section
/// bends alike in y and z, so each frequency is a pair. Within 1e-4 (cubic frames converge as h⁴).
#[test]
fn eb_cantilever_from_model_file() {
    let (_, an) = from_file_with_analysis(&data("eb_cantilever.toml"), &[], None).unwrap();
    let an = an.unwrap();
    let f = &an.table.frequency_hz;
    let (e, rho, a, i, l): (f64, f64, f64, f64, f64) =
        (2.1e11, 7850.0, 4.0e-4, 0.02_f64.powi(4) / 12.0, 1.0);
    let exact =
        |bl: f64| bl * bl / (2.0 * std::f64::consts::PI * l * l) * (e * i / (rho * a)).sqrt();
    eprintln!(
        "cantilever: {f:?} Hz; exact {} {}",
        exact(1.875104),
        exact(4.694091)
    );
    assert_eq!(an.modes.rigid_body_modes, 0);
    for (k, bl) in [(0, 1.875104), (1, 1.875104), (2, 4.694091), (3, 4.694091)] {
        let x = exact(bl);
        assert!(
            (f[k] - x).abs() <= 1e-4 * x,
            "mode {}: {} vs {x}",
            k + 1,
            f[k]
        );
    }
}

/// Frequencies (Hz) and the number of rigid-body modes of a model file in tests/data.
fn modes_of(name: &str) -> (Vec<f64>, usize) {
    let (_, an) = from_file_with_analysis(&data(name), &[], None).unwrap();
    let an = an.unwrap();
    (an.table.frequency_hz.clone(), an.modes.rigid_body_modes)
}

/// Asserts `|f[first + k] / reference[k] - 1| <= 0.01` for every k not in `skip`.
fn within_one_percent(label: &str, f: &[f64], first: usize, reference: &[f64], skip: &[usize]) {
    for (k, r) in reference.iter().enumerate() {
        if skip.contains(&k) {
            continue;
        }
        let x = f[first + k];
        assert!(
            (x / r - 1.0).abs() <= 0.01,
            "{label} mode {}: {x} Hz vs NAFEMS {r} Hz ({:+.2} %)",
            first + k + 1,
            100.0 * (x / r - 1.0)
        );
    }
}

// References: NAFEMS, "Selected Benchmarks for Natural Frequency Analysis" (R0015, Abbassian,
// Dawswell and Knowles, 1987), values as tabulated in the Altair OptiStruct Verification
// Problems (OS-V: 0400 Pin-ended Double Cross, 0420 Free Thin Square Plate, 0425 Clamped Thin
// Rhombic Plate, 0430 Cantilevered Thin Square Plate, 0470 Simply-Supported Thick Square Plate)
// and, for FV32, the ENERCALC 3D verification example F-03 "Cantilevered Tapered Membrane
// Vibration" (which cites NAFEMS Test No. 32); FV12 also in the CATIA V5 Analysis verification
// "Free Thin Square Plate". The model files and meshes are written by
// `cargo run --release -p meid --example fem_convergence -- --write-data crates/meid/tests/data`;
// the mesh-convergence table is in docs/explanations/fem.md.

/// NAFEMS FV2, pin-ended double cross (fv2.toml): eight frame arms of 5 m, 16 elements each,
/// pinned (ux = uy = 0) at the arm ends, in-plane by per-DOF constraints (uz = rx = ry = 0 on
/// the set of all nodes). Reference 11.336, 17.709 (modes 2-8), 45.345, 57.390 (modes 10-16) Hz;
/// each within 1 % (measured: largest −0.55 %, modes 10-11 at 57.076 Hz; modes 2-3 at 17.681 Hz,
/// −0.16 %: the reference lists one value for groups the Euler-Bernoulli solution splits).
#[test]
fn nafems_fv2_double_cross_from_model_file() {
    let (f, rigid) = modes_of("fv2.toml");
    eprintln!("FV2: {f:?} Hz");
    assert_eq!(rigid, 0);
    let mut r = vec![11.336];
    r.extend([17.709; 7]);
    r.push(45.345);
    r.extend([57.390; 7]);
    within_one_percent("FV2", &f, 0, &r, &[]);
    // The symmetric groups are degenerate: modes 2-3, 4-8, 10-11, 12-16.
    for (a, b) in [(1, 2), (3, 7), (9, 10), (11, 15)] {
        assert!(
            (f[b] - f[a]).abs() <= 1e-6 * f[a],
            "modes {}-{}: {f:?}",
            a + 1,
            b + 1
        );
    }
}

/// Thin-plate (Kirchhoff) frequencies of FV12's elastic modes 7-12 (Hz), from the Rayleigh-Ritz
/// solution of `fem_kirchhoff_ritz.rs` (Legendre degree 17, converged to 1e-7; its test asserts
/// these figures). The sixth is a degenerate pair, 7.356 Hz twice.
const FV12_KIRCHHOFF: [f64; 6] = [1.621654, 2.359496, 2.922282, 4.190243, 4.190243, 7.356004];

/// NAFEMS FV15's first six thin-plate frequencies (Hz), Ritz upper bounds (degree 21) from
/// `fem_kirchhoff_ritz.rs`: the exact Kirchhoff values are at most these.
const FV15_KIRCHHOFF: [f64; 6] = [
    7.903801, 12.822646, 17.857669, 18.931972, 23.692730, 27.632182,
];

/// NAFEMS FV12, free square plate (fv12.toml, 48×48 MITC4 from a Gmsh file): six rigid-body
/// modes at exactly 0 Hz, found from the problem (no supports at all), then 1.622, 2.360, 2.922,
/// 4.233, 4.233, 7.416 Hz. Modes 7, 8, 9 and 12 are within 1 % (measured −0.05, +0.02, +0.08,
/// −0.59 %). The 4.233 Hz pair is NOT met, and cannot be by a correct plate element: the exact
/// thin-plate pair is 4.1902 Hz (a Ritz upper bound, `fem_kirchhoff_ritz.rs`), 1.01 % below the
/// reference, and meid's pair, 4.1905 Hz, is within 0.01 % of it. The test asserts 1 % against
/// NAFEMS except for the pair, and 0.5 % against the thin-plate solution for all six (measured
/// −0.03, +0.04, +0.07, +0.01, +0.01, +0.22 %); the pair degenerate.
#[test]
fn nafems_fv12_free_plate_from_model_file() {
    let (f, rigid) = modes_of("fv12.toml");
    eprintln!("FV12: {f:?} Hz");
    assert_eq!(rigid, 6, "{f:?}");
    assert!(f[..6].iter().all(|x| *x == 0.0));
    let r = [1.622, 2.360, 2.922, 4.233, 4.233, 7.416];
    within_one_percent("FV12", &f, 6, &r, &[3, 4]);
    assert!((f[10] - f[9]).abs() <= 1e-6 * f[9], "{f:?}");
    for (k, x) in FV12_KIRCHHOFF.iter().enumerate() {
        let e = f[6 + k] / x - 1.0;
        assert!(
            e.abs() <= 0.005,
            "FV12 mode {}: {} Hz vs thin plate {x} Hz ({:+.2} %)",
            k + 7,
            f[6 + k],
            100.0 * e
        );
    }
}

/// NAFEMS FV15, clamped 45° rhombic plate (fv15.toml, 64×64 skewed MITC4 from a Gmsh file, all
/// edges clamped): 7.938, 12.835, 17.941, 19.133, 24.009, 27.922 Hz, each within 1 % at this
/// mesh (measured −0.38, +0.10, −0.17, −0.93, −0.89, −0.67 %). Modes 4 and 5 still fall with
/// refinement; their extrapolated limits, −1.16 % and −1.45 %, are outside 1 % of NAFEMS, but
/// the exact thin-plate frequencies are themselves 1.06, 1.33 and 1.05 % (at least) below NAFEMS for modes
/// 4-6 (Ritz upper bounds, `fem_kirchhoff_ritz.rs`). Also asserted: within 0.5 % of those
/// thin-plate values (measured +0.05, +0.20, +0.30, +0.12, +0.43, +0.37 %, from above).
#[test]
fn nafems_fv15_clamped_skew_plate_from_model_file() {
    let (f, rigid) = modes_of("fv15.toml");
    eprintln!("FV15: {f:?} Hz");
    assert_eq!(rigid, 0);
    within_one_percent(
        "FV15",
        &f,
        0,
        &[7.938, 12.835, 17.941, 19.133, 24.009, 27.922],
        &[],
    );
    for (k, x) in FV15_KIRCHHOFF.iter().enumerate() {
        let e = f[k] / x - 1.0;
        assert!(
            e.abs() <= 0.005,
            "FV15 mode {}: {} Hz vs thin plate {x} Hz ({:+.2} %)",
            k + 1,
            f[k],
            100.0 * e
        );
    }
}

/// NAFEMS FV16, square plate clamped on one edge (fv16.toml, 48×48 MITC4):
/// 0.421, 1.029, 2.582, 3.306, 3.753, 6.555 Hz, each within 1 % (measured −0.73, −0.49, −0.66,
/// −0.90, −0.65, −0.43 %; 64×64 moves them by ≤ 0.06 %).
#[test]
fn nafems_fv16_cantilevered_plate_from_model_file() {
    let (f, rigid) = modes_of("fv16.toml");
    eprintln!("FV16: {f:?} Hz");
    assert_eq!(rigid, 0);
    within_one_percent(
        "FV16",
        &f,
        0,
        &[0.421, 1.029, 2.582, 3.306, 3.753, 6.555],
        &[],
    );
}

/// NAFEMS FV32, cantilevered tapered membrane (fv32.toml, 64×32 shells, membrane only by
/// per-DOF constraints uz = rx = ry = 0 at every node, ux = uy = 0 on the wide edge):
/// 44.623, 130.03, 162.70, 246.05, 379.90, 391.44 Hz, each within 1 % (measured +0.03, +0.09,
/// −0.00, +0.16, +0.23, +0.02 %).
#[test]
fn nafems_fv32_tapered_membrane_from_model_file() {
    let (f, rigid) = modes_of("fv32.toml");
    eprintln!("FV32: {f:?} Hz");
    assert_eq!(rigid, 0);
    within_one_percent(
        "FV32",
        &f,
        0,
        &[44.623, 130.03, 162.70, 246.05, 379.90, 391.44],
        &[],
    );
}

/// Mindlin's simply supported plate, mode (m, n), ω² the smaller root of
/// `(κGh k² − ρh ω²)(D k² + κGh − ρh³/12 ω²) − (κGh)² k² = 0`, k² = (m² + n²) π²/a²
/// (Mindlin, J. Appl. Mech. 18, 1951), Hz.
fn mindlin_ss_hz(m: usize, n: usize, a: f64, h: f64, kappa: f64) -> f64 {
    let (e, nu, rho) = (2.0e11, 0.3, 8000.0);
    let d = e * h.powi(3) / (12.0 * (1.0 - nu * nu));
    let kgh = kappa * e / (2.0 * (1.0 + nu)) * h;
    let k2 = ((m * m + n * n) as f64) * std::f64::consts::PI.powi(2) / (a * a);
    let (p, q) = (kgh * k2, d * k2 + kgh);
    let (rh, ri) = (rho * h, rho * h.powi(3) / 12.0);
    // rh ri x² − (rh q + ri p) x + (p q − kgh² k2) = 0, smaller root in a stable form.
    let b = rh * q + ri * p;
    let c = p * q - kgh * kgh * k2;
    let x = 2.0 * c / (b + (b * b - 4.0 * rh * ri * c).sqrt());
    x.sqrt() / (2.0 * std::f64::consts::PI)
}

/// NAFEMS Test 21, simply supported thick square plate 10 × 10 × 1 m (nafems_t21.toml, 48×48
/// MITC4, κ = π²/12), hard simple support from per-DOF constraints: 45.897, 109.44 (×2), 167.89,
/// 204.51 (×2), 256.50 (×2) Hz, each within 1 % (measured +0.04, +0.16, +0.16, +0.16, +0.36,
/// +0.36, +0.30, +0.30 %), and within 0.5 % of Mindlin's closed form (which gives the NAFEMS
/// values to 5 digits: 45.895, 109.444, 167.886, 204.513, 256.502 Hz).
#[test]
fn nafems_test21_thick_plate_from_model_file() {
    let (f, rigid) = modes_of("nafems_t21.toml");
    eprintln!("Test 21: {f:?} Hz");
    assert_eq!(rigid, 0);
    within_one_percent(
        "Test 21",
        &f,
        0,
        &[
            45.897, 109.44, 109.44, 167.89, 204.51, 204.51, 256.50, 256.50,
        ],
        &[],
    );
    let kappa = std::f64::consts::PI.powi(2) / 12.0;
    for (k, (m, n)) in [
        (1, 1),
        (1, 2),
        (1, 2),
        (2, 2),
        (1, 3),
        (1, 3),
        (2, 3),
        (2, 3),
    ]
    .into_iter()
    .enumerate()
    {
        let x = mindlin_ss_hz(m, n, 10.0, 1.0, kappa);
        assert!(
            (f[k] / x - 1.0).abs() <= 0.005,
            "mode {} ({m},{n}): {} vs Mindlin {x}",
            k + 1,
            f[k]
        );
    }
    assert!((mindlin_ss_hz(1, 1, 10.0, 1.0, kappa) / 45.897 - 1.0).abs() < 1e-4);
    for (a, b) in [(1, 2), (4, 5), (6, 7)] {
        assert!(
            (f[b] - f[a]).abs() <= 1e-6 * f[a],
            "modes {}-{}: {f:?}",
            a + 1,
            b + 1
        );
    }
}

/// A 10 kg point mass with rotary inertia [0.3, 0.2, 0.4] kg·m² on a 0.5 m rigid arm from a node
/// on six springs to ground (offset_mass.toml: masses, rigid_links, springs on all six DOFs, no
/// elements). Closed form, u_1 = u_0 + θ_0 × r: ux: kx/m; rx: krx/Jx; (uy, rz) and (uz, ry):
/// `m J λ² − (k (J + m r²) + k_r m) λ + k k_r = 0`. All six frequencies to 1e-9.
#[test]
fn offset_point_mass_on_rigid_arm_from_model_file() {
    let (f, rigid) = modes_of("offset_mass.toml");
    assert_eq!(rigid, 0);
    let (m, r) = (10.0_f64, 0.5_f64);
    let (jx, jy, jz) = (0.3, 0.2, 0.4);
    let (kx, ky, kz, krx, kry, krz) = (1.0e4, 2.0e4, 3.0e4, 500.0, 700.0, 900.0);
    let hz = |l: f64| l.sqrt() / (2.0 * std::f64::consts::PI);
    let mut exact = vec![hz(kx / m), hz(krx / jx)];
    for (k, kr, j) in [(ky, krz, jz), (kz, kry, jy)] {
        let (a, b, c) = (m * j, k * (j + m * r * r) + kr * m, k * kr);
        let d = (b * b - 4.0 * a * c).sqrt();
        exact.push(hz((b - d) / (2.0 * a)));
        exact.push(hz((b + d) / (2.0 * a)));
    }
    exact.sort_by(f64::total_cmp);
    eprintln!("offset mass: {f:?} Hz; exact {exact:?}");
    for (x, e) in f.iter().zip(&exact) {
        assert!((x / e - 1.0).abs() <= 1e-9, "{f:?} vs {exact:?}");
    }
}

/// FV2's repeated eigenvalues (modes 2-8 and 10-16 share two frequencies) through both solvers:
/// every mode shape, ψ and effective mass is finite, the modes are M-orthonormal to 1e-10 (a
/// valid basis of each eigenspace), and the frequencies meet NAFEMS as above. FV2 vibrates in its
/// plane (uz constrained at every node), so no mode moves the strike point O_b along z: its
/// effective mass is infinite, which the model's diagnostics name, and a blow there is refused
/// naming `points.bed_contact`.
#[test]
fn fv2_repeated_roots_give_finite_orthonormal_modes_with_both_solvers() {
    use meid::model::fem::FemAnalysis;
    fn m_orthonormality_error(an: &FemAnalysis) -> f64 {
        let phi = &an.modes.shapes;
        let (n, m) = (phi.nrows(), phi.ncols());
        let mut mphi = vec![vec![0.0; n]; m];
        for t in an.model.mass.triplet_iter() {
            for (j, col) in mphi.iter_mut().enumerate() {
                col[t.row] += t.val * phi[(t.col, j)];
            }
        }
        let mut worst = 0.0_f64;
        for (i, mi) in mphi.iter().enumerate() {
            for j in 0..m {
                let g: f64 = (0..n).map(|r| phi[(r, j)] * mi[r]).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                worst = worst.max((g - want).abs());
            }
        }
        worst
    }
    let mut r = vec![11.336];
    r.extend([17.709; 7]);
    r.push(45.345);
    r.extend([57.390; 7]);
    for solver in ["dense", "lanczos"] {
        let set = format!("structure.fem.solver=\"{solver}\"");
        let (model, an) = from_file_with_analysis(&data("fv2.toml"), &[set], None).unwrap();
        let an = an.unwrap();
        assert_eq!(an.solver, solver);
        assert!(
            an.modes
                .shapes
                .col_iter()
                .all(|c| c.iter().all(|v| v.is_finite())),
            "{solver}: non-finite mode shape"
        );
        let e = m_orthonormality_error(&an);
        assert!(e <= 1e-10, "{solver}: max |ΦᵀMΦ − I| = {e:e}");
        let report = an.report().unwrap();
        assert_eq!(report.modes.len(), 16);
        for row in &report.modes {
            let em = row.effective_mass_kg.as_ref().unwrap();
            for v in [em.x, em.y, em.z, em.rx, em.ry, em.rz] {
                assert!(v.is_finite(), "{solver} mode {}: {em:?}", row.index);
            }
            for (p, v) in &row.psi_per_sqrt_kg {
                assert!(v.is_finite(), "{solver} mode {} ψ({p}) = {v}", row.index);
            }
        }
        an.modal.validate().unwrap();
        within_one_percent(&format!("FV2 {solver}"), &an.table.frequency_hz, 0, &r, &[]);
        let d = model.diagnostics();
        assert!(
            d.warnings
                .iter()
                .any(|w| w.contains("points.bed_contact = 'O_b'")
                    && w.contains("no retained mode moves it")),
            "{solver}: {:?}",
            d.warnings
        );
        let sys = model.impact_system(meid::model::Case::AsSpecified).unwrap();
        let e = meid::analysis::energy::simulate(&sys, &model.options(), false)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("points.bed_contact") && e.contains("immovable") && !e.contains("heavy"),
            "{solver}: {e}"
        );
    }
}
