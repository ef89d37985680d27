//! The machine in production: the three cases (no damper, the damper, the same mass added
//! rigidly) in their periodic steady state at a stroke rate, the largest stroke rate at which
//! the damper still returns, the stroke-rate map, and the verdict in words.
//!
//! Every level here is a steady blow's ([`super::steady`]): the first blow of a train starts
//! from rest and is not what the floor sees in production.
//!
//! # Why a damper stops returning
//! After a blow the damper leaves the bed with the momentum it took. Outwards its one-way
//! dashpot is off (paper Eq. 7) and it swings on `k_d` at `ω_a = √(k_d/m_d)`; back towards the
//! bed the dashpot acts, and with `c_d > 2√(k_d m_d)` the return is an overdamped creep whose
//! slow root is
//!
//! ```text
//! s₁ = −ω_a (ζ_a − √(ζ_a² − 1)) ≈ −k_d / c_d     (ζ_a = c_d / (2√(k_d m_d)) ≫ 1)
//! ```
//!
//! so the gap closes with the time constant `τ ≈ c_d / k_d` (0.39 s for the paper's
//! k_d = 1.8e3 N/m, c_d = 700 N·s/m). The base's residual vibration then keeps it off: the
//! dashpot acts only while the damper moves towards the bed, so it rectifies that vibration
//! into a mean push away, `k_d ⟨z_d − u_f⟩ = c_d ⟨max(−(ż_d − u̇_f), 0)⟩`. At a stroke
//! interval of a few τ or less the damper is still away at the next strike: it no longer
//! takes the blow's momentum, and it adds its mass and spring to the base instead. The
//! largest stroke rate at which it touches the bed in every steady blow is
//! [`return_rate`]'s answer; a stiffer spring or a weaker dashpot (smaller `c_d/k_d`) raises it.

use serde::Serialize;

use super::compare::CaseName;
use super::steady::{steady_state, SteadyOptions, SteadyState};
use crate::integrate::Options;
use crate::model::{Case, Model};
use crate::{Error, Result};

/// The stroke rate assumed when neither the command nor the model gives one (blows/min).
pub const ASSUMED_RATE_BPM: f64 = 60.0;

/// Where a stroke rate came from ([`stroke_rate`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RateOrigin {
    /// Given to the command (`--rate-bpm`, an API argument).
    Given,
    /// The model's `[production] rate_bpm`.
    Model,
    /// Neither: [`ASSUMED_RATE_BPM`].
    Assumed,
}

impl RateOrigin {
    /// Words for a report: where the rate came from.
    pub fn describe(self) -> &'static str {
        match self {
            RateOrigin::Given => "the rate asked for",
            RateOrigin::Model => "the model's [production] rate_bpm",
            RateOrigin::Assumed => {
                "assumed: the model gives no stroke rate ([production] rate_bpm)"
            }
        }
    }
}

/// The stroke rate (blows/min) to judge a machine at: `given` (a command's `--rate-bpm`),
/// else the model's `[production] rate_bpm`, else [`ASSUMED_RATE_BPM`]; with its origin.
/// Errors name `rate_bpm` when the rate is not a finite number > 0.
pub fn stroke_rate(model: &Model, given: Option<f64>) -> Result<(f64, RateOrigin)> {
    let (rate, origin) = match (given, model.stroke_rate_bpm()) {
        (Some(r), _) => (r, RateOrigin::Given),
        (None, Some(r)) => (r, RateOrigin::Model),
        (None, None) => (ASSUMED_RATE_BPM, RateOrigin::Assumed),
    };
    super::blows::blow_interval_s(rate)?;
    Ok((rate, origin))
}

/// The three cases at one stroke rate.
#[derive(Debug, Clone, Serialize)]
pub struct Production {
    pub rate_bpm: f64,
    pub interval_s: f64,
    /// Steady states by case (`no-damper`, `damper`, `added-mass`), those the model has.
    pub cases: Vec<CaseSteady>,
    /// The largest stroke rate (blows/min) at which the damper touches the bed in every steady
    /// blow ([`return_rate`]); `None` without a damper or when not searched.
    pub damper_return: Option<ReturnRate>,
    /// The verdict, one sentence per case, in words ([`verdict`]).
    pub verdict: Vec<String>,
}

