//! General machine files: `[[impactor]]`, `[[damper]]` and `[[contact]]` arrays around any
//! structure, read into an [`impact::network::Network`](crate::impact::network::Network).
//!
//! A model file is a **general machine** when it has an `[[impactor]]` array, or writes
//! `damper` or `contact` as arrays of tables (`[[damper]]`, `[[contact]]`). The paper's
//! sections (`[slider]`, `[points]`, a `[damper]` table, `[contact.slider_bed]`,
//! `[contact.bed_damper]`, `[added_mass]`, `[measurement]`) are the shorthand of the paper's
//! machine and are not mixed with the arrays: a file is one form or the other
//! ([`is_general`]). The paper's form runs on the paper's engine, unchanged.
//!
//! Fields (SI units; `docs/reference/model-file.md`, "General machines"):
//!
//! | section | fields |
//! |---|---|
//! | `[[impactor]]` | `name`, `mass` (kg), `velocity` (m/s at t = 0, +z towards what it strikes; default 0), `force` (N, constant from t = 0, +z; default 0) |
//! | `[[damper]]` | `name`, `mass` (kg), `stiffness` (N/m), `damping` (N·s/m, default 0), `dashpot` (`one-way`/`two-way`), `point` (the structure point it touches), `anchor` (a structure point or `ground`, default `ground`) |
//! | `[[contact]]` | `name`, `between = [A, B]` (structure points, impactors, dampers or `ground`; A strikes B moving along +z), `gap` (m; > 0 open, < 0 preloaded; default 0), `law` (`linear`: `stiffness`, `damping` or `restitution`, `release` (`force`/`overlap`); `rigid`: `restitution` in [0, 1] only, no preload) |
//!
//! `restitution = e` on a linear contact sets `C = 2ζ(e)√(K m*)` with `ζ(e)` of its release
//! rule ([`crate::impact::restitution::zeta_of_e`]) and the reduced mass of the two ends,
//! `1/m* = aᵀM⁻¹a` (`a` the contact's relative vector: `1/m_body` for a body,
//! `Σ_i ψ_i(P)²` for a structure point, summed over both ends; the ground adds nothing).
//!
//! `law = "rigid"` is the instantaneous impact with Newton's restitution `e` ∈ [0, 1]
//! ([`crate::impact::ContactLaw::Rigid`], [`crate::integrate::network`], "Rigid contacts"): it
//! takes `restitution` (required) and no `stiffness`, `damping`, `exponent` or `alpha` (a rigid
//! contact has none), and no preload (`gap` < 0 would overlap it); `release` does not apply.
//!
//! Every damper must touch its `point` through a contact `between = [point, damper]` (in
//! either order). Names are unique across impactors, dampers and structure points.

use serde::{Deserialize, Serialize};

use super::fem::{self, ReductionContext};
use super::spec::{
    ContactSpec, DashpotKindSpec, LawSpec, MethodSpec, ProductionSpec, ReleaseSpec, SimulationSpec,
    StructureSpec,
};
use super::{source, strict, Source};
use crate::impact::network::{Body, End, Link, Network, Suspension};
use crate::impact::{restitution, Contact, ContactLaw, DashpotKind, Release};
use crate::integrate::{network as engine, Options};
use crate::modal::ModalModel;
use crate::{Error, Result};

/// A general machine file.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NetworkSpec {
    #[serde(default)]
    pub name: Option<String>,
    pub structure: StructureSpec,
    #[serde(default)]
    pub impactor: Vec<ImpactorSpec>,
    #[serde(default)]
    pub damper: Vec<DamperEntrySpec>,
    #[serde(default)]
    pub contact: Vec<ContactEntrySpec>,
    #[serde(default)]
    pub simulation: SimulationSpec,
    /// `[production]`: the stroke rate at which `meid blows`, `optimize --place` and `sweep`
    /// judge the machine on its steady blow ([`crate::analysis::network_blows`]); a command's
    /// `--rate-bpm` overrides it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub production: Option<ProductionSpec>,
}

/// `[[impactor]]`: a rigid body that strikes.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImpactorSpec {
    pub name: String,
    /// kg.
    pub mass: f64,
    /// m/s at t = 0, positive along +z.
    #[serde(default)]
    pub velocity: f64,
    /// N, constant from t = 0, positive along +z.
    #[serde(default)]
    pub force: f64,
}

