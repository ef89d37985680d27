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
//! a bound). A Taylor step whose bound `max|g| ≤ Σ|a_k|L^k` cannot beat the extremes found so
//! far is not searched, nor is a window or cell of a closed-form segment whose range bound (a
//! cubic Hermite interpolant plus its remainder, envelopes for the fast terms:
//! `exp_extremes`) cannot: the result is the same, only cheaper.
//!
//! # A channel that cannot move
//! The velocity of an impactor in free flight is constant: its slope `ℓ_σᵀA_σX(s)` has a zero
//! row of `A_σ` behind it, so `p₀ = p₁ = p₂ = 0` and every `A_k = 0` exactly
//! ([`Functional::is_zero`]). The search for sign changes of such a slope can find none (the
//! lifted value `G = noise ≥ 0` is never negative, [`super::roots::Search::advance`]), but it
//! proves that only by halving every cell down to `h/2¹⁰` and stepping across it at that size
//! (about 14,000 evaluations of `g'` and of its curvature bound per cell, each one `exp` and
//! `sincos` per term). Meanwhile the channel's bounds stay within their round-off allowance
//! of its constant value, so every cell "could improve" it and is searched: on the FE press
//! (`examples/press-off-centre-4-dampers.toml`, 46-49 terms) that was 99 % of the run
//! (issue 29). Such a slope is not searched; the value at each such cell's start is still
//! offered, so the extremes are the same bit for bit.

use faer::c64;

