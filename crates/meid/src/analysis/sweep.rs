//! Parameter sweeps: energy maps and families of curves (paper section 4, Figs. 3-5, 9, 12,
//! 16, 17).
//!
//! A [`Sweep`] varies one or more quantities ([`Vary`]) over a Cartesian grid, simulates one
//! blow at every point with [`crate::analysis::simulate`] and records every metric of the
//! [`Summary`] plus the varied values and the derived K_s, K_d, m_d.
//!
//! # Quantities
//!
//! A `SPEC` is `NAME=LIST` (`md/mb=0.35,0.7,1.0`), `NAME=A..B:N` (N linearly spaced values,
//! `A` and `B` included) or `NAME=A..B:N:log` (N values spaced evenly in `ln`). `NAME` is a
//! derived ratio of the paper or a model field path (`damper.mass`,
//! `contact.slider_bed.stiffness`, ...), set as `--set PATH=VALUE` would.
//!
//! With `w_s = sqrt(K_s/m_s)` (slider contact), `w_d = sqrt(K_d/m_d)` (damper contact),
//! `w_ref` = [`Model::reference_omega`] and `m_b` = [`Sweep::bed_mass_kg`] if given, else
//! [`Model::bed_mass`] of the point's model (after step 1, so a varied bed mass or bed plate
//! carries m_b with it), a point is built in this fixed order:
//!
//! 1. field paths, in the order given;
//! 2. `ws/w_ref = r`: `w_s = r w_ref`, `K_s = m_s w_s w_s`;
//! 3. `w_d`: `wd/ws = r` gives `w_d = r sqrt(K_s/m_s)`, `wd/w_ref = r` gives `w_d = r w_ref`,
//!    otherwise `w_d = sqrt(K_d/m_d)` of the point so far;
//! 4. `md/mb = r`: `m_d = r m_b`;
//! 5. if a ratio in 3 or 4 was given: `K_d = m_d w_d w_d` (so `md/mb` keeps `w_d`).
//!
//! Field values are set as `--set PATH=LITERAL` would, with the literal of the field's kind
//! ([`field_kind`]): a whole-number field (`structure.fem.machine.elements_per_side`) gets an
//! integer and refuses a non-integral value, naming the field. The sweep compiles its field
//! paths once into typed setters ([`crate::model::setter`]), which write a point's values into
//! the typed model without TOML; a path they do not cover, or a point a check refuses, takes the
//! TOML route (the model written as a table, the literals set, the table read back), which gives
//! the same model or the error in its own words. A varied `simulation.*` field sets that
//! point's integration options ([`point_options`]); a varied `simulation.duration` runs the
//! point for its duration instead of stopping at the end of the collision.
//!
//! # Cases
//!
//! [`Sweep::with_cases`] runs every point once per [`Case`] (`none`, `damper`, `added-mass`,
//! `as-specified`): the bare machine, the impact damper and the rigid added mass
//! ([`Model::added_mass`]: `added_mass.mass`, else the point's m_d, at `added_mass.point`, else
//! the bed contact point) are compared in one run (paper Fig. 9). The point's model is built
//! once; each case is [`Model::impact_system`] of it. The metric columns are then repeated per
//! case, named `METRIC:CASE` (`energy_ratio:none`, `energy_ratio:damper`, ...), case by case in
//! the order given. Without cases the columns are the plain [`METRICS`] of the model as
//! specified (the files are those of a sweep without this option, byte for byte).
//!
//! # Cost and reproducibility
//!
//! The model file is parsed once. Derived ratios and fields are set on a clone of the
//! [`ModelSpec`](crate::model::ModelSpec), and the structure's modal model is reused unless
//! the point changes the structural part of the model ([`crate::model::StructureKey`]: the
//! `structure` table, the role points and, where the reduction uses it, the contact
//! frequency); the structures built for such points are kept in [`Sweep::cache`] and shared
//! by the points with the same structural part. Points run in
//! parallel (rayon) and are collected in grid order, and numbers are written with Rust's
//! shortest round-trip formatting (`{:e}`), so the CSV is byte-identical for any thread count
//! and a resumed sweep reproduces an uninterrupted one exactly.
//!
//! The sweep machinery (grid, journal, resume) is hand-written: it is a few hundred lines over
//! rayon and csv, and no crate offers resumable parameter studies of this shape.
//!
//! # Example
//!
//! ```no_run
//! use meid::analysis::sweep::{Sweep, Vary};
//! use meid::model::Model;
//!
//! # fn main() -> meid::Result<()> {
//! let model = Model::from_file("examples/paper-lumped.toml".as_ref(), &[])?;
//! let sweep = Sweep::new(model, vec![Vary::parse("wd/ws=0.3..3:41:log")?])?;
//! let result = sweep.run(&|done, total| { let _ = (done, total); });
//! let best = result.argmin("energy_ratio").expect("some point succeeded");
//! let r = result.points[best].metric("energy_ratio");
//! # let _ = r;
//! result.write("out".as_ref())?; // sweep.csv, sweep.json
//! # Ok(())
//! # }
//! ```

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;
use std::sync::Mutex;

use rayon::prelude::*;
use serde::Serialize;

use crate::analysis::{simulate, Summary};
use crate::integrate::{Method, Options};
use crate::model::{
    uses_contact_omega, Case, CompiledFields, FieldValue, Model, SetterKind, StructureCache,
};
use crate::{Error, Result};

/// A quantity a sweep can vary. In JSON it is written as its [`Quantity::name`]
/// (`"wd/ws"`, `"damper.mass"`), the name a SPEC gives it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Quantity {
    /// w_s / w_ref.
    WsOverWref,
    /// w_d / w_ref.
    WdOverWref,
    /// w_d / w_s.
    WdOverWs,
    /// m_d / m_b.
    MdOverMb,
    /// A model field path, set like `--set PATH=VALUE`.
    Field(String),
}

impl Quantity {
    /// Parses a name: one of the ratios or a dotted field path.
    pub fn parse(name: &str) -> Result<Self> {
        let n = name.trim();
        Ok(match n {
            "ws/w_ref" | "ws/wref" => Quantity::WsOverWref,
            "wd/w_ref" | "wd/wref" => Quantity::WdOverWref,
            "wd/ws" => Quantity::WdOverWs,
            "md/mb" => Quantity::MdOverMb,
            _ if n.contains('/') => {
                return Err(Error::invalid(
                    "vary",
                    format!("unknown ratio `{n}`; known ratios: ws/w_ref, wd/w_ref, wd/ws, md/mb (or give a model field path such as damper.mass)"),
                ))
            }
            _ if n.is_empty()
                || !n
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "._[]-".contains(c)) =>
            {
                return Err(Error::invalid(
                    "vary",
                    format!("`{n}` is neither a ratio (ws/w_ref, wd/w_ref, wd/ws, md/mb) nor a field path"),
                ))
            }
            _ => Quantity::Field(n.to_string()),
        })
    }

    /// The name as written in SPECs and CSV headers.
    pub fn name(&self) -> String {
        match self {
            Quantity::WsOverWref => "ws/w_ref".into(),
            Quantity::WdOverWref => "wd/w_ref".into(),
            Quantity::WdOverWs => "wd/ws".into(),
            Quantity::MdOverMb => "md/mb".into(),
            Quantity::Field(p) => p.clone(),
        }
    }

    /// The paper's symbol: `ω_s/ω_ref`, `ω_d/ω_ref`, `ω_d/ω_s`, `m_d/m_b`; for the model
    /// fields of the paper's Fig. 1 their symbol (`K_s`, `C_s`, `K_d`, `C_d`, `m_d`, `k_d`,
    /// `c_d`, `m_s`, `v_s`), else the field path.
    pub fn symbol(&self) -> String {
        match self {
            Quantity::WsOverWref => "ω_s/ω_ref".into(),
            Quantity::WdOverWref => "ω_d/ω_ref".into(),
            Quantity::WdOverWs => "ω_d/ω_s".into(),
            Quantity::MdOverMb => "m_d/m_b".into(),
            Quantity::Field(p) => match p.as_str() {
                "contact.slider_bed.stiffness" => "K_s",
                "contact.slider_bed.damping" => "C_s",
                "contact.bed_damper.stiffness" => "K_d",
                "contact.bed_damper.damping" => "C_d",
                "damper.mass" => "m_d",
                "damper.stiffness" => "k_d",
                "damper.damping" => "c_d",
                "slider.mass" => "m_s",
                "slider.velocity" => "v_s",
                other => other,
            }
            .into(),
        }
    }

    /// SI unit of the quantity: `1` for the ratios, by the field's last name otherwise
    /// (`…stiffness` N/m, `…mass` kg, `…damping` N·s/m, `…velocity` m/s); `None` when
    /// unknown.
    pub fn unit(&self) -> Option<&'static str> {
        match self {
            Quantity::Field(p) => {
                if p.ends_with("stiffness") {
                    Some("N/m")
                } else if p.ends_with("mass") {
                    Some("kg")
                } else if p.ends_with("damping") {
                    Some("N·s/m")
                } else if p.ends_with("velocity") {
                    Some("m/s")
                } else {
                    None
                }
            }
            _ => Some("1"),
        }
    }

    /// Axis label in the paper's terms with the unit: `"ω_d/ω_s (1)"`, `"K_s (N/m)"`; a
    /// field of unknown unit is labelled `"PATH (as in the model file)"`.
    pub fn axis_label(&self) -> String {
        match self.unit() {
            Some(u) => format!("{} ({u})", self.symbol()),
            None => format!("{} (as in the model file)", self.symbol()),
        }
    }

    /// Legend text for one value: `"m_d/m_b = 0.35"`, `"K_s = 4.3e7 N/m"` (four
    /// significant digits at most).
    pub fn legend_entry(&self, value: f64) -> String {
        let v = crate::plot::axis::fmt_tick(&value);
        match self.unit() {
            Some("1") | None => format!("{} = {v}", self.symbol()),
            Some(u) => format!("{} = {v} {u}", self.symbol()),
        }
    }

    /// True for quantities naturally varied on a log scale (ratios, stiffnesses, masses).
    pub fn is_scale_like(&self) -> bool {
        match self {
            Quantity::Field(p) => p.contains("stiffness") || p.contains("mass"),
            _ => true,
        }
    }
}

