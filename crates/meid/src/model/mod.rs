//! Model files: TOML in, a validated [`Model`] out.
//!
//! A model names a structure, the slider, an impact damper and/or an added mass at a named
//! point (or neither), the two contacts and the simulation settings; under a lumped structure,
//! optionally a `[foundation]` on soil and `[[receiver]]`s around it ([`foundation`]). See
//! `docs/reference/model-file.md` for the full reference and `examples/paper-lumped.toml` for a complete
//! file.
//!
//! # Units (SI throughout; field names carry no suffix except `frequencies_hz`)
//!
//! | field | unit |
//! |---|---|
//! | `mass` | kg |
//! | `velocity` | m/s |
//! | `stiffness` (springs, linear contacts, damper spring) | N/m |
//! | `stiffness` (hertz) / (hunt-crossley, exponent n) | N/m^1.5 / N/m^n |
//! | `damping` (dashpots, contacts) | N·s/m |
//! | `alpha` (hunt-crossley) | s/m |
//! | `restitution` (contacts, sets `damping` or `alpha`: [`contacts`]) | 1 |
//! | `damping_ratios` | 1 (fraction of critical) |
//! | `frequencies_hz` | Hz |
//! | `shapes` (mass-normalised) | 1/√kg |
//! | `duration` | s |
//! | `sample_rate` | Hz |
//!
//! Errors name the file, line and column (or the `--set` that caused them), the field and
//! the valid range; unknown keys get a did-you-mean.

mod cache;
pub mod contacts;
pub mod expand;
pub mod fem;
pub mod foundation;
pub mod general;
pub mod imported;
mod keyhash;
mod lumped;
pub mod material;
pub mod network;
pub mod network_fields;
pub mod network_paths;
mod plausible;
pub mod setter;
pub mod source;
pub mod spec;
pub mod strict;

use std::path::Path;

pub(crate) use cache::uses_contact_omega;
pub use cache::{StructureCache, StructureKey};
pub use contacts::{ContactName, ContactSetting};
pub use general::BED_PART;
pub use setter::{CompiledFields, FieldSetter, FieldValue, SetterKind};
pub use source::Source;
pub use spec::*;

use crate::impact::{Absorber, Damper, DashpotKind, ImpactSystem, Slider};
use crate::integrate::{Method, Options};
use crate::modal::ModalModel;
use crate::{Error, Result};

/// The largest blow energy `½ m_s v_s²` (J) a model may have (see [`Model::from_text`]'s
/// checks): far above any forging machine's (~1e6 J), far below double precision's 1.8e308.
pub const MAX_BLOW_ENERGY_J: f64 = 1e100;

/// The magnitudes a model's real numbers may have: 0, or between [`MIN_MAGNITUDE`] and
/// [`MAX_MAGNITUDE`] (SI units). meid multiplies inputs together (a stiffness by a squared
/// length, E t³, m v², k/m ...): with every input inside 1e-100..1e100, products of up to three
/// of them stay inside double precision's normal range 2.2e-308..1.8e308; a mass or a
/// thickness of 1e-308, or a length of 1e308, would not.
pub const MAX_MAGNITUDE: f64 = 1e100;
/// See [`MAX_MAGNITUDE`].
pub const MIN_MAGNITUDE: f64 = 1e-100;

/// Every finite real number of the model (file and overrides) is 0 or within
/// [`MIN_MAGNITUDE`]..=[`MAX_MAGNITUDE`] in magnitude; the first that is not is an error
/// naming its field. NaN and infinities are left to each field's own check (which says what
/// the field takes).
fn check_magnitudes(spec: &ModelSpec, src: &Source) -> Result<()> {
    let Ok(table) = toml::Table::try_from(spec) else {
        return Ok(());
    };
    check_table_magnitudes(&table, src)
}

/// [`check_magnitudes`] of a model table.
pub(crate) fn check_table_magnitudes(table: &toml::Table, src: &Source) -> Result<()> {
    fn walk(v: &toml::Value, path: &str, out: &mut Option<(String, f64)>) {
        if out.is_some() {
            return;
        }
        match v {
            toml::Value::Float(x) => {
                let a = x.abs();
                if x.is_finite() && a != 0.0 && !(MIN_MAGNITUDE..=MAX_MAGNITUDE).contains(&a) {
                    *out = Some((path.to_string(), *x));
                }
            }
            toml::Value::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    walk(item, &format!("{path}[{i}]"), out);
                }
            }
            toml::Value::Table(t) => {
                for (k, item) in t {
                    let p = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}.{k}")
                    };
                    walk(item, &p, out);
                }
            }
            _ => {}
        }
    }
    let mut found = None;
    walk(&toml::Value::Table(table.clone()), "", &mut found);
    match found {
        Some((path, x)) => Err(src.error(
            &path,
            format!(
                "{path} = {x:e} is out of the range meid computes with: give 0 or a magnitude between {MIN_MAGNITUDE:e} and {MAX_MAGNITUDE:e} (SI units; products of a few inputs must stay inside double precision, 2.2e-308 to 1.8e308)"
            ),
        )),
        None => Ok(()),
    }
}

/// A validated model: the spec, the structure reduced to modes, and where it came from.
#[derive(Debug, Clone)]
pub struct Model {
    pub spec: ModelSpec,
    /// The bare structure (no added mass), as modes.
    pub structure: ModalModel,
    pub source: Source,
    /// The files the model reads besides its own text ([`referenced_paths`]), with their
    /// content's size and hash when the model was built.
    pub files: Vec<InputFile>,
}

