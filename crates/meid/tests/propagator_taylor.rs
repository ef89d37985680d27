//! The Taylor propagator (short stretches of the exact integrator) against closed forms and
//! against the spectral propagator.

use faer::Mat;
use meid::integrate::propagator::Propagator;

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
    let p = Propagator::taylor(a, &[1.0, 0.0]).unwrap();
    let tau = p.validity();
    // The validity is 2/‖D⁻¹AD‖_∞: a fraction of the period 2π/ω.
    assert!(tau > 0.5 / w && tau <= 2.0 / w, "tau {tau}");
    let seg = p.segment(&[1.0, 0.0]);
    let mut out = [0.0; 2];
    for frac in [0.0, 0.1, 0.5, 1.0] {
        let s = frac * tau;
        seg.state(s, &mut out);
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
    let spectral = Propagator::new(&k, &c, &m, a.clone()).unwrap();
    let taylor = Propagator::taylor(a, &x0).unwrap();
    let (ss, ts) = (spectral.segment(&x0), taylor.segment(&x0));
    let (mut xs, mut xt) = ([0.0; 6], [0.0; 6]);
    let tau = taylor.validity();
    for frac in [0.25, 0.5, 1.0] {
        ss.state(frac * tau, &mut xs);
        ts.state(frac * tau, &mut xt);
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