impl Serialize for Quantity {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&self.name())
    }
}

/// Axis label of a sweep metric ([`METRICS`], [`DERIVED`]) with its unit, in words:
/// `"energy ratio E_p+/E_s− (1)"`, `"peak bed acceleration (m/s²)"`; the unit is read
/// from the name's suffix (`_j` J, `_n` N, `_s` s, `_m_per_s2` m/s², …), `(1)` otherwise.
pub fn metric_label(metric: &str) -> String {
    const UNITS: [(&str, &str); 7] = [
        ("_m_per_s2", "m/s²"),
        ("_m_per_s", "m/s"),
        ("_n_per_m", "N/m"),
        ("_kg", "kg"),
        ("_j", "J"),
        ("_n", "N"),
        ("_s", "s"),
    ];
    match metric {
        "energy_ratio" => return "energy ratio E_p+/E_s− (1)".into(),
        "wd_over_ws" => return "ω_d/ω_s (1)".into(),
        "ws_over_w_ref" => return "ω_s/ω_ref (1)".into(),
        _ => {}
    }
    let (stem, unit) = UNITS
        .iter()
        .find_map(|(suffix, u)| metric.strip_suffix(suffix).map(|s| (s, *u)))
        .unwrap_or((metric, "1"));
    format!("{} ({unit})", stem.replace('_', " "))
}

/// How the values of a [`Vary`] were given.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Spacing {
    /// An explicit list.
    List,
    /// `A..B:N`.
    Linear,
    /// `A..B:N:log`.
    Log,
}

/// One varied quantity and its values.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Vary {
    /// The SPEC as given.
    pub spec: String,
    pub quantity: Quantity,
    pub spacing: Spacing,
    pub values: Vec<f64>,
}

fn parse_number(s: &str, spec: &str, field: &str) -> Result<f64> {
    let v: f64 = s.trim().parse().map_err(|_| {
        Error::invalid(
            field,
            format!(
                "`{spec}`: `{}` is not a number (a range is A..B:N or A..B:N:log, a list v1,v2,…)",
                s.trim()
            ),
        )
    })?;
    if !v.is_finite() {
        return Err(Error::invalid(
            field,
            format!("`{spec}`: values must be finite, got `{}`", s.trim()),
        ));
    }
    Ok(v)
}

/// The values of a range or list `rhs` (`A..B:N`, `A..B:N:log` or `v1,v2,…`; module docs);
/// `spec` is quoted in errors, which are reported at `field`.
pub fn parse_values(rhs: &str, spec: &str, field: &str) -> Result<(Spacing, Vec<f64>)> {
    let (spacing, values) = if let Some((a, rest)) = rhs.split_once("..") {
        let parts: Vec<&str> = rest.split(':').collect();
        let (b, n, log) = match parts.as_slice() {
            [b, n] => (*b, *n, false),
            [b, n, s] if s.trim() == "log" => (*b, *n, true),
            [_, _, s] => {
                return Err(Error::invalid(
                    field,
                    format!("`{spec}`: unknown spacing `{}` (only `log`)", s.trim()),
                ))
            }
            _ => {
                return Err(Error::invalid(
                    field,
                    format!("`{spec}`: a range needs a count: A..B:N or A..B:N:log"),
                ))
            }
        };
        let a = parse_number(a, spec, field)?;
        let b = parse_number(b, spec, field)?;
        let n: usize = n.trim().parse().map_err(|_| {
            Error::invalid(
                field,
                format!("`{spec}`: the count `{}` is not a whole number", n.trim()),
            )
        })?;
        if n < 2 {
            return Err(Error::invalid(
                field,
                format!("`{spec}`: a range needs N >= 2 points (got {n}); give a single value as NAME=VALUE"),
            ));
        }
        if a >= b {
            return Err(Error::invalid(
                field,
                format!("`{spec}`: a range needs A < B (got {a}..{b})"),
            ));
        }
        if log && a <= 0.0 {
            return Err(Error::invalid(
                field,
                format!("`{spec}`: a log range needs A > 0 (got {a})"),
            ));
        }
        crate::limits::check_memory(
            &format!("`{spec}`: {n} values (8 B each)"),
            8.0 * n as f64,
            field,
            "the count N of the range",
        )?;
        let values: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / (n - 1) as f64;
                if i == n - 1 {
                    b
                } else if log {
                    (a.ln() + t * (b.ln() - a.ln())).exp()
                } else {
                    a + t * (b - a)
                }
            })
            .collect();
        (if log { Spacing::Log } else { Spacing::Linear }, values)
    } else {
        let values = rhs
            .split(',')
            .map(|s| parse_number(s, spec, field))
            .collect::<Result<Vec<f64>>>()?;
        (Spacing::List, values)
    };
    Ok((spacing, values))
}

impl Vary {
    /// Parses `NAME=LIST`, `NAME=A..B:N` or `NAME=A..B:N:log` (see the module docs).
    pub fn parse(spec: &str) -> Result<Self> {
        let usage =
            "expected NAME=LIST (md/mb=0.35,0.7,1.0), NAME=A..B:N (linear) or NAME=A..B:N:log";
        let (name, rhs) = spec
            .split_once('=')
            .ok_or_else(|| Error::invalid("vary", format!("`{spec}`: {usage}")))?;
        let quantity = Quantity::parse(name)?;
        let rhs = rhs.trim();
        if rhs.is_empty() {
            return Err(Error::invalid(
                "vary",
                format!("`{spec}`: no values; {usage}"),
            ));
        }
        let (spacing, values) = parse_values(rhs, spec, "vary")?;
        if !matches!(quantity, Quantity::Field(_)) && values.iter().any(|&v| v <= 0.0) {
            return Err(Error::invalid(
                "vary",
                format!("`{spec}`: the ratio {} must be > 0", quantity.name()),
            ));
        }
        Ok(Vary {
            spec: spec.trim().to_string(),
            quantity,
            spacing,
            values,
        })
    }
}

