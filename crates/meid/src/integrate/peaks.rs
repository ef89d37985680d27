//! Exact extremes of the response channels ([`crate::impact::Channel`]) on the continuous
//! solution, independent of the output sample rate.
//!
//! Within a stretch of one mode every channel of a linear system is `g(s) = ℓ_σᵀX(s)`: a
//! polynomial on a Taylor step, a sum of exponentials (plus `p₀ + p₁s` for rigid motion) on a
//! closed-form segment. Its extremes on `[0, L]` are at the ends (the one-sided values at the
//! switches that bound the stretch: a channel such as the bed acceleration jumps there) or where
//! `g'` changes sign; those roots are located by the same bracketing search as the switches
//! ([`super::roots`]) to `1e-9` of the fastest period, which leaves the value off by about
//! `½|g''|δ² ≈ 2e-17 |g|max` for a channel oscillating at up to that frequency (an estimate, not
//! a bound). A stretch (or a window of a long segment) whose bound `max|g| ≤ Σ|a_k|L^k`
//! (polynomial) or `|p₀| + |p₁|L + Σ|A_k| e^{Re λ_k s}` (exponentials) cannot beat the extremes
//! found so far is not searched: the result is the same, only cheaper.

use super::propagator::{ExpSum, Functional, Segment};
use super::roots::{for_each_extremum, Scalar, SearchOptions};
use super::taylor::{self, Coefficients, Poly};
use crate::impact::{Channel, CHANNELS, N_CHANNELS};

/// The search for extremes: a location to `1e-9` of the fastest period (see the module docs).
pub(crate) const EXTREMUM_SEARCH: SearchOptions = SearchOptions {
    max_step: f64::INFINITY,
    tolerance: 1e-9,
};

/// Largest and smallest value of one channel over a run, with their times (s). Before any
/// value is offered `max = −∞`, `min = +∞`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extremes {
    pub max: f64,
    pub t_max: f64,
    pub min: f64,
    pub t_min: f64,
}

impl Default for Extremes {
    fn default() -> Self {
        Self {
            max: f64::NEG_INFINITY,
            t_max: f64::NAN,
            min: f64::INFINITY,
            t_min: f64::NAN,
        }
    }
}

impl Extremes {
    /// Takes the value `v` at time `t` (the earliest of equal extremes is kept). A NaN is kept
    /// as the maximum so that [`Extremes::is_finite`] reports it.
    #[inline]
    pub fn offer(&mut self, v: f64, t: f64) {
        if v > self.max || v.is_nan() {
            self.max = v;
            self.t_max = t;
        }
        if v < self.min {
            self.min = v;
            self.t_min = t;
        }
    }
    /// True once a value has been offered.
    pub fn is_set(&self) -> bool {
        !self.t_max.is_nan() || !self.t_min.is_nan()
    }
    /// False when a non-finite value was offered.
    pub fn is_finite(&self) -> bool {
        !self.is_set() || (self.max.is_finite() && self.min.is_finite())
    }
    /// The value of largest magnitude, with its time: `(value, t)`; `(0, NaN)` before any value.
    pub fn peak(&self) -> (f64, f64) {
        if !self.is_set() {
            return (0.0, f64::NAN);
        }
        if self.max.abs() >= self.min.abs() {
            (self.max, self.t_max)
        } else {
            (self.min, self.t_min)
        }
    }
    /// Largest magnitude.
    pub fn abs_peak(&self) -> f64 {
        self.peak().0.abs()
    }
    /// Could a value within `±bound` change these extremes?
    #[inline]
    fn could_improve(&self, bound: f64) -> bool {
        !(bound <= self.max && -bound >= self.min)
    }
}

/// The extremes of every channel, indexed by [`Channel::index`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Peaks(pub [Extremes; N_CHANNELS]);

impl Peaks {
    pub fn get(&self, c: Channel) -> &Extremes {
        &self.0[c.index()]
    }
    pub fn get_mut(&mut self, c: Channel) -> &mut Extremes {
        &mut self.0[c.index()]
    }
    /// Offers all channel values at one instant.
    pub fn offer_all(&mut self, v: &[f64; N_CHANNELS], t: f64) {
        for (e, &x) in self.0.iter_mut().zip(v) {
            e.offer(x, t);
        }
    }
    /// The first channel with a non-finite extreme, if any.
    pub fn non_finite(&self) -> Option<Channel> {
        CHANNELS.into_iter().find(|c| !self.get(*c).is_finite())
    }
}

/// Extremes of `p(s) = Σ a_k s^k` on `[0, len]` (a Taylor step of validity `tau` starting at
/// time `t0`), offered to `ext`.
pub(crate) fn on_poly(
    a: &Coefficients,
    tau: f64,
    period: f64,
    t0: f64,
    len: f64,
    ext: &mut Extremes,
) {
    ext.offer(a[0], t0);
    if len <= 0.0 {
        return;
    }
    if !ext.could_improve(taylor::abs_horner(a, len)) {
        // The end value cannot beat the extremes either: nothing to do.
        return;
    }
    ext.offer(taylor::eval(a, len), t0 + len);
    let mut da = [0.0; taylor::ORDER + 1];
    for (k, d) in da.iter_mut().take(taylor::ORDER).enumerate() {
        *d = (k + 1) as f64 * a[k + 1];
    }
    // A slope of one sign throughout (a concave bound) leaves the extremes at the ends.
    if taylor::keeps_sign(&da, 1.0, len) || taylor::keeps_sign(&da, -1.0, len) {
        return;
    }
    // A monotone slope (its derivative `p''` keeps its sign) has at most one root, where its
    // end values differ in sign: safeguarded Newton on it, without the general search.
    let mut d2a = [0.0; taylor::ORDER + 1];
    for (k, d) in d2a.iter_mut().take(taylor::ORDER).enumerate() {
        *d = (k + 1) as f64 * da[k + 1];
    }
    if taylor::keeps_sign(&d2a, 1.0, len) || taylor::keeps_sign(&d2a, -1.0, len) {
        let (g0, g1) = (da[0], taylor::eval(&da, len));
        if g0 * g1 < 0.0 {
            let s = monotone_root(&da, &d2a, len, g0, EXTREMUM_SEARCH.tolerance * period);
            ext.offer(taylor::eval(a, s), t0 + s);
        }
        return;
    }
    let slope = Poly::new(&da, tau, period);
    for_each_extremum(&slope, 0.0, len, EXTREMUM_SEARCH, |s, _| {
        ext.offer(taylor::eval(a, s), t0 + s)
    });
}

