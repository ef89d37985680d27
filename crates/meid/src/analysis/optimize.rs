//! Derivative-free minimisers for design studies: Brent's method in one variable and a
//! bounded, restarted Nelder-Mead simplex search with a coordinate polish in several.
//!
//! The objectives here are impact simulations: each evaluation is expensive, there are no
//! gradients, and a design point can fail (a simulation that does not converge). Every
//! minimiser therefore takes an objective returning `f64`, `Option<f64>` or
//! `Result<f64, E>` (see [`ObjectiveValue`]): a failure, or any non-finite value, counts as
//! `+∞`, is tallied in `failures` and is recorded in the history with `f = +∞`.
//! Both minimisers count evaluations and keep the full history `(x, f)` for plots.
//!
//! Why hand-written: the Rust crates that offer these (argmin, optimize) either lack
//! bounds and restarts, do not tolerate failing objectives, or bring a large dependency
//! tree; the algorithms are short and fully specified in the references below.
//!
//! * Brent: R. P. Brent, *Algorithms for Minimization without Derivatives*, Prentice-Hall
//!   1973, ch. 5 (golden-section search safeguarded by successive parabolic interpolation).
//! * Nelder-Mead: J. A. Nelder, R. Mead, Comput. J. 7 (1965) 308-313, with the
//!   dimension-adaptive coefficients of F. Gao, L. Han, Comput. Optim. Appl. 51 (2012)
//!   259-277 (α = 1, β = 1 + 2/n, γ = 0.75 - 1/(2n), δ = 1 - 1/n for n ≥ 3; the classic
//!   1, 2, ½, ½ for n ≤ 2). Bounds are handled by searching in box-normalised coordinates
//!   `u = (x - lower)/(upper - lower) ∈ [0, 1]ⁿ` and projecting every trial point onto the
//!   box. Restarting from the best vertex with a fresh simplex (Kelley, SIAM J. Optim. 10
//!   (1999) 43-55, discusses why restarts cure stagnation such as McKinnon's example) and a
//!   one-dimensional Brent polish along each coordinate make the search robust; extra
//!   starting points drawn uniformly in the box from a seeded SplitMix64 generator give a
//!   deterministic multi-start.
//! * Global search in the box ([`minimize_box_global`]): a deterministic grid of `N` points
//!   per variable (`u_i = i/(N−1)`, i = 0..N−1, in box-normalised coordinates; `Nⁿ`
//!   evaluations, run in parallel and collected in grid order, so the result does not depend
//!   on the thread count), then [`minimize_box`] from each of the best few grid points that
//!   are lower than all their `3ⁿ − 1` grid neighbours (distinct basins), the best result
//!   kept. A local method alone ends in the basin of its start; the grid finds every basin
//!   wider than about two grid cells (A. Törn, A. Žilinskas, *Global Optimization*, LNCS 350,
//!   Springer 1989, ch. 2: "multistart from the best points of a sample").

use rayon::prelude::*;

use crate::rng::SplitMix64;
use crate::{Error, Result};

/// What an objective may return. `None`, `Err(_)` and non-finite numbers are failures,
/// treated as `+∞` and counted.
pub trait ObjectiveValue {
    /// The finite objective value, or `None` for a failed evaluation.
    fn into_value(self) -> Option<f64>;
}

impl ObjectiveValue for f64 {
    fn into_value(self) -> Option<f64> {
        self.is_finite().then_some(self)
    }
}

impl ObjectiveValue for Option<f64> {
    fn into_value(self) -> Option<f64> {
        self.and_then(ObjectiveValue::into_value)
    }
}

impl<E> ObjectiveValue for std::result::Result<f64, E> {
    fn into_value(self) -> Option<f64> {
        self.ok().and_then(ObjectiveValue::into_value)
    }
}

/// Options of [`brent_minimize`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrentOptions {
    /// Absolute tolerance on x (same unit as x). The search stops when the bracket around
    /// the best point is within `2 (relative_tolerance |x| + x_tolerance)`.
    pub x_tolerance: f64,
    /// Relative tolerance on x; below √ε ≈ 1.5e-8 it is meaningless (f is flat to rounding).
    pub relative_tolerance: f64,
    /// Evaluation budget.
    pub max_evaluations: usize,
}

impl Default for BrentOptions {
    fn default() -> Self {
        BrentOptions {
            x_tolerance: 1e-10,
            relative_tolerance: f64::EPSILON.sqrt(),
            max_evaluations: 500,
        }
    }
}

