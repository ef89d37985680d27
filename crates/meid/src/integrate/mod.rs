//! Time integration of the impact system: the problem → solve → solution pattern.
//!
//! * [`Method::Exact`]: between switches the system is linear time invariant, so each
//!   stretch is propagated in closed form ([`propagator`]); switches are located on the exact
//!   solution ([`roots`]) to ~1e-13 of the fastest period. Linear contact laws only.
//! * [`Method::Dopri5`]: Dormand-Prince 5(4) with PI step control, dense output and the same
//!   event location on the dense output ([`dopri5`]). Any contact law (Hertz, Hunt-Crossley).
//!
//! Both call an [`Observer`] on a uniform output grid and return a [`Solution`] with the events,
//! the end-of-collision snapshot, exact peak contact forces and the energy dissipated.
//!
//! **End of collision** (default stopping point of a study): the first instant, after the slider
//! has touched the bed, at which both the slider-bed and the bed-damper contacts are open
//! (just the slider-bed contact without a damper).

pub mod dopri5;
pub mod exact;
pub mod expm;
pub mod network;
pub mod peaks;
pub mod propagator;
pub mod roots;
pub mod small;
mod switching;
pub mod taylor;

use crate::impact::{Channel, ImpactSystem, Mode, Switch};
use crate::{Error, Result};

/// Integration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Closed-form propagation between exactly located switches (linear contact laws).
    #[default]
    Exact,
    /// Dormand-Prince 5(4), adaptive, with event location (any contact law).
    Dopri5,
}

impl std::str::FromStr for Method {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "exact" => Ok(Method::Exact),
            "dopri5" => Ok(Method::Dopri5),
            _ => Err(Error::invalid(
                "method",
                format!("unknown method '{s}'; valid: exact, dopri5"),
            )),
        }
    }
}

/// Settings of a run.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    pub method: Method,
    /// Simulated time span (s).
    pub duration: f64,
    /// Output sample rate (Hz); `None` for no samples.
    pub sample_rate: Option<f64>,
    /// Time of the first output sample (s), `0 ≤ φ < 1/sample_rate`: samples at
    /// `t_j = φ + j/f_s`. A train of blows ([`crate::analysis::blows`]) starts each blow at
    /// its exact strike time and puts its samples on the train's grid `i/f_s` with it.
    pub sample_phase_s: f64,
    /// Stop at the end of the collision instead of the end of `duration`.
    pub stop_at_collision_end: bool,
    /// Relative tolerance (dopri5).
    pub rtol: f64,
    /// Absolute tolerance (dopri5), per state component in SI units.
    pub atol: f64,
    /// Give up after this many switching events (chattering guard).
    pub max_events: usize,
    /// Exact method: Taylor steps a run may take in one mode before it builds the mode's closed
    /// form (default [`exact::TAYLOR_STEPS_PER_MODE`]; 0 for closed forms only). Both are exact
    /// to round-off; the choice is a matter of speed.
    pub taylor_steps_per_mode: usize,
    /// Track the run's levels: the response channels' exact extremes ([`Totals::peaks`]) and
    /// the energy dissipated ([`Totals::dissipated`]); default true. The exact method skips
    /// both when false (the run's peaks and dissipated energy then stay 0, so its energy
    /// balance cannot be checked): a search that only needs the final state of intermediate runs (the steady
    /// state's Newton iterates, [`crate::analysis::steady`]) saves their cost, and checks the
    /// run whose levels it reports. dopri5 always tracks them.
    pub levels: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            method: Method::Exact,
            duration: 0.5,
            sample_rate: Some(20_000.0),
            sample_phase_s: 0.0,
            stop_at_collision_end: false,
            rtol: 1e-8,
            atol: 1e-14,
            max_events: DEFAULT_MAX_EVENTS,
            taylor_steps_per_mode: exact::TAYLOR_STEPS_PER_MODE,
            levels: true,
        }
    }
}

/// Default of [`Options::max_events`] (`simulation.max_events`): a 60 s run of the paper's
/// machines under a constant slider force takes up to about 1.1e5 switches (a one-way dashpot
/// switching at each turn of a 20 kHz contact oscillation while it decays).
pub const DEFAULT_MAX_EVENTS: usize = 1_000_000;

