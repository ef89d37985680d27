//! From the floor to the neighbours: the foundation's impedances, its checks (block and anvil
//! amplitude, pad stress, soil pressure) and the ground vibration at the model's receivers with
//! DIN 4150-3's and the people-in-buildings checks (docs/explanations/foundation.md).
//!
//! Every number comes from meid's exact solution of one blow ([`crate::analysis::energy`]): the
//! block's displacement, velocity and acceleration, the pad's compression and the soil's force
//! `k_z u + c_z u̇` are response functionals of the modal state, so their peaks are located on
//! the continuous solution like every channel's. A receiver at distance r sees the block's
//! velocity scaled by the Bornitz factor ([`standards::bornitz_factor`], with r1 the block's
//! equivalent radius): its peak particle velocity is the block's exact peak times that factor,
//! and its time history the block's sampled history times the same factor (a
//! frequency-independent law keeps the waveform).

pub mod standards;

use serde::Serialize;

use crate::analysis::energy::{self, ChannelPeak};
use crate::analysis::spectrum::{self, Padding, Window};
use crate::analysis::steady::{self, Regime, Replayed, SteadyOptions, SteadyState};
use crate::integrate::Options;
use crate::modal::FloorForce;
use crate::model::foundation::{self, Excitation, Foundation, Impedance, BUILDINGS, G_N};
use crate::model::{Case, Model};
use crate::{Error, Result};

/// The verdict of one check.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Check {
    /// What is checked ("block amplitude", "DIN 4150-3 long-term, line 2", ...).
    pub check: String,
    /// The value and its limit, SI units (`limit` `None`: not applicable).
    pub value: f64,
    pub limit: Option<f64>,
    pub unit: &'static str,
    /// "pass", "fail" or "not applicable".
    pub verdict: &'static str,
    /// `(limit − value)/limit` (positive: within by that share; negative: exceeds).
    pub margin: Option<f64>,
    /// Where the limit comes from, or why there is none.
    pub basis: String,
}

impl Check {
    fn new(
        check: String,
        value: f64,
        limit: Option<f64>,
        unit: &'static str,
        basis: String,
    ) -> Self {
        let (verdict, margin) = match limit {
            Some(l) => (
                if value <= l { "pass" } else { "fail" },
                Some((l - value) / l),
            ),
            None => ("not applicable", None),
        };
        Check {
            check,
            value,
            limit,
            unit,
            verdict,
            margin,
            basis,
        }
    }
}

/// The foundation's numbers and checks for one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FoundationResult {
    /// The blow the checks judge: one from rest, or the steady blow of the train.
    pub blow_basis: BlowBasis,
    /// The `[foundation]` as meid reads it: the mass on the soil, k_z, c_z, r1, the law.
    pub model: Foundation,
    pub impedances: Vec<Impedance>,
    /// The block alone on the soil: √(k_z/m) (rad/s) and the damping ratio c_z/(2√(k_z m)).
    pub block_omega_rad_per_s: f64,
    pub block_damping_ratio: f64,
    /// Exact peaks over the run: block displacement, velocity, acceleration and soil force.
    pub block_peaks: Vec<ChannelPeak>,
    pub peak_block_displacement_m: f64,
    pub peak_block_velocity_m_per_s: f64,
    pub peak_anvil_displacement_m: Option<f64>,
    pub peak_pad_stress_pa: Option<f64>,
    pub static_soil_pressure_pa: f64,
    pub peak_dynamic_soil_pressure_pa: f64,
    pub checks: Vec<Check>,
}

