//! Repeated blows at a stroke rate: the machine, the damper and the floor keep their state
//! from one blow to the next; only the slider is fresh.
//!
//! # Formulation
//!
//! Blow `k` (`k = 0..N-1`) starts at `t_k = k T`, `T = 60 / rate` s exactly (it used to be
//! rounded to whole output samples, so every number depended on `--rate`: at 70 /min the
//! floor force of blow 6 was 82.33 N at 20 kHz and 82.93 N at 300 Hz). The record stays on
//! one uniform grid `t = i/f_s`: blow `k` is sampled from its strike with the phase
//! `⌈t_k f_s⌉/f_s − t_k` ([`crate::integrate::Options::sample_phase_s`]). It is the impact
//! engine run over `[0, T]` ([`crate::integrate::solve_from`]) from the final state of blow
//! `k-1` with the slider replaced: `z_s = u_b(O_b) = ψ(O_b)ᵀq` (just touching, overlap 0) and
//! `ż_s = v_s`. The first blow starts from rest ([`ImpactSystem::initial_state`]), so one
//! blow of length `T` is exactly [`super::simulate`] with `duration = T`. The rebounding slider
//! of the previous blow is removed with its kinetic energy (it has left the die).
//!
//! Per blow we report the energy share the blow left in the machine,
//!
//! ```text
//! η_k = (E_s− − E_s+ − (E_d+ − E_d,k−)) / E_s−       (paper Eq. 10, with the damper's
//!                                                    energy at the start of the blow removed)
//! ```
//!
//! (`E_d = ½ m_d ż_d² + ½ k_d (z_d − u_f)²`; for the first blow `E_d,0− = 0` and `η_0` is the
//! paper's `E_p+/E_s−`), the machine energy `KE_p + PE_p` left from earlier blows at the
//! strike, and the peak bed acceleration at B, floor force and slider-bed contact force of
//! the blow. **Steady state**: the blow-to-blow relative change of the peak floor force, the
//! peak bed acceleration and `η` all below a tolerance (default 1 %).
//!
//! For a damper, each blow also reports the gap `z_d − u_b(O_b)` at the strike and the time
//! the bed-damper contact was closed: with the paper's one-way dashpot (Eq. 7) the damper
//! returns with the slow root of an overdamped oscillator (time constant ≈ c_d/k_d, 0.39 s on
//! the paper example) and the dashpot rectifies the base's residual vibration
//! (`k_d ⟨z_d − u_f⟩ = c_d ⟨max(−(ż_d − u̇_f), 0)⟩`), so at stroke rates faster than its
//! return the damper no longer touches the bed after the first blow. docs/explanations/blows.md gives the
//! figures, and the comb filter of the rigid-body mode that makes a single stroke rate a poor
//! basis for comparing cases.
//!
//! **The interval must outlast the collision**: a blow whose collision (slider-bed or bed-damper
//! contact closed) has not ended at the next strike, `t_c > T`, is refused with `t_c` (found by
//! running the blow on until its collision ends) and the largest valid rate `60 / T_min`,
//! `T_min = ⌈t_c f_s⌉ / f_s`. A machine still moving at the strike is accepted: that is what a
//! train is for. The reported damper gap is `max(z_d − u_b, 0)` (a closed contact's compression
//! is no gap).
//!
//! Chaining restarts of the existing engine (rather than a periodic-forcing engine) keeps the
//! exact propagator and its event location unchanged: a new blow is just a new initial state.

use serde::Serialize;

use super::energy::{check_run, Balance, EnergyTerms, History, Recorder};
use crate::impact::{dot, Channel, ImpactSystem, Mode, Switch};
use crate::integrate::{self, Options, Solution};
use crate::{Error, Result};

/// Settings of a blow train.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlowOptions {
    /// Number of blows N ≥ 1.
    pub blows: usize,
    /// Stroke rate (blows per minute), > 0.
    pub rate_bpm: f64,
    /// Relative blow-to-blow change below which the train counts as steady.
    pub steady_tolerance: f64,
}

impl Default for BlowOptions {
    fn default() -> Self {
        Self {
            blows: 10,
            rate_bpm: 60.0,
            steady_tolerance: 0.01,
        }
    }
}

/// What one blow did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlowReport {
    /// 1-based blow number.
    pub blow: usize,
    /// Strike time t_k (s).
    pub start_s: f64,
    /// η_k (see the module docs); `None` if the collision did not end within the blow.
    pub energy_ratio: Option<f64>,
    /// End of the collision after the strike (s), if it ended.
    pub collision_end_s: Option<f64>,
    /// KE_p + PE_p of the structure at the strike (J): what earlier blows left.
    pub machine_energy_at_strike_j: f64,
    /// E_d of the damper at the strike (J).
    pub damper_energy_at_strike_j: f64,
    /// Gap `max(z_d − u_b(O_b), 0)` between the damper and the bed at the strike (m): 0 when
    /// the damper is back against the bed (the contact closed, its compression is no gap),
    /// positive when it has not returned (it then cannot take the blow's momentum until the
    /// bed has travelled the gap). Never negative. `None` without a damper.
    pub damper_gap_at_strike_m: Option<f64>,
    /// Time the bed-damper contact was closed during the blow interval (s); 0 when the damper
    /// never touched the bed. `None` without a damper.
    pub damper_contact_time_s: Option<f64>,
    pub peak_bed_acceleration_m_per_s2: f64,
    pub peak_floor_force_n: f64,
    pub peak_contact_force_slider_bed_n: f64,
}

