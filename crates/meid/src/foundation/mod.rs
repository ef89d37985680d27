//! From the floor to the neighbours: the foundation's impedances, its checks (block and anvil
//! amplitude, pad stress, soil pressure) and the ground vibration at the model's receivers with
//! DIN 4150-3's and the people-in-buildings checks (docs/foundation.md).
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

/// The run of `case` measured at the mode-shape row `row` (a point, or a difference of two),
/// with the force to the floor replaced by `floor` when given.
fn probe(
    model: &Model,
    case: Case,
    row: Vec<f64>,
    floor: Option<FloorForce>,
    record: bool,
) -> Result<energy::Run> {
    let mut m = model.clone();
    m.structure.points.insert(PROBE.to_string(), row);
    if floor.is_some() {
        m.structure.floor_force = floor;
    }
    m.spec.points.measurement = PROBE.to_string();
    let sys = m.impact_system(case)?;
    energy::simulate(&sys, &m.options(), record)
}

fn peak<'a>(run: &'a energy::Run, key: &str) -> Result<&'a ChannelPeak> {
    run.summary
        .peaks
        .iter()
        .find(|p| p.channel == key)
        .ok_or_else(|| Error::numerical("foundation", format!("no {key} channel in the run")))
}

/// The foundation and receivers of `model` for `case`; `None` without a `[foundation]`.
pub fn assess(model: &Model, case: Case) -> Result<Option<FoundationAssessment>> {
    let Some(found) = model.foundation()? else {
        return Ok(None);
    };
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
    let run = probe(model, case, block, Some(soil), true)?;
    let disp = peak(&run, "bed_displacement_m")?.clone();
    let vel = peak(&run, "bed_velocity_m_per_s")?.clone();
    let acc = peak(&run, "bed_acceleration_m_per_s2")?.clone();
    let force = peak(&run, "floor_force_n")?.clone();
    let anvil = match &spec.anvil {
        Some(a) => Some(
            peak(
                &probe(model, case, row(a)?, None, false)?,
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
            let r = probe(model, case, rel, None, false)?;
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
    let receivers = receivers(model, &found, &vel, &history)?;
    Ok(Some(FoundationAssessment {
        case: case.name(),
        foundation: FoundationResult {
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

/// The receivers' vibration from the block's exact peak velocity `vel` and its sampled history.
fn receivers(
    model: &Model,
    f: &Foundation,
    vel: &ChannelPeak,
    h: &energy::History,
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
    let f_zc = i_peak.and_then(|i| standards::zero_crossing_hz(&h.time_s, v, i));
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
    let weighted = standards::wm_filter(&h.bed_acceleration_m_per_s2, fs);
    let mtvv_block = standards::max_running_rms(&weighted, fs, 1.0);
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