/// One case's steady state.
#[derive(Debug, Clone, Serialize)]
pub struct CaseSteady {
    pub case: &'static str,
    pub steady_state: SteadyState,
}

impl Production {
    /// The steady state of a case, if computed.
    pub fn case(&self, c: CaseName) -> Option<&SteadyState> {
        self.cases
            .iter()
            .find(|x| x.case == c.name())
            .map(|x| &x.steady_state)
    }
}

/// The largest rate at which the damper still returns (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ReturnRate {
    /// Largest stroke rate found at which the damper touches the bed in every steady blow
    /// (blows/min), to the resolution below; `None` when it touches at none of the rates
    /// tried (down to `lowest_rate_bpm`).
    pub rate_bpm: Option<f64>,
    /// Relative resolution of `rate_bpm` (the bisection's bracket).
    pub resolution: f64,
    /// Lowest rate tried (blows/min).
    pub lowest_rate_bpm: f64,
    /// The overdamped return's time constant `c_d / k_d` (s) and the dashpot's damping ratio
    /// `ζ_a = c_d / (2√(k_d m_d))` (module docs).
    pub return_time_constant_s: f64,
    pub damper_damping_ratio: f64,
}

/// The cases of `model` in their steady state at `rate_bpm`; with `search_return`, also the
/// damper's return rate. The verdict is filled.
pub fn production(
    model: &Model,
    rate_bpm: f64,
    so: &SteadyOptions,
    search_return: bool,
) -> Result<Production> {
    let opts = model.options();
    let mut cases = Vec::new();
    let has_damper = model
        .impact_system(Case::Damper)
        .is_ok_and(|s| s.damper.is_some());
    let names: Vec<CaseName> = if has_damper {
        vec![CaseName::NoDamper, CaseName::Damper, CaseName::AddedMass]
    } else {
        vec![CaseName::NoDamper]
    };
    let so = SteadyOptions { rate_bpm, ..*so };
    let results: Vec<Result<(CaseName, SteadyState)>> = {
        use rayon::prelude::*;
        names
            .par_iter()
            .map(|&c| {
                let sys = model.impact_system(case_of(c))?;
                Ok((c, steady_state(&sys, &opts, &so)?))
            })
            .collect()
    };
    for r in results {
        let (c, s) = r?;
        cases.push(CaseSteady {
            case: c.name(),
            steady_state: s,
        });
    }
    let damper_return = if has_damper && search_return {
        let sys = model.impact_system(Case::Damper)?;
        Some(return_rate(&sys, &opts, &so, rate_bpm)?)
    } else {
        None
    };
    let mut p = Production {
        rate_bpm,
        interval_s: 60.0 / rate_bpm,
        cases,
        damper_return,
        verdict: Vec::new(),
    };
    p.verdict = verdict(&p);
    Ok(p)
}

fn case_of(c: CaseName) -> Case {
    match c {
        CaseName::NoDamper => Case::NoDamper,
        CaseName::Damper => Case::Damper,
        CaseName::AddedMass => Case::AddedMass,
    }
}

/// Does the damper touch the bed in every steady blow at `rate`? (An irregular train counts
/// as not returning: it does not touch in every blow of a settled regime.)
fn touches(
    sys: &crate::impact::ImpactSystem,
    opts: &Options,
    so: &SteadyOptions,
    rate: f64,
) -> Result<bool> {
    let s = steady_state(
        sys,
        opts,
        &SteadyOptions {
            rate_bpm: rate,
            ..*so
        },
    )?;
    Ok(s.damper_returns())
}

