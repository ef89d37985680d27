//! The "Test against model" section of `meid report` (issue 32 item 5): when the measured
//! records hold the blow's force and responses at the model's points, the report does what
//! `meid frf`, `meid identify`, `meid correlate` and (with `--fit`) `meid calibrate --modal`
//! do, on the same records and with their defaults, and sets the test beside the model:
//!
//! 1. **FRFs**: H1 accelerance (or mobility, receptance: by the response's quantity) of every
//!    response mapped to a model point against the blow force, with coherence over the blows
//!    ([`crate::measure::frf::estimate`]), processed as the section "Measured against
//!    simulated" processes the records (the same trigger, pre-trigger, record and window).
//! 2. **Modes**: LSCF poles and LSFD shapes ([`crate::identify`]) in the band from the first
//!    line above 0 Hz to 1.25 times the highest retained model mode (at most the last line),
//!    orders 1 … `max(20, 4 n)` (`n` the model modes in the band, at most 48), the default
//!    stability criteria; the stabilisation diagram.
//! 3. **Correlation**: the identified modes paired with the model's by the MAC at the mapped
//!    points ([`crate::measure::correlate`]: its pairing rule, MAC ≥ 0.5).
//! 4. **Updated model** (with `--fit`): the model values fitted to the identified modes
//!    ([`crate::measure::modal_update`]: relative frequency errors and `√W (1 − MAC)`).
//!
//! **Which records.** The case `none` (the bare machine) if measured, else the model as
//! specified, else the first case given. **Which channels.** The force is the channel mapped to
//! the blow (`--channel NAME=blow`, `[measurement] channels`, or its name: blow, hammer,
//! slider), else the only force not mapped to the floor. A response is a motion channel
//! sampled with the force whose point's entity (UFF record 6) or name is a model point, or the
//! channel mapped to the measurement point B (`--channel NAME=B` or its name); other channels
//! are left out, each named in a note. Without a force or a mapped response the section says
//! what is missing (with `--fit`, that is an error).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use serde::Serialize;

use super::figures::sig;
use super::html::{Block, Figure, Section, Table};
use crate::identify::{identify, FrfData, Identification, Settings as IdentifySettings};
use crate::measure::calibrate::{
    calibrated_model_text_by, parameters, parse_bounds, parse_fit, Settings as FitSettings,
};
use crate::measure::correlate::{
    correlate, parse_point_label, Correlation, IdentifiedMode, IdentifiedModes, Mapping,
    ModelModes, Settings as CorrelateSettings,
};
use crate::measure::frf::{estimate, frf_plots, FrfSet, FrfSettings};
use crate::measure::mapping::{map_records, MeasurementSpec};
use crate::measure::modal_update::{calibrate_modal, ModalCalibration, ModalProblem};
use crate::measure::process::{groups, Processing};
use crate::measure::validate::{case_name, MeasuredCase};
use crate::measure::{Quantity, SimChannel};
use crate::model::{Case, Model};
use crate::{Error, Result};

/// The data file of the section, linked under each of its figures.
pub const DATA_FILE: &str = "test_against_model.json";

/// The updated model's file (with `--fit`), written beside the page: the model's own text with
/// the fitted values in place, as `meid calibrate --modal -o` writes it.
pub const CALIBRATED_FILE: &str = "calibrated.toml";

/// Model updating asked of the section (`meid report --fit`, `--bounds`, `--mac-weight`).
#[derive(Debug, Clone, PartialEq)]
pub struct UpdateRequest {
    /// Model paths to fit, as `--set` names them (`PATH[,PATH…]` per entry); empty: no update.
    pub fit: Vec<String>,
    /// `PATH=LO..HI[,…]` bounds.
    pub bounds: Vec<String>,
    /// Weight `W` of `(1 − MAC)` beside the relative frequency errors.
    pub mac_weight: f64,
}

impl Default for UpdateRequest {
    fn default() -> Self {
        UpdateRequest {
            fit: Vec::new(),
            bounds: Vec::new(),
            mac_weight: 1.0,
        }
    }
}

/// A measured response and the model point it stands for.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MappedChannel {
    pub channel: String,
    /// Its point label (UFF record 6, or the channel's name and position, +Z).
    pub point: String,
    pub model_point: String,
    /// How: "point" (its entity names the model point), "name" (its name does) or
    /// "measurement point" (mapped to B).
    pub rule: String,
}