/// A file a model reads besides its own text (a Gmsh mesh, a UFF or CalculiX `.frd` modes
/// file) as it was when the model was built: its size and the FNV-1a 64 of its bytes
/// ([`crate::input::digest`]). Studies put these in their fingerprint, so results computed
/// from another version of the file are never taken for this model's.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputFile {
    /// The path as the model resolves it (relative to the model file's directory).
    pub path: std::path::PathBuf,
    pub bytes: u64,
    /// 16 hex digits.
    pub fnv1a: String,
}

/// The files a model of `spec` read from `source_name` refers to, resolved as the readers do
/// (relative to the model file's directory): `structure.fem.mesh.file`,
/// `structure.fem.model.mesh` and `structure.modes.file`.
pub fn referenced_paths(spec: &ModelSpec, source_name: &str) -> Vec<std::path::PathBuf> {
    let dir = Path::new(source_name)
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let st = &spec.structure;
    let fem = st.fem.as_ref();
    fem.and_then(|f| f.mesh.as_ref().map(|m| m.file.as_str()))
        .into_iter()
        .chain(fem.and_then(|f| f.model.as_ref().and_then(|g| g.mesh.as_deref())))
        .chain(st.modes.as_ref().map(|m| m.file.as_str()))
        .map(|f| dir.join(f))
        .collect()
}

/// [`InputFile`]s of `paths`, read now.
fn input_files(paths: Vec<std::path::PathBuf>) -> Result<Vec<InputFile>> {
    paths
        .into_iter()
        .map(|path| {
            let (bytes, fnv1a) = crate::input::digest(&path)?;
            Ok(InputFile { path, bytes, fnv1a })
        })
        .collect()
}

/// Which absorber to build the impact system with (for comparisons).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Case {
    /// As the model file says.
    AsSpecified,
    /// The bare machine.
    NoDamper,
    /// The impact damper of the file.
    Damper,
    /// A rigid added mass ([`Model::added_mass`]: `added_mass.mass`, else the damper's mass,
    /// at `added_mass.point`, else the bed contact point).
    AddedMass,
}

impl Case {
    /// The name `--case` takes (`as-specified`, `none`, `damper`, `added-mass`).
    pub fn name(self) -> &'static str {
        match self {
            Case::AsSpecified => "as-specified",
            Case::NoDamper => "none",
            Case::Damper => "damper",
            Case::AddedMass => "added-mass",
        }
    }
}

impl std::str::FromStr for Case {
    type Err = Error;
    /// `as-specified`, `none`, `damper` or `added-mass` (the CLI's `--case`).
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "as-specified" => Ok(Case::AsSpecified),
            "none" => Ok(Case::NoDamper),
            "damper" => Ok(Case::Damper),
            "added-mass" => Ok(Case::AddedMass),
            _ => Err(Error::invalid(
                "case",
                format!("unknown case '{s}'; valid: as-specified, none, damper, added-mass"),
            )),
        }
    }
}

impl Model {
    /// Reads and validates a model file, applying `--set PATH=VALUE` overrides in order.
    pub fn from_file(path: &Path, overrides: &[String]) -> Result<Self> {
        let text = crate::input::read_text(path)?;
        Self::from_text(&path.display().to_string(), text, overrides)
    }

    /// Parses and validates model text; `name` is used in error messages.
    pub fn from_text(name: &str, text: String, overrides: &[String]) -> Result<Self> {
        Self::from_text_with(name, text, overrides, build_structure)
    }

    /// [`Model::from_text`] with the structure built by `build` (see `fem::from_file_with_analysis`).
    pub(crate) fn from_text_with(
        name: &str,
        text: String,
        overrides: &[String],
        build: impl FnOnce(&ModelSpec, &Source) -> Result<ModalModel>,
    ) -> Result<Self> {
        // 1. The file as written: syntax, unknown keys and types, with positions.
        let mut table: toml::Table =
            toml::from_str(&text).map_err(|e| source::toml_error(name, &text, &e))?;
        if network::is_general(&table) {
            return Err(Error::Input {
                location: name.to_string(),
                message: "this is a general machine ([[impactor]], [[damper]] or [[contact]] arrays): `meid simulate`, `meid blows`, `meid sweep` and `meid optimize --place` run it; the other commands take the paper's machine ([slider], [damper], [contact.slider_bed]) for now".into(),
            });
        }
        refuse_rigid_paper_form(name, &text, &table)?;
        let from_file: ModelSpec = spec_from_text(name, &text)?;
        let mut src = Source {
            name: name.to_string(),
            text,
            overrides: Vec::new(),
        };
        // 2. Overrides.
        let spec = if overrides.is_empty() {
            from_file
        } else {
            for o in overrides {
                let applied = source::apply_override(&mut table, o)?;
                src.overrides.push(applied);
            }
            spec_from_table(table, &src)?
        };
        // 3. Values.
        check_magnitudes(&spec, &src)?;
        let structure = build(&spec, &src)?;
        let files = input_files(referenced_paths(&spec, &src.name))?;
        let model = Model {
            spec,
            structure,
            source: src,
            files,
        };
        model.validate()?;
        Ok(model)
    }

    /// The content of the files the model refers to, for a study's fingerprint: empty for a
    /// model without such files, else `|files ` and `size:fnv1a` of each, in
    /// [`referenced_paths`] order.
    pub fn files_fingerprint(&self) -> String {
        if self.files.is_empty() {
            return String::new();
        }
        let each: Vec<String> = self
            .files
            .iter()
            .map(|f| format!("{}:{}", f.bytes, f.fnv1a))
            .collect();
        format!("|files {}", each.join(","))
    }