/// The error of a run that exceeded `max` switching events at time `t`: it names the switch
/// that toggled most among the last events, how often, and what to change.
pub(crate) fn too_many_events(method: &str, events: &[Event], max: usize, t: f64) -> Error {
    let tail = &events[events.len().saturating_sub(1000)..];
    let mut counts = [0usize; 3];
    let switches = [Switch::SliderBed, Switch::BedDamper, Switch::Dashpot];
    for e in tail {
        for (c, &s) in counts.iter_mut().zip(&switches) {
            if e.from.on(s) != e.to.on(s) {
                *c += 1;
            }
        }
    }
    let (most, n) = counts
        .iter()
        .enumerate()
        .max_by_key(|&(_, c)| *c)
        .map_or((0, 0), |(i, &c)| (i, c));
    let name = [
        "the slider-bed contact",
        "the bed-damper contact",
        "the one-way dashpot",
    ][most];
    let span = match (tail.first(), tail.last()) {
        (Some(a), Some(b)) if n > 1 => (b.t - a.t) / n as f64,
        _ => f64::NAN,
    };
    let hint = if method == "dopri5" {
        "; this is typical of a body resting on a vibrating one with little preload, which \
         dopri5 follows only to its tolerances: simulation.method = \"exact\" (linear contact \
         laws) follows it exactly"
    } else {
        ""
    };
    Error::numerical(
        method,
        format!(
            "more than {max} switching events before t = {t:.6} s (simulation.max_events); \
             of the last {} events {n} switched {name}, one every {span:.3e} s on average{hint}; \
             raise simulation.max_events or shorten simulation.duration",
            tail.len()
        ),
    )
}

/// Receives the state on the output grid.
pub trait Observer {
    /// `t` (s), state `X = [x; ẋ]`, current mode.
    fn sample(&mut self, t: f64, x: &[f64], mode: Mode);
}

/// An observer that ignores everything.
pub struct NoOutput;

impl Observer for NoOutput {
    fn sample(&mut self, _t: f64, _x: &[f64], _mode: Mode) {}
}

/// A switching event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    pub t: f64,
    pub from: Mode,
    pub to: Mode,
}

/// Running totals kept along a run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Totals {
    /// Energy dissipated by every dashpot and modal damping (J), integrated exactly.
    pub dissipated: f64,
    /// Extremes of every response channel ([`crate::impact::Channel`]) on the continuous
    /// solution, with their times ([`peaks`]).
    pub peaks: peaks::Peaks,
    /// Time each contact has been closed (s): slider-bed, bed-damper.
    pub closed_time: [f64; 2],
}

impl Totals {
    /// Peak compressive contact force (N) of contact `ci` (0 slider-bed, 1 bed-damper): the
    /// largest value of its force channel, 0 if it never closed.
    pub fn peak_force(&self, ci: usize) -> f64 {
        let c = [Channel::ContactSliderBed, Channel::ContactBedDamper][ci.min(1)];
        let e = self.peaks.get(c);
        if e.is_set() {
            e.max.max(0.0)
        } else {
            0.0
        }
    }
}

/// A point of the run's path: from time `t` on, the system is in `mode`, starting from state
/// `x = [x; ẋ]` there. A run's [`Solution::path`] has one at t = 0 and one at each mode change,
/// so that each stretch between two of them is a linear time-invariant motion for linear
/// contact laws: the exact spectrum ([`crate::analysis::spectrum`]) is built from them.
///
/// Where a closed contact of the current mode has a non-linear law (Hertz, Hunt-Crossley), the
/// motion between switches is not LTI: `dopri5` then also adds a point at the end of each
/// accepted step, with the same mode. Those knots are the ends of its steps, which its error
/// control keeps short against the motion, and between two of them the state is represented by
/// the cubic Hermite interpolant of the knots' states and derivatives
/// `Ẋ = [ẋ; ẍ]` (`ẍ` from [`ImpactSystem::accelerations`] in the knot's mode).
#[derive(Debug, Clone, PartialEq)]
pub struct PathPoint {
    pub t: f64,
    pub mode: Mode,
    pub x: Vec<f64>,
}

/// The state of the run at the end of the collision.
#[derive(Debug, Clone, PartialEq)]
pub struct CollisionEnd {
    pub t: f64,
    pub x: Vec<f64>,
    pub totals: Totals,
}