/// Result of a one-variable minimisation.
#[derive(Debug, Clone, PartialEq)]
pub struct Minimum1d {
    /// Best point found.
    pub x: f64,
    /// Objective at `x`.
    pub f: f64,
    /// Objective evaluations made (including failed ones).
    pub evaluations: usize,
    /// Evaluations that failed (counted as `+∞`).
    pub failures: usize,
    /// `true` if the tolerance was met before the evaluation budget ran out.
    pub converged: bool,
    /// Every evaluation in order, `(x, f)`, with `f = +∞` for failures.
    pub history: Vec<(f64, f64)>,
}

/// Minimises `f` on `[a, b]` by Brent's method (Brent 1973, ch. 5, procedure `localmin`):
/// golden-section steps `c = (3 - √5)/2` of the larger sub-interval, replaced by the
/// minimum of the parabola through the three best points whenever that step falls inside
/// the bracket and is less than half the step before last. Finds a local minimum; on a
/// unimodal function, the global one. Failed evaluations (`+∞`) force golden-section steps.
pub fn brent_minimize<F, R>(f: F, a: f64, b: f64, options: &BrentOptions) -> Result<Minimum1d>
where
    F: FnMut(f64) -> R,
    R: ObjectiveValue,
{
    brent_search(f, a, None, b, options)
}

/// [`brent_minimize`] started from an interior point `x ∈ (a, b)` whose value `fx` is already
/// known (a bracket `f(x) ≤ f(a), f(b)` from a scan), which saves the first evaluation.
pub(crate) fn brent_minimize_from<F, R>(
    f: F,
    a: f64,
    start: (f64, f64),
    b: f64,
    options: &BrentOptions,
) -> Result<Minimum1d>
where
    F: FnMut(f64) -> R,
    R: ObjectiveValue,
{
    brent_search(f, a, Some(start), b, options)
}

/// Brent's method on `[a, b]` ([`brent_minimize`]), from `start = (x, f(x))` when given.
fn brent_search<F, R>(
    mut f: F,
    a: f64,
    start: Option<(f64, f64)>,
    b: f64,
    options: &BrentOptions,
) -> Result<Minimum1d>
where
    F: FnMut(f64) -> R,
    R: ObjectiveValue,
{
    check_brent(a, b, options)?;
    let BrentOptions {
        x_tolerance,
        relative_tolerance,
        max_evaluations,
    } = *options;
    let mut history = Vec::new();
    let mut failures = 0usize;
    let mut eval = |x: f64, history: &mut Vec<(f64, f64)>, failures: &mut usize| -> f64 {
        let v = f(x).into_value().unwrap_or_else(|| {
            *failures += 1;
            f64::INFINITY
        });
        history.push((x, v));
        v
    };

    let golden = 0.5 * (3.0 - 5.0_f64.sqrt());
    let (lo, hi) = (a, b);
    let (x, fx) = match start {
        Some((x, fx)) if x > a && x < b => {
            let fx = fx.into_value().unwrap_or(f64::INFINITY);
            history.push((x, fx));
            (x, fx)
        }
        Some((x, _)) => {
            return Err(Error::invalid(
                "start",
                format!("must lie inside ({a}, {b}), got {x}"),
            ))
        }
        None => {
            let x = lo + golden * (hi - lo);
            (x, eval(x, &mut history, &mut failures))
        }
    };
    let mut st = BrentState {
        lo,
        hi,
        x,
        fx,
        w: x,
        fw: fx,
        v: x,
        fv: fx,
        d: 0.0,
        e: 0.0,
    };
    let mut converged = false;
    while history.len() < max_evaluations {
        let m = 0.5 * (st.lo + st.hi);
        let tol = relative_tolerance * st.x.abs() + x_tolerance;
        let tol2 = 2.0 * tol;
        if (st.x - m).abs() <= tol2 - 0.5 * (st.hi - st.lo) {
            converged = true;
            break;
        }
        let u = st.next_point(m, tol, golden);
        let fu = eval(u, &mut history, &mut failures);
        st.update(u, fu);
    }
    let (x, fx) = (st.x, st.fx);
    if !fx.is_finite() {
        return Err(Error::numerical(
            "Brent minimisation",
            format!("all {} evaluations on [{a}, {b}] failed", history.len()),
        ));
    }
    Ok(Minimum1d {
        x,
        f: fx,
        evaluations: history.len(),
        failures,
        converged,
        history,
    })
}

