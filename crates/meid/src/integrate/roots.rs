//! Locating sign changes of scalar functions of time: switching events and force extrema.
//!
//! A switch happens where an indicator `g(s)` (an overlap, a contact force, a relative
//! velocity) changes sign. Between two samples `g` may cross zero and come back (grazing);
//! sampling alone misses that. The search therefore steps over `(0, s_max]` with intervals
//! `[a, b]` that are either
//!
//! 1. **proved root-free**: with `G = ±g`, `D = ±g'` and a bound `M₂ ≥ |g''|` on `[a, b]`,
//!    `g` stays above `max(G_a + D_a t − M₂t²/2, G_b − D_b τ − M₂τ²/2)` (`t = s − a`, `τ = b − s`);
//!    if the two positive stretches of these parabolas cover `[a, b]` no root can hide there.
//!    For the exact propagator `g` is a sum of exponentials and `M₂ = Σ|A_k||λ_k|² e^{Re λ_k s}`
//!    is rigorous;
//! 2. or short (`≤ h_grid`, an eighth of the fastest period present in `g`) with a cubic Hermite
//!    interpolant of `g, g'` that keeps its sign; otherwise the interval is halved, down to
//!    `h_grid/2¹⁰`, below which a touch without a sign change is a tangency, not a contact.
//!
//! A sign change found this way is refined by safeguarded Newton-bisection on the exact `g`
//! to [`SearchOptions::tolerance`] of the fastest period (`1e-13` by default; a few ulps of `s`
//! at least).

/// A scalar function of time with its slope and a bound on its second derivative.
pub trait Scalar {
    /// `(g(s), g'(s))`.
    fn value_slope(&self, s: f64) -> (f64, f64);
    /// An upper bound of `|g''|` on `[a, b]`; `f64::INFINITY` when none is known.
    fn curvature_bound(&self, a: f64, b: f64) -> f64;
    /// The shortest period (s) present in the function, or `f64::INFINITY`.
    fn fastest_period(&self) -> f64;
    /// Size of the round-off in computed values of `g` (the same units as `g`): values within
    /// it of zero are not taken as a sign change. Without it a function that starts at zero
    /// and moves off it slowly (a dashpot's relative velocity at rest) "crosses" on its own
    /// round-off at `s ≈ 1e-17` again and again.
    fn noise(&self) -> f64 {
        0.0
    }
}

impl<T: Scalar + ?Sized> Scalar for &T {
    #[inline]
    fn value_slope(&self, s: f64) -> (f64, f64) {
        (**self).value_slope(s)
    }
    #[inline]
    fn curvature_bound(&self, a: f64, b: f64) -> f64 {
        (**self).curvature_bound(a, b)
    }
    #[inline]
    fn fastest_period(&self) -> f64 {
        (**self).fastest_period()
    }
    #[inline]
    fn noise(&self) -> f64 {
        (**self).noise()
    }
}

/// Settings of the crossing search.
#[derive(Debug, Clone, Copy)]
pub struct SearchOptions {
    /// Intervals between samples never exceed this (s); `INFINITY` for no limit.
    pub max_step: f64,
    /// Tolerance of the refined root, relative to the fastest period (default `1e-13`).
    pub tolerance: f64,
}

impl Default for SearchOptions {
    fn default() -> Self {
        Self {
            max_step: f64::INFINITY,
            tolerance: 1e-13,
        }
    }
}

/// Finds the first `s ∈ (0, s_max]` where `sign0·g` becomes negative, given that it is
/// non-negative just after `s = 0`. Returns the first point past the crossing (so that
/// `sign0·g(s) < 0` or `s` is within the tolerance of the root).
pub fn first_crossing<F: Scalar + ?Sized>(
    f: &F,
    s_max: f64,
    sign0: f64,
    opts: SearchOptions,
) -> Option<f64> {
    if s_max.is_nan() || s_max <= 0.0 {
        return None;
    }
    let mut search = Search::new(f, sign0, opts);
    search.advance(s_max).map(|(a, b)| search.refine(a, b))
}