/// One receiver's ground vibration and checks.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReceiverResult {
    pub name: String,
    pub distance_m: f64,
    pub building: String,
    /// DIN 4150-3's line (1, 2, 3).
    pub building_line: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
    /// v(r)/v(r1).
    pub attenuation_factor: f64,
    /// Peak particle velocity (vertical, the one component meid computes; m/s) and its time.
    pub ppv_m_per_s: f64,
    pub ppv_time_s: f64,
    /// Dominant frequency by the zero-crossing method (used by the DIN 4150-3 check) and by the
    /// peak of the amplitude spectrum (Hz).
    pub frequency_zero_crossing_hz: Option<f64>,
    pub frequency_spectrum_peak_hz: Option<f64>,
    /// The largest 1 s running r.m.s. of the W_m-weighted acceleration (m/s²).
    pub weighted_acceleration_mtvv_m_per_s2: f64,
    pub checks: Vec<Check>,
    /// The sentence of the verdict.
    pub verdict: String,
    /// The sampled velocity history (m/s) on [`FoundationAssessment::time_s`].
    #[serde(skip)]
    pub velocity_m_per_s: Vec<f64>,
}

/// The foundation and receivers of one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FoundationAssessment {
    pub case: &'static str,
    pub foundation: FoundationResult,
    pub receivers: Vec<ReceiverResult>,
    #[serde(skip)]
    pub time_s: Vec<f64>,
}

/// The name of the probe point the assessment measures at (not a model name).
const PROBE: &str = " foundation probe";

/// Which blow the checks judge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Basis {
    /// One blow struck on the machine at rest (`[simulation] duration`).
    FromRest,
    /// The periodic steady blow of the train at this stroke rate ([`steady::steady_state`]):
    /// what the neighbours feel in production.
    Steady(SteadyOptions),
}

impl Basis {
    /// The model's own basis: the steady blow at its `[production] rate_bpm`, else one blow
    /// from rest.
    pub fn of(model: &Model) -> Self {
        match model.stroke_rate_bpm() {
            Some(rate_bpm) => Basis::Steady(SteadyOptions {
                rate_bpm,
                ..SteadyOptions::default()
            }),
            None => Basis::FromRest,
        }
    }
}

/// The blow the checks judged, as the JSON and the report state it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlowBasis {
    /// "one blow from rest" or "steady blow of the train".
    pub blow: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_bpm: Option<f64>,
    /// The steady regime ("period-1", …, "irregular"), whether it converged and its residual
    /// (energy norm relative to the blow's energy, [`steady`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub regime: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub converged: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual: Option<f64>,
    /// With a damper: whether it touches the bed in every steady blow.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damper_touches_bed: Option<bool>,
    /// The sentence: which blow, and what that means for the checks.
    pub statement: String,
}

/// What one probe measured: its channels' exact peaks (over the judged blows) and, when
/// recorded, its samples (the steady period's blows one after the other).
struct Measured {
    peaks: Vec<ChannelPeak>,
    history: Option<energy::History>,
}

/// The judged blow(s) of one case: from rest, or the steady state to replay.
enum Blows {
    FromRest,
    Steady(Box<SteadyState>),
}

/// The run of `case` measured at the mode-shape row `row` (a point, or a difference of two),
/// with the force to the floor replaced by `floor` when given. The probe changes what is
/// measured, not the dynamics: a steady state found on the case's system replays on it.
fn probe(
    model: &Model,
    case: Case,
    row: Vec<f64>,
    floor: Option<FloorForce>,
    record: bool,
    blows: &Blows,
) -> Result<Measured> {
    let mut m = model.clone();
    m.structure.points.insert(PROBE.to_string(), row);
    if floor.is_some() {
        m.structure.floor_force = floor;
    }
    m.spec.points.measurement = PROBE.to_string();
    let sys = m.impact_system(case)?;
    let opts = m.options();
    let s = match blows {
        Blows::FromRest => {
            let run = energy::simulate(&sys, &opts, record)?;
            return Ok(Measured {
                peaks: run.summary.peaks,
                history: run.history,
            });
        }
        Blows::Steady(s) => s,
    };
    let opts = Options {
        sample_rate: if record { opts.sample_rate } else { None },
        ..opts
    };
    if record {
        let n = s.blows.len() as f64 * energy::sample_count(s.interval_s, opts.sample_rate);
        crate::limits::check_memory(
            &format!("the steady blows' history ({n:.3e} samples)"),
            energy::History::bytes_for(n),
            "simulation.sample_rate",
            "simulation.sample_rate (--rate)",
        )?;
    }
    let replayed = steady::replay(&sys, &opts, s)?;
    let per_blow: Vec<Vec<ChannelPeak>> = replayed
        .iter()
        .map(|r| energy::channel_peaks(&sys, &r.solution.totals.peaks))
        .collect();
    let history = record.then(|| period_history(&replayed, s.interval_s));
    Ok(Measured {
        peaks: worst_peaks(&per_blow, s.interval_s),
        history,
    })
}

