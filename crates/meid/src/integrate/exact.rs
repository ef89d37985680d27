//! Exact event-driven propagation of the piecewise-linear impact system.
//!
//! A stretch in one mode is propagated in one of two forms, both exact to round-off:
//!
//! * **Taylor steps** ([`super::taylor`]): `X(s) = Σ_{k≤24} A^k X₀ s^k / k!` over a third of
//!   the fastest period, where the truncation is below 2.6e-17. No eigen-decomposition is needed;
//!   a run takes them in a mode until it has spent [`Options::taylor_steps_per_mode`] there
//!   (default [`TAYLOR_STEPS_PER_MODE`]). A blow of the paper's machine is over in 4 such
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
//!    the dissipated energy `∫ ẋᵀ C_σ ẋ dt` (closed form, or Gauss-Legendre at round-off level
//!    on a Taylor step);
//! 5. the new mode at the switch (`switching::ModeSelector::select`).

use std::rc::Rc;

use faer::{c64, Mat};

use super::peaks;
use super::propagator::{Functional, Propagator, Segment};
use super::roots::{Scalar, Search, SearchOptions};
use super::switching::{ModeSelector, MODES};
use super::taylor::{self, Poly, TaylorMatrix};
use super::{CollisionEnd, Event, Grid, Observer, Options, PathPoint, Solution, Totals};
use crate::impact::{Channel, ChannelMap, ImpactSystem, Mode, Switch, CHANNELS, N_CHANNELS};
use crate::{Error, Result};

/// A mode's closed form, built the first time a run needs it.
struct ModeData {
    prop: Rc<Propagator>,
    /// The mode's damping matrix `C_σ` (dissipation).
    damping: Mat<f64>,
    /// Transition matrix for the output step.
    step: Option<Mat<f64>>,
}

/// Taylor steps a run may take in one mode before it builds the mode's closed form (the default
/// of [`super::Options::taylor_steps_per_mode`]).
///
/// A Taylor step costs `P` mat-vecs and a polynomial search and spans `2.2/‖D⁻¹AD‖_∞` (about a
/// third of the fastest period); the closed form costs an eigen-decomposition up front and a
/// sum of exponentials per evaluation, and pays off over long stretches. A blow of the paper's
/// machine takes 4 steps in all (a dashpot switching off after 0.8 µs, 0.5 ms of slider
/// contact in 2 steps, 0.17 ms of damper contact in 1); a long free flight switches to the
/// closed form after this many steps.
pub const TAYLOR_STEPS_PER_MODE: usize = 16;

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
    let mut run = Run::new(sys, x0, opts);
    loop {
        let st = run.stretch(obs)?;
        // Advance.
        let t_before = run.t;
        run.t += st.s_end;
        if st.run_ends {
            break;
        }
        if !st.switched {
            // End of a Taylor step: the same mode goes on, the indicators on the same sides.
            continue;
        }
        let (no_progress, micro) = run.progress(st.s_end, st.period, t_before)?;
        let new_mode = run.next_mode(no_progress, micro);
        if new_mode != run.mode {
            run.switch_to(new_mode)?;
        }
        run.mode = new_mode;
        if run.collision_ends() && opts.stop_at_collision_end {
            break;
        }
        if run.t >= run.t_end {
            // A switch at the very end of the run: the sample at t_end, if still due.
            run.last_sample(obs);
            break;
        }
    }
    Ok(run.finish())
}

/// A stretch's end: its length `s_end` (s), whether it ended on a switch, whether the run
/// ends with it, and the mode's fastest period (s).
struct Stretch {
    s_end: f64,
    switched: bool,
    run_ends: bool,
    period: f64,
}

/// The Taylor-step workspace, reused from step to step: the first-order matrices prepared per
/// mode, per mode the Taylor coefficients of the forced response from rest (a constant slider
/// force), the coefficients `c_0 … c_P` of the current step, the indicators' projectors and
/// polynomials, and the searches' buffer.
struct TaylorWork {
    tmats: [Option<TaylorMatrix>; MODES],
    forced_coef: [Option<Vec<f64>>; MODES],
    coef: Vec<f64>,
    ind_proj: Vec<taylor::Projector>,
    ind_polys: Vec<[f64; taylor::ORDER + 1]>,
    searches: Vec<Search<Lifted<Poly>>>,
    /// Scratch space of [`TaylorMatrix::dissipated`].
    work: Vec<f64>,
}

