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
    // The validity is 2.2/‖D⁻¹AD‖_∞: a fraction of the period 2π/ω.
    assert!(tau > 0.5 / w && tau <= 2.2 / w, "tau {tau}");
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

/// The energy a Taylor step dissipates, `∫ ẋᵀCẋ ds` (10-point Gauss-Legendre on the step's
/// polynomial, `C = −M A₂₂`), equals the loss of mechanical energy `E(0) − E(s)`,
/// `E = ½ẋᵀMẋ + ½xᵀKx`: for one oscillator (closed form of x(s)), and for chains of 3 and 9
/// masses (fixed-size and general code), where `E(s)` comes from the step's state. Damping is
/// strong (ζ of a few per cent to 30 %) so that the loss is not a small difference.
#[test]
fn dissipation_equals_energy_loss() {
    // One oscillator: m = 2 kg, k = 7.2e7 N/m, ζ = 0.3.
    let (m, k, z) = (2.0_f64, 7.2e7_f64, 0.3_f64);
    let w = (k / m).sqrt();
    let c = 2.0 * z * w * m;
    let a = Mat::<f64>::from_fn(2, 2, |i, j| match (i, j) {
        (0, 1) => 1.0,
        (1, 0) => -k / m,
        (1, 1) => -c / m,
        _ => 0.0,
    });
    let tm = TaylorMatrix::new(&a).unwrap();
    let mut coef = vec![0.0; (ORDER + 1) * 2];
    tm.expand(&[0.0, 1.5], &mut coef);
    let wd = w * (1.0 - z * z).sqrt();
    let mut work = Vec::new();
    for frac in [0.2, 0.7, 1.0] {
        let s = frac * tm.validity();
        // x(0) = 0, ẋ(0) = v0: x = v0/ω_d e^{−ζωs} sin ω_d s.
        let e = (-z * w * s).exp();
        let x = 1.5 / wd * e * (wd * s).sin();
        let v = 1.5 * e * ((wd * s).cos() - z * w / wd * (wd * s).sin());
        let loss = 0.5 * m * 1.5 * 1.5 - (0.5 * m * v * v + 0.5 * k * x * x);
        let d = tm.dissipated(&coef, &[m], s, &mut work).unwrap();
        assert!(
            (d - loss).abs() <= 1e-13 * loss,
            "oscillator at {frac} tau: {d} vs {loss}"
        );
    }
    // Chains: masses to the right, springs and dashpots between neighbours and to the ground.
    for n in [3usize, 9] {
        let mass: Vec<f64> = (0..n).map(|i| 1.0 + 0.7 * i as f64).collect();
        let ks: Vec<f64> = (0..=n).map(|i| 2.0e7 * (1.0 + 0.3 * i as f64)).collect();
        let cs: Vec<f64> = (0..=n).map(|i| 900.0 * (1.0 + 0.5 * i as f64)).collect();
        let band = |v: &[f64], i: usize, j: usize| -> f64 {
            if i == j {
                v[i] + v[i + 1]
            } else if i + 1 == j || j + 1 == i {
                -v[i.max(j)]
            } else {
                0.0
            }
        };
        let kk = Mat::<f64>::from_fn(n, n, |i, j| band(&ks, i, j));
        let cc = Mat::<f64>::from_fn(n, n, |i, j| band(&cs, i, j));
        let a = Mat::<f64>::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
            (true, true) => 0.0,
            (true, false) => f64::from(j - n == i),
            (false, true) => -kk[(i - n, j)] / mass[i - n],
            (false, false) => -cc[(i - n, j - n)] / mass[i - n],
        });
        let tm = TaylorMatrix::new(&a).unwrap();
        let x0: Vec<f64> = (0..2 * n)
            .map(|i| {
                if i < n {
                    1e-5 * (i as f64 - 1.0)
                } else {
                    0.4 - 0.1 * (i - n) as f64
                }
            })
            .collect();
        let mut coef = vec![0.0; (ORDER + 1) * 2 * n];
        tm.expand(&x0, &mut coef);
        let energy = |x: &[f64]| -> f64 {
            let mut e = 0.0;
            for i in 0..n {
                e += 0.5 * mass[i] * x[n + i] * x[n + i];
                for j in 0..n {
                    e += 0.5 * x[i] * kk[(i, j)] * x[j];
                }
            }
            e
        };
        let mut xs = vec![0.0; 2 * n];
        for frac in [0.3, 1.0] {
            let s = frac * tm.validity();
            taylor::state(&coef, s, &mut xs);
            let loss = energy(&x0) - energy(&xs);
            let d = tm.dissipated(&coef, &mass, s, &mut work).unwrap();
            assert!(
                loss > 1e-3 * energy(&x0),
                "{n} masses: loss {loss} too small to test"
            );
            assert!(
                (d - loss).abs() <= 1e-12 * energy(&x0),
                "{n} masses at {frac} tau: {d} vs {loss}"
            );
        }
    }
}