/// Convergence of the train to a steady blow-to-blow level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Steady {
    /// True when the last two blows differ by less than the tolerance in every level.
    pub converged: bool,
    /// The first blow (1-based) from which every later blow stays within the tolerance of
    /// its predecessor.
    pub from_blow: Option<usize>,
    /// Relative changes between the last two blows (0 with a single blow).
    pub last_change_peak_floor_force: f64,
    pub last_change_peak_bed_acceleration: f64,
    pub last_change_energy_ratio: f64,
    /// Levels of the last blow.
    pub peak_floor_force_n: f64,
    pub peak_bed_acceleration_m_per_s2: f64,
    pub energy_ratio: Option<f64>,
}

/// A finished train.
#[derive(Debug, Clone)]
pub struct BlowsRun {
    /// Blow interval T actually used (s).
    pub interval_s: f64,
    pub blows: Vec<BlowReport>,
    pub steady: Steady,
    /// Gap `max(z_d − u_b, 0)` at the end of the last interval, i.e. at the next strike (m); `None`
    /// without a damper.
    pub damper_gap_at_next_strike_m: Option<f64>,
    /// Concatenated histories on one uniform grid (when recorded); `dissipated_j` is the
    /// energy dissipated since t = 0.
    pub history: Option<History>,
    /// Each blow's run (times relative to its strike at `blows[k].start_s`): the paths the
    /// exact spectrum of the train is built from ([`super::esd::Trajectory::append`]).
    pub solutions: Vec<Solution>,
}

/// The blow interval for a stroke rate, `T = 60/R` s exactly (the output sample rate does
/// not change it: the samples of each blow are put on the train's grid instead, see the
/// module docs).
pub fn blow_interval_s(rate_bpm: f64) -> Result<f64> {
    if !(rate_bpm.is_finite() && rate_bpm > 0.0) {
        return Err(Error::invalid(
            "rate_bpm",
            format!("the stroke rate must be > 0 blows per minute (got {rate_bpm})"),
        ));
    }
    Ok(60.0 / rate_bpm)
}

/// The phase `φ_k = ⌈t_k f_s⌉/f_s − t_k ∈ [0, 1/f_s)` of the first train sample `i/f_s` at or
/// after the strike `t_k` ([`Options::sample_phase_s`]); a phase below 1e-9/f_s (rounding of a
/// strike on the grid) is 0, so that sample is the previous blow's last one (dropped).
fn strike_phase(t_k: f64, fs: f64) -> f64 {
    let dt = 1.0 / fs;
    let phase = (t_k * fs).ceil() / fs - t_k;
    if phase < 1e-9 * dt || phase >= dt * (1.0 - 1e-9) {
        0.0
    } else {
        phase
    }
}

/// A stroke rate rounded to 4 significant digits, up (`up`) or down, so that the rate printed
/// is still on the valid side of a limit.
fn rate_4_digits(r: f64, up: bool) -> f64 {
    let scale = 10f64.powi(3 - r.log10().floor() as i32);
    let v = r * scale;
    (if up { v.ceil() } else { v.floor() }) / scale
}

fn relative_change(a: f64, b: f64) -> f64 {
    let scale = a.abs().max(b.abs());
    if scale == 0.0 {
        0.0
    } else {
        (a - b).abs() / scale
    }
}

/// Runs `blow.blows` blows of `sys` every `60 / blow.rate_bpm` s. `opts.duration` is ignored
/// (the blow interval is the duration of each run); `opts.sample_rate` is the output grid.
/// With `record`, the concatenated history is held in memory ([`BlowsRun::history`]); the
/// estimate of that and of the kept per-blow solutions is checked against
/// [`crate::limits::max_memory`] before the first blow.
pub fn run_blows(
    sys: &ImpactSystem,
    opts: &Options,
    blow: &BlowOptions,
    record: bool,
) -> Result<BlowsRun> {
    if record {
        let interval = blow_interval_s(blow.rate_bpm)?;
        let n = blow.blows as f64 * super::energy::sample_count(interval, opts.sample_rate);
        crate::limits::check_memory(
            &format!(
                "the history of {} blows ({n:.3e} samples × {} B)",
                blow.blows,
                super::energy::HISTORY_SAMPLE_BYTES
            ),
            History::bytes_for(n),
            "blows",
            "the number of blows (--blows) or simulation.sample_rate (--rate)",
        )?;
    }
    let mut history = record.then(History::default);
    if let Some(h) = history.as_mut() {
        let interval = blow_interval_s(blow.rate_bpm)?;
        let n = blow.blows as f64 * super::energy::sample_count(interval, opts.sample_rate);
        h.reserve(n as usize + 2);
    }
    let mut sink = |b: &History| -> Result<()> {
        if let Some(h) = history.as_mut() {
            extend(h, b);
        }
        Ok(())
    };
    let mut run = run_blows_with(
        sys,
        opts,
        blow,
        if record { Some(&mut sink) } else { None },
        true,
    )?;
    run.history = history;
    Ok(run)
}

/// Memory (bytes) a blow train holds besides the samples: one [`BlowReport`] per blow, and one
/// [`Solution`] per blow when kept (its path and events counted at their minimum, the strike
/// and the end of the blow).
pub fn train_bytes(sys: &ImpactSystem, blows: usize, keep_solutions: bool) -> f64 {
    let per_blow = std::mem::size_of::<BlowReport>() as f64
        + if keep_solutions {
            let state = (2 * sys.dofs() * 8) as f64;
            (std::mem::size_of::<Solution>()
                + 2 * std::mem::size_of::<integrate::PathPoint>()
                + std::mem::size_of::<integrate::CollisionEnd>()) as f64
                + 4.0 * state
        } else {
            0.0
        };
    blows as f64 * per_blow
}