/// Names of the recorded metrics in CSV order: the [`Summary`] fields (units in the names;
/// ratios and counts are dimensionless). `method` is the same for every point and is kept
/// in `sweep.json`.
pub const METRICS: [&str; 24] = [
    "energy_ratio",
    "collision_end_s",
    "slider_energy_before_j",
    "slider_energy_after_j",
    "damper_energy_after_j",
    "machine_energy_after_j",
    "machine_kinetic_energy_after_j",
    "machine_potential_energy_after_j",
    "dissipated_energy_after_j",
    "slider_rebound_velocity_m_per_s",
    "damper_velocity_m_per_s",
    "contact_time_slider_bed_s",
    "contact_time_bed_damper_s",
    "peak_contact_force_slider_bed_n",
    "peak_contact_force_bed_damper_n",
    "peak_bed_acceleration_m_per_s2",
    "peak_floor_force_n",
    "energy_balance_residual",
    "energy_balance_residual_run_end",
    "simulated_time_s",
    "switching_events",
    "steps",
    "wd_over_ws",
    "ws_over_w_ref",
];

/// Derived columns written after the varied values.
pub const DERIVED: [&str; 4] = [
    "slider_contact_stiffness_n_per_m",
    "damper_contact_stiffness_n_per_m",
    "damper_mass_kg",
    "slider_mass_kg",
];

fn summary_metrics(s: &Summary) -> Vec<Option<f64>> {
    vec![
        s.energy_ratio,
        s.collision_end_s,
        Some(s.slider_energy_before_j),
        s.slider_energy_after_j,
        s.damper_energy_after_j,
        s.machine_energy_after_j,
        s.machine_kinetic_energy_after_j,
        s.machine_potential_energy_after_j,
        s.dissipated_energy_after_j,
        s.slider_rebound_velocity_m_per_s,
        s.damper_velocity_m_per_s,
        s.contact_time_slider_bed_s,
        s.contact_time_bed_damper_s,
        Some(s.peak_contact_force_slider_bed_n),
        Some(s.peak_contact_force_bed_damper_n),
        Some(s.peak_bed_acceleration_m_per_s2),
        Some(s.peak_floor_force_n),
        s.energy_balance_residual,
        Some(s.energy_balance_residual_run_end),
        Some(s.simulated_time_s),
        Some(s.switching_events as f64),
        Some(s.steps as f64),
    ]
}

/// The result at one grid point.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointResult {
    /// Position in the grid (row-major, the last [`Vary`] fastest).
    pub index: usize,
    /// Values of the varied quantities, in [`Sweep::vary`] order.
    pub values: Vec<f64>,
    /// [`DERIVED`]: K_s (N/m), K_d (N/m), m_d (kg), m_s (kg) of the point (NaN if unknown).
    pub derived: Vec<f64>,
    /// [`METRICS`] (None: not defined, e.g. the collision did not end; NaN: the point failed);
    /// with cases ([`Sweep::cases`]) the [`METRICS`] of each case in turn.
    pub metrics: Vec<Option<f64>>,
    /// Why the point failed.
    pub error: Option<String>,
}

impl PointResult {
    /// A metric by name ([`METRICS`] or [`DERIVED`]); NaN if undefined or failed. With
    /// cases, a [`METRICS`] name reads the first case ([`PointResult::case_metric`]).
    pub fn metric(&self, name: &str) -> f64 {
        self.case_metric(0, name)
    }

    /// A metric of the `k`-th case of the sweep (0 without cases; [`DERIVED`] names are the
    /// point's, whatever `k`); NaN if undefined, failed or unknown.
    pub fn case_metric(&self, k: usize, name: &str) -> f64 {
        if let Some(i) = METRICS.iter().position(|m| *m == name) {
            return self
                .metrics
                .get(k * METRICS.len() + i)
                .copied()
                .flatten()
                .unwrap_or(f64::NAN);
        }
        if let Some(i) = DERIVED.iter().position(|m| *m == name) {
            return self.derived.get(i).copied().unwrap_or(f64::NAN);
        }
        f64::NAN
    }
}

/// The system of one point: the model with the point's values set, and what was derived.
#[derive(Debug, Clone)]
pub struct PointModel {
    pub model: Model,
    /// [`DERIVED`] values.
    pub derived: Vec<f64>,
}

/// A parameter sweep: build, then [`Sweep::run`] or [`Sweep::run_resumable`].
#[derive(Debug, Clone)]
pub struct Sweep {
    /// The base model (file values and `--set` overrides).
    pub model: Model,
    pub vary: Vec<Vary>,
    /// Integration options of every point. Default: the model's, with
    /// `stop_at_collision_end = true` (the sample rate then only serves the peak bed
    /// acceleration and floor force during the collision).
    pub options: Options,
    /// m_b (kg) for `md/mb`, when given (`--bed-mass`); `None`: each point's
    /// [`Model::bed_mass`].
    pub bed_mass_kg: Option<f64>,
    /// The cases run at every point ([`Sweep::with_cases`]); empty: the model as specified,
    /// with the plain [`METRICS`] columns.
    pub cases: Vec<Case>,
    /// The structures the points built (when a varied field changes the structural part of
    /// the model, [`crate::model::StructureKey`]), shared by the points.
    pub cache: std::sync::Arc<StructureCache>,
    /// The varied field paths compiled on the model ([`crate::model::setter`]).
    fields: CompiledFields,
}

/// The name of a case in `--cases` and in the `METRIC:CASE` columns: `none`, `damper`,
/// `added-mass`, `as-specified` (what [`Case`]'s `FromStr` reads).
pub fn case_name(c: Case) -> &'static str {
    match c {
        Case::AsSpecified => "as-specified",
        Case::NoDamper => "none",
        Case::Damper => "damper",
        Case::AddedMass => "added-mass",
    }
}

/// Legend text of a case (the paper's terms).
pub fn case_label(c: Case) -> &'static str {
    match c {
        Case::AsSpecified => "as specified",
        Case::NoDamper => "without damper",
        Case::Damper => "impact damper",
        Case::AddedMass => "added mass",
    }
}

/// Everything a sweep produced, in grid order.
#[derive(Debug, Clone, Serialize)]
pub struct SweepResult {
    pub spec: SweepSpec,
    pub points: Vec<PointResult>,
}

/// The description of a sweep kept with its results (`sweep.json`).
#[derive(Debug, Clone, Serialize)]
pub struct SweepSpec {
    pub model: String,
    pub model_name: Option<String>,
    pub overrides: Vec<String>,
    pub vary: Vec<Vary>,
    pub method: &'static str,
    /// The options every point starts from; a varied `simulation.*` column overrides its
    /// setting per point (a varied duration also clears `stop_at_collision_end`).
    pub duration_s: f64,
    pub stop_at_collision_end: bool,
    pub sample_rate_hz: Option<f64>,
    pub reference_omega_rad_per_s: Option<f64>,
    /// The reference mode (structure number, frequency, effective mass) when the sweep varies a
    /// ratio to ω_ref (ws/w_ref, wd/w_ref).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_mode: Option<crate::model::ReferenceMode>,
    pub bed_mass_kg: Option<f64>,
    /// The cases run at every point ([`case_name`]); absent without cases.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub cases: Vec<String>,
    pub columns: Vec<String>,
}

impl Sweep {
    /// A sweep of `model` over the grid of `vary` (checked: quantities distinct, w_ref / m_b /
    /// damper available where the ratios need them, field paths numeric, whole-number fields
    /// given whole numbers). m_b is each point's [`Model::bed_mass`].
    pub fn new(model: Model, vary: Vec<Vary>) -> Result<Self> {
        Self::with_bed_mass(model, vary, None)
    }

    /// [`Sweep::new`] with the bed mass m_b (kg) for `md/mb` given (`None`: each point's
    /// [`Model::bed_mass`]). The given mass is applied before the quantities are checked.
    pub fn with_bed_mass(model: Model, vary: Vec<Vary>, bed_mass_kg: Option<f64>) -> Result<Self> {
        let mut options = model.options();
        options.stop_at_collision_end = true;
        let bed_mass_kg = check_bed_mass(bed_mass_kg)?;
        let paths: Vec<&str> = vary
            .iter()
            .filter_map(|v| match &v.quantity {
                Quantity::Field(p) => Some(p.as_str()),
                _ => None,
            })
            .collect();
        let fields = model.compile_fields(&paths);
        let s = Sweep {
            model,
            vary,
            options,
            bed_mass_kg,
            cases: Vec::new(),
            cache: Default::default(),
            fields,
        };
        s.check()?;
        Ok(s)
    }