/// `[[damper]]`: a mass on a spring and dashpot touching a structure point.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DamperEntrySpec {
    pub name: String,
    /// kg.
    pub mass: f64,
    /// N/m.
    pub stiffness: f64,
    /// N·s/m.
    #[serde(default)]
    pub damping: f64,
    #[serde(default)]
    pub dashpot: DashpotKindSpec,
    /// The structure point it touches (through a `[[contact]]`).
    pub point: String,
    /// A structure point or "ground" (default).
    #[serde(default = "ground")]
    pub anchor: String,
}

fn ground() -> String {
    "ground".into()
}

/// `[[contact]]`: a unilateral contact between two ends.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ContactEntrySpec {
    pub name: String,
    /// `[A, B]`: A strikes B moving along +z.
    pub between: Vec<String>,
    /// m: > 0 open at t = 0, < 0 preloaded.
    #[serde(default)]
    pub gap: f64,
    #[serde(default)]
    pub law: LawSpec,
    /// N/m; required by the linear law, refused by the rigid one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    #[serde(default)]
    pub damping: Option<f64>,
    #[serde(default)]
    pub exponent: Option<f64>,
    #[serde(default)]
    pub alpha: Option<f64>,
    #[serde(default)]
    pub restitution: Option<f64>,
    #[serde(default)]
    pub release: ReleaseSpec,
}

/// The paper's sections a general machine file may not have, and what replaces each.
const PAPER_ONLY: [(&str, &str); 4] = [
    ("slider", "an [[impactor]]"),
    (
        "points",
        "the names of structure points in [[contact]] between, [[damper]] point and anchor",
    ),
    ("added_mass", "a mass in the structure"),
    (
        "measurement",
        "nothing yet (the general machine reports every named point)",
    ),
];

/// True when the model table is a general machine (module documentation).
pub fn is_general(table: &toml::Table) -> bool {
    table.contains_key("impactor")
        || matches!(table.get("damper"), Some(toml::Value::Array(_)))
        || matches!(table.get("contact"), Some(toml::Value::Array(_)))
}

/// True when `path` is a readable TOML file of a general machine ([`is_general`]); false for
/// anything else (whose reader reports unreadable files and syntax errors).
pub fn is_general_file(path: &std::path::Path) -> bool {
    crate::input::read_text(path)
        .ok()
        .and_then(|t| toml::from_str::<toml::Table>(&t).ok())
        .is_some_and(|t| is_general(&t))
}

/// A validated general machine: the spec, the structure as modes, the network.
#[derive(Debug, Clone)]
pub struct NetworkModel {
    pub spec: NetworkSpec,
    pub structure: ModalModel,
    pub source: Source,
    pub network: Network,
    /// What the model set for the user (restitution turned into damping).
    pub notes: Vec<String>,
}

impl NetworkModel {
    /// Reads a general machine file, applying `--set PATH=VALUE` overrides in order.
    pub fn from_file(path: &std::path::Path, overrides: &[String]) -> Result<Self> {
        let text = crate::input::read_text(path)?;
        Self::from_text(&path.display().to_string(), text, overrides)
    }

    /// Parses and validates a general machine's text; `name` is used in errors. An override's
    /// path may name an array entry by its name (`damper.damper1.mass`,
    /// [`super::network_paths`]).
    pub fn from_text(name: &str, text: String, overrides: &[String]) -> Result<Self> {
        let (spec, src) = read_spec(name, text, overrides)?;
        Self::of_spec(spec, src, |spec, src, ctx| {
            super::build_structure_of(&spec.structure, None, src, ctx)
        })
    }

    /// The model of a read `spec` (values from `src`), its structure from `structure` (called
    /// with the spec, source and reduction context): checked as a model file is.
    pub(crate) fn of_spec(
        spec: NetworkSpec,
        src: Source,
        structure: impl FnOnce(&NetworkSpec, &Source, &ReductionContext) -> Result<ModalModel>,
    ) -> Result<Self> {
        check_fields(&spec, &src)?;
        let ctx = context(&spec);
        let structure = structure(&spec, &src, &ctx)?;
        let (network, notes) = assemble(&spec, &structure, &src)?;
        // An impossible preload is an input error, found before any run.
        engine::initial_state(&network).map_err(|e| locate(e, &spec, &src))?;
        Ok(Self {
            spec,
            structure,
            source: src,
            network,
            notes,
        })
    }