/// Each channel's peak over the blows of a period (blow `b` struck at `b·T`): the largest
/// magnitude, the largest maximum and the smallest minimum, each at its time in the period.
fn worst_peaks(per_blow: &[Vec<ChannelPeak>], interval_s: f64) -> Vec<ChannelPeak> {
    let mut out: Vec<ChannelPeak> = Vec::new();
    for (b, peaks) in per_blow.iter().enumerate() {
        let t0 = b as f64 * interval_s;
        for p in peaks {
            let mut q = p.clone();
            q.time_s += t0;
            q.max_time_s += t0;
            q.min_time_s += t0;
            match out.iter_mut().find(|o| o.channel == p.channel) {
                None => out.push(q),
                Some(o) => {
                    if q.peak > o.peak {
                        (o.peak, o.time_s) = (q.peak, q.time_s);
                    }
                    if q.max > o.max {
                        (o.max, o.max_time_s) = (q.max, q.max_time_s);
                    }
                    if q.min < o.min {
                        (o.min, o.min_time_s) = (q.min, q.min_time_s);
                    }
                }
            }
        }
    }
    out
}

/// The steady period's samples: blow `b`'s samples at `b·T + t`, the sample at a blow's end
/// left out where the next blow's strike repeats it.
fn period_history(replayed: &[Replayed], interval_s: f64) -> energy::History {
    let mut h = energy::History::default();
    let n = replayed.len();
    for (b, r) in replayed.iter().enumerate() {
        let t0 = b as f64 * interval_s;
        let rows = r.history.time_s.len();
        for i in 0..rows {
            let mut row = r.history.row(i);
            if b + 1 < n && i + 1 == rows && row[0] >= interval_s * (1.0 - 1e-12) {
                continue;
            }
            row[0] += t0;
            h.push_row(&row);
        }
    }
    h
}

fn peak<'a>(run: &'a Measured, key: &str) -> Result<&'a ChannelPeak> {
    run.peaks
        .iter()
        .find(|p| p.channel == key)
        .ok_or_else(|| Error::numerical("foundation", format!("no {key} channel in the run")))
}

/// The blows `basis` judges in `case`, and their statement.
fn judged_blows(model: &Model, case: Case, basis: &Basis) -> Result<(Blows, BlowBasis)> {
    let so = match basis {
        Basis::FromRest => {
            return Ok((
                Blows::FromRest,
                BlowBasis {
                    blow: "one blow from rest",
                    rate_bpm: None,
                    regime: None,
                    converged: None,
                    residual: None,
                    damper_touches_bed: None,
                    statement: "the checks judge one blow struck on the machine at rest \
                                (no stroke rate given: [production] rate_bpm or --rate-bpm)"
                        .into(),
                },
            ))
        }
        Basis::Steady(so) => so,
    };
    let sys = model.impact_system(case)?;
    let s = steady::steady_state(&sys, &model.options(), so)?;
    let rate = crate::num(s.rate_bpm);
    let statement = match (s.regime, s.converged) {
        (Regime::Period(1), true) => format!(
            "the checks judge the steady blow of the train at {rate} /min (period-1, residual \
             {:.1e}){}",
            s.residual,
            returns_clause(s.damper_touches_bed)
        ),
        (Regime::Period(k), true) => format!(
            "the checks judge the steady blows of the train at {rate} /min (period-{k}: the \
             largest peak over its {k} blows, residual {:.1e}){}",
            s.residual,
            returns_clause(s.damper_touches_bed)
        ),
        _ => format!(
            "the checks judge the last {} blows of the train at {rate} /min, which settles in \
             no period of at most {} blows (an estimate; residual {:.1e})",
            s.blows.len(),
            so.max_period,
            s.residual
        ),
    };
    let basis = BlowBasis {
        blow: "steady blow of the train",
        rate_bpm: Some(s.rate_bpm),
        regime: Some(s.regime.name()),
        converged: Some(s.converged),
        residual: Some(s.residual),
        damper_touches_bed: s.damper_touches_bed,
        statement,
    };
    Ok((Blows::Steady(Box::new(s)), basis))
}