    /// Runs every point once per case (module docs, "Cases"): the metric columns become
    /// `METRIC:CASE`. Refuses a case listed twice and a case the model cannot build (`damper`
    /// without a `[damper]`, `added-mass` without `[added_mass]` or `[damper]`), naming it.
    pub fn with_cases(mut self, cases: Vec<Case>) -> Result<Self> {
        for (i, c) in cases.iter().enumerate() {
            if cases[..i].contains(c) {
                return Err(Error::invalid(
                    "cases",
                    format!("the case `{}` is listed twice", case_name(*c)),
                ));
            }
            self.model.impact_system(*c).map_err(|e| {
                Error::invalid(
                    "cases",
                    format!(
                        "the case `{}` cannot be built on this model: {e}",
                        case_name(*c)
                    ),
                )
            })?;
        }
        self.cases = cases;
        self.check()?;
        Ok(self)
    }

    /// The cases a point runs: [`Sweep::cases`], or the model as specified.
    fn point_cases(&self) -> Vec<Case> {
        if self.cases.is_empty() {
            vec![Case::AsSpecified]
        } else {
            self.cases.clone()
        }
    }

    /// Column name of a metric of the `k`-th case: `METRIC:CASE` with cases, `METRIC` without.
    pub fn metric_column(&self, k: usize, metric: &str) -> String {
        match self.cases.get(k) {
            Some(c) => format!("{metric}:{}", case_name(*c)),
            None => metric.to_string(),
        }
    }

    fn check(&self) -> Result<()> {
        if self.vary.is_empty() {
            return Err(Error::invalid("vary", "give at least one --vary SPEC"));
        }
        for (i, v) in self.vary.iter().enumerate() {
            if v.values.is_empty() {
                return Err(Error::invalid(
                    "vary",
                    format!("`{}` has no values", v.spec),
                ));
            }
            if self.vary[..i].iter().any(|w| w.quantity == v.quantity) {
                return Err(Error::invalid(
                    "vary",
                    format!("{} is varied twice", v.quantity.name()),
                ));
            }
        }
        let points: f64 = self.vary.iter().map(|v| v.values.len() as f64).product();
        let per_point = self.bytes_per_point();
        crate::limits::check_memory(
            &format!("the grid of {points:.3e} points ({per_point} B each)"),
            points * per_point,
            "vary",
            "the counts of the --vary ranges",
        )?;
        let qs: Vec<&Quantity> = self.vary.iter().map(|v| &v.quantity).collect();
        let m_b = self.bed_mass_kg.or_else(|| self.model.bed_mass());
        check_quantities(&self.model, &qs, m_b)?;
        let table = spec_table(&self.model)?;
        for v in &self.vary {
            if let Quantity::Field(p) = &v.quantity {
                let kind = kind_in(&table, p, "--vary")?;
                for &x in &v.values {
                    field_literal(p, x, kind, "--vary")?;
                }
            }
        }
        Ok(())
    }

    /// When every point of `result` failed: that failure as an error (the first point's, with
    /// its kind: an input error stays an input error), noting how many points failed. `None`
    /// when at least one point succeeded.
    pub fn all_failed_error(&self, result: &SweepResult) -> Option<Error> {
        let first = result.points.first()?;
        if result.failures() < result.points.len() {
            return None;
        }
        Some(failure_error(
            &self.model,
            &self.quantities(),
            &first.values,
            self.bed_mass_kg,
            first.error.as_deref().unwrap_or("failed"),
            &format!("all {} points of the sweep failed", result.points.len()),
            &format!("point {}", first.index),
        ))
    }

    /// Memory one grid point takes (bytes): its [`PointResult`] (values, derived quantities,
    /// metrics) and its text in `sweep.csv` and `sweep.json`, each ≤ 24 characters per column.
    pub fn bytes_per_point(&self) -> f64 {
        let metrics = (METRICS.len() * self.cases.len().max(1)) as f64;
        let columns = (self.vary.len() + DERIVED.len()) as f64 + metrics + 2.0;
        std::mem::size_of::<PointResult>() as f64
            + 8.0 * (self.vary.len() + DERIVED.len()) as f64
            + 16.0 * metrics
            + 2.0 * 24.0 * columns
    }

    /// Number of grid points.
    pub fn len(&self) -> usize {
        self.vary.iter().map(|v| v.values.len()).product()
    }

    /// True if the grid is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Values of the varied quantities at grid point `index` (row-major, last fastest).
    pub fn values_at(&self, index: usize) -> Vec<f64> {
        let mut rest = index;
        let mut out = vec![0.0; self.vary.len()];
        for (k, v) in self.vary.iter().enumerate().rev() {
            let n = v.values.len();
            out[k] = v.values[rest % n];
            rest /= n;
        }
        out
    }

    fn quantities(&self) -> Vec<&Quantity> {
        self.vary.iter().map(|v| &v.quantity).collect()
    }

    /// Column names of `sweep.csv`: `index`, varied names, [`DERIVED`], [`METRICS`] (per case,
    /// `METRIC:CASE`, with cases), `error`.
    pub fn columns(&self) -> Vec<String> {
        let mut c = vec!["index".to_string()];
        c.extend(self.vary.iter().map(|v| v.quantity.name()));
        c.extend(DERIVED.iter().map(|s| s.to_string()));
        for k in 0..self.cases.len().max(1) {
            c.extend(METRICS.iter().map(|m| self.metric_column(k, m)));
        }
        c.push("error".into());
        c
    }

    /// The model of grid point `index` (see the module docs for the order of resolution).
    pub fn point_model(&self, index: usize) -> Result<PointModel> {
        point_model_compiled(
            &self.model,
            Some(&self.fields),
            &self.quantities(),
            &self.values_at(index),
            self.bed_mass_kg,
            Some(&self.cache),
        )
    }

    /// The integration options of grid point `index`: [`Sweep::options`] with the point's
    /// varied `simulation.*` fields ([`point_options`]).
    pub fn point_options(&self, index: usize) -> Result<Options> {
        let pm = self.point_model(index)?;
        Ok(point_options(&self.options, &self.quantities(), &pm.model))
    }

    /// Simulates grid point `index`; failures become a [`PointResult`] with its error.
    pub fn run_point(&self, index: usize) -> PointResult {
        let values = self.values_at(index);
        let quantities = self.quantities();
        let pm = point_model_compiled(
            &self.model,
            Some(&self.fields),
            &quantities,
            &values,
            self.bed_mass_kg,
            Some(&self.cache),
        );
        evaluate_model(
            pm,
            &quantities,
            &values,
            &self.options,
            index,
            &self.point_cases(),
        )
    }

    /// Runs every point in parallel (on the current rayon pool); `progress(done, total)` is
    /// called after each point from the worker threads.
    pub fn run(&self, progress: &(dyn Fn(usize, usize) + Sync)) -> SweepResult {
        let all: Vec<usize> = (0..self.len()).collect();
        let (points, _) = self.run_indices(&all, progress, 0, None);
        SweepResult {
            spec: self.spec(),
            points,
        }
    }