    /// The run's settings (`[simulation]`): the method (exact, or dopri5 with its `rtol`,
    /// `atol`), the duration and the event cap.
    pub fn options(&self) -> Result<Options> {
        let s = &self.spec.simulation;
        Ok(Options {
            method: match s.method {
                MethodSpec::Exact => crate::integrate::Method::Exact,
                MethodSpec::Dopri5 => crate::integrate::Method::Dopri5,
            },
            rtol: s.rtol,
            atol: s.atol,
            duration: s.duration,
            sample_rate: None,
            max_events: s.max_events as usize,
            ..Options::default()
        })
    }

    /// Runs the machine (`solve` with the model's options), with errors that name a model
    /// field located in the file.
    pub fn solve(&self, opts: &Options) -> Result<engine::NetSolution> {
        engine::solve(&self.network, opts).map_err(|e| locate(e, &self.spec, &self.source))
    }
}

/// The spec of a general machine's text with `overrides` applied in order (named array
/// paths translated, [`super::network_paths::translate`]), and its source.
pub(crate) fn read_spec(
    name: &str,
    text: String,
    overrides: &[String],
) -> Result<(NetworkSpec, Source)> {
    let mut table: toml::Table =
        toml::from_str(&text).map_err(|e| source::toml_error(name, &text, &e))?;
    let mut src = Source {
        name: name.to_string(),
        text,
        overrides: Vec::new(),
    };
    for o in overrides {
        for t in super::network_paths::translate(&table, o)? {
            let applied = source::apply_override(&mut table, &t)?;
            src.overrides.push(applied);
        }
    }
    for (key, instead) in PAPER_ONLY {
        if table.contains_key(key) {
            return Err(src.error(
                key,
                format!(
                    "[{key}] is the paper machine's shorthand and cannot be mixed with [[impactor]], [[damper]] or [[contact]] arrays: use {instead}"
                ),
            ));
        }
    }
    if let Some(toml::Value::Table(_)) = table.get("damper") {
        return Err(src.error(
            "damper",
            "a [damper] table is the paper machine's shorthand; in a general machine write [[damper]] (an array of tables, with name, point and anchor)",
        ));
    }
    let spec: NetworkSpec = if src.overrides.is_empty() {
        let de = toml::de::Deserializer::parse(&src.text)
            .map_err(|e| source::toml_error(name, &src.text, &e))?;
        strict::deserialize(de).map_err(|(e, track)| {
            source::toml_error_message(name, &src.text, &e, strict::message(e.message(), &track))
        })?
    } else {
        strict::deserialize(toml::Value::Table(table.clone())).map_err(|(e, track)| {
            Error::Input {
                location: src
                    .overrides
                    .iter()
                    .map(|(p, v)| format!("--set {p}={v}"))
                    .collect::<Vec<_>>()
                    .join(" "),
                message: strict::message(e.message(), &track),
            }
        })?
    };
    super::check_table_magnitudes(&table, &src)?;
    Ok((spec, src))
}

/// An API error naming `<entity name>.<field>` turned into one located at the entity's model
/// path (`contact[2].gap`).
fn locate(e: Error, spec: &NetworkSpec, src: &Source) -> Error {
    let Error::InvalidValue { field, message } = e else {
        return e;
    };
    let (entity, rest) = field.split_once('.').unwrap_or((&field, ""));
    let path = spec
        .contact
        .iter()
        .position(|c| c.name == entity)
        .map(|i| format!("contact[{i}]"))
        .or_else(|| {
            spec.impactor
                .iter()
                .position(|c| c.name == entity)
                .map(|i| format!("impactor[{i}]"))
        })
        .or_else(|| {
            spec.damper
                .iter()
                .position(|c| c.name == entity)
                .map(|i| format!("damper[{i}]"))
        });
    match path {
        Some(p) => {
            let full = if rest.is_empty() {
                p
            } else {
                format!("{p}.{rest}")
            };
            src.error(&full, format!("{full} ({entity}): {message}"))
        }
        None => src.error(&field, format!("{field}: {message}")),
    }
}

