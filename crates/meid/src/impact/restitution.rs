//! Coefficient of restitution of a contact law: the exact relations between a free two-body
//! impact's restitution `e` and the law's damping, and their inverses (model field
//! `contact.*.restitution`).
//!
//! # The free two-body impact
//! Two rigid bodies of masses `m₁`, `m₂` meet with approach velocity `v_in > 0` and interact
//! only through the contact. Their overlap `δ` obeys
//!
//! ```text
//! m* δ̈ = −f(δ, δ̇),   m* = m₁ m₂ / (m₁ + m₂),   δ(0) = 0,  δ̇(0) = v_in,
//! ```
//!
//! and the contact releases at a time `t_r` (when `δ` or `f` returns to zero, see
//! [`Release`]) with `δ̇(t_r) = −v_out`. The coefficient of restitution is `e = v_out / v_in`
//! (Newton's, equal to Poisson's for these laws since the impulse splits accordingly).
//!
//! # Hunt-Crossley
//! meid writes the law `f = K δⁿ (1 + 3/2 α δ̇)` (Hunt and Crossley 1975, whose α makes
//! `e ≈ 1 − α v_in` for small damping). The same law as `f = K δⁿ (1 + ξ δ̇)` (issue's form,
//! Lankarani-Nikravesh, Flores) has `ξ = 3/2 α`; with `c = ξ` the equation of motion
//! `m* δ̈ = −K δⁿ (1 + c δ̇)` does not contain `t` explicitly, so with `v = δ̇`,
//! `δ̈ = v dv/dδ` and it separates in the phase plane:
//!
//! ```text
//! v / (1 + c v) dv = −(K/m*) δⁿ dδ.
//! ```
//!
//! Compression runs from `(δ, v) = (0, v_in)` to `(δ_max, 0)`, restitution from `(δ_max, 0)`
//! back to `(0, −v_out)`. Integrating both, the right-hand sides are `∓(K/m*) δ_max^{n+1}/(n+1)`
//! and cancel when added, so with `G(u) = u − ln(1 + u)` (`∫₀ᵘ s/(1+s) ds`) and
//! `x = c v_in = 3/2 α v_in`, `y = c v_out = e x`:
//!
//! ```text
//! G(x) = G(−y),   i.e.   x − ln(1 + x) = −e x − ln(1 − e x).
//! ```
//!
//! The relation holds for every exponent `n`, stiffness `K` and mass `m*`: `e` depends on
//! `x` alone. The restitution force `1 + c v` cannot change sign before the overlap closes:
//! `G(−y) → ∞` as `y → 1`, while `G(−y) = G(x)` is finite, so `v > −1/c` throughout and the
//! force returns to zero exactly with the overlap (`δⁿ → 0`). Both release rules therefore give
//! the same `e`. `G(−e x)` increases with `e` and `G(x)` with `x`, so each `x ∈ [0, ∞)` has one
//! `e ∈ (0, 1]` ([`e_of_x`]) and each `e` one `x` ([`x_of_e`]): `e = 1 ↔ x = 0`, `e → 0` as
//! `x → ∞`, and `e = 1 − 2x/3 + O(x²)` (i.e. `1 − α v_in`) for small `x`. In closed form
//! `e x = 1 + W₀(−(1 + x) e^{−(1 + x)})` with Lambert's W (principal branch; Carvalho and
//! Martins, Mech. Mach. Theory 139, 2019); meid solves the monotone relation by bisection.
//!
//! The approximations in use give, at a requested `e = 0.5` (exact `x = 1.432751`):
//!
//! | formula | `x = ξ v_in` | restitution it really gives |
//! |---|---|---|
//! | exact ([`x_of_e`]) | 1.432751 | 0.5 |
//! | Lankarani-Nikravesh, `ξ = 3(1 − e²)/(4 v_in)` | 0.5625 | 0.725241 |
//! | Flores et al., `ξ = 8(1 − e)/(5 e v_in)` | 1.6 | 0.470445 |
//!
//! (At e = 0.1 the two give 0.665 and 0.069.) Since `x = ξ v_in`, a Hunt-Crossley contact
//! sized for one approach velocity rebounds with another `e` at another velocity.
//!
//! # Linear spring-dashpot
//! `f = K δ + C δ̇` with `ω = √(K/m*)` and `ζ = C / (2 √(K m*))`: `δ̈ + 2ζω δ̇ + ω² δ = 0`,
//! whose restitution depends on `ζ` and the release rule only (not on `v_in`, `K` or `m*`
//! separately).
//!
//! **Release at zero overlap** ([`Release::Overlap`]). For `ζ < 1`,
//! `δ = (v_in/ω_d) e^{−ζωt} sin ω_d t` (`ω_d = ω √(1 − ζ²)`) returns to zero at `t = π/ω_d`
//! with `δ̇ = −v_in e^{−ζωπ/ω_d}`:
//!
//! ```text
//! e = exp(−π ζ / √(1 − ζ²)),      ζ = L / √(1 + L²)  with  L = −ln(e)/π.
//! ```
//!
//! For `ζ ≥ 1` the overlap decays without crossing zero: the bodies never separate (`e = 0`).
//!
//! **Release at zero force** ([`Release::Force`], meid's default). The contact lets go when
//! `K δ + C δ̇ = −m* δ̈` reaches zero. With `ζ = cos ψ` (`ψ ∈ (0, π/2]`) the solution above gives
//! `δ̈ = −(v_in ω / sin ψ) e^{−ζωt} sin(2ψ − ω_d t)`, negative from `t = 0` (where `f = C v_in`)
//! until `ω_d t_r = 2ψ < π`, before the overlap closes; there
//! `δ̇ = −(v_in/sin ψ) e^{−ζωt_r} sin ψ = −v_in e^{−ζωt_r}`. The release equation
//! `sin(2ψ − ω_d t) = 0`, transcendental in general, has this root in closed form. For
//! `ζ = cosh χ > 1` the same steps with hyperbolic functions give `ω √(ζ²−1) t_r = 2χ`; for
//! `ζ = 1`, `ω t_r = 2`. Together:
//!
//! ```text
//! e = exp(−2 ζ Λ(ζ)),   Λ = arccos(ζ)/√(1 − ζ²) (ζ < 1),  1 (ζ = 1),  arcosh(ζ)/√(ζ² − 1) (ζ > 1),
//! ```
//!
//! a continuous decreasing function from `e(0) = 1` through `e(1) = e⁻² = 0.135335` to
//! `e ≈ 1/(4ζ²)` for large `ζ`: every `e ∈ (0, 1]` is reached, also by an overdamped contact.
//! The inverse ([`zeta_of_e`]) is found by bisection.
//!
//! At `ζ = 0.5` the rules differ by almost a factor 2: zero overlap `e = 0.163034`, zero force
//! `e = 0.298436` (ratio 1.8305): the force rule lets go at `ω_d t = 2π/3` instead of `π`, before
//! the dashpot has pulled the bodies apart further. For small `ζ` both are `1 − πζ + O(ζ²)`.