fn returns_clause(touches: Option<bool>) -> &'static str {
    match touches {
        Some(true) => "; the damper returns to the bed before every strike",
        Some(false) => "; the damper does not return to the bed between blows",
        None => "",
    }
}

/// The foundation and receivers of `model` for `case` on the model's own basis
/// ([`Basis::of`]); `None` without a `[foundation]`.
pub fn assess(model: &Model, case: Case) -> Result<Option<FoundationAssessment>> {
    assess_with(model, case, &Basis::of(model))
}

/// The foundation and receivers of `model` for `case`, judging the blow(s) `basis` names;
/// `None` without a `[foundation]`.
pub fn assess_with(
    model: &Model,
    case: Case,
    basis: &Basis,
) -> Result<Option<FoundationAssessment>> {
    let Some(found) = model.foundation()? else {
        return Ok(None);
    };
    let (blows, blow_basis) = judged_blows(model, case, basis)?;
    let spec = model
        .spec
        .foundation
        .as_ref()
        .ok_or_else(|| Error::invalid("foundation", "the model has no [foundation]"))?;
    let st = &model.structure;
    let row = |name: &str| -> Result<Vec<f64>> {
        st.points.get(name).cloned().ok_or_else(|| {
            Error::invalid(
                "foundation",
                format!("'{name}' is not a point of the structure"),
            )
        })
    };
    let block = row(&found.mass_name)?;
    let soil = FloorForce {
        stiffness: block.iter().map(|v| found.k_z_n_per_m * v).collect(),
        damping: block.iter().map(|v| found.c_z_n_s_per_m * v).collect(),
    };
    let run = probe(model, case, block, Some(soil), true, &blows)?;
    let disp = peak(&run, "bed_displacement_m")?.clone();
    let vel = peak(&run, "bed_velocity_m_per_s")?.clone();
    let acc = peak(&run, "bed_acceleration_m_per_s2")?.clone();
    let force = peak(&run, "floor_force_n")?.clone();
    let anvil = match &spec.anvil {
        Some(a) => Some(
            peak(
                &probe(model, case, row(a)?, None, false, &blows)?,
                "bed_displacement_m",
            )?
            .peak,
        ),
        None => None,
    };
    let lumped = model.spec.structure.lumped.as_ref();
    let pad = match (&spec.pad, lumped) {
        (Some(p), Some(l)) => {
            let sp = l
                .springs
                .iter()
                .find(|s| s.name.as_deref() == Some(&p.spring))
                .ok_or_else(|| Error::invalid("foundation.pad.spring", "no such spring"))?;
            let (a, b) = (row(&sp.nodes[0])?, row(&sp.nodes[1])?);
            let rel: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x - y).collect();
            let r = probe(model, case, rel, None, false, &blows)?;
            Some(sp.stiffness * peak(&r, "bed_displacement_m")?.peak / p.area)
        }
        _ => None,
    };
    let total_mass: f64 =
        lumped.map_or(0.0, |l| l.masses.iter().map(|m| m.mass).sum::<f64>()) + found.block_mass_kg;
    let area = found.area_m2();
    let static_p = total_mass * G_N / area;
    let dynamic_p = force.peak / area;
    let allow = &spec.allowable;
    let checks = [
        (
            "block amplitude",
            Some(disp.peak),
            allow.block_amplitude,
            "m",
        ),
        ("anvil amplitude", anvil, allow.anvil_amplitude, "m"),
        ("pad stress", pad, allow.pad_stress, "Pa"),
        (
            "soil pressure (static + dynamic)",
            Some(static_p + dynamic_p),
            allow.soil_pressure,
            "Pa",
        ),
    ]
    .into_iter()
    .filter_map(|(name, value, limit, unit)| {
        let basis = match limit {
            Some(_) => "foundation.allowable".to_string(),
            None => "no allowable value given (foundation.allowable)".to_string(),
        };
        value.map(|v| Check::new(name.into(), v, limit, unit, basis))
    })
    .collect();
    let m_soil = found.mass_on_soil_kg;
    let history = run.history.unwrap_or_default();
    let (interval_s, period_s) = match &blows {
        Blows::FromRest => (None, None),
        Blows::Steady(s) => (
            Some(s.interval_s),
            Some(s.interval_s * s.blows.len() as f64),
        ),
    };
    let receivers = receivers(model, &found, &vel, &history, interval_s, period_s)?;
    Ok(Some(FoundationAssessment {
        case: case.name(),
        foundation: FoundationResult {
            blow_basis,
            impedances: foundation::impedances(&found),
            block_omega_rad_per_s: (found.k_z_n_per_m / m_soil).sqrt(),
            block_damping_ratio: found.c_z_n_s_per_m / (2.0 * (found.k_z_n_per_m * m_soil).sqrt()),
            block_peaks: vec![disp.clone(), vel.clone(), acc, force],
            peak_block_displacement_m: disp.peak,
            peak_block_velocity_m_per_s: vel.peak,
            peak_anvil_displacement_m: anvil,
            peak_pad_stress_pa: pad,
            static_soil_pressure_pa: static_p,
            peak_dynamic_soil_pressure_pa: dynamic_p,
            checks,
            model: found,
        },
        receivers,
        time_s: history.time_s,
    }))
}

