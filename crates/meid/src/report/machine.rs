//! One page about a user's machine (`meid report MODEL.toml`): the model, its modes and how
//! much the retained modes keep, the energy map around the current design with the design
//! marked, none / damper / added mass (exact time peaks, spectra, one-third-octave levels and
//! dB reductions, each with its measure), a blow train at the stroke rate, the optimiser's
//! damper against the paper's rule ω_d = ω_s, and a Monte Carlo study when the inputs are
//! given a distribution.
//!
//! [`MachineReport::run`] does the studies (the library's own: [`crate::analysis`]);
//! [`MachineReport::write`] writes the pictures, data and `index.html` into a directory. No
//! number on the page depends on the output sample rate: peaks are exact on the continuous
//! solution, spectra are the exact transforms of the response, the map and the optimiser stop
//! each run at the end of the collision (energy) or take exact peaks (force).

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use super::figures::{self, sig, MapSpec, Mark};
use super::html::{Block, Page, Section, Table};
use crate::analysis::blows::{run_blows_with, BlowOptions, BlowsRun};
use crate::analysis::compare::{CaseName, CompareOptions, Comparison, ComparisonResult};
use crate::analysis::impacts::{self, ImpactTotals};
use crate::analysis::montecarlo::{MonteCarlo, MonteCarloResult, Uncertain};
use crate::analysis::production::{self, Production};
use crate::analysis::steady::SteadyOptions;
use crate::analysis::study::{Objective, OptimizeReport, OptimizeStudy};
use crate::analysis::sweep::{Quantity, Spacing, Sweep, SweepResult, Vary};
use crate::integrate::network::ImpactRow;
use crate::integrate::Options;
use crate::measure::mapping::MeasurementSpec;
use crate::measure::validate::Validation;
use crate::model::fem::{self, ModeReport};
use crate::model::spec::{DashpotKindSpec, LawSpec, MethodSpec};
use crate::model::{Case, Model};
use crate::{Error, Result};

/// Settings of a machine report.
#[derive(Debug, Clone, PartialEq)]
pub struct MachineOptions {
    /// Stroke rate of the blow train and the production steady state (blows per minute);
    /// `None`: the model's `[production] rate_bpm`, else 60 assumed
    /// ([`production::stroke_rate`]).
    pub rate_bpm: Option<f64>,
    /// Blows in the train.
    pub blows: usize,
    /// Grid points per axis of the energy map (made odd so that the design is a grid point).
    pub map_points: usize,
    /// The map spans `value / span .. value · span` of each contact frequency around the
    /// design (its square for stiffnesses).
    pub map_span: f64,
    /// Record length (s) of the comparison's time histories (the exact spectra and peaks do
    /// not depend on it).
    pub record_s: f64,
    /// Uncertain inputs of the Monte Carlo study (none: no study).
    pub uncertain: Vec<Uncertain>,
    /// Monte Carlo samples and seed.
    pub samples: usize,
    pub seed: u64,
    /// Measured files `[CASE=]FILE` (as `meid validate --measured`); empty: the model's
    /// `[measurement] files`, if any. With either, the page has the comparison
    /// ([`super::measured`]).
    pub measured: Vec<String>,
    /// `NAME=TARGET` channel mappings over the model's `[measurement] channels`.
    pub channels: Vec<String>,
    /// Processing of the measurements (trigger, pre-trigger, record, window) over the
    /// model's `[measurement]` section ([`MeasurementSpec::over`]).
    pub processing: MeasurementSpec,
    /// Model updating of the section "Test against model" (`--fit`; empty: none).
    pub update: super::testlab::UpdateRequest,
}

impl Default for MachineOptions {
    fn default() -> Self {
        Self {
            rate_bpm: None,
            blows: 10,
            map_points: 41,
            map_span: 3.0,
            record_s: 2.0,
            uncertain: Vec::new(),
            samples: 100,
            seed: 1,
            measured: Vec::new(),
            channels: Vec::new(),
            processing: MeasurementSpec::default(),
            update: super::testlab::UpdateRequest::default(),
        }
    }
}

/// The axes of the energy map (JSON: `{"kind": "ratios", "reference_mode": 6}` or
/// `{"kind": "stiffnesses"}`).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum MapAxes {
    /// ω_s/ω_n and ω_d/ω_n, ω_n the reference mode (its number in the mode table).
    Ratios { reference_mode: usize },
    /// K_s and K_d (non-linear contact laws, or no reference mode).
    Stiffnesses,
}

/// The energy map around the design.
#[derive(Debug, Clone, Serialize)]
pub struct EnergyMap {
    pub axes: MapAxes,
    /// The design in axis values (the grid's centre).
    pub design: (f64, f64),
    /// E_p+/E_s− at the design point of the grid.
    pub design_energy_ratio: f64,
    /// The smallest E_p+/E_s− on the grid and where (axis values).
    pub minimum: Option<(f64, f64, f64)>,
    /// The smallest value lies on the grid's edge (the true minimum may lie outside the map).
    pub minimum_on_edge: bool,
    pub sweep: SweepResult,
}

/// Everything [`MachineReport::run`] computed.
#[derive(Debug, Clone)]
pub struct MachineReport {
    /// The model file as given.
    pub model_path: String,
    pub model: Model,
    pub modes: ModeReport,
    pub options: MachineOptions,
    pub map: Option<EnergyMap>,
    pub comparison: ComparisonResult,
    /// One train per case of the comparison.
    pub blows: Vec<(CaseName, BlowsRun)>,
    /// The stroke rate of the train and the steady state (blows/min), and where it came from.
    pub rate_bpm: f64,
    pub rate_origin: production::RateOrigin,
    /// The cases in their periodic steady state at the stroke rate, with the verdict
    /// ([`production::production`]); `None` when it failed (the reason is in `notes`).
    pub production: Option<Production>,
    /// The optimiser over ω_d/ω_s, minimising the energy left (E_p+/E_s−) and the peak floor
    /// force.
    pub optimize: Vec<OptimizeReport>,
    pub montecarlo: Option<MonteCarloResult>,
    /// The simulation beside measured records, when some were given.
    pub measured: Option<Validation>,
    /// The test against the model from the measured blows ([`super::testlab`]): `None`
    /// without measured records.
    pub test_against_model: Option<super::testlab::Outcome>,
    /// Why a study was left out (no damper, a failed study ...); shown on the page.
    pub notes: Vec<String>,
    /// With a `[foundation]`: its checks and the receivers' for each case of the comparison
    /// ([`crate::foundation::assess`]); empty without one.
    pub foundation: Vec<(CaseName, crate::foundation::FoundationAssessment)>,
    /// Every closing of each contact in each case's blow over the record
    /// ([`crate::analysis::impacts`]).
    pub impacts: Vec<CaseImpacts>,
}

/// The stages of [`MachineReport::run`], in order, for progress reporting.
pub const STAGES: [&str; 7] = [
    "modes",
    "Monte Carlo",
    "energy map",
    "comparison",
    "blow trains",
    "optimiser",
    "page",
];

/// One case's closings of each contact and their totals per contact.
pub type CaseImpacts = (CaseName, Vec<ImpactRow>, Vec<ImpactTotals>);

