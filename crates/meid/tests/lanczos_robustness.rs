//! Sparse Lanczos: automatic re-shift, user shift, input errors.

use crate::lanczos_support;

use faer::sparse::Triplet;
use lanczos_support::*;
use meid::modal::lanczos::{lowest_modes, LanczosOptions};

/// A long chain (λ_8 ≈ 1e-7 s): the automatic shift -1e-6 s lies far below the band, so the
/// solver must re-shift. Reference: ω_j = 2 sqrt(k/m) sin((2j-1)π/(2(2n+1))). The residual
/// tolerance is unattainable (s/λ₁ ≈ 2e9), so the eigenvalue error is bounded by the
/// first-order residual bound |δλ|/λ ≤ 2 · residual (ω: half of that).
#[test]
fn long_chain_reshifts_and_matches_closed_form() {
    let (n, kk, mm) = (50_000, 1.0e6, 1.0);
    let (k, m) = chain_fixed_free(n, kk, mm);
    let opts = LanczosOptions {
        count: 8,
        block_size: 2,
        ..Default::default()
    };
    let r = lowest_modes(k.as_ref(), m.as_ref(), &opts).unwrap();
    eprintln!("{:?} res {:?}", r.stats, r.residuals);
    assert!(r.stats.reshifts >= 1);
    for j in 1..=8 {
        let exact = chain_fixed_free_omega(n, kk, mm, j);
        let got = r.omega_rad_per_s[j - 1];
        let bound = r.residuals[j - 1].max(1e-12);
        assert!(
            (got - exact).abs() <= bound * exact,
            "mode {j}: {got} vs {exact} (bound {bound:e})"
        );
    }
    assert!(r.orthonormality_error <= 1e-10);
    assert_eq!(r.sturm_count, r.computed_below_sturm_shift);
    assert!(r.sturm_count >= 8);
}

/// A user shift is used as given (no re-shift) and gives the same modes as the automatic one
/// (fixed-free chain closed form, 1e-9 relative).
#[test]
fn user_shift_is_respected() {
    let (n, kk, mm) = (300, 1.0e4, 2.0);
    let (k, m) = chain_fixed_free(n, kk, mm);
    let opts = LanczosOptions {
        count: 6,
        block_size: 3,
        shift: Some(-0.5),
        ..Default::default()
    };
    let r = lowest_modes(k.as_ref(), m.as_ref(), &opts).unwrap();
    assert_eq!(r.shift, -0.5);
    assert_eq!(r.stats.reshifts, 0);
    for j in 1..=6 {
        let exact = chain_fixed_free_omega(n, kk, mm, j);
        assert!((r.omega_rad_per_s[j - 1] - exact).abs() <= 1e-9 * exact);
    }
}

/// A shift very close to zero (-1e-12 s) on a free-floating truss (6 rigid modes): K - σM is
/// nearly singular (condition ≈ 1e12), so every solve carries a relative error ≈ 1e-4. The
/// solver must either find all 6 rigid-body modes and the right elastic ones (dense
/// reference, 1e-8 relative), or fail with an error; never return a wrong set of modes.
#[test]
fn shift_near_zero_keeps_rigid_modes_or_fails_loudly() {
    let (k, m) = truss_lattice([4, 4, 3], 1.0e7, 4.0e6, 2.0);
    let dense = dense_eigenvalues(&k, &m);
    let s = 1.0e7 * 4.0; // order of max K_ii/M_ii
    let opts = LanczosOptions {
        count: 12,
        shift: Some(-1e-12 * s),
        max_iter: 60,
        ..Default::default()
    };
    match lowest_modes(k.as_ref(), m.as_ref(), &opts) {
        Ok(r) => {
            eprintln!("near-zero shift: solved, {:?}", r.stats);
            assert_eq!(r.rigid_body_modes, 6);
            assert_eq!(r.sturm_count, r.computed_below_sturm_shift);
            for (got, de) in r.eigenvalues.iter().zip(&dense).skip(6) {
                assert!((got - de).abs() <= 1e-8 * de, "{got} vs {de}");
            }
        }
        Err(e) => {
            let e = e.to_string();
            eprintln!("near-zero shift: {e}");
            assert!(
                e.contains("Sturm")
                    || (e.contains("no convergence") && e.contains("nearly singular")),
                "{e}"
            );
        }
    }
}

fn small_pair() -> (Sp, Sp) {
    chain_fixed_free(60, 1.0, 1.0)
}

#[test]
fn asymmetric_stiffness_is_rejected() {
    let (_, m) = small_pair();
    let mut t = Vec::new();
    for i in 0..60 {
        t.push(Triplet::new(i, i, 2.0));
    }
    t.push(Triplet::new(3, 1, -1.0)); // no mirror entry
    let k = from_triplets(60, &t);
    let e = lowest_modes(
        k.as_ref(),
        m.as_ref(),
        &LanczosOptions {
            count: 3,
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("not symmetric") && e.contains("(3, 1)"), "{e}");
}

#[test]
fn massless_dof_is_rejected() {
    let (k, _) = small_pair();
    let mut t = Vec::new();
    for i in 0..60 {
        t.push(Triplet::new(i, i, if i == 7 { 0.0 } else { 1.0 }));
    }
    let m = from_triplets(60, &t);
    let e = lowest_modes(
        k.as_ref(),
        m.as_ref(),
        &LanczosOptions {
            count: 3,
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("mass matrix") && e.contains("entry 7"), "{e}");
}

/// A negative spring makes K indefinite (one eigenvalue ≈ -k/m·O(1)): reported, not returned.
#[test]
fn indefinite_stiffness_is_rejected() {
    let n = 60;
    let mut t = Vec::new();
    for j in 0..n {
        let kj = if j == 30 { -50.0 } else { 1.0 };
        t.push(Triplet::new(j, j, kj));
        if j > 0 {
            t.push(Triplet::new(j - 1, j - 1, kj));
            t.push(Triplet::new(j - 1, j, -kj));
            t.push(Triplet::new(j, j - 1, -kj));
        }
    }
    let k = from_triplets(n, &t);
    let (_, m) = small_pair();
    let e = lowest_modes(
        k.as_ref(),
        m.as_ref(),
        &LanczosOptions {
            count: 3,
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("positive"), "{e}");
}

#[test]
fn bad_options_are_rejected() {
    let (k, m) = small_pair();
    let run = |o: LanczosOptions| {
        lowest_modes(k.as_ref(), m.as_ref(), &o)
            .unwrap_err()
            .to_string()
    };
    assert!(run(LanczosOptions {
        count: 0,
        ..Default::default()
    })
    .contains("mode count"));
    assert!(run(LanczosOptions {
        count: 3,
        shift: Some(1.0),
        ..Default::default()
    })
    .contains("shift"));
    assert!(run(LanczosOptions {
        count: 3,
        tol: 0.0,
        ..Default::default()
    })
    .contains("tolerance"));
    assert!(run(LanczosOptions {
        count: 55,
        ..Default::default()
    })
    .contains("too few"));
    let (k2, m2) = chain_fixed_free(2, 1.0, 1.0);
    let o = LanczosOptions {
        count: 1,
        ..Default::default()
    };
    let e = lowest_modes(k2.as_ref(), m2.as_ref(), &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("too few"), "{e}");
}