/// The checks that need no structure: names, numbers, ranges.
fn check_fields(spec: &NetworkSpec, src: &Source) -> Result<()> {
    if let Some(p) = &spec.production {
        if !(p.rate_bpm.is_finite() && p.rate_bpm > 0.0) {
            return Err(field_error(
                src,
                "production.rate_bpm".into(),
                format!(
                    "must be a finite number > 0 blows per minute (got {})",
                    crate::num(p.rate_bpm)
                ),
            ));
        }
    }
    if spec.impactor.is_empty() {
        return Err(field_error(
            src,
            "impactor".into(),
            "a general machine needs at least one [[impactor]] (name, mass, velocity)".into(),
        ));
    }
    check_bodies(spec, src)?;
    let mut contact_names: Vec<&str> = Vec::new();
    for (i, c) in spec.contact.iter().enumerate() {
        check_contact_entry(&format!("contact[{i}]"), c, spec.simulation.method)
            .map_err(|(path, msg)| field_error(src, path, msg))?;
    }
    for (i, c) in spec.contact.iter().enumerate() {
        if contact_names.contains(&c.name.as_str()) {
            return Err(field_error(
                src,
                format!("contact[{i}].name"),
                format!("'{}' names two contacts: names must be unique", c.name),
            ));
        }
        contact_names.push(&c.name);
    }
    Ok(())
}

/// The error of model path `path`, located in the file: `path: msg`.
fn field_error(src: &Source, path: String, msg: String) -> Error {
    src.error(&path, format!("{path}: {msg}"))
}

/// The bodies' names (usable, unique), masses, the impactors' velocities and forces, the
/// dampers' springs, dashpots and anchors.
fn check_bodies(spec: &NetworkSpec, src: &Source) -> Result<()> {
    let fail = |path: String, msg: String| Err(field_error(src, path, msg));
    let mut names: Vec<(&str, String)> = Vec::new();
    let entries = spec
        .impactor
        .iter()
        .enumerate()
        .map(|(i, b)| (format!("impactor[{i}]"), &b.name, b.mass))
        .chain(
            spec.damper
                .iter()
                .enumerate()
                .map(|(i, d)| (format!("damper[{i}]"), &d.name, d.mass)),
        );
    for (path, name, mass) in entries {
        if name.is_empty() || name == "ground" {
            return fail(
                format!("{path}.name"),
                format!("'{name}' is not a usable name (empty or 'ground')"),
            );
        }
        if let Some((_, other)) = names.iter().find(|(n, _)| *n == name) {
            return fail(
                format!("{path}.name"),
                format!("'{name}' is also the name of {other}: names must be unique"),
            );
        }
        names.push((name, path.clone()));
        if !(mass.is_finite() && mass > 0.0) {
            return fail(
                format!("{path}.mass"),
                format!("must be a finite number > 0 kg (got {})", crate::num(mass)),
            );
        }
    }
    for (i, b) in spec.impactor.iter().enumerate() {
        for (what, v, unit) in [("velocity", b.velocity, "m/s"), ("force", b.force, "N")] {
            if !v.is_finite() {
                return fail(
                    format!("impactor[{i}].{what}"),
                    format!("must be a finite number of {unit} (got {})", crate::num(v)),
                );
            }
        }
    }
    for (i, d) in spec.damper.iter().enumerate() {
        for (what, v, unit) in [
            ("stiffness", d.stiffness, "N/m"),
            ("damping", d.damping, "N·s/m"),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return fail(
                    format!("damper[{i}].{what}"),
                    format!("must be a finite number ≥ 0 {unit} (got {})", crate::num(v)),
                );
            }
        }
        if d.anchor == d.name {
            return fail(
                format!("damper[{i}].anchor"),
                format!(
                    "damper '{}' is anchored to itself: give a structure point or \"ground\"",
                    d.name
                ),
            );
        }
    }
    Ok(())
}