use super::propagator::{ExpSum, Functional, Segment};
use super::roots::{for_each_extremum, HermiteCubic, Scalar, SearchOptions};
#[cfg(test)]
use super::taylor::Poly;
use super::taylor::{self, Coefficients};
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
    /// Takes the value `v` at time `t` (the earliest of equal extremes is kept, in whatever
    /// order they are offered). A NaN is kept
    /// as the maximum so that [`Extremes::is_finite`] reports it.
    #[inline]
    pub fn offer(&mut self, v: f64, t: f64) {
        if v > self.max || v.is_nan() || (v == self.max && t < self.t_max) {
            self.max = v;
            self.t_max = t;
        }
        if v < self.min || (v == self.min && t < self.t_min) {
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
        self.could_improve_range(-bound, bound)
    }
    /// Could a value within `[lo, hi]` change these extremes? (True when either is NaN.)
    #[inline]
    fn could_improve_range(&self, lo: f64, hi: f64) -> bool {
        !(hi <= self.max && lo >= self.min)
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

/// Extremes of `p(s) = Σ_{k≤deg} a_k s^k` on `[0, len]` (a Taylor step of validity `tau`
/// starting at time `t0`, truncated at degree `deg` by [`taylor::degree_for_reach`]; the
/// coefficients above `deg` must be zero), offered to `ext`.
///
/// The evaluations and the search run on the lowest of 8, 12, 16, 20 or `P` that holds `deg`: a
/// stretch much shorter than the step's validity costs a third of a full one.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(crate) fn on_poly(
    a: &Coefficients,
    deg: usize,
    tau: f64,
    period: f64,
    t0: f64,
    len: f64,
    ext: &mut Extremes,
) {
    match deg {
        0..=8 => on_poly_m::<9>(a, tau, period, t0, len, ext),
        9..=12 => on_poly_m::<13>(a, tau, period, t0, len, ext),
        13..=16 => on_poly_m::<17>(a, tau, period, t0, len, ext),
        17..=20 => on_poly_m::<21>(a, tau, period, t0, len, ext),
        _ => on_poly_m::<{ taylor::ORDER + 1 }>(a, tau, period, t0, len, ext),
    }
}

/// `Σ_{k<M} c_k x^k`.
#[inline(always)]
fn horner<const M: usize>(c: &Coefficients, x: f64) -> f64 {
    taylor::poly4::<M>(x, |k| c[k])
}

/// [`on_poly`] on the first `M` coefficients.
#[inline(always)]
fn on_poly_m<const M: usize>(
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
    if !ext.could_improve(taylor::poly4::<M>(len, |k| a[k].abs())) {
        // The end value cannot beat the extremes either: nothing to do.
        return;
    }
    ext.offer(horner::<M>(a, len), t0 + len);
    let mut da = [0.0; taylor::ORDER + 1];
    for (k, d) in da.iter_mut().take(M - 1).enumerate() {
        *d = (k + 1) as f64 * a[k + 1];
    }
    // A slope of one sign throughout (a concave bound) leaves the extremes at the ends.
    if one_signed::<M>(&da, len) {
        return;
    }
    // A slope that starts at zero (a channel from rest, `p' = s^j q(s)`) has its sign changes
    // in `(0, len]` where `q` has them: search `q`, whose start value is clearly signed. The
    // slope itself starts at a root of order `j` and a dip of `3a₃s² + 4a₄s³` narrower than
    // the search grid would not show in its end values.
    if let Some(j) = da[..M - 1].iter().position(|&c| c != 0.0) {
        da.copy_within(j..M - 1, 0);
        da[M - 1 - j..].fill(0.0);
    }
    // A monotone slope (its derivative `p''` keeps its sign) has at most one root, where its
    // end values differ in sign: safeguarded Newton on it, without the general search.
    let mut d2a = [0.0; taylor::ORDER + 1];
    for (k, d) in d2a.iter_mut().take(M - 1).enumerate() {
        *d = (k + 1) as f64 * da[k + 1];
    }
    if one_signed::<M>(&d2a, len) {
        let (g0, g1) = (da[0], horner::<M>(&da, len));
        if g0 * g1 < 0.0 {
            let tol = EXTREMUM_SEARCH.tolerance * period;
            let s = monotone_root::<M>(&da, &d2a, len, (g0, g1), tol);
            ext.offer(horner::<M>(a, s), t0 + s);
        }
        return;
    }
    let slope = Slope::<M> {
        a: da,
        da: d2a,
        period,
        noise: 64.0 * f64::EPSILON * taylor::poly4::<M>(tau, |k| da[k].abs()),
    };
    for_each_extremum(&slope, 0.0, len, EXTREMUM_SEARCH, |s, _| {
        ext.offer(horner::<M>(a, s), t0 + s)
    });
}

/// The slope `Σ_{k<M} a_k s^k` of a channel on a Taylor step, for the general search: as
/// [`taylor::Poly`] on the first `M` coefficients (the same round-off size, 64 ulps of `Σ|a_k|τ^k`).
struct Slope<const M: usize> {
    a: Coefficients,
    /// `(k + 1) a_{k+1}`.
    da: Coefficients,
    period: f64,
    noise: f64,
}

impl<const M: usize> Scalar for Slope<M> {
    #[inline]
    fn value_slope(&self, s: f64) -> (f64, f64) {
        (horner::<M>(&self.a, s), horner::<M>(&self.da, s))
    }
    /// `Σ k(k−1)|a_k| b^{k−2}` (s ≥ 0).
    #[inline]
    fn curvature_bound(&self, _a: f64, b: f64) -> f64 {
        taylor::poly4::<M>(b.abs(), |k| {
            if k + 2 < M {
                taylor::K_K1[k + 2] * self.a[k + 2].abs()
            } else {
                0.0
            }
        })
    }
    fn fastest_period(&self) -> f64 {
        self.period
    }
    fn noise(&self) -> f64 {
        self.noise
    }
}

/// True when `p(s) = Σ_{k<M} a_k s^k` is non-zero with one sign on all of `(0, len]`, or is
/// identically zero: with `j` the first index where `a_j ≠ 0`, `p(s) = s^j q(s)` with
/// `q(s) = Σ_k a_{j+k} s^k` and `s^j > 0` on `(0, len]`, so the concave certificate of `q`
/// ([`taylor::keeps_sign`]: `b₀ > 0` and `b₀ + b₁len + Σ_{k≥2} min(b_k, 0) len^k > 0` with
/// `b_k = sign(a_j)·a_{j+k}`) proves it. (A slope that starts at exactly zero, a channel
/// starting from rest, has `j ≥ 1`: the certificate of `p` itself needs `p(0) ≠ 0`.) A slope
/// one-signed on `(0, len]` makes its integral monotone on `[0, len]`.
#[inline]
fn one_signed<const M: usize>(a: &Coefficients, len: f64) -> bool {
    if a[0] != 0.0 {
        return keeps_sign::<M>(a, len);
    }
    let Some(j) = a[..M].iter().position(|v| *v != 0.0) else {
        return true;
    };
    let mut q = [0.0; taylor::ORDER + 1];
    q[..M - j].copy_from_slice(&a[j..M]);
    keeps_sign::<M>(&q, len)
}

/// [`taylor::keeps_sign`] on the first `M` coefficients, with the sign of `a₀`: true when
/// `p(s) = Σ_{k<M} a_k s^k` has the sign of `a₀ ≠ 0` on all of `[0, len]`.
#[inline(always)]
fn keeps_sign<const M: usize>(a: &Coefficients, len: f64) -> bool {
    let sign = a[0].signum();
    let b0 = sign * a[0];
    if b0.is_nan() || b0 <= 0.0 {
        return false;
    }
    // Σ_{k≥2} min(b_k, 0) len^(k−2).
    let neg = taylor::poly4::<M>(len, |k| {
        if k + 2 < M {
            (sign * a[k + 2]).min(0.0)
        } else {
            0.0
        }
    });
    b0 + len * (sign * a[1] + len * neg) > 0.0
}

/// The root of `g = Σ g_k s^k` (slope `dg`) on `[0, len]`, given that `g` is monotone there and
/// `g(0) = g0` and `g(len) = g1` differ in sign: Newton steps from the secant point, kept inside
/// the bracket (bisection when one leaves it or does not halve the bracket), to `tol` (s): the
/// search ends when the bracket is that narrow or a Newton step is shorter than `tol/4`
/// (Newton's error is then of the order of the step squared over the slope's scale, far
/// below `tol`; a step that no longer moves `s` ends it too).
fn monotone_root<const M: usize>(
    g: &Coefficients,
    dg: &Coefficients,
    len: f64,
    (g0, g1): (f64, f64),
    tol: f64,
) -> f64 {
    let (mut lo, mut hi) = (0.0, len);
    let side = g0.signum();
    let mut s = (len * g0 / (g0 - g1)).clamp(0.0, len);
    if !(s > 0.0 && s < len) {
        s = 0.5 * len;
    }
    let mut last_step = f64::INFINITY;
    for _ in 0..100 {
        let v = horner::<M>(g, s);
        if v == 0.0 {
            return s;
        }
        if v.signum() == side {
            lo = s;
        } else {
            hi = s;
        }
        if hi - lo <= tol.max(4.0 * f64::EPSILON * hi) || last_step < 0.25 * tol {
            break;
        }
        let d = horner::<M>(dg, s);
        let newton = s - v / d;
        let step = (newton - s).abs();
        if d != 0.0 && newton > lo && newton < hi && step < 0.5 * (hi - lo) {
            if newton == s {
                break;
            }
            s = newton;
            last_step = step;
        } else {
            s = 0.5 * (lo + hi);
            last_step = f64::INFINITY;
        }
    }
    s
}

/// Extremes of `ℓᵀX(s)` on `[0, len]` of a closed-form segment starting at time `t0`, offered
/// to `ext`; `la = ℓᵀA` is the functional of the slope. A sum of exponentials is searched by
/// [`exp_extremes`]; the matrix-exponential fallback by one search over the whole segment.
#[inline(never)]
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
    match &f {
        Functional::Exp(e) => exp_extremes(e, &df, t0, len, ext),
        _ => for_each_extremum(&df, 0.0, len, EXTREMUM_SEARCH, |s, _| {
            ext.offer(value(s), t0 + s)
        }),
    }
}

