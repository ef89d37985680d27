//! Typed field updates: a study's varied fields set on the typed [`ModelSpec`], without TOML.
//!
//! A study (sweep, Monte Carlo) builds one model per point: the base model with a few fields
//! set, as `--set PATH=VALUE` would ([`Model::with_fields`]: the spec written to a TOML table,
//! the values set in it, the table read back strictly and every number's magnitude checked
//! again). Here each varied path is compiled once, at the study's set-up, into a
//! [`FieldSetter`]: the field's place in the typed spec, found on the base model. A point then
//!
//! 1. clones the base spec and writes its values through the setters (a real field takes a
//!    real, a whole-number field a whole number ≥ 0, an enumerated or text field its text);
//! 2. checks the magnitude of each real number it set (finite, and 0 or within
//!    [`super::MIN_MAGNITUDE`]..=[`super::MAX_MAGNITUDE`], as [`super::check_magnitudes`]
//!    checks the whole file; the other numbers are the base's, already checked);
//! 3. takes the base's structure unless a setter can change the [`StructureKey`] (a field
//!    under `structure`, `foundation` or `points`, or, when the reduction uses the contact
//!    frequency ω_c, the slider's mass, the damper's mass and the contacts, and the slider's
//!    velocity when a contact law is not linear): then
//!    the key of the point, a hash of typed values, finds the structure in the cache or builds
//!    it;
//! 4. runs every other check of a model file ([`Model::validate_values`]) on the point's model.
//!
//! The point's model is the TOML route's (spec, structure, files and `source` with the point's
//! `PATH=LITERAL` overrides, which its later errors name), value for value. When a setter does
//! not apply (a path typed setters do not cover, such as an array element of a general FE
//! model, a material or a file name; a value of the wrong kind) or when a check in 2-4 fails,
//! [`Model::with_values_typed`] gives `None` and the caller takes the TOML route, which then
//! gives the model or the error, in the same words as always.

use super::cache::{uses_contact_omega, StructureCache, StructureKey};
use super::spec::{
    DashpotKindSpec, Excitation, LawSpec, MethodSpec, PerDirection, ReleaseSpec, SolverSpec,
    SupportSpec,
};
use super::{Model, ModelSpec, MAX_MAGNITUDE, MIN_MAGNITUDE};
use crate::Result;

/// A value a typed setter writes.
#[derive(Debug, Clone, PartialEq)]
pub enum FieldValue {
    /// A real number (SI units of the field).
    Real(f64),
    /// A whole number (a count, an index).
    Integer(i64),
    /// A text: a point name, or an enumerated setting (`"two-way"`, `"dopri5"`, ...).
    Text(String),
}

impl FieldValue {
    /// The TOML literal `--set PATH=LITERAL` takes for this value: a real in shortest
    /// round-trip form (`{:e}`), a whole number as an integer literal, a text quoted.
    pub fn literal(&self) -> String {
        match self {
            FieldValue::Real(v) => format!("{v:e}"),
            FieldValue::Integer(i) => i.to_string(),
            FieldValue::Text(s) => toml::Value::String(s.clone()).to_string(),
        }
    }
}

/// What a field holds, as a study gives it values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SetterKind {
    Real,
    Whole,
    Text,
}

/// A compiled field path: where in the typed spec `--set PATH=…` writes.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldSetter {
    path: String,
    target: Target,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Target {
    Slider(u8),
    Damper(u8),
    /// `false`: slider_bed; `true`: bed_damper.
    Contact(bool, u8),
    Sim(u8),
    ProductionRate,
    AddedMass(u8),
    Point(u8),
    ReferenceMode,
    LumpedMass(usize),
    LumpedSpring(usize),
    LumpedDashpot(usize),
    Fem(u8),
    Machine(u8),
    /// `false`: the bed plate; `true`: the base plate.
    Plate(bool, u8),
    Foundation(u8),
    Soil(u8),
    Ground(u8),
}