/// One model mode against the test.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeRow {
    /// 1-based, in the model's retained modes.
    pub model_mode: usize,
    pub label: String,
    pub model_frequency_hz: f64,
    pub model_damping_ratio: f64,
    /// The paired identified mode (1-based), its frequency, damping (window removed), the
    /// frequency error `100 (f_test − f_model)/f_model` % and the MAC; `None`: not found.
    pub test_mode: Option<usize>,
    pub test_frequency_hz: Option<f64>,
    pub test_damping_ratio: Option<f64>,
    pub error_percent: Option<f64>,
    pub mac: Option<f64>,
}

/// Everything the section computed.
#[derive(Debug, Clone, Serialize)]
pub struct TestAgainstModel {
    /// The lead sentence.
    pub verdict: String,
    pub case: String,
    pub files: Vec<String>,
    pub channels: Vec<MappedChannel>,
    pub frf: FrfSet,
    pub band_hz: (f64, f64),
    pub max_order: usize,
    pub identified_modes: Vec<crate::identify::Mode>,
    /// The model modes in the band, compared with the test (1-based numbers in `modes`).
    pub modes: Vec<ModeRow>,
    pub correlation: Correlation,
    pub update: Option<ModalCalibration>,
    /// The updated model's file name ([`CALIBRATED_FILE`]) when there is an update.
    pub calibrated_model_file: Option<String>,
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
    #[serde(skip)]
    pub identification: Identification,
    /// The updated model's text (written as [`CALIBRATED_FILE`]).
    #[serde(skip)]
    pub calibrated_model: Option<String>,
}

/// The section's result: done, or why not.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "status", rename_all = "kebab-case")]
pub enum Outcome {
    Done(Box<TestAgainstModel>),
    Skipped { reason: String },
}

/// The case the section uses (module docs).
fn pick_case(cases: &[MeasuredCase]) -> Option<&MeasuredCase> {
    [Case::NoDamper, Case::AsSpecified]
        .iter()
        .find_map(|c| cases.iter().find(|m| m.case == *c))
        .or_else(|| cases.first())
}