/// The state of a run between stretches ([`solve_from`]).
struct Run<'s, 'o> {
    sys: &'s ImpactSystem,
    opts: &'o Options,
    t_end: f64,
    masses: Vec<f64>,
    selector: ModeSelector<'s>,
    /// Closed forms of the modes that stay long, built on first use.
    cache: [Option<Rc<ModeData>>; MODES],
    /// Taylor steps taken per mode.
    taylor_steps: [usize; MODES],
    tw: TaylorWork,
    /// A constant slider force: `Ẋ = A_σ X + b` (`b` first-order, `force_2nd` second-order).
    forcing: Option<Vec<f64>>,
    force_2nd: Option<Vec<f64>>,
    grid: Option<Grid>,
    /// The response channels of each mode met (their vectors, projectors and slopes), built on
    /// first use: their exact extremes are tracked stretch by stretch (`super::peaks`).
    map: ChannelMap,
    channels: [Option<ModeChannels>; MODES],
    chan_poly: taylor::Coefficients,
    chan_buf: Vec<f64>,
    x: Vec<f64>,
    t: f64,
    mode: Mode,
    /// The indicators' sides, and those the last stretch was searched from.
    signs: Vec<f64>,
    searched_signs: Vec<f64>,
    moved: Vec<bool>,
    events: Vec<Event>,
    path: Vec<PathPoint>,
    totals: Totals,
    collision_end: Option<CollisionEnd>,
    segments: usize,
    /// Consecutive stretches of no length, and of micro-stretches ([`MICRO_STRETCH`]).
    zero_length: usize,
    micro_stretches: usize,
    /// Scratch states.
    buf: Vec<f64>,
    buf2: Vec<f64>,
}

impl<'s, 'o> Run<'s, 'o> {
    /// The initial state and mode, the forcing, and the empty caches and workspaces.
    fn new(sys: &'s ImpactSystem, x0: &[f64], opts: &'o Options) -> Self {
        let nd = sys.dofs();
        let n = 2 * nd;
        let masses = sys.mass_diag();
        let mut selector = ModeSelector::new(sys);
        let n_ind = selector.indicators().len();
        let x = x0.to_vec();
        let mut signs = vec![0.0; n_ind];
        let (mode, _) = selector.select(&x, Mode(0), &mut signs);
        let forcing = sys.forcing();
        let force_2nd: Option<Vec<f64>> = forcing.as_ref().map(|b| b[nd..].to_vec());
        let force_2nd: Option<Vec<f64>> = force_2nd.map(|mut f| {
            f.iter_mut().zip(&masses).for_each(|(fi, mi)| *fi *= mi);
            f
        });
        let ind_proj: Vec<taylor::Projector> = selector
            .vectors()
            .iter()
            .map(|l| taylor::Projector::new(l))
            .collect();
        let tw = TaylorWork {
            tmats: Default::default(),
            forced_coef: Default::default(),
            coef: vec![0.0; (taylor::ORDER + 1) * n],
            ind_proj,
            ind_polys: vec![[0.0; taylor::ORDER + 1]; n_ind],
            searches: Vec::with_capacity(n_ind),
            work: Vec::new(),
        };
        let path = vec![PathPoint {
            t: 0.0,
            mode,
            x: x.clone(),
        }];
        Run {
            sys,
            opts,
            t_end: opts.duration,
            masses,
            selector,
            cache: Default::default(),
            taylor_steps: [0; MODES],
            tw,
            forcing,
            force_2nd,
            grid: Grid::new(opts),
            map: ChannelMap::new(sys),
            channels: Default::default(),
            chan_poly: [0.0; taylor::ORDER + 1],
            chan_buf: Vec::new(),
            x,
            t: 0.0,
            mode,
            signs,
            searched_signs: vec![0.0; n_ind],
            moved: vec![false; n_ind],
            events: Vec::new(),
            path,
            totals: Totals::default(),
            collision_end: None,
            segments: 0,
            zero_length: 0,
            micro_stretches: 0,
            buf: vec![0.0; n],
            buf2: vec![0.0; n],
        }
    }

    /// One stretch in the current mode from `t`: by a Taylor step until the run has built the
    /// mode's closed form (and for at most `opts.taylor_steps_per_mode` steps in that mode),
    /// else in closed form. A Taylor step is exact to round-off over its validity (a third of
    /// the fastest period) and needs no eigen-decomposition, so a short stretch, or a blow
    /// that is over in a few periods, never builds one. The choice depends only on the run's
    /// own history (never on the per-thread cache), so results do not depend on the thread
    /// count.
    fn stretch(&mut self, obs: &mut dyn Observer) -> Result<Stretch> {
        self.segments += 1;
        debug_assert!(usize::from(self.mode.0) < MODES, "three switch bits");
        let mi = usize::from(self.mode.0) % MODES;
        let use_taylor =
            self.cache[mi].is_none() && self.taylor_steps[mi] < self.opts.taylor_steps_per_mode;
        if use_taylor {
            self.taylor_stretch(mi, obs)
        } else {
            self.closed_stretch(mi, obs)
        }
    }

