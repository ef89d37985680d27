//! Exact event-driven propagation of the piecewise-linear impact system.
//!
//! Each mode's closed-form [`Propagator`] is built the first time the mode is entered and kept
//! for the run (and in a small per-thread cache, [`Propagator::shared`], for the next run of
//! the same matrices). A stretch in one mode is handled as follows:
//!
//! 1. the side of every indicator at the stretch start (`switching::lex_sign`, from the
//!    mode selection that chose the mode);
//! 2. the first sign change of any indicator on the closed-form solution ([`super::roots`]):
//!    all indicators are searched over common windows growing from one fastest period, so the
//!    search ends at the earliest crossing; capped by the end of the run;
//! 3. output samples inside the stretch: the first evaluated in closed form, the next ones by
//!    the real transition matrix `E = exp(A Δt)` (one mat-vec per sample), re-seeded from the
//!    closed form every 64 samples;
//! 4. exact contact-force maxima (roots of the force's derivative), closed-contact times, and
//!    the dissipated energy `∫ ẋᵀ C_σ ẋ dt` integrated in closed form;
//! 5. the new mode at the switch (`switching::select_mode`).

use std::collections::HashMap;

use faer::{c64, Mat};

use super::propagator::{Functional, Propagator, Segment};
use super::roots::{maxima, Search, SearchOptions};
use super::switching::{lex_sign, select_mode};
use super::{CollisionEnd, Event, Grid, Observer, Options, Solution, Totals};
use crate::impact::{ImpactSystem, Indicator, Mode, Switch};
use crate::{Error, Result};

struct ModeData {
    prop: std::rc::Rc<Propagator>,
    c: Mat<f64>,
    /// Transition matrix for the output step.
    step: Option<Mat<f64>>,
}

/// A stretch handled by the Taylor propagator: the switch at `s_end` lies within its validity.
struct TaylorStretch {
    prop: Propagator,
    s_end: f64,
    /// The mode's damping matrix (dissipation).
    c: Mat<f64>,
    /// Transition matrix for the output step.
    step: Option<Mat<f64>>,
}

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
        Ok(ModeData {
            prop,
            c,
            step: None,
        })
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

    loop {
        let search = SearchOptions::default();
        let horizon = t_end - t;
        segments += 1;
        // A mode met for the first time is tried with the Taylor propagator from this state
        // first: when a switch comes within its validity (a few tenths of the fastest period)
        // the stretch needs no eigen-decomposition. Otherwise the closed form is built. The
        // choice depends only on the run's own history (never on the per-thread cache), so
        // results do not depend on the thread count.
        let mut taylor: Option<TaylorStretch> = None;
        if !cache.contains_key(&mode) {
            if let Some(tp) = Propagator::taylor((*a_of(mode)).clone(), &x) {
                let seg = tp.segment(&x);
                let reach = tp.validity().min(horizon);
                if let Some(s) = first_switch(&seg, &ind_vecs, &signs, tp.period(), reach, search) {
                    if s < reach {
                        let (_, c) = sys.matrices(mode);
                        let step = grid.as_ref().map(|g| tp.transition(g.dt));
                        taylor = Some(TaylorStretch {
                            prop: tp,
                            s_end: s,
                            c,
                            step,
                        });
                    }
                }
            }
        }
        if taylor.is_none() {
            if let std::collections::hash_map::Entry::Vacant(e) = cache.entry(mode) {
                e.insert(build(mode, (*a_of(mode)).clone())?);
            }
            let md = cache
                .get_mut(&mode)
                .ok_or_else(|| Error::numerical("exact", "mode cache"))?;
            if let (Some(g), None) = (&grid, &md.step) {
                md.step = Some(md.prop.transition(g.dt));
            }
        }
        let (prop, c_mode, step_mat): (&Propagator, &Mat<f64>, Option<&Mat<f64>>) = match &taylor {
            Some(ts) => (&ts.prop, &ts.c, ts.step.as_ref()),
            None => {
                let md = cache
                    .get(&mode)
                    .ok_or_else(|| Error::numerical("exact", "mode cache"))?;
                (&*md.prop, &md.c, md.step.as_ref())
            }
        };
        let seg = prop.segment(&x);
        let period = prop.period();

        // 1-2: the first switch.
        let mut s_end = horizon;
        let mut switched = false;
        let found = match &taylor {
            Some(ts) => Some(ts.s_end),
            None => first_switch(&seg, &ind_vecs, &signs, period, horizon, search),
        };
        if let Some(s) = found {
            if s < s_end {
                s_end = s;
                switched = true;
            }
        }
        if s_end < 0.0 {
            s_end = 0.0;
        }

        // 3: output samples in [t, t + s_end) (and at t_end on the last stretch).
        if let Some(g) = grid.as_mut() {
            let last = !switched;
            let mut j = g.next;
            let mut k = 0usize;
            let step = step_mat;
            loop {
                let tj = g.time(j);
                let inside = if last {
                    tj <= t + s_end * (1.0 + 1e-15) + 1e-15 * t_end
                } else {
                    tj < t + s_end
                };
                if !inside || tj > t_end * (1.0 + 1e-12) {
                    break;
                }
                if k % 64 == 0 || step.is_none() {
                    seg.state(tj - t, &mut buf);
                } else if let Some(e) = step {
                    // faer's kernel (SIMD with run-time dispatch), sequential.
                    faer::linalg::matmul::matmul(
                        faer::MatMut::from_column_major_slice_mut(&mut buf2, n, 1),
                        faer::Accum::Replace,
                        e.as_ref(),
                        faer::MatRef::from_column_major_slice(&buf, n, 1),
                        1.0,
                        faer::Par::Seq,
                    );
                    std::mem::swap(&mut buf, &mut buf2);
                }
                obs.sample(tj, &buf, mode);
                j += 1;
                k += 1;
            }
            g.next = j;
        }

        // 4: peaks, contact times, dissipation.
        for (ci, s) in [Switch::SliderBed, Switch::BedDamper]
            .into_iter()
            .enumerate()
        {
            if mode.on(s) && (ci == 0 || sys.damper.is_some()) {
                totals.closed_time[ci] += s_end;
                let peak = max_on_segment(&seg, &force_vecs[ci], &prop.a, s_end, period);
                totals.peak_force[ci] = totals.peak_force[ci].max(peak);
            }
        }
        totals.dissipated += dissipated(&seg, c_mode, nd, s_end);

        // Advance.
        seg.state(s_end, &mut buf);
        x.copy_from_slice(&buf);
        t += s_end;
        if !switched {
            break;
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
            ind_vecs.iter().map(|l| lex_sign(l, &a, &x)).collect()
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
        rejected: 0,
        fallback_modes,
    })
}

