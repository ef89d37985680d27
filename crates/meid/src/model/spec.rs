//! The model file schema (TOML). Units: see the table in [`super`].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::general::ConstraintSpec;
use super::material::MaterialSpec;

/// A whole model file.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelSpec {
    /// Free text shown in reports.
    #[serde(default)]
    pub name: Option<String>,
    pub structure: StructureSpec,
    pub points: PointsSpec,
    pub slider: SliderSpec,
    #[serde(default)]
    pub damper: Option<DamperSpec>,
    #[serde(default)]
    pub added_mass: Option<AddedMassSpec>,
    pub contact: ContactsSpec,
    #[serde(default)]
    pub simulation: SimulationSpec,
    /// `[production]`: how the machine runs in production (its stroke rate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub production: Option<ProductionSpec>,
    /// `[measurement]`: how measured channels map to meid's and how they are processed
    /// ([`crate::measure::mapping`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measurement: Option<crate::measure::mapping::MeasurementSpec>,
    /// `[foundation]`: the block on the soil under a lumped structure
    /// ([`super::foundation`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub foundation: Option<FoundationSpec>,
    /// `[[receiver]]`: where the ground vibration is checked ([`super::foundation`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub receiver: Vec<ReceiverSpec>,
}

/// The structure: exactly one of the forms.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct StructureSpec {
    /// The reference mode ω_ref of the ratios ω_s/ω_ref, ω_d/ω_ref (the paper's ω_6), by the
    /// structure's mode number (1-based, as `meid modes` lists every computed mode); it must be
    /// a retained mode. Not given: the retained mode with the largest effective modal mass
    /// along the blow ([`super::Model::reference_mode`]).
    #[serde(default)]
    pub reference_mode: Option<usize>,
    #[serde(default)]
    pub lumped: Option<LumpedSpec>,
    #[serde(default)]
    pub modal: Option<ModalSpec>,
    #[serde(default)]
    pub fem: Option<FemSpec>,
    /// `[structure.modes]`: modes read from a file another tool wrote (UFF 55 + 2411, CalculiX
    /// `.frd`; [`super::imported`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub modes: Option<ModesFileSpec>,
}

/// Point masses, springs and dashpots along z; modes from `K φ = ω² M φ`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LumpedSpec {
    pub masses: Vec<MassSpec>,
    #[serde(default)]
    pub springs: Vec<SpringSpec>,
    #[serde(default)]
    pub dashpots: Vec<DashpotSpec>,
    /// Modal damping ratio per mode (ascending frequency), or one value for all. Default 0.
    #[serde(default)]
    pub damping_ratios: Option<Ratios>,
    /// Names of springs/dashpots to ground whose forces make the force to the floor
    /// (default: every spring and dashpot attached to "ground").
    #[serde(default)]
    pub floor: Option<Vec<String>>,
}

/// One value or one per mode.
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(untagged)]
pub enum Ratios {
    All(f64),
    PerMode(Vec<f64>),
}