/// The largest stroke rate at or below `rate_bpm` at which the damper touches the bed in every
/// steady blow: if it does at `rate_bpm`, that rate; else the rate is halved until it does
/// (down to `rate_bpm / 64`, or the lowest rate the run-length limit allows), then the bracket is bisected in log-rate to 0.5 %. The search
/// assumes one change from returning to not returning inside the bracket; a rate-dependent
/// comb filter can make returning non-monotonic in the rate, so the answer is the edge of the
/// bracket found, not a guarantee for every lower rate.
pub fn return_rate(
    sys: &crate::impact::ImpactSystem,
    opts: &Options,
    so: &SteadyOptions,
    rate_bpm: f64,
) -> Result<ReturnRate> {
    let Some(d) = sys.damper.as_ref() else {
        return Err(Error::invalid(
            "damper",
            "the damper's return rate needs a model with a damper",
        ));
    };
    let tau = if d.stiffness > 0.0 {
        d.damping / d.stiffness
    } else {
        f64::INFINITY
    };
    let zeta = d.damping / (2.0 * (d.stiffness * d.mass).sqrt());
    let resolution = 0.005;
    let lowest = rate_bpm / 64.0;
    let mut out = ReturnRate {
        rate_bpm: None,
        resolution,
        lowest_rate_bpm: lowest,
        return_time_constant_s: tau,
        damper_damping_ratio: zeta,
    };
    if touches(sys, opts, so, rate_bpm)? {
        out.rate_bpm = Some(rate_bpm);
        out.lowest_rate_bpm = rate_bpm;
        return Ok(out);
    }
    let mut hi = rate_bpm;
    let mut lo = rate_bpm / 2.0;
    loop {
        // A rate whose blow exceeds the run-length limit ([`crate::integrate::check_cost`]) ends the
        // search there: the lowest rate tried is reported.
        match touches(sys, opts, so, lo) {
            Ok(true) => break,
            Ok(false) => {}
            Err(_) => {
                out.lowest_rate_bpm = hi;
                return Ok(out);
            }
        }
        hi = lo;
        lo /= 2.0;
        if lo < lowest * (1.0 - 1e-12) {
            return Ok(out);
        }
    }
    while hi / lo > 1.0 + resolution {
        let mid = (lo * hi).sqrt();
        if touches(sys, opts, so, mid).unwrap_or(false) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    out.rate_bpm = Some(lo);
    Ok(out)
}

/// `20 log10(a/b)` (dB).
pub(crate) fn db(a: f64, b: f64) -> f64 {
    20.0 * (a / b).log10()
}

/// "3.6 dB higher" / "2.1 dB lower".
fn change(a: f64, b: f64) -> String {
    let v = db(a, b);
    if v.abs() < 0.05 {
        "the same (within 0.05 dB)".into()
    } else if v > 0.0 {
        format!("{:.1} dB higher", v)
    } else {
        format!("{:.1} dB lower", -v)
    }
}

/// [`change`] followed by what it compares with: "3.6 dB higher than", "the same (within
/// 0.05 dB) as".
fn change_than(a: f64, b: f64) -> String {
    let c = change(a, b);
    if c.starts_with("the same") {
        c + " as"
    } else {
        c + " than"
    }
}

fn sig(v: f64, d: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor() as i32;
    let decimals = (d as i32 - 1 - e).max(0) as usize;
    format!("{v:.decimals$}")
}

/// The verdict in words, one sentence per case, the damper's first (module docs): whether the
/// damper returns between blows, its steady floor force and bed acceleration against the
/// machine without it, the added mass's, and the rate at which it returns.
pub fn verdict(p: &Production) -> Vec<String> {
    let rate = crate::num(p.rate_bpm);
    let mut out = Vec::new();
    let none = p.case(CaseName::NoDamper);
    let levels = |s: &SteadyState| {
        format!(
            "steady floor force {} N, bed acceleration {} m/s²",
            sig(s.peak_floor_force_n, 4),
            sig(s.peak_bed_acceleration_m_per_s2, 4)
        )
    };
    let regime = |s: &SteadyState| match s.period_blows {
        Some(1) if s.converged => String::new(),
        Some(k) if s.converged => {
            format!(" (a period-{k} regime: levels are the largest over its {k} blows)")
        }
        _ => " (irregular: no repeating pattern was found, the levels are an estimate)".into(),
    };
    if let (Some(d), Some(n)) = (p.case(CaseName::Damper), none) {
        let returns = d.damper_touches_bed == Some(true);
        let head = if returns {
            format!(
                "At {rate} blows/min the damper returns to the bed before every blow and takes its momentum: "
            )
        } else {
            let gap = d.damper_gap_at_strike_m.map_or(String::new(), |g| {
                format!(" (gap {} mm at the strike)", sig(1e3 * g, 3))
            });
            format!(
                "At {rate} blows/min the damper does not return between blows: in the steady blow it no longer touches the bed{gap}, and "
            )
        };
        out.push(format!(
            "{head}the steady floor force is {} without it ({} N against {} N) and the bed acceleration {} ({} against {} m/s²){}.",
            change_than(d.peak_floor_force_n, n.peak_floor_force_n),
            sig(d.peak_floor_force_n, 4),
            sig(n.peak_floor_force_n, 4),
            change(d.peak_bed_acceleration_m_per_s2, n.peak_bed_acceleration_m_per_s2),
            sig(d.peak_bed_acceleration_m_per_s2, 4),
            sig(n.peak_bed_acceleration_m_per_s2, 4),
            regime(d),
        ));
        if let Some(r) = &p.damper_return {
            out.push(match r.rate_bpm {
                Some(_) if returns => format!(
                    "It returns at this rate; its return time constant c_d/k_d is {} s.",
                    sig(r.return_time_constant_s, 3)
                ),
                Some(x) => format!(
                    "It returns at {} blows/min or less (to {} %; its return is an overdamped creep with time constant c_d/k_d = {} s): a stiffer damper spring or a weaker dashpot lets it return faster.",
                    sig(x, 3),
                    sig(100.0 * r.resolution, 1),
                    sig(r.return_time_constant_s, 3)
                ),
                None => format!(
                    "It does not return at any rate down to {} blows/min (return time constant c_d/k_d = {} s).",
                    sig(r.lowest_rate_bpm, 3),
                    sig(r.return_time_constant_s, 3)
                ),
            });
        }
    }
    if let (Some(a), Some(n)) = (p.case(CaseName::AddedMass), none) {
        out.push(format!(
            "The same mass added rigidly instead gives a steady floor force {} and a bed acceleration {} the machine without it{}.",
            change(a.peak_floor_force_n, n.peak_floor_force_n),
            change_than(a.peak_bed_acceleration_m_per_s2, n.peak_bed_acceleration_m_per_s2),
            regime(a),
        ));
    }
    if let Some(n) = none {
        out.push(format!(
            "Without a damper, at {rate} blows/min: {}{}.",
            levels(n),
            regime(n)
        ));
    }
    out
}

/// One stroke rate of the map ([`stroke_rate_map`]).
#[derive(Debug, Clone, Serialize)]
pub struct RateRow {
    pub rate_bpm: f64,
    pub cases: Vec<CaseSteady>,
}

/// The steady states of every case at each of `rates` (blows/min), in parallel over the rates.
/// `progress(done, total)` is called as rates finish.
pub fn stroke_rate_map(
    model: &Model,
    rates: &[f64],
    so: &SteadyOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<RateRow>> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    for &r in rates {
        super::blows::blow_interval_s(r)?;
    }
    let done = AtomicUsize::new(0);
    let n = rates.len();
    rates
        .par_iter()
        .map(|&r| {
            let p = production(model, r, so, false)?;
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, n);
            Ok(RateRow {
                rate_bpm: r,
                cases: p.cases,
            })
        })
        .collect()
}

/// The largest rate of a map at which the damper touches the bed in every steady blow, with
/// every lower rate of the map touching too (`None` when the lowest rate already fails).
pub fn largest_returning_rate(rows: &[RateRow]) -> Option<f64> {
    let mut best = None;
    let mut sorted: Vec<&RateRow> = rows.iter().collect();
    sorted.sort_by(|a, b| a.rate_bpm.total_cmp(&b.rate_bpm));
    for r in sorted {
        let d = r.cases.iter().find(|c| c.case == CaseName::Damper.name())?;
        if d.steady_state.damper_returns() {
            best = Some(r.rate_bpm);
        } else {
            break;
        }
    }
    best
}