/// The result of a run.
#[derive(Debug, Clone)]
pub struct Solution {
    pub events: Vec<Event>,
    /// The path of the run (see [`PathPoint`]); the run ends at (`t_final`, `x_final`).
    pub path: Vec<PathPoint>,
    pub collision_end: Option<CollisionEnd>,
    pub t_final: f64,
    pub x_final: Vec<f64>,
    pub mode_final: Mode,
    /// Totals over the whole run.
    pub totals: Totals,
    /// Stretches propagated (exact: closed-form segments and Taylor steps, see
    /// [`exact::TAYLOR_STEPS_PER_MODE`]) or accepted steps (dopri5).
    pub steps: usize,
    /// Of `steps`, those taken by the Taylor propagator (exact).
    pub taylor_steps: usize,
    /// Rejected steps (dopri5).
    pub rejected: usize,
    /// Modes that needed the matrix-exponential fallback (exact).
    pub fallback_modes: usize,
}

/// Simulates `sys` with `opts`, calling `obs` on the output grid.
pub fn solve(sys: &ImpactSystem, opts: &Options, obs: &mut dyn Observer) -> Result<Solution> {
    solve_from(sys, &sys.initial_state(), opts, obs)
}

/// As [`solve`], but starting from the state `x0 = [x; ẋ]` (length `2 · sys.dofs()`) at
/// t = 0 instead of [`ImpactSystem::initial_state`]. The initial contact modes are chosen from
/// `x0` exactly as at the start of [`solve`]. Used to chain blows (`analysis::blows`):
/// `solve` is `solve_from(sys, &sys.initial_state(), ..)`, bit for bit.
pub fn solve_from(
    sys: &ImpactSystem,
    x0: &[f64],
    opts: &Options,
    obs: &mut dyn Observer,
) -> Result<Solution> {
    if x0.len() != 2 * sys.dofs() {
        return Err(Error::invalid(
            "initial state",
            format!(
                "needs {} values ([x; ẋ] for {} coordinates), got {}",
                2 * sys.dofs(),
                sys.dofs(),
                x0.len()
            ),
        ));
    }
    if let Some(i) = x0.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(
            "initial state",
            format!("value {i} is not finite ({})", x0[i]),
        ));
    }
    if !(opts.duration.is_finite() && opts.duration > 0.0) {
        return Err(Error::invalid(
            "simulation.duration",
            format!("must be > 0 s (got {})", opts.duration),
        ));
    }
    if let Some(r) = opts.sample_rate {
        if !(r.is_finite() && r > 0.0) {
            return Err(Error::invalid(
                "simulation.sample_rate",
                format!("must be > 0 Hz (got {r})"),
            ));
        }
        let phase = opts.sample_phase_s;
        if !(phase >= 0.0 && phase < 1.0 / r) {
            return Err(Error::invalid(
                "sample_phase_s",
                format!(
                    "must lie in [0, 1/sample_rate) = [0, {}) s (got {phase})",
                    1.0 / r
                ),
            ));
        }
    }
    check_cost(sys, opts)?;
    match opts.method {
        Method::Exact => exact::solve_from(sys, x0, opts, obs),
        Method::Dopri5 => dopri5::solve_from(sys, x0, opts, obs),
    }
}

/// The most periods of its fastest time scale a run may span ([`check_cost`]).
pub const MAX_PERIODS: f64 = 1e7;

/// Bounds a run's cost before it starts: the number of periods of the system's fastest time
/// scale over `opts.duration` must stay below [`MAX_PERIODS`]. The rates considered are the
/// structure's highest frequency, each linear contact's `√(K/m)` (m the lighter body it
/// touches) and `C/m`, and the damper's `√(k_d/m_d)` and `c_d/m_d`. Switch searches and
/// integration steps cannot be fewer than a few per such period, so a run beyond the limit
/// would take hours (a 1e20 N/m contact on a 3.5 kg damper is a 1.2 ns period: 4e8 of them in
/// 0.5 s); it is refused with the field responsible.
pub fn check_cost(sys: &ImpactSystem, opts: &Options) -> Result<()> {
    let Some((rate, source)) = fastest_rate(sys) else {
        return Ok(());
    };
    let periods = opts.duration * rate / (2.0 * std::f64::consts::PI);
    if periods > MAX_PERIODS {
        return Err(Error::invalid(
            "simulation.duration",
            format!(
                "the run would span {periods:.2e} periods of its fastest time scale \
                 (2π/{rate:.3e} s, set by {source}); the limit is {MAX_PERIODS:e}. Lower that \
                 stiffness or damping (a contact 1e3 times stiffer than the structure already \
                 acts as rigid), raise the mass, or shorten simulation.duration \
                 ({:e} s)",
                opts.duration
            ),
        ));
    }
    Ok(())
}