/// One `[[contact]]` entry at model path `p` (`contact[i]`): two different ends, a finite
/// gap, a positive stiffness, the linear law, damping ≥ 0 or a restitution in (0, 1] (not
/// both). The error is `(field path, message)`.
fn check_contact_entry(
    p: &str,
    c: &ContactEntrySpec,
    method: MethodSpec,
) -> std::result::Result<(), (String, String)> {
    if c.between.len() != 2 {
        return Err((
            format!("{p}.between"),
            format!(
                "needs two ends [A, B] (A strikes B moving along +z), got {}",
                c.between.len()
            ),
        ));
    }
    if c.between[0] == c.between[1] {
        return Err((
            format!("{p}.between"),
            format!(
                "'{}' cannot touch itself: a contact joins two different ends",
                c.between[0]
            ),
        ));
    }
    if !c.gap.is_finite() {
        return Err((
            format!("{p}.gap"),
            format!(
                "must be a finite number of metres (> 0 open, < 0 preloaded, 0 touching; got {})",
                crate::num(c.gap)
            ),
        ));
    }
    if c.law == LawSpec::Rigid {
        if method == MethodSpec::Dopri5 {
            return Err((format!("{p}.law"), "law = \"rigid\" runs with simulation.method = \"exact\" only (its impulses and resting constraint are the exact engine's); with dopri5 give the contact law = \"linear\" (a stiffness and a restitution), \"hertz\" or \"hunt-crossley\"".into()));
        }
        return check_rigid_entry(p, c);
    }
    let stiffness = c.stiffness.ok_or_else(|| {
        (
            format!("{p}.stiffness"),
            "missing: the linear law needs a contact stiffness K (N/m); or write law = \"rigid\" with a restitution for instantaneous impacts".to_string(),
        )
    })?;
    if !(stiffness.is_finite() && stiffness > 0.0) {
        return Err((
            format!("{p}.stiffness"),
            format!(
                "must be a finite number > 0 N/m (got {})",
                crate::num(stiffness)
            ),
        ));
    }
    if c.law != LawSpec::Linear {
        return check_nonlinear_entry(p, c, method);
    }
    if c.exponent.is_some() || c.alpha.is_some() {
        return Err((format!("{p}.alpha"), "exponent and alpha belong to law = \"hunt-crossley\"; the linear law takes damping or restitution".into()));
    }
    check_damping_or_restitution(p, ("damping", c.damping, "N·s/m"), c.restitution)
}

/// A contact's damping coefficient `(name, value, unit)` (finite, ≥ 0) or its restitution
/// (in (0, 1]), not both.
fn check_damping_or_restitution(
    p: &str,
    (name, coefficient, unit): (&str, Option<f64>, &str),
    restitution: Option<f64>,
) -> std::result::Result<(), (String, String)> {
    if let Some(d) = coefficient {
        if !(d.is_finite() && d >= 0.0) {
            return Err((
                format!("{p}.{name}"),
                format!("must be a finite number ≥ 0 {unit} (got {})", crate::num(d)),
            ));
        }
    }
    if let Some(e) = restitution {
        if !(e > 0.0 && e <= 1.0) {
            return Err((
                format!("{p}.restitution"),
                format!(
                    "the coefficient of restitution must be in (0, 1] (1: elastic; got {})",
                    crate::num(e)
                ),
            ));
        }
        if let Some(d) = coefficient {
            return Err((
                format!("{p}.restitution"),
                format!(
                    "given together with {p}.{name} = {} {unit}; give one of them (restitution sets {name})",
                    crate::num(d)
                ),
            ));
        }
    }
    Ok(())
}

/// A `law = "hertz"` or `"hunt-crossley"` entry at model path `p` (its stiffness checked):
/// dopri5 only; no damping; Hertz takes no restitution, exponent or alpha; Hunt-Crossley an
/// exponent > 0, an alpha ≥ 0 or a restitution in (0, 1] (not both).
fn check_nonlinear_entry(
    p: &str,
    c: &ContactEntrySpec,
    method: MethodSpec,
) -> std::result::Result<(), (String, String)> {
    let name = if c.law == LawSpec::Hertz {
        "hertz"
    } else {
        "hunt-crossley"
    };
    if method != MethodSpec::Dopri5 {
        return Err((
            format!("{p}.law"),
            format!("law = \"{name}\" needs simulation.method = \"dopri5\" (the exact method takes piecewise-linear contacts: law = \"linear\" or \"rigid\"); add [simulation] method = \"dopri5\""),
        ));
    }
    if let Some(d) = c.damping.filter(|d| *d != 0.0) {
        return Err((
            format!("{p}.damping"),
            format!("damping = {} is given with law = \"{name}\": only the linear law takes damping; hunt-crossley takes alpha (s/m) or restitution", crate::num(d)),
        ));
    }
    if c.law == LawSpec::Hertz {
        for (what, v) in [
            ("exponent", c.exponent),
            ("alpha", c.alpha),
            ("restitution", c.restitution),
        ] {
            if let Some(v) = v {
                return Err((
                    format!("{p}.{what}"),
                    format!("{what} = {} is given with law = \"hertz\" (f = K δ^1.5, undamped): use law = \"hunt-crossley\" (f = K δ^n (1 + 3/2 α δ̇)) for exponent, alpha or restitution", crate::num(v)),
                ));
            }
        }
        return Ok(());
    }
    if let Some(n) = c.exponent {
        if !(n.is_finite() && n > 0.0) {
            return Err((
                format!("{p}.exponent"),
                format!(
                    "must be a finite number > 0 (1.5 for Hertzian geometry; got {})",
                    crate::num(n)
                ),
            ));
        }
    }
    check_damping_or_restitution(p, ("alpha", c.alpha, "s/m"), c.restitution)
}