impl<'de> Deserialize<'de> for Ratios {
    /// A number or an array of numbers; anything else is refused in the model's terms
    /// ("expected a number (fraction of critical, e.g. 0.02) or a list of numbers, one per
    /// mode").
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Ratios;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(
                    "a number (fraction of critical, e.g. 0.02) or a list of numbers, one per mode",
                )
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Ratios, E> {
                Ok(Ratios::All(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Ratios, E> {
                Ok(Ratios::All(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Ratios, E> {
                Ok(Ratios::All(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Ratios, A::Error> {
                numbers(seq).map(Ratios::PerMode)
            }
        }
        d.deserialize_any(V)
    }
}

/// A number (a float or an integer, read as f64).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Number(pub f64);

impl<'de> Deserialize<'de> for Number {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Number;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a number")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Number, E> {
                Ok(Number(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Number, E> {
                Ok(Number(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Number, E> {
                Ok(Number(v as f64))
            }
        }
        d.deserialize_any(V)
    }
}

/// The numbers of an array (each element a number; see [`Number`]).
pub(crate) fn numbers<'de, A: serde::de::SeqAccess<'de>>(mut seq: A) -> Result<Vec<f64>, A::Error> {
    let mut out = Vec::new();
    while let Some(Number(x)) = seq.next_element()? {
        out.push(x);
    }
    Ok(out)
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MassSpec {
    pub name: String,
    /// kg.
    pub mass: f64,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpringSpec {
    #[serde(default)]
    pub name: Option<String>,
    /// Two mass names, or a mass name and "ground".
    pub nodes: [String; 2],
    /// N/m.
    pub stiffness: f64,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DashpotSpec {
    #[serde(default)]
    pub name: Option<String>,
    pub nodes: [String; 2],
    /// N·s/m.
    pub damping: f64,
}

/// Modes brought from elsewhere (another FE code, a modal test).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModalSpec {
    /// Natural frequencies (Hz), one per mode; 0 for rigid-body modes.
    pub frequencies_hz: Vec<f64>,
    #[serde(default)]
    pub damping_ratios: Option<Ratios>,
    /// Mass-normalised mode-shape values in z at named points: `name = [ψ_1, …, ψ_n]` (m/(kg^½·m)…
    /// i.e. displacement per unit modal coordinate, 1/√kg).
    pub shapes: BTreeMap<String, Vec<f64>>,
    /// Force to the floor per unit modal displacement (N) and velocity (N·s), per mode.
    #[serde(default)]
    pub floor_force: Option<FloorSpec>,
}

/// Modes imported from a file another tool wrote: an experimental modal analysis or an FE code
/// (UFF datasets 55 + 2411, CalculiX `.frd`). See [`super::imported`].
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModesFileSpec {
    /// The file, relative to the model file's directory: `.uff`/`.unv` (UFF) or `.frd`.
    pub file: String,
    /// `"uff"` or `"frd"`; default from the file's extension.
    #[serde(default)]
    pub format: Option<String>,
    /// meid point name → node label in the file: `{ O_b = 12, B = 7 }`.
    pub points: BTreeMap<String, i64>,
    /// The direction (in the file's axes) the slider moves when it strikes: meid's +z. The
    /// shape value at a point is `d · u(node)` with `d` this vector normalised. Default
    /// `[0, 0, -1]` (as `[structure.fem.model]`).
    #[serde(default)]
    pub impact_direction: Option<[f64; 3]>,
    /// States that the file's shapes are mass-normalised (ψᵀMψ = 1). Needed when the file gives
    /// no modal mass; refused when it gives one that is not 1.
    #[serde(default)]
    pub mass_normalised: Option<bool>,
    /// The file's mode numbers to keep (default: all).
    #[serde(default)]
    pub select: Option<Vec<i64>>,
    /// Keep only modes up to this frequency (Hz).
    #[serde(default)]
    pub max_hz: Option<f64>,
    /// Modal damping ratios, one for all or one per retained mode; default: the file's
    /// (UFF 55 record 8), else 0.
    #[serde(default)]
    pub damping_ratios: Option<Ratios>,
    /// The file's unit system: `"m-kg-s"` (default, SI) or `"mm-t-s"` (mm, tonne, s, N: a
    /// mass-normalised shape in mm/√t is `ψ · 1e-3/√1e3` in m/√kg).
    #[serde(default)]
    pub units: Option<String>,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FloorSpec {
    pub stiffness: Vec<f64>,
    #[serde(default)]
    pub damping: Option<Vec<f64>>,
}

/// Which structure points play which role.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PointsSpec {
    /// O_b: where the slider strikes and the damper touches.
    pub bed_contact: String,
    /// O_f: where the damper spring is anchored, or "ground". Default "ground".
    #[serde(default)]
    pub damper_anchor: Option<String>,
    /// B: the accelerometer point.
    pub measurement: String,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SliderSpec {
    /// m_s (kg).
    pub mass: f64,
    /// v_s (m/s), towards the bed.
    pub velocity: f64,
    /// F (N): a constant force on the slider from t = 0, positive towards the bed (its weight
    /// on a vertical hammer, a drive or air pressure). Default 0; must be finite and ≥ 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub force: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum DashpotKindSpec {
    #[default]
    OneWay,
    TwoWay,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DamperSpec {
    /// m_d (kg).
    pub mass: f64,
    /// k_d (N/m).
    pub stiffness: f64,
    /// c_d (N·s/m).
    #[serde(default)]
    pub damping: f64,
    /// "one-way" (paper Eq. 7, default) or "two-way".
    #[serde(default)]
    pub dashpot: DashpotKindSpec,
}

/// `[added_mass]`: a rigid mass fixed to a named point of the structure.
///
/// Without a `[damper]` it is the absorber of the model (`mass` required). With a `[damper]` it
/// only sets the "added mass" case of comparisons (`meid compare`, `--case added-mass`):
/// `mass` then defaults to the damper's mass m_d.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct AddedMassSpec {
    /// kg. Required without a `[damper]`; with one, default m_d.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// The named structure point the mass is fixed to (default `points.bed_contact`), e.g. the
    /// floating base (paper Figs. 10-11: "add a mass on the bed or floating base").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<String>,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ContactsSpec {
    pub slider_bed: ContactSpec,
    #[serde(default)]
    pub bed_damper: Option<ContactSpec>,
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum LawSpec {
    #[default]
    Linear,
    Hertz,
    HuntCrossley,
    /// Instantaneous impacts with Newton's restitution (general machines only).
    Rigid,
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ReleaseSpec {
    #[default]
    Force,
    Overlap,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// "linear" (default), "hertz" or "hunt-crossley".
    #[serde(default)]
    pub law: LawSpec,
    /// K: N/m (linear), N/m^1.5 (hertz), N/m^n (hunt-crossley).
    pub stiffness: f64,
    /// C (N·s/m), linear law only; default 0 (or set by `restitution`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// n of Hunt-Crossley (default 1.5).
    #[serde(default)]
    pub exponent: Option<f64>,
    /// α (s/m) of Hunt-Crossley; default 0 (or set by `restitution`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f64>,
    /// e ∈ (0, 1]: the coefficient of restitution of a free two-body impact through this
    /// contact, which sets C (linear) or α (hunt-crossley) instead of giving them
    /// ([`crate::impact::restitution`]; the masses and approach velocity used:
    /// [`super::Model::contact_setting`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restitution: Option<f64>,
    /// "force" (default: release when the force returns to zero) or "overlap" (Eqs. 5, 8).
    #[serde(default)]
    pub release: ReleaseSpec,
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum MethodSpec {
    #[default]
    Exact,
    Dopri5,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    #[serde(default)]
    pub method: MethodSpec,
    /// s.
    #[serde(default = "default_duration")]
    pub duration: f64,
    /// Hz.
    #[serde(default = "default_rate")]
    pub sample_rate: f64,
    #[serde(default = "default_rtol")]
    pub rtol: f64,
    #[serde(default = "default_atol")]
    pub atol: f64,
    /// Switching events a run may take before it stops with an error (chattering guard).
    #[serde(default = "default_max_events")]
    pub max_events: u64,
}

impl Default for SimulationSpec {
    fn default() -> Self {
        Self {
            method: MethodSpec::Exact,
            duration: default_duration(),
            sample_rate: default_rate(),
            rtol: default_rtol(),
            atol: default_atol(),
            max_events: default_max_events(),
        }
    }
}

/// `[production]`: the machine's operating condition in production.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProductionSpec {
    /// The stroke rate (blows per minute): blows repeated every `60 / rate_bpm` s. With it,
    /// `meid blows`, `compare`, `optimize` and `report` judge the damper on the periodic
    /// steady blow at this rate (a command's `--rate-bpm` overrides it).
    pub rate_bpm: f64,
}

fn default_duration() -> f64 {
    0.5
}
fn default_rate() -> f64 {
    20_000.0
}
fn default_rtol() -> f64 {
    1e-8
}
fn default_atol() -> f64 {
    1e-14
}
fn default_max_events() -> u64 {
    crate::integrate::DEFAULT_MAX_EVENTS as u64
}

/// `[structure.fem]`: the parametric machine or a Gmsh mesh, reduced to selected modes.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct FemSpec {
    /// The parametric machine (paper Fig. 1).
    #[serde(default)]
    pub machine: Option<MachineFileSpec>,
    /// A Gmsh `.msh` 4.1 quad mesh.
    #[serde(default)]
    pub mesh: Option<MeshFileSpec>,
    /// The general model (nodes, shells, frames, discrete elements, constraints).
    #[serde(default)]
    pub model: Option<super::general::GeneralSpec>,
    /// Mode selection: "auto" (default, module docs), "participation", a list of 1-based mode
    /// numbers, or `{ band_hz = [lo, hi] }`.
    #[serde(default)]
    pub select: Option<SelectSpec>,
    /// "auto": most modes added above the cutoff (default no limit); "participation": modes
    /// kept (default 2).
    #[serde(default)]
    pub auto_count: Option<usize>,
    /// "auto": the cutoff (Hz; default 3 × the highest contact frequency); "participation":
    /// the highest frequency considered (default: all computed modes).
    #[serde(default)]
    pub auto_max_hz: Option<f64>,
    /// Points whose motion ranks modes (default: the model's O_b, O_f and B, those in the mesh).
    #[serde(default)]
    pub contact_points: Option<Vec<String>>,
    /// Modal damping ratio, one value or one per selected mode (default 0).
    #[serde(default)]
    pub damping_ratios: Option<Ratios>,
    /// Rayleigh damping `[alpha (1/s), beta (s)]`: `D_ii = α + β ω_i²`.
    #[serde(default)]
    pub rayleigh: Option<[f64; 2]>,
    /// "dense" or "lanczos"; default dense below 1000 DOF.
    #[serde(default)]
    pub solver: Option<SolverSpec>,
    /// Number of lowest modes computed (default 30; all for dense if fewer DOFs).
    #[serde(default)]
    pub count: Option<usize>,
    /// Static correction (default true): the selected modes plus pseudo-modes that restore the
    /// full static flexibility at the named points ([`crate::modal::static_correction`]).
    #[serde(default)]
    pub static_correction: Option<bool>,
}

/// Mode selection.
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(untagged)]
pub enum SelectSpec {
    /// "auto".
    Keyword(String),
    /// 1-based mode numbers.
    Indices(Vec<usize>),
    /// `{ band_hz = [lo, hi] }`.
    Band { band_hz: [f64; 2] },
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SolverSpec {
    Dense,
    Lanczos,
}

/// A rectangular plate centred on the z axis (m).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PlateFileSpec {
    pub length_x: f64,
    pub length_y: f64,
    pub thickness: f64,
    #[serde(default)]
    pub material: Option<MaterialSpec>,
}

/// Column cross-section (m, m², m⁴): a solid circle, a tube, a solid rectangle, or given values.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct SectionFileSpec {
    #[serde(default)]
    pub diameter: Option<f64>,
    /// Tube wall (with `diameter`).
    #[serde(default)]
    pub wall: Option<f64>,
    #[serde(default)]
    pub width: Option<f64>,
    #[serde(default)]
    pub depth: Option<f64>,
    #[serde(default)]
    pub area: Option<f64>,
    #[serde(default)]
    pub iy: Option<f64>,
    #[serde(default)]
    pub iz: Option<f64>,
    #[serde(default)]
    pub j: Option<f64>,
}

impl<'de> Deserialize<'de> for SelectSpec {
    /// A keyword, a list of mode numbers or `{ band_hz = [lo, hi] }`; anything else is refused
    /// naming the three forms.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = SelectSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(
                    "\"auto\", \"participation\", a list of 1-based mode numbers (e.g. [6, 10]) or { band_hz = [lo, hi] }",
                )
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<SelectSpec, E> {
                Ok(SelectSpec::Keyword(v.to_string()))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<SelectSpec, A::Error> {
                let mut out = Vec::new();
                while let Some(i) = seq.next_element::<usize>()? {
                    out.push(i);
                }
                Ok(SelectSpec::Indices(out))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<SelectSpec, A::Error> {
                #[derive(Deserialize)]
                #[serde(deny_unknown_fields)]
                struct Band {
                    band_hz: [f64; 2],
                }
                let b = Band::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(SelectSpec::Band { band_hz: b.band_hz })
            }
        }
        d.deserialize_any(V)
    }
}

/// One value for x, y, z or three.
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(untagged)]
pub enum PerDirection {
    All(f64),
    Xyz([f64; 3]),
}

impl<'de> Deserialize<'de> for PerDirection {
    /// A number or `[x, y, z]` (exactly three numbers).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = PerDirection;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a number (the same for x, y and z) or [x, y, z] (three numbers)")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<PerDirection, E> {
                Ok(PerDirection::All(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<PerDirection, E> {
                Ok(PerDirection::All(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<PerDirection, E> {
                Ok(PerDirection::All(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                seq: A,
            ) -> Result<PerDirection, A::Error> {
                let v = super::spec::numbers(seq)?;
                match v[..] {
                    [x, y, z] => Ok(PerDirection::Xyz([x, y, z])),
                    _ => Err(serde::de::Error::invalid_length(
                        v.len(),
                        &"[x, y, z] (exactly three numbers)",
                    )),
                }
            }
        }
        d.deserialize_any(V)
    }
}

impl PerDirection {
    /// The values along x, y and z (one value for all three when one is given).
    pub(crate) fn xyz(&self) -> [f64; 3] {
        match self {
            PerDirection::All(v) => [*v; 3],
            PerDirection::Xyz(v) => *v,
        }
    }
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SupportSpec {
    FloatingBase,
    FixedColumns,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AddedMassFileSpec {
    /// "bed" or "base".
    pub plate: String,
    /// From the plate centre (m).
    pub offset: [f64; 2],
    /// kg.
    pub mass: f64,
    /// `[Ixx, Iyy, Izz]` (kg·m²).
    #[serde(default)]
    pub inertia: Option<[f64; 3]>,
}

/// `[structure.fem.machine]`: parameters of [`MachineSpec`]; omitted ones keep its defaults.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct MachineFileSpec {
    #[serde(default)]
    pub elements_per_side: Option<usize>,
    #[serde(default)]
    pub material: Option<MaterialSpec>,
    #[serde(default)]
    pub bed: Option<PlateFileSpec>,
    #[serde(default)]
    pub column: Option<SectionFileSpec>,
    #[serde(default)]
    pub column_material: Option<MaterialSpec>,
    /// m.
    #[serde(default)]
    pub column_length: Option<f64>,
    /// m from the bed edges.
    #[serde(default)]
    pub column_inset: Option<f64>,
    #[serde(default)]
    pub column_elements: Option<usize>,
    #[serde(default)]
    pub support: Option<SupportSpec>,
    #[serde(default)]
    pub base: Option<PlateFileSpec>,
    /// N/m per spring, one value or `[x, y, z]`.
    #[serde(default)]
    pub spring_stiffness: Option<PerDirection>,
    /// N·s/m per spring.
    #[serde(default)]
    pub spring_damping: Option<PerDirection>,
    /// m from the base edges.
    #[serde(default)]
    pub spring_inset: Option<f64>,
    /// Accelerometer B from the bed centre (m).
    #[serde(default)]
    pub b_offset: Option<[f64; 2]>,
    /// Further named points on the bed, `name = [x, y]` from the bed centre (m): strike points
    /// and damper points of a general machine ([[impactor]], [[damper]], [[contact]]).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub bed_points: BTreeMap<String, [f64; 2]>,
    #[serde(default)]
    pub added_masses: Vec<AddedMassFileSpec>,
    #[serde(default)]
    pub spiders: Option<bool>,
    /// Half-size of the square column footprint tied rigidly to each plate (m, default 0.02).
    #[serde(default)]
    pub spider_half_size: Option<f64>,
}

/// `[structure.fem.mesh]`: a Gmsh quad mesh (shells of one thickness and material).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshFileSpec {
    /// `.msh` path, relative to the model file's directory.
    pub file: String,
    /// m.
    pub thickness: f64,
    #[serde(default)]
    pub material: Option<MaterialSpec>,
    /// Model point name → physical group name (e.g. `O_b = "contact"`); groups keep their own
    /// names as well.
    #[serde(default)]
    pub points: BTreeMap<String, String>,
    /// Physical groups clamped (all six DOFs); the floor force is their reaction.
    #[serde(default)]
    pub fixed: Vec<String>,
    /// Constraints on a subset of DOFs: `{ set = "edges", dofs = ["uz"] }` (a hard simple
    /// support); the floor force includes their reactions.
    #[serde(default)]
    pub constraints: Vec<ConstraintSpec>,
    /// Springs to ground at every node of a group: `{ group = "feet", stiffness = [kx, ky, kz] }`.
    #[serde(default)]
    pub springs: Vec<GroupSpringSpec>,
    /// Impact direction (unit vector the slider moves along); default `[0, 0, -1]`.
    #[serde(default)]
    pub impact_direction: Option<[f64; 3]>,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GroupSpringSpec {
    pub group: String,
    /// N/m per node.
    pub stiffness: PerDirection,
    /// N·s/m per node.
    #[serde(default)]
    pub damping: Option<PerDirection>,
}

/// `[foundation]`: the block on the soil ([`super::foundation`], docs/explanations/foundation.md).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FoundationSpec {
    /// The lumped mass that rests on the soil.
    pub mass: String,
    /// L (m), plan dimension along which the block rocks in [`Impedances::rocking`].
    pub length: f64,
    /// B (m).
    pub width: f64,
    /// h (m): needed for the block's volume (`block_density`), its rocking inertia and an
    /// embedment.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
    /// D (m), 0 ≤ D ≤ h. Default 0 (a surface footing).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub embedment: Option<f64>,
    /// kg, added to `mass`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub block_mass: Option<f64>,
    /// kg/m³: the block's mass is `block_density · L B h`, added to `mass`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub block_density: Option<f64>,
    pub soil: SoilSpec,
    /// How ground vibration decays with distance (Bornitz).
    #[serde(default)]
    pub ground: GroundSpec,
    /// `"long-term"` or `"short-term"` (an occasional blow): which DIN 4150-3 limits apply.
    /// Not given: long-term, because of the model's `[production] rate_bpm` (repeated blows)
    /// or, without one, as the conservative choice ([`super::foundation::excitation_of`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub excitation: Option<Excitation>,
    /// The lumped mass that is the anvil (for the anvil-amplitude check).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anvil: Option<String>,
    /// The elastic pad under the anvil (for the pad-stress check).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pad: Option<PadSpec>,
    /// Allowable values of the foundation checks; a check without one is not applicable.
    #[serde(default)]
    pub allowable: AllowableSpec,
}

/// `[foundation.soil]` (module docs): exactly one of the three forms.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct SoilSpec {
    /// G (Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_modulus: Option<f64>,
    /// V_s (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_wave_velocity: Option<f64>,
    /// ν.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson: Option<f64>,
    /// ρ (kg/m³).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<f64>,
    /// D_m (fraction of critical), default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material_damping: Option<f64>,
    /// Whether the half-space's radiation dashpot c_z acts (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radiation_damping: Option<bool>,
    /// C_u (N/m³), IS 2974.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uniform_compression: Option<f64>,
    /// k_z (N/m) given directly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness_z: Option<f64>,
    /// c_z (N·s/m) given directly (with `stiffness_z` or `uniform_compression`), default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping_z: Option<f64>,
}

/// `[foundation.ground]`: the Bornitz attenuation `v(r) = v(r1) (r1/r)^n e^{−α (r − r1)}`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct GroundSpec {
    /// n: 0.5 for surface (Rayleigh) waves (default), 1 for body waves, 2 for body waves along
    /// the surface.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub geometric_exponent: Option<f64>,
    /// α (1/m), default 0 (no material attenuation: the largest ground vibration).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attenuation: Option<f64>,
}

/// DIN 4150-3's classes of excitation.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Excitation {
    #[default]
    LongTerm,
    ShortTerm,
}

/// `[foundation.pad]`: the spring of the lumped structure that is the elastic pad, and its area.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PadSpec {
    /// The name of a `structure.lumped.springs` entry.
    pub spring: String,
    /// m².
    pub area: f64,
}

/// `[foundation.allowable]`: the limits of the foundation checks (SI units).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct AllowableSpec {
    /// Peak displacement of the block (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub block_amplitude: Option<f64>,
    /// Peak displacement of the anvil (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anvil_amplitude: Option<f64>,
    /// Peak compressive stress in the pad (Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pad_stress: Option<f64>,
    /// Static + dynamic soil pressure under the block (Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub soil_pressure: Option<f64>,
}

/// `[[receiver]]`: where the ground vibration is checked ([`super::foundation`]).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ReceiverSpec {
    pub name: String,
    /// r (m) from the block's centre.
    pub distance: f64,
    /// `"industrial"`, `"residential"` or `"sensitive"` (DIN 4150-3 lines 1, 2, 3).
    pub building: String,
    /// What the people there do (a label, e.g. "residential, night").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
    /// The limit (m/s²) of the largest 1 s running r.m.s. of the W_m-weighted acceleration.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub people_limit: Option<f64>,
}