/// Runs the section on the measured `cases` (read as the comparison reads them), processed
/// with `p`, channels mapped by `section` and `flags`; `update` with a fit asks for the
/// updated model. `None` without measured records.
pub fn run(
    model: &Model,
    cases: &[MeasuredCase],
    p: &Processing,
    section: Option<&MeasurementSpec>,
    flags: &BTreeMap<String, SimChannel>,
    update: &UpdateRequest,
) -> Result<Option<Outcome>> {
    let Some(case) = pick_case(cases) else {
        return Ok(None);
    };
    // A bad --fit path is an input error, found before the FRFs.
    let fit = if update.fit.is_empty() {
        None
    } else {
        let paths = parse_fit(&update.fit)?;
        let bounds = parse_bounds(&update.bounds)?;
        Some(parameters(model, &paths, &bounds)?)
    };
    let wanted = fit.is_some();
    let skip = |reason: String| -> Result<Option<Outcome>> {
        if wanted {
            Err(Error::Input {
                location: case.files.join(", "),
                message: format!("--fit: no test to update the model from: {reason}"),
            })
        } else {
            Ok(Some(Outcome::Skipped { reason }))
        }
    };
    let (records, force, channels, mut notes) = match choose_channels(model, case, section, flags) {
        Ok(x) => x,
        Err(reason) => return skip(reason),
    };
    let s = FrfSettings {
        force: Some(force),
        responses: channels.iter().map(|c| c.channel.clone()).collect(),
        kind: frf_kind(&records, &channels),
        ..FrfSettings::default()
    };
    let point = model.spec.points.measurement.clone();
    let set = match estimate(&records, p, &s, &point) {
        Ok(set) => set,
        Err(e) => return skip(format!("the FRFs: {e}")),
    };
    let mm = ModelModes::new(model, None);
    let Some((band, in_band)) = band_of(&set, &mm.frequencies_hz) else {
        return skip(format!(
            "no model mode lies within the measured lines ({} .. {} Hz)",
            sig(set.channels[0].frequency_hz[0], 4),
            sig(
                set.channels[0].frequency_hz.last().copied().unwrap_or(0.0),
                4
            )
        ));
    };
    let max_order = (4 * in_band.len()).clamp(20, 48);
    let data = FrfData {
        frequency_hz: set.channels[0].frequency_hz.clone(),
        outputs: set.channels.len(),
        inputs: 1,
        h: set.channels.iter().map(|c| c.h.clone()).collect(),
        kind: set.kind,
        window_decay_per_s: set.window_decay_per_s,
    };
    let settings = IdentifySettings {
        band_hz: Some(band),
        max_order,
        ..IdentifySettings::default()
    };
    let id = match identify(&data, &settings) {
        Ok(id) => id,
        Err(e) => return skip(format!("the identification: {e}")),
    };
    // The mapped channels in the FRFs' order (the identified shapes' order).
    let channels: Vec<MappedChannel> = set
        .channels
        .iter()
        .filter_map(|c| channels.iter().find(|m| m.channel == c.response).cloned())
        .collect();
    let ident = identified(case, &set, &channels, &id);
    let mapping = Mapping {
        explicit: ident
            .points
            .iter()
            .zip(&channels)
            .map(|(p, c)| (p.label.clone(), c.model_point.clone()))
            .collect(),
        geometry: None,
    };
    // One measured point: the MAC of any two shapes is 1, so the pairs are by frequency.
    let corr_settings = CorrelateSettings {
        by_frequency: channels.len() == 1,
        ..CorrelateSettings::default()
    };
    let correlation = correlate(&ident, &mm, &mapping, &corr_settings)?;
    let update = match fit {
        Some(params) if !correlation.pairs.is_empty() => Some(updated_model(
            model,
            params,
            &ident,
            mapping,
            corr_settings,
            update.mac_weight,
        )?),
        Some(_) => {
            return skip(format!(
                "no identified mode pairs with a model mode at MAC ≥ {}",
                corr_settings.min_mac
            ))
        }
        None => None,
    };
    let modes = mode_rows(model, &mm, &in_band, &correlation, &id);
    let mut warnings = set.warnings.clone();
    warnings.extend(id.warnings.iter().cloned());
    warnings.extend(correlation.warnings.iter().cloned());
    notes.extend(set.notes.iter().cloned());
    notes.extend(id.notes.iter().cloned());
    let verdict = verdict(&modes, band.1, channels.len());
    Ok(Some(Outcome::Done(Box::new(TestAgainstModel {
        verdict,
        case: case_name(case.case).into(),
        files: case.files.clone(),
        channels,
        band_hz: band,
        max_order,
        identified_modes: id.modes.clone(),
        modes,
        correlation,
        calibrated_model_file: update.as_ref().map(|_| CALIBRATED_FILE.to_string()),
        calibrated_model: update.as_ref().map(|(_, text)| text.clone()),
        update: update.map(|(c, _)| c),
        warnings,
        notes,
        frf: set,
        identification: id,
    }))))
}

/// The model updated to the identified modes (`meid calibrate --modal`'s fit) and its file's
/// text ([`CALIBRATED_FILE`]).
fn updated_model(
    model: &Model,
    params: Vec<crate::measure::calibrate::FitParameter>,
    ident: &IdentifiedModes,
    mapping: Mapping,
    corr_settings: CorrelateSettings,
    mac_weight: f64,
) -> Result<(ModalCalibration, String)> {
    let problem = ModalProblem::new(
        model,
        params,
        ident,
        None,
        mapping,
        corr_settings,
        mac_weight,
        FitSettings::default(),
    )?;
    let c = calibrate_modal(&problem)?;
    let text = calibrated_model_text_by(
        model,
        problem.parameters(),
        &c.values(),
        "meid report --fit",
    )?;
    Ok((c, text))
}

/// The records sampled with the force, the force's name, the mapped responses and the notes
/// on channels left out; `Err(reason)` when the section cannot run (module docs).
type Chosen = (
    Vec<crate::measure::Record>,
    String,
    Vec<MappedChannel>,
    Vec<String>,
);