/// Every closing of each contact in each case of `comparison`, over the comparison's record of
/// `record_s` seconds ([`impacts::impacts`] of the case's run; exact for linear laws).
fn case_impacts(
    model: &Model,
    comparison: &ComparisonResult,
    record_s: f64,
) -> Result<Vec<CaseImpacts>> {
    comparison
        .cases
        .iter()
        .map(|c| {
            let sys = model.impact_system(case_of(c.case))?;
            let opts = Options {
                duration: record_s,
                sample_rate: None,
                stop_at_collision_end: false,
                ..model.options()
            };
            let run = crate::analysis::energy::simulate(&sys, &opts, false)?;
            let rows = impacts::impacts(&sys, &run.solution)?;
            let totals = impacts::totals(&sys, &rows);
            Ok((c.case, rows, totals))
        })
        .collect()
}

fn case_of(c: CaseName) -> Case {
    match c {
        CaseName::NoDamper => Case::NoDamper,
        CaseName::Damper => Case::Damper,
        CaseName::AddedMass => Case::AddedMass,
    }
}

/// `v` spaced evenly in ln from `c/span` to `c·span`, `n` values (odd), the middle one
/// exactly `c`.
fn log_grid(c: f64, span: f64, n: usize) -> Vec<f64> {
    let half = (n / 2) as i64;
    (-half..=half)
        .map(|k| {
            if k == 0 {
                c
            } else {
                c * span.powf(k as f64 / half as f64)
            }
        })
        .collect()
}

fn law_name(l: LawSpec) -> &'static str {
    match l {
        LawSpec::Linear => "linear",
        LawSpec::Hertz => "hertz",
        LawSpec::HuntCrossley => "hunt-crossley",
        LawSpec::Rigid => "rigid",
    }
}

/// Refuses report settings no study can use (a bad stroke rate, no blows, fewer than 3 map
/// points per axis, a map span ≤ 1, a record length ≤ 0 s) and an energy map too large for the
/// memory, before anything is run.
fn check_options(options: &MachineOptions) -> Result<()> {
    if let Some(r) = options.rate_bpm {
        crate::analysis::blows::blow_interval_s(r)?;
    }
    if options.blows == 0 {
        return Err(Error::invalid("blows", "needs at least one blow"));
    }
    if options.map_points < 3 {
        return Err(Error::invalid(
            "map_points",
            format!(
                "the energy map needs at least 3 points per axis (got {})",
                options.map_points
            ),
        ));
    }
    if !(options.map_span.is_finite() && options.map_span > 1.0) {
        return Err(Error::invalid(
            "map_span",
            format!(
                "the map's span factor must be > 1 (got {})",
                options.map_span
            ),
        ));
    }
    if !(options.record_s.is_finite() && options.record_s > 0.0) {
        return Err(Error::invalid(
            "record_s",
            format!("the record length must be > 0 s (got {})", options.record_s),
        ));
    }
    // The map's grid is estimated before anything is allocated (a sweep point ~2 KiB).
    let n = (options.map_points | 1) as f64;
    crate::limits::check_memory(
        &format!("the energy map's {n} × {n} grid (2 KiB per point)"),
        n * n * 2048.0,
        "map_points",
        "the map's points per axis (--map-points)",
    )?;
    Ok(())
}

/// One blow train of `blows_per_train` blows at `rate_bpm` for each case of the comparison,
/// each blow starting from the state the previous one left.
fn blow_trains(
    model: &Model,
    comparison: &ComparisonResult,
    blows_per_train: usize,
    rate_bpm: f64,
) -> Result<Vec<(CaseName, BlowsRun)>> {
    let mut blows = Vec::new();
    let train = BlowOptions {
        blows: blows_per_train,
        rate_bpm,
        ..BlowOptions::default()
    };
    for c in comparison.cases.iter().map(|c| c.case) {
        let sys = model.impact_system(case_of(c))?;
        blows.push((
            c,
            run_blows_with(&sys, &model.options(), &train, None, false)?,
        ));
    }
    Ok(blows)
}

/// The optimiser over ω_d/ω_s for the energy left (E_p+/E_s−) and the peak floor force; a
/// failed objective, or a model without a damper, leaves a note instead.
fn optimize_studies(model: &Model, notes: &mut Vec<String>) -> Vec<OptimizeReport> {
    let mut optimize = Vec::new();
    if model.spec.damper.is_some() && model.spec.contact.bed_damper.is_some() {
        for objective in [Objective::Energy, Objective::FloorForce] {
            let study =
                OptimizeStudy::new(model.clone(), vec![(Quantity::WdOverWs, None)], objective)
                    .and_then(|s| s.run());
            match study {
                Ok(r) => optimize.push(r),
                Err(e) => notes.push(format!("optimiser ({}): {e}", objective.metric())),
            }
        }
    } else {
        notes.push("optimiser: the model has no [damper] to tune".into());
    }
    optimize
}

/// The rows of the model table: quantity, symbol, value, unit.
#[derive(Default)]
struct ModelRows(Vec<Vec<String>>);

impl ModelRows {
    fn row(&mut self, q: &str, sym: &str, v: String, unit: &str) {
        self.0.push(vec![q.into(), sym.into(), v, unit.into()]);
    }
}

impl MachineReport {
    /// Loads `path` (with `--set` overrides) and runs every study; `progress` is called with
    /// each stage's name ([`STAGES`]) before it starts.
    pub fn run(
        path: &Path,
        overrides: &[String],
        options: &MachineOptions,
        progress: &dyn Fn(&str),
    ) -> Result<Self> {
        check_options(options)?;
        progress(STAGES[0]);
        let (model, analysis) = fem::from_file_with_analysis(path, overrides, None)?;
        let modes = match &analysis {
            Some(an) => an.report()?,
            None => fem::report_from_modal(&model.structure),
        }
        .with_diagnostics(model.diagnostics());
        drop(analysis);
        let (rate_bpm, rate_origin) = production::stroke_rate(&model, options.rate_bpm)?;
        let mut notes = Vec::new();
        let mut options = options.clone();
        options.map_points |= 1;

        // Measured records next: a bad file is an input error, found before the long studies.
        let (measured, test_against_model) = match super::measured::run(
            path,
            &model,
            &options.measured,
            &options.channels,
            &options.processing,
        )? {
            Some((v, inputs)) => {
                let t = super::testlab::run(
                    &model,
                    &inputs.cases,
                    &inputs.processing,
                    model.spec.measurement.as_ref(),
                    &inputs.flags,
                    &options.update,
                )?;
                (Some(v), t)
            }
            None if !options.update.fit.is_empty() => {
                return Err(crate::Error::invalid(
                    "--fit",
                    "the model is updated to the modes of measured blows: give them with --measured none=FILE (or the model's [measurement] files)",
                ))
            }
            None => (None, None),
        };

        // Monte Carlo first: a bad --vary is an input error, found before the long studies.
        progress(STAGES[1]);
        let montecarlo = if options.uncertain.is_empty() {
            None
        } else {
            Some(
                MonteCarlo {
                    model: model.clone(),
                    inputs: options.uncertain.clone(),
                    samples: options.samples,
                    seed: options.seed,
                }
                .run()?,
            )
        };

        progress(STAGES[2]);
        let map = match Self::energy_map(&model, &options) {
            Ok(m) => m,
            Err(e) => {
                notes.push(format!("energy map: {e}"));
                None
            }
        };
        if map.is_none() && model.spec.damper.is_none() {
            notes.push("energy map: the model has no [damper]; the map of E_p+/E_s− over the damper's contact frequency needs one".into());
        }

        progress(STAGES[3]);
        let comparison = Comparison::new(
            model.clone(),
            CompareOptions {
                duration_s: options.record_s,
                ..CompareOptions::default()
            },
        )
        .run()?;

        // With a [foundation]: the block, the soil and the receivers in each case.
        let mut foundation = Vec::new();
        for c in comparison.cases.iter().map(|c| c.case) {
            // Judged on the steady blow at the report's stroke rate, as the production section.
            let basis = crate::foundation::Basis::Steady(SteadyOptions {
                rate_bpm,
                ..SteadyOptions::default()
            });
            if let Some(a) = crate::foundation::assess_with(&model, case_of(c), &basis)? {
                foundation.push((c, a));
            }
        }

        let impacts = case_impacts(&model, &comparison, options.record_s)?;

        progress(STAGES[4]);
        let blows = blow_trains(&model, &comparison, options.blows, rate_bpm)?;

        let production =
            match production::production(&model, rate_bpm, &SteadyOptions::default(), true) {
                Ok(p) => Some(p),
                Err(e) => {
                    notes.push(format!("production steady state: {e}"));
                    None
                }
            };

        progress(STAGES[5]);
        let optimize = optimize_studies(&model, &mut notes);
        Ok(MachineReport {
            rate_bpm,
            rate_origin,
            model_path: path.display().to_string(),
            model,
            modes,
            options,
            map,
            comparison,
            blows,
            production,
            optimize,
            montecarlo,
            measured,
            test_against_model,
            notes,
            foundation,
            impacts,
        })
    }