    /// Attaches a file position to errors about a field.
    pub fn locate_error(&self, e: Error) -> Error {
        match e {
            Error::InvalidValue { field, message } => Error::Input {
                location: self.source.locate(&field),
                message: format!("{field}: {message}"),
            },
            other => other,
        }
    }

    fn validate(&self) -> Result<()> {
        // The impact system (masses, stiffnesses, ...) is built by its last check.
        self.validate_settings()
    }

    /// The value checks of [`Model::from_text`] on top of reading the file, in order: the
    /// tables' settings and the named points ([`Model::check_settings`],
    /// [`Model::check_points`]), every real number's magnitude ([`check_magnitudes`]), the
    /// blow's energy ([`Model::check_blow`]), `[simulation]` ([`Model::check_simulation`]) and
    /// the impact system with the propagator's limits ([`Model::check_system`]). The first
    /// failing check is the error.
    pub(crate) fn validate_settings(&self) -> Result<()> {
        self.check_settings()?;
        self.check_points()?;
        check_magnitudes(&self.spec, &self.source)?;
        self.check_blow()?;
        self.check_simulation()?;
        self.check_system()
    }

    /// The checks of [`Model::validate_settings`] but the magnitudes of the numbers: what a
    /// model whose numbers were checked one by one ([`setter`]) still needs.
    pub(crate) fn validate_values(&self) -> Result<()> {
        self.check_settings()?;
        self.check_points()?;
        self.check_blow()?;
        self.check_simulation()?;
        self.check_system()
    }

    /// `structure.reference_mode` a retained mode, `[added_mass]` with a mass, `[production]`,
    /// `[measurement]`, the receivers, a `[damper]` with its contact.
    fn check_settings(&self) -> Result<()> {
        let s = &self.spec;
        let src = &self.source;
        if let Some(r) = s.structure.reference_mode {
            let st = &self.structure;
            if !(0..st.len()).any(|i| st.mode_numbers[i] == r && !st.is_pseudo(i)) {
                return Err(src.error(
                    "structure.reference_mode",
                    format!(
                        "structure.reference_mode = {r} is not a retained mode of the structure: it names a mode by the structure's number (as `meid modes` lists them); the retained modes are {}",
                        self.retained_modes_text()
                    ),
                ));
            }
        }
        if let Some(a) = &s.added_mass {
            if a.mass.is_none() && s.damper.is_none() {
                return Err(src.error(
                    "added_mass",
                    "added_mass.mass is missing: give the added mass in kg (it defaults to the damper's mass only when the model has a [damper])",
                ));
            }
        }
        if let Some(p) = &s.production {
            if !(p.rate_bpm.is_finite() && p.rate_bpm > 0.0) {
                return Err(src.error(
                    "production.rate_bpm",
                    format!(
                        "production.rate_bpm must be a finite number > 0 blows per minute (got {})",
                        crate::num(p.rate_bpm)
                    ),
                ));
            }
        }
        if let Some(m) = &s.measurement {
            if let Err((field, message)) = m.check(&s.points.measurement) {
                return Err(src.error(&field, format!("{field}: {message}")));
            }
        }
        foundation::check_receivers(s, self.foundation()?.as_ref(), src)?;
        if s.damper.is_some() && s.contact.bed_damper.is_none() {
            return Err(src.error(
                "damper",
                "a [damper] needs its contact: add [contact.bed_damper]",
            ));
        }
        Ok(())
    }