/// A crossing search that can be resumed: [`Search::advance`] proves "no crossing" up to a
/// limit and can later go on from there. Several indicators searched in growing common windows
/// stop as soon as the earliest crossing is known, instead of each running to the end of the
/// run. The search owns its function (a reference works too: `&F` is a [`Scalar`]).
pub struct Search<F> {
    f: F,
    sign0: f64,
    /// `sign0 · noise`, added to `g` so that round-off around zero is not a sign change.
    lift: f64,
    period: f64,
    h_grid: f64,
    max_step: f64,
    tolerance: f64,
    /// Proved free of crossings up to `a`, where `G = sign0 (g + lift)` and `G'` are `ga`, `da`.
    a: f64,
    ga: f64,
    da: f64,
    h: f64,
    found: Option<(f64, f64)>,
    /// `G` at the ends of `found`.
    found_values: (f64, f64),
}

impl<F: Scalar> Search<F> {
    /// Starts a search for the first `s > 0` where `sign0·g` becomes negative.
    pub fn new(f: F, sign0: f64, opts: SearchOptions) -> Self {
        let period = f.fastest_period();
        let h_grid = (period / 8.0).min(opts.max_step);
        let lift = sign0 * f.noise();
        let (g0, d0) = f.value_slope(0.0);
        // A start value of the wrong sign within round-off counts as zero.
        let ga = (sign0 * (g0 + lift)).max(0.0);
        // Starting at zero (within round-off), the caller's sign says where `g` is heading
        // (from its derivatives); a slope of the wrong sign is then round-off too.
        let mut da = sign0 * d0;
        if ga <= 2.0 * lift.abs() {
            da = da.max(0.0);
        }
        Self {
            f,
            sign0,
            lift,
            period,
            h_grid,
            max_step: opts.max_step,
            tolerance: opts.tolerance,
            a: 0.0,
            ga,
            da,
            h: h_grid,
            found: None,
            found_values: (0.0, 0.0),
        }
    }

    /// The bracket found by [`Search::advance`], if any.
    pub fn found(&self) -> Option<(f64, f64)> {
        self.found
    }

    /// `sign0 · (g + lift)` and its slope.
    fn eval(&self, s: f64) -> (f64, f64) {
        let (g, d) = self.f.value_slope(s);
        (self.sign0 * (g + self.lift), self.sign0 * d)
    }

    /// Searches `(a, limit]` where `a` is how far earlier calls got; returns a bracket
    /// `[a, b]` of the first crossing if there is one up to `limit` (and keeps returning it);
    /// [`Search::refine`] locates the root in it.
    pub fn advance(&mut self, limit: f64) -> Option<(f64, f64)> {
        if self.found.is_some() {
            return self.found;
        }
        let h_grid = self.h_grid.min(limit);
        let h_min = (h_grid / 1024.0).max(limit * 1e-15);
        if !self.h.is_finite() {
            self.h = h_grid;
        }
        while self.a < limit {
            let a = self.a;
            let h = self.h;
            let b = if limit - a <= h * 1.000001 {
                limit
            } else {
                a + h
            };
            let (gb, db) = self.eval(b);
            let len = b - a;
            if gb < 0.0 {
                if len > h_grid * 1.000001 {
                    // A long interval may hold several crossings: narrow it to the grid step
                    // before taking it as the bracket of the first.
                    self.h = len / 2.0;
                    continue;
                }
                self.found = Some((a, b));
                self.found_values = (self.ga, gb);
                return self.found;
            }
            let bound = self.f.curvature_bound(a, b);
            if proved_positive(self.ga, self.da, gb, db, bound, len) {
                self.a = b;
                self.ga = gb;
                self.da = db;
                self.h = (2.0 * h).min(self.max_step);
                continue;
            }
            if len <= h_grid * 1.000001 {
                if hermite_dip(self.ga, self.da, gb, db, len).is_some() && len > h_min {
                    // The cubic dips below zero: look closer, left part first.
                    self.h = len / 2.0;
                    continue;
                }
                self.a = b;
                self.ga = gb;
                self.da = db;
                self.h = h_grid;
                continue;
            }
            self.h = len / 2.0;
        }
        None
    }