    /// Runs the grid points `range` only (a shard of the sweep: a point depends only on its
    /// index, so any split gives the same rows); `progress(done, range length)`.
    pub fn run_range(
        &self,
        range: std::ops::Range<usize>,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Vec<PointResult>> {
        if range.end > self.len() || range.start > range.end {
            return Err(Error::invalid(
                "shard",
                format!(
                    "points {}..{} are outside the grid of {} points",
                    range.start,
                    range.end,
                    self.len()
                ),
            ));
        }
        let n = range.len();
        let done = std::sync::atomic::AtomicUsize::new(0);
        Ok(range
            .into_par_iter()
            .map(|i| {
                let r = self.run_point(i);
                let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                progress(d, n);
                r
            })
            .collect())
    }

    /// The result of the whole grid from its points in any order (e.g. the shards' rows):
    /// refused unless every grid point is there exactly once.
    pub fn result_from(&self, mut points: Vec<PointResult>) -> Result<SweepResult> {
        points.sort_by_key(|p| p.index);
        let total = self.len();
        for (i, p) in points.iter().enumerate() {
            if p.index != i {
                let what = if p.index < i {
                    format!("point {} is given twice", p.index)
                } else {
                    format!("point {i} is missing")
                };
                return Err(Error::invalid(
                    "shards",
                    format!("{what}; the sweep has {total} points"),
                ));
            }
        }
        if points.len() != total {
            return Err(Error::invalid(
                "shards",
                format!(
                    "{} of the sweep's {total} points are given; points {}..{total} are missing",
                    points.len(),
                    points.len()
                ),
            ));
        }
        Ok(SweepResult {
            spec: self.spec(),
            points,
        })
    }

    /// A fingerprint of everything that determines the results (model, grid, options), as in
    /// the journal's first line: shards of one sweep have the same.
    pub fn fingerprint_text(&self) -> String {
        self.fingerprint()
    }

    fn run_indices(
        &self,
        indices: &[usize],
        progress: &(dyn Fn(usize, usize) + Sync),
        already: usize,
        journal: Option<(&Path, &Mutex<std::fs::File>)>,
    ) -> (Vec<PointResult>, Option<Error>) {
        let total = self.len();
        let done = std::sync::atomic::AtomicUsize::new(already);
        let journal_error: Mutex<Option<Error>> = Mutex::new(None);
        let out: Vec<PointResult> = indices
            .par_iter()
            .map(|&i| {
                let r = self.run_point(i);
                if let Some((path, j)) = journal {
                    let mut line = crate::input::seal_row(self.row(&r).trim_end_matches('\n'));
                    line.push('\n');
                    if let Ok(mut f) = j.lock() {
                        if let Err(e) = f.write_all(line.as_bytes()).and_then(|_| f.flush()) {
                            if let Ok(mut je) = journal_error.lock() {
                                je.get_or_insert(Error::io(path, e));
                            }
                        }
                    }
                }
                let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                progress(d, total);
                r
            })
            .collect();
        let err = journal_error.into_inner().ok().flatten();
        (out, err)
    }

    /// The sweep's description (for `sweep.json`).
    pub fn spec(&self) -> SweepSpec {
        SweepSpec {
            model: self.model.source.name.clone(),
            model_name: self.model.spec.name.clone(),
            overrides: self
                .model
                .source
                .overrides
                .iter()
                .map(|(p, v)| format!("{p}={v}"))
                .collect(),
            vary: self.vary.clone(),
            method: match self.options.method {
                Method::Exact => "exact",
                Method::Dopri5 => "dopri5",
            },
            duration_s: self.options.duration,
            stop_at_collision_end: self.options.stop_at_collision_end
                && !self
                    .vary
                    .iter()
                    .any(|v| v.quantity == Quantity::Field("simulation.duration".into())),
            sample_rate_hz: self.options.sample_rate,
            reference_omega_rad_per_s: self.model.reference_omega(),
            reference_mode: self
                .vary
                .iter()
                .any(|v| matches!(v.quantity, Quantity::WsOverWref | Quantity::WdOverWref))
                .then(|| self.model.reference_mode())
                .flatten(),
            bed_mass_kg: self.bed_mass_kg.or_else(|| self.model.bed_mass()),
            cases: self
                .cases
                .iter()
                .map(|c| case_name(*c).to_string())
                .collect(),
            columns: self.columns(),
        }
    }

    /// One CSV row (with its newline) for a point.
    pub fn row(&self, r: &PointResult) -> String {
        format_row(r)
    }

    /// A fingerprint of everything that determines the results (model spec and text, the
    /// content of the files it refers to, grid, options): FNV-1a 64 over their JSON/debug
    /// text. A journal or shard from another sweep is refused.
    fn fingerprint(&self) -> String {
        let mut text = serde_json::to_string(&self.model.spec).unwrap_or_default();
        let _ = write!(
            text,
            "|{:?}|{:?}|{:?}|{}{}",
            self.vary,
            self.options,
            self.bed_mass_kg,
            self.model.source.text,
            self.model.files_fingerprint()
        );
        if !self.cases.is_empty() {
            let _ = write!(text, "|cases {:?}", self.cases);
        }
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in text.bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        format!("{h:016x}")
    }

    /// The journal's first line: its format version and this sweep's fingerprint.
    fn journal_first_line(&self) -> String {
        format!("# meid sweep journal v2 {}\n", self.fingerprint())
    }

    /// The journal's header: the columns of `sweep.csv` and the row checksum.
    fn journal_header(&self) -> String {
        let mut s = self.columns().join(",");
        s.push_str(",row_fnv1a\n");
        s
    }

    /// Runs the sweep keeping a journal: every finished point is appended (and flushed) to
    /// `journal` as its CSV row followed by the row's checksum ([`crate::input::seal_row`]),
    /// so an interrupted sweep loses no finished point. With `resume`, the rows already in the
    /// journal whose checksum matches and whose cells are what a run writes
    /// ([`check_cells`]) are reused; a row cut short, edited or holding a non-finite value
    /// where a run writes none is dropped and its point computed again. A journal of another
    /// sweep (fingerprint) or of an older format is refused. The journal is kept; delete it
    /// after [`SweepResult::write`] if wanted.
    pub fn run_resumable(
        &self,
        journal: &Path,
        resume: bool,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<SweepResult> {
        let total = self.len();
        let first = self.journal_first_line();
        let header = self.journal_header();
        let mut known: Vec<Option<PointResult>> = vec![None; total];
        let kept = if resume {
            self.read_journal(journal, &mut known)?
        } else {
            None
        };
        // (Re)write the journal: the kept rows, or a fresh header.
        let file = match kept {
            Some(JournalKept::Prefix(len)) => {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(journal)
                    .map_err(|e| Error::io(journal, e))?;
                f.set_len(len as u64).map_err(|e| Error::io(journal, e))?;
                std::fs::OpenOptions::new()
                    .append(true)
                    .open(journal)
                    .map_err(|e| Error::io(journal, e))?
            }
            Some(JournalKept::Rows(rows)) => {
                let mut text = format!("{first}{header}");
                text.push_str(&rows);
                crate::io::write_atomic(journal, text.as_bytes())?;
                std::fs::OpenOptions::new()
                    .append(true)
                    .open(journal)
                    .map_err(|e| Error::io(journal, e))?
            }
            None => {
                if let Some(dir) = journal.parent().filter(|p| !p.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
                }
                let mut f = std::fs::File::create(journal).map_err(|e| Error::io(journal, e))?;
                f.write_all(first.as_bytes())
                    .and_then(|_| f.write_all(header.as_bytes()))
                    .and_then(|_| f.flush())
                    .map_err(|e| Error::io(journal, e))?;
                f
            }
        };
        let missing: Vec<usize> = (0..total).filter(|&i| known[i].is_none()).collect();
        let already = total - missing.len();
        let lock = Mutex::new(file);
        let (fresh, journal_error) =
            self.run_indices(&missing, progress, already, Some((journal, &lock)));
        if let Some(e) = journal_error {
            return Err(e);
        }
        for r in fresh {
            let i = r.index;
            known[i] = Some(r);
        }
        let points: Vec<PointResult> = known.into_iter().flatten().collect();
        if points.len() != total {
            return Err(Error::numerical("sweep", "points missing after the run"));
        }
        Ok(SweepResult {
            spec: self.spec(),
            points,
        })
    }

    /// Reads the rows of a journal into `known` (see [`Sweep::run_resumable`]); `None` when
    /// there is nothing to resume (no journal, or one without a finished row).
    fn read_journal(
        &self,
        journal: &Path,
        known: &mut [Option<PointResult>],
    ) -> Result<Option<JournalKept>> {
        let first = self.journal_first_line();
        let header = self.journal_header();
        let bytes = match crate::input::read_bytes(journal) {
            Ok(b) => b,
            Err(Error::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
                return Ok(None)
            }
            Err(e) => return Err(e),
        };
        let text = String::from_utf8_lossy(&bytes);
        // A journal without a finished point (empty, or cut within its first two lines,
        // whichever sweep wrote them) holds nothing to resume: start afresh.
        let lines = text
            .split_inclusive('\n')
            .filter(|l| l.ends_with('\n'))
            .count();
        if lines <= 2
            && (text.is_empty()
                || text.starts_with("# meid sweep journal")
                || format!("{first}{header}").starts_with(&*text))
        {
            return Ok(None);
        }
        if text.starts_with("# meid sweep journal v1 ") {
            return Err(Error::Input {
                location: journal.display().to_string(),
                message: "a sweep journal of an older meid (format v1, rows without checksums, which cannot be verified); drop --resume and give --force to compute the sweep afresh".into(),
            });
        }
        if !text.starts_with(&first) {
            return Err(Error::invalid(
                "resume",
                format!(
                    "{} is the journal of a different sweep (model, a file it reads, --vary or options changed); remove it or drop --resume",
                    journal.display()
                ),
            ));
        }
        let total = known.len();
        let mut offset = first.len();
        let mut good = String::new();
        let mut dropped = false;
        for line in text[first.len()..].split_inclusive('\n') {
            if !line.ends_with('\n') {
                break; // cut short by an interruption
            }
            if line == header {
                offset += line.len();
                continue;
            }
            let row = crate::input::unseal_row(line.trim_end_matches('\n'));
            match row.and_then(|r| self.parse_row(r)) {
                Some(r) if r.index < total && check_cells(&r, self.cases.len().max(1)).is_ok() => {
                    let i = r.index;
                    known[i] = Some(r);
                    good.push_str(line);
                    if !dropped {
                        offset += line.len();
                    }
                }
                _ => dropped = true,
            }
        }
        Ok(Some(if dropped {
            JournalKept::Rows(good)
        } else {
            JournalKept::Prefix(offset)
        }))
    }

    /// Parses a journal row ([`Sweep::row`] without its newline); `None` if it does not fit
    /// this sweep.
    pub fn parse_row(&self, line: &str) -> Option<PointResult> {
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(false)
            .from_reader(line.as_bytes());
        let rec = rdr.records().next()?.ok()?;
        let nv = self.vary.len();
        let nm = METRICS.len() * self.cases.len().max(1);
        if rec.len() != 1 + nv + DERIVED.len() + nm + 1 {
            return None;
        }
        let num = |s: &str| -> Option<f64> { s.parse().ok() };
        let index: usize = rec.get(0)?.parse().ok()?;
        let values: Option<Vec<f64>> = (1..=nv).map(|k| num(rec.get(k)?)).collect();
        let values = values?;
        if values != self.values_at(index.min(self.len().saturating_sub(1))) {
            return None;
        }
        let derived: Option<Vec<f64>> = (0..DERIVED.len())
            .map(|k| num(rec.get(1 + nv + k)?))
            .collect();
        let mut metrics = Vec::with_capacity(nm);
        for k in 0..nm {
            let s = rec.get(1 + nv + DERIVED.len() + k)?;
            metrics.push(if s.is_empty() { None } else { Some(num(s)?) });
        }
        let e = rec.get(rec.len() - 1)?;
        Some(PointResult {
            index,
            values,
            derived: derived?,
            metrics,
            error: if e.is_empty() {
                None
            } else {
                Some(e.to_string())
            },
        })
    }
}

/// What of a journal is kept on resuming.
enum JournalKept {
    /// Its first `n` bytes (every complete row was good).
    Prefix(usize),
    /// These rows (with their newlines) after a fresh first line and header: some rows were
    /// dropped.
    Rows(String),
}

/// Checks that the cells of a row read back (journal, shard) are what a run writes: no
/// infinite value anywhere; a NaN only where a run writes one — every cell of a failed point,
/// the derived K_d and m_d and the ratios `wd_over_ws`, `ws_over_w_ref` of a model without
/// them; a run's own metrics (the energy ratio, energies, forces, ...) of a point that did
/// not fail are finite or empty. `cases` is the number of cases (1 without `--cases`). The
/// error names the first offending column.
pub fn check_cells(r: &PointResult, cases: usize) -> std::result::Result<(), String> {
    let bad = |what: &str, v: f64| Err(format!("{what} is {}", crate::num(v)));
    for (k, v) in r.values.iter().enumerate() {
        if !v.is_finite() {
            return bad(&format!("varied value {}", k + 1), *v);
        }
    }
    for (k, v) in r.derived.iter().enumerate() {
        if v.is_infinite() || (v.is_nan() && r.error.is_none() && (k == 0 || k == 3)) {
            return bad(DERIVED[k], *v);
        }
    }
    if r.metrics.len() != METRICS.len() * cases {
        return Err(format!(
            "{} metric cells, expected {}",
            r.metrics.len(),
            METRICS.len() * cases
        ));
    }
    let own = METRICS.len() - 2;
    for (k, m) in r.metrics.iter().enumerate() {
        let Some(v) = *m else { continue };
        let name = METRICS[k % METRICS.len()];
        if v.is_infinite() || (v.is_nan() && r.error.is_none() && k % METRICS.len() < own) {
            return bad(name, v);
        }
    }
    Ok(())
}

fn csv_quote(s: &str) -> String {
    let clean = s.replace(['\n', '\r'], " | ");
    format!("\"{}\"", clean.replace('"', "\"\""))
}

impl SweepResult {
    /// `sweep.csv`: header with units, one row per point in grid order.
    pub fn csv(&self) -> String {
        let mut s = self.spec.columns.join(",");
        s.push('\n');
        for p in &self.points {
            s.push_str(&format_row(p));
        }
        s
    }

    /// Writes `sweep.csv` (atomically) and `sweep.json` (spec and rows) into `dir`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        crate::io::write_atomic(&dir.join("sweep.csv"), self.csv().as_bytes())?;
        crate::io::write_json(&dir.join("sweep.json"), self)
    }

    /// The value of a column at point `i`: a [`METRICS`] name (the first case), a
    /// `METRIC:CASE` column of a sweep with cases, or a [`DERIVED`] name; NaN if undefined.
    pub fn value(&self, i: usize, column: &str) -> f64 {
        let Some(p) = self.points.get(i) else {
            return f64::NAN;
        };
        match column.split_once(':') {
            Some((metric, case)) => match self.spec.cases.iter().position(|c| c == case) {
                Some(k) => p.case_metric(k, metric),
                None => f64::NAN,
            },
            None => p.metric(column),
        }
    }

    /// Index (into `points`) of the smallest finite value of a column ([`SweepResult::value`]).
    pub fn argmin(&self, metric: &str) -> Option<usize> {
        let mut best: Option<(usize, f64)> = None;
        for i in 0..self.points.len() {
            let v = self.value(i, metric);
            if v.is_finite() && best.is_none_or(|(_, b)| v < b) {
                best = Some((i, v));
            }
        }
        best.map(|(i, _)| i)
    }

    /// Number of failed points.
    pub fn failures(&self) -> usize {
        self.points.iter().filter(|p| p.error.is_some()).count()
    }
}

/// One CSV row: numbers in shortest round-trip form (`{:e}`), empty for undefined metrics,
/// `NaN` for failed points, the error quoted.
fn format_row(r: &PointResult) -> String {
    let mut fields: Vec<String> = vec![r.index.to_string()];
    fields.extend(r.values.iter().map(|v| format!("{v:e}")));
    fields.extend(r.derived.iter().map(|v| format!("{v:e}")));
    fields.extend(
        r.metrics
            .iter()
            .map(|m| m.map_or(String::new(), |v| format!("{v:e}"))),
    );
    fields.push(r.error.as_deref().map_or(String::new(), csv_quote));
    let mut s = fields.join(",");
    s.push('\n');
    s
}

/// A given bed mass must be a finite number > 0 kg.
pub(crate) fn check_bed_mass(m: Option<f64>) -> Result<Option<f64>> {
    match m {
        Some(m) if !(m.is_finite() && m > 0.0) => Err(Error::invalid(
            "bed mass",
            format!("m_b must be a finite number > 0 kg (got {m})"),
        )),
        m => Ok(m),
    }
}

/// The error of a failed point, with its kind: the point's model and impact system are built
/// again and their error returned (an input error stays an input error); if they build, the
/// failure was the run's, reported as a numerical error with the `recorded` message. `note`
/// says how many points failed, `which` names the point shown (e.g. "point 0").
pub(crate) fn failure_error(
    base: &Model,
    quantities: &[&Quantity],
    values: &[f64],
    bed_mass_kg: Option<f64>,
    recorded: &str,
    note: &str,
    which: &str,
) -> Error {
    let tag = format!("{note}; this is {which}'s error");
    let built = point_model(base, quantities, values, bed_mass_kg)
        .and_then(|pm| pm.model.impact_system(Case::AsSpecified).map(|_| ()));
    match built {
        Err(Error::Input { location, message }) => Error::Input {
            location,
            message: format!("{message} ({tag})"),
        },
        Err(Error::InvalidValue { field, message }) => Error::InvalidValue {
            field,
            message: format!("{message} ({tag})"),
        },
        Err(Error::Numerical { context, message }) => Error::Numerical {
            context,
            message: format!("{message} ({tag})"),
        },
        Err(e @ Error::Io { .. }) => e,
        Ok(()) => Error::numerical("sweep", format!("{note}; {which}: {recorded}")),
    }
}

/// Checks that the quantities can be resolved on `model`.
pub fn check_quantities(model: &Model, qs: &[&Quantity], bed_mass_kg: Option<f64>) -> Result<()> {
    let has = |q: &Quantity| qs.contains(&q);
    if has(&Quantity::WdOverWs) && has(&Quantity::WdOverWref) {
        return Err(Error::invalid(
            "vary",
            "give w_d either as wd/ws or as wd/w_ref, not both",
        ));
    }
    let needs_ref = has(&Quantity::WsOverWref) || has(&Quantity::WdOverWref);
    if needs_ref && model.reference_omega().is_none() {
        return Err(Error::invalid(
            "vary",
            "ws/w_ref and wd/w_ref need the model's reference mode: set structure.reference_mode to the structure's number of the mode (as `meid modes` lists them); without it meid takes the mode with the largest effective mass along the blow, which tabulated and imported modes do not tell",
        ));
    }
    let needs_damper =
        has(&Quantity::WdOverWs) || has(&Quantity::WdOverWref) || has(&Quantity::MdOverMb);
    if needs_damper && (model.spec.damper.is_none() || model.spec.contact.bed_damper.is_none()) {
        return Err(Error::invalid(
            "vary",
            "wd/ws, wd/w_ref and md/mb need a [damper] and [contact.bed_damper] in the model",
        ));
    }
    if has(&Quantity::MdOverMb) && !bed_mass_kg.is_some_and(|m| m > 0.0) {
        return Err(Error::invalid(
            "vary",
            "md/mb needs the bed mass m_b, which this model cannot tell (it can for a lumped mass at points.bed_contact, the parametric FE machine struck on its bed plate, or a general model whose bed elements carry part = \"bed\" with points.bed_contact on them); give --bed-mass KG",
        ));
    }
    Ok(())
}

/// The TOML table of a model's spec (what `--set` paths address).
fn spec_table(model: &Model) -> Result<toml::Table> {
    toml::Table::try_from(&model.spec)
        .map_err(|e| Error::numerical("sweep", format!("cannot serialise the model: {e}")))
}

/// The type of a numeric model field: a real number or a whole number (a count or an index,
/// e.g. `structure.fem.machine.elements_per_side`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FieldKind {
    Real,
    Whole,
}