    /// The energy map study: ω_s/ω_n × ω_d/ω_n (linear contacts with a reference mode) or
    /// K_s × K_d around the design. `None` without a damper.
    fn energy_map(model: &Model, options: &MachineOptions) -> Result<Option<EnergyMap>> {
        let s = &model.spec;
        let (Some(d), Some(cd)) = (&s.damper, &s.contact.bed_damper) else {
            return Ok(None);
        };
        let cs = &s.contact.slider_bed;
        let n = options.map_points;
        let linear = cs.law == LawSpec::Linear && cd.law == LawSpec::Linear;
        let (axes, vary, design) = match (model.reference_omega(), linear) {
            (Some(w_ref), true) if w_ref > 0.0 => {
                let ws = (cs.stiffness / s.slider.mass).sqrt() / w_ref;
                let wd = (cd.stiffness / d.mass).sqrt() / w_ref;
                let number = model.reference_mode().map_or(1, |r| r.number);
                let mk = |q: Quantity, c: f64| Vary {
                    spec: format!("{}=grid around {c:e}", q.name()),
                    quantity: q,
                    spacing: Spacing::Log,
                    values: log_grid(c, options.map_span, n),
                };
                (
                    MapAxes::Ratios {
                        reference_mode: number,
                    },
                    vec![mk(Quantity::WsOverWref, ws), mk(Quantity::WdOverWref, wd)],
                    (ws, wd),
                )
            }
            _ => {
                let span = options.map_span * options.map_span;
                let mk = |p: &str, c: f64| Vary {
                    spec: format!("{p}=grid around {c:e}"),
                    quantity: Quantity::Field(p.into()),
                    spacing: Spacing::Log,
                    values: log_grid(c, span, n),
                };
                (
                    MapAxes::Stiffnesses,
                    vec![
                        mk("contact.slider_bed.stiffness", cs.stiffness),
                        mk("contact.bed_damper.stiffness", cd.stiffness),
                    ],
                    (cs.stiffness, cd.stiffness),
                )
            }
        };
        let sweep = Sweep::new(model.clone(), vary)?;
        let result = sweep.run(&|_, _| {});
        if let Some(e) = sweep.all_failed_error(&result) {
            return Err(e);
        }
        let centre = (n / 2) * n + n / 2;
        let design_energy_ratio = result.points[centre].metric("energy_ratio");
        let best = result.argmin("energy_ratio");
        let minimum = best.map(|i| {
            let p = &result.points[i];
            (p.values[0], p.values[1], p.metric("energy_ratio"))
        });
        let minimum_on_edge = best.is_some_and(|i| {
            let (a, b) = (i / n, i % n);
            a == 0 || b == 0 || a == n - 1 || b == n - 1
        });
        Ok(Some(EnergyMap {
            axes,
            design,
            design_energy_ratio,
            minimum,
            minimum_on_edge,
            sweep: result,
        }))
    }

    fn case(&self, c: CaseName) -> Option<&crate::analysis::compare::CaseResult> {
        self.comparison.cases.iter().find(|x| x.case == c)
    }

    /// ω_n's name on the page, e.g. `ω_6`.
    fn reference_name(&self) -> String {
        match self.map.as_ref().map(|m| &m.axes) {
            Some(MapAxes::Ratios { reference_mode }) => format!("ω_{reference_mode}"),
            _ => "ω_ref".into(),
        }
    }

    /// The key results as short lines (the page's first section and the CLI's summary).
    /// The verdict in sentences: the production verdict at the stroke rate
    /// ([`production::verdict`]), then the single blow from rest.
    pub fn verdict(&self) -> Vec<String> {
        let mut out = self
            .production
            .as_ref()
            .map_or_else(Vec::new, |p| p.verdict.clone());
        if let (Some(n), Some(d)) = (self.case(CaseName::NoDamper), self.case(CaseName::Damper)) {
            out.push(format!(
                "For a single blow from rest (the paper's study) the damper changes the peak floor force by {:+.1} dB and the bed acceleration by {:+.1} dB (negative: better).",
                20.0 * (d.peak_floor_force_n / n.peak_floor_force_n).log10(),
                20.0 * (d.peak_bed_acceleration_m_per_s2 / n.peak_bed_acceleration_m_per_s2).log10(),
            ));
        }
        // A receiver over its DIN 4150-3 limit in any case (section "Foundation and
        // surroundings").
        out.extend(super::foundation::failing_sentences(&self.foundation));
        out
    }