    /// Safeguarded Newton on a bracket `[a, b]` from [`Search::advance`], `G(a) ≥ 0 > G(b)`:
    /// starts from the secant point, falls back to bisection when a Newton step leaves the
    /// bracket or the bracket stops shrinking, and, once the steps are small, probes one
    /// tolerance past the Newton point so that the bracket closes from both sides. Returns a
    /// point `≥` the root within the tolerance (`1e-13` of the fastest period by default; or a
    /// few ulps of `b`).
    pub fn refine(&self, mut a: f64, mut b: f64) -> f64 {
        let tol_abs = if self.period.is_finite() {
            self.tolerance * self.period
        } else {
            0.0
        };
        let (ga, gb) = if self.found == Some((a, b)) {
            self.found_values
        } else {
            (self.eval(a).0, self.eval(b).0)
        };
        let ga = ga.max(0.0);
        let mut x = if ga - gb > 0.0 {
            (a + (b - a) * ga / (ga - gb)).clamp(a, b)
        } else {
            0.5 * (a + b)
        };
        // rtsafe-style safeguard: Newton only while its steps at least halve. Once a Newton
        // step is below the tolerance, the next point is put half a tolerance past the Newton
        // root, on the other side of the current point, so that the bracket closes.
        let mut dx_old = b - a;
        for _ in 0..200 {
            let tol = tol_abs.max(4.0 * f64::EPSILON * b.abs());
            if b - a <= tol {
                break;
            }
            let (g, d) = self.eval(x);
            if g < 0.0 {
                b = x;
            } else {
                a = x;
            }
            let width = b - a;
            if width <= tol {
                break;
            }
            let newton = if d != 0.0 { x - g / d } else { f64::NAN };
            let dx = (newton - x).abs();
            if newton >= a && newton <= b && 2.0 * dx <= dx_old {
                dx_old = dx;
                x = if dx < 0.5 * tol {
                    if g < 0.0 {
                        newton - 0.5 * tol
                    } else {
                        newton + 0.5 * tol
                    }
                } else {
                    newton
                };
                if x <= a || x >= b {
                    x = if g < 0.0 {
                        a + 0.5 * (b - a).min(tol)
                    } else {
                        b - 0.5 * (b - a).min(tol)
                    };
                }
            } else {
                dx_old = 0.5 * width;
                x = 0.5 * (a + b);
            }
        }
        b
    }
}

/// The maxima of `g` inside `(0, s_max]`, as the sign changes of `slope` (= g') from + to −,
/// located to the search tolerance; sign changes from − to + (minima) are only bracketed and
/// stepped over, not refined.
pub fn maxima<F: Scalar + ?Sized>(slope: &F, s_max: f64, opts: SearchOptions) -> Vec<f64> {
    let mut out = Vec::new();
    for_each_maximum(slope, s_max, opts, |t| out.push(t));
    out
}

/// [`maxima`] without collecting them: `visit(t)` for each maximum, in order.
pub fn for_each_maximum<F: Scalar + ?Sized>(
    slope: &F,
    s_max: f64,
    opts: SearchOptions,
    mut visit: impl FnMut(f64),
) {
    crossings(slope, s_max, opts, false, |t, sign| {
        if sign > 0.0 {
            visit(t);
        }
    });
}

/// The extrema of `g` inside `(a, b]` as the sign changes of `slope` (= g'), each located to
/// the search tolerance: `visit(t, is_max)` in order (`is_max` for a change from + to −).
pub fn for_each_extremum<F: Scalar + ?Sized>(
    slope: &F,
    a: f64,
    b: f64,
    opts: SearchOptions,
    mut visit: impl FnMut(f64, bool),
) {
    let shifted = Shifted {
        f: slope,
        offset: a,
    };
    crossings(&shifted, b - a, opts, true, |t, sign| {
        visit(a + t, sign > 0.0)
    });
}

/// All sign changes of `g` in `(0, s_max]`, in order, each with the sign `g` had before it.
pub fn all_crossings<F: Scalar + ?Sized>(
    f: &F,
    s_max: f64,
    opts: SearchOptions,
) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    crossings(f, s_max, opts, true, |t, sign| out.push((t, sign)));
    out
}