/// Windows of [`exp_extremes`] are about this many of the functional's fastest periods long.
const WINDOW_PERIODS: f64 = 4.0;
/// Cells of a window are at most an eighth of the fastest period long.
const CELLS_PER_PERIOD: f64 = 8.0;
/// The exponentials of the bounds are advanced by one complex product per window (per cell
/// inside a window), and recomputed directly every this many windows.
const RESEED: usize = 32;
/// Relative round-off allowance of the bounds (a multiple of the functional's size).
const BOUND_PAD: f64 = 1e-12;

/// Extremes on `[0, len]` (value and time, offered to `ext`, the ends already offered) of
/// `g(s) = p₀ + p₁s + p₂s² + Re Σ_k A_k e^{λ_k s}`, whose slope is `dg` (`p₂ ≠ 0` only for
/// the slider in flight under a constant force).
///
/// The segment is cut into `N` equal windows of about four fastest periods and each window
/// into cells of at most an eighth of the fastest period. Only the cells whose range bound
/// can beat the extremes found so far are searched for the roots of `g'`
/// ([`for_each_extremum`]); the result is that of searching everything, only cheaper.
///
/// Range bound of `g` on `[a, b]`, `h = b − a`: split the terms into a resolved part `g_S`
/// (with `p₀ + p₁s + p₂s²`, which the cubic interpolates exactly) and the rest `g_F`. With `H` the cubic Hermite interpolant of `g_S` from
/// `g_S(a), g_S'(a), g_S(b), g_S'(b)`, `|g_S − H| ≤ M₄ (s−a)²(b−s)²/4! ≤ M₄h⁴/384` where
/// `M₄ = Σ_S |A_k| |λ_k|⁴ max(e^{Re λ_k a}, e^{Re λ_k b})`, and `|g_F| ≤ Σ_F |A_k|
/// max(e^{Re λ_k a}, e^{Re λ_k b})`; so
///
/// `min H − M₄h⁴/384 − F ≤ g(s) ≤ max H + M₄h⁴/384 + F` on `[a, b]`,
///
/// and each term goes to the side where it counts less: into `S` when `(|λ_k|h)⁴ < 384`.
/// On a cell (`|λ_k|h ≤ π/4`) every term is resolved and the bound is within
/// `(π/4)⁴/384 ≈ 1e-3` of each term's size from the true range.
///
/// 1. Every window gets its bound (values of the exponentials advanced by one complex
///    product per window), and the window boundaries with the largest and smallest values
///    are evaluated exactly and offered: the extremes found so far are then close to the
///    segment's own before any search, wherever in the segment they sit.
/// 2. The windows, in time order, whose bound can beat the extremes so far are cut into cells
///    with their own bounds; each cell that can beat them is searched.
///
/// The bounds carry an allowance for round-off (`1e-12` of the functional's size, plus its
/// noise), so a window or cell is skipped only when its values cannot beat the extremes.
#[inline(never)]
fn exp_extremes(e: &ExpSum, dg: &Functional<'_>, t0: f64, len: f64, ext: &mut Extremes) {
    let value = |s: f64| e.derivative(0, s);
    let period = e.fastest_period();
    if !(period.is_finite() && period > 0.0) || e.amp.is_empty() {
        // A zero slope has no sign change to find (module docs, "A channel that cannot move").
        if !dg.is_zero() {
            for_each_extremum(dg, 0.0, len, EXTREMUM_SEARCH, |s, _| {
                ext.offer(value(s), t0 + s)
            });
        }
        return;
    }
    let win = ExpWindows::new(e, len, period);
    let (lo, hi, seeds) = win.bounds();
    for (g, s) in seeds {
        if g.is_finite() {
            ext.offer(value(s), t0 + s);
        }
    }
    win.refine(dg, t0, (&lo, &hi), ext);
}

/// A resolved term of [`exp_extremes`]' window bounds: `(A, λ, e^{λw}, e^{Re λ w},
/// |λ|⁴·max(1, e^{Re λ w}), z, env)`, `z = A e^{λa}` and `env = |A| e^{Re λ a}` at the window's
/// start `a`.
type Resolved = (c64, c64, c64, f64, f64, c64, f64);
/// An unresolved term, bounded by its envelope only: `(|A|, Re λ, e^{Re λ w}, env)`.
type Unresolved = (f64, f64, f64, f64);

/// The windows and cells of [`exp_extremes`] on `[0, len]` of one exponential sum, with the
/// terms' magnitudes `|A_k|`, `|λ_k|⁴` and the round-off allowance `pad` of the bounds.
struct ExpWindows<'e> {
    e: &'e ExpSum,
    len: f64,
    /// Windows: `n_win` of length `w`; cells: `n_cell` of length `hc` per window.
    n_win: usize,
    w: f64,
    n_cell: usize,
    hc: f64,
    mags: Vec<f64>,
    l4: Vec<f64>,
    pad: f64,
}