fn kind_in(table: &toml::Table, path: &str, flag: &str) -> Result<FieldKind> {
    let probe = |raw: &str| -> std::result::Result<(), String> {
        let mut t = table.clone();
        crate::model::source::apply_override(&mut t, &format!("{path}={raw}"))
            .map_err(|e| e.to_string())?;
        crate::model::strict::deserialize::<crate::model::ModelSpec, _>(toml::Value::Table(t))
            .map(|_| ())
            .map_err(|(e, track)| crate::model::strict::message(e.message(), &track))
    };
    match probe("1.5") {
        Ok(()) => Ok(FieldKind::Real),
        Err(real) => match probe("1") {
            Ok(()) => Ok(FieldKind::Whole),
            Err(_) => Err(Error::Input {
                location: format!("{flag} {path}"),
                message: format!("`{path}` cannot be set to a number: {real}"),
            }),
        },
    }
}

/// Whether the model field `path` takes a real or a whole number; an error naming the field
/// when it is not a numeric field of the model (unknown key, a string, a table, ...).
pub fn field_kind(model: &Model, path: &str) -> Result<FieldKind> {
    kind_in(&spec_table(model)?, path, "--vary")
}

/// The TOML literal of value `v` for a field of kind `kind`: real numbers in shortest
/// round-trip form (`{:e}`), whole numbers as integer literals (`8`, not `8e0`, which a
/// whole-number field refuses); a non-integral value for a whole-number field is an error
/// naming the field.
pub fn field_literal(path: &str, v: f64, kind: FieldKind, flag: &str) -> Result<String> {
    match kind {
        FieldKind::Real => Ok(format!("{v:e}")),
        FieldKind::Whole => {
            // 2^53: every integer up to it is an exact f64.
            if v.is_finite() && v.fract() == 0.0 && v.abs() <= 9_007_199_254_740_992.0 {
                Ok(format!("{}", v as i64))
            } else {
                Err(Error::Input {
                    location: format!("{flag} {path}={v}"),
                    message: format!(
                        "{path} takes a whole number (a count or an index); {v} is not one"
                    ),
                })
            }
        }
    }
}