fn choose_channels(
    model: &Model,
    case: &MeasuredCase,
    section: Option<&MeasurementSpec>,
    flags: &BTreeMap<String, SimChannel>,
) -> std::result::Result<Chosen, String> {
    let records = &case.records;
    let point = model.spec.points.measurement.clone();
    let mapped = map_records(records, section, flags, &point).map_err(|e| e.to_string())?;
    let force = match mapped.get(&SimChannel::BlowForce) {
        Some(&k) => k,
        None => {
            let floor = mapped.get(&SimChannel::FloorForce).copied();
            let forces: Vec<usize> = (0..records.len())
                .filter(|&k| records[k].quantity == Quantity::Force && Some(k) != floor)
                .collect();
            match forces[..] {
                [k] => k,
                [] => return Err(format!(
                    "the measured records of case {} ({}) hold no blow force (the force that strikes the machine, in N): FRFs need it; name it blow, hammer or slider, or map it with --channel NAME=blow",
                    case_name(case.case),
                    case.files.join(", ")
                )),
                _ => return Err(format!(
                    "the measured records of case {} hold several forces and none is mapped to the blow: map it with --channel NAME=blow",
                    case_name(case.case)
                )),
            }
        }
    };
    let group = groups(records)
        .into_iter()
        .find(|g| g.contains(&force))
        .unwrap_or_else(|| vec![force]);
    let model_points: BTreeSet<&str> = model.structure.points.keys().map(|s| s.as_str()).collect();
    let mut chosen: Vec<(usize, MappedChannel)> = Vec::new();
    let mut notes = Vec::new();
    for &k in group.iter().filter(|&&k| k != force) {
        let r = &records[k];
        if !matches!(
            r.quantity,
            Quantity::Acceleration | Quantity::Velocity | Quantity::Displacement
        ) {
            continue;
        }
        let entity = r.point.as_ref().map(|p| p.entity.as_str()).unwrap_or("");
        let direction = r.point.as_ref().map_or(3, |p| p.direction);
        let (model_point, rule) = if model_points.contains(entity) {
            (entity.to_string(), "point")
        } else if model_points.contains(r.name.as_str()) {
            (r.name.clone(), "name")
        } else if mapped.get(&SimChannel::BedAcceleration) == Some(&k) {
            (point.clone(), "measurement point")
        } else {
            notes.push(format!(
                "'{}' ({}) names no model point ({}): left out of the test against the model; name its point or channel after one, or map it to the measurement point with --channel {}=B",
                r.name,
                r.origin,
                model_points.iter().copied().collect::<Vec<_>>().join(", "),
                r.name
            ));
            continue;
        };
        if !matches!(direction, 0 | 3 | -3) {
            notes.push(format!(
                "'{}' ({}) measures along direction {direction}, not the model's axis (±Z): left out of the test against the model",
                r.name, r.origin
            ));
            continue;
        }
        // One channel per model point: an acceleration before a velocity before a
        // displacement (the same sensor's integrals add nothing to the shapes).
        let rank = |q: Quantity| match q {
            Quantity::Acceleration => 0,
            Quantity::Velocity => 1,
            _ => 2,
        };
        if let Some(j) = chosen
            .iter()
            .position(|(_, c)| c.model_point == model_point)
        {
            let (kept, _) = chosen[j];
            let (better, worse) = if rank(r.quantity) < rank(records[kept].quantity) {
                (k, kept)
            } else {
                (kept, k)
            };
            notes.push(format!(
                "'{}' and '{}' both measure model point {model_point}: '{}' is used",
                records[better].name, records[worse].name, records[better].name
            ));
            if better == kept {
                continue;
            }
            chosen.remove(j);
        }
        chosen.push((
            k,
            MappedChannel {
                channel: r.name.clone(),
                point: r
                    .point
                    .as_ref()
                    .map_or_else(|| format!("{}:{} +Z", r.name, k + 1), |p| p.label()),
                model_point,
                rule: rule.into(),
            },
        ));
    }
    // In the records' order, as the FRFs come out of `estimate`.
    chosen.sort_by_key(|(k, _)| *k);
    let channels: Vec<MappedChannel> = chosen.into_iter().map(|(_, c)| c).collect();
    if channels.is_empty() {
        return Err(format!(
            "no response of case {} ({}) sampled with the blow force '{}' maps to a model point ({}): map the accelerometer at the measurement point with --channel NAME=B, or name the channels' points after the model's",
            case_name(case.case),
            case.files.join(", "),
            records[force].name,
            model_points.iter().copied().collect::<Vec<_>>().join(", ")
        ));
    }
    let group_records = group.iter().map(|&k| records[k].clone()).collect();
    Ok((group_records, records[force].name.clone(), channels, notes))
}