/// The interval and options of [`brent_search`] checked: finite `a < b`, a positive finite
/// `x_tolerance`, a non-negative finite `relative_tolerance`, at least one evaluation.
fn check_brent(a: f64, b: f64, options: &BrentOptions) -> Result<()> {
    if !(a.is_finite() && b.is_finite() && a < b) {
        return Err(Error::invalid(
            "interval",
            format!("needs finite a < b, got [{a}, {b}]"),
        ));
    }
    let BrentOptions {
        x_tolerance,
        relative_tolerance,
        max_evaluations,
    } = *options;
    if !(x_tolerance > 0.0 && x_tolerance.is_finite()) {
        return Err(Error::invalid(
            "x_tolerance",
            format!("must be positive and finite, got {x_tolerance}"),
        ));
    }
    if !(relative_tolerance >= 0.0 && relative_tolerance.is_finite()) {
        return Err(Error::invalid(
            "relative_tolerance",
            format!("must be non-negative and finite, got {relative_tolerance}"),
        ));
    }
    if max_evaluations < 1 {
        return Err(Error::invalid("max_evaluations", "must be at least 1"));
    }
    Ok(())
}

/// Brent's bracket `[lo, hi]` and its three best points: `x` the best so far, `w` the second
/// best, `v` the previous `w` (values `fx`, `fw`, `fv`); `d` the last step, `e` the one before.
struct BrentState {
    lo: f64,
    hi: f64,
    x: f64,
    fx: f64,
    w: f64,
    fw: f64,
    v: f64,
    fv: f64,
    d: f64,
    e: f64,
}

impl BrentState {
    /// The next point `u`, at least `tol` from `x`: `x + p/q`, the minimum of the parabola
    /// through `(v, fv)`, `(w, fw)`, `(x, fx)`, when that step falls inside the bracket and is
    /// less than half the step before last; else the golden-section step `golden · e` into
    /// the larger sub-interval (`m` the bracket's midpoint).
    fn next_point(&mut self, m: f64, tol: f64, golden: f64) -> f64 {
        let Self {
            lo,
            hi,
            x,
            fx,
            w,
            fw,
            v,
            fv,
            ..
        } = *self;
        let tol2 = 2.0 * tol;
        let (mut d, mut e) = (self.d, self.e);
        let mut parabolic = false;
        if e.abs() > tol {
            // Parabola through (v, fv), (w, fw), (x, fx): step d = p / q from x.
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            let e_prev = e;
            // NaN (from infinite values) fails every comparison: golden section is taken.
            if p.abs() < (0.5 * q * e_prev).abs() && p > q * (lo - x) && p < q * (hi - x) {
                e = d;
                d = p / q;
                let u = x + d;
                if u - lo < tol2 || hi - u < tol2 {
                    d = if x < m { tol } else { -tol };
                }
                parabolic = true;
            }
        }
        if !parabolic {
            e = if x < m { hi - x } else { lo - x };
            d = golden * e;
        }
        (self.d, self.e) = (d, e);
        if d.abs() >= tol {
            x + d
        } else if d > 0.0 {
            x + tol
        } else {
            x - tol
        }
    }

    /// The bracket and the best points after the evaluation `f(u) = fu`.
    fn update(&mut self, u: f64, fu: f64) {
        let x = self.x;
        if fu <= self.fx {
            if u < x {
                self.hi = x;
            } else {
                self.lo = x;
            }
            (self.v, self.fv) = (self.w, self.fw);
            (self.w, self.fw) = (self.x, self.fx);
            (self.x, self.fx) = (u, fu);
        } else {
            if u < x {
                self.lo = u;
            } else {
                self.hi = u;
            }
            if fu <= self.fw || self.w == x {
                (self.v, self.fv) = (self.w, self.fw);
                (self.w, self.fw) = (u, fu);
            } else if fu <= self.fv || self.v == x || self.v == self.w {
                (self.v, self.fv) = (u, fu);
            }
        }
    }
}