/// The first switch on a segment within `horizon` (s after its start), or `None`. All
/// indicators (those with a non-zero sign) are searched over common windows growing from one
/// fastest period, so the search ends at the earliest crossing; only the earliest bracket is
/// refined (and any other bracket starting before its root).
fn first_switch(
    seg: &Segment<'_>,
    ind_vecs: &[Vec<f64>],
    signs: &[f64],
    period: f64,
    horizon: f64,
    search: SearchOptions,
) -> Option<f64> {
    let mut funcs = Vec::with_capacity(ind_vecs.len());
    for (l, &sign0) in ind_vecs.iter().zip(signs) {
        if sign0 != 0.0 {
            // (sign 0: identically zero, never crosses)
            funcs.push((seg.functional(l), sign0));
        }
    }
    let mut searches: Vec<Search<'_, Functional<'_>>> = funcs
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

/// `∫₀^len ẋᵀ C ẋ ds` on a segment, in closed form for the spectral form
/// (`ẋ = Re Σ β_k e^{λ_k s}`, so the integrand is a sum of exponentials), otherwise by
/// 8-point Gauss-Legendre quadrature on sub-intervals of a quarter of the fastest period.
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
    let pieces = ((len / (seg_period(seg) / 4.0)).ceil() as usize).clamp(1, 1_000_000);
    let h = len / pieces as f64;
    let mut x = vec![0.0; 2 * nd];
    let mut total = 0.0;
    for p in 0..pieces {
        let mid = (p as f64 + 0.5) * h;
        for (xi, wi) in GL_X.iter().zip(GL_W) {
            for sgn in [-1.0, 1.0] {
                seg.state(mid + sgn * xi * h / 2.0, &mut x);
                let v = &x[nd..];
                let mut e = 0.0;
                for i in 0..nd {
                    for j in 0..nd {
                        e += v[i] * c[(i, j)] * v[j];
                    }
                }
                total += wi * h / 2.0 * e;
            }
        }
    }
    total
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