/// The FRF type of the responses: accelerance when any is an acceleration, else mobility for
/// velocities, else receptance.
fn frf_kind(
    records: &[crate::measure::Record],
    channels: &[MappedChannel],
) -> crate::identify::FrfKind {
    use crate::identify::FrfKind;
    let q: Vec<Quantity> = channels
        .iter()
        .filter_map(|c| records.iter().find(|r| r.name == c.channel))
        .map(|r| r.quantity)
        .collect();
    if q.contains(&Quantity::Acceleration) {
        FrfKind::Accelerance
    } else if q.contains(&Quantity::Velocity) {
        FrfKind::Mobility
    } else {
        FrfKind::Receptance
    }
}

/// The band (module docs) and the model modes in it (0-based); `None` when none is.
fn band_of(set: &FrfSet, model_hz: &[f64]) -> Option<((f64, f64), Vec<usize>)> {
    let f = &set.channels.first()?.frequency_hz;
    let (lo, last) = (*f.first()?, *f.last()?);
    let top = model_hz
        .iter()
        .copied()
        .filter(|&x| x >= lo && x <= last)
        .fold(f64::NAN, f64::max);
    if !top.is_finite() {
        return None;
    }
    let hi = (1.25 * top).min(last);
    let in_band = (0..model_hz.len())
        .filter(|&j| model_hz[j] >= lo && model_hz[j] <= hi)
        .collect();
    Some(((lo, hi), in_band))
}

/// The identified modes as `meid correlate` reads them: one point per FRF, labelled as the
/// channel's point.
fn identified(
    case: &MeasuredCase,
    set: &FrfSet,
    channels: &[MappedChannel],
    id: &Identification,
) -> IdentifiedModes {
    IdentifiedModes {
        file: case.files.join(", "),
        points: set
            .channels
            .iter()
            .zip(channels)
            .map(|(c, m)| {
                let mut p = parse_point_label(&m.point);
                p.direction = c.response_point.direction;
                p
            })
            .collect(),
        modes: id.modes.iter().map(IdentifiedMode::from).collect(),
    }
}

/// The model's damping ratio of mode `j`: `d_jj/(2 ω_j)` of its modal damping.
fn model_damping(model: &Model, j: usize) -> f64 {
    let s = &model.structure;
    let n = s.omega_rad_per_s.len();
    let w = s.omega_rad_per_s[j];
    let d = s.damping.get(j * n + j).copied().unwrap_or(0.0);
    if w > 0.0 {
        d / (2.0 * w)
    } else {
        0.0
    }
}

fn mode_rows(
    model: &Model,
    mm: &ModelModes,
    in_band: &[usize],
    c: &Correlation,
    id: &Identification,
) -> Vec<ModeRow> {
    in_band
        .iter()
        .map(|&j| {
            let pair = c.pairs.iter().find(|p| p.model_mode == j + 1);
            ModeRow {
                model_mode: j + 1,
                label: mm.labels.get(j).cloned().unwrap_or_default(),
                model_frequency_hz: mm.frequencies_hz[j],
                model_damping_ratio: model_damping(model, j),
                test_mode: pair.map(|p| p.identified_mode),
                test_frequency_hz: pair.map(|p| p.identified_frequency_hz),
                test_damping_ratio: pair
                    .and_then(|p| id.modes.get(p.identified_mode - 1))
                    .map(|m| m.damping_ratio),
                error_percent: pair.map(|p| p.error_percent),
                mac: pair.map(|p| p.mac),
            }
        })
        .collect()
}