/// The root of `g = Σ g_k s^k` (slope `dg`) on `[0, len]`, given that `g` is monotone there and
/// `g(0) = g0` and `g(len)` differ in sign: Newton steps kept inside the bracket (bisection when
/// one leaves it or does not halve the bracket), to `tol` (s).
fn monotone_root(g: &Coefficients, dg: &Coefficients, len: f64, g0: f64, tol: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, len);
    let side = g0.signum();
    let mut s = 0.5 * len;
    for _ in 0..100 {
        let v = taylor::eval(g, s);
        if v == 0.0 {
            return s;
        }
        if v.signum() == side {
            lo = s;
        } else {
            hi = s;
        }
        if hi - lo <= tol.max(4.0 * f64::EPSILON * hi) {
            break;
        }
        let d = taylor::eval(dg, s);
        let newton = s - v / d;
        s = if d != 0.0 && newton > lo && newton < hi && (newton - s).abs() < 0.5 * (hi - lo) {
            newton
        } else {
            0.5 * (lo + hi)
        };
    }
    s
}

/// Extremes of `ℓᵀX(s)` on `[0, len]` of a closed-form segment starting at time `t0`, offered
/// to `ext`; `la = ℓᵀA` is the functional of the slope. Long segments are searched window by
/// window (four of the functional's fastest periods each), skipping windows whose bound
/// cannot beat the extremes found so far.
pub(crate) fn on_segment(
    seg: &Segment<'_>,
    l: &[f64],
    la: &[f64],
    t0: f64,
    len: f64,
    ext: &mut Extremes,
) {
    let f = seg.functional(l);
    let value = |s: f64| match &f {
        Functional::Exp(e) => e.derivative(0, s),
        other => other.value_slope(s).0,
    };
    ext.offer(value(0.0), t0);
    if len <= 0.0 {
        return;
    }
    ext.offer(value(len), t0 + len);
    let df = seg.functional(la);
    let Functional::Exp(e) = &f else {
        for_each_extremum(&df, 0.0, len, EXTREMUM_SEARCH, |s, _| {
            ext.offer(value(s), t0 + s)
        });
        return;
    };
    let period = e.fastest_period();
    let window = if period.is_finite() && period > 0.0 {
        4.0 * period
    } else {
        len
    };
    let mut a = 0.0;
    while a < len {
        let b = if len - a <= 1.5 * window {
            len
        } else {
            a + window
        };
        if ext.could_improve(exp_bound(e, a, b)) {
            ext.offer(value(a), t0 + a);
            for_each_extremum(&df, a, b, EXTREMUM_SEARCH, |s, _| {
                ext.offer(value(s), t0 + s)
            });
        }
        a = b;
    }
}

/// A bound of `|g(s)|` on `[a, b]` for `g = p₀ + p₁s + p₂s² + Re Σ A_k e^{λ_k s}`.
fn exp_bound(e: &ExpSum, a: f64, b: f64) -> f64 {
    let lin = (e.p0 + e.p1 * a).abs().max((e.p0 + e.p1 * b).abs()) + e.p2.abs() * b * b;
    lin + e
        .amp
        .iter()
        .zip(&e.lam)
        .map(|(amp, l)| {
            let s = if l.re < 0.0 { a } else { b };
            amp.norm() * (l.re * s).exp()
        })
        .sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polynomial_extremes_are_exact() {
        // p(s) = sin-like cubic: p = s - s³ on [0, 1.5]: max 2/(3√3) at 1/√3, min at 1.5.
        let mut a = [0.0; taylor::ORDER + 1];
        a[1] = 1.0;
        a[3] = -1.0;
        let mut e = Extremes::default();
        on_poly(&a, 2.0, 1.0, 10.0, 1.5, &mut e);
        let s = 1.0 / 3f64.sqrt();
        assert!((e.max - 2.0 / (3.0 * 3f64.sqrt())).abs() < 1e-15);
        assert!((e.t_max - (10.0 + s)).abs() < 1e-9);
        assert!((e.min - (1.5 - 1.5f64.powi(3))).abs() < 1e-15);
        assert_eq!(e.t_min, 11.5);
        assert_eq!(e.peak(), (e.min, e.t_min));
    }

    #[test]
    fn bound_skips_only_what_cannot_improve() {
        let mut a = [0.0; taylor::ORDER + 1];
        a[0] = 0.1;
        a[2] = 0.1;
        let mut e = Extremes::default();
        e.offer(5.0, 0.0);
        e.offer(-5.0, 1.0);
        on_poly(&a, 2.0, 1.0, 3.0, 1.0, &mut e);
        assert_eq!((e.max, e.min), (5.0, -5.0));
        e.offer(0.15, 9.0);
        let mut f = Extremes::default();
        f.offer(0.15, 0.0);
        on_poly(&a, 2.0, 1.0, 3.0, 1.0, &mut f);
        assert!((f.max - 0.2).abs() < 1e-15 && f.t_max == 4.0);
    }
}