/// Receives the samples of each blow of a train ([`run_blows_with`]).
pub type HistorySink<'a> = dyn FnMut(&History) -> Result<()> + 'a;

/// [`run_blows`] handing each blow's samples (times from the train's start, the first sample
/// of a later blow dropped, `dissipated_j` since t = 0) to `on_history` as soon as the blow is
/// done, instead of holding the train's history: with a sink that writes them to a file, a
/// train of any length is recorded in the memory of one blow. `keep_solutions` keeps each
/// blow's [`Solution`] ([`BlowsRun::solutions`], for the exact spectrum of the train);
/// without it that list is empty. [`BlowsRun::history`] is `None`.
pub fn run_blows_with(
    sys: &ImpactSystem,
    opts: &Options,
    blow: &BlowOptions,
    on_history: Option<&mut HistorySink<'_>>,
    keep_solutions: bool,
) -> Result<BlowsRun> {
    run_blows_progress(sys, opts, blow, on_history, keep_solutions, &|_, _| {})
}

/// [`run_blows_with`] calling `progress(blows done, blows)` after each blow.
pub fn run_blows_progress(
    sys: &ImpactSystem,
    opts: &Options,
    blow: &BlowOptions,
    on_history: Option<&mut HistorySink<'_>>,
    keep_solutions: bool,
    progress: &dyn Fn(usize, usize),
) -> Result<BlowsRun> {
    run_blows_each(sys, opts, blow, on_history, keep_solutions, progress, None)
}

/// Receives each blow's run: `(blow, 1-based; its strike time in the train, s; its run)`.
pub type BlowSink<'a> = dyn FnMut(usize, f64, &Solution) -> Result<()> + 'a;

/// [`run_blows_progress`] handing each blow's run to `on_blow` (when given) as it ends: the
/// per-impact table of a train ([`super::impacts::blow_impacts`]) without keeping the runs.
pub fn run_blows_each(
    sys: &ImpactSystem,
    opts: &Options,
    blow: &BlowOptions,
    mut on_history: Option<&mut HistorySink<'_>>,
    keep_solutions: bool,
    progress: &dyn Fn(usize, usize),
    mut on_blow: Option<&mut BlowSink<'_>>,
) -> Result<BlowsRun> {
    let record = on_history.is_some();
    if blow.blows == 0 {
        return Err(Error::invalid("blows", "needs at least one blow"));
    }
    if !(blow.steady_tolerance.is_finite() && blow.steady_tolerance > 0.0) {
        return Err(Error::invalid(
            "steady_tolerance",
            format!("must be > 0 (got {})", blow.steady_tolerance),
        ));
    }
    let interval = blow_interval_s(blow.rate_bpm)?;
    // The train is one run chained: the same time bound as a single run
    // ([`integrate::check_cost`]) over its whole simulated time `N · T`.
    if let Some((rate, what)) = integrate::fastest_rate(sys) {
        let periods = blow.blows as f64 * interval * rate / (2.0 * std::f64::consts::PI);
        if periods > integrate::MAX_PERIODS
            && interval * rate / (2.0 * std::f64::consts::PI) > integrate::MAX_PERIODS
        {
            // One blow alone is too long: the rate is too low (more blows would not help).
            let t_max = integrate::MAX_PERIODS * 2.0 * std::f64::consts::PI / rate;
            let r_min = rate_4_digits(60.0 / t_max, true);
            return Err(Error::invalid(
                "stroke rate (--rate-bpm)",
                format!(
                    "one blow every {interval} s (--rate-bpm {}) would span {:.2e} periods of \
                     the fastest time scale (2π/{rate:.3e} s, set by {what}); the limit is {:e} \
                     per run. Give --rate-bpm at least {}",
                    crate::num(blow.rate_bpm),
                    interval * rate / (2.0 * std::f64::consts::PI),
                    integrate::MAX_PERIODS,
                    crate::num(r_min)
                ),
            ));
        }
        if periods > integrate::MAX_PERIODS {
            return Err(Error::invalid(
                "blows",
                format!(
                    "{} blows of {interval} s would span {periods:.2e} periods of the fastest \
                     time scale (2π/{rate:.3e} s, set by {what}); the limit is {:e}. Reduce the \
                     number of blows (--blows) to at most {}",
                    blow.blows,
                    integrate::MAX_PERIODS,
                    (integrate::MAX_PERIODS * 2.0 * std::f64::consts::PI / (rate * interval))
                        .floor()
                ),
            ));
        }
    }
    {
        let per_blow_samples = if record {
            super::energy::sample_count(interval, opts.sample_rate)
        } else {
            0.0
        };
        crate::limits::check_memory(
            &format!(
                "a train of {} blows ({} B per blow{})",
                blow.blows,
                train_bytes(sys, 1, keep_solutions),
                if record {
                    format!(", and the history of one blow: {per_blow_samples:.3e} samples")
                } else {
                    String::new()
                }
            ),
            train_bytes(sys, blow.blows, keep_solutions) + History::bytes_for(per_blow_samples),
            "blows",
            "the number of blows (--blows)",
        )?;
    }
    let mut o = *opts;
    o.duration = interval;
    let mut x0 = sys.initial_state();
    let mut reports = Vec::with_capacity(blow.blows);
    let mut dissipated_before = 0.0;
    let mut solutions = Vec::with_capacity(if keep_solutions { blow.blows } else { 0 });
    for k in 0..blow.blows {
        let t0 = k as f64 * interval;
        let mut rec = Recorder::new(sys).starting_at(&x0);
        let o_blow = if record {
            let phase = o.sample_rate.map_or(0.0, |fs| strike_phase(t0, fs));
            Options {
                sample_phase_s: phase,
                ..o
            }
        } else {
            Options {
                sample_rate: None,
                ..o
            }
        };
        let done = one_blow(sys, &o_blow, opts, &x0, k, t0, blow.rate_bpm, &mut rec)?;
        if let Some(sink) = on_history.as_mut() {
            // The recorder counts dissipation as E_s− − Σ stored; add what was stored at the
            // strike besides the fresh slider, and what earlier blows dissipated.
            let offset = done.stored_at_strike_j - done.blow_energy_j + dissipated_before;
            let mut h = History::default();
            append(&mut h, std::mem::take(&mut rec.history), t0, k > 0, offset);
            sink(&h)?;
        }
        let sol = done.solution;
        if let Some(f) = on_blow.as_mut() {
            f(k + 1, t0, &sol)?;
        }
        reports.push(done.report);
        dissipated_before += sol.totals.dissipated;
        // The next strike: same structure and damper state, a fresh slider touching the bed.
        x0 = next_strike(sys, &sol.x_final);
        if keep_solutions {
            solutions.push(sol);
        }
        progress(k + 1, blow.blows);
    }
    let steady = steady_state(&reports, blow.steady_tolerance);
    Ok(BlowsRun {
        interval_s: interval,
        blows: reports,
        steady,
        damper_gap_at_next_strike_m: damper_gap(sys, &x0),
        history: None,
        solutions,
    })
}