/// The lead sentence: how many model modes the test finds, the worst frequency error, the
/// least MAC.
fn verdict(rows: &[ModeRow], hi_hz: f64, points: usize) -> String {
    let found: Vec<&ModeRow> = rows.iter().filter(|r| r.test_mode.is_some()).collect();
    let mut s = format!(
        "{} of {} model mode(s) below {} Hz are found in the test",
        found.len(),
        rows.len(),
        sig(hi_hz, 4)
    );
    let error = |r: &ModeRow| r.error_percent.unwrap_or(0.0).abs();
    if let Some(w) = found.iter().max_by(|a, b| error(a).total_cmp(&error(b))) {
        s.push_str(&format!(
            "; worst frequency error {} % at model mode {}",
            signed(w.error_percent.unwrap_or(0.0), 1),
            w.model_mode
        ));
        let least = found
            .iter()
            .filter_map(|r| r.mac)
            .fold(f64::INFINITY, f64::min);
        if points > 1 {
            s.push_str(&format!("; MAC ≥ {least:.2} on all pairs"));
        } else {
            s.push_str(
                "; one measured point, so the MAC is 1 for any pair and the pairs are by frequency",
            );
        }
    }
    s.push('.');
    s
}

/// The section: with a result, its sentence, tables and pictures (written into `dir`, the
/// numbers into [`DATA_FILE`]); skipped, why; without measurements, how to give them.
pub fn section(dir: &Path, outcome: Option<&Outcome>) -> Result<Section> {
    let blocks = match outcome {
        None => vec![Block::Paragraph(
            "No test against the model: give measured blows with meid report MODEL.toml --measured none=FILE, the blow force and responses at the model's points sampled together (UFF 58/58b, CSV), and the page shows their FRFs, the identified modes, the modes paired with the model's by the MAC and, with --fit PATH, the model updated to them (docs/reference/report.md).".into(),
        )],
        Some(Outcome::Skipped { reason }) => vec![Block::Paragraph(format!(
            "No test against the model: {reason}."
        ))],
        Some(Outcome::Done(t)) => done_blocks(dir, t)?,
    };
    Ok(Section {
        id: "test-against-model".into(),
        heading: "Test against model".into(),
        blocks,
    })
}

fn done_blocks(dir: &Path, t: &TestAgainstModel) -> Result<Vec<Block>> {
    crate::io::write_json(&dir.join(DATA_FILE), t)?;
    let mut blocks = vec![Block::List(vec![t.verdict.clone()])];
    if let Some(u) = &t.update {
        blocks.push(Block::List(vec![update_sentence(u)]));
    }
    blocks.push(Block::Paragraph(format!(
        "Case {} ({}): {} blow(s) found on '{}', {} averaged; record {} s from {} s before the trigger, Δf = {} Hz; responses {}. H1 {} with coherence (meid frf), modes by LSCF and LSFD in {} .. {} Hz, orders 1 … {} (meid identify; damping with the window's decay removed), paired with the model's {}, MAC ≥ {} (meid correlate).",
        t.case,
        t.files.join(", "),
        t.frf.blows,
        t.frf.force,
        t.frf.blows_averaged,
        sig(t.frf.record_s, 4),
        sig(t.frf.pretrigger_s, 3),
        sig(t.frf.frequency_resolution_hz, 4),
        t.channels
            .iter()
            .map(|c| format!("'{}' at {} ({})", c.channel, c.model_point, c.rule))
            .collect::<Vec<_>>()
            .join(", "),
        t.frf.kind.name(),
        sig(t.band_hz.0, 4),
        sig(t.band_hz.1, 4),
        t.max_order,
        if t.correlation.settings.by_frequency {
            "by frequency (one measured point: the MAC of any pair is 1)"
        } else {
            "by the MAC at the mapped points"
        },
        t.correlation.settings.min_mac
    )));
    blocks.push(Block::Table(pairs_table(t)));
    if let Some(u) = &t.update {
        blocks.push(Block::Table(update_table(u)));
        blocks.push(Block::Table(update_pairs_table(u)));
    }
    if let Some(text) = &t.calibrated_model {
        crate::io::write_atomic(&dir.join(CALIBRATED_FILE), text.as_bytes())?;
        blocks.push(Block::Paragraph(format!(
            "The updated model is written beside this page as {CALIBRATED_FILE} (the model file \
             with the fitted values in place; meid calibrate --modal -o writes the same file)."
        )));
    }
    frf_plots(dir, &t.frf)?;
    band_plots(dir, t)?;
    crate::measure::identified::stabilisation_plot(dir, &t.identification)?;
    let drawn = t.correlation.plots(dir)?;
    blocks.extend(figures(dir, t));
    let mut remarks: Vec<String> = t.warnings.iter().map(|w| format!("warning: {w}")).collect();
    remarks.extend(t.notes.iter().cloned());
    remarks.extend(drawn);
    if !remarks.is_empty() {
        blocks.push(Block::List(remarks));
    }
    Ok(blocks)
}