/// Sign changes of `g` in order, `visit(t, sign before)` for each; those from − to + are
/// refined only when `refine_rising` (otherwise the end of their bracket is reported).
fn crossings<F: Scalar + ?Sized>(
    f: &F,
    s_max: f64,
    opts: SearchOptions,
    refine_rising: bool,
    mut visit: impl FnMut(f64, f64),
) {
    let mut start = 0.0;
    let mut count = 0usize;
    let (g0, d0) = f.value_slope(0.0);
    let mut sign = if g0.abs() > f.noise() {
        g0.signum()
    } else if d0 != 0.0 {
        d0.signum()
    } else {
        1.0
    };
    while start < s_max {
        let shifted = Shifted { f, offset: start };
        let mut search = Search::new(&shifted, sign, opts);
        match search.advance(s_max - start) {
            Some((a, b)) => {
                let t = start
                    + if sign > 0.0 || refine_rising {
                        search.refine(a, b)
                    } else {
                        b
                    };
                visit(t, sign);
                count += 1;
                if t <= start || count > 1_000_000 {
                    break;
                }
                start = t;
                sign = -sign;
            }
            None => break,
        }
    }
}

struct Shifted<'a, F: ?Sized> {
    f: &'a F,
    offset: f64,
}

impl<F: Scalar + ?Sized> Scalar for Shifted<'_, F> {
    fn value_slope(&self, s: f64) -> (f64, f64) {
        self.f.value_slope(self.offset + s)
    }
    fn curvature_bound(&self, a: f64, b: f64) -> f64 {
        self.f.curvature_bound(self.offset + a, self.offset + b)
    }
    fn fastest_period(&self) -> f64 {
        self.f.fastest_period()
    }
    fn noise(&self) -> f64 {
        self.f.noise()
    }
}

/// Is `g > 0` on `[0, len]` provable from values, slopes and `|g''| ≤ m2`?
fn proved_positive(ga: f64, da: f64, gb: f64, db: f64, m2: f64, len: f64) -> bool {
    if !m2.is_finite() || gb <= 0.0 || ga < 0.0 {
        return false;
    }
    // Positive stretch of G + D t − m2 t²/2 starting at t = 0.
    let reach = |g: f64, d: f64| -> f64 {
        if m2 <= 0.0 {
            if d >= 0.0 {
                f64::INFINITY
            } else {
                g / -d
            }
        } else {
            (d + (d * d + 2.0 * m2 * g).sqrt()) / m2
        }
    };
    let from_a = if ga > 0.0 || da > 0.0 {
        reach(ga, da)
    } else {
        0.0
    };
    let from_b = reach(gb, -db);
    from_a + from_b > len
}

/// The cubic Hermite interpolant on `[0, h]` with values `g0`, `g1` and slopes `d0`, `d1` at
/// the ends, in `u = s/h ∈ [0, 1]`:
///
/// `p(u) = (2u³ − 3u² + 1) g0 + (u³ − 2u² + u) h d0 + (−2u³ + 3u²) g1 + (u³ − u²) h d1`,
/// `p'(u) = c2 u² + c1 u + c0` ([`HermiteCubic::slope_coefficients`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct HermiteCubic {
    pub g0: f64,
    pub d0: f64,
    pub g1: f64,
    pub d1: f64,
    pub h: f64,
}

impl HermiteCubic {
    /// `p(u)`.
    pub(crate) fn value(&self, u: f64) -> f64 {
        let HermiteCubic { g0, d0, g1, d1, h } = *self;
        let u2 = u * u;
        let u3 = u2 * u;
        (2.0 * u3 - 3.0 * u2 + 1.0) * g0
            + (u3 - 2.0 * u2 + u) * h * d0
            + (-2.0 * u3 + 3.0 * u2) * g1
            + (u3 - u2) * h * d1
    }