    /// A Taylor step in mode `mi`: the first switch within the step's validity (steps 1-2 of
    /// the module documentation), the output samples from the polynomial (3), and the peaks,
    /// contact times and dissipation (4); `x` is left at the stretch's end.
    fn taylor_stretch(&mut self, mi: usize, obs: &mut dyn Observer) -> Result<Stretch> {
        let horizon = self.t_end - self.t;
        self.taylor_steps[mi] += 1;
        let (tau, period) = self.expand(mi)?;
        // 1-2: the first switch, within the step's validity.
        let reach = tau.min(horizon);
        let tw = &mut self.tw;
        for (l, p) in tw.ind_proj.iter().zip(tw.ind_polys.iter_mut()) {
            l.apply(&tw.coef, p);
        }
        // (Indicators proved to keep their sign on the step, `Poly::keeps_sign`, are not
        // searched.)
        tw.searches.clear();
        for (p, &sign) in tw.ind_polys.iter().zip(&self.signs) {
            if sign != 0.0 && !taylor::keeps_sign(p, sign, reach) {
                let f = Lifted::new(Poly::new(p, tau, period), p[0], sign);
                tw.searches
                    .push(Search::new(f, sign, SearchOptions::default()));
            }
        }
        let found = first_switch(&mut tw.searches, period, reach);
        let (s_end, switched) = stretch_end(found, reach, reach >= horizon);
        let run_ends = !switched && s_end >= horizon;
        // 3: output samples, from the polynomial.
        if let Some(g) = self.grid.as_mut() {
            let coef = &self.tw.coef;
            let state = |s: f64, out: &mut [f64]| taylor::state(coef, s, out);
            let span = (self.t, s_end, run_ends, self.t_end);
            let (buf, buf2) = (&mut self.buf, &mut self.buf2);
            emit_samples(g, span, self.mode, &state, None, obs, buf, buf2);
        }
        self.book_taylor(mi, tau, period, s_end)?;
        Ok(Stretch {
            s_end,
            switched,
            run_ends,
            period,
        })
    }

    /// The Taylor coefficients of the step from `x` in mode `mi` (with the forced response
    /// from rest added under a constant force), the mode's first-order matrix prepared on
    /// first use; returns the step's validity `τ` and the fastest period (s).
    fn expand(&mut self, mi: usize) -> Result<(f64, f64)> {
        let n = self.x.len();
        let mode = self.mode;
        let tw = &mut self.tw;
        let tm = match &tw.tmats[mi] {
            Some(tm) => tm,
            None => {
                let tm = TaylorMatrix::from_col_major(n, self.selector.matrix(mode)).ok_or_else(
                    || Error::numerical("exact", format!("mode {mode:?}: non-finite matrix")),
                )?;
                tw.tmats[mi].insert(tm)
            }
        };
        tm.expand(&self.x, &mut tw.coef);
        if let Some(b) = &self.forcing {
            let fc = tw.forced_coef[mi].get_or_insert_with(|| {
                let mut fc = vec![0.0; (taylor::ORDER + 1) * n];
                tm.forced_coefficients(b, &mut fc);
                fc
            });
            for (c, f) in tw.coef.iter_mut().zip(fc.iter()) {
                *c += f;
            }
        }
        Ok((tm.validity(), tm.period()))
    }

    /// Step 4 on a Taylor step of length `s_end`: the closed-contact times, the channels'
    /// extremes (on their polynomials, only to the degree the stretch needs: the remainder
    /// bound no larger than the full step's, `taylor::degree_for_reach`), the dissipated
    /// energy (both only with [`Options::levels`]), and the state at the end.
    fn book_taylor(&mut self, mi: usize, tau: f64, period: f64, s_end: f64) -> Result<()> {
        let (t, mode) = (self.t, self.mode);
        self.closed_time(s_end);
        if self.opts.levels {
            let mc = mode_channels(
                &mut self.channels,
                &self.map,
                self.sys,
                &mut self.selector,
                mode,
                false,
                &mut self.chan_buf,
            )?;
            for &c in mc.zeros() {
                self.totals.peaks.0[c].offer(0.0, t);
            }
            let tw = &self.tw;
            let tm = tw.tmats[mi]
                .as_ref()
                .ok_or_else(|| Error::numerical("exact", "Taylor matrix"))?;
            let deg = tm.degree(s_end);
            for (r, &c) in mc.moving().iter().enumerate() {
                mc.project(r, &tw.coef, deg, &mut self.chan_poly);
                peaks::on_poly(
                    &self.chan_poly,
                    deg,
                    tau,
                    period,
                    t,
                    s_end,
                    &mut self.totals.peaks.0[c],
                );
            }
        }
        let tw = &mut self.tw;
        let tm = tw.tmats[mi]
            .as_ref()
            .ok_or_else(|| Error::numerical("exact", "Taylor matrix"))?;
        if self.opts.levels {
            self.totals.dissipated += tm
                .dissipated(&tw.coef, &self.masses, s_end, &mut tw.work)
                .ok_or_else(|| Error::numerical("exact", "first-order matrix without [0, I]"))?;
        }
        taylor::state(&tw.coef, s_end, &mut self.x);
        Ok(())
    }