/// Options of [`minimize_box`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NelderMeadOptions {
    /// Edge of the initial simplex as a fraction of each box width (0 < step ≤ 0.5).
    pub initial_step: f64,
    /// A simplex has converged when every vertex is within `x_tolerance` of the best one in
    /// every coordinate, measured as a fraction of the box width, and (see `f_tolerance`)
    /// its values agree.
    pub x_tolerance: f64,
    /// A simplex has converged when the spread of its values is at most
    /// `f_tolerance · (1 + |f_best|)` (and see `x_tolerance`); a restart cycle that gains
    /// no more than that ends the search from this start.
    pub f_tolerance: f64,
    /// Evaluation budget over all starts, restarts and polishing.
    pub max_evaluations: usize,
    /// Maximum number of fresh simplices built around the best point per start.
    pub max_restarts: usize,
    /// Additional starting points drawn uniformly in the box (multi-start).
    pub random_starts: usize,
    /// Seed of the generator for the random starts and the simplex orientations.
    pub seed: u64,
    /// Finish each restart cycle with a Brent line search along each coordinate.
    pub polish: bool,
}

impl Default for NelderMeadOptions {
    fn default() -> Self {
        NelderMeadOptions {
            initial_step: 0.1,
            x_tolerance: 1e-8,
            f_tolerance: 1e-12,
            max_evaluations: 10_000,
            max_restarts: 20,
            random_starts: 0,
            seed: 0,
            polish: true,
        }
    }
}

/// Result of a several-variable minimisation.
#[derive(Debug, Clone, PartialEq)]
pub struct MinimumNd {
    /// Best point found (inside the box).
    pub x: Vec<f64>,
    /// Objective at `x`.
    pub f: f64,
    /// Objective evaluations made (including failed ones).
    pub evaluations: usize,
    /// Evaluations that failed (counted as `+∞`).
    pub failures: usize,
    /// `true` if the last start ended by meeting the tolerances (not the budget).
    pub converged: bool,
    /// Simplex restarts made in total.
    pub restarts: usize,
    /// Every evaluation in order, `(x, f)`, with `f = +∞` for failures.
    pub history: Vec<(Vec<f64>, f64)>,
}

/// The objective in normalised coordinates, with counting and history.
struct Evaluator<'a, F> {
    f: F,
    lower: &'a [f64],
    width: Vec<f64>,
    max_evaluations: usize,
    failures: usize,
    history: Vec<(Vec<f64>, f64)>,
}

impl<F, R> Evaluator<'_, F>
where
    F: FnMut(&[f64]) -> R,
    R: ObjectiveValue,
{
    fn to_x(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .zip(self.lower)
            .zip(&self.width)
            .map(|((ui, lo), w)| lo + ui.clamp(0.0, 1.0) * w)
            .collect()
    }
    fn exhausted(&self) -> bool {
        self.history.len() >= self.max_evaluations
    }
    fn eval(&mut self, u: &[f64]) -> f64 {
        let x = self.to_x(u);
        let v = (self.f)(&x).into_value().unwrap_or_else(|| {
            self.failures += 1;
            f64::INFINITY
        });
        self.history.push((x, v));
        v
    }
}

fn project(u: &mut [f64]) {
    for ui in u.iter_mut() {
        *ui = ui.clamp(0.0, 1.0);
    }
}