impl<'e> ExpWindows<'e> {
    /// Windows of about [`WINDOW_PERIODS`] fastest periods `period`, cells of at most
    /// `1/`[`CELLS_PER_PERIOD`] of it; the allowance is [`BOUND_PAD`] of the sum's largest
    /// possible size on `[0, len]` plus its noise.
    fn new(e: &'e ExpSum, len: f64, period: f64) -> Self {
        let n_win = ((len / (WINDOW_PERIODS * period)).round() as usize).max(1);
        let w = len / n_win as f64;
        let n_cell = ((w * CELLS_PER_PERIOD / period).ceil() as usize).max(1);
        let hc = w / n_cell as f64;
        let mags: Vec<f64> = e.amp.iter().map(|a| a.norm()).collect();
        let pad = BOUND_PAD
            * (e.p0.abs()
                + e.p1.abs() * len
                + e.p2.abs() * len * len
                + mags
                    .iter()
                    .zip(&e.lam)
                    .map(|(m, l)| m * (l.re * len).exp().max(1.0))
                    .sum::<f64>())
            + e.noise();
        let l4: Vec<f64> = e.lam.iter().map(|l| l.norm_sqr() * l.norm_sqr()).collect();
        ExpWindows {
            e,
            len,
            n_win,
            w,
            n_cell,
            hc,
            mags,
            l4,
            pad,
        }
    }

    /// The end of window `i`.
    fn end(&self, i: usize) -> f64 {
        if i + 1 == self.n_win {
            self.len
        } else {
            (i + 1) as f64 * self.w
        }
    }

    /// The terms split into those resolved on a window (`(|λ_k|w)⁴ < 384`), advanced as
    /// exponentials, and the others, advanced as envelopes.
    fn terms(&self) -> (Vec<Resolved>, Vec<Unresolved>) {
        let (e, w) = (self.e, self.w);
        let k = e.amp.len();
        let w4 = w.powi(4) / 384.0;
        let resolved: Vec<bool> = self.l4.iter().map(|l| l * w4 < 1.0).collect();
        let mut slow: Vec<Resolved> = Vec::with_capacity(k);
        let mut fast: Vec<Unresolved> = Vec::with_capacity(k);
        for j in 0..k {
            let (amp, lam, mag) = (e.amp[j], e.lam[j], self.mags[j]);
            let decay = (lam.re * w).exp();
            if resolved[j] {
                // (A, λ, e^{λw}, e^{Re λ w}, l4·max(1, e^{Re λ w}), z, env)
                slow.push((
                    amp,
                    lam,
                    (lam * w).exp(),
                    decay,
                    self.l4[j] * decay.max(1.0),
                    amp,
                    mag,
                ));
            } else {
                // (|A|, Re λ, e^{Re λ w}, env)
                fast.push((mag, lam.re, decay, mag));
            }
        }
        (slow, fast)
    }

    /// Step 1: every window's range bound `(lo, hi)`, and the window boundaries where the
    /// resolved part is largest and smallest (`(value, s)` each, as seeds). The resolved terms
    /// are advanced as exponentials `z_k = A_k e^{λ_k a}`, the others only as envelopes
    /// `|A_k| e^{Re λ_k a}`; a decaying envelope below 1e-3 of the round-off allowance leaves
    /// the loop, its bound at that time kept as a constant (it only decreases afterwards).
    fn bounds(&self) -> (Vec<f64>, Vec<f64>, [(f64, f64); 2]) {
        let (e, w, n_win) = (self.e, self.w, self.n_win);
        let (mut slow, mut fast) = self.terms();
        let mut dropped = 0.0;
        let drop_below = 1e-3 * self.pad;
        let (mut lo, mut hi) = (vec![0.0; n_win], vec![0.0; n_win]);
        let sums = |slow: &[Resolved], s: f64| {
            let (mut g, mut d) = (e.p0 + (e.p1 + e.p2 * s) * s, e.p1 + 2.0 * e.p2 * s);
            for t in slow {
                g += t.5.re;
                d += (t.5 * t.1).re;
            }
            (g, d)
        };
        let (mut gs0, mut ds0) = sums(&slow, 0.0);
        let (mut best_max, mut best_min) = ((f64::NEG_INFINITY, 0.0), (f64::INFINITY, 0.0));
        for i in 0..n_win {
            let b = self.end(i);
            let reseed = (i + 1) % RESEED == 0 || i + 1 == n_win;
            let mut m4 = 0.0;
            for t in slow.iter_mut() {
                m4 += t.6 * t.4;
                if reseed {
                    t.5 = t.0 * (t.1 * b).exp();
                    t.6 = t.5.norm();
                } else {
                    t.5 *= t.2;
                    t.6 *= t.3;
                }
            }
            let mut far = dropped;
            let mut j = 0;
            while j < fast.len() {
                let t = &mut fast[j];
                let top = t.3 * t.2.max(1.0);
                far += top;
                t.3 = if reseed {
                    t.0 * (t.1 * b).exp()
                } else {
                    t.3 * t.2
                };
                if t.2 < 1.0 && top < drop_below {
                    dropped += top;
                    fast.swap_remove(j);
                } else {
                    j += 1;
                }
            }
            let (gs1, ds1) = sums(&slow, b);
            let h = b - i as f64 * w;
            let (hlo, hhi) = hermite_range(gs0, ds0, gs1, ds1, h);
            let rem = m4 * h.powi(4) / 384.0 + far + self.pad;
            lo[i] = hlo - rem;
            hi[i] = hhi + rem;
            // Seeds: the boundaries where the resolved part is largest and smallest (the rest is
            // within `far` of zero there).
            if i + 1 < n_win {
                if gs1 > best_max.0 {
                    best_max = (gs1, b);
                }
                if gs1 < best_min.0 {
                    best_min = (gs1, b);
                }
            }
            (gs0, ds0) = (gs1, ds1);
        }
        (lo, hi, [best_max, best_min])
    }