    /// The closed-contact times over a stretch of length `s_end` in the current mode.
    fn closed_time(&mut self, s_end: f64) {
        for ci in 0..2 {
            if closed(self.sys, self.mode, ci) {
                self.totals.closed_time[ci] += s_end;
            }
        }
    }

    /// The closed form of mode `mi`, built on first use (with the output step's transition
    /// matrix when there is an output grid and no forcing: with a forcing the samples are
    /// evaluated one by one, the transition matrix propagating the deviation from the
    /// particular solution only).
    fn closed_form(&mut self, mi: usize) -> Result<Rc<ModeData>> {
        if self.cache[mi].is_none() {
            let n = self.x.len();
            let (k, c) = self.sys.matrices(self.mode);
            let am = self.selector.matrix(self.mode);
            let a = Mat::from_fn(n, n, |i, j| am[j * n + i]);
            let force_2nd = self.force_2nd.as_deref();
            let prop = Propagator::shared_forced(&k, &c, &self.masses, a, force_2nd)?;
            let step = match &self.grid {
                Some(g) if !prop.is_forced() => Some(prop.transition(g.dt)),
                _ => None,
            };
            self.cache[mi] = Some(Rc::new(ModeData {
                prop,
                damping: c,
                step,
            }));
        }
        self.cache[mi]
            .clone()
            .ok_or_else(|| Error::numerical("exact", "mode cache"))
    }

    /// A stretch in closed form in mode `mi`: the first switch before the end of the run
    /// (steps 1-2 of the module documentation), the output samples (3), and the peaks, contact
    /// times and dissipation (4); `x` is left at the stretch's end.
    fn closed_stretch(&mut self, mi: usize, obs: &mut dyn Observer) -> Result<Stretch> {
        let horizon = self.t_end - self.t;
        let md = self.closed_form(mi)?;
        let prop = &*md.prop;
        let seg = prop.segment(&self.x);
        let period = prop.period();
        // 1-2: the first switch.
        let found = {
            let funcs: Vec<Functional<'_>> = self
                .selector
                .vectors()
                .iter()
                .map(|l| seg.functional(l))
                .collect();
            let mut closed_searches: Vec<Search<Lifted<&Functional<'_>>>> = funcs
                .iter()
                .zip(&self.signs)
                .zip(self.selector.vectors())
                .filter(|((_, s), _)| **s != 0.0)
                .map(|((f, s), l)| {
                    let v = l.iter().zip(&self.x).map(|(a, b)| a * b).sum();
                    Search::new(Lifted::new(f, v, *s), *s, SearchOptions::default())
                })
                .collect();
            first_switch(&mut closed_searches, period, horizon)
        };
        let (s_end, switched) = stretch_end(found, horizon, true);
        let run_ends = !switched;
        // 3: output samples.
        if let Some(g) = self.grid.as_mut() {
            let state = |s: f64, out: &mut [f64]| seg.state(s, out);
            let span = (self.t, s_end, run_ends, self.t_end);
            let step = md.step.as_ref();
            let (buf, buf2) = (&mut self.buf, &mut self.buf2);
            emit_samples(g, span, self.mode, &state, step, obs, buf, buf2);
        }
        self.book_closed(&seg, &md.damping, s_end)?;
        Ok(Stretch {
            s_end,
            switched,
            run_ends,
            period,
        })
    }

    /// Step 4 on a closed-form stretch of length `s_end`: the closed-contact times, the
    /// channels' extremes (`peaks::on_segment`), the dissipated energy `∫ ẋᵀC_σẋ dt`
    /// (`damping` = `C_σ`; both only with [`Options::levels`]), and the state at the end.
    fn book_closed(&mut self, seg: &Segment<'_>, damping: &Mat<f64>, s_end: f64) -> Result<()> {
        let (t, mode) = (self.t, self.mode);
        let n = self.x.len();
        self.closed_time(s_end);
        if self.opts.levels {
            let mc = mode_channels(
                &mut self.channels,
                &self.map,
                self.sys,
                &mut self.selector,
                mode,
                true,
                &mut self.chan_buf,
            )?;
            for &c in mc.zeros() {
                self.totals.peaks.0[c].offer(0.0, t);
            }
            let slope_len = n + usize::from(self.forcing.is_some());
            for ((&c, l), la) in mc
                .moving()
                .iter()
                .zip(mc.dense.chunks_exact(n))
                .zip(mc.slopes.chunks_exact(slope_len))
            {
                peaks::on_segment(seg, l, la, t, s_end, &mut self.totals.peaks.0[c]);
            }
        }
        if self.opts.levels {
            self.totals.dissipated += dissipated(seg, damping, n / 2, s_end);
        }
        seg.state(s_end, &mut self.buf);
        self.x.copy_from_slice(&self.buf);
        Ok(())
    }