/// The place a target writes to.
enum Slot<'a> {
    Real(&'a mut f64),
    OptReal(&'a mut Option<f64>),
    OptCount(&'a mut Option<usize>),
    U64(&'a mut u64),
    Text(&'a mut String),
    OptText(&'a mut Option<String>),
    PerDir(&'a mut Option<PerDirection>),
    Dashpot(&'a mut DashpotKindSpec),
    Law(&'a mut LawSpec),
    Release(&'a mut ReleaseSpec),
    Method(&'a mut MethodSpec),
    Solver(&'a mut Option<SolverSpec>),
    Support(&'a mut Option<SupportSpec>),
    Excitation(&'a mut Option<Excitation>),
}

fn name_of(names: &[&str], key: &str) -> Option<u8> {
    names.iter().position(|n| *n == key).map(|i| i as u8)
}

const SLIDER: [&str; 3] = ["mass", "velocity", "force"];
const DAMPER: [&str; 4] = ["mass", "stiffness", "damping", "dashpot"];
const CONTACT: [&str; 7] = [
    "law",
    "stiffness",
    "damping",
    "exponent",
    "alpha",
    "restitution",
    "release",
];
const SIM: [&str; 6] = [
    "method",
    "duration",
    "sample_rate",
    "rtol",
    "atol",
    "max_events",
];
const ADDED: [&str; 2] = ["mass", "point"];
const POINTS: [&str; 3] = ["bed_contact", "damper_anchor", "measurement"];
const FEM: [&str; 4] = ["count", "auto_count", "auto_max_hz", "solver"];
const MACHINE: [&str; 9] = [
    "elements_per_side",
    "column_elements",
    "column_length",
    "column_inset",
    "spring_inset",
    "spider_half_size",
    "spring_stiffness",
    "spring_damping",
    "support",
];
const PLATE: [&str; 3] = ["length_x", "length_y", "thickness"];
const FOUNDATION: [&str; 7] = [
    "length",
    "width",
    "height",
    "embedment",
    "block_mass",
    "block_density",
    "excitation",
];
const SOIL: [&str; 8] = [
    "shear_modulus",
    "shear_wave_velocity",
    "poisson",
    "density",
    "material_damping",
    "uniform_compression",
    "stiffness_z",
    "damping_z",
];
const GROUND: [&str; 2] = ["geometric_exponent", "attenuation"];

/// `name[i]` → `(name, i)`.
fn indexed(seg: &str) -> Option<(&str, usize)> {
    let (name, rest) = seg.split_once('[')?;
    Some((name, rest.strip_suffix(']')?.parse().ok()?))
}

/// The target of a dotted path, when typed setters cover it.
fn target_of(path: &str) -> Option<Target> {
    let segs: Vec<&str> = path.split('.').collect();
    Some(match segs.as_slice() {
        ["slider", k] => Target::Slider(name_of(&SLIDER, k)?),
        ["damper", k] => Target::Damper(name_of(&DAMPER, k)?),
        ["contact", "slider_bed", k] => Target::Contact(false, name_of(&CONTACT, k)?),
        ["contact", "bed_damper", k] => Target::Contact(true, name_of(&CONTACT, k)?),
        ["simulation", k] => Target::Sim(name_of(&SIM, k)?),
        ["production", "rate_bpm"] => Target::ProductionRate,
        ["added_mass", k] => Target::AddedMass(name_of(&ADDED, k)?),
        ["points", k] => Target::Point(name_of(&POINTS, k)?),
        ["structure", "reference_mode"] => Target::ReferenceMode,
        ["structure", "lumped", item, k] => match (indexed(item)?, *k) {
            (("masses", i), "mass") => Target::LumpedMass(i),
            (("springs", i), "stiffness") => Target::LumpedSpring(i),
            (("dashpots", i), "damping") => Target::LumpedDashpot(i),
            _ => return None,
        },
        ["structure", "fem", k] => Target::Fem(name_of(&FEM, k)?),
        ["structure", "fem", "machine", k] => Target::Machine(name_of(&MACHINE, k)?),
        ["structure", "fem", "machine", "bed", k] => Target::Plate(false, name_of(&PLATE, k)?),
        ["structure", "fem", "machine", "base", k] => Target::Plate(true, name_of(&PLATE, k)?),
        ["foundation", "soil", k] => Target::Soil(name_of(&SOIL, k)?),
        ["foundation", "ground", k] => Target::Ground(name_of(&GROUND, k)?),
        ["foundation", k] => Target::Foundation(name_of(&FOUNDATION, k)?),
        _ => return None,
    })
}

/// The place of `t` in `s`; `None` when a table on the way is absent (setting the field would
/// create it: the TOML route reads the new table and says what it lacks).
fn slot(t: Target, s: &mut ModelSpec) -> Option<Slot<'_>> {
    use Slot as S;
    Some(match t {
        Target::Slider(k) => {
            let sl = &mut s.slider;
            S::Real(
                [&mut sl.mass, &mut sl.velocity, &mut sl.force]
                    .into_iter()
                    .nth(k.into())?,
            )
        }
        Target::Damper(k) => {
            let d = s.damper.as_mut()?;
            match k {
                0 => S::Real(&mut d.mass),
                1 => S::Real(&mut d.stiffness),
                2 => S::Real(&mut d.damping),
                _ => S::Dashpot(&mut d.dashpot),
            }
        }
        Target::Contact(bed_damper, k) => {
            let c = if bed_damper {
                s.contact.bed_damper.as_mut()?
            } else {
                &mut s.contact.slider_bed
            };
            match k {
                0 => S::Law(&mut c.law),
                1 => S::Real(&mut c.stiffness),
                2 => S::OptReal(&mut c.damping),
                3 => S::OptReal(&mut c.exponent),
                4 => S::OptReal(&mut c.alpha),
                5 => S::OptReal(&mut c.restitution),
                _ => S::Release(&mut c.release),
            }
        }
        Target::Sim(k) => {
            let m = &mut s.simulation;
            match k {
                0 => S::Method(&mut m.method),
                1 => S::Real(&mut m.duration),
                2 => S::Real(&mut m.sample_rate),
                3 => S::Real(&mut m.rtol),
                4 => S::Real(&mut m.atol),
                _ => S::U64(&mut m.max_events),
            }
        }
        Target::ProductionRate => S::Real(&mut s.production.as_mut()?.rate_bpm),
        Target::AddedMass(k) => {
            let a = s.added_mass.as_mut()?;
            match k {
                0 => S::OptReal(&mut a.mass),
                _ => S::OptText(&mut a.point),
            }
        }
        Target::Point(k) => {
            let p = &mut s.points;
            match k {
                0 => S::Text(&mut p.bed_contact),
                1 => S::OptText(&mut p.damper_anchor),
                _ => S::Text(&mut p.measurement),
            }
        }
        Target::ReferenceMode => S::OptCount(&mut s.structure.reference_mode),
        Target::LumpedMass(i) => S::Real(&mut s.structure.lumped.as_mut()?.masses.get_mut(i)?.mass),
        Target::LumpedSpring(i) => {
            S::Real(&mut s.structure.lumped.as_mut()?.springs.get_mut(i)?.stiffness)
        }
        Target::LumpedDashpot(i) => {
            S::Real(&mut s.structure.lumped.as_mut()?.dashpots.get_mut(i)?.damping)
        }
        Target::Fem(k) => {
            let f = s.structure.fem.as_mut()?;
            match k {
                0 => S::OptCount(&mut f.count),
                1 => S::OptCount(&mut f.auto_count),
                2 => S::OptReal(&mut f.auto_max_hz),
                _ => S::Solver(&mut f.solver),
            }
        }
        Target::Machine(k) => machine_slot(k, s)?,
        Target::Plate(base, k) => {
            let m = s.structure.fem.as_mut()?.machine.as_mut()?;
            let p = if base {
                m.base.as_mut()?
            } else {
                m.bed.as_mut()?
            };
            S::Real(
                [&mut p.length_x, &mut p.length_y, &mut p.thickness]
                    .into_iter()
                    .nth(k.into())?,
            )
        }
        Target::Foundation(k) => {
            let f = s.foundation.as_mut()?;
            match k {
                0 => S::Real(&mut f.length),
                1 => S::Real(&mut f.width),
                2 => S::OptReal(&mut f.height),
                3 => S::OptReal(&mut f.embedment),
                4 => S::OptReal(&mut f.block_mass),
                5 => S::OptReal(&mut f.block_density),
                _ => S::Excitation(&mut f.excitation),
            }
        }
        Target::Soil(k) => {
            let o = &mut s.foundation.as_mut()?.soil;
            S::OptReal(
                [
                    &mut o.shear_modulus,
                    &mut o.shear_wave_velocity,
                    &mut o.poisson,
                    &mut o.density,
                    &mut o.material_damping,
                    &mut o.uniform_compression,
                    &mut o.stiffness_z,
                    &mut o.damping_z,
                ]
                .into_iter()
                .nth(k.into())?,
            )
        }
        Target::Ground(k) => {
            let g = &mut s.foundation.as_mut()?.ground;
            S::OptReal(
                [&mut g.geometric_exponent, &mut g.attenuation]
                    .into_iter()
                    .nth(k.into())?,
            )
        }
    })
}

fn machine_slot(k: u8, s: &mut ModelSpec) -> Option<Slot<'_>> {
    let m = s.structure.fem.as_mut()?.machine.as_mut()?;
    Some(match k {
        0 => Slot::OptCount(&mut m.elements_per_side),
        1 => Slot::OptCount(&mut m.column_elements),
        2 => Slot::OptReal(&mut m.column_length),
        3 => Slot::OptReal(&mut m.column_inset),
        4 => Slot::OptReal(&mut m.spring_inset),
        5 => Slot::OptReal(&mut m.spider_half_size),
        6 => Slot::PerDir(&mut m.spring_stiffness),
        7 => Slot::PerDir(&mut m.spring_damping),
        _ => Slot::Support(&mut m.support),
    })
}

/// An enumerated setting read from its text as the model file reads it (kebab-case names).
fn variant<T: serde::de::DeserializeOwned>(text: &str) -> Option<T> {
    use serde::de::IntoDeserializer;
    let de: serde::de::value::StrDeserializer<'_, serde::de::value::Error> =
        text.into_deserializer();
    T::deserialize(de).ok()
}

impl Slot<'_> {
    fn kind(&self) -> SetterKind {
        match self {
            Slot::Real(_) | Slot::OptReal(_) | Slot::PerDir(_) => SetterKind::Real,
            Slot::OptCount(_) | Slot::U64(_) => SetterKind::Whole,
            _ => SetterKind::Text,
        }
    }

    /// Writes `v`; `None` (nothing written) when `v` is not of the field's kind or not one of
    /// its values.
    fn write(self, v: &FieldValue) -> Option<()> {
        use FieldValue as V;
        match (self, v) {
            (Slot::Real(x), V::Real(v)) => *x = *v,
            (Slot::OptReal(x), V::Real(v)) => *x = Some(*v),
            (Slot::PerDir(x), V::Real(v)) => *x = Some(PerDirection::All(*v)),
            (Slot::OptCount(x), V::Integer(i)) => *x = Some(usize::try_from(*i).ok()?),
            (Slot::U64(x), V::Integer(i)) => *x = u64::try_from(*i).ok()?,
            (Slot::Text(x), V::Text(t)) => t.clone_into(x),
            (Slot::OptText(x), V::Text(t)) => *x = Some(t.clone()),
            (Slot::Dashpot(x), V::Text(t)) => *x = variant(t)?,
            (Slot::Law(x), V::Text(t)) => *x = variant(t)?,
            (Slot::Release(x), V::Text(t)) => *x = variant(t)?,
            (Slot::Method(x), V::Text(t)) => *x = variant(t)?,
            (Slot::Solver(x), V::Text(t)) => *x = Some(variant(t)?),
            (Slot::Support(x), V::Text(t)) => *x = Some(variant(t)?),
            (Slot::Excitation(x), V::Text(t)) => *x = Some(variant(t)?),
            _ => return None,
        }
        Some(())
    }
}

impl FieldSetter {
    /// The setter of `path` on models shaped like `spec` (the tables on the way present);
    /// `None` when typed setters do not cover the path (the TOML route then sets it).
    pub fn compile(spec: &ModelSpec, path: &str) -> Option<Self> {
        let target = target_of(path.trim())?;
        let mut probe = spec.clone();
        slot(target, &mut probe)?;
        Some(FieldSetter {
            path: path.trim().to_string(),
            target,
        })
    }

    /// The path as given.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Real, whole number or text.
    pub fn kind(&self, spec: &ModelSpec) -> Option<SetterKind> {
        let mut probe = spec.clone();
        slot(self.target, &mut probe).map(|s| s.kind())
    }

    /// Writes `v` into `spec`; `None` when it cannot (see [`Slot::write`]).
    fn set(&self, spec: &mut ModelSpec, v: &FieldValue) -> Option<()> {
        slot(self.target, spec)?.write(v)
    }

    /// Whether setting this field can change a model's [`StructureKey`]: a field under
    /// `structure`, `foundation` or `points`; with `omega` (the reduction uses the contact
    /// frequency ω_c) also the slider's mass, the damper's mass and the contacts, and with
    /// `nonlinear` (a contact law of the model is not linear: its ω_c depends on the approach
    /// velocity, [`super::fem::contact_omega`]) the slider's velocity.
    fn structural(&self, omega: bool, nonlinear: bool) -> bool {
        match self.target {
            Target::Slider(k) => omega && (k == 0 || (k == 1 && nonlinear)),
            Target::Damper(k) => omega && k == 0,
            Target::Contact(..) => omega,
            Target::Sim(_) | Target::ProductionRate | Target::AddedMass(_) => false,
            _ => true,
        }
    }
}

/// A study's varied fields, compiled once on its base model ([`Model::compile_fields`]).
#[derive(Debug, Clone)]
pub struct CompiledFields {
    paths: Vec<String>,
    /// `None`: typed setters do not cover the path.
    setters: Vec<Option<FieldSetter>>,
    kinds: Vec<Option<SetterKind>>,
    /// Whether a point can have another structure than the base's.
    structural: bool,
    base_key: StructureKey,
}

impl CompiledFields {
    /// The kind of the `i`-th field, when typed setters cover it.
    pub fn kind(&self, i: usize) -> Option<SetterKind> {
        self.kinds.get(i).copied().flatten()
    }

    /// Whether every field has a typed setter.
    pub fn all_typed(&self) -> bool {
        self.setters.iter().all(Option::is_some)
    }

    /// The paths, in order.
    pub fn paths(&self) -> &[String] {
        &self.paths
    }

    /// The base model's [`StructureKey`].
    pub fn base_key(&self) -> StructureKey {
        self.base_key
    }
}

impl Model {
    /// Compiles `paths` on this model (module docs).
    pub fn compile_fields(&self, paths: &[&str]) -> CompiledFields {
        let setters: Vec<Option<FieldSetter>> = paths
            .iter()
            .map(|p| FieldSetter::compile(&self.spec, p))
            .collect();
        let kinds = setters
            .iter()
            .map(|s| s.as_ref().and_then(|s| s.kind(&self.spec)))
            .collect();
        let omega = uses_contact_omega(&self.spec.structure);
        let c = &self.spec.contact;
        let nonlinear = std::iter::once(&c.slider_bed)
            .chain(c.bed_damper.as_ref())
            .any(|c| c.law != LawSpec::Linear);
        // A varied contact law is structural itself (with omega), so the base's laws decide.
        let structural = setters
            .iter()
            .flatten()
            .any(|s| s.structural(omega, nonlinear));
        CompiledFields {
            paths: paths.iter().map(|p| p.trim().to_string()).collect(),
            setters,
            kinds,
            structural,
            base_key: self.structure_key(),
        }
    }

    /// This model with `values` set through the typed setters of `fields` (module docs):
    /// the model [`Model::with_fields`] gives for `PATH=LITERAL` ([`FieldValue::literal`]).
    /// `None` when a field has no typed setter, a value is not of its field's kind, or a check
    /// fails: the TOML route then gives the model or the error.
    pub fn with_values_typed(
        &self,
        fields: &CompiledFields,
        values: &[FieldValue],
        cache: Option<&StructureCache>,
    ) -> Option<Model> {
        if values.len() != fields.setters.len() {
            return None;
        }
        let mut spec = self.spec.clone();
        let mut source = self.source.clone();
        for (setter, v) in fields.setters.iter().zip(values) {
            let setter = setter.as_ref()?;
            setter.set(&mut spec, v)?;
            if let FieldValue::Real(x) = v {
                // A NaN or an infinity is left to the TOML route, which reads its literal
                // (`NaN` is not a TOML number, `inf` is) and checks it there.
                let a = x.abs();
                if !x.is_finite() || (a != 0.0 && !(MIN_MAGNITUDE..=MAX_MAGNITUDE).contains(&a)) {
                    return None;
                }
            }
            source.overrides.push((setter.path.clone(), v.literal()));
        }
        let structure = if fields.structural {
            let key = StructureKey::of(&spec, &source.name);
            self.structure_of_key(key, fields.base_key, &spec, &source, cache)
                .ok()?
        } else {
            self.structure.clone()
        };
        let model = Model {
            spec,
            structure,
            source,
            files: self.files.clone(),
        };
        model.validate_values().ok()?;
        Some(model)
    }

    /// [`Model::with_values_typed`], else the TOML route ([`Model::with_fields`] of
    /// `PATH=LITERAL`), which gives the model or the error.
    pub fn with_values(
        &self,
        fields: &CompiledFields,
        values: &[FieldValue],
        cache: Option<&StructureCache>,
    ) -> Result<Model> {
        if let Some(m) = self.with_values_typed(fields, values, cache) {
            return Ok(m);
        }
        let texts: Vec<String> = fields
            .paths
            .iter()
            .zip(values)
            .map(|(p, v)| format!("{p}={}", v.literal()))
            .collect();
        self.with_fields(&texts, cache)
    }
}