/// One Nelder-Mead run from `start` (normalised) with edge `step`; returns the best vertex
/// and whether the tolerances were met.
fn nelder_mead_run<F, R>(
    ev: &mut Evaluator<'_, F>,
    start: (&[f64], f64),
    step: f64,
    rng: &mut SplitMix64,
    options: &NelderMeadOptions,
) -> (Vec<f64>, f64, bool)
where
    F: FnMut(&[f64]) -> R,
    R: ObjectiveValue,
{
    let n = start.0.len();
    let nf = n as f64;
    let (alpha, beta, gamma, delta) = if n <= 2 {
        (1.0, 2.0, 0.5, 0.5)
    } else {
        (1.0, 1.0 + 2.0 / nf, 0.75 - 0.5 / nf, 1.0 - 1.0 / nf)
    };
    // Initial simplex: the start and one step along each axis, with a random sign (kept
    // inside the box) so that restarts do not rebuild the same simplex.
    let mut simplex: Vec<(Vec<f64>, f64)> = vec![(start.0.to_vec(), start.1)];
    for i in 0..n {
        if ev.exhausted() {
            return (start.0.to_vec(), start.1, false);
        }
        let mut u = start.0.to_vec();
        let sign = if rng.next_u64() & 1 == 0 { 1.0 } else { -1.0 };
        let mut t = u[i] + sign * step;
        if !(0.0..=1.0).contains(&t) {
            t = u[i] - sign * step;
        }
        u[i] = t.clamp(0.0, 1.0);
        let fu = ev.eval(&u);
        simplex.push((u, fu));
    }
    let mut converged = false;
    while !ev.exhausted() {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (f_best, f_worst) = (simplex[0].1, simplex[n].1);
        if !f_best.is_finite() {
            break; // every vertex failed: nothing to follow
        }
        let size = simplex[1..]
            .iter()
            .flat_map(|(u, _)| u.iter().zip(&simplex[0].0).map(|(a, b)| (a - b).abs()))
            .fold(0.0_f64, f64::max);
        let spread = f_worst - f_best;
        if size <= options.x_tolerance && spread <= options.f_tolerance * (1.0 + f_best.abs()) {
            converged = true;
            break;
        }
        let mut centroid = vec![0.0; n];
        for (u, _) in &simplex[..n] {
            for (c, ui) in centroid.iter_mut().zip(u) {
                *c += ui / nf;
            }
        }
        let along = |t: f64| -> Vec<f64> {
            let mut u: Vec<f64> = centroid
                .iter()
                .zip(&simplex[n].0)
                .map(|(c, w)| c + t * (c - w))
                .collect();
            project(&mut u);
            u
        };
        let ur = along(alpha);
        let fr = ev.eval(&ur);
        if fr < f_best {
            let ue = along(alpha * beta);
            let fe = if ev.exhausted() {
                f64::INFINITY
            } else {
                ev.eval(&ue)
            };
            simplex[n] = if fe < fr { (ue, fe) } else { (ur, fr) };
            continue;
        }
        if fr < simplex[n - 1].1 {
            simplex[n] = (ur, fr);
            continue;
        }
        if ev.exhausted() {
            break;
        }
        // Contraction: outside if the reflection improved on the worst, else inside.
        let (uc, fc, accept) = if fr < f_worst {
            let uc = along(alpha * gamma);
            let fc = ev.eval(&uc);
            (uc, fc, fc <= fr)
        } else {
            let uc = along(-gamma);
            let fc = ev.eval(&uc);
            (uc, fc, fc < f_worst)
        };
        if accept {
            simplex[n] = (uc, fc);
            continue;
        }
        // Shrink towards the best vertex.
        let best = simplex[0].0.clone();
        for vertex in simplex.iter_mut().skip(1) {
            if ev.exhausted() {
                break;
            }
            for (ui, bi) in vertex.0.iter_mut().zip(&best) {
                *ui = bi + delta * (*ui - bi);
            }
            vertex.1 = ev.eval(&vertex.0);
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (u, f) = simplex.swap_remove(0);
    (u, f, converged)
}

/// Brent line search along each coordinate within `±radius` (normalised) of `u`.
fn coordinate_polish<F, R>(
    ev: &mut Evaluator<'_, F>,
    u: &mut [f64],
    fu: &mut f64,
    radius: f64,
    options: &NelderMeadOptions,
) where
    F: FnMut(&[f64]) -> R,
    R: ObjectiveValue,
{
    for i in 0..u.len() {
        let budget = ev.max_evaluations.saturating_sub(ev.history.len());
        if budget < 3 {
            return;
        }
        let (lo, hi) = ((u[i] - radius).max(0.0), (u[i] + radius).min(1.0));
        if hi <= lo {
            continue;
        }
        let brent = BrentOptions {
            x_tolerance: (0.1 * options.x_tolerance).max(1e-15),
            relative_tolerance: f64::EPSILON.sqrt(),
            max_evaluations: budget.min(200),
        };
        let base = u.to_vec();
        let line = brent_minimize(
            |t: f64| {
                let mut trial = base.clone();
                trial[i] = t;
                ev.eval(&trial)
            },
            lo,
            hi,
            &brent,
        );
        if let Ok(m) = line {
            if m.f < *fu {
                u[i] = m.x;
                *fu = m.f;
            }
        }
    }
}

/// Every variable's bounds finite with `lower < upper`.
fn check_box(lower: &[f64], upper: &[f64]) -> Result<()> {
    for (i, (&lo, &hi)) in lower.iter().zip(upper).enumerate() {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(Error::invalid(
                "bounds",
                format!("variable {i}: needs finite lower < upper, got [{lo}, {hi}]"),
            ));
        }
    }
    Ok(())
}

/// Minimises `f(x)` over the box `lower ≤ x ≤ upper` from `x0`, by Nelder-Mead simplex
/// searches in box-normalised coordinates with projection onto the box, restarts from the
/// best point, a coordinate-wise Brent polish and optional seeded random extra starts (see
/// the module documentation for the formulation and references). Deterministic for a given
/// seed. Each start cycles "simplex search, polish" until a cycle improves `f` by no more
/// than `f_tolerance · (1 + |f|)` (or does not move `x` at all), or `max_restarts` is
/// reached. Returns the best point over all starts.
pub fn minimize_box<F, R>(
    f: F,
    x0: &[f64],
    lower: &[f64],
    upper: &[f64],
    options: &NelderMeadOptions,
) -> Result<MinimumNd>
where
    F: FnMut(&[f64]) -> R,
    R: ObjectiveValue,
{
    let n = x0.len();
    if n == 0 {
        return Err(Error::invalid("x0", "needs at least one variable"));
    }
    if lower.len() != n || upper.len() != n {
        return Err(Error::invalid(
            "bounds",
            format!(
                "{} variables but {} lower and {} upper bounds",
                n,
                lower.len(),
                upper.len()
            ),
        ));
    }
    check_box(lower, upper)?;
    for i in 0..n {
        let (lo, hi, x) = (lower[i], upper[i], x0[i]);
        if !(x >= lo && x <= hi) {
            return Err(Error::invalid(
                "x0",
                format!("variable {i}: start {x} lies outside [{lo}, {hi}]"),
            ));
        }
    }
    let o = options;
    if !(o.initial_step > 0.0 && o.initial_step <= 0.5) {
        return Err(Error::invalid(
            "initial_step",
            format!("must lie in (0, 0.5], got {}", o.initial_step),
        ));
    }
    if !(o.x_tolerance > 0.0 && o.x_tolerance.is_finite()) {
        return Err(Error::invalid(
            "x_tolerance",
            format!("must be positive and finite, got {}", o.x_tolerance),
        ));
    }
    if !(o.f_tolerance >= 0.0 && o.f_tolerance.is_finite()) {
        return Err(Error::invalid(
            "f_tolerance",
            format!("must be non-negative and finite, got {}", o.f_tolerance),
        ));
    }
    if o.max_evaluations < n + 1 {
        return Err(Error::invalid(
            "max_evaluations",
            format!("must allow at least one simplex ({} evaluations)", n + 1),
        ));
    }
    let width: Vec<f64> = lower.iter().zip(upper).map(|(l, u)| u - l).collect();
    let mut ev = Evaluator {
        f,
        lower,
        width,
        max_evaluations: o.max_evaluations,
        failures: 0,
        history: Vec::new(),
    };
    let mut rng = SplitMix64::new(o.seed);
    let mut starts: Vec<Vec<f64>> = vec![x0
        .iter()
        .zip(lower)
        .zip(&ev.width)
        .map(|((x, lo), w)| (x - lo) / w)
        .collect()];
    for _ in 0..o.random_starts {
        starts.push((0..n).map(|_| rng.next_f64()).collect());
    }

    let mut best: Option<(Vec<f64>, f64)> = None;
    let mut converged = false;
    let mut restarts = 0usize;
    for start in starts {
        if ev.exhausted() {
            break;
        }
        let mut u = start;
        let mut fu = ev.eval(&u);
        let mut start_converged = false;
        for cycle in 0..=o.max_restarts {
            if ev.exhausted() {
                break;
            }
            if cycle > 0 {
                restarts += 1;
            }
            let (u_prev, f_prev) = (u.clone(), fu);
            let (u_nm, f_nm, _) = nelder_mead_run(&mut ev, (&u, fu), o.initial_step, &mut rng, o);
            if f_nm <= fu {
                (u, fu) = (u_nm, f_nm);
            }
            if o.polish && fu.is_finite() {
                let radius = (100.0 * o.x_tolerance).max(1e-6).min(o.initial_step);
                coordinate_polish(&mut ev, &mut u, &mut fu, radius, o);
            }
            let moved = u
                .iter()
                .zip(&u_prev)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0_f64, f64::max);
            let gained = f_prev - fu;
            if fu.is_finite() && (gained <= o.f_tolerance * (1.0 + fu.abs()) || moved == 0.0) {
                start_converged = true;
                break;
            }
            if !fu.is_finite() {
                break; // nothing but failures around this start
            }
        }
        if best.as_ref().is_none_or(|b| fu < b.1) {
            best = Some((u, fu));
            converged = start_converged;
        }
    }
    match best {
        Some((u, f)) if f.is_finite() => Ok(MinimumNd {
            x: ev.to_x(&u),
            f,
            evaluations: ev.history.len(),
            failures: ev.failures,
            converged,
            restarts,
            history: ev.history,
        }),
        _ => Err(Error::numerical(
            "bounded Nelder-Mead",
            format!(
                "all {} evaluations failed; no feasible point found",
                ev.history.len()
            ),
        )),
    }
}