    /// After a stretch of length `s_end` that ended on a switch (`t` advanced from
    /// `t_before`): whether it made no progress (shorter than round-off of the time scale, or
    /// not moving `t` at all: 2.5e-17 s at t = 3.7 s) and whether it was a micro-stretch
    /// ([`MICRO_STRETCH`]). More than 50 stretches without progress in a row, or more than
    /// [`MAX_MICRO_STRETCHES`] micro-stretches, are an error.
    fn progress(&mut self, s_end: f64, period: f64, t_before: f64) -> Result<(bool, bool)> {
        let (t, mode) = (self.t, self.mode);
        let no_progress = s_end <= 1e-14 * period.min(self.t_end) || t == t_before;
        if no_progress {
            self.zero_length += 1;
            if self.zero_length > 50 {
                return Err(Error::numerical(
                    "exact propagator",
                    format!(
                        "switches chatter at t = {t:.9e} s without time advancing (mode {:?})",
                        mode
                    ),
                ));
            }
        } else {
            self.zero_length = 0;
        }
        // A stretch far shorter than the time scale that ended without changing the mode: the
        // search saw an indicator leave its side, but the selection keeps the side (a
        // derivative within its round-off band taken as zero, a higher one of the other sign).
        let micro = !no_progress && s_end <= MICRO_STRETCH * period.min(self.t_end);
        if micro {
            self.micro_stretches += 1;
            if self.micro_stretches > MAX_MICRO_STRETCHES {
                return Err(Error::numerical(
                    "exact propagator",
                    format!(
                        "{MAX_MICRO_STRETCHES} stretches shorter than {MICRO_STRETCH:e} of the \
                         time scale in a row at t = {t:.9e} s (mode {mode:?}): the switch \
                         indicators do not settle"
                    ),
                ));
            }
        } else {
            self.micro_stretches = 0;
        }
        Ok((no_progress, micro))
    }

    /// Step 5: the new mode at the switch, and the indicators' sides under its dynamics (those
    /// of the mode taken when no mode is consistent), with the trajectory deciding after a
    /// micro-stretch ([`Run::settle_micro`]) and an indicator at rest at zero left unsearched.
    fn next_mode(&mut self, no_progress: bool, micro: bool) -> Mode {
        let mode = self.mode;
        self.searched_signs.copy_from_slice(&self.signs);
        let (mut new_mode, _) = self.selector.select(&self.x, mode, &mut self.signs);
        if micro && new_mode == mode {
            new_mode = self.settle_micro(new_mode);
        }
        if no_progress && new_mode == mode && self.forcing.is_some() {
            // Resting contact under a constant force: an indicator that "crossed" without time
            // advancing and without changing the mode is at zero within round-off (a dashpot's
            // relative velocity at rest against static forces of 1e5 N/m·mm). It is not
            // searched (sign 0) until the next switch that changes the mode, so the run
            // progresses instead of re-finding the same crossing.
            for (sg, l) in self.signs.iter_mut().zip(self.selector.vectors()) {
                let v: f64 = l.iter().zip(&self.x).map(|(a, b)| a * b).sum();
                if *sg * v <= 0.0 {
                    *sg = 0.0;
                }
            }
        }
        new_mode
    }

    /// After a micro-stretch that kept the mode, the trajectory decides what the derivatives
    /// cannot: an indicator that left the side it was searched from (its value now of the
    /// other sign, where the stretch's closed form took it) takes the side it went to, and the
    /// mode follows (returned; `new_mode` if none moved). Without this a dashpot velocity
    /// falling at 1.02e-6 m/s² (round-off band 1.05e-6 m/s², second derivative +2.5e-5 m/s³)
    /// is re-found 3e-15 s later, millions of times.
    fn settle_micro(&mut self, new_mode: Mode) -> Mode {
        let signs = &mut self.signs;
        self.moved.fill(false);
        for (i, l) in self.selector.vectors().iter().enumerate() {
            let was = self.searched_signs[i];
            let v: f64 = l.iter().zip(&self.x).map(|(a, b)| a * b).sum();
            if was != 0.0 && was * v < 0.0 && signs[i] == was {
                signs[i] = -was;
                self.moved[i] = true;
            }
        }
        if !self.moved.iter().any(|&m| m) {
            return new_mode;
        }
        let new_mode = self.selector.implied(signs);
        // The other indicators' sides under the new mode's dynamics.
        let kept = signs.clone();
        self.selector.signs(new_mode, &self.x, signs);
        for (i, sg) in signs.iter_mut().enumerate() {
            if self.moved[i] {
                *sg = kept[i];
            }
        }
        new_mode
    }