/// One blow simulated ([`one_blow`]): its report, its run, and the energies that place its
/// history in a train.
pub(crate) struct BlowDone {
    pub report: BlowReport,
    pub solution: Solution,
    /// Everything stored at the strike, the fresh slider included (J).
    pub stored_at_strike_j: f64,
    /// The fresh slider's kinetic energy `E_s− = ½ m_s v_s²` (J).
    pub blow_energy_j: f64,
}

/// The damper's energy `E_d = ½ m_d ż_d² + ½ k_d (z_d − u_f)²` (J) at state `x`; 0 without a
/// damper.
pub(crate) fn damper_energy(sys: &ImpactSystem, x: &[f64]) -> f64 {
    let nd = sys.dofs();
    match &sys.damper {
        Some(d) => {
            let vd = x[nd + sys.damper_index()];
            let r = dot(sys.relative_vector(Switch::Dashpot), &x[..nd]);
            0.5 * d.mass * vd * vd + 0.5 * d.stiffness * r * r
        }
        None => 0.0,
    }
}

/// The gap `max(z_d − u_b(O_b), 0)` between damper and bed at state `x` (m); `None` without a
/// damper. A gap is ≥ 0: with the contact closed (the bed against the damper, overlap
/// δ = u_b − z_d > 0) it is 0; δ is the penalty contact's compression (δ = F/K_d for a linear
/// law), not a distance between the bodies. (`max` also turns −0 into 0.)
pub(crate) fn damper_gap(sys: &ImpactSystem, x: &[f64]) -> Option<f64> {
    let nd = sys.dofs();
    sys.damper
        .as_ref()
        .map(|_| (-dot(sys.relative_vector(Switch::BedDamper), &x[..nd])).max(0.0))
}

/// The state at the next strike from the state `x` at the end of a blow: structure and damper
/// unchanged, the rebounded slider replaced by a fresh one just touching the bed,
/// `z_s = u_b(O_b) = ψ(O_b)ᵀq` (overlap 0), `ż_s = v_s`.
pub(crate) fn next_strike(sys: &ImpactSystem, x: &[f64]) -> Vec<f64> {
    let n = sys.n_modes();
    let nd = sys.dofs();
    let mut x0 = x.to_vec();
    x0[sys.slider_index()] = dot(&sys.points.bed_contact, &x0[..n]);
    x0[nd + sys.slider_index()] = sys.slider.velocity;
    x0
}

