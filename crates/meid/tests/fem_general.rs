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

/// NAFEMS FV12, free square plate (fv12.toml, 24×24 MITC4 from a Gmsh file): six rigid-body
/// modes at exactly 0 Hz, found from the problem (no supports at all), then the NAFEMS
/// reference 1.622, 2.360, 2.922, 4.233, 4.233, 7.416 Hz within 1 %.
#[test]
fn nafems_fv12_free_plate_from_model_file() {
    let (_, an) = from_file_with_analysis(&data("fv12.toml"), &[], None).unwrap();
    let an = an.unwrap();
    let f = &an.table.frequency_hz;
    eprintln!("FV12: {f:?} Hz");
    assert_eq!(an.modes.rigid_body_modes, 6, "{f:?}");
    assert!(f[..6].iter().all(|x| *x == 0.0));
    for (k, r) in [1.622, 2.360, 2.922, 4.233, 4.233, 7.416]
        .iter()
        .enumerate()
    {
        assert!(
            (f[6 + k] - r).abs() <= 0.01 * r,
            "mode {}: {} vs {r}",
            7 + k,
            f[6 + k]
        );
    }
}
