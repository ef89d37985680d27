//! Exact event-driven propagation of the piecewise-linear impact system.
//!
//! A stretch in one mode is propagated in one of two forms, both exact to round-off:
//!
//! * **Taylor steps** ([`super::taylor`]): `X(s) = Σ_{k≤24} A^k X₀ s^k / k!` over a third of
//!   the fastest period, where the truncation is below 2.4e-18. No eigen-decomposition is needed;
//!   a run takes them in a mode until it has spent [`Options::taylor_steps_per_mode`] there
//!   (default [`TAYLOR_STEPS_PER_MODE`]). A blow of the paper's machine is over in 5 such
//!   steps (0.68 ms), so it never builds a closed form;
//! * **closed form** ([`Propagator`], spectral with a matrix-exponential fallback): built the
//!   first time a run needs it (and kept for the run, and in a small per-thread cache,
//!   [`Propagator::shared`], for the next run of the same matrices); it pays off over long
//!   stretches (free vibration after the blow).
//!
//! The choice depends only on the run's own history, never on the cache, so results do not
//! depend on the thread count. Each stretch:
//!
//! 1. the side of every indicator at the stretch start (`switching::lex_signs`, from the
//!    mode selection that chose the mode);
//! 2. the first sign change of any indicator ([`super::roots`]): all indicators are searched
//!    over common windows growing from one fastest period, so the search ends at the earliest
//!    crossing; capped by the end of the run (and by a Taylor step's validity, after which
//!    the same mode goes on with a new step);
//! 3. output samples inside the stretch: from the polynomial on a Taylor step; in closed form
//!    the first evaluated directly, the next ones by the real transition matrix
//!    `E = exp(A Δt)` (one mat-vec per sample), re-seeded every 64 samples;
//! 4. exact contact-force maxima (roots of the force's derivative), closed-contact times, and
//!    the dissipated energy `∫ ẋᵀ C_σ ẋ dt` (closed form, or Gauss-Legendre below round-off
//!    on a Taylor step);
//! 5. the new mode at the switch (`switching::select_mode`).

use std::collections::HashMap;

use faer::{c64, Mat};

use super::propagator::{Functional, Propagator, Segment};
use super::roots::{maxima, Scalar, Search, SearchOptions};
use super::switching::{lex_signs, select_mode};
use super::taylor::{self, Poly, TaylorMatrix};
use super::{CollisionEnd, Event, Grid, Observer, Options, Solution, Totals};
use crate::impact::{ImpactSystem, Indicator, Mode, Switch};
use crate::{Error, Result};

struct ModeData {
    prop: std::rc::Rc<Propagator>,
    /// Transition matrix for the output step.
    step: Option<Mat<f64>>,
}

/// Taylor steps a run may take in one mode before it builds the mode's closed form (the default
/// of [`super::Options::taylor_steps_per_mode`]).
///
/// A Taylor step costs `P` mat-vecs and a polynomial search and spans `2/‖D⁻¹AD‖_∞` (about a
/// third of the fastest period); the closed form costs an eigen-decomposition up front and a
/// sum of exponentials per evaluation, and pays off over long stretches. A blow of the paper's
/// machine takes 5 steps in all (a dashpot switching off after 0.8 µs, 0.5 ms of slider
/// contact in 3 steps, 0.17 ms of damper contact in 1); a long free flight switches to the
/// closed form after this many steps.
pub const TAYLOR_STEPS_PER_MODE: usize = 16;

/// Number of modes: three switch bits (slider-bed, bed-damper, dashpot).
const MODES: usize = 8;

/// Runs the exact propagator. See the module documentation.
pub fn solve(sys: &ImpactSystem, opts: &Options, obs: &mut dyn Observer) -> Result<Solution> {
    solve_from(sys, &sys.initial_state(), opts, obs)
}