/// The integration options of a point: `options`, with the `[simulation]` fields the point
/// varies (`simulation.duration`, `sample_rate`, `rtol`, `atol`) taken from the point's model.
/// A varied `simulation.duration` also runs the point for its whole duration
/// (`stop_at_collision_end = false`), as `--duration` does.
pub fn point_options(options: &Options, quantities: &[&Quantity], model: &Model) -> Options {
    let sim = &model.spec.simulation;
    let mut o = *options;
    for q in quantities {
        let Quantity::Field(p) = q else { continue };
        match p.as_str() {
            "simulation.duration" => {
                o.duration = sim.duration;
                o.stop_at_collision_end = false;
            }
            "simulation.sample_rate" => o.sample_rate = Some(sim.sample_rate),
            "simulation.rtol" => o.rtol = sim.rtol,
            "simulation.atol" => o.atol = sim.atol,
            _ => {}
        }
    }
    o
}

/// Builds the model of one point: `base` with `quantities = values` resolved in the order of
/// the module docs. The structure's modes are reused unless the fields change the structural
/// part of the model ([`crate::model::StructureKey`]). Field values are written as TOML
/// literals of the field's kind ([`field_literal`]); the point's settings are checked as a
/// model file's are.
pub fn point_model(
    base: &Model,
    quantities: &[&Quantity],
    values: &[f64],
    bed_mass_kg: Option<f64>,
) -> Result<PointModel> {
    point_model_cached(base, quantities, values, bed_mass_kg, None)
}

/// [`point_model`] keeping the structures it builds in `cache` (a study's points share them).
pub fn point_model_cached(
    base: &Model,
    quantities: &[&Quantity],
    values: &[f64],
    bed_mass_kg: Option<f64>,
    cache: Option<&StructureCache>,
) -> Result<PointModel> {
    point_model_compiled(base, None, quantities, values, bed_mass_kg, cache)
}

/// The field paths among `quantities`, in order.
fn field_paths<'a>(quantities: &[&'a Quantity]) -> Vec<&'a str> {
    quantities
        .iter()
        .filter_map(|q| match q {
            Quantity::Field(p) => Some(p.as_str()),
            _ => None,
        })
        .collect()
}

/// The model of `base` with the field quantities set by their typed setters (`compiled`, when
/// it compiles the same paths, else compiled now; [`crate::model::setter`]); `None` when a
/// field has no typed setter, a value does not fit its field or a check fails (the TOML route
/// then gives the model or the error).
fn typed_fields_model(
    base: &Model,
    compiled: Option<&CompiledFields>,
    quantities: &[&Quantity],
    values: &[f64],
    cache: Option<&StructureCache>,
) -> Option<Model> {
    let paths = field_paths(quantities);
    let own;
    let fields = match compiled {
        Some(c)
            if c.paths()
                .iter()
                .map(String::as_str)
                .eq(paths.iter().copied()) =>
        {
            c
        }
        _ => {
            own = base.compile_fields(&paths);
            &own
        }
    };
    let mut typed = Vec::with_capacity(paths.len());
    for (q, &v) in quantities.iter().zip(values) {
        if !matches!(q, Quantity::Field(_)) {
            continue;
        }
        typed.push(match fields.kind(typed.len())? {
            SetterKind::Real => FieldValue::Real(v),
            // As field_literal: every integer up to 2^53 is an exact f64.
            SetterKind::Whole if v.fract() == 0.0 && v.abs() <= 9_007_199_254_740_992.0 => {
                FieldValue::Integer(v as i64)
            }
            _ => return None,
        });
    }
    base.with_values_typed(fields, &typed, cache)
}