    /// The switch to `new_mode` at `t`: a contact released by the force rule takes its elastic
    /// energy with it (counted as dissipated); the path point and the event are recorded, and
    /// more than `opts.max_events` is an error.
    fn switch_to(&mut self, new_mode: Mode) -> Result<()> {
        let (t, mode) = (self.t, self.mode);
        if self.opts.levels {
            self.totals.dissipated +=
                super::dopri5::contact_energy_jump(self.sys, mode, new_mode, &self.x);
        }
        self.path.push(PathPoint {
            t,
            mode: new_mode,
            x: self.x.clone(),
        });
        self.events.push(Event {
            t,
            from: mode,
            to: new_mode,
        });
        if self.events.len() > self.opts.max_events {
            return Err(super::too_many_events(
                "exact propagator",
                &self.events,
                self.opts.max_events,
                t,
            ));
        }
        Ok(())
    }

    /// Records the end of the collision (both contacts open) the first time it is reached;
    /// true if it was reached now.
    fn collision_ends(&mut self) -> bool {
        let mode = self.mode;
        if self.collision_end.is_some() || mode.on(Switch::SliderBed) || mode.on(Switch::BedDamper)
        {
            return false;
        }
        self.collision_end = Some(CollisionEnd {
            t: self.t,
            x: self.x.clone(),
            totals: self.totals,
        });
        true
    }

    /// The sample at `t_end`, if still due, after a switch at the very end of the run.
    fn last_sample(&mut self, obs: &mut dyn Observer) {
        if let Some(g) = self.grid.as_mut() {
            let xe = self.x.clone();
            let state = |_: f64, out: &mut [f64]| out.copy_from_slice(&xe);
            let span = (self.t, 0.0, true, self.t_end);
            let (buf, buf2) = (&mut self.buf, &mut self.buf2);
            emit_samples(g, span, self.mode, &state, None, obs, buf, buf2);
        }
    }

    /// The finished run: its events, path, totals and counts (the closed forms built by the
    /// matrix-exponential fallback among them).
    fn finish(self) -> Solution {
        let fallback_modes = self
            .cache
            .iter()
            .flatten()
            .filter(|m| !m.prop.is_spectral())
            .count();
        Solution {
            events: self.events,
            path: self.path,
            collision_end: self.collision_end,
            t_final: self.t,
            x_final: self.x,
            mode_final: self.mode,
            totals: self.totals,
            steps: self.segments,
            taylor_steps: self.taylor_steps.iter().sum(),
            rejected: 0,
            fallback_modes,
        }
    }
}

/// A stretch that ends at a switch after at most this fraction of the fastest period, without
/// changing the mode, is a *micro-stretch*: the trajectory, not the derivatives' signs, then
/// decides the side of the indicator that crossed.
const MICRO_STRETCH: f64 = 1e-9;
/// More micro-stretches than this in a row are an error (never a hang).
const MAX_MICRO_STRETCHES: usize = 1000;

/// An indicator searched from the side the mode selection gave it. The selection decides an
/// indicator within its zero band (`1e-9` of its terms, `switching::lex_signs`) by its
/// derivatives; when the value `v` itself is then on the other side (a contact overlapping by
/// 6e-13 m at a static preload of 1e-3 m, moving apart), that start is taken as zero: the
/// noise is raised to `|v|` plus the function's own, so the search does not report the start
/// as a crossing (a zero-length stretch, again and again), and reports a real return across
/// zero. Otherwise the function is unchanged.
pub(crate) struct Lifted<F> {
    f: F,
    noise: f64,
}

impl<F: Scalar> Lifted<F> {
    pub(crate) fn new(f: F, value: f64, sign: f64) -> Self {
        let own = f.noise();
        let noise = if value * sign < 0.0 {
            own + value.abs()
        } else {
            own
        };
        Self { f, noise }
    }
}

