//! Taylor steps (`integrate::taylor`, short stretches of the exact integrator) against closed
//! forms, against the spectral propagator and against a plain `A^k X₀ / k!`.

use faer::Mat;
use meid::integrate::propagator::Propagator;
use meid::integrate::taylor::{self, TaylorMatrix, ORDER};

/// The coefficients of a step from `x0` (rows of `n`) and its validity.
fn expand(a: &Mat<f64>, x0: &[f64]) -> (Vec<f64>, f64) {
    let tm = TaylorMatrix::new(a).unwrap();
    let mut coef = vec![0.0; (ORDER + 1) * x0.len()];
    tm.expand(x0, &mut coef);
    (coef, tm.validity())
}

/// `ẍ + 2ζω ẋ + ω² x = 0`, x(0) = 1, ẋ(0) = 0:
/// `x = e^{−ζωs}(cos ω_d s + ζω/ω_d sin ω_d s)`, `ẋ = −(ω²/ω_d) e^{−ζωs} sin ω_d s`.
#[test]
fn damped_oscillator_within_validity() {
    let (w, z) = (6000.0_f64, 0.05_f64);
    let wd = w * (1.0 - z * z).sqrt();
    let a = Mat::<f64>::from_fn(2, 2, |i, j| match (i, j) {
        (0, 1) => 1.0,
        (1, 0) => -w * w,
        (1, 1) => -2.0 * z * w,
        _ => 0.0,
    });
    let (coef, tau) = expand(&a, &[1.0, 0.0]);
    // The validity is 2/‖D⁻¹AD‖_∞: a fraction of the period 2π/ω.
    assert!(tau > 0.5 / w && tau <= 2.0 / w, "tau {tau}");
    let mut out = [0.0; 2];
    for frac in [0.0, 0.1, 0.5, 1.0] {
        let s = frac * tau;
        taylor::state(&coef, s, &mut out);
        let e = (-z * w * s).exp();
        let x = e * ((wd * s).cos() + z * w / wd * (wd * s).sin());
        let v = -(w * w / wd) * e * (wd * s).sin();
        assert!(
            (out[0] - x).abs() < 1e-14,
            "x at {frac} tau: {} vs {x}",
            out[0]
        );
        assert!(
            (out[1] - v).abs() < 1e-14 * w,
            "v at {frac} tau: {} vs {v}",
            out[1]
        );
    }
}

/// A 3-DOF damped chain (masses 1.2, 10, 3.5; stiffnesses of the paper's size): the Taylor
/// propagator and the eigen-decomposition agree on the state within the Taylor validity.
#[test]
fn chain_agrees_with_spectral_form() {
    let m = [1.2, 10.0, 3.5];
    let k = Mat::<f64>::from_fn(3, 3, |i, j| {
        let ks = [4.3e7, 1.25e8];
        match (i, j) {
            (0, 0) => ks[0],
            (1, 1) => ks[0] + ks[1],
            (2, 2) => ks[1],
            (0, 1) | (1, 0) => -ks[0],
            (1, 2) | (2, 1) => -ks[1],
            _ => 0.0,
        }
    });
    let c = Mat::<f64>::from_fn(3, 3, |i, j| match (i, j) {
        (2, 2) => 700.0,
        (1, 1) => 30.0,
        _ => 0.0,
    });
    let a = Mat::<f64>::from_fn(6, 6, |i, j| {
        if i < 3 {
            if j == i + 3 {
                1.0
            } else {
                0.0
            }
        } else if j < 3 {
            -k[(i - 3, j)] / m[i - 3]
        } else {
            -c[(i - 3, j - 3)] / m[i - 3]
        }
    });
    let x0 = [0.0, 1e-6, 0.0, 1.2, 0.0, -0.3];
    let (coef, tau) = expand(&a, &x0);
    let spectral = Propagator::new(&k, &c, &m, a).unwrap();
    let ss = spectral.segment(&x0);
    let (mut xs, mut xt) = ([0.0; 6], [0.0; 6]);
    for frac in [0.25, 0.5, 1.0] {
        ss.state(frac * tau, &mut xs);
        taylor::state(&coef, frac * tau, &mut xt);
        for i in 0..6 {
            let scale = if i < 3 { 1e-4 } else { 1.0 };
            assert!(
                (xs[i] - xt[i]).abs() < 1e-12 * scale,
                "component {i} at {frac} tau: spectral {} taylor {}",
                xs[i],
                xt[i]
            );
        }
    }
}

/// The fixed-size expansion (first-order form, 2 to 8 degrees of freedom), the general one
/// (9 degrees of freedom) and the one for a matrix without the `[[0, I], …]` structure all equal
/// `A^k X₀ / k!` computed by plain mat-vecs, to round-off.
#[test]
fn expansion_equals_matrix_powers() {
    let mut rng = meid::rng::SplitMix64::new(7);
    for (nd, structured) in (2..=9).map(|nd| (nd, true)).chain([(3, false)]) {
        let n = 2 * nd;
        let a = Mat::<f64>::from_fn(n, n, |i, j| {
            let r = rng.next_f64() - 0.5;
            match (structured, i < nd) {
                (true, true) => f64::from(j == nd + i),
                _ => 1e3 * r,
            }
        });
        let x0: Vec<f64> = (0..n).map(|_| rng.next_f64() - 0.5).collect();
        let (coef, _) = expand(&a, &x0);
        let mut y = x0.clone();
        for k in 0..=ORDER {
            let ck = &coef[k * n..(k + 1) * n];
            let scale = y.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for i in 0..n {
                assert!(
                    (ck[i] - y[i]).abs() <= 1e-13 * scale,
                    "nd {nd}, structured {structured}, k {k}, i {i}: {} vs {}",
                    ck[i],
                    y[i]
                );
            }
            // y ← A y / (k + 1)
            y = (0..n)
                .map(|i| (0..n).map(|j| a[(i, j)] * y[j]).sum::<f64>() / (k + 1) as f64)
                .collect();
        }
    }
}