/// The receivers' vibration from the block's exact peak velocity `vel` and its sampled history
/// (one blow from rest, or the steady period of `period_s` seconds of blows struck every
/// `interval_s`: [`weighted_mtvv`], [`zero_crossing_of_blow`]).
fn receivers(
    model: &Model,
    f: &Foundation,
    vel: &ChannelPeak,
    h: &energy::History,
    interval_s: Option<f64>,
    period_s: Option<f64>,
) -> Result<Vec<ReceiverResult>> {
    let fs = model.spec.simulation.sample_rate;
    let v = &h.bed_velocity_m_per_s;
    // The sample nearest the exact peak: the zero crossings around it.
    let i_peak = h
        .time_s
        .iter()
        .enumerate()
        .min_by(|a, b| {
            (a.1 - vel.time_s)
                .abs()
                .total_cmp(&(b.1 - vel.time_s).abs())
        })
        .map(|(i, _)| i);
    let f_zc = i_peak.and_then(|i| zero_crossing_of_blow(&h.time_s, v, i, interval_s));
    let f_spec = if v.len() >= 2 {
        let s = spectrum::amplitude_spectrum_padded(
            v,
            fs,
            Window::Rectangular,
            Padding::NextPowerOfTwo,
        )?;
        s.amplitude
            .iter()
            .enumerate()
            .skip(1)
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(k, _)| s.frequency_hz[k])
    } else {
        None
    };
    let mtvv_block = weighted_mtvv(&h.bed_acceleration_m_per_s2, fs, period_s);
    let mut out = Vec::new();
    for r in &model.spec.receiver {
        let line = BUILDINGS
            .iter()
            .position(|b| *b == r.building)
            .map_or(2, |i| i + 1);
        let a = standards::bornitz_factor(
            f.equivalent_radius_m,
            r.distance,
            f.geometric_exponent,
            f.attenuation_per_m,
        );
        let ppv = a * vel.peak;
        let mut checks = Vec::new();
        let din = match f.excitation {
            Excitation::LongTerm => Check::new(
                format!("DIN 4150-3 long-term, line {line}"),
                ppv,
                Some(standards::din4150_3_long_term_m_per_s(line)),
                "m/s",
                "DIN 4150-3 (1999-02) Table 3 (all frequencies; the standard measures it at the highest floor, meid's value is the ground's)".into(),
            ),
            Excitation::ShortTerm => match f_zc {
                Some(fz) => Check::new(
                    format!("DIN 4150-3 short-term, line {line}, at {fz:.1} Hz"),
                    ppv,
                    Some(standards::din4150_3_short_term_m_per_s(line, fz)),
                    "m/s",
                    "DIN 4150-3 (1999-02) Table 1, foundation, at the zero-crossing frequency".into(),
                ),
                None => Check::new(
                    format!("DIN 4150-3 short-term, line {line}"),
                    ppv,
                    None,
                    "m/s",
                    "no dominant frequency: the record does not cross zero around its peak".into(),
                ),
            },
        };
        checks.push(din);
        let mtvv = a * mtvv_block;
        checks.push(Check::new(
            "people in buildings (W_m, MTVV 1 s)".into(),
            mtvv,
            r.people_limit,
            "m/s²",
            r.people_limit.map_or_else(
                || "no limit given (receiver.people_limit)".to_string(),
                |_| "receiver.people_limit".to_string(),
            ),
        ));
        let verdict = sentence(r.distance, line, &checks[0]);
        out.push(ReceiverResult {
            name: r.name.clone(),
            distance_m: r.distance,
            building: r.building.clone(),
            building_line: line,
            kind: r.kind.clone(),
            attenuation_factor: a,
            ppv_m_per_s: ppv,
            ppv_time_s: vel.time_s,
            frequency_zero_crossing_hz: f_zc,
            frequency_spectrum_peak_hz: f_spec,
            weighted_acceleration_mtvv_m_per_s2: mtvv,
            checks,
            verdict,
            velocity_m_per_s: v.iter().map(|x| a * x).collect(),
        });
    }
    Ok(out)
}