    /// The named points (`points.*`, `added_mass.point`) are points of the structure, and an
    /// added mass sits at a point some retained mode moves.
    fn check_points(&self) -> Result<()> {
        let s = &self.spec;
        let src = &self.source;
        for (role, name) in [
            ("points.bed_contact", Some(&s.points.bed_contact)),
            ("points.measurement", Some(&s.points.measurement)),
            ("points.damper_anchor", s.points.damper_anchor.as_ref()),
            (
                "added_mass.point",
                s.added_mass.as_ref().and_then(|a| a.point.as_ref()),
            ),
        ] {
            let Some(name) = name else { continue };
            if role == "points.damper_anchor" && name == "ground" {
                continue;
            }
            if !self.structure.points.contains_key(name) {
                let known: Vec<&str> = self.structure.points.keys().map(|k| k.as_str()).collect();
                let extra = if role == "points.damper_anchor" {
                    ", ground"
                } else {
                    ""
                };
                return Err(src.error(
                    role,
                    format!(
                        "{role}: unknown point '{name}'; valid: {}{extra}",
                        known.join(", ")
                    ),
                ));
            }
        }
        // An added mass at a point no retained mode moves (a clamped support: ψ = 0 in every
        // mode) changes nothing; the added-mass case would silently be the bare machine.
        if let Some(point) = s.added_mass.as_ref().and_then(|a| a.point.as_ref()) {
            if let Some(psi) = self.structure.points.get(point) {
                if psi.iter().all(|v| *v == 0.0) {
                    return Err(src.error(
                        "added_mass.point",
                        format!(
                            "added_mass.point: '{point}' does not move in any retained mode (ψ = 0 along the impact direction in all {} of them: a fixed support), so a mass there changes nothing and the added-mass case would be the bare structure; give a point that moves",
                            psi.len()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The blow's energy `½ m_s v_s²` at most [`MAX_BLOW_ENERGY_J`].
    fn check_blow(&self) -> Result<()> {
        let s = &self.spec;
        let src = &self.source;
        let (m_s, v_s) = (s.slider.mass, s.slider.velocity);
        let e_s = 0.5 * m_s * v_s * v_s;
        if m_s.is_finite()
            && v_s.is_finite()
            && m_s > 0.0
            && (e_s.is_nan() || e_s > MAX_BLOW_ENERGY_J)
        {
            return Err(src.error(
                "slider.velocity",
                format!(
                    "slider.mass = {} kg and slider.velocity = {} m/s strike with ½ m_s v_s² = {e_s:e} J; meid takes at most {MAX_BLOW_ENERGY_J:e} J (the largest forging hammers strike with ~1e6 J), so that the energies, powers and their products in the energy balance stay far from double precision's limit 1.8e308",
                    crate::num(m_s),
                    crate::num(v_s)
                ),
            ));
        }
        Ok(())
    }

    /// `[simulation]`: duration and sample rate > 0, rtol in (0, 1), atol > 0, max_events in
    /// 1..=1e8.
    fn check_simulation(&self) -> Result<()> {
        let src = &self.source;
        let sim = &self.spec.simulation;
        for (field, v, unit) in [
            ("simulation.duration", sim.duration, "s"),
            ("simulation.sample_rate", sim.sample_rate, "Hz"),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(src.error(
                    field,
                    format!(
                        "{field} must be a finite number > 0 {unit} (got {})",
                        crate::num(v)
                    ),
                ));
            }
        }
        if !(sim.rtol > 0.0 && sim.rtol < 1.0) {
            return Err(src.error(
                "simulation.rtol",
                format!(
                    "simulation.rtol must be in (0, 1) (got {})",
                    crate::num(sim.rtol)
                ),
            ));
        }
        if !(sim.atol > 0.0 && sim.atol.is_finite()) {
            return Err(src.error(
                "simulation.atol",
                format!("simulation.atol must be > 0 (got {})", crate::num(sim.atol)),
            ));
        }
        if !(1..=100_000_000).contains(&sim.max_events) {
            return Err(src.error(
                "simulation.max_events",
                format!(
                    "simulation.max_events must be between 1 and 100000000 (got {}); each \
                     event keeps the state at the switch",
                    sim.max_events
                ),
            ));
        }
        Ok(())
    }

    /// Everything the impact system checks (masses, stiffnesses, ...), with positions, and the
    /// frequency spreads the closed-form propagator cannot carry (meaningless results).
    fn check_system(&self) -> Result<()> {
        let src = &self.source;
        self.impact_system(Case::AsSpecified)?;
        // Frequency spreads the closed-form propagator cannot carry (meaningless results).
        match self.propagator_findings().errors.into_iter().next() {
            Some((field, message)) => Err(src.error(&field, message)),
            None => Ok(()),
        }
    }

    /// The model's `[foundation]`, checked ([`foundation::Foundation::from_spec`]), with its
    /// `anvil` and `pad` checked against the lumped structure; `None` without one.
    pub fn foundation(&self) -> Result<Option<foundation::Foundation>> {
        let s = &self.spec;
        let (Some(f), Some(l)) = (&s.foundation, &s.structure.lumped) else {
            return Ok(None);
        };
        let rate = s.production.as_ref().map(|p| p.rate_bpm);
        let found = foundation::Foundation::from_spec(f, l, rate, &self.source)?;
        let src = &self.source;
        if let Some(a) = &f.anvil {
            if !l.masses.iter().any(|m| &m.name == a) {
                let known: Vec<&str> = l.masses.iter().map(|m| m.name.as_str()).collect();
                return Err(src.error(
                    "foundation.anvil",
                    format!(
                        "foundation.anvil: unknown mass '{a}'; valid: {}",
                        known.join(", ")
                    ),
                ));
            }
        }
        if let Some(p) = &f.pad {
            let spring = l
                .springs
                .iter()
                .find(|sp| sp.name.as_deref() == Some(&p.spring));
            match spring {
                Some(sp) if !sp.nodes.iter().any(|n| n == "ground") => {}
                _ => {
                    let known: Vec<&str> = l
                        .springs
                        .iter()
                        .filter(|sp| !sp.nodes.iter().any(|n| n == "ground"))
                        .filter_map(|sp| sp.name.as_deref())
                        .collect();
                    return Err(src.error(
                        "foundation.pad.spring",
                        format!(
                            "foundation.pad.spring: '{}' is not a named structure.lumped spring between two masses; valid: {}",
                            p.spring,
                            known.join(", ")
                        ),
                    ));
                }
            }
            if !(p.area.is_finite() && p.area > 0.0) {
                return Err(src.error(
                    "foundation.pad.area",
                    format!(
                        "foundation.pad.area must be a finite number > 0 m² (got {})",
                        crate::num(p.area)
                    ),
                ));
            }
        }
        for (field, v, unit) in [
            ("block_amplitude", f.allowable.block_amplitude, "m"),
            ("anvil_amplitude", f.allowable.anvil_amplitude, "m"),
            ("pad_stress", f.allowable.pad_stress, "Pa"),
            ("soil_pressure", f.allowable.soil_pressure, "Pa"),
        ] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    let p = format!("foundation.allowable.{field}");
                    return Err(src.error(
                        &p,
                        format!(
                            "{p} must be a finite number > 0 {unit} (got {})",
                            crate::num(v)
                        ),
                    ));
                }
            }
        }
        Ok(Some(found))
    }

    /// The impact system for a case.
    pub fn impact_system(&self, case: Case) -> Result<ImpactSystem> {
        let s = &self.spec;
        let slider = Slider {
            mass: s.slider.mass,
            velocity: s.slider.velocity,
        };
        let slider_bed = self.slider_bed_setting()?.contact;
        let bed_damper = self.contact_setting(ContactName::BedDamper)?;
        let damper = match (&s.damper, bed_damper) {
            (Some(d), Some(c)) => Some((
                Damper {
                    mass: d.mass,
                    stiffness: d.stiffness,
                    damping: d.damping,
                    dashpot: match d.dashpot {
                        DashpotKindSpec::OneWay => DashpotKind::OneWay,
                        DashpotKindSpec::TwoWay => DashpotKind::TwoWay,
                    },
                },
                c.contact,
            )),
            _ => None,
        };
        let added = self.added_mass();
        let absorber = match case {
            Case::AsSpecified => match (&damper, &s.added_mass) {
                (Some((d, c)), _) => Absorber::Damper(*d, *c),
                (None, Some(_)) => {
                    let (mass_kg, point) = added.ok_or_else(|| {
                        self.source.error(
                            "added_mass",
                            "added_mass.mass is missing: give the added mass in kg",
                        )
                    })?;
                    Absorber::AddedMass { mass_kg, point }
                }
                _ => Absorber::None,
            },
            Case::NoDamper => Absorber::None,
            Case::Damper => match damper {
                Some((d, c)) => Absorber::Damper(d, c),
                None => {
                    return Err(Error::invalid(
                        "damper",
                        "the model has no [damper] to compare",
                    ))
                }
            },
            Case::AddedMass => match added {
                Some((mass_kg, point)) => Absorber::AddedMass { mass_kg, point },
                None => {
                    return Err(Error::invalid(
                        "added_mass",
                        "the model has neither [damper] nor [added_mass]",
                    ))
                }
            },
        };
        let anchor = match s.points.damper_anchor.as_deref() {
            None | Some("ground") => None,
            Some(p) => Some(p),
        };
        ImpactSystem::new(
            &self.structure,
            &s.points.bed_contact,
            anchor,
            &s.points.measurement,
            slider,
            slider_bed,
            absorber,
        )
        .and_then(|sys| sys.with_slider_force(s.slider.force))
        .map_err(|e| self.locate_error(e))
    }

    fn prefix(&self, e: Error, path: &str) -> Error {
        match e {
            Error::InvalidValue { field, message } => {
                let full = format!("{path}.{field}");
                Error::Input {
                    location: self.source.locate(&full),
                    message: format!("{full}: {message}"),
                }
            }
            other => other,
        }
    }

    /// The machine's stroke rate in production (`[production] rate_bpm`, blows per minute), if
    /// the model gives one.
    pub fn stroke_rate_bpm(&self) -> Option<f64> {
        self.spec.production.as_ref().map(|p| p.rate_bpm)
    }

    /// Integration options from `[simulation]`.
    pub fn options(&self) -> Options {
        let s = &self.spec.simulation;
        Options {
            method: match s.method {
                MethodSpec::Exact => Method::Exact,
                MethodSpec::Dopri5 => Method::Dopri5,
            },
            duration: s.duration,
            sample_rate: Some(s.sample_rate),
            stop_at_collision_end: false,
            rtol: s.rtol,
            atol: s.atol,
            max_events: usize::try_from(s.max_events).unwrap_or(usize::MAX),
            ..Options::default()
        }
    }

    /// ω_ref (rad/s): the reference mode's frequency ([`Model::reference_mode`]).
    pub fn reference_omega(&self) -> Option<f64> {
        self.reference_mode().map(|r| r.omega_rad_per_s)
    }

    /// The reference mode ω_ref of the ratios ω_s/ω_ref and ω_d/ω_ref: the retained mode
    /// `structure.reference_mode` names by the structure's mode number; not given, the
    /// retained mode with the largest effective modal mass along the blow, `Γ_i² = (φ_iᵀ M r)²`
    /// (the mode the machine bounces in as a whole: the rigid-body mode on a floating base, the
    /// bed mode without one), among the modes that vibrate (ω > 0). `None` when the file names
    /// none and the effective masses are not known (tabulated or imported modes).
    pub fn reference_mode(&self) -> Option<ReferenceMode> {
        let st = &self.structure;
        let (index, given) = match self.spec.structure.reference_mode {
            Some(r) => (
                (0..st.len()).find(|&i| st.mode_numbers[i] == r && !st.is_pseudo(i))?,
                true,
            ),
            None => {
                let m = st.effective_mass_kg.as_ref()?;
                // Static-correction pseudo-modes are not modes of the structure.
                let best = (0..st.len())
                    .filter(|&i| {
                        st.omega_rad_per_s[i] > 0.0 && m[i].is_finite() && !st.is_pseudo(i)
                    })
                    .max_by(|&a, &b| m[a].total_cmp(&m[b]))?;
                (best, false)
            }
        };
        let w = st.omega_rad_per_s[index];
        let psi = st
            .points
            .get(&self.spec.points.bed_contact)
            .and_then(|v| v.get(index).copied())
            .unwrap_or(f64::NAN);
        Some(ReferenceMode {
            number: st.mode_numbers.get(index).copied().unwrap_or(index + 1),
            index,
            omega_rad_per_s: w,
            frequency_hz: w / (2.0 * std::f64::consts::PI),
            effective_mass_kg: st.effective_mass_kg.as_ref().map(|m| m[index]),
            strike_point: self.spec.points.bed_contact.clone(),
            strike_point_mass_kg: 1.0 / (psi * psi),
            given,
        })
    }

    /// The retained modes as `5 (6.350 Hz), 10 (285.8 Hz)` for messages.
    fn retained_modes_text(&self) -> String {
        let st = &self.structure;
        st.mode_numbers
            .iter()
            .zip(&st.omega_rad_per_s)
            .enumerate()
            .filter(|(i, _)| !st.is_pseudo(*i))
            .map(|(_, (k, w))| format!("{k} ({:.4} Hz)", w / (2.0 * std::f64::consts::PI)))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The warning when the reference mode barely moves the strike point: its mass there,
    /// `1/ψ_ref(P)²`, more than [`REFERENCE_MASS_SPREAD`] times the smallest of the retained
    /// modes' (the blow hardly excites the mode every ratio is scaled by).
    fn reference_warning(&self) -> Option<String> {
        let r = self.reference_mode()?;
        let psi = self.structure.points.get(&r.strike_point)?;
        let (k, lightest) = psi
            .iter()
            .map(|p| 1.0 / (p * p))
            .enumerate()
            .filter(|(i, m)| m.is_finite() && !self.structure.is_pseudo(*i))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        let ratio = r.strike_point_mass_kg / lightest;
        if ratio.is_finite() && ratio <= REFERENCE_MASS_SPREAD {
            return None;
        }
        let st = &self.structure;
        let by = if r.given {
            "structure.reference_mode"
        } else {
            "structure.reference_mode (not given: the largest effective mass along the blow)"
        };
        Some(format!(
            "{}: {by}: the reference mode ω_ref, mode {} ({:.4} Hz), barely moves the strike point '{}': its mass there 1/ψ² = {:.4e} kg is {:.3e} times that of mode {} ({:.4} Hz, {lightest:.4e} kg), so the blow hardly excites the mode every ω_s/ω_ref and ω_d/ω_ref is scaled by. Name the mode the machine bounces in by its number in `meid modes` (retained: {})",
            self.source.locate("structure.reference_mode"),
            r.number,
            r.frequency_hz,
            r.strike_point,
            r.strike_point_mass_kg,
            ratio,
            st.mode_numbers.get(k).copied().unwrap_or(k + 1),
            st.omega_rad_per_s[k] / (2.0 * std::f64::consts::PI),
            self.retained_modes_text()
        ))
    }

    /// The added mass of the "added mass" case, `(m_a (kg), point)`: `added_mass.mass`, else the
    /// damper's mass m_d; at `added_mass.point`, else `points.bed_contact`. `None` when the
    /// model has neither `[added_mass]` nor `[damper]`.
    pub fn added_mass(&self) -> Option<(f64, String)> {
        let s = &self.spec;
        let a = s.added_mass.clone().unwrap_or_default();
        let mass = a.mass.or(s.damper.as_ref().map(|d| d.mass))?;
        let point = a.point.unwrap_or_else(|| s.points.bed_contact.clone());
        Some((mass, point))
    }

    /// Bed mass m_b (kg) for the mass ratio `md/mb`, when the model can tell:
    ///
    /// * `[structure.lumped]`: the mass named by `points.bed_contact`;
    /// * `[structure.fem.machine]` with `points.bed_contact` on the bed plate (`O_b` or `B`):
    ///   the bed plate's mass `ρ L_x L_y t` (exactly the sum of its shell elements' masses)
    ///   plus the `added_masses` on plate `"bed"`;
    /// * `[structure.fem.model]` (a user's mesh, or `meid model expand`'s machine) with elements
    ///   labelled `part = "bed"` and every node of `points.bed_contact` on them: their mass
    ///   ([`crate::structure::Mesh::mass_of`]: `ρ t A` per shell, `ρ A L` per frame, plus the
    ///   point masses of the part);
    /// * otherwise (`[structure.modal]`, no bed part, a contact point off the bed) `None`: give
    ///   it (`--bed-mass`).
    pub fn bed_mass(&self) -> Option<f64> {
        let st = &self.spec.structure;
        let contact = self.spec.points.bed_contact.as_str();
        if let Some(l) = &st.lumped {
            return l.masses.iter().find(|m| m.name == contact).map(|m| m.mass);
        }
        if let Some(m) = st.fem.as_ref().and_then(|f| f.machine.as_ref()) {
            if contact != "O_b" && contact != "B" {
                return None;
            }
            let spec = fem::machine_spec(m).ok()?;
            let added: f64 = spec
                .added_masses
                .iter()
                .filter(|a| a.plate == crate::structure::machine::Plate::Bed)
                .map(|a| a.mass_kg)
                .sum();
            let m_b = spec.bed.mass_kg() + added;
            return (m_b.is_finite() && m_b > 0.0).then_some(m_b);
        }
        if st.fem.as_ref().is_some_and(|f| f.model.is_some()) {
            // Found when the structure was built, from the same mesh as its modes.
            return self.structure.bed_mass_kg;
        }
        None
    }
}

/// Reads a model file's text strictly ([`strict`]): errors name the file, line, column and
/// field, in the model's terms.
pub fn spec_from_text(name: &str, text: &str) -> Result<ModelSpec> {
    let de = toml::de::Deserializer::parse(text).map_err(|e| source::toml_error(name, text, &e))?;
    strict::deserialize(de).map_err(|(e, track)| {
        source::toml_error_message(name, text, &e, strict::message(e.message(), &track))
    })
}

/// Reads a model table (the file with `--set` overrides applied) strictly ([`strict`]):
/// errors name the `--set` that set the failing field (all of them when none did) and the
/// field.
pub fn spec_from_table(table: toml::Table, src: &Source) -> Result<ModelSpec> {
    strict::deserialize(toml::Value::Table(table)).map_err(|(e, track)| {
        let message = strict::message(e.message(), &track);
        let path = track.path.unwrap_or_default();
        let own: Vec<String> = src
            .overrides
            .iter()
            .filter(|(p, _)| source::path_within(&path, p) || source::path_within(p, &path))
            .map(|(p, v)| format!("--set {p}={v}"))
            .collect();
        let location = if own.is_empty() {
            src.overrides
                .iter()
                .map(|(p, v)| format!("--set {p}={v}"))
                .collect::<Vec<_>>()
                .join(" ")
        } else {
            own.join(" ")
        };
        Error::Input { location, message }
    })
}

fn build_structure(spec: &ModelSpec, src: &Source) -> Result<ModalModel> {
    let ctx = fem::ReductionContext::of(spec);
    build_structure_of(&spec.structure, spec.foundation.as_ref(), src, &ctx)
}

/// The structure of a `[structure]` section (on the soil of `foundation`, when given), reduced
/// in the context `ctx`.
pub(crate) fn build_structure_of(
    st: &StructureSpec,
    foundation: Option<&spec::FoundationSpec>,
    src: &Source,
    ctx: &fem::ReductionContext,
) -> Result<ModalModel> {
    let given = usize::from(st.lumped.is_some())
        + usize::from(st.modal.is_some())
        + usize::from(st.fem.is_some())
        + usize::from(st.modes.is_some());
    if given > 1 {
        return Err(src.error(
            "structure",
            "give one of [structure.lumped], [structure.modal], [structure.fem] or [structure.modes], not several",
        ));
    }
    if let Some(f) = foundation {
        let Some(l) = &st.lumped else {
            return Err(src.error(
                "foundation",
                "foundation: the block on the soil is built under a [structure.lumped] (the engine is one-axis and the soil joins a lumped mass to the ground); give the structure as masses and springs",
            ));
        };
        // The excitation class does not enter the structure: no stroke rate needed here.
        let found = foundation::Foundation::from_spec(f, l, None, src)?;
        return lumped::modal_model(&found.augment(l), src, ctx);
    }
    if let Some(l) = &st.lumped {
        return lumped::modal_model(l, src, ctx);
    }
    if let Some(m) = &st.modal {
        return lumped::from_modal_spec(m, src);
    }
    if let Some(f) = &st.fem {
        return fem::modal_model(f, src, ctx);
    }
    if let Some(m) = &st.modes {
        return imported::modal_model(m, src);
    }
    Err(src.error(
        "structure",
        "the structure is missing: add [structure.lumped] (masses, springs), [structure.modal] (frequencies_hz, shapes), [structure.fem] or [structure.modes] (file = a UFF or CalculiX .frd file)",
    ))
}

/// How many times the strike-point mass `1/ψ(P)²` of the reference mode may exceed the smallest
/// of the retained modes' before [`Model::diagnostics`] warns that the reference barely moves
/// the strike point.
pub const REFERENCE_MASS_SPREAD: f64 = 100.0;

/// The reference mode ω_ref of the ratios ω_s/ω_ref and ω_d/ω_ref ([`Model::reference_mode`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ReferenceMode {
    /// The structure's mode number (1-based, as `meid modes` lists them).
    pub number: usize,
    /// Its position among the retained modes (0-based).
    #[serde(skip)]
    pub index: usize,
    pub omega_rad_per_s: f64,
    pub frequency_hz: f64,
    /// Effective modal mass along the blow `Γ² = (φᵀ M r)²` (kg), when the mass matrix is known.
    pub effective_mass_kg: Option<f64>,
    /// The strike point (`points.bed_contact`).
    pub strike_point: String,
    /// The mode's mass at the strike point, `1/ψ(P)²` (kg): what the slider meets in this mode.
    pub strike_point_mass_kg: f64,
    /// Named by `structure.reference_mode` (else chosen by the largest effective mass).
    pub given: bool,
}

impl ReferenceMode {
    /// `ω_ref = mode 5, 6.3500 Hz (effective mass 50.99 kg, 1/ψ(O_b)² = 51.00 kg)`, printed
    /// beside the ratios ω_s/ω_ref and ω_d/ω_ref.
    pub fn describe(&self) -> String {
        let eff = self
            .effective_mass_kg
            .map_or(String::new(), |m| format!("effective mass {m:.4} kg, "));
        format!(
            "ω_ref = mode {}, {:.4} Hz ({eff}1/ψ({})² = {:.4} kg{})",
            self.number,
            self.frequency_hz,
            self.strike_point,
            self.strike_point_mass_kg,
            if self.given {
                ""
            } else {
                "; chosen as the largest effective mass, structure.reference_mode not given"
            }
        )
    }
}

/// What a report shows beside a model's results: how much of the structure the retained modes
/// keep, what building it did, and what looks doubtful.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Diagnostics {
    /// Captured share of the static flexibility at each named point with a role.
    pub truncation: Vec<crate::modal::truncation::TruncationRow>,
    /// E.g. a spring treated as rigid.
    pub notes: Vec<String>,
    /// Each names the model field concerned.
    pub warnings: Vec<String>,
}

impl Model {
    /// The truncation table of the role points (O_b, O_f, B), the structure's notes, and the
    /// warnings: the structure's own, captured shares below 95 %
    /// ([`crate::modal::truncation::SHARE_WARNING`]), frequency spreads the closed-form
    /// propagator resolves only approximately ([`crate::modal::conditioning`]), and imported
    /// modes of unstated units that make the struck point implausibly light
    /// ([`imported::unit_suspicion`]), and typed values no machine has, with their likely unit
    /// slip ([`plausible`]).
    pub fn diagnostics(&self) -> Diagnostics {
        let ctx = fem::ReductionContext::of(&self.spec);
        let truncation = self.structure.truncation(&ctx.role_points);
        let mut warnings = self.structure.warnings.clone();
        warnings.extend(
            truncation
                .iter()
                .filter_map(crate::modal::truncation::share_warning),
        );
        for (field, message) in self.propagator_findings().warnings {
            warnings.push(format!("{}: {message}", self.source.locate(&field)));
        }
        let bed = &self.spec.points.bed_contact;
        if let Some(why) = self.structure.immovable_point("points.bed_contact", bed) {
            warnings.push(format!(
                "{}: {why}",
                self.source.locate("points.bed_contact")
            ));
        }
        // Here, not with the structure: it reads the slider, which the structure cache's key
        // leaves out.
        warnings.extend(imported::unit_suspicion(
            &self.structure,
            self.spec.slider.mass,
            &self.spec.points.bed_contact,
        ));
        warnings.extend(self.reference_warning());
        warnings.extend(plausible::unit_slips(&self.spec, &self.source));
        let mut notes = self.structure.notes.clone();
        notes.extend(self.contact_notes());
        notes.extend(self.mass_ratio_note(&truncation));
        Diagnostics {
            truncation,
            notes,
            warnings,
        }
    }

    /// The damper's mass against the mass the structure opposes to a blow at O_b,
    /// `m_d / m_eff(O_b)` with `m_eff = 1/Σ ψ_i(O_b)²` over the retained modes
    /// ([`crate::modal::truncation`]): the ratio the momentum exchange depends on, which can
    /// differ much from `m_d / m_b` (a bed mode moves only part of the bed's mass).
    fn mass_ratio_note(&self, rows: &[crate::modal::truncation::TruncationRow]) -> Option<String> {
        let damper = self.spec.damper.as_ref()?;
        let bed = &self.spec.points.bed_contact;
        let r = rows.iter().find(|r| &r.point == bed)?;
        let m_eff = r.effective_mass_kg?;
        let dominant = match (r.dominant_mode, r.dominant_mode_effective_mass_kg) {
            (Some(n), Some(m)) => format!("; mode {n} alone: {} kg", crate::num(round4(m))),
            _ => String::new(),
        };
        Some(format!(
            "at O_b ('{bed}') the structure meets a blow as m_eff = {} kg (1/Σψ² over the retained modes{dominant}): m_d/m_eff = {}",
            crate::num(round4(m_eff)),
            crate::num(round4(damper.mass / m_eff))
        ))
    }

    /// The damper spring (always acting) and the linear contacts (acting while closed) against
    /// the structure's modes, for the exact method's closed-form propagator (dopri5 has no
    /// null tolerance: a wide spread only makes its steps small).
    fn propagator_findings(&self) -> crate::modal::conditioning::Findings {
        use crate::modal::conditioning::{propagator_findings, Findings, Link};
        let s = &self.spec;
        if s.simulation.method != MethodSpec::Exact {
            return Findings::default();
        }
        let psi = |name: &str| self.structure.points.get(name).cloned();
        let mut persistent = Vec::new();
        let mut contacts = Vec::new();
        let linear = |c: &ContactSpec| c.law == LawSpec::Linear && c.stiffness > 0.0;
        if linear(&s.contact.slider_bed) {
            contacts.push(Link {
                field: "contact.slider_bed.stiffness".into(),
                stiffness: s.contact.slider_bed.stiffness,
                body_mass: s.slider.mass,
                psi: psi(&s.points.bed_contact),
            });
        }
        if let Some(d) = &s.damper {
            if d.stiffness > 0.0 {
                persistent.push(Link {
                    field: "damper.stiffness".into(),
                    stiffness: d.stiffness,
                    body_mass: d.mass,
                    psi: s
                        .points
                        .damper_anchor
                        .as_deref()
                        .filter(|a| *a != "ground")
                        .and_then(psi),
                });
            }
            if let Some(c) = s.contact.bed_damper.as_ref().filter(|c| linear(c)) {
                contacts.push(Link {
                    field: "contact.bed_damper.stiffness".into(),
                    stiffness: c.stiffness,
                    body_mass: d.mass,
                    psi: psi(&s.points.bed_contact),
                });
            }
        }
        propagator_findings(
            &self.structure.omega_rad_per_s,
            &persistent,
            &contacts,
            s.simulation.duration,
        )
    }
}

/// `v` to 4 significant digits (for notes).
fn round4(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(3 - v.abs().log10().floor() as i32);
    (v * scale).round() / scale
}

/// A paper-form contact with `law = "rigid"` (which also leaves out the stiffness the paper's
/// form requires) is refused before the sections are read, saying how to write the machine as
/// a general one ([`crate::impact::RIGID_PAPER_FORM`]).
fn refuse_rigid_paper_form(name: &str, text: &str, table: &toml::Table) -> Result<()> {
    let Some(toml::Value::Table(contacts)) = table.get("contact") else {
        return Ok(());
    };
    for which in ["slider_bed", "bed_damper"] {
        let rigid = contacts
            .get(which)
            .and_then(|c| c.get("law"))
            .and_then(|l| l.as_str())
            == Some("rigid");
        if rigid {
            let src = Source {
                name: name.to_string(),
                text: text.to_string(),
                overrides: Vec::new(),
            };
            let path = format!("contact.{which}.law");
            return Err(src.error(
                &path,
                format!("{path}: {}", crate::impact::RIGID_PAPER_FORM),
            ));
        }
    }
    Ok(())
}