/// A `law = "rigid"` entry at model path `p`: a restitution in [0, 1], no stiffness, damping,
/// exponent or alpha, no preload.
fn check_rigid_entry(p: &str, c: &ContactEntrySpec) -> std::result::Result<(), (String, String)> {
    for (what, v) in [
        ("stiffness", c.stiffness),
        ("damping", c.damping),
        ("exponent", c.exponent),
        ("alpha", c.alpha),
    ] {
        if let Some(v) = v {
            return Err((
                format!("{p}.{what}"),
                format!(
                    "{what} = {} is given with law = \"rigid\": a rigid contact has no stiffness or damping (its impacts are instantaneous, their loss set by restitution = e alone); remove {what}, or use law = \"linear\" for a compliant contact",
                    crate::num(v)
                ),
            ));
        }
    }
    let Some(e) = c.restitution else {
        return Err((
            format!("{p}.restitution"),
            "missing: law = \"rigid\" needs restitution = e, the coefficient of restitution in [0, 1] (0: plastic, 1: elastic; IS 2974-2 uses 0.5 for a hammer's tup on its anvil)".into(),
        ));
    };
    if !(0.0..=1.0).contains(&e) {
        return Err((
            format!("{p}.restitution"),
            format!(
                "the rigid law's coefficient of restitution must be in [0, 1] (0: plastic, 1: elastic; got {})",
                crate::num(e)
            ),
        ));
    }
    if c.gap < 0.0 {
        return Err((
            format!("{p}.gap"),
            format!(
                "a rigid contact cannot be preloaded (gap = {} m would overlap it): give a gap ≥ 0, or use law = \"linear\" for a preload",
                crate::num(c.gap)
            ),
        ));
    }
    Ok(())
}

/// The reduction context of the structure: the named points the machine uses, and the fastest
/// contact frequency `√(K/m)` against a body.
pub(crate) fn context(spec: &NetworkSpec) -> ReductionContext {
    let masses: Vec<(&str, f64)> = spec
        .impactor
        .iter()
        .map(|b| (b.name.as_str(), b.mass))
        .chain(spec.damper.iter().map(|d| (d.name.as_str(), d.mass)))
        .collect();
    let v = spec
        .impactor
        .iter()
        .map(|b| b.velocity.abs())
        .fold(0.0, f64::max);
    let mut w: f64 = 0.0;
    let mut role_points: Vec<(String, Vec<String>)> = Vec::new();
    let mut add = |name: &str, role: &str| {
        if masses.iter().any(|(n, _)| *n == name) || name == "ground" {
            return;
        }
        match role_points.iter_mut().find(|(n, _)| n == name) {
            Some((_, r)) => r.push(role.into()),
            None => role_points.push((name.into(), vec![role.into()])),
        }
    };
    for c in &spec.contact {
        for e in &c.between {
            add(e, "contact");
            if let Some((_, m)) = masses.iter().find(|(n, _)| n == e) {
                let cs = ContactSpec {
                    law: c.law,
                    stiffness: c.stiffness.unwrap_or(0.0),
                    damping: c.damping,
                    exponent: c.exponent,
                    alpha: c.alpha,
                    restitution: c.restitution,
                    release: c.release,
                };
                w = w.max(fem::contact_omega(&cs, *m, 2.0 * v).unwrap_or(0.0));
            }
        }
    }
    for d in &spec.damper {
        add(&d.point, "damper_point");
        add(&d.anchor, "damper_anchor");
    }
    ReductionContext {
        contact_omega_rad_per_s: w,
        role_points,
    }
}