/// Options of [`minimize_box_global`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlobalOptions {
    /// Grid points per variable, `N ≥ 2` (the grid has `Nⁿ` points, both bounds included).
    pub grid_points: usize,
    /// Local searches: started from the best this many grid points that are lower than all
    /// their grid neighbours (fewer if the grid has fewer such points).
    pub starts: usize,
    /// Evaluation budget over the grid and all local searches; the budget left after the
    /// grid is shared equally by the starts (so each search, and the result, is the same
    /// whatever the thread count).
    pub max_evaluations: usize,
    /// The local search ([`minimize_box`]); its `max_evaluations` is replaced by each
    /// start's share, and its `initial_step` by `max(one grid cell, 1/(N−1))` capped at 0.5.
    pub local: NelderMeadOptions,
}

/// One local search of [`minimize_box_global`].
#[derive(Debug, Clone, PartialEq)]
pub struct LocalSearch {
    /// The grid point it started from, and its value.
    pub start: Vec<f64>,
    pub f_start: f64,
    /// Where it ended, and its value.
    pub x: Vec<f64>,
    pub f: f64,
    /// Its evaluations.
    pub evaluations: usize,
    pub converged: bool,
}

/// Result of [`minimize_box_global`].
#[derive(Debug, Clone, PartialEq)]
pub struct GlobalMinimum {
    /// Best point over the grid and every local search.
    pub x: Vec<f64>,
    /// Objective at `x`.
    pub f: f64,
    /// Evaluations in all: the grid's plus every local search's.
    pub evaluations: usize,
    /// Evaluations of the grid, `Nⁿ`.
    pub grid_evaluations: usize,
    /// Grid points per variable.
    pub grid_points: usize,
    /// Failed evaluations (grid and local searches).
    pub failures: usize,
    /// `true` if the local search that gave `x` met its tolerances.
    pub converged: bool,
    /// The local searches, best start first.
    pub searches: Vec<LocalSearch>,
}