    /// Step 2: the windows, in time order, whose bound `(lo, hi)` can beat the extremes so
    /// far, cut into cells with their own bounds; each cell that can beat them is searched
    /// for the roots of the slope `dg`.
    fn refine(&self, dg: &Functional<'_>, t0: f64, (lo, hi): (&[f64], &[f64]), ext: &mut Extremes) {
        let (e, w, hc, n_cell, n_win) = (self.e, self.w, self.hc, self.n_cell, self.n_win);
        let (k, mags, pad) = (e.amp.len(), &self.mags, self.pad);
        let value = |s: f64| e.derivative(0, s);
        // No sign change of a zero slope to search for (module docs).
        let slope_is_zero = dg.is_zero();
        let mut z = vec![c64::new(0.0, 0.0); k];
        let mut env = vec![0.0; k];
        let cell_step: Vec<c64> = e.lam.iter().map(|l| (l * hc).exp()).collect();
        let cell_decay: Vec<f64> = e.lam.iter().map(|l| (l.re * hc).exp()).collect();
        let cell_top: Vec<f64> = cell_decay
            .iter()
            .zip(&self.l4)
            .map(|(d, l4)| d.max(1.0) * l4)
            .collect();
        let full = |z: &[c64], s: f64| {
            let (mut g, mut d) = (e.p0 + (e.p1 + e.p2 * s) * s, e.p1 + 2.0 * e.p2 * s);
            for (zk, l) in z.iter().zip(&e.lam) {
                g += zk.re;
                d += (zk * l).re;
            }
            (g, d)
        };
        for i in 0..n_win {
            if !ext.could_improve_range(lo[i], hi[i]) {
                continue;
            }
            let a = i as f64 * w;
            let b = self.end(i);
            for j in 0..k {
                z[j] = e.amp[j] * (e.lam[j] * a).exp();
                env[j] = mags[j] * (e.lam[j].re * a).exp();
            }
            let (mut g0, mut d0) = full(&z, a);
            for c in 0..n_cell {
                let ca = a + c as f64 * hc;
                let cb = if c + 1 == n_cell { b } else { ca + hc };
                let mut m4 = 0.0;
                for j in 0..k {
                    m4 += env[j] * cell_top[j];
                    z[j] *= cell_step[j];
                    env[j] *= cell_decay[j];
                }
                let (g1, d1) = full(&z, cb);
                let (hlo, hhi) = hermite_range(g0, d0, g1, d1, cb - ca);
                let rem = m4 * (cb - ca).powi(4) / 384.0 + pad;
                if ext.could_improve_range(hlo - rem, hhi + rem) {
                    ext.offer(value(ca), t0 + ca);
                    if !slope_is_zero {
                        for_each_extremum(dg, ca, cb, EXTREMUM_SEARCH, |s, _| {
                            ext.offer(value(s), t0 + s)
                        });
                    }
                }
                (g0, d0) = (g1, d1);
            }
        }
    }
}