/// What sets a system's fastest time scale ([`fastest_rate`]); its `Display` names the field.
/// Kept as numbers and formatted only for a message: the check runs before every run, and a
/// few formatted numbers would cost more than a collision's exact integration.
#[derive(Debug, Clone, Copy)]
pub enum RateSource {
    /// The structure's highest retained mode.
    Structure,
    /// A linear contact's stiffness (field, N/m, kg).
    ContactStiffness(&'static str, f64, f64),
    /// A linear contact's damping (field, N·s/m, kg).
    ContactDamping(&'static str, f64, f64),
    /// The damper spring (N/m, kg).
    DamperStiffness(f64, f64),
    /// The damper dashpot (N·s/m, kg).
    DamperDamping(f64, f64),
}

impl std::fmt::Display for RateSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            RateSource::Structure => write!(f, "the structure's highest retained mode"),
            RateSource::ContactStiffness(field, k, m) => {
                write!(f, "{field}.stiffness = {k:e} N/m on {m:e} kg")
            }
            RateSource::ContactDamping(field, c, m) => {
                write!(f, "{field}.damping = {c:e} N·s/m on {m:e} kg")
            }
            RateSource::DamperStiffness(k, m) => {
                write!(f, "damper.stiffness = {k:e} N/m on damper.mass = {m:e} kg")
            }
            RateSource::DamperDamping(c, m) => {
                write!(f, "damper.damping = {c:e} N·s/m on damper.mass = {m:e} kg")
            }
        }
    }
}

/// The fastest time scale of `sys` (rad/s) and what sets it (see [`check_cost`]); `None` when
/// no rate is finite.
pub fn fastest_rate(sys: &ImpactSystem) -> Option<(f64, RateSource)> {
    let mut rates: [(f64, RateSource); 7] = [(f64::NAN, RateSource::Structure); 7];
    let mut count = 0;
    let mut push = |r: f64, s: RateSource| {
        rates[count] = (r, s);
        count += 1;
    };
    let w_max = sys
        .structure
        .omega_rad_per_s
        .iter()
        .copied()
        .fold(0.0, f64::max);
    push(w_max, RateSource::Structure);
    let ms = sys.slider.mass;
    let md = sys.damper.map(|d| d.mass);
    let mut law = |c: &crate::impact::Contact, m: f64, field: &'static str| {
        if let crate::impact::ContactLaw::Linear { stiffness, damping } = c.law {
            push(
                (stiffness / m).sqrt(),
                RateSource::ContactStiffness(field, stiffness, m),
            );
            push(damping / m, RateSource::ContactDamping(field, damping, m));
        }
    };
    law(&sys.slider_bed, ms, "contact.slider_bed");
    if let (Some(c), Some(m)) = (&sys.bed_damper, md) {
        law(c, m, "contact.bed_damper");
    }
    if let Some(d) = &sys.damper {
        push(
            (d.stiffness / d.mass).sqrt(),
            RateSource::DamperStiffness(d.stiffness, d.mass),
        );
        push(
            d.damping / d.mass,
            RateSource::DamperDamping(d.damping, d.mass),
        );
    }
    rates
        .into_iter()
        .filter(|(r, _)| r.is_finite())
        .max_by(|a, b| a.0.total_cmp(&b.0))
}

/// Output grid helper: sample `j` is at `j / rate`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Grid {
    pub dt: f64,
    pub next: u64,
    /// Time of sample 0 ([`Options::sample_phase_s`]).
    pub phase: f64,
}

impl Grid {
    /// The output grid of `opts`: `t_j = φ + j/f_s`, or `None` without samples.
    pub fn new(opts: &Options) -> Option<Self> {
        opts.sample_rate.map(|r| Grid {
            dt: 1.0 / r,
            next: 0,
            phase: opts.sample_phase_s,
        })
    }
    #[inline]
    pub fn time(&self, j: u64) -> f64 {
        self.phase + j as f64 * self.dt
    }
}