/// `test_frf_magnitude` and `test_frf_coherence`: the FRFs and their coherence in the band
/// of the identification, the model's modes marked.
fn band_plots(dir: &Path, t: &TestAgainstModel) -> Result<()> {
    use crate::plot::{line_plot, LinePlot, Marker, Series};
    let (lo, hi) = t.band_hz;
    let series = |y: &dyn Fn(&crate::measure::frf::FrfChannel, usize) -> f64| -> Vec<Series> {
        t.frf
            .channels
            .iter()
            .map(|c| {
                let k: Vec<usize> = (0..c.frequency_hz.len())
                    .filter(|&k| c.frequency_hz[k] >= lo && c.frequency_hz[k] <= hi)
                    .collect();
                Series {
                    label: c.response.clone(),
                    x: k.iter().map(|&k| c.frequency_hz[k]).collect(),
                    y: k.iter().map(|&k| y(c, k)).collect(),
                    ..Default::default()
                }
            })
            .collect()
    };
    let markers: Vec<Marker> = t
        .modes
        .iter()
        .map(|r| Marker {
            x: r.model_frequency_hz,
            label: format!("model {}", r.model_mode),
        })
        .collect();
    let what = format!(
        "H1 {} against '{}' ({} blow(s))",
        t.frf.kind.name(),
        t.frf.force,
        t.frf.blows_averaged
    );
    line_plot(
        dir.join("test_frf_magnitude"),
        &LinePlot {
            title: format!("|H|: {what}"),
            x_label: "frequency (Hz)".into(),
            y_label: format!("|H| ({})", t.frf.unit),
            y_log: true,
            series: series(&|c, k| c.h[k].norm()),
            markers: markers.clone(),
            x_range: Some(t.band_hz),
            ..Default::default()
        },
    )?;
    line_plot(
        dir.join("test_frf_coherence"),
        &LinePlot {
            title: format!("coherence γ²: {what}"),
            x_label: "frequency (Hz)".into(),
            y_label: "γ² (1)".into(),
            series: series(&|c, k| c.coherence[k]),
            markers,
            x_range: Some(t.band_hz),
            ..Default::default()
        },
    )?;
    Ok(())
}