/// As [`solve`], from the state `x0 = [x; ẋ]` (length `2 · dofs`) at t = 0 instead of
/// [`ImpactSystem::initial_state`] (used to chain blows).
pub fn solve_from(
    sys: &ImpactSystem,
    x0: &[f64],
    opts: &Options,
    obs: &mut dyn Observer,
) -> Result<Solution> {
    for s in [Switch::SliderBed, Switch::BedDamper] {
        if (s == Switch::SliderBed || sys.damper.is_some()) && !sys.contact(s).law.is_linear() {
            return Err(Error::invalid(
                "simulation.method",
                "method 'exact' needs linear contact laws; use 'dopri5' for hertz or hunt-crossley",
            ));
        }
    }
    let nd = sys.dofs();
    let n = 2 * nd;
    let masses = sys.mass_diag();
    let inds = sys.indicators();
    let ind_vecs: Vec<Vec<f64>> = inds.iter().map(|&i| sys.indicator_vector(i)).collect();
    // `ℓ` of each contact's force (for its peaks), built once per run.
    let force_vecs: Vec<Vec<f64>> = [Switch::SliderBed, Switch::BedDamper]
        .into_iter()
        .map(|s| {
            if s == Switch::SliderBed || sys.damper.is_some() {
                contact_force_vector(sys, s)
            } else {
                Vec::new()
            }
        })
        .collect();
    let mut cache: HashMap<Mode, ModeData> = HashMap::new();
    let mut grid = Grid::new(opts.sample_rate);
    let t_end = opts.duration;

    // `a` is the mode's first-order matrix (shared with the mode selection's cache).
    let build = |mode: Mode, a: Mat<f64>| -> Result<ModeData> {
        let (k, c) = sys.matrices(mode);
        let prop = Propagator::shared(&k, &c, &masses, a)?;
        Ok(ModeData { prop, step: None })
    };

    let mut x = x0.to_vec();
    let mut t = 0.0;
    // First-order matrices of the modes met, for the mode selection.
    let mut a_cache: HashMap<Mode, std::rc::Rc<Mat<f64>>> = HashMap::new();
    let mut a_of = |m: Mode| -> std::rc::Rc<Mat<f64>> {
        a_cache
            .entry(m)
            .or_insert_with(|| std::rc::Rc::new(sys.first_order(m)))
            .clone()
    };
    let (mut mode, _, mut signs) = select_mode(sys, &x, Mode(0), &ind_vecs, &mut a_of);
    let mut events = Vec::new();
    let mut totals = Totals::default();
    let mut collision_end: Option<CollisionEnd> = None;
    let mut segments = 0usize;
    let mut zero_length = 0usize;
    let mut buf = vec![0.0; n];
    let mut buf2 = vec![0.0; n];
    let mut taylor_steps = [0usize; MODES];
    // Damping matrices of the modes met (dissipation).
    let mut c_cache: HashMap<Mode, std::rc::Rc<Mat<f64>>> = HashMap::new();
    let mut c_of = |m: Mode| -> std::rc::Rc<Mat<f64>> {
        c_cache
            .entry(m)
            .or_insert_with(|| std::rc::Rc::new(sys.matrices(m).1))
            .clone()
    };

    // Taylor-step workspace: the first-order matrices prepared per mode, the coefficients
    // c_0 … c_P of the current step, and the polynomials of the indicators and of a force.
    let mut tmats: [Option<TaylorMatrix>; MODES] = Default::default();
    let mut coef = vec![0.0; (taylor::ORDER + 1) * n];
    let mut ind_polys = vec![[0.0; taylor::ORDER + 1]; ind_vecs.len()];
    let mut gl_work = Vec::new();
    // Each linear contact's force from its overlap polynomial: (indicator index, K, C).
    let force_from_overlap: [Option<(usize, f64, f64)>; 2] = [Switch::SliderBed, Switch::BedDamper]
        .map(|s| {
            let i = inds.iter().position(|&ind| ind == Indicator::Overlap(s))?;
            match sys.contact(s).law {
                crate::impact::ContactLaw::Linear { stiffness, damping } => {
                    Some((i, stiffness, damping))
                }
                _ => None,
            }
        });

    loop {
        let search = SearchOptions::default();
        let horizon = t_end - t;
        segments += 1;
        // Until the run has built a mode's closed form (and for at most
        // `opts.taylor_steps_per_mode` steps in that mode), the mode is propagated by Taylor steps
        // from the current state: each is exact to round-off over its validity (a third of the
        // fastest period) and needs no eigen-decomposition, so a short stretch, or a blow that
        // is over in a few periods, never builds one. The choice depends only on the run's own
        // history (never on the per-thread cache), so results do not depend on the thread
        // count.
        debug_assert!(usize::from(mode.0) < MODES, "three switch bits");
        let mi = usize::from(mode.0) % MODES;
        let use_taylor =
            !cache.contains_key(&mode) && taylor_steps[mi] < opts.taylor_steps_per_mode;
        let (s_end, switched, run_ends, period);
        if use_taylor {
            taylor_steps[mi] += 1;
            let tm = match &tmats[mi] {
                Some(tm) => tm,
                None => {
                    let tm = TaylorMatrix::new(&a_of(mode)).ok_or_else(|| {
                        Error::numerical("exact", format!("mode {mode:?}: non-finite matrix"))
                    })?;
                    tmats[mi].insert(tm)
                }
            };
            tm.expand(&x, &mut coef);
            let tau = tm.validity();
            period = tm.period();
            // 1-2: the first switch, within the step's validity.
            let reach = tau.min(horizon);
            for (l, p) in ind_vecs.iter().zip(ind_polys.iter_mut()) {
                taylor::project(l, &coef, p);
            }
            // (Indicators whose constant term dominates cannot cross within the step.)
            let funcs: Vec<(Poly<'_>, f64)> = ind_polys
                .iter()
                .zip(&signs)
                .filter(|(_, s)| **s != 0.0)
                .map(|(p, s)| (Poly::new(p, tau, period), *s))
                .filter(|(p, s)| !p.keeps_sign(*s, reach))
                .collect();
            let found = first_switch(&funcs, period, reach, search);
            (s_end, switched) = stretch_end(found, reach, reach >= horizon);
            run_ends = !switched && s_end >= horizon;
            // 3: output samples, from the polynomial.
            if let Some(g) = grid.as_mut() {
                let state = |s: f64, out: &mut [f64]| taylor::state(&coef, s, out);
                let span = (t, s_end, run_ends, t_end);
                emit_samples(g, span, mode, &state, None, obs, &mut buf, &mut buf2);
            }
            // 4: peaks, contact times, dissipation.
            for ci in 0..2 {
                if closed(sys, mode, ci) {
                    totals.closed_time[ci] += s_end;
                    let mut f = [0.0; taylor::ORDER + 1];
                    match force_from_overlap[ci] {
                        // f = K δ + C δ̇ from the overlap's polynomial (δ̇ its derivative).
                        Some((i, k, c)) => {
                            let d = &ind_polys[i];
                            for (j, fj) in f.iter_mut().enumerate() {
                                let next = d.get(j + 1).map_or(0.0, |v| (j + 1) as f64 * v);
                                *fj = k * d[j] + c * next;
                            }
                        }
                        None => taylor::project(&force_vecs[ci], &coef, &mut f),
                    }
                    let peak = poly_max(&f, tau, period, s_end);
                    totals.peak_force[ci] = totals.peak_force[ci].max(peak);
                }
            }
            totals.dissipated += taylor_dissipated(&coef, &c_of(mode), nd, s_end, &mut gl_work);
            taylor::state(&coef, s_end, &mut x);
        } else {
            if let std::collections::hash_map::Entry::Vacant(e) = cache.entry(mode) {
                e.insert(build(mode, (*a_of(mode)).clone())?);
            }
            let md = cache
                .get_mut(&mode)
                .ok_or_else(|| Error::numerical("exact", "mode cache"))?;
            if let (Some(g), None) = (&grid, &md.step) {
                md.step = Some(md.prop.transition(g.dt));
            }
            let md = &*md;
            let prop = &*md.prop;
            let seg = prop.segment(&x);
            period = prop.period();
            // 1-2: the first switch.
            let funcs: Vec<(Functional<'_>, f64)> = ind_vecs
                .iter()
                .zip(&signs)
                .filter(|(_, s)| **s != 0.0)
                .map(|(l, s)| (seg.functional(l), *s))
                .collect();
            let found = first_switch(&funcs, period, horizon, search);
            (s_end, switched) = stretch_end(found, horizon, true);
            run_ends = !switched;
            // 3: output samples.
            if let Some(g) = grid.as_mut() {
                let state = |s: f64, out: &mut [f64]| seg.state(s, out);
                let span = (t, s_end, run_ends, t_end);
                let step = md.step.as_ref();
                emit_samples(g, span, mode, &state, step, obs, &mut buf, &mut buf2);
            }
            // 4: peaks, contact times, dissipation.
            for ci in 0..2 {
                if closed(sys, mode, ci) {
                    totals.closed_time[ci] += s_end;
                    let peak = max_on_segment(&seg, &force_vecs[ci], &prop.a, s_end, period);
                    totals.peak_force[ci] = totals.peak_force[ci].max(peak);
                }
            }
            totals.dissipated += dissipated(&seg, &c_of(mode), nd, s_end);
            seg.state(s_end, &mut buf);
            x.copy_from_slice(&buf);
        }

        // Advance.
        t += s_end;
        if run_ends {
            break;
        }
        if !switched {
            // End of a Taylor step: the same mode goes on, the indicators on the same sides.
            continue;
        }
        if s_end <= 1e-14 * period.min(t_end) {
            zero_length += 1;
            if zero_length > 50 {
                return Err(Error::numerical(
                    "exact propagator",
                    format!(
                        "switches chatter at t = {t:.9e} s without time advancing (mode {:?})",
                        mode
                    ),
                ));
            }
        } else {
            zero_length = 0;
        }
        // 5: the new mode.
        let (new_mode, consistent, new_signs) = select_mode(sys, &x, mode, &ind_vecs, &mut a_of);
        // The signs are those under `new_mode`'s dynamics when it is consistent; otherwise
        // (no consistent mode) they are recomputed for the mode taken.
        signs = if consistent {
            new_signs
        } else {
            let a = a_of(new_mode);
            let mut s = vec![0.0; ind_vecs.len()];
            lex_signs(&ind_vecs, &a, &x, &mut s);
            s
        };
        if new_mode != mode {
            events.push(Event {
                t,
                from: mode,
                to: new_mode,
            });
            if events.len() > opts.max_events {
                return Err(Error::numerical(
                    "exact propagator",
                    format!(
                        "more than {} switching events before t = {t:.6} s",
                        opts.max_events
                    ),
                ));
            }
        }
        mode = new_mode;
        if collision_end.is_none() && !mode.on(Switch::SliderBed) && !mode.on(Switch::BedDamper) {
            collision_end = Some(CollisionEnd {
                t,
                x: x.clone(),
                totals,
            });
            if opts.stop_at_collision_end {
                break;
            }
        }
        if t >= t_end {
            // A switch at the very end of the run: the sample at t_end, if still due.
            if let Some(g) = grid.as_mut() {
                let xe = x.clone();
                let state = |_: f64, out: &mut [f64]| out.copy_from_slice(&xe);
                let span = (t, 0.0, true, t_end);
                emit_samples(g, span, mode, &state, None, obs, &mut buf, &mut buf2);
            }
            break;
        }
    }
    let fallback_modes = cache.values().filter(|m| !m.prop.is_spectral()).count();
    Ok(Solution {
        events,
        collision_end,
        t_final: t,
        x_final: x,
        mode_final: mode,
        totals,
        steps: segments,
        taylor_steps: taylor_steps.iter().sum(),
        rejected: 0,
        fallback_modes,
    })
}

/// Where a stretch ends: at the first switch `found` if it comes before `reach`, else at
/// `reach`; and whether it ends at a switch. A switch found exactly at `reach` counts when
/// `reach` is only the end of a Taylor step (`reach_is_run_end` false): the sign change is real
/// (the search bracketed it), and the next step must not start past it.
fn stretch_end(found: Option<f64>, reach: f64, reach_is_run_end: bool) -> (f64, bool) {
    match found {
        Some(s) if s < reach || (s <= reach && !reach_is_run_end) => (s.clamp(0.0, reach), true),
        _ => (reach, false),
    }
}

/// True when contact `ci` (0 slider-bed, 1 bed-damper) exists and is closed in `mode`.
fn closed(sys: &ImpactSystem, mode: Mode, ci: usize) -> bool {
    let s = [Switch::SliderBed, Switch::BedDamper][ci];
    mode.on(s) && (ci == 0 || sys.damper.is_some())
}

/// Output samples in `[t, t + len)` (and at `t_end` when the run ends with this stretch), with
/// `span = (t, len, run_ends, t_end)`: the first from `state`, the next ones by the transition
/// matrix `step` (one mat-vec per sample) when given, re-seeded from `state` every 64 samples.
#[allow(clippy::too_many_arguments)]
fn emit_samples(
    g: &mut Grid,
    span: (f64, f64, bool, f64),
    mode: Mode,
    state: &dyn Fn(f64, &mut [f64]),
    step: Option<&Mat<f64>>,
    obs: &mut dyn Observer,
    buf: &mut Vec<f64>,
    buf2: &mut Vec<f64>,
) {
    let (t, len, last, t_end) = span;
    let n = buf.len();
    let mut j = g.next;
    let mut k = 0usize;
    loop {
        let tj = g.time(j);
        let inside = if last {
            tj <= t + len * (1.0 + 1e-15) + 1e-15 * t_end
        } else {
            tj < t + len
        };
        if !inside || tj > t_end * (1.0 + 1e-12) {
            break;
        }
        match step {
            Some(e) if k % 64 != 0 => {
                // faer's kernel (SIMD with run-time dispatch), sequential.
                faer::linalg::matmul::matmul(
                    faer::MatMut::from_column_major_slice_mut(buf2, n, 1),
                    faer::Accum::Replace,
                    e.as_ref(),
                    faer::MatRef::from_column_major_slice(buf, n, 1),
                    1.0,
                    faer::Par::Seq,
                );
                std::mem::swap(buf, buf2);
            }
            _ => state(tj - t, buf),
        }
        obs.sample(tj, buf, mode);
        j += 1;
        k += 1;
    }
    g.next = j;
}

/// The first switch within `horizon` (s after the stretch start), or `None`, of the
/// indicators `funcs` (each with its side at the start; those identically zero left out).
/// All are searched over common windows growing from one fastest period, so the search ends
/// at the earliest crossing; only the earliest bracket is refined (and any other bracket
/// starting before its root).
fn first_switch<F: Scalar>(
    funcs: &[(F, f64)],
    period: f64,
    horizon: f64,
    search: SearchOptions,
) -> Option<f64> {
    let mut searches: Vec<Search<'_, F>> = funcs
        .iter()
        .map(|(f, sign0)| Search::new(f, *sign0, search))
        .collect();
    let mut limit = if period.is_finite() {
        period.min(horizon)
    } else {
        horizon
    };
    loop {
        let mut brackets: Vec<(f64, f64, usize)> = Vec::new();
        for (i, sr) in searches.iter_mut().enumerate() {
            if let Some((a, b)) = sr.advance(limit) {
                brackets.push((a, b, i));
            }
        }
        if !brackets.is_empty() {
            brackets.sort_by(|p, q| p.0.total_cmp(&q.0));
            let mut first = f64::INFINITY;
            for &(a, b, i) in &brackets {
                if a < first {
                    first = first.min(searches[i].refine(a, b));
                }
            }
            return Some(first);
        }
        if limit >= horizon {
            return None;
        }
        limit = (4.0 * limit).min(horizon);
    }
}

/// `ℓ` with `f = ℓᵀX` for a closed linear contact's force.
pub(crate) fn contact_force_vector(sys: &ImpactSystem, s: Switch) -> Vec<f64> {
    sys.indicator_vector(Indicator::Force(s))
}

/// Maximum of `ℓᵀX(s)` on `[0, len]`: endpoints and the interior maxima, where the derivative
/// `ℓᵀA X` changes sign from + to −.
fn max_on_segment(seg: &Segment<'_>, l: &[f64], a: &Mat<f64>, len: f64, _period: f64) -> f64 {
    let f = seg.functional(l);
    let val = |s: f64| match &f {
        Functional::Exp(e) => e.derivative(0, s),
        other => super::roots::Scalar::value_slope(other, s).0,
    };
    let mut best = val(0.0).max(val(len));
    let la: Vec<f64> = (0..a.ncols())
        .map(|j| (0..a.nrows()).map(|i| l[i] * a[(i, j)]).sum())
        .collect();
    let df = seg.functional(&la);
    for s in maxima(&df, len, SearchOptions::default()) {
        best = best.max(val(s));
    }
    best
}

/// 8-point Gauss-Legendre rule on [−1, 1]: the positive nodes and their weights.
const GL_X: [f64; 4] = [
    0.1834346424956498,
    0.525_532_409_916_329,
    0.7966664774136267,
    0.9602898564975363,
];
const GL_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.3137066458778873,
    0.2223810344533745,
    0.1012285362903763,
];

/// `∫₀^len ẋᵀ C ẋ ds` on a closed-form segment: exactly for the spectral form
/// (`ẋ = Re Σ β_k e^{λ_k s}`, so the integrand is a sum of exponentials), otherwise (the
/// matrix-exponential fallback) by 8-point Gauss-Legendre quadrature on sub-intervals of a
/// quarter of the fastest period. Taylor steps have [`taylor_dissipated`].
fn dissipated(seg: &Segment<'_>, c: &Mat<f64>, nd: usize, len: f64) -> f64 {
    if len <= 0.0 || c.norm_l2() == 0.0 {
        return 0.0;
    }
    if let Some((beta, lam)) = seg.velocity_terms() {
        // ẋᵀCẋ = ½ Σ_kl Re[(β_kᵀCβ_l) e^{(λ_k+λ_l)s} + (β_kᵀCβ̄_l) e^{(λ_k+λ̄_l)s}].
        let kk = beta.len();
        let cb: Vec<Vec<c64>> = beta
            .iter()
            .map(|b| {
                (0..nd)
                    .map(|i| (0..nd).fold(c64::new(0.0, 0.0), |acc, j| acc + b[j] * c[(i, j)]))
                    .collect()
            })
            .collect();
        let mut total = 0.0;
        for k in 0..kk {
            for l in 0..kk {
                let mut p = c64::new(0.0, 0.0);
                let mut q = c64::new(0.0, 0.0);
                for i in 0..nd {
                    p += beta[k][i] * cb[l][i];
                    q += beta[k][i] * cb[l][i].conj();
                }
                total += 0.5 * (p * exp_integral(lam[k] + lam[l], len)).re;
                total += 0.5 * (q * exp_integral(lam[k] + lam[l].conj(), len)).re;
            }
        }
        return total;
    }
    // Quadrature fallback.
    let pieces = ((len / (seg_period(seg) / 4.0)).ceil() as usize).clamp(1, 1_000_000);
    let h = len / pieces as f64;
    let mut x = vec![0.0; 2 * nd];
    let mut total = 0.0;
    for p in 0..pieces {
        let mid = (p as f64 + 0.5) * h;
        for (xi, wi) in GL_X.iter().zip(GL_W) {
            for sgn in [-1.0, 1.0] {
                seg.state(mid + sgn * xi * h / 2.0, &mut x);
                total += wi * h / 2.0 * quad_form(c, &x[nd..]);
            }
        }
    }
    total
}

/// 10-point Gauss-Legendre rule on [−1, 1]: the positive nodes and their weights.
const GL10_X: [f64; 5] = [
    0.148_874_338_981_631_22,
    0.433_395_394_129_247_2,
    0.679_409_568_299_024_4,
    0.865_063_366_688_984_5,
    0.973_906_528_517_171_7,
];
const GL10_W: [f64; 5] = [
    0.295_524_224_714_752_87,
    0.269_266_719_309_996_35,
    0.219_086_362_515_982_04,
    0.149_451_349_150_580_6,
    0.066_671_344_308_688_14,
];

/// `∫₀^len ẋᵀ C ẋ ds` on a Taylor step with coefficients `coef` (`len` within its validity
/// `2/ρ`, ρ bounding the growth rate of ẋ and so `2ρ` that of ẋᵀCẋ): the 10-point
/// Gauss-Legendre rule's error, `L^21 (10!)^4 / (21 (20!)^3) · max|f⁽²⁰⁾|` with
/// `|f⁽²⁰⁾| ≤ (2ρ)^20 max|f|`, is at most `4^20 (10!)^4 / (21 (20!)^3) ≈ 6.4e-19` of
/// `L max|f|`: below round-off. Only the velocity half of the polynomial is evaluated.
/// `work` is scratch space (reused between calls).
fn taylor_dissipated(
    coef: &[f64],
    c: &Mat<f64>,
    nd: usize,
    len: f64,
    work: &mut Vec<[f64; 10]>,
) -> f64 {
    if len <= 0.0 || (0..nd).all(|j| c.col_as_slice(j).iter().all(|v| *v == 0.0)) {
        return 0.0;
    }
    // The 10 nodes and weights on [0, len].
    let mut s = [0.0; 10];
    let mut w = [0.0; 10];
    for (q, (xi, wi)) in GL10_X.iter().zip(GL10_W).enumerate() {
        s[2 * q] = 0.5 * len * (1.0 - xi);
        s[2 * q + 1] = 0.5 * len * (1.0 + xi);
        w[2 * q] = 0.5 * len * wi;
        w[2 * q + 1] = 0.5 * len * wi;
    }
    // ẋ at all nodes at once (Horner over k; `v[i]` holds component i at the 10 nodes).
    let n = 2 * nd;
    work.clear();
    work.resize(2 * nd, [0.0; 10]);
    let (v, cv) = work.split_at_mut(nd);
    for ck in coef.chunks_exact(n).rev() {
        for (vi, &cki) in v.iter_mut().zip(&ck[nd..]) {
            for (x, sj) in vi.iter_mut().zip(&s) {
                *x = *x * sj + cki;
            }
        }
    }
    // Σ_nodes w ẋᵀCẋ, with (Cẋ)_i = Σ_j C_ij ẋ_j column by column.
    let mut total = 0.0;
    for (j, vj) in v.iter().enumerate() {
        for (i, cij) in c.col_as_slice(j).iter().enumerate() {
            if *cij != 0.0 {
                for (x, y) in cv[i].iter_mut().zip(vj) {
                    *x += cij * y;
                }
            }
        }
    }
    for (vi, cvi) in v.iter().zip(cv.iter()) {
        for q in 0..10 {
            total += w[q] * vi[q] * cvi[q];
        }
    }
    total
}

/// Maximum over `[0, len]` of a force `Σ a_k s^k` on a Taylor step (`tau` its validity): the
/// endpoints and the interior maxima, where the derivative `Σ (k+1) a_{k+1} s^k` changes sign
/// from + to −.
fn poly_max(a: &[f64; taylor::ORDER + 1], tau: f64, period: f64, len: f64) -> f64 {
    let mut da = [0.0; taylor::ORDER + 1];
    for (k, d) in da.iter_mut().take(taylor::ORDER).enumerate() {
        *d = (k + 1) as f64 * a[k + 1];
    }
    let f = Poly::new(a, tau, period);
    let mut best = f.value(0.0).max(f.value(len));
    let df = Poly::new(&da, tau, period);
    // A slope of one sign throughout (by dominance) leaves the maximum at an end.
    if !(df.keeps_sign(1.0, len) || df.keeps_sign(-1.0, len)) {
        for s in maxima(&df, len, SearchOptions::default()) {
            best = best.max(f.value(s));
        }
    }
    best
}

/// `vᵀ C v`.
fn quad_form(c: &Mat<f64>, v: &[f64]) -> f64 {
    let mut e = 0.0;
    for (j, vj) in v.iter().enumerate() {
        if *vj != 0.0 {
            let cv: f64 = c.col_as_slice(j).iter().zip(v).map(|(a, b)| a * b).sum();
            e += cv * vj;
        }
    }
    e
}

fn seg_period(seg: &Segment<'_>) -> f64 {
    let p = seg.propagator().period();
    if p.is_finite() {
        p
    } else {
        1.0
    }
}

/// `∫₀^T e^{z s} ds`, stable for small `|z T|`.
fn exp_integral(z: c64, t: f64) -> c64 {
    let zt = z * t;
    if zt.norm() < 1e-4 {
        t * (1.0 + zt / 2.0 + zt * zt / 6.0 + zt * zt * zt / 24.0)
    } else {
        (zt.exp() - 1.0) / z
    }
}