/// Blow `k` (0-based, struck at `t0` in the train) from the strike state `x0`, with the run
/// options `o_blow` (duration = the blow interval) and `observer` on its output grid: the
/// blow's energy balance is checked (with [`Options::levels`]; without, its final state), a collision not over at the next strike refused
/// ([`collision_longer_than_interval`], with the user's `opts`), and η_k and the peaks
/// reported (module docs).
#[allow(clippy::too_many_arguments)]
pub(crate) fn one_blow(
    sys: &ImpactSystem,
    o_blow: &Options,
    opts: &Options,
    x0: &[f64],
    k: usize,
    t0: f64,
    rate_bpm: f64,
    observer: &mut dyn integrate::Observer,
) -> Result<BlowDone> {
    let nd = sys.dofs();
    let e_s = 0.5 * sys.slider.mass * sys.slider.velocity.powi(2);
    // Energies at the strike, in the mode the contacts are in (overlap > 0 = closed).
    let mut mode0 = Mode(0);
    for s in [Switch::SliderBed, Switch::BedDamper] {
        if s == Switch::BedDamper && sys.damper.is_none() {
            continue;
        }
        let d = dot(sys.relative_vector(s), &x0[..nd]);
        mode0 = mode0.with(s, d > 0.0);
    }
    let e0 = EnergyTerms::at(sys, mode0, x0);
    let ed0 = damper_energy(sys, x0);
    let sol = integrate::solve_from(sys, x0, o_blow, observer)?;
    // The blow's energy balance: what was stored at the strike = what is stored at its
    // end + what it dissipated.
    let e_end = EnergyTerms::at(sys, sol.mode_final, &sol.x_final);
    // (With a constant slider force, plus its work W_F = F (z_s − z_s0).)
    let balance = Balance::new(
        sol.t_final,
        e0.total(),
        sys.force_work(x0, &sol.x_final),
        &e_end,
        sol.totals.dissipated,
    );
    // Without the levels (a search's iterate) the dissipated energy is not tracked: only the
    // state is checked; the run whose levels are reported is checked whole.
    let balances = if o_blow.levels { &[balance][..] } else { &[] };
    check_run(sys, o_blow, &sol, balances)?;
    let Some(end) = sol.collision_end.as_ref() else {
        return Err(collision_longer_than_interval(
            sys,
            opts,
            x0,
            k,
            o_blow.duration,
            rate_bpm,
        ));
    };
    let energy_ratio = {
        let vs = end.x[nd + sys.slider_index()];
        let es_after = 0.5 * sys.slider.mass * vs * vs;
        // The slider force's work during the collision counts as energy put in (as in
        // `energy::simulate`); 0 without a force.
        let w = sys.force_work(x0, &end.x);
        (e_s + w - es_after - (damper_energy(sys, &end.x) - ed0)) / (e_s + w)
    };
    let report = BlowReport {
        blow: k + 1,
        start_s: t0,
        energy_ratio: Some(energy_ratio),
        collision_end_s: Some(t0 + end.t),
        machine_energy_at_strike_j: e0.ke_machine + e0.pe_machine,
        damper_energy_at_strike_j: ed0,
        damper_gap_at_strike_m: damper_gap(sys, x0),
        damper_contact_time_s: sys.damper.as_ref().map(|_| sol.totals.closed_time[1]),
        peak_bed_acceleration_m_per_s2: sol.totals.peaks.get(Channel::BedAcceleration).abs_peak(),
        peak_floor_force_n: sol.totals.peaks.get(Channel::FloorForce).abs_peak(),
        peak_contact_force_slider_bed_n: end.totals.peak_force(0),
    };
    Ok(BlowDone {
        report,
        solution: sol,
        stored_at_strike_j: e0.total(),
        blow_energy_j: e_s,
    })
}

/// The error of a blow whose collision (a contact closed: slider-bed or bed-damper, see
/// [`integrate::CollisionEnd`]) had not ended when the next blow was due, `t_c > T`: the next
/// blow would strike a slider still on the bed, and the blow's η, peaks and damper gap would
/// mean nothing. The collision's duration `t_c` is found by running blow `k` on from its strike
/// `x0` until the collision ends (at most `max(simulation.duration, T)`); the largest valid
/// stroke rate is then `R_max = 60 / t_c` (rounded down to 4 digits).
fn collision_longer_than_interval(
    sys: &ImpactSystem,
    opts: &Options,
    x0: &[f64],
    k: usize,
    interval: f64,
    rate_bpm: f64,
) -> Error {
    let bound = opts.duration.max(interval);
    let probe = Options {
        duration: bound,
        sample_rate: None,
        stop_at_collision_end: true,
        ..*opts
    };
    let t_c = integrate::solve_from(sys, x0, &probe, &mut integrate::NoOutput)
        .ok()
        .and_then(|s| s.collision_end.map(|c| c.t));
    let sig = |v: f64| crate::num(format!("{v:.4e}").parse().unwrap_or(v));
    let head = format!(
        "blow {} is not over when the next blow is due: a blow every {} s (--rate-bpm {}) is \
         shorter than the collision",
        k + 1,
        sig(interval),
        crate::num(rate_bpm),
    );
    let msg = match t_c {
        Some(t_c) => {
            // Rounded down to 4 significant digits, so that the rate printed is valid.
            let r_max = rate_4_digits(60.0 / t_c, false);
            format!(
                "{head} (the collision of blow {} lasts {} s, until both contacts open). \
                 Give --rate-bpm at most {} (one blow per {} s)",
                k + 1,
                sig(t_c),
                crate::num(r_max),
                sig(t_c)
            )
        }
        None => format!(
            "{head} (the collision of blow {} had not ended after {} s either: the slider \
             does not leave the bed). A train of blows needs collisions that end",
            k + 1,
            crate::num(bound)
        ),
    };
    Error::invalid("stroke rate (--rate-bpm)", msg)
}

/// Appends the samples of `b` (already shifted) to `h`.
fn extend(h: &mut History, b: &History) {
    for i in 0..b.time_s.len() {
        h.push_row(&b.row(i));
    }
}

/// Appends the samples of one blow, shifted by `t0`; the first sample of a later blow
/// (t = t0, the previous blow's last sample with a fresh slider) is dropped.
fn append(h: &mut History, b: History, t0: f64, skip_first: bool, dissipated_offset: f64) {
    let start = usize::from(skip_first && !b.time_s.is_empty() && b.time_s[0] == 0.0);
    let tail = |v: Vec<f64>| v.into_iter().skip(start);
    h.time_s.extend(tail(b.time_s).map(|t| t0 + t));
    h.bed_displacement_m.extend(tail(b.bed_displacement_m));
    h.bed_velocity_m_per_s.extend(tail(b.bed_velocity_m_per_s));
    h.bed_acceleration_m_per_s2
        .extend(tail(b.bed_acceleration_m_per_s2));
    h.floor_force_n.extend(tail(b.floor_force_n));
    h.contact_force_slider_bed_n
        .extend(tail(b.contact_force_slider_bed_n));
    h.contact_force_bed_damper_n
        .extend(tail(b.contact_force_bed_damper_n));
    h.damper_force_n.extend(tail(b.damper_force_n));
    h.slider_displacement_m
        .extend(tail(b.slider_displacement_m));
    h.slider_velocity_m_per_s
        .extend(tail(b.slider_velocity_m_per_s));
    h.damper_displacement_m
        .extend(tail(b.damper_displacement_m));
    h.damper_velocity_m_per_s
        .extend(tail(b.damper_velocity_m_per_s));
    h.energy.extend(b.energy.into_iter().skip(start));
    h.dissipated_j
        .extend(tail(b.dissipated_j).map(|d| d + dissipated_offset));
}