use super::Release;
use crate::{Error, Result};

/// `G(u) = u − ln(1 + u)` for `u > −1`, accurate to a few ulps also for small `|u|`, where the
/// difference cancels (series `Σ_{k≥2} (−u)^k / k`).
fn g(u: f64) -> f64 {
    if u.abs() <= 0.25 {
        let (mut sum, mut pow, mut k) = (0.0_f64, u * u, 2.0);
        while pow.abs() > 1e-18 * sum.abs() || k < 3.0 {
            sum += pow / k;
            pow *= -u;
            k += 1.0;
        }
        sum
    } else {
        u - u.ln_1p()
    }
}

/// The sign of `G(−e x) − G(x)` (the restitution relation's imbalance): negative when the
/// rebound velocity `e x` is too small, positive when too large. For small `x` it is evaluated
/// as `x² Σ_{k≥2} x^{k−2} (e^k − (−1)^k)/k`, with `1 − e^k` from `expm1`, so that `e` close to 1
/// keeps full relative precision.
fn imbalance(x: f64, e: f64) -> f64 {
    if x <= 0.25 {
        // |e^k − (−1)^k| ≤ 2: the terms after x^{k−2} add at most 2 x^{k−1}/(1 − x).
        let ln_e = e.ln();
        let (mut sum, mut size, mut pow, mut k) = (0.0, 0.0, 1.0, 2_i32);
        loop {
            let kf = f64::from(k);
            let coef = if k % 2 == 0 {
                (kf * ln_e).exp_m1()
            } else {
                e.powi(k) + 1.0
            };
            let term = pow * coef / kf;
            sum += term;
            size += term.abs();
            pow *= x;
            k += 1;
            if 3.0 * pow <= 1e-18 * size || k > 400 {
                break;
            }
        }
        sum
    } else {
        g(-e * x) - g(x)
    }
}