/// `v` with a sign and `decimals` decimals; a value that rounds to zero has none.
fn signed(v: f64, decimals: usize) -> String {
    let s = format!("{v:+.decimals$}");
    if s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

fn figures(dir: &Path, t: &TestAgainstModel) -> Vec<Block> {
    let what = format!("against the blow force '{}'", t.frf.force);
    [
        (
            "test_frf_magnitude",
            format!(
                "Measured FRF magnitudes |H| ({}) of the mapped responses {what}, case {}, in the band of the identification; the model's modes marked (all lines: frf_magnitude.png).",
                t.frf.unit, t.case
            ),
        ),
        (
            "test_frf_coherence",
            format!(
                "Coherence γ² of the FRFs over {} blow(s) (with one blow it is 1 by construction and says nothing of the noise).",
                t.frf.blows_averaged
            ),
        ),
        (
            "stabilisation",
            "Stabilisation diagram: the poles of every model order; the identified modes are numbered.".to_string(),
        ),
        (
            "mac",
            "MAC of the identified modes (rows) against the model's (columns) at the measured points.".to_string(),
        ),
    ]
    .into_iter()
    .filter(|(stem, _)| dir.join(format!("{stem}.png")).is_file())
    .map(|(stem, caption)| {
        Block::Figure(Figure {
            src: format!("{stem}.png"),
            alt: caption.clone(),
            caption,
            data: vec![format!("{stem}.svg"), DATA_FILE.into()],
        })
    })
    .collect()
}

fn opt(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map_or_else(|| "not found".into(), f)
}

/// The paired-mode table: per model mode in the band, model and test frequency, error,
/// damping test vs model, MAC.
pub fn pairs_table(t: &TestAgainstModel) -> Table {
    Table {
        caption: "Model modes in the band against the test: frequency error 100 (f_test − f_model)/f_model; damping ratios of the test (window removed) and of the model; MAC at the measured points.".into(),
        header: [
            "model mode",
            "f model (Hz)",
            "test mode",
            "f test (Hz)",
            "error (%)",
            "ζ test",
            "ζ model",
            "MAC",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
        rows: t
            .modes
            .iter()
            .map(|r| {
                vec![
                    format!("{} ({})", r.model_mode, r.label),
                    format!("{:.3}", r.model_frequency_hz),
                    r.test_mode.map_or_else(|| "—".into(), |m| m.to_string()),
                    opt(r.test_frequency_hz, |f| format!("{f:.3}")),
                    opt(r.error_percent, |e| signed(e, 2)),
                    opt(r.test_damping_ratio, |z| format!("{z:.4}")),
                    format!("{:.4}", r.model_damping_ratio),
                    opt(r.mac, |m| format!("{m:.3}")),
                ]
            })
            .collect(),
        ..Default::default()
    }
}

fn update_sentence(u: &ModalCalibration) -> String {
    let values: Vec<String> = u
        .parameters
        .iter()
        .map(|e| {
            format!(
                "{} {} → {} ({} %)",
                e.path,
                sig(e.start, 5),
                sig(e.value, 5),
                signed(100.0 * (e.value - e.start) / e.start, 2)
            )
        })
        .collect();
    let worst = |f: &dyn Fn(&crate::measure::modal_update::PairUpdate) -> f64| {
        u.pairs.iter().map(f).fold(0.0_f64, |m, e| m.max(e.abs()))
    };
    format!(
        "Updated model: {}; the largest frequency error of the paired modes falls from {:.2} % to {:.2} % ({}).",
        values.join(", "),
        worst(&|p| p.error_before_percent),
        worst(&|p| p.error_after_percent),
        u.convergence.describe()
    )
}

/// The fitted values with their intervals.
pub fn update_table(u: &ModalCalibration) -> Table {
    Table {
        caption: "The updated model's values (meid calibrate --modal on the identified modes): start, fit, linearised 95 % interval.".into(),
        header: ["path", "start", "fitted", "change (%)", "95 % interval", "status"]
            .iter()
            .map(|s| s.to_string())
            .collect(),
        rows: u
            .parameters
            .iter()
            .map(|e| {
                vec![
                    e.path.clone(),
                    sig(e.start, 6),
                    sig(e.value, 6),
                    signed(100.0 * (e.value - e.start) / e.start, 3),
                    if e.ci95_low.is_finite() {
                        format!("{} .. {}", sig(e.ci95_low, 6), sig(e.ci95_high, 6))
                    } else {
                        "—".into()
                    },
                    if e.at_bound {
                        "at a bound".into()
                    } else {
                        e.identifiability.describe().into()
                    },
                ]
            })
            .collect(),
        ..Default::default()
    }
}

/// The paired modes with the model's values and the updated ones.
pub fn update_pairs_table(u: &ModalCalibration) -> Table {
    Table {
        caption: "Paired modes before and after the update: the model's frequency, its error against the test and the MAC.".into(),
        header: [
            "test mode",
            "model mode",
            "f test (Hz)",
            "f before (Hz)",
            "error before (%)",
            "MAC before",
            "f after (Hz)",
            "error after (%)",
            "MAC after",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
        rows: u
            .pairs
            .iter()
            .map(|p| {
                vec![
                    p.identified_mode.to_string(),
                    p.model_mode.to_string(),
                    format!("{:.3}", p.identified_frequency_hz),
                    format!("{:.3}", p.model_frequency_before_hz),
                    signed(p.error_before_percent, 2),
                    format!("{:.3}", p.mac_before),
                    format!("{:.3}", p.model_frequency_after_hz),
                    signed(p.error_after_percent, 2),
                    format!("{:.3}", p.mac_after),
                ]
            })
            .collect(),
        ..Default::default()
    }
}