fn steady_state(r: &[BlowReport], tol: f64) -> Steady {
    let change = |a: &BlowReport, b: &BlowReport| -> [f64; 3] {
        [
            relative_change(a.peak_floor_force_n, b.peak_floor_force_n),
            relative_change(
                a.peak_bed_acceleration_m_per_s2,
                b.peak_bed_acceleration_m_per_s2,
            ),
            match (a.energy_ratio, b.energy_ratio) {
                (Some(x), Some(y)) => relative_change(x, y),
                (None, None) => 0.0,
                _ => f64::INFINITY,
            },
        ]
    };
    let changes: Vec<[f64; 3]> = r.windows(2).map(|w| change(&w[0], &w[1])).collect();
    let within = |c: &[f64; 3]| c.iter().all(|v| *v < tol);
    // The first blow from which every later change is within the tolerance.
    let mut from_blow = None;
    if changes.last().is_some_and(within) {
        let mut i = changes.len();
        while i > 0 && within(&changes[i - 1]) {
            i -= 1;
        }
        // changes[i] compares blows i+1 and i+2 (1-based): steady from blow i+1.
        from_blow = Some(i + 1);
    }
    let last = changes.last().copied().unwrap_or([0.0; 3]);
    let lb = r.last();
    Steady {
        converged: from_blow.is_some(),
        from_blow,
        last_change_peak_floor_force: last[0],
        last_change_peak_bed_acceleration: last[1],
        last_change_energy_ratio: last[2],
        peak_floor_force_n: lb.map_or(0.0, |b| b.peak_floor_force_n),
        peak_bed_acceleration_m_per_s2: lb.map_or(0.0, |b| b.peak_bed_acceleration_m_per_s2),
        energy_ratio: lb.and_then(|b| b.energy_ratio),
    }
}

#[cfg(test)]
mod tests {
    //! Checks of the blow chaining against closed forms (two-body impact and spring-mounted mass closed forms)
    //! and against single runs.

    use super::*;
    use crate::analysis::simulate;
    use crate::model::{Case, Model};