    pub fn key_results(&self) -> Vec<String> {
        let mut out = Vec::new();
        let none = self.case(CaseName::NoDamper);
        let damper = self.case(CaseName::Damper);
        let added = self.case(CaseName::AddedMass);
        if let (Some(n), Some(d)) = (none, damper) {
            if let (Some(en), Some(ed)) = (n.energy_ratio, d.energy_ratio) {
                out.push(format!(
                    "Energy left in the machine after one blow (E_p+/E_s−, paper Eq. 10): {} % without damper, {} % with the impact damper ({:+.2} dB, energy ratio).",
                    sig(100.0 * en, 4),
                    sig(100.0 * ed, 4),
                    10.0 * (en / ed).log10()
                ));
            }
            out.push(format!(
                "Exact time peaks of one blow from rest, without → with damper: bed acceleration {} → {} m/s² ({:+.2} dB), floor force {} → {} N ({:+.2} dB).",
                sig(n.peak_bed_acceleration_m_per_s2, 4),
                sig(d.peak_bed_acceleration_m_per_s2, 4),
                20.0 * (n.peak_bed_acceleration_m_per_s2 / d.peak_bed_acceleration_m_per_s2).log10(),
                sig(n.peak_floor_force_n, 4),
                sig(d.peak_floor_force_n, 4),
                20.0 * (n.peak_floor_force_n / d.peak_floor_force_n).log10(),
            ));
        }
        if let (Some(n), Some(a)) = (none, added) {
            out.push(format!(
                "The same mass fixed rigidly instead ({} kg at {}): bed acceleration {:+.2} dB, floor force {:+.2} dB (time peaks).",
                self.comparison.added_mass.as_ref().map_or("—".into(), |m| sig(m.0, 4)),
                self.comparison.added_mass.as_ref().map_or("—".into(), |m| m.1.clone()),
                20.0 * (n.peak_bed_acceleration_m_per_s2 / a.peak_bed_acceleration_m_per_s2).log10(),
                20.0 * (n.peak_floor_force_n / a.peak_floor_force_n).log10(),
            ));
        }
        if let Some(m) = &self.map {
            if let Some((x, y, e)) = m.minimum {
                let (xn, yn) = self.map_names();
                out.push(format!(
                    "Energy map: E_p+/E_s− = {} % at the design; the map's smallest, {} %, is at {xn} = {}, {yn} = {} (grid value{}).",
                    sig(100.0 * m.design_energy_ratio, 4),
                    sig(100.0 * e, 4),
                    sig(x, 4),
                    sig(y, 4),
                    if m.minimum_on_edge { ", on the map's edge: lower values may lie outside it" } else { "" }
                ));
            }
        }
        for r in &self.optimize {
            out.push(format!(
                "Optimiser ({}): ω_d/ω_s = {} gives {} against {} with the rule ω_d = ω_s ({:+.2} %).",
                objective_text(r.objective),
                sig(r.wd_over_ws_at_optimum, 4),
                objective_value(r.objective, r.objective_value),
                objective_value(r.objective, r.objective_at_wd_equal_ws),
                100.0 * (r.objective_at_wd_equal_ws / r.objective_value - 1.0)
            ));
        }
        if let Some(p) = &self.production {
            if let (Some(n), Some(d)) = (p.case(CaseName::NoDamper), p.case(CaseName::Damper)) {
                let line = format!(
                    "In production at {} blows/min ({}; the periodic steady blow, {}): peak floor force {} N without damper, {} N with it ({:+.2} dB); bed acceleration {} → {} m/s² ({:+.2} dB); the damper {} the bed in the steady blow{}.",
                    figures::plain(p.rate_bpm),
                    self.rate_origin.describe(),
                    d.regime.name(),
                    sig(n.peak_floor_force_n, 4),
                    sig(d.peak_floor_force_n, 4),
                    20.0 * (n.peak_floor_force_n / d.peak_floor_force_n).log10(),
                    sig(n.peak_bed_acceleration_m_per_s2, 4),
                    sig(d.peak_bed_acceleration_m_per_s2, 4),
                    20.0 * (n.peak_bed_acceleration_m_per_s2 / d.peak_bed_acceleration_m_per_s2).log10(),
                    if d.damper_touches_bed == Some(true) { "touches" } else { "does not touch" },
                    d.damper_gap_at_strike_m
                        .map_or(String::new(), |g| format!(" (gap at the strike {} mm)", sig(1e3 * g, 3)))
                );
                // A stroke rate the user gave makes the steady blow the answer: it leads.
                if self.rate_origin == production::RateOrigin::Assumed {
                    out.push(line);
                } else {
                    out.insert(0, line);
                }
            }
        }
        if let Some(mc) = &self.montecarlo {
            if let Some(s) = mc.metric_stats.first() {
                out.push(format!(
                    "Monte Carlo ({} samples, seed {}): E_p+/E_s− mean {} %, P95 {} % (estimates from the samples).",
                    mc.samples.len(),
                    mc.seed,
                    sig(100.0 * s.mean, 4),
                    sig(100.0 * s.p95, 4)
                ));
            }
        }
        if let Some(v) = &self.measured {
            out.push(super::measured::key_result(v));
        }
        if let Some(super::testlab::Outcome::Done(t)) = &self.test_against_model {
            out.push(format!("Test against model: {}", t.verdict));
        }
        out
    }

    fn map_names(&self) -> (String, String) {
        match self.map.as_ref().map(|m| &m.axes) {
            Some(MapAxes::Ratios { .. }) => {
                let r = self.reference_name();
                (format!("ω_s/{r}"), format!("ω_d/{r}"))
            }
            _ => ("K_s (N/m)".into(), "K_d (N/m)".into()),
        }
    }

    /// The model summary table: machine, masses, contacts, damper, method.
    pub fn model_table(&self) -> Table {
        let mut t = ModelRows::default();
        self.machine_rows(&mut t);
        let w_s = self.contact_rows(&mut t);
        self.damper_rows(&mut t, w_s);
        self.method_rows(&mut t);
        let rows = t.0;
        Table {
            caption: "The model".into(),
            header: vec![
                "quantity".into(),
                "symbol".into(),
                "value".into(),
                "unit".into(),
            ],
            rows,
            ..Default::default()
        }
    }