/// The end a name refers to, or an error with the valid names (did-you-mean).
fn end_of(
    name: &str,
    spec: &NetworkSpec,
    structure: &ModalModel,
    path: &str,
    src: &Source,
) -> Result<End> {
    if name == "ground" {
        return Ok(End::Ground);
    }
    if let Some(i) = spec.impactor.iter().position(|b| b.name == name) {
        return Ok(End::Body(i));
    }
    if let Some(i) = spec.damper.iter().position(|d| d.name == name) {
        return Ok(End::Body(spec.impactor.len() + i));
    }
    if structure.points.contains_key(name) {
        return Ok(End::Point(name.into()));
    }
    let known: Vec<&str> = structure
        .points
        .keys()
        .map(|k| k.as_str())
        .chain(spec.impactor.iter().map(|b| b.name.as_str()))
        .chain(spec.damper.iter().map(|d| d.name.as_str()))
        .chain(["ground"])
        .collect();
    let hint = known
        .iter()
        .map(|c| (strsim::jaro_winkler(name, c), *c))
        .filter(|(s, _)| *s > 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, c)| format!("; did you mean '{c}'?"))
        .unwrap_or_default();
    Err(src.error(
        path,
        format!(
            "{path}: unknown name '{name}'{hint} (valid: structure points {}, impactors, dampers, ground: {})",
            structure.points.keys().cloned().collect::<Vec<_>>().join(", "),
            known.join(", ")
        ),
    ))
}

/// The law of a checked Hertz or Hunt-Crossley entry at `path` with ends `ends`: with
/// `restitution = e`, Hunt-Crossley's `α = 2 x(e)/(3 v_in)` ([`restitution::x_of_e`]) at the
/// contact's closing speed at t = 0, `v_in = aᵀẋ(0)` (the impactors' velocities), as the
/// paper's form sizes it at the slider's velocity; a contact that does not close at t = 0 has
/// no approach velocity to size α from: refused (give alpha).
fn nonlinear_law(
    c: &ContactEntrySpec,
    path: &str,
    ends: [&End; 2],
    bodies: &[Body],
    src: &Source,
    notes: &mut Vec<String>,
) -> Result<ContactLaw> {
    let stiffness = c.stiffness.unwrap_or(0.0);
    if c.law == LawSpec::Hertz {
        return Ok(ContactLaw::Hertz { stiffness });
    }
    let alpha = match c.restitution {
        None => c.alpha.unwrap_or(0.0),
        Some(e) => {
            let speed = |end: &End| match end {
                End::Body(k) => bodies[*k].velocity,
                _ => 0.0,
            };
            let v_in = speed(ends[0]) - speed(ends[1]);
            let field = format!("{path}.restitution");
            if !(v_in.is_finite() && v_in > 0.0) {
                return Err(src.error(&field, format!("{field}: a hunt-crossley contact's restitution depends on the approach velocity, and this contact does not close at t = 0 (closing speed {} m/s from the impactors' velocities): give alpha (s/m), or use law = \"linear\", whose restitution does not depend on the approach velocity", crate::num(v_in))));
            }
            let x = restitution::x_of_e(e).map_err(|err| match err {
                Error::InvalidValue { message, .. } => {
                    src.error(&field, format!("{field}: {message}"))
                }
                other => other,
            })?;
            let alpha = 2.0 * x / (3.0 * v_in);
            notes.push(format!(
                "{path} ({}): restitution e = {} → alpha = {alpha:.5e} s/m (x = 3/2 α v_in = {x:.5} at the closing speed v_in = {} m/s at t = 0; at another approach velocity this α gives another e)",
                c.name,
                crate::num(e),
                crate::num(v_in)
            ));
            alpha
        }
    };
    Ok(ContactLaw::HuntCrossley {
        stiffness,
        exponent: c.exponent.unwrap_or(1.5),
        alpha,
    })
}