impl<F: Scalar> Scalar for Lifted<F> {
    #[inline]
    fn value_slope(&self, s: f64) -> (f64, f64) {
        self.f.value_slope(s)
    }
    #[inline]
    fn curvature_bound(&self, a: f64, b: f64) -> f64 {
        self.f.curvature_bound(a, b)
    }
    #[inline]
    fn fastest_period(&self) -> f64 {
        self.f.fastest_period()
    }
    #[inline]
    fn noise(&self) -> f64 {
        self.noise
    }
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
            Some(e) if !k.is_multiple_of(64) => {
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
/// indicators being searched (each search started with the indicator's side at the start;
/// those identically zero left out). All are searched over common windows growing from one
/// fastest period, so the search ends at the earliest crossing; only the earliest bracket is
/// refined (and any other bracket starting before its root), in the order of their starts.
pub(crate) fn first_switch<F: Scalar>(
    searches: &mut [Search<F>],
    period: f64,
    horizon: f64,
) -> Option<f64> {
    let mut limit = if period.is_finite() {
        period.min(horizon)
    } else {
        horizon
    };
    loop {
        let mut any = false;
        for sr in searches.iter_mut() {
            any |= sr.advance(limit).is_some();
        }
        if any {
            // Brackets by increasing start (ties by index), without sorting into a buffer.
            let mut first = f64::INFINITY;
            let mut last: Option<(f64, usize)> = None;
            loop {
                let next = searches
                    .iter()
                    .enumerate()
                    .filter_map(|(i, sr)| sr.found().map(|(a, b)| (a, b, i)))
                    .filter(|&(a, _, i)| last.is_none_or(|(la, li)| (a, i) > (la, li)))
                    .min_by(|p, q| p.0.total_cmp(&q.0).then(p.2.cmp(&q.2)));
                let Some((a, b, i)) = next else { break };
                if a < first {
                    first = first.min(searches[i].refine(a, b));
                }
                last = Some((a, i));
            }
            return Some(first);
        }
        if limit >= horizon {
            return None;
        }
        limit = (4.0 * limit).min(horizon);
    }
}

/// The response channels of one mode: those that move (their vectors `ℓ_σ` as non-zeros for
/// the Taylor projections and, once a closed-form segment needs them, dense with the slope
/// vectors `ℓ_σᵀA_σ`), and those identically zero in it. One allocation per mode met (two more
/// for a mode with a closed form).
struct ModeChannels {
    /// Channel indices of the moving channels (`moving` of them), then of the zero ones.
    index: [usize; N_CHANNELS],
    moving: usize,
    zero: [usize; N_CHANNELS],
    n_zero: usize,
    /// Row `r`'s non-zeros `(i, ℓ_i)` are `nz[nz_off[r] .. nz_off[r + 1]]`.
    nz_off: [usize; N_CHANNELS + 1],
    nz: Vec<(usize, f64)>,
    /// Rows of `n` (built with the slopes).
    dense: Vec<f64>,
    /// Built when a closed-form segment first needs them.
    slopes: Vec<f64>,
}

impl ModeChannels {
    /// Channel indices of the moving channels.
    fn moving(&self) -> &[usize] {
        &self.index[..self.moving]
    }
    /// Channel indices of the channels identically zero in the mode.
    fn zeros(&self) -> &[usize] {
        &self.zero[..self.n_zero]
    }
    /// The coefficients `ℓ_rᵀc_k`, k = 0..=deg, of moving channel `r` on a Taylor step
    /// (`coef`: rows of `n`); those above `deg` are left zero.
    #[inline(never)]
    fn project(&self, r: usize, coef: &[f64], deg: usize, out: &mut taylor::Coefficients) {
        let nz = &self.nz[self.nz_off[r]..self.nz_off[r + 1]];
        let n = coef.len() / out.len();
        out.fill(0.0);
        for &(i, v) in nz {
            if i < n {
                for (o, ck) in out.iter_mut().zip(coef.chunks_exact(n)).take(deg + 1) {
                    *o += v * ck[i];
                }
            }
        }
    }
}

/// The channels of `mode`, built on first use (with their dense and slope vectors when
/// `need_slopes`). `buf` is scratch space for [`ChannelMap::vectors_into`].
#[allow(clippy::too_many_arguments)]
fn mode_channels<'c>(
    cache: &'c mut [Option<ModeChannels>; MODES],
    map: &ChannelMap,
    sys: &ImpactSystem,
    selector: &mut ModeSelector,
    mode: Mode,
    need_slopes: bool,
    buf: &mut Vec<f64>,
) -> Result<&'c ModeChannels> {
    let mi = usize::from(mode.0) % MODES;
    let n = 2 * sys.dofs();
    let vectors = |buf: &mut Vec<f64>| {
        buf.resize(N_CHANNELS * n, 0.0);
        map.vectors_into(sys, mode, buf)
            .ok_or_else(|| Error::numerical("exact", "a closed contact has a non-linear law"))
    };
    let kept = |c: Channel| !(c.needs_damper() && sys.damper.is_none());
    if cache[mi].is_none() {
        vectors(buf)?;
        let mut mc = ModeChannels {
            index: [0; N_CHANNELS],
            moving: 0,
            zero: [0; N_CHANNELS],
            n_zero: 0,
            nz_off: [0; N_CHANNELS + 1],
            nz: Vec::with_capacity(buf.iter().filter(|v| **v != 0.0).count()),
            dense: Vec::new(),
            slopes: Vec::new(),
        };
        for (c, l) in CHANNELS.into_iter().zip(buf.chunks_exact(n)) {
            if !kept(c) {
                continue;
            }
            if l.iter().all(|v| *v == 0.0) {
                mc.zero[mc.n_zero] = c.index();
                mc.n_zero += 1;
                continue;
            }
            mc.index[mc.moving] = c.index();
            mc.nz.extend(
                l.iter()
                    .enumerate()
                    .filter(|(_, v)| **v != 0.0)
                    .map(|(i, v)| (i, *v)),
            );
            mc.moving += 1;
            mc.nz_off[mc.moving] = mc.nz.len();
        }
        cache[mi] = Some(mc);
    }
    if need_slopes {
        if let Some(mc) = cache[mi].as_mut().filter(|mc| mc.slopes.is_empty()) {
            vectors(buf)?;
            mc.dense = CHANNELS
                .into_iter()
                .zip(buf.chunks_exact(n))
                .filter(|(c, _)| kept(*c) && mc.index[..mc.moving].contains(&c.index()))
                .flat_map(|(_, l)| l.iter().copied())
                .collect();
            // ℓᵀA with A column-major: (ℓᵀA)_j = Σ_i ℓ_i A_ij; with a constant forcing b the
            // slope is the affine ℓᵀA X + ℓᵀb, ℓᵀb appended (an augmented-state functional,
            // `Segment::functional`).
            let b = sys.forcing();
            let a = selector.matrix(mode);
            mc.slopes = mc
                .dense
                .chunks_exact(n)
                .flat_map(|l| {
                    let lb = b
                        .as_ref()
                        .map(|b| b.iter().zip(l).map(|(x, y)| x * y).sum());
                    (0..n)
                        .map(move |j| {
                            a[j * n..(j + 1) * n]
                                .iter()
                                .zip(l)
                                .map(|(x, y)| x * y)
                                .sum()
                        })
                        .chain(lb)
                })
                .collect();
        }
    }
    cache[mi]
        .as_ref()
        .ok_or_else(|| Error::numerical("exact", "channel cache"))
}