/// `Nⁿ`, or `None` on overflow.
pub fn grid_size(grid_points: usize, n: usize) -> Option<usize> {
    let n = u32::try_from(n).ok()?;
    grid_points.checked_pow(n)
}

/// The grid indices of point `idx` (first variable slowest).
fn grid_indices(mut idx: usize, n: usize, points: usize) -> Vec<usize> {
    let mut out = vec![0; n];
    for k in (0..n).rev() {
        out[k] = idx % points;
        idx /= points;
    }
    out
}

/// Minimises `f(x)` over the box `lower ≤ x ≤ upper` globally within the resolution of a
/// grid: evaluates the `Nⁿ` grid points `x = lower + (i/(N−1))·(upper − lower)` (in parallel,
/// on the current rayon pool), takes the grid points lower than all their `3ⁿ − 1` grid
/// neighbours (ties broken by grid order), the best `starts` of them, runs [`minimize_box`]
/// from each (in parallel, each with an equal share of the budget left) and returns the
/// lowest point found. Deterministic: the same for any thread count. `f` must be
/// `Fn + Sync` (it is called from several threads).
pub fn minimize_box_global<F, R>(
    f: F,
    lower: &[f64],
    upper: &[f64],
    options: &GlobalOptions,
) -> Result<GlobalMinimum>
where
    F: Fn(&[f64]) -> R + Sync,
    R: ObjectiveValue,
{
    let n = lower.len();
    let total = check_global(lower, upper, options)?;
    let points = options.grid_points;
    let to_x = |idx: usize| grid_x(idx, lower, upper, points);
    let values: Vec<f64> = (0..total)
        .into_par_iter()
        .map(|idx| f(&to_x(idx)).into_value().unwrap_or(f64::INFINITY))
        .collect();
    let grid_failures = values.iter().filter(|v| !v.is_finite()).count();
    let mut minima = grid_minima(&values, n, points);
    if minima.is_empty() {
        return Err(Error::numerical(
            "global box search",
            format!("all {total} grid evaluations failed; no feasible point found"),
        ));
    }
    minima.sort_by(|&a, &b| values[a].total_cmp(&values[b]).then(a.cmp(&b)));
    minima.truncate(options.starts);
    let share = (options.max_evaluations - total) / minima.len();
    let step = (1.0 / (points - 1) as f64).min(0.5);
    let local = NelderMeadOptions {
        initial_step: step,
        max_evaluations: share,
        ..options.local
    };
    let runs: Vec<(usize, Option<MinimumNd>)> = minima
        .par_iter()
        .map(|&idx| {
            let x0 = to_x(idx);
            if share < n + 1 {
                return (idx, None);
            }
            (
                idx,
                minimize_box(|x: &[f64]| f(x), &x0, lower, upper, &local).ok(),
            )
        })
        .collect();
    let mut best: (Vec<f64>, f64, bool) = (to_x(minima[0]), values[minima[0]], false);
    let mut evaluations = total;
    let mut failures = grid_failures;
    let mut searches = Vec::new();
    for (idx, run) in runs {
        let start = to_x(idx);
        let Some(m) = run else { continue };
        evaluations += m.evaluations;
        failures += m.failures;
        if m.f < best.1 {
            best = (m.x.clone(), m.f, m.converged);
        }
        searches.push(LocalSearch {
            start,
            f_start: values[idx],
            x: m.x,
            f: m.f,
            evaluations: m.evaluations,
            converged: m.converged,
        });
    }
    Ok(GlobalMinimum {
        x: best.0,
        f: best.1,
        evaluations,
        grid_evaluations: total,
        grid_points: points,
        failures,
        converged: best.2,
        searches,
    })
}