/// The largest 1 s running r.m.s. of the W_m-weighted acceleration `a` sampled at `fs_hz`
/// (ISO 2631-2's MTVV with τ = 1 s, [`standards::wm_filter`]).
///
/// From rest (`period_s` `None`) `a` is the one blow, the filter starting at rest. In the
/// steady train `a` is one period of a periodic signal: it is repeated until the filter has
/// forgotten its start, [`SETTLE_S`] (its slowest poles, the 0.79 Hz high-pass of Q = 1/√2,
/// decay as e^{−3.5 t/s}: to 3e-5 in 3 s), and then for one more second and one more period,
/// and only the windows after that are counted: the steady r.m.s., which no choice of how many
/// periods are repeated changes.
fn weighted_mtvv(a: &[f64], fs_hz: f64, period_s: Option<f64>) -> f64 {
    let Some(period) = period_s else {
        return standards::max_running_rms(&standards::wm_filter(a, fs_hz), fs_hz, 1.0);
    };
    // One period's samples (a sample at its end would be the next period's first).
    let n = ((period * fs_hz).round() as usize).min(a.len());
    let one = &a[..n];
    if one.is_empty() {
        return 0.0;
    }
    let reps = ((SETTLE_S + 1.0 + period) / period).ceil() as usize + 1;
    let tiled: Vec<f64> = one.iter().copied().cycle().take(reps * n).collect();
    let weighted = standards::wm_filter(&tiled, fs_hz);
    let start = ((SETTLE_S * fs_hz) as usize).min(weighted.len());
    standards::max_running_rms(&weighted[start..], fs_hz, 1.0)
}