/// 8-point Gauss-Legendre rule on [−1, 1]: the positive nodes and their weights.
pub(crate) const GL_X: [f64; 4] = [
    0.1834346424956498,
    0.525_532_409_916_329,
    0.7966664774136267,
    0.9602898564975363,
];
pub(crate) const GL_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.3137066458778873,
    0.2223810344533745,
    0.1012285362903763,
];

/// `∫₀^len ẋᵀ C ẋ ds` on a closed-form segment: exactly for the spectral form
/// (`ẋ = Re Σ β_k e^{λ_k s}`, so the integrand is a sum of exponentials), otherwise (the
/// matrix-exponential fallback) by 8-point Gauss-Legendre quadrature on sub-intervals of a
/// quarter of the fastest period. Taylor steps have [`taylor_dissipated`].
pub(crate) fn dissipated(seg: &Segment<'_>, c: &Mat<f64>, nd: usize, len: f64) -> f64 {
    if len <= 0.0 || c.norm_l2() == 0.0 {
        return 0.0;
    }
    if let Some((beta, lam)) = seg.velocity_terms() {
        // ẋᵀCẋ = ½ Σ_kl Re[(β_kᵀCβ_l) e^{(λ_k+λ_l)s} + (β_kᵀCβ̄_l) e^{(λ_k+λ̄_l)s}]; with a
        // forcing, ẋ also has the particular x_1 + x_2 s (C x_2 = 0: x_2 is rigid motion), so
        // + 2 Re Σ_k (x_1ᵀCβ_k) e^{λ_k s} + x_1ᵀCx_1.
        let mut extra = 0.0;
        if let Some((x1, _)) = seg.particular_velocity() {
            if x1.iter().any(|v| *v != 0.0) {
                let cx1: Vec<f64> = (0..nd)
                    .map(|i| (0..nd).map(|j| c[(i, j)] * x1[j]).sum())
                    .collect();
                extra += len * x1.iter().zip(&cx1).map(|(a, b)| a * b).sum::<f64>();
                for (b, l) in beta.iter().zip(&lam) {
                    let p = b
                        .iter()
                        .zip(&cx1)
                        .fold(c64::new(0.0, 0.0), |acc, (bi, ci)| acc + bi * ci);
                    extra += 2.0 * (p * exp_integral(*l, len)).re;
                }
            }
        }
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
        return total + extra;
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
pub(crate) fn exp_integral(z: c64, t: f64) -> c64 {
    let zt = z * t;
    if zt.norm() < 1e-4 {
        t * (1.0 + zt / 2.0 + zt * zt / 6.0 + zt * zt * zt / 24.0)
    } else {
        (zt.exp() - 1.0) / z
    }
}