    /// `(c2, c1, c0)` of `p'(u) = c2 u² + c1 u + c0`.
    pub(crate) fn slope_coefficients(&self) -> (f64, f64, f64) {
        let HermiteCubic { g0, d0, g1, d1, h } = *self;
        (
            3.0 * (2.0 * g0 + h * d0 - 2.0 * g1 + h * d1),
            2.0 * (-3.0 * g0 - 2.0 * h * d0 + 3.0 * g1 - h * d1),
            h * d0,
        )
    }
}

/// If the cubic Hermite interpolant through (0, ga, da), (len, gb, db) dips to ≤ 0 inside,
/// returns where (relative to the interval start).
pub(crate) fn hermite_dip(ga: f64, da: f64, gb: f64, db: f64, len: f64) -> Option<f64> {
    let cubic = HermiteCubic {
        g0: ga,
        d0: da,
        g1: gb,
        d1: db,
        h: len,
    };
    let p = |u: f64| cubic.value(u);
    // p'(u) = 0 is a quadratic: find its roots in (0,1).
    let (c2, c1, c0) = cubic.slope_coefficients();
    let mut cands = [0.5_f64, f64::NAN, f64::NAN];
    if c2.abs() > 1e-300 {
        let disc = c1 * c1 - 4.0 * c2 * c0;
        if disc >= 0.0 {
            let r = disc.sqrt();
            cands[1] = (-c1 + r) / (2.0 * c2);
            cands[2] = (-c1 - r) / (2.0 * c2);
        }
    } else if c1.abs() > 1e-300 {
        cands[1] = -c0 / c1;
    }
    for u in cands {
        if u > 0.0 && u < 1.0 && p(u) <= 0.0 {
            return Some(u * len);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// g(s) = cos(w s) - c: known roots.
    struct Cos {
        w: f64,
        c: f64,
    }
    impl Scalar for Cos {
        fn value_slope(&self, s: f64) -> (f64, f64) {
            ((self.w * s).cos() - self.c, -self.w * (self.w * s).sin())
        }
        fn curvature_bound(&self, _a: f64, _b: f64) -> f64 {
            self.w * self.w
        }
        fn fastest_period(&self) -> f64 {
            2.0 * std::f64::consts::PI / self.w
        }
    }

    #[test]
    fn finds_first_root_to_tolerance() {
        let f = Cos { w: 1000.0, c: 0.3 };
        let s = first_crossing(&f, 1.0, 1.0, SearchOptions::default()).unwrap();
        let exact = 0.3_f64.acos() / 1000.0;
        assert!((s - exact).abs() < 1e-15, "{s} vs {exact}");
    }

    /// A grazing dip: cos reaches -c+1 = 1e-6 below zero only for a tiny time
    /// (c = 1 - 1e-6 crossing both ways near the minimum of cos at π/w is not it; use c just
    /// above -1 so that cos(ws) - c dips below zero around s = π/w).
    #[test]
    fn catches_shallow_crossing_and_recrossing() {
        let w = 1000.0;
        let f = Cos { w, c: -1.0 + 1e-7 };
        // Roots at π/w ± sqrt(2e-7)/w, a window of about 0.9 µs inside a 6.3 ms period.
        let s = first_crossing(&f, 0.01, 1.0, SearchOptions::default()).unwrap();
        let exact = (std::f64::consts::PI - (2.0e-7_f64).sqrt()) / w;
        assert!((s - exact).abs() < 1e-12, "{s} vs {exact}");
    }

    #[test]
    fn no_root_when_positive() {
        let f = Cos { w: 50.0, c: -1.5 };
        assert!(first_crossing(&f, 10.0, 1.0, SearchOptions::default()).is_none());
    }

    #[test]
    fn all_crossings_of_cosine() {
        let w = 100.0;
        let f = Cos { w, c: 0.0 };
        let roots = all_crossings(&f, 1.0, SearchOptions::default());
        let expected = ((1.0 * w / std::f64::consts::PI) - 0.5).floor() as usize + 1;
        assert_eq!(roots.len(), expected);
        for (k, (s, _)) in roots.iter().enumerate() {
            let exact = (k as f64 + 0.5) * std::f64::consts::PI / w;
            assert!((s - exact).abs() < 1e-13, "{k}: {s} vs {exact}");
        }
    }
}