/// The number of grid points of [`minimize_box_global`], the box and options checked: as
/// many lower as upper bounds (at least one), each below its upper one, at least 2 grid points
/// per variable and one local search, and a budget that holds the grid and one simplex.
fn check_global(lower: &[f64], upper: &[f64], options: &GlobalOptions) -> Result<usize> {
    let n = lower.len();
    if n == 0 || upper.len() != n {
        return Err(Error::invalid(
            "bounds",
            format!(
                "needs as many lower as upper bounds, at least one; got {} and {}",
                n,
                upper.len()
            ),
        ));
    }
    check_box(lower, upper)?;
    let points = options.grid_points;
    if points < 2 {
        return Err(Error::invalid(
            "grid_points",
            format!("needs at least 2 points per variable (both bounds), got {points}"),
        ));
    }
    if options.starts < 1 {
        return Err(Error::invalid("starts", "needs at least one local search"));
    }
    grid_size(points, n)
        .filter(|&t| t.checked_add(n + 1).is_some_and(|m| m <= options.max_evaluations))
        .ok_or_else(|| {
            Error::invalid(
                "max_evaluations",
                format!(
                    "{} evaluations cannot hold a grid of {points}^{n} points and one simplex ({} more)",
                    options.max_evaluations,
                    n + 1
                ),
            )
        })
}

/// The point of grid index `idx` (last variable fastest) of `points` per variable, both
/// bounds included (the last exactly the upper bound).
fn grid_x(idx: usize, lower: &[f64], upper: &[f64], points: usize) -> Vec<f64> {
    grid_indices(idx, lower.len(), points)
        .iter()
        .zip(lower)
        .zip(upper)
        .map(|((&i, &lo), &hi)| {
            if i + 1 == points {
                hi
            } else {
                lo + (hi - lo) * (i as f64 / (points - 1) as f64)
            }
        })
        .collect()
}

/// The grid points lower than every grid neighbour (`values` by grid index, `(value, index)`
/// ordered; failed points, `∞`, left out), in index order.
fn grid_minima(values: &[f64], n: usize, points: usize) -> Vec<usize> {
    let total = values.len();
    let below = |a: usize, b: usize| (values[a], a) < (values[b], b);
    let stencil = grid_size(3, n).unwrap_or(0);
    (0..total)
        .filter(|&idx| values[idx].is_finite())
        .filter(|&idx| {
            let ind = grid_indices(idx, n, points);
            (0..stencil).all(|s| {
                let mut nb = 0usize;
                let mut code = s;
                for &i in &ind {
                    let d = code % 3;
                    code /= 3;
                    let j = i + d;
                    if j == 0 || j > points {
                        return true; // outside the grid
                    }
                    nb = nb * points + (j - 1);
                }
                nb == idx || below(idx, nb)
            })
        })
        .collect()
}