/// DIN 4150-3's zero-crossing frequency of the blow whose velocity peaks at sample `i_peak`
/// ([`standards::zero_crossing_hz`]), on the change of velocity since that blow's strike.
///
/// From rest the strike is at t = 0 with the block at rest, and this is the velocity itself. In
/// the steady train (`interval_s` given) the block still moves slightly at the strike (the
/// previous blow's tail, a damper creeping back): a crossing of that small offset may lie far
/// from the blow or nowhere in it, so the crossings are sought in `v − v(strike)`, the blow's own
/// response, from the strike on.
fn zero_crossing_of_blow(
    t: &[f64],
    v: &[f64],
    i_peak: usize,
    interval_s: Option<f64>,
) -> Option<f64> {
    let Some(interval) = interval_s else {
        return standards::zero_crossing_hz(t, v, i_peak);
    };
    let t_peak = *t.get(i_peak)?;
    let strike = (t_peak / interval).floor() * interval;
    let i0 = t.iter().position(|&x| x >= strike - 1e-12 * interval)?;
    let v0 = v[i0];
    let rel: Vec<f64> = v[i0..].iter().map(|x| x - v0).collect();
    standards::zero_crossing_hz(&t[i0..], &rel, i_peak.checked_sub(i0)?)
}

/// How long the W_m filter runs on the repeated steady period before its windows count (s).
const SETTLE_S: f64 = 3.0;

/// "the receiver at 20 m, building line 2, exceeds the long-term limit by 35 %".
fn sentence(r: f64, line: usize, c: &Check) -> String {
    let kind = if c.check.contains("long-term") {
        "long-term"
    } else {
        "short-term"
    };
    match (c.limit, c.margin) {
        (Some(l), Some(m)) if m < 0.0 => format!(
            "the receiver at {} m, building line {line}, exceeds the {kind} limit ({:.3} mm/s) by {:.0} %",
            crate::num(r),
            l * 1e3,
            -100.0 * m
        ),
        (Some(l), Some(m)) => format!(
            "the receiver at {} m, building line {line}, is within the {kind} limit ({:.3} mm/s) by {:.0} %",
            crate::num(r),
            l * 1e3,
            100.0 * m
        ),
        _ => format!(
            "the receiver at {} m, building line {line}: no {kind} limit applies ({})",
            crate::num(r),
            c.basis
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One period of a steady sinusoid `A sin(2π f t)`: its W_m-weighted steady r.m.s. is
    /// `A |W_m(f)| / √2` (the 1 s windows hold whole cycles), whatever the period it is given
    /// as (one, or two of the same signal).
    #[test]
    fn steady_mtvv_of_a_sinusoid_is_its_weighted_rms() {
        let (fs, f, amp) = (20_000.0, 20.0, 3.0);
        let wave = |period: f64| -> Vec<f64> {
            let n = (period * fs) as usize + 1;
            (0..n)
                .map(|i| amp * (2.0 * std::f64::consts::PI * f * i as f64 / fs).sin())
                .collect()
        };
        let want = amp * standards::wm_gain(f) / 2f64.sqrt();
        for period in [0.25, 0.5, 1.0, 2.5] {
            let got = weighted_mtvv(&wave(period), fs, Some(period));
            assert!(
                (got / want - 1.0).abs() < 1e-4,
                "T = {period}: {got} vs {want}"
            );
        }
        // The same steady signal given as two periods of 0.5 s, or one of 1 s.
        let one = weighted_mtvv(&wave(1.0), fs, Some(1.0));
        let halves = weighted_mtvv(&wave(0.5), fs, Some(0.5));
        assert!((one / halves - 1.0).abs() < 1e-9, "{one} vs {halves}");
    }
}