/// [`point_model_cached`] with the field paths compiled once for the study (`compiled`;
/// `None`: compiled for this point).
pub(crate) fn point_model_compiled(
    base: &Model,
    compiled: Option<&CompiledFields>,
    quantities: &[&Quantity],
    values: &[f64],
    bed_mass_kg: Option<f64>,
    cache: Option<&StructureCache>,
) -> Result<PointModel> {
    // 1. Field paths: typed setters, else the TOML route (which gives the model or the error).
    let has_fields = quantities.iter().any(|q| matches!(q, Quantity::Field(_)));
    let typed = has_fields
        .then(|| typed_fields_model(base, compiled, quantities, values, cache))
        .flatten();
    let mut model;
    if let Some(m) = typed {
        model = m;
    } else if !has_fields {
        model = base.clone();
    } else {
        let mut table = spec_table(base)?;
        let mut fields: Vec<String> = Vec::new();
        for (q, v) in quantities.iter().zip(values) {
            if let Quantity::Field(p) = q {
                let kind = kind_in(&table, p, "--vary")?;
                fields.push(format!("{p}={}", field_literal(p, *v, kind, "--vary")?));
            }
        }
        let mut source = base.source.clone();
        for f in &fields {
            let applied = crate::model::source::apply_override(&mut table, f)?;
            source.overrides.push(applied);
        }
        let spec = crate::model::strict::deserialize(toml::Value::Table(table)).map_err(
            |(e, track)| Error::Input {
                location: fields
                    .iter()
                    .map(|f| format!("--vary {f}"))
                    .collect::<Vec<_>>()
                    .join(" "),
                message: crate::model::strict::message(e.message(), &track),
            },
        )?;
        model = base.with_spec(spec, source, cache)?;
    }
    let get = |q: Quantity| quantities.iter().position(|x| **x == q).map(|i| values[i]);
    // Ratios set contact stiffnesses and the damper's mass, which enter the structure's key
    // only through the contact frequency.
    let ratios = quantities.iter().any(|q| !matches!(q, Quantity::Field(_)));
    let base_key = || compiled.map_or_else(|| base.structure_key(), |c| c.base_key());
    let key_before = (ratios && uses_contact_omega(&model.spec.structure)).then(|| {
        if has_fields {
            model.structure_key()
        } else {
            base_key()
        }
    });
    let w_ref = model.reference_omega();
    // Only md/mb needs m_b (derived from the point's model: building a general model's mesh).
    let m_b = if quantities.contains(&&Quantity::MdOverMb) {
        bed_mass_kg.or_else(|| model.bed_mass())
    } else {
        None
    };
    let spec = &mut model.spec;
    let m_s = spec.slider.mass;
    // 2. w_s.
    if let Some(r) = get(Quantity::WsOverWref) {
        let w_ref = w_ref.ok_or_else(|| Error::invalid("vary", "ws/w_ref needs w_ref"))?;
        let w_s = r * w_ref;
        spec.contact.slider_bed.stiffness = m_s * w_s * w_s;
    }
    let k_s = spec.contact.slider_bed.stiffness;
    // 3.-5. w_d and m_d.
    let wd_ratio = get(Quantity::WdOverWs).map(|r| (r, true));
    let wd_ratio = wd_ratio.or(get(Quantity::WdOverWref).map(|r| (r, false)));
    let md_ratio = get(Quantity::MdOverMb);
    if wd_ratio.is_some() || md_ratio.is_some() {
        let (Some(d), Some(c)) = (spec.damper.as_mut(), spec.contact.bed_damper.as_mut()) else {
            return Err(Error::invalid(
                "vary",
                "wd/ws, wd/w_ref and md/mb need a [damper] and [contact.bed_damper]",
            ));
        };
        let w_d = match wd_ratio {
            Some((r, true)) => r * (k_s / m_s).sqrt(),
            Some((r, false)) => {
                r * w_ref.ok_or_else(|| Error::invalid("vary", "wd/w_ref needs w_ref"))?
            }
            None => (c.stiffness / d.mass).sqrt(),
        };
        if let Some(r) = md_ratio {
            let m_b = m_b.ok_or_else(|| {
                Error::invalid("vary", "md/mb needs the bed mass m_b: give --bed-mass KG")
            })?;
            d.mass = r * m_b;
        }
        c.stiffness = d.mass * w_d * w_d;
    }
    // A contact frequency changed by a ratio can change the structure's reduction (a lumped
    // model's rigid springs, an FE `select = "auto"` cutoff): then the point gets its own.
    if let Some(before) = key_before {
        let key = model.structure_key();
        if key != before {
            model.structure =
                base.structure_of_key(key, base_key(), &model.spec, &model.source, cache)?;
        }
    }
    let derived = vec![
        model.spec.contact.slider_bed.stiffness,
        model
            .spec
            .contact
            .bed_damper
            .as_ref()
            .map_or(f64::NAN, |c| c.stiffness),
        model.spec.damper.as_ref().map_or(f64::NAN, |d| d.mass),
        model.spec.slider.mass,
    ];
    Ok(PointModel { model, derived })
}

/// Simulates one point (`quantities = values`) of the model as specified; never fails: errors
/// are recorded.
pub fn evaluate(
    base: &Model,
    quantities: &[&Quantity],
    values: &[f64],
    bed_mass_kg: Option<f64>,
    options: &Options,
    index: usize,
) -> PointResult {
    evaluate_cached(base, quantities, values, bed_mass_kg, options, index, None)
}

/// [`evaluate`] with the point's structure from (or kept in) `cache`.
pub fn evaluate_cached(
    base: &Model,
    quantities: &[&Quantity],
    values: &[f64],
    bed_mass_kg: Option<f64>,
    options: &Options,
    index: usize,
    cache: Option<&StructureCache>,
) -> PointResult {
    evaluate_cases(
        base,
        quantities,
        values,
        bed_mass_kg,
        options,
        index,
        &[Case::AsSpecified],
        cache,
    )
}

/// Simulates one point once per case (the point's model is built once, its structure from or
/// kept in `cache`); the metrics are the [`METRICS`] of each case in turn. A case that fails
/// gets NaN metrics and its error (prefixed with the case's name when there are several cases)
/// in [`PointResult::error`].
#[allow(clippy::too_many_arguments)]
pub fn evaluate_cases(
    base: &Model,
    quantities: &[&Quantity],
    values: &[f64],
    bed_mass_kg: Option<f64>,
    options: &Options,
    index: usize,
    cases: &[Case],
    cache: Option<&StructureCache>,
) -> PointResult {
    let pm = point_model_cached(base, quantities, values, bed_mass_kg, cache);
    evaluate_model(pm, quantities, values, options, index, cases)
}

/// [`evaluate_cases`] of the point's model `pm` (or the error building it).
fn evaluate_model(
    pm: Result<PointModel>,
    quantities: &[&Quantity],
    values: &[f64],
    options: &Options,
    index: usize,
    cases: &[Case],
) -> PointResult {
    let nan_metrics = || vec![Some(f64::NAN); METRICS.len() * cases.len()];
    let pm = match pm {
        Ok(pm) => pm,
        Err(e) => {
            return PointResult {
                index,
                values: values.to_vec(),
                derived: vec![f64::NAN; DERIVED.len()],
                metrics: nan_metrics(),
                error: Some(e.to_string()),
            }
        }
    };
    let options = point_options(options, quantities, &pm.model);
    let mut metrics = Vec::with_capacity(METRICS.len() * cases.len());
    let mut errors: Vec<String> = Vec::new();
    for &case in cases {
        let run = pm
            .model
            .impact_system(case)
            .and_then(|sys| simulate(&sys, &options, false));
        match run {
            Ok(run) => {
                metrics.extend(summary_metrics(&run.summary));
                let [k_s, k_d, m_d, m_s] =
                    [pm.derived[0], pm.derived[1], pm.derived[2], pm.derived[3]];
                let w_s = (k_s / m_s).sqrt();
                let w_d = (k_d / m_d).sqrt();
                metrics.push(Some(w_d / w_s));
                metrics.push(Some(
                    pm.model.reference_omega().map_or(f64::NAN, |w| w_s / w),
                ));
            }
            Err(e) => {
                metrics.extend(std::iter::repeat_n(Some(f64::NAN), METRICS.len()));
                errors.push(if cases.len() > 1 {
                    format!("case {}: {e}", case_name(case))
                } else {
                    e.to_string()
                });
            }
        }
    }
    PointResult {
        index,
        values: values.to_vec(),
        derived: pm.derived,
        metrics,
        error: (!errors.is_empty()).then(|| errors.join("; ")),
    }
}