/// Bisection of a function on `[lo, hi]` that is negative left of its root and positive right
/// of it, to adjacent doubles.
fn bisect(mut lo: f64, mut hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    for _ in 0..2200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Hunt-Crossley: the restitution `e ∈ (0, 1]` of a free two-body impact with
/// `x = 3/2 α v_in = ξ v_in ≥ 0` (module docs: `x − ln(1 + x) = −e x − ln(1 − e x)`);
/// `x = +∞` gives 0. Independent of the exponent, stiffness and masses.
pub fn e_of_x(x: f64) -> Result<f64> {
    if x.is_nan() || x < 0.0 {
        return Err(Error::invalid(
            "x",
            format!("x = 3/2 α v_in must be ≥ 0 (got {})", crate::num(x)),
        ));
    }
    if x == 0.0 {
        return Ok(1.0);
    }
    if x.is_infinite() {
        return Ok(0.0);
    }
    Ok(bisect(0.0, 1.0f64.min(1.0 / x), |e| imbalance(x, e)))
}

/// Hunt-Crossley: the `x = 3/2 α v_in = ξ v_in` that makes a free two-body impact rebound with
/// restitution `e ∈ (0, 1]` (inverse of [`e_of_x`]); `α = 2x / (3 v_in)`.
pub fn x_of_e(e: f64) -> Result<f64> {
    check_e(e)?;
    if e == 1.0 {
        return Ok(0.0);
    }
    Ok(bisect(0.0, 1.0 / e, |x| imbalance(x, e)))
}

/// `Λ(ζ)` of the zero-force release (module docs): `arccos ζ / √(1 − ζ²)`, 1, or
/// `arcosh ζ / √(ζ² − 1)`, each written so that it stays accurate near `ζ = 1`.
fn lambda(zeta: f64) -> f64 {
    if zeta < 1.0 {
        let s = ((1.0 - zeta) * (1.0 + zeta)).sqrt();
        s.atan2(zeta) / s
    } else if zeta > 1.0 {
        let s = ((zeta - 1.0) * (zeta + 1.0)).sqrt();
        s.asinh() / s
    } else {
        1.0
    }
}

/// Linear spring-dashpot: the restitution of a free two-body impact with damping ratio
/// `ζ = C / (2√(K m*)) ≥ 0` under the release rule (module docs): zero overlap
/// `exp(−πζ/√(1 − ζ²))` (0 for `ζ ≥ 1`: no separation), zero force `exp(−2ζΛ(ζ))`.
pub fn e_of_zeta(zeta: f64, release: Release) -> Result<f64> {
    if !(zeta >= 0.0 && zeta.is_finite()) {
        return Err(Error::invalid(
            "zeta",
            format!(
                "the damping ratio ζ must be a finite number ≥ 0 (got {})",
                crate::num(zeta)
            ),
        ));
    }
    Ok(match release {
        Release::Overlap if zeta >= 1.0 => 0.0,
        Release::Overlap => {
            let s = ((1.0 - zeta) * (1.0 + zeta)).sqrt();
            (-std::f64::consts::PI * zeta / s).exp()
        }
        Release::Force => (-2.0 * zeta * lambda(zeta)).exp(),
    })
}

/// Linear spring-dashpot: the damping ratio `ζ = C / (2√(K m*))` that makes a free two-body
/// impact rebound with restitution `e ∈ (0, 1]` under the release rule (inverse of
/// [`e_of_zeta`]): zero overlap `ζ = L/√(1 + L²)`, `L = −ln(e)/π` (always `< 1`); zero force by
/// bisection on `2ζΛ(ζ) = −ln e`.
pub fn zeta_of_e(e: f64, release: Release) -> Result<f64> {
    check_e(e)?;
    if e == 1.0 {
        return Ok(0.0);
    }
    let target = -e.ln();
    Ok(match release {
        Release::Overlap => {
            let l = target / std::f64::consts::PI;
            l / (1.0 + l * l).sqrt()
        }
        Release::Force => {
            let f = |z: f64| 2.0 * z * lambda(z) - target;
            let mut hi = 1.0;
            while f(hi) < 0.0 {
                hi *= 2.0;
            }
            bisect(0.0, hi, f)
        }
    })
}

/// `e` must be in (0, 1].
fn check_e(e: f64) -> Result<()> {
    if e > 0.0 && e <= 1.0 {
        Ok(())
    } else {
        Err(Error::invalid(
            "restitution",
            format!(
                "the coefficient of restitution must be in (0, 1] (1: elastic; got {})",
                crate::num(e)
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ES: [f64; 5] = [0.1, 0.3, 0.5, 0.7, 0.9];

    /// The free two-body impact `m* δ̈ = −f(δ, δ̇)` from `(0, v_in)`, integrated by classical
    /// RK4 with `steps_per_t` steps per `t_ref`, until `release(δ, δ̇)` turns negative (after
    /// the first step); the crossing is located by bisecting the last step's length. Returns
    /// `−δ̇` at release. Panics if the contact has not released after `1e7` steps.
    fn integrate(
        accel: impl Fn(f64, f64) -> f64,
        release: impl Fn(f64, f64) -> f64,
        v_in: f64,
        t_ref: f64,
        steps_per_t: f64,
    ) -> f64 {
        let h = t_ref / steps_per_t;
        let step = |(d, v): (f64, f64), h: f64| {
            let (k1d, k1v) = (v, accel(d, v));
            let (k2d, k2v) = (
                v + 0.5 * h * k1v,
                accel(d + 0.5 * h * k1d, v + 0.5 * h * k1v),
            );
            let (k3d, k3v) = (
                v + 0.5 * h * k2v,
                accel(d + 0.5 * h * k2d, v + 0.5 * h * k2v),
            );
            let (k4d, k4v) = (v + h * k3v, accel(d + h * k3d, v + h * k3v));
            (
                d + h / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d),
                v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
            )
        };
        let mut s = (0.0, v_in);
        for i in 0..10_000_000 {
            let next = step(s, h);
            if i > 0 && release(next.0, next.1) < 0.0 {
                let (mut lo, mut hi) = (0.0, h);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    let t = step(s, mid);
                    if release(t.0, t.1) < 0.0 {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                return -step(s, 0.5 * (lo + hi)).1;
            }
            s = next;
        }
        panic!("no release");
    }

    /// (m* kg, K, v_in m/s): a slider against a bed, a light and a heavy pair, two speeds.
    const CASES: [(f64, f64, f64); 3] = [
        (1.0714, 4.3e7, 1.2),
        (0.02, 3.0e9, 6.2),
        (800.0, 2.0e6, 0.3),
    ];

    /// Hunt-Crossley: the restitution of the directly integrated impact equals [`e_of_x`] of the
    /// requested e's [`x_of_e`] to 1e-8, for n = 1, 1.5, 2 and each (m*, K, v_in) (e depends on
    /// x = 3/2 α v_in alone), and the force factor 1 + 3/2 α δ̇ stays positive until the overlap
    /// closes (both release rules agree).
    #[test]
    fn hunt_crossley_matches_direct_integration() {
        for &e in &ES {
            let x = x_of_e(e).unwrap();
            for n in [1.0, 1.5, 2.0] {
                for (m, k, v) in CASES {
                    let c = x / v; // 3/2 α
                    let d_max = ((n + 1.0) * m * v * v / (2.0 * k)).powf(1.0 / (n + 1.0));
                    let min_factor = std::cell::Cell::new(f64::INFINITY);
                    let accel = |d: f64, r: f64| {
                        let factor = 1.0 + c * r;
                        if d > 0.0 {
                            min_factor.set(min_factor.get().min(factor));
                        }
                        -k * d.max(0.0).powf(n) * factor / m
                    };
                    let out = integrate(accel, |d, _| d, v, d_max / v, 40_000.0 / e);
                    let got = out / v;
                    assert!(
                        (got - e).abs() <= 1e-8,
                        "e {e} n {n} m {m} K {k} v {v}: integrated {got}"
                    );
                    assert!(min_factor.get() > 0.0, "e {e} n {n}: force changed sign");
                }
            }
        }
    }

    /// Linear spring-dashpot: the directly integrated impact released at zero overlap and at
    /// zero force rebounds with the requested e when ζ = [`zeta_of_e`] (C = 2ζ√(K m*)), to
    /// 1e-9, whatever m*, K and v_in.
    #[test]
    fn linear_matches_direct_integration() {
        for &e in &ES {
            for release in [Release::Overlap, Release::Force] {
                let zeta = zeta_of_e(e, release).unwrap();
                for (m, k, v) in CASES {
                    let c = 2.0 * zeta * (k * m).sqrt();
                    let accel = |d: f64, r: f64| -(k * d + c * r) / m;
                    let out = match release {
                        Release::Overlap => integrate(accel, |d, _| d, v, (m / k).sqrt(), 20_000.0),
                        Release::Force => {
                            integrate(accel, |d, r| k * d + c * r, v, (m / k).sqrt(), 20_000.0)
                        }
                    };
                    let got = out / v;
                    assert!(
                        (got - e).abs() <= 1e-9,
                        "e {e} {release:?} ζ {zeta} m {m}: integrated {got}"
                    );
                }
            }
        }
    }

    /// Overdamped and critically damped linear contacts: released at zero force they separate
    /// with exp(−2ζΛ(ζ)) (e(1) = e⁻²), as integration shows; at zero overlap they never separate.
    #[test]
    fn linear_overdamped_force_release() {
        for zeta in [1.0, 1.0 + 1e-9, 1.7, 6.0] {
            let e = e_of_zeta(zeta, Release::Force).unwrap();
            // m* = K = v_in = 1: ω = 1, C = 2ζ.
            let c = 2.0 * zeta;
            let out = integrate(|d, r| -(d + c * r), |d, r| d + c * r, 1.0, 1.0, 20_000.0);
            assert!((out - e).abs() <= 1e-9, "ζ {zeta}: {out} vs {e}");
            assert_eq!(e_of_zeta(zeta, Release::Overlap).unwrap(), 0.0);
        }
        assert!((e_of_zeta(1.0, Release::Force).unwrap() - (-2.0f64).exp()).abs() <= 1e-16);
        // Continuity at ζ = 1 from both sides.
        for d in [1e-6, 1e-10] {
            for z in [1.0 - d, 1.0 + d] {
                let got = e_of_zeta(z, Release::Force).unwrap();
                assert!((got - (-2.0f64).exp()).abs() <= 2.0 * d, "{z}: {got}");
            }
        }
    }

    /// e → x → e and e → ζ → e to 1e-12 (and the forward maps decrease), over (0, 1].
    #[test]
    fn round_trips() {
        let mut es = ES.to_vec();
        es.extend([1e-6, 1e-3, 0.01, 0.25, 0.999, 0.999_999, 1.0 - 1e-12, 1.0]);
        for &e in &es {
            let x = x_of_e(e).unwrap();
            assert!(
                (e_of_x(x).unwrap() - e).abs() <= 1e-12 * e.max(1e-3),
                "e {e}: x {x}"
            );
            for release in [Release::Overlap, Release::Force] {
                let z = zeta_of_e(e, release).unwrap();
                let back = e_of_zeta(z, release).unwrap();
                assert!(
                    (back - e).abs() <= 1e-12,
                    "{release:?} e {e}: ζ {z} → {back}"
                );
            }
        }
        // x(1 − ε) ≈ 3ε/2 (e = 1 − 2x/3 + O(x²)): the small-x series keeps this precise.
        let e = 1.0 - 1e-12;
        let eps = 1.0 - e; // exact (the double nearest 1 − 1e-12 is not 1e-12 away)
        let x = x_of_e(e).unwrap();
        assert!((x / (1.5 * eps) - 1.0).abs() <= 1e-6, "{x}");
        let xs: Vec<f64> = (0..200)
            .map(|i| 10f64.powf(-6.0 + 0.05 * i as f64))
            .collect();
        let ex: Vec<f64> = xs.iter().map(|&x| e_of_x(x).unwrap()).collect();
        assert!(ex.windows(2).all(|w| w[1] < w[0]), "e(x) must decrease");
        for release in [Release::Overlap, Release::Force] {
            let ez: Vec<f64> = (0..99)
                .map(|i| e_of_zeta(0.01 * i as f64, release).unwrap())
                .collect();
            assert!(ez.windows(2).all(|w| w[1] < w[0]), "{release:?}");
        }
    }

    /// The numbers the module documentation quotes: the exact x at e = 0.5, what the
    /// Lankarani-Nikravesh (x = 3(1 − e²)/4) and Flores (x = 8(1 − e)/(5e)) sizings really
    /// give, and the two linear rules at ζ = 0.5 (closed forms exp(−π/√3) and exp(−2π/(3√3))).
    #[test]
    fn documented_values() {
        let close = |a: f64, b: f64, tol: f64| assert!((a - b).abs() <= tol, "{a} vs {b}");
        close(x_of_e(0.5).unwrap(), 1.432751, 5e-7);
        close(e_of_x(3.0 * (1.0 - 0.25) / 4.0).unwrap(), 0.725241, 5e-7);
        close(e_of_x(8.0 * 0.5 / 2.5).unwrap(), 0.470445, 5e-7);
        close(e_of_x(3.0 * (1.0 - 0.01) / 4.0).unwrap(), 0.665, 5e-4);
        close(e_of_x(8.0 * 0.9 / 0.5).unwrap(), 0.069, 5e-4);
        let s3 = 3f64.sqrt();
        let over = e_of_zeta(0.5, Release::Overlap).unwrap();
        let force = e_of_zeta(0.5, Release::Force).unwrap();
        close(over, (-std::f64::consts::PI / s3).exp(), 1e-15);
        close(
            force,
            (-2.0 * std::f64::consts::PI / (3.0 * s3)).exp(),
            1e-15,
        );
        close(over, 0.163034, 5e-7);
        close(force, 0.298436, 5e-7);
        close(force / over, 1.8305, 5e-5);
        // Small damping: e = 1 − α v_in (x = 3/2 α v_in) and e = 1 − πζ to first order.
        close((1.0 - e_of_x(1.5e-6).unwrap()) / 1e-6, 1.0, 1e-5);
        for r in [Release::Overlap, Release::Force] {
            close(
                (1.0 - e_of_zeta(1e-7, r).unwrap()) / 1e-7,
                std::f64::consts::PI,
                1e-5,
            );
        }
    }

    #[test]
    fn bad_values_are_refused() {
        for e in [0.0, -0.1, 1.0 + 1e-15, 2.0, f64::NAN, f64::INFINITY] {
            assert!(x_of_e(e).is_err(), "{e}");
            assert!(zeta_of_e(e, Release::Force).is_err(), "{e}");
            assert!(zeta_of_e(e, Release::Overlap).is_err(), "{e}");
        }
        assert!(e_of_x(-1.0).is_err() && e_of_x(f64::NAN).is_err());
        assert_eq!(e_of_x(f64::INFINITY).unwrap(), 0.0);
        assert!(e_of_zeta(-0.1, Release::Force).is_err());
        assert!(e_of_zeta(f64::INFINITY, Release::Force).is_err());
    }
}