    fn paper(overrides: &[&str]) -> Model {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/paper-lumped.toml"
        );
        let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        Model::from_file(path.as_ref(), &o).unwrap()
    }

    /// Blow 1 of a 3-blow train is the single run of duration T, bit for bit: the train's
    /// first interval (samples 0..=T fs) and report equal `simulate` with `duration = T`.
    #[test]
    fn first_blow_of_a_train_is_the_single_run() {
        let model = paper(&[]);
        let sys = model.impact_system(Case::Damper).unwrap();
        let mut opts = model.options();
        opts.duration = 0.5;
        let single = simulate(&sys, &opts, true).unwrap();
        let b = BlowOptions {
            blows: 3,
            rate_bpm: 120.0,
            ..BlowOptions::default()
        };
        let train = run_blows(&sys, &opts, &b, true).unwrap();
        let (h1, h) = (single.history.unwrap(), train.history.unwrap());
        let n = h1.time_s.len();
        assert_eq!(n, 10_001);
        assert_eq!(h.time_s.len(), 3 * 10_000 + 1);
        assert_eq!(h.time_s[..n], h1.time_s[..]);
        assert_eq!(h.floor_force_n[..n], h1.floor_force_n[..]);
        assert_eq!(
            h.bed_acceleration_m_per_s2[..n],
            h1.bed_acceleration_m_per_s2[..]
        );
        assert_eq!(h.damper_displacement_m[..n], h1.damper_displacement_m[..]);
        assert_eq!(h.dissipated_j[..n], h1.dissipated_j[..]);
        let r = &train.blows[0];
        assert_eq!(r.energy_ratio, single.summary.energy_ratio);
        assert_eq!(r.peak_floor_force_n, single.summary.peak_floor_force_n);
        assert_eq!(r.damper_gap_at_strike_m, Some(0.0));
    }

    /// The spring-mounted mass of the periodic-impulse test below (M = 100 kg on 1e5 N/m,
    /// ζ = 2 %) struck by m_s = 0.01 kg at 1 m/s through a linear undamped contact K = 1e6 N/m.
    fn mounted_mass() -> Model {
        mounted(100.0, 1.0e5, 0.02, 0.01, 1.0)
    }

    /// A mass `m` (kg) on a spring `k` (N/m) to the floor, modal damping `zeta`, struck by a
    /// slider `ms` (kg) at `vs` (m/s) through a linear undamped contact of 1e6 N/m.
    fn mounted(m: f64, k: f64, zeta: f64, ms: f64, vs: f64) -> Model {
        let text = format!(
            r#"
name = "spring-mounted mass"
[structure]
reference_mode = 1
[structure.lumped]
damping_ratios = [{zeta}]
masses = [{{ name = "bed", mass = {m} }}]
springs = [{{ name = "mount", nodes = ["bed", "ground"], stiffness = {k} }}]
floor = ["mount"]
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = {ms}
velocity = {vs}
[contact.slider_bed]
law = "linear"
stiffness = 1.0e6
damping = 0.0
release = "force"
[simulation]
method = "exact"
duration = 1.0
sample_rate = 20000.0
"#
        );
        Model::from_text("mounted.toml", text, &[]).unwrap()
    }

    /// A stroke interval shorter than the collision is refused. The collision of the mounted
    /// mass is the half period of the two-body contact oscillation, `t_c = π / sqrt(K/μ)`,
    /// μ = m_s M/(m_s + M) = 0.3141 ms (the mount, ω = 31.6 rad/s, moves M by ~1e-4 of the
    /// contact's travel in that time: 1e-3 relative tolerance). At 20 kHz the shortest valid
    /// interval is ⌈t_c f_s⌉/f_s = 7 samples = 0.35 ms, so the largest valid rate is
    /// 60/0.35e-3 = 171 428.6 /min (printed rounded down: 171400). A train at that rate runs
    /// (with η for every blow), one at 2 samples per blow (0.1 ms) is refused naming t_c.
    #[test]
    fn an_interval_shorter_than_the_collision_is_refused() {
        let model = mounted_mass();
        let sys = model.impact_system(Case::NoDamper).unwrap();
        let opts = model.options();
        let (ms, m, k) = (0.01_f64, 100.0_f64, 1.0e6_f64);
        let t_closed = std::f64::consts::PI / (k * (ms + m) / (ms * m)).sqrt();
        let probe = Options {
            stop_at_collision_end: true,
            sample_rate: None,
            ..opts
        };
        let t_c =
            integrate::solve_from(&sys, &sys.initial_state(), &probe, &mut integrate::NoOutput)
                .unwrap()
                .collision_end
                .unwrap()
                .t;
        assert!(
            ((t_c - t_closed) / t_closed).abs() < 1e-3,
            "collision {t_c} s, closed form {t_closed} s"
        );
        let train = |rate_bpm: f64| {
            let b = BlowOptions {
                blows: 5,
                rate_bpm,
                ..BlowOptions::default()
            };
            run_blows(&sys, &opts, &b, false)
        };
        let e = train(60.0 / 1e-4).unwrap_err().to_string();
        assert!(e.contains("shorter than the collision"), "{e}");
        assert!(
            e.contains(&format!(
                "lasts {} s",
                crate::num(format!("{t_c:.4e}").parse().unwrap())
            )),
            "{e}"
        );
        // R_max = 60/t_c rounded down to 4 digits (it was 60/(t_c rounded up to whole
        // samples), the interval being rounded to samples).
        let r_max = 60.0 / t_c;
        let scale = 10f64.powi(3 - r_max.log10().floor() as i32);
        let r_max = (r_max * scale).floor() / scale;
        assert!(e.contains(&format!("at most {}", crate::num(r_max))), "{e}");
        let r = train(r_max).unwrap();
        assert_eq!(r.interval_s, 60.0 / r_max);
        assert!(r.blows.iter().all(|b| b.energy_ratio.is_some()));
        // 0.3 ms < t_c: refused
        assert!(train(60.0 / 3e-4).is_err());
    }

    /// Periodic impulses on a damped spring-mounted mass (M = 100 kg, k = 1e5 N/m, ζ = 0.02)
    /// struck by a light slider (m_s = 0.01 kg, v_s = 1 m/s, stiff undamped contact: an impulse
    /// to ~1e-4). Closed form of the periodic steady state (superposed impulse responses, a
    /// geometric series), with λ = −ζω + iω_d and the impulse J applied at each strike t = 0:
    ///
    /// ```text
    /// u(t) = J/(M ω_d) · Im[e^{λt} / (1 − e^{λT})],  0 ≤ t < T
    /// J = 2 μ (v_s − u̇(T⁻)),  μ = m_s M/(m_s + M)          (elastic impact, e = 1)
    /// ```
    ///
    /// The steady peak floor force max k|u| of the last of 25 blows must match to 0.2 % (the
    /// contact lasts 0.3 ms of the 199 ms period) for a stroke interval of a whole number of
    /// periods (residual in phase: 1/(1 − r) ≈ 2.1× the first blow's peak) and of a whole number
    /// plus a half (residual in antiphase: ≈ 0.65×), r = exp(−ζωT). A state carried wrongly
    /// between blows (phase, velocity) breaks the series.
    #[test]
    fn periodic_impulses_reach_the_closed_form_steady_state() {
        let (m, k, zeta, ms, vs) = (100.0_f64, 1.0e5_f64, 0.02_f64, 0.01_f64, 1.0_f64);
        let model = mounted(m, k, zeta, ms, vs);
        let sys = model.impact_system(Case::NoDamper).unwrap();
        let opts = model.options();
        let w = (k / m).sqrt();
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let mu = ms * m / (ms + m);
        let period = 2.0 * std::f64::consts::PI / wd;
        let mut peaks = Vec::new();
        for cycles in [5.0, 5.5] {
            let b = BlowOptions {
                blows: 25,
                rate_bpm: 60.0 / (cycles * period),
                steady_tolerance: 1e-3,
            };
            let r = run_blows(&sys, &opts, &b, false).unwrap();
            let t_blow = r.interval_s;
            // Closed form with complex arithmetic by hand: e^{λt} = e^{−ζωt}(cos ω_d t + i sin ω_d t).
            let series = |t: f64| -> (f64, f64) {
                // returns Im[e^{λt}/(1 − e^{λT})] and Im[λ e^{λt}/(1 − e^{λT})]
                let (ea, eb) = {
                    let g = (-zeta * w * t).exp();
                    (g * (wd * t).cos(), g * (wd * t).sin())
                };
                let (da, db) = {
                    let g = (-zeta * w * t_blow).exp();
                    (1.0 - g * (wd * t_blow).cos(), -g * (wd * t_blow).sin())
                };
                let den = da * da + db * db;
                // (ea + i eb)/(da + i db)
                let (qa, qb) = ((ea * da + eb * db) / den, (eb * da - ea * db) / den);
                // λ (qa + i qb), λ = −ζω + i ω_d
                let (la, lb) = (-zeta * w, wd);
                (qb, la * qb + lb * qa)
            };
            let g = series(t_blow).1 / (m * wd);
            let j = 2.0 * mu * vs / (1.0 + 2.0 * mu * g);
            let steps = 200_000;
            let peak = (0..=steps)
                .map(|i| {
                    let t = t_blow * i as f64 / steps as f64;
                    (k * j / (m * wd) * series(t).0).abs()
                })
                .fold(0.0_f64, f64::max);
            let got = r.blows.last().unwrap().peak_floor_force_n;
            let first = r.blows[0].peak_floor_force_n;
            assert!(
                ((got - peak) / peak).abs() < 2e-3,
                "{cycles} periods per blow: steady peak {got} N, closed form {peak} N (first blow {first} N)"
            );
            assert!(r.steady.converged, "{:?}", r.steady);
            peaks.push(got / first);
        }
        // in phase ≈ 2.1×, antiphase ≈ 0.65× the first blow: the stroke rate decides.
        assert!(peaks[0] > 2.0 && peaks[1] < 0.7, "{peaks:?}");
    }

    /// The damper's free flight and return after a blow (damper anchored to the ground, so its
    /// spring-dashpot sees z_d alone), against the closed form: outwards the one-way dashpot is
    /// off (paper Eq. 7: c_d = 0 for ż_d > 0), `z = z_a cos ω_a τ + (v_a/ω_a) sin ω_a τ`,
    /// ω_a = sqrt(k_d/m_d) = 22.68 rad/s, up to `z_max = sqrt(z_a² + (v_a/ω_a)²)`; back towards
    /// the bed it is on, ζ_a = c_d / (2 sqrt(k_d m_d)) = 4.41 (overdamped), and from rest
    /// `z = z_max (s₂ e^{s₁τ} − s₁ e^{s₂τ}) / (s₂ − s₁)`, s₁,₂ = −ω_a (ζ_a ∓ sqrt(ζ_a² − 1))
    /// = −2.61, −197.4 1/s: the slow root gives a return time constant ≈ c_d/k_d = 0.39 s.
    /// Tolerance 1e-9 m on a 14 mm excursion (the propagator is exact to round-off). The
    /// reported gap at the next strike (T = 0.5 s) is z(T) − u_b(T).
    #[test]
    fn damper_free_return_matches_the_closed_form() {
        let model = paper(&["points.damper_anchor=\"ground\""]);
        let sys = model.impact_system(Case::Damper).unwrap();
        let d = sys.damper.unwrap();
        let b = BlowOptions {
            blows: 2,
            rate_bpm: 120.0,
            ..BlowOptions::default()
        };
        let r = run_blows(&sys, &model.options(), &b, true).unwrap();
        let h = r.history.unwrap();
        let n1 = (r.interval_s * 20_000.0).round() as usize; // last sample of blow 1
                                                             // first sample clear of the collision: contact open, damper moving away
        let a = (0..n1)
            .find(|&i| {
                h.time_s[i] > 0.005
                    && h.contact_force_bed_damper_n[i] == 0.0
                    && h.damper_velocity_m_per_s[i] > 0.0
            })
            .unwrap();
        let (za, va, ta) = (
            h.damper_displacement_m[a],
            h.damper_velocity_m_per_s[a],
            h.time_s[a],
        );
        let wa = (d.stiffness / d.mass).sqrt();
        let za_ = d.damping / (2.0 * (d.stiffness * d.mass).sqrt());
        assert!(za_ > 1.0);
        let root = (za_ * za_ - 1.0).sqrt();
        let (s1, s2) = (-wa * (za_ - root), -wa * (za_ + root));
        let tau_star = va.atan2(wa * za) / wa;
        let zmax = (za * za + (va / wa).powi(2)).sqrt();
        let closed = |t: f64| -> f64 {
            let tau = t - ta;
            if tau <= tau_star {
                za * (wa * tau).cos() + va / wa * (wa * tau).sin()
            } else {
                let s = tau - tau_star;
                zmax * (s2 * (s1 * s).exp() - s1 * (s2 * s).exp()) / (s2 - s1)
            }
        };
        assert!(zmax > 0.01, "excursion {zmax} m");
        let mut worst = 0.0_f64;
        for i in a..=n1 {
            assert_eq!(
                h.contact_force_bed_damper_n[i], 0.0,
                "bed touched the damper"
            );
            worst = worst.max((h.damper_displacement_m[i] - closed(h.time_s[i])).abs());
        }
        assert!(
            worst < 1e-9,
            "damper return off the closed form by {worst} m"
        );
        let gap = r.blows[1].damper_gap_at_strike_m.unwrap();
        let expect = closed(r.interval_s) - h.bed_displacement_m[n1];
        assert!(
            (gap - expect).abs() < 1e-9,
            "gap {gap} m, closed form {expect} m"
        );
        assert!(gap > 3e-3, "the damper is still {gap} m away after 0.5 s");
        // blow 1: the damper took the blow (contact closed for a fraction of a millisecond)
        let c1 = r.blows[0].damper_contact_time_s.unwrap();
        assert!(c1 > 0.0 && c1 < 2e-3, "bed-damper contact {c1} s");
    }
}