    /// The model table's machine rows: structure, retained modes, reference mode, bed and
    /// slider masses, slider velocity and the blow energy E_s− = ½ m_s v_s².
    fn machine_rows(&self, t: &mut ModelRows) {
        let s = &self.model.spec;
        let m = &self.model;
        let structure = if let Some(l) = &s.structure.lumped {
            format!(
                "lumped: {} masses, {} springs",
                l.masses.len(),
                l.springs.len()
            )
        } else if s.structure.fem.is_some() {
            format!("finite elements: {} DOFs", self.modes.dofs)
        } else {
            "tabulated modes".into()
        };
        t.row("structure", "", structure, "");
        t.row(
            "retained modes",
            "",
            format!(
                "{} ({} Hz)",
                m.structure.len(),
                m.structure
                    .omega_rad_per_s
                    .iter()
                    .map(|w| sig(w / (2.0 * std::f64::consts::PI), 4))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            "",
        );
        if let Some(r) = m.reference_mode() {
            t.row(
                "reference mode",
                &self.reference_name(),
                format!("{} rad/s; {}", sig(r.omega_rad_per_s, 5), r.describe()),
                "",
            );
        }
        if let Some(mb) = m.bed_mass() {
            t.row("bed mass", "m_b", sig(mb, 5), "kg");
        }
        t.row("slider mass", "m_s", sig(s.slider.mass, 5), "kg");
        t.row("slider velocity", "v_s", sig(s.slider.velocity, 5), "m/s");
        t.row(
            "blow energy",
            "E_s− = ½ m_s v_s²",
            sig(0.5 * s.slider.mass * s.slider.velocity.powi(2), 5),
            "J",
        );
    }

    /// The model table's slider-bed contact rows (K_s, ω_s = √(K_s/m_s), C_s); returns ω_s
    /// (rad/s).
    fn contact_rows(&self, t: &mut ModelRows) -> f64 {
        let s = &self.model.spec;
        let m = &self.model;
        let cs = &s.contact.slider_bed;
        t.row(
            "slider-bed contact",
            "K_s",
            format!("{} ({} law)", sig(cs.stiffness, 5), law_name(cs.law)),
            if cs.law == LawSpec::Linear {
                "N/m"
            } else {
                "N/m^n"
            },
        );
        let w_s = (cs.stiffness / s.slider.mass).sqrt();
        if cs.law == LawSpec::Linear {
            t.row(
                "slider contact frequency",
                "ω_s = √(K_s/m_s)",
                sig(w_s, 5),
                "rad/s",
            );
            if let Some(r) = m.reference_mode() {
                t.row(
                    "",
                    &format!("ω_s/{}", self.reference_name()),
                    format!(
                        "{} (ω_ref: mode {}, {} Hz)",
                        sig(w_s / r.omega_rad_per_s, 4),
                        r.number,
                        sig(r.frequency_hz, 4)
                    ),
                    "1",
                );
            }
        }
        // C_s as given, or as `restitution` set it.
        let c_s = match m.slider_bed_setting().map(|c| c.contact.law) {
            Ok(crate::impact::ContactLaw::Linear { damping, .. }) => damping,
            _ => 0.0,
        };
        if c_s != 0.0 {
            t.row(
                "slider-bed contact damping",
                "C_s",
                match cs.restitution {
                    Some(e) => format!("{} (from restitution e = {})", sig(c_s, 4), crate::num(e)),
                    None => sig(c_s, 4),
                },
                "N·s/m",
            );
        }
        w_s
    }

    /// The model table's damper rows: m_d, m_d/m_b, k_d, c_d, K_d, ω_d = √(K_d/m_d) and ω_d/ω_s
    /// (`w_s` in rad/s).
    fn damper_rows(&self, t: &mut ModelRows, w_s: f64) {
        let s = &self.model.spec;
        let m = &self.model;
        match &s.damper {
            Some(d) => {
                t.row("damper mass", "m_d", sig(d.mass, 5), "kg");
                if let Some(mb) = m.bed_mass() {
                    t.row("", "m_d/m_b", sig(d.mass / mb, 4), "1");
                }
                t.row("damper spring", "k_d", sig(d.stiffness, 5), "N/m");
                t.row(
                    "damper dashpot",
                    "c_d",
                    format!(
                        "{} ({})",
                        sig(d.damping, 5),
                        match d.dashpot {
                            DashpotKindSpec::OneWay => "one-way, paper Eq. 7",
                            DashpotKindSpec::TwoWay => "two-way",
                        }
                    ),
                    "N·s/m",
                );
                if let Some(cd) = &s.contact.bed_damper {
                    t.row(
                        "bed-damper contact",
                        "K_d",
                        format!("{} ({} law)", sig(cd.stiffness, 5), law_name(cd.law)),
                        if cd.law == LawSpec::Linear {
                            "N/m"
                        } else {
                            "N/m^n"
                        },
                    );
                    if cd.law == LawSpec::Linear {
                        let w_d = (cd.stiffness / d.mass).sqrt();
                        t.row(
                            "damper contact frequency",
                            "ω_d = √(K_d/m_d)",
                            sig(w_d, 5),
                            "rad/s",
                        );
                        t.row("", "ω_d/ω_s", sig(w_d / w_s, 4), "1");
                    }
                }
            }
            None => t.row("damper", "", "none in the model".into(), ""),
        }
    }

    /// The model table's last rows: the added mass of the comparison, the method, the
    /// simulated time and the output sample rate.
    fn method_rows(&self, t: &mut ModelRows) {
        let s = &self.model.spec;
        let m = &self.model;
        if let Some((mass, point)) = m.added_mass() {
            t.row(
                "added mass (comparison case)",
                "m_a",
                format!("{} at {point}", sig(mass, 5)),
                "kg",
            );
        }
        let sim = &s.simulation;
        t.row(
            "method",
            "",
            match sim.method {
                MethodSpec::Exact => {
                    "exact (piecewise-linear closed form, exactly located switches)".into()
                }
                MethodSpec::Dopri5 => format!(
                    "dopri5 (adaptive Dormand-Prince 5(4), rtol {}, atol {})",
                    sim.rtol, sim.atol
                ),
            },
            "",
        );
        t.row("simulated time of one run", "", sig(sim.duration, 4), "s");
        t.row("output sample rate", "", sig(sim.sample_rate, 6), "Hz");
    }

    /// Writes the pictures and data into `dir` and returns the page. `generator` is the lead's
    /// note of what produced the page (e.g. `meid 0.1.0 (commit …)`).
    pub fn page(&self, dir: &Path, generator: &str) -> Result<Page> {
        let name = self
            .model
            .spec
            .name
            .clone()
            .unwrap_or_else(|| self.model_path.clone());

        let mut sections = vec![
            // The verdict, in words, first.
            Section {
                id: "verdict".into(),
                heading: "Verdict".into(),
                blocks: vec![Block::List(self.verdict())],
            },
            self.results_section(),
            self.model_section(dir)?,
            self.modes_section(),
            self.map_section(dir)?,
            self.cases_section(dir)?,
        ];
        sections.extend(super::foundation::section(dir, &self.foundation)?);
        sections.extend([
            super::measured::section(dir, self.measured.as_ref())?,
            super::testlab::section(dir, self.test_against_model.as_ref())?,
            self.blows_section(dir)?,
            self.optimiser_section(),
            self.montecarlo_section(dir)?,
            self.method_section(),
        ]);
        Ok(Page {
            title: format!("meid report: {name}"),
            lead: format!("Model {} — {generator}.", self.model_path),
            sections,
        })
    }

    /// The model: its sketch first (the FE mesh with the strike, damper, anchor, measurement
    /// and floor points; [`crate::report::sketch`]), then the table of its values. A lumped or
    /// tabulated structure has no mesh: a note says so instead of the picture.
    fn model_section(&self, dir: &Path) -> Result<Section> {
        let mut blocks = Vec::new();
        match crate::report::sketch::model_sketch(&self.model)? {
            Some(sketch) => {
                crate::plot::mesh::sketch_plot(dir.join("model_sketch"), &sketch)?;
                blocks.push(Block::Figure(super::html::Figure {
                    src: "model_sketch.png".into(),
                    alt: "the model's FE mesh with its strike, damper, anchor, measurement and floor points".into(),
                    caption: crate::report::sketch::caption(&sketch),
                    data: vec!["model_sketch.svg".into()],
                }));
            }
            None => blocks.push(Block::Paragraph(
                "No sketch of the model: its structure is lumped or tabulated (no FE mesh to draw).".into(),
            )),
        }
        blocks.push(Block::Table(self.model_table()));
        Ok(Section {
            id: "model".into(),
            heading: "Model".into(),
            blocks,
        })
    }

    /// The key results, and the studies left out with why.
    fn results_section(&self) -> Section {
        let mut blocks = vec![Block::List(self.key_results())];
        if !self.notes.is_empty() {
            blocks.push(Block::Paragraph("Left out:".into()));
            blocks.push(Block::List(self.notes.clone()));
        }
        Section {
            id: "results".into(),
            heading: "Key results".into(),
            blocks,
        }
    }

    /// The mode table, the truncation table (what the retained modes keep), the modes' notes
    /// and warnings.
    fn modes_section(&self) -> Section {
        let mut blocks = vec![Block::Table(figures::mode_table(&self.modes))];
        if !self.modes.truncation.is_empty() {
            blocks.push(Block::Table(figures::truncation_table(
                &self.modes.truncation,
            )));
        }
        if !self.modes.notes.is_empty() {
            blocks.push(Block::List(self.modes.notes.clone()));
        }
        if !self.modes.warnings.is_empty() {
            blocks.push(Block::Paragraph("Warnings:".into()));
            blocks.push(Block::List(self.modes.warnings.clone()));
        }
        Section {
            id: "modes".into(),
            heading: "Modes and truncation".into(),
            blocks,
        }
    }

    /// The energy map E_p+/E_s− (paper Eq. 10) around the design, its picture written into
    /// `dir`, with the design and the grid's smallest value.
    fn map_section(&self, dir: &Path) -> Result<Section> {
        let mut blocks = Vec::new();
        match &self.map {
            Some(m) => {
                let (xn, yn) = self.map_names();
                let ratio = matches!(m.axes, MapAxes::Ratios { .. });
                let n = self.options.map_points;
                let caption = format!(
                    "Energy left in the machine after one blow, E_p+/E_s− (%, paper Eq. 10, each run stopped at the end of the collision), over {xn} × {yn} on a {n} × {n} grid spanning ÷/× {} around the current design (the point marked \"design\", E_p+/E_s− = {} % there){}.",
                    figures::plain(if ratio { self.options.map_span } else { self.options.map_span.powi(2) }),
                    sig(100.0 * m.design_energy_ratio, 3),
                    if ratio {
                        format!(
                            "; the dashed line is the paper's rule ω_d = ω_s; {}",
                            self.model
                                .reference_mode()
                                .map_or(String::new(), |r| r.describe())
                        )
                    } else {
                        String::new()
                    }
                );
                let fig = figures::energy_map(
                    dir,
                    "energy-map",
                    &MapSpec {
                        sweep: Some(&m.sweep),
                        metric: "energy_ratio".into(),
                        z_scale: Some(100.0),
                        title: format!("energy left in the machine, {xn} × {yn}"),
                        x_label: if ratio { format!("{xn} (1)") } else { xn.clone() },
                        y_label: if ratio { format!("{yn} (1)") } else { yn.clone() },
                        colorbar_label: "E_p+/E_s− (%)".into(),
                        marks: vec![Mark {
                            label: "design".into(),
                            x: m.design.0,
                            y: m.design.1,
                        }],
                        diagonal_label: if ratio { "ω_d = ω_s".into() } else { String::new() },
                        caption,
                    },
                )?;
                blocks.push(Block::Figure(fig));
                if let Some((x, y, e)) = m.minimum {
                    blocks.push(Block::Paragraph(format!(
                        "At the design ({xn} = {}, {yn} = {}) E_p+/E_s− = {} %. The grid's smallest value is {} % at {xn} = {}, {yn} = {}: a grid value (grid step × {} in each axis){}.",
                        sig(m.design.0, 4),
                        sig(m.design.1, 4),
                        sig(100.0 * m.design_energy_ratio, 4),
                        sig(100.0 * e, 4),
                        sig(x, 4),
                        sig(y, 4),
                        sig(
                            (if ratio { self.options.map_span } else { self.options.map_span.powi(2) })
                                .powf(2.0 / (n - 1) as f64),
                            4
                        ),
                        if m.minimum_on_edge {
                            ", on the map's edge: the energy keeps falling outside the map (widen it with --map-span)"
                        } else {
                            ", within one grid step of the map's minimum"
                        }
                    )));
                }
            }
            None => blocks.push(Block::Paragraph(
                "No energy map: the model has no damper, or the map failed (see Key results, Left out).".into(),
            )),
        }
        Ok(Section {
            id: "energy-map".into(),
            heading: "Energy map around the design".into(),
            blocks,
        })
    }

    /// None / damper / added mass: one blow in each case, its exact peaks, dB reductions by
    /// measure and the comparison's pictures (written into `dir`).
    fn cases_section(&self, dir: &Path) -> Result<Section> {
        let r = &self.comparison;
        let mut blocks = vec![
            Block::Paragraph(format!(
                "One blow of the machine in each case{}. {}",
                r.added_mass
                    .as_ref()
                    .map_or(String::new(), |(m, p)| format!(
                        " (the added mass is {} kg fixed rigidly at {p})",
                        sig(*m, 4)
                    )),
                r.spectrum_text().trim()
            )),
            Block::Table(figures::case_peaks_table(r)),
        ];
        if !r.reductions.is_empty() {
            blocks.push(Block::Table(figures::reductions_table(r)));
        }
        if !self.impacts.is_empty() {
            blocks.push(Block::Table(self.impacts_table()));
        }
        for f in figures::comparison_figures(dir, "cases", r)? {
            blocks.push(Block::Figure(f));
        }
        Ok(Section {
            id: "cases".into(),
            heading: "Without damper, with the damper, with an added mass".into(),
            blocks,
        })
    }

    /// Per case and contact: the number of closings over the record, the first closing (time,
    /// approach velocity, restitution) and the totals ([`impacts::totals`]: impulse, time
    /// closed, dissipated energy, the largest contact force and its time).
    fn impacts_table(&self) -> Table {
        let ms = |t: f64| sig(1e3 * t, 4);
        let mut rows = Vec::new();
        for (case, list, totals) in &self.impacts {
            for t in totals.iter().filter(|t| t.impacts > 0) {
                let Some(first) = list.iter().find(|r| r.contact == t.contact) else {
                    continue;
                };
                rows.push(vec![
                    case.label().to_string(),
                    t.contact.clone(),
                    t.impacts.to_string(),
                    ms(first.start_s),
                    sig(first.approach_velocity_m_per_s, 4),
                    first.restitution.map_or("—".into(), |e| sig(e, 4)),
                    format!("{} at {} ms", sig(t.peak_force_n, 4), ms(t.peak_time_s)),
                    sig(t.impulse_n_s, 4),
                    ms(t.closed_time_s),
                    sig(t.dissipated_j, 4),
                ]);
            }
        }
        Table {
            caption: format!(
                "Impacts in the blow: every closing of each contact over the {} s record (a contact that never closes is not listed), the first closing's approach velocity and restitution (exit over approach velocity), the largest contact force and the totals; exact for linear contact laws (impulse and dissipation integrated in closed form on each stretch), report.json member impacts",
                crate::num(self.options.record_s)
            ),
            header: vec![
                "case".into(),
                "contact".into(),
                "closings".into(),
                "first at (ms)".into(),
                "approach velocity (m/s)".into(),
                "restitution, first".into(),
                "largest force (N)".into(),
                "impulse, total (N·s)".into(),
                "time closed, total (ms)".into(),
                "dissipated, total (J)".into(),
            ],
            rows,
            ..Default::default()
        }
    }

    /// The blow trains at the stroke rate: the last blow of each case's train (peaks, η,
    /// whether it is steady, the damper's gap) and the trains' pictures (written into `dir`).
    fn blows_section(&self, dir: &Path) -> Result<Section> {
        let runs: Vec<(CaseName, &BlowsRun)> = self.blows.iter().map(|(c, r)| (*c, r)).collect();
        let mut rows = Vec::new();
        for (c, run) in &runs {
            let last = run.blows.last();
            rows.push(vec![
                c.label().to_string(),
                last.map_or("—".into(), |b| sig(b.peak_floor_force_n, 4)),
                last.map_or("—".into(), |b| sig(b.peak_bed_acceleration_m_per_s2, 4)),
                last.and_then(|b| b.energy_ratio)
                    .map_or("—".into(), |e| sig(100.0 * e, 4)),
                if run.steady.converged {
                    format!("yes, from blow {}", run.steady.from_blow.unwrap_or(1))
                } else {
                    format!(
                        "no (last change {} % in floor force)",
                        sig(100.0 * run.steady.last_change_peak_floor_force, 2)
                    )
                },
                run.damper_gap_at_next_strike_m
                    .map_or("—".into(), |g| sig(1e3 * g, 4)),
                run.blows
                    .iter()
                    .skip(1)
                    .filter(|b| b.damper_contact_time_s == Some(0.0))
                    .count()
                    .to_string(),
            ]);
        }
        let interval = runs.first().map_or(f64::NAN, |(_, r)| r.interval_s);
        let mut blocks = vec![
            Block::Paragraph(format!(
                "{} blows at {} blows/min (interval {} s = 60/rate exactly); each blow starts from the state the previous one left, with a fresh slider at v_s. The rate: {} (meid report --rate-bpm sets another). A single rate reads the rigid-body mode's comb filter as much as the damper (docs/explanations/blows.md, \"Repeated blows\"): check the neighbouring rates before concluding.",
                self.options.blows,
                figures::plain(self.rate_bpm),
                figures::plain(interval),
                self.rate_origin.describe()
            )),
            Block::Table(Table {
                caption: "The last blow of each train".into(),
                header: vec![
                    "case".into(),
                    "peak |F_floor| (N), time peak".into(),
                    "peak |a_B| (m/s²), time peak".into(),
                    "η = energy left (%)".into(),
                    "steady (1 % tolerance)".into(),
                    "damper gap at the next strike (mm)".into(),
                    "blows after the first without bed-damper contact".into(),
                ],
                rows,
                ..Default::default()
            }),
        ];
        for f in figures::blow_train_figures(dir, "blows", &runs, self.rate_bpm)? {
            blocks.push(Block::Figure(f));
        }
        Ok(Section {
            id: "blows".into(),
            heading: "Repeated blows".into(),
            blocks,
        })
    }

    /// The optimiser's ω_d/ω_s for each objective against the paper's rule ω_d = ω_s.
    fn optimiser_section(&self) -> Section {
        let mut blocks = Vec::new();
        if self.optimize.is_empty() {
            blocks.push(Block::Paragraph(
                "No optimisation: the model has no damper (see Key results, Left out).".into(),
            ));
        } else {
            let rows = self
                .optimize
                .iter()
                .map(|r| {
                    vec![
                        objective_text(r.objective),
                        format!(
                            "{}..{}{}",
                            sig(r.variables[0].lower, 3),
                            sig(r.variables[0].upper, 3),
                            if r.variables[0].log { " (log)" } else { "" }
                        ),
                        sig(r.wd_over_ws_at_optimum, 5),
                        objective_value(r.objective, r.objective_value),
                        objective_value(r.objective, r.objective_at_wd_equal_ws),
                        format!(
                            "{:+.2}",
                            100.0 * (r.objective_at_wd_equal_ws / r.objective_value - 1.0)
                        ),
                        format!(
                            "{}{}",
                            r.simulations,
                            if r.converged { "" } else { " (budget reached)" }
                        ),
                        serde_json::to_value(r.local_check.verdict)
                            .ok()
                            .and_then(|v| v.as_str().map(str::to_string))
                            .unwrap_or_default(),
                    ]
                })
                .collect();
            blocks.push(Block::Paragraph("The damper contact frequency ω_d/ω_s (K_d = m_d ω_d², other inputs as in the model) that minimises each objective: a 33-point scan in ln(ω_d/ω_s) then Brent's method around each scan basin, set against the paper's rule ω_d = ω_s (section 4.1).".into()));
            blocks.push(Block::Table(Table {
                caption: "The optimiser's damper against the rule ω_d = ω_s".into(),
                header: vec![
                    "objective".into(),
                    "bounds of ω_d/ω_s".into(),
                    "best ω_d/ω_s".into(),
                    "objective there".into(),
                    "objective with ω_d = ω_s".into(),
                    "rule vs best (%)".into(),
                    "simulations".into(),
                    "what the best is (neighbours ±0.1 % of ln range)".into(),
                ],
                rows,
                ..Default::default()
            }));
        }
        Section {
            id: "optimiser".into(),
            heading: "Optimiser against the rule ω_d = ω_s".into(),
            blocks,
        }
    }

    /// The Monte Carlo study: its inputs' distributions, the sample statistics with 95 %
    /// confidence intervals and the histograms (written into `dir`).
    fn montecarlo_section(&self, dir: &Path) -> Result<Section> {
        let mut blocks = Vec::new();
        match &self.montecarlo {
            Some(mc) => {
                let inputs: Vec<String> = mc
                    .inputs
                    .iter()
                    .map(|u| format!("{} ~ {}", u.path, distribution_text(&u.distribution)))
                    .collect();
                blocks.push(Block::Paragraph(format!(
                    "{} samples (seed {}, {} failed) with {}; every other input as in the model. Means and percentiles are estimates from the samples (standard error of the mean ≈ std/√n).",
                    mc.samples.len(),
                    mc.seed,
                    mc.failed,
                    inputs.join(", ")
                )));
                let rows = mc
                    .input_stats
                    .iter()
                    .chain(&mc.metric_stats)
                    .map(|s| {
                        let ci = |(a, b): (f64, f64)| {
                            if a.is_finite() && b.is_finite() {
                                format!("{} – {}", sig(a, 4), sig(b, 4))
                            } else {
                                "too few samples".to_string()
                            }
                        };
                        vec![
                            s.name.clone(),
                            s.count.to_string(),
                            sig(s.mean, 4),
                            ci(s.mean_ci95),
                            sig(s.std, 3),
                            sig(s.p5, 4),
                            sig(s.p50, 4),
                            sig(s.p95, 4),
                            ci((
                                s.p95_ci95.0.unwrap_or(f64::NAN),
                                s.p95_ci95.1.unwrap_or(f64::NAN),
                            )),
                        ]
                    })
                    .collect();
                blocks.push(Block::Table(Table {
                    caption: "Sample statistics, estimates from n samples with 95 % confidence intervals (mean: Student t; P95: order statistics) (units in the names: N/m, m/s², N; energy_ratio is E_p+/E_s−, 1)".into(),
                    header: vec![
                        "quantity".into(),
                        "n".into(),
                        "mean".into(),
                        "mean, 95 % CI".into(),
                        "std".into(),
                        "P5".into(),
                        "P50".into(),
                        "P95".into(),
                        "P95, 95 % CI".into(),
                    ],
                    rows,
                    ..Default::default()
                }));
                montecarlo_histograms(mc, dir, &mut blocks)?;
            }
            None => blocks.push(Block::Paragraph(
                "No Monte Carlo study: the model gives no distribution. Give one with --vary PATH=DIST, e.g. meid report MODEL.toml --vary 'contact.slider_bed.stiffness=lognormal(K_s,0.2)' (K_s varies with the workpiece; distributions: normal(μ,σ), lognormal(mean,cov), uniform(a,b)).".into(),
            )),
        }
        Ok(Section {
            id: "montecarlo".into(),
            heading: "Monte Carlo over uncertain inputs".into(),
            blocks,
        })
    }

    /// How the numbers were obtained: exact peaks, exact spectra, named measures.
    fn method_section(&self) -> Section {
        let mut method = String::new();
        let _ = write!(
            method,
            "Peaks are exact: located on the continuous piecewise solution between exactly located switches, not on the output samples. Spectra are the exact Fourier transforms of the response including its free decay; one-third-octave levels integrate them by adaptive Gauss-Kronrod. Reductions name their measure (time-peak 20 log10 of peaks; esd-peak, band-level, signal-energy and energy-ratio 10 log10 of energies). The energy map and the energy objective stop each run at the end of the collision; the floor-force objective runs the model's {} s.",
            sig(self.model.spec.simulation.duration, 4)
        );
        Section {
            id: "method".into(),
            heading: "How the numbers were obtained".into(),
            blocks: vec![
                Block::Paragraph(method),
                Block::Paragraph("Files: every picture as PNG and SVG, its data as CSV (linked under each caption), and report.json with the numbers of this page.".into()),
            ],
        }
    }

    /// The numbers of the page as JSON (`report.json`, `meid report --json`).
    pub fn summary_json(&self) -> serde_json::Value {
        let map = self.map.as_ref().map(|m| {
            serde_json::json!({
                "axes": m.axes,
                "design": m.design,
                "design_energy_ratio": m.design_energy_ratio,
                "minimum": m.minimum,
            })
        });
        let blows: Vec<serde_json::Value> = self
            .blows
            .iter()
            .map(|(c, r)| {
                serde_json::json!({
                    "case": c,
                    "interval_s": r.interval_s,
                    "blows": r.blows,
                    "steady": r.steady,
                    "damper_gap_at_next_strike_m": r.damper_gap_at_next_strike_m,
                })
            })
            .collect();
        let mc = self.montecarlo.as_ref().map(|mc| {
            serde_json::json!({
                "seed": mc.seed,
                "samples": mc.samples.len(),
                "failed": mc.failed,
                "inputs": mc.inputs,
                "input_stats": mc.input_stats,
                "metric_stats": mc.metric_stats,
            })
        });
        let mut out = serde_json::json!({
            "model": self.model_path,
            "name": self.model.spec.name,
            "verdict": self.verdict(),
            "key_results": self.key_results(),
            "production": self.production,
            "modes": self.modes,
            "energy_map": map,
            "comparison": self.comparison.summary(),
            "blow_trains": blows,
            "rate_bpm": self.rate_bpm,
            "rate_origin": self.rate_origin,
            "optimize": self.optimize,
            "montecarlo": mc,
            "measured": self.measured,
            "test_against_model": self.test_against_model,
            "warnings": self.modes.warnings,
            "notes": self.notes,
        });
        // Every closing of each contact, per case.
        if let Some(o) = out.as_object_mut() {
            let mut m = serde_json::Map::new();
            for (c, rows, _) in &self.impacts {
                m.insert(
                    c.name().into(),
                    serde_json::to_value(rows).unwrap_or_default(),
                );
            }
            o.insert("impacts".into(), m.into());
        }
        // With a [foundation], as `meid compare --json` carries it: per case.
        if let (false, Some(o)) = (self.foundation.is_empty(), out.as_object_mut()) {
            let mut f = serde_json::Map::new();
            let mut r = serde_json::Map::new();
            for (c, a) in &self.foundation {
                f.insert(
                    c.name().into(),
                    serde_json::to_value(&a.foundation).unwrap_or_default(),
                );
                r.insert(
                    c.name().into(),
                    serde_json::to_value(&a.receivers).unwrap_or_default(),
                );
            }
            o.insert("foundation".into(), f.into());
            o.insert("receivers".into(), r.into());
        }
        out
    }

    /// Writes the pictures, the data, `report.json` and `index.html` into `dir` (which must
    /// exist), then checks the page ([`super::html::check_page`]).
    pub fn write(&self, dir: &Path, generator: &str) -> Result<Page> {
        let page = self.page(dir, generator)?;
        crate::io::write_json(&dir.join("report.json"), &self.summary_json())?;
        let index = dir.join("index.html");
        page.write(&index)?;
        super::html::verify_page_file(&index)?;
        Ok(page)
    }
}

/// `lognormal(mean 4.3e7, cov 0.2)` etc.
fn distribution_text(d: &crate::analysis::montecarlo::Distribution) -> String {
    use crate::analysis::montecarlo::Distribution as D;
    match *d {
        D::Normal { mean, std } => format!("normal(μ = {}, σ = {})", sig(mean, 5), sig(std, 4)),
        D::LogNormal { mean, cov } => {
            format!("lognormal(mean {}, cov {})", sig(mean, 5), sig(cov, 4))
        }
        D::Uniform { low, high } => format!("uniform({}, {})", sig(low, 5), sig(high, 5)),
    }
}

/// The histograms of the energy left and the peak floor force over the Monte Carlo samples,
/// with the sample mean and 95th percentile marked (pictures written into `dir`).
fn montecarlo_histograms(mc: &MonteCarloResult, dir: &Path, blocks: &mut Vec<Block>) -> Result<()> {
    for (k, (metric, stem, quantity, unit, scale)) in [
        (
            "energy_ratio",
            "mc-energy-ratio",
            "energy left in the machine",
            "E_p+/E_s− (%)",
            100.0,
        ),
        (
            "peak_floor_force_n",
            "mc-floor-force",
            "peak force to the floor",
            "peak |F_floor| (N)",
            1.0,
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let values: Vec<f64> = mc
            .metric(metric)?
            .into_iter()
            .filter(|v| v.is_finite())
            .map(|v| v * scale)
            .collect();
        let Some(st) = mc.metric_stats.iter().find(|s| s.name == metric) else {
            continue;
        };
        if values.is_empty() {
            continue;
        }
        let mut st = st.clone();
        for v in [
            &mut st.mean,
            &mut st.std,
            &mut st.p5,
            &mut st.p50,
            &mut st.p95,
        ] {
            *v *= scale;
        }
        let _ = k;
        let fig = figures::histogram_figure(
                dir,
                stem,
                quantity,
                unit,
                &values,
                &st,
                format!(
                    "Histogram of the {quantity}, {unit}, over {} samples, with the sample mean ({}) and 95th percentile ({}) marked (estimates).",
                    values.len(),
                    sig(st.mean, 4),
                    sig(st.p95, 4)
                ),
            )?;
        blocks.push(Block::Figure(fig));
    }
    Ok(())
}

fn objective_text(o: Objective) -> String {
    match o {
        Objective::Energy => "energy left E_p+/E_s−".into(),
        Objective::BedAccel => "peak bed acceleration, time peak".into(),
        Objective::FloorForce => "peak floor force, time peak".into(),
    }
}

fn objective_value(o: Objective, v: f64) -> String {
    match o {
        Objective::Energy => format!("{} %", sig(100.0 * v, 4)),
        Objective::BedAccel => format!("{} m/s²", sig(v, 4)),
        Objective::FloorForce => format!("{} N", sig(v, 4)),
    }
}

#[cfg(test)]
mod tests {
    use super::log_grid;

    #[test]
    fn log_grid_is_centred_on_the_design() {
        let g = log_grid(150.0, 3.0, 5);
        assert_eq!(g.len(), 5);
        assert_eq!(g[2], 150.0);
        assert!((g[0] - 50.0).abs() < 1e-12 && (g[4] - 450.0).abs() < 1e-9);
        assert!(g.windows(2).all(|w| w[0] < w[1]));
    }
}