/// The network of a checked spec, and the notes of the contacts whose damping `restitution` set.
fn assemble(
    spec: &NetworkSpec,
    structure: &ModalModel,
    src: &Source,
) -> Result<(Network, Vec<String>)> {
    let mut bodies: Vec<Body> = spec
        .impactor
        .iter()
        .map(|b| Body {
            name: b.name.clone(),
            mass: b.mass,
            velocity: b.velocity,
            force: b.force,
        })
        .collect();
    let mut suspensions = Vec::new();
    for (i, d) in spec.damper.iter().enumerate() {
        let path = format!("damper[{i}]");
        let b = bodies.len();
        bodies.push(Body {
            name: d.name.clone(),
            mass: d.mass,
            velocity: 0.0,
            force: 0.0,
        });
        let point = end_of(&d.point, spec, structure, &format!("{path}.point"), src)?;
        if !matches!(point, End::Point(_)) {
            return Err(src.error(
                &format!("{path}.point"),
                format!(
                    "{path}.point: '{}' is not a structure point (a damper touches the structure)",
                    d.point
                ),
            ));
        }
        let touches = spec.contact.iter().any(|c| {
            c.between.len() == 2
                && ((c.between[0] == d.point && c.between[1] == d.name)
                    || (c.between[1] == d.point && c.between[0] == d.name))
        });
        if !touches {
            return Err(src.error(&format!("{path}.point"), format!("{path}.point: damper '{}' touches '{}', but no [[contact]] joins them: add one with between = [\"{}\", \"{}\"]", d.name, d.point, d.point, d.name)));
        }
        let anchor = end_of(&d.anchor, spec, structure, &format!("{path}.anchor"), src)?;
        if matches!(anchor, End::Body(_)) {
            return Err(src.error(&format!("{path}.anchor"), format!("{path}.anchor: '{}' is a body; a damper is anchored to a structure point or \"ground\"", d.anchor)));
        }
        suspensions.push(Suspension {
            name: d.name.clone(),
            body: b,
            stiffness: d.stiffness,
            damping: d.damping,
            dashpot: match d.dashpot {
                DashpotKindSpec::OneWay => DashpotKind::OneWay,
                DashpotKindSpec::TwoWay => DashpotKind::TwoWay,
            },
            anchor,
        });
    }
    let mut links = Vec::new();
    let mut notes = Vec::new();
    let masses: Vec<f64> = bodies.iter().map(|b| b.mass).collect();
    for (i, c) in spec.contact.iter().enumerate() {
        let path = format!("contact[{i}]");
        let a = end_of(
            &c.between[0],
            spec,
            structure,
            &format!("{path}.between"),
            src,
        )?;
        let b = end_of(
            &c.between[1],
            spec,
            structure,
            &format!("{path}.between"),
            src,
        )?;
        if a == End::Ground && b == End::Ground {
            return Err(src.error(
                &format!("{path}.between"),
                format!("{path}.between: a contact between the ground and itself"),
            ));
        }
        let release = match c.release {
            ReleaseSpec::Force => Release::Force,
            ReleaseSpec::Overlap => Release::Overlap,
        };
        if c.law == LawSpec::Rigid {
            links.push(Link {
                name: c.name.clone(),
                ends: [a, b],
                gap: c.gap,
                contact: Contact {
                    law: ContactLaw::Rigid {
                        restitution: c.restitution.unwrap_or(1.0),
                    },
                    release,
                },
            });
            continue;
        }
        let stiffness = c.stiffness.unwrap_or(0.0);
        if matches!(c.law, LawSpec::Hertz | LawSpec::HuntCrossley) {
            let law = nonlinear_law(c, &path, [&a, &b], &bodies, src, &mut notes)?;
            links.push(Link {
                name: c.name.clone(),
                ends: [a, b],
                gap: c.gap,
                contact: Contact { law, release },
            });
            continue;
        }
        let damping = match c.restitution {
            None => c.damping.unwrap_or(0.0),
            Some(e) => {
                let inv_m: f64 = [&a, &b]
                    .iter()
                    .map(|end| match end {
                        End::Body(k) => 1.0 / masses[*k],
                        End::Point(p) => structure.points[p].iter().map(|v| v * v).sum(),
                        End::Ground => 0.0,
                    })
                    .sum();
                let zeta = restitution::zeta_of_e(e, release).map_err(|e| locate(e, spec, src))?;
                let m_red = 1.0 / inv_m;
                let damping = 2.0 * zeta * (stiffness * m_red).sqrt();
                notes.push(format!(
                    "{path} ({}): restitution e = {} → damping C = {damping:.5e} N·s/m (ζ = {zeta:.5}, m* = {m_red:.5e} kg, 1/m* = aᵀM⁻¹a over its two ends)",
                    c.name,
                    crate::num(e)
                ));
                damping
            }
        };
        links.push(Link {
            name: c.name.clone(),
            ends: [a, b],
            gap: c.gap,
            contact: Contact {
                law: ContactLaw::Linear { stiffness, damping },
                release,
            },
        });
    }
    let net =
        Network::new(structure, bodies, suspensions, links).map_err(|e| locate(e, spec, src))?;
    Ok((net, notes))
}