/// The range `(min, max)` on `[0, h]` of the cubic Hermite interpolant with values `g0`, `g1`
/// and slopes `d0`, `d1` at the ends.
fn hermite_range(g0: f64, d0: f64, g1: f64, d1: f64, h: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (g0.min(g1), g0.max(g1));
    let cubic = HermiteCubic { g0, d0, g1, d1, h };
    let p = |u: f64| cubic.value(u);
    let (c2, c1, c0) = cubic.slope_coefficients();
    let mut take = |u: f64| {
        if u > 0.0 && u < 1.0 {
            let v = p(u);
            lo = lo.min(v);
            hi = hi.max(v);
        }
    };
    if c2 != 0.0 {
        let disc = c1 * c1 - 4.0 * c2 * c0;
        if disc >= 0.0 {
            // Roots without cancellation.
            let q = -0.5 * (c1 + c1.signum() * disc.sqrt());
            if q != 0.0 {
                take(q / c2);
                take(c0 / q);
            } else {
                take(0.0);
            }
        }
    } else if c1 != 0.0 {
        take(-c0 / c1);
    }
    if g0.is_nan() || g1.is_nan() || d0.is_nan() || d1.is_nan() {
        return (f64::NAN, f64::NAN);
    }
    (lo, hi)
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
        on_poly(&a, taylor::ORDER, 2.0, 1.0, 10.0, 1.5, &mut e);
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
        on_poly(&a, taylor::ORDER, 2.0, 1.0, 3.0, 1.0, &mut e);
        assert_eq!((e.max, e.min), (5.0, -5.0));
        e.offer(0.15, 9.0);
        let mut f = Extremes::default();
        f.offer(0.15, 0.0);
        on_poly(&a, taylor::ORDER, 2.0, 1.0, 3.0, 1.0, &mut f);
        assert!((f.max - 0.2).abs() < 1e-15 && f.t_max == 4.0);
    }

    /// The coefficients `a_k = Re Σ_j A_j λ_j^k / k!` of `Re Σ_j A_j e^{λ_j s}` (a channel on
    /// a Taylor step), with the step's validity `τ = 2.2/ρ`, `ρ = max|λ_j|`, and period `2π/ρ`.
    fn exp_sum_poly(modes: &[(f64, f64, f64, f64)]) -> (Coefficients, f64, f64) {
        let mut a = [0.0; taylor::ORDER + 1];
        let mut rho = 0.0f64;
        for &(f, zeta, amp, phase) in modes {
            let w = 2.0 * std::f64::consts::PI * f;
            let lam = c64::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt());
            rho = rho.max(lam.norm());
            let mut term = c64::new(amp * phase.cos(), amp * phase.sin());
            for (k, ak) in a.iter_mut().enumerate() {
                if k > 0 {
                    term = term * lam / k as f64;
                }
                *ak += term.re;
            }
        }
        (a, 2.2 / rho, 2.0 * std::f64::consts::PI / rho)
    }

    /// The unpruned search: both ends and every root of the full-degree slope
    /// ([`for_each_extremum`] on [`Poly`], no bound, no certificate).
    fn unpruned(a: &Coefficients, tau: f64, period: f64, len: f64) -> Extremes {
        let mut e = Extremes::default();
        e.offer(a[0], 0.0);
        e.offer(taylor::eval(a, len), len);
        let mut da = [0.0; taylor::ORDER + 1];
        for (k, d) in da.iter_mut().take(taylor::ORDER).enumerate() {
            *d = (k + 1) as f64 * a[k + 1];
        }
        // With the slope's root of order `j` at a start from rest divided out (`p' = s^j q`).
        if let Some(j) = da.iter().position(|&c| c != 0.0) {
            da.copy_within(j.., 0);
            da[taylor::ORDER + 1 - j..].fill(0.0);
        }
        let slope = Poly::new(&da, tau, period);
        for_each_extremum(&slope, 0.0, len, EXTREMUM_SEARCH, |s, _| {
            e.offer(taylor::eval(a, s), s)
        });
        e
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(400))]

        /// [`on_poly`] (degree lowered by `taylor::degree_for_reach`, the bound, the one-sign
        /// certificates with leading zeros stripped, the monotone Newton) against the
        /// unpruned search of the full-degree polynomial and dense evaluation, on sums of 1-3
        /// damped oscillations over a fraction of the validity from 1e-4 to 1 (the blow's
        /// first stretch is 3e-3 of it); `from_rest` zeroes the slope at 0 (a channel starting
        /// from rest, `a₁ = 0`, and `a₂ = 0` too when `flat`).
        #[test]
        fn lowered_degree_and_certificates_match_unpruned_search(
            modes in proptest::collection::vec(
                (1.0f64..5000.0, 0.0f64..0.3, -1.0f64..1.0, 0.0f64..6.3), 1..4),
            frac_exp in -4.0f64..0.0,
            from_rest in proptest::bool::ANY,
            flat in proptest::bool::ANY,
        ) {
            let (mut a, tau, period) = exp_sum_poly(&modes);
            if from_rest {
                a[1] = 0.0;
                if flat {
                    a[2] = 0.0;
                }
            }
            let len = tau * 10f64.powf(frac_exp);
            let deg = taylor::degree_for_reach(2.2 * len / tau);
            let mut lowered = a;
            lowered[deg + 1..].fill(0.0);
            let mut got = Extremes::default();
            on_poly(&lowered, deg, tau, period, 0.0, len, &mut got);
            let want = unpruned(&a, tau, period, len);
            // Scale: lowering the degree drops a remainder that `degree_for_reach` bounds
            // relative to the state's size (‖X₀‖ ≈ Σ|A_j|), not to the values of a channel
            // whose modal terms cancel (`a₀` ≪ Σ|A_j|).
            let amplitudes: f64 = modes.iter().map(|m| m.2.abs()).sum();
            let scale = taylor::abs_horner(&a, len).max(amplitudes);
            let tol = 1e-14 * scale;
            proptest::prop_assert!((got.max - want.max).abs() <= tol, "max {got:?} {want:?}");
            proptest::prop_assert!((got.min - want.min).abs() <= tol, "min {got:?} {want:?}");
            // The times reported are where the full polynomial takes those values.
            proptest::prop_assert!((taylor::eval(&a, got.t_max) - want.max).abs() <= tol);
            proptest::prop_assert!((taylor::eval(&a, got.t_min) - want.min).abs() <= tol);
            for i in 0..=2000 {
                let s = len * f64::from(i) / 2000.0;
                let v = taylor::eval(&a, s);
                proptest::prop_assert!(
                    v <= got.max + tol && v >= got.min - tol,
                    "{v} at {s}"
                );
            }
        }
    }

    #[test]
    fn degree_for_reach_bounds_the_remainder() {
        // Full reach needs every term; a short stretch few; the bound holds at each.
        assert_eq!(taylor::degree_for_reach(2.2), taylor::ORDER);
        assert_eq!(taylor::degree_for_reach(f64::NAN), taylor::ORDER);
        assert_eq!(taylor::degree_for_reach(0.0), 2);
        let full: f64 = (taylor::ORDER + 1..60)
            .map(|k| (1..=k).fold(1.0, |t, i| t * 2.2 / i as f64))
            .sum();
        for r in [1e-6, 1e-3, 0.0066, 0.1, 0.5, 1.0, 1.28, 2.0, 2.19] {
            let d = taylor::degree_for_reach(r);
            let tail = |d: usize| -> f64 {
                (d + 1..60)
                    .map(|k| (1..=k).fold(1.0, |t, i| t * r / i as f64))
                    .sum()
            };
            assert!(tail(d) <= full, "r = {r}: degree {d}");
            assert!(
                d == 2 || tail(d - 1) > full,
                "r = {r}: degree {d} not the lowest"
            );
        }
        assert!(taylor::degree_for_reach(0.0066) <= 6);
    }

    /// The Hermite cubic's range against dense evaluation.
    #[test]
    fn hermite_range_is_the_cubics_range() {
        for (g0, d0, g1, d1, h) in [
            (0.0, 1.0, 0.0, -1.0, 2.0),
            (1.0, -3.0, 0.5, 2.0, 1.0),
            (0.0, 0.0, 1.0, 0.0, 0.5),
            (2.0, 5.0, -1.0, 5.0, 1.5),
        ] {
            let (lo, hi) = hermite_range(g0, d0, g1, d1, h);
            let (mut dlo, mut dhi) = (f64::INFINITY, f64::NEG_INFINITY);
            for i in 0..=100_000 {
                let u = i as f64 / 100_000.0;
                let v = (2.0 * u.powi(3) - 3.0 * u * u + 1.0) * g0
                    + (u.powi(3) - 2.0 * u * u + u) * h * d0
                    + (-2.0 * u.powi(3) + 3.0 * u * u) * g1
                    + (u.powi(3) - u * u) * h * d1;
                dlo = dlo.min(v);
                dhi = dhi.max(v);
            }
            assert!(lo <= dlo + 1e-14 && lo >= dlo - 1e-8, "{lo} vs {dlo}");
            assert!(hi >= dhi - 1e-14 && hi <= dhi + 1e-8, "{hi} vs {dhi}");
        }
        assert!(hermite_range(f64::NAN, 0.0, 1.0, 0.0, 1.0).0.is_nan());
    }

    /// Uncoupled unit-mass oscillators `(f Hz, ζ)`, started from `x0 = [x; ẋ]`: the segment's
    /// extremes of `ℓᵀX` by [`on_segment`] (windows and cells skipped by their bounds), by one
    /// search over the whole segment without any skipping, and by dense evaluation; then
    /// [`on_segment`] again, given beforehand extremes `1e-9` inside the exhaustive ones (at
    /// t = −1 s), which leaves the bounds almost no room: it must still find the true ones.
    fn segment_extremes(
        modes: &[(f64, f64)],
        x0: &[f64],
        l: &[f64],
        len: f64,
    ) -> (Extremes, Extremes, Extremes, f64) {
        use super::super::propagator::Propagator;
        use faer::Mat;
        let n = modes.len();
        let w: Vec<f64> = modes
            .iter()
            .map(|(f, _)| 2.0 * std::f64::consts::PI * f)
            .collect();
        let k = Mat::from_fn(n, n, |i, j| if i == j { w[i] * w[i] } else { 0.0 });
        let c = Mat::from_fn(
            n,
            n,
            |i, j| {
                if i == j {
                    2.0 * modes[i].1 * w[i]
                } else {
                    0.0
                }
            },
        );
        let a = Mat::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
            (true, false) => f64::from(u8::from(j - n == i)),
            (false, true) => -k[(i - n, j)],
            (false, false) => -c[(i - n, j - n)],
            _ => 0.0,
        });
        let la: Vec<f64> = (0..2 * n)
            .map(|j| (0..2 * n).map(|i| l[i] * a[(i, j)]).sum())
            .collect();
        let p = Propagator::new(&k, &c, &vec![1.0; n], a).unwrap();
        let seg = p.segment(x0);
        let mut pruned = Extremes::default();
        on_segment(&seg, l, &la, 0.0, len, &mut pruned);
        let Functional::Exp(e) = seg.functional(l) else {
            panic!("spectral form expected")
        };
        let df = seg.functional(&la);
        let mut all = Extremes::default();
        all.offer(e.derivative(0, 0.0), 0.0);
        all.offer(e.derivative(0, len), len);
        for_each_extremum(&df, 0.0, len, EXTREMUM_SEARCH, |s, _| {
            all.offer(e.derivative(0, s), s)
        });
        let mut dense = Extremes::default();
        let h = e.fastest_period() / 256.0;
        let steps = (len / h).ceil() as usize;
        for i in 0..=steps {
            let s = (i as f64 * h).min(len);
            dense.offer(e.derivative(0, s), s);
        }
        // Largest curvature, for how far the dense grid may fall short: ½ max|g''| h².
        let gap = 0.5 * e.curvature_bound(0.0, len) * h * h;
        let margin = 1e-9 * all.max.abs().max(all.min.abs());
        let mut tight = Extremes::default();
        tight.offer(all.max - margin, -1.0);
        tight.offer(all.min + margin, -1.0);
        on_segment(&seg, l, &la, 0.0, len, &mut tight);
        assert_eq!((tight.max, tight.min), (pruned.max, pruned.min));
        assert_eq!((tight.t_max, tight.t_min), (pruned.t_max, pruned.t_min));
        (pruned, all, dense, gap)
    }

    fn assert_same(pruned: &Extremes, all: &Extremes, dense: &Extremes, gap: f64, scale: f64) {
        for (p, a, d) in [
            (pruned.max, all.max, dense.max),
            (-pruned.min, -all.min, -dense.min),
        ] {
            assert!(
                (p - a).abs() <= 1e-14 * scale,
                "pruned {p} vs exhaustive {a}"
            );
            assert!(p >= d - 1e-14 * scale, "dense {d} above {p}");
            assert!(p <= d + gap + 1e-14 * scale, "{p} beyond dense {d} + {gap}");
        }
        assert!(
            (pruned.t_max - all.t_max).abs() < 1e-9,
            "{pruned:?} {all:?}"
        );
        assert!(
            (pruned.t_min - all.t_min).abs() < 1e-9,
            "{pruned:?} {all:?}"
        );
    }

    /// A free body (no stiffness, no damping: an impactor in flight) beside two oscillators:
    /// its velocity is constant, the slope functional is exactly zero
    /// ([`Functional::is_zero`]) and the search it is spared finds nothing (the equivalence
    /// the skip rests on); the extremes are the constant, first reached at the start, and the
    /// body's displacement (slope = the constant velocity) still gets its exact ends.
    #[test]
    fn constant_channel_of_a_free_body() {
        use super::super::propagator::Propagator;
        use faer::Mat;
        let (w1, w2) = (
            2.0 * std::f64::consts::PI * 50.0,
            2.0 * std::f64::consts::PI * 2900.0,
        );
        let diag = |v: [f64; 3]| Mat::from_fn(3, 3, |i, j| if i == j { v[i] } else { 0.0 });
        let k = diag([0.0, w1 * w1, w2 * w2]);
        let c = diag([0.0, 0.02 * w1, 0.02 * w2]);
        let a = Mat::from_fn(6, 6, |i, j| match (i < 3, j < 3) {
            (true, false) => f64::from(u8::from(j - 3 == i)),
            (false, true) => -k[(i - 3, j)],
            (false, false) => -c[(i - 3, j - 3)],
            _ => 0.0,
        });
        let p = Propagator::new(&k, &c, &[1.2, 1.0, 1.0], a).unwrap();
        let seg = p.segment(&[0.0, 1e-3, -2e-4, -0.417, 0.3, 2.0]);
        let len = 0.05;
        // Velocity of the free body: ℓ = e₄, ℓᵀA = 0.
        let (l, la) = ([0.0, 0.0, 0.0, 1.0, 0.0, 0.0], [0.0; 6]);
        let df = seg.functional(&la);
        assert!(df.is_zero());
        let mut visits = 0;
        for_each_extremum(&df, 0.0, len, EXTREMUM_SEARCH, |_, _| visits += 1);
        assert_eq!(visits, 0);
        let mut e = Extremes::default();
        on_segment(&seg, &l, &la, 2.0, len, &mut e);
        // (−0.417 to the round-off of the mass-scaled rigid split, √1.2 and back.)
        assert_eq!((e.max, e.t_max, e.t_min), (e.min, 2.0, 2.0), "{e:?}");
        assert!((e.max + 0.417).abs() <= 2.0 * f64::EPSILON, "{e:?}");
        // Its displacement −0.417 s: the slope is not zero, the extremes are the ends.
        let (l, la) = (
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        );
        assert!(!seg.functional(&la).is_zero());
        let mut e = Extremes::default();
        on_segment(&seg, &l, &la, 2.0, len, &mut e);
        assert_eq!((e.max, e.t_max, e.t_min), (0.0, 2.0, 2.0 + len));
        assert!((e.min + 0.417 * len).abs() <= 1e-16, "{e:?}");
        // An oscillator's velocity: its slope is not zero.
        assert!(!seg
            .functional(&[0.0, -w1 * w1, 0.0, 0.0, -0.02 * w1, 0.0])
            .is_zero());
    }

    /// A slow mode peaking late (25 ms) under a fast one that starts almost as large and
    /// decays: the early windows' bounds are close to the late maximum, which must still be
    /// found (and the minimum at 75 ms).
    #[test]
    fn late_slow_peak_under_a_decaying_fast_mode() {
        let modes = [(10.0, 0.005), (3000.0, 0.02), (300.0, 0.01)];
        let ws = 2.0 * std::f64::consts::PI * 10.0;
        // Slow: from rest at 0 with velocity, amplitude 1 mm; fast: 0.97 mm; middle: 0.02 mm.
        let x0 = [0.0, 0.97e-3, 0.02e-3, 1e-3 * ws, 0.0, 0.0];
        let l = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0];
        let (p, a, d, gap) = segment_extremes(&modes, &x0, &l, 0.2);
        assert!((p.t_max - 0.025).abs() < 2e-3, "{p:?}");
        assert!((p.t_min - 0.075).abs() < 2e-3, "{p:?}");
        assert_same(&p, &a, &d, gap, 1e-3);
    }

    /// Random sums of damped oscillations (a fixed pseudo-random sequence): every extreme the
    /// pruned search reports is the exhaustive search's, and no dense sample beats it.
    #[test]
    fn pruned_extremes_match_exhaustive_search() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..24 {
            let n = 2 + (rnd() * 3.0) as usize;
            let modes: Vec<(f64, f64)> = (0..n)
                .map(|_| (10f64.powf(1.0 + 2.7 * rnd()), 0.002 + 0.05 * rnd()))
                .collect();
            let x0: Vec<f64> = (0..2 * n)
                .map(|i| {
                    let v = rnd() - 0.5;
                    if i < n {
                        v
                    } else {
                        v * 2.0 * std::f64::consts::PI * modes[i - n].0
                    }
                })
                .collect();
            let l: Vec<f64> = (0..2 * n)
                .map(|i| (rnd() - 0.5) * if i < n { 1.0 } else { 1e-3 })
                .collect();
            let len = 0.01 + 0.3 * rnd();
            let (p, a, d, gap) = segment_extremes(&modes, &x0, &l, len);
            let scale = a.max.abs().max(a.min.abs());
            assert_same(&p, &a, &d, gap, scale);
        }
    }
}
