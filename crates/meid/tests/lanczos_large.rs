//! Medium-size problems (run with `cargo test --release -p meid --test suite -- lanczos_large:: --ignored`).
//! Timing and peak memory are measured by `examples/eig_bench.rs` under `/usr/bin/time -v`,
//! not asserted here.

use crate::lanczos_support;

use lanczos_support::*;
use meid::modal::lanczos::{lowest_modes, LanczosOptions};

/// Free 3-D scalar-spring lattice, 26 × 26 × 25 nodes = 50,700 DOF, 20 lowest modes.
/// Reference: λ = (k/m) Σ 4 sin²(π p_a/(2N_a)) (3 rigid modes, triple eigenvalues);
/// tolerance 1e-9 relative (1e-9 λ_max absolute for the rigid modes). The Sturm count must
/// equal the closed-form number of eigenvalues below σ_u.
#[test]
#[ignore]
fn lattice_50k_dof_closed_form() {
    let dims = [26, 26, 25];
    let (kk, mm) = (1.0e7, 2.0);
    let (k, m) = scalar_lattice(dims, kk, mm);
    let exact = scalar_lattice_spectrum(dims, kk, mm);
    let r = lowest_modes(
        k.as_ref(),
        m.as_ref(),
        &LanczosOptions {
            count: 20,
            ..Default::default()
        },
    )
    .unwrap();
    eprintln!("{:?}", r.stats);
    assert_eq!(r.rigid_body_modes, 3);
    let lmax = exact[exact.len() - 1];
    for (j, &ex) in exact.iter().enumerate().take(20) {
        let tol = if ex == 0.0 { 1e-9 * lmax } else { 1e-9 * ex };
        let got = r.eigenvalues[j];
        assert!((got - ex).abs() <= tol, "mode {j}: {got} vs {ex}");
    }
    let below = exact.iter().filter(|&&l| l < r.sturm_shift).count();
    assert_eq!(r.sturm_count, below);
    assert_eq!(r.sturm_count, r.computed_below_sturm_shift);
    assert!(r.orthonormality_error <= 1e-10);
    assert!(r.max_residual <= 1e-10, "{}", r.max_residual);
}

/// Free truss plate (130 × 130 × 2 nodes, 101,400 DOF, face and body diagonals): exactly 6
/// rigid-body modes, Sturm count equal to the computed count, M-orthonormal shapes. Its
/// s/λ₁ ≈ 6e7 puts the attainable residual (≈ ε s/λ₁ ≈ 1.3e-8) above 1e-10, so the residual is
/// checked against that bound instead.
#[test]
#[ignore]
fn truss_plate_100k_dof() {
    let (k, m) = truss_lattice([130, 130, 2], 1.0e7, 4.0e6, 2.0);
    let r = lowest_modes(
        k.as_ref(),
        m.as_ref(),
        &LanczosOptions {
            count: 20,
            ..Default::default()
        },
    )
    .unwrap();
    eprintln!("{:?}", r.stats);
    assert_eq!(r.rigid_body_modes, 6);
    assert_eq!(r.sturm_count, r.computed_below_sturm_shift);
    assert!(r.sturm_count >= 20);
    assert!(r.orthonormality_error <= 1e-10);
    let attainable = 4.0 * f64::EPSILON * r.stiffness_scale / r.eigenvalues[6];
    assert!(
        r.max_residual <= attainable,
        "{} vs {attainable}",
        r.max_residual
    );
}
