//! `[structure.modes]`: a structure's modes read from a file another tool wrote, an FE code
//! (CalculiX `.frd`, any code's UFF export) or an experimental modal analysis (UFF datasets 55
//! with 2411), mapped to meid's named points. Every study then runs on them as on any
//! [`ModalModel`].
//!
//! ```toml
//! [structure.modes]
//! file = "beam.frd"               # or "test.uff" / ".unv" (datasets 2411 + 55)
//! points = { O_b = 62, B = 52 }   # meid point → node label in the file
//! impact_direction = [0, 0, -1]   # the slider's direction in the file's axes (meid's +z)
//! mass_normalised = true          # only needed when the file gives no modal masses
//! ```
//!
//! # What is read
//!
//! For each mode `k` of the file: the frequency `f_k` (Hz), the modal mass `m_k` (UFF 55
//! record 8; `.frd` `1PGM`, the generalised mass φᵀMφ), the damping ratio (UFF 55) and the
//! nodal translations `u_k(node)`. The value of the shape at a point `P` mapped to `node` is
//!
//! ```text
//! ψ_k(P) = s · (d · u_k(node)) / √m_k,     d = impact_direction / |impact_direction|
//! ```
//!
//! with `s = 1` for a file in m, kg, s and `s = 1e-3/√1e3` for one in mm, tonne, s
//! (`units = "mm-t-s"`, or the file's dataset 164: a displacement in mm per √t is 1e-3 m per
//! √(1e3 kg)). Dividing by
//! `√m_k` makes the shapes mass-normalised, `ψ_kᵀ M ψ_k = 1`, which is what paper Eq. 9
//! and every meid study assume.
//!
//! # Mass normalisation: checked, never assumed silently
//!
//! * The file gives `m_k > 0` for every kept mode: the shapes are divided by `√m_k`; when a
//!   `m_k` differs from 1 a note says so, with the range of the modal masses.
//!   `mass_normalised = true` with a `m_k` more than [`MASS_TOLERANCE`] away from 1 is refused
//!   (the file and the model contradict each other).
//! * The file gives no modal mass (UFF 55 writes 0 or nothing usable, a `.frd` without
//!   `1PGM`): refused, unless `mass_normalised = true` states that the shapes are
//!   mass-normalised; a note then records that assumption.
//!
//! # Units
//!
//! A UFF file may declare its unit system (dataset 164: length and force factors to SI, time
//! in s, so the mass factor is force/length, [`uff::Units`]). The shapes are then converted
//! from the file's length per √(file mass) to m/√kg, `s = √(mass factor) / length factor`,
//! and a note says so. `units` in the model is checked against it: a contradiction (e.g.
//! `units = "mm-t-s"` for a file whose dataset 164 says SI) is refused, and so is a file whose
//! modes follow different datasets 164. A `.frd` file, or a UFF file without dataset 164,
//! carries no units: they are SI unless `units = "mm-t-s"`. The force to the floor and the static flexibility are not in the
//! files either: an imported model has no floor force and no truncation table (unknown
//! flexibility).

use std::path::{Path, PathBuf};

use super::source::Source;
use super::spec::ModesFileSpec;
use crate::io::{frd, uff};
use crate::modal::ModalModel;
use crate::{Error, Result};

/// The section of the model file the imported modes come from (errors name its fields).
const BASE: &str = "structure.modes";

/// How far from 1 (relative) a modal mass the file gives may be while
/// `mass_normalised = true` (UFF 55 writes 6 significant digits).
pub const MASS_TOLERANCE: f64 = 1e-4;

/// Relative frequency difference under which two modes of a file share one eigenvalue: the
/// file's own precision (UFF 55 writes frequencies with 6 significant digits, E13.5).
pub const REPEATED_TOLERANCE: f64 = 1e-5;

/// One mode as a file gives it, in the file's units.
#[derive(Debug, Clone, PartialEq)]
pub struct FileMode {
    /// The file's mode number.
    pub number: i64,
    /// Hz.
    pub frequency_hz: f64,
    /// The modal (generalised) mass `φᵀMφ`, when the file gives a usable one (finite, > 0).
    pub modal_mass: Option<f64>,
    /// Viscous damping ratio, when the file gives one.
    pub damping_ratio: Option<f64>,
    /// `(node label, [ux, uy, uz])`.
    pub shapes: Vec<(i64, [f64; 3])>,
    /// The unit system the file declares for this mode (UFF dataset 164), if any.
    pub units: Option<uff::Units>,
}

/// The modes of a UFF file's datasets 55 (real normal modes). A modal mass of 0 (or not
/// finite and positive) counts as none.
pub fn modes_from_uff(f: &uff::UffFile) -> Vec<FileMode> {
    f.modes
        .iter()
        .map(|m| FileMode {
            number: m.number,
            frequency_hz: m.frequency_hz,
            modal_mass: (m.modal_mass.is_finite() && m.modal_mass > 0.0).then_some(m.modal_mass),
            damping_ratio: m.damping_ratio.is_finite().then_some(m.damping_ratio),
            shapes: m.shapes.clone(),
            units: m.units.clone(),
        })
        .collect()
}

/// The modes of a `.frd` file's frequency steps.
pub fn modes_from_frd(f: &frd::FrdFile) -> Vec<FileMode> {
    f.modes
        .iter()
        .map(|m| FileMode {
            number: m.number,
            frequency_hz: m.frequency_hz,
            modal_mass: m.generalised_mass.filter(|g| g.is_finite() && *g > 0.0),
            damping_ratio: None,
            shapes: m.displacements.clone(),
            units: None,
        })
        .collect()
}

/// The file's format: `format`, else the extension.
fn format_of(spec: &ModesFileSpec, path: &Path, src: &Source) -> Result<&'static str> {
    let given = match &spec.format {
        Some(f) => f.to_ascii_lowercase(),
        None => path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default(),
    };
    match given.as_str() {
        "uff" | "unv" | "uf" => Ok("uff"),
        "frd" => Ok("frd"),
        other => Err(src.error(
            if spec.format.is_some() {
                "structure.modes.format"
            } else {
                "structure.modes.file"
            },
            format!(
                "{BASE}: cannot tell the format of '{}' ('{other}'): give a .uff/.unv (UFF datasets 2411 + 55) or .frd (CalculiX) file, or format = \"uff\" or \"frd\"",
                spec.file
            ),
        )),
    }
}

/// How many times lighter than the slider the structure's effective mass at the struck point
/// may be before an import whose file does not state its units is warned about: a file in
/// mm-t-s read as SI makes every effective mass 1e9 times too small (a 10 kg bed struck by a
/// 1.2 kg slider, ratio 0.12, reads as 1.2e8).
pub const UNIT_SUSPICION_RATIO: f64 = 1e6;

/// The warning for imported modes whose units nothing states (`structure.unstated_units`)
/// when they make the struck point's effective mass `1/Σ_k ψ_k(P)²` more than
/// [`UNIT_SUSPICION_RATIO`] times lighter than the slider (`slider_mass_kg`, striking `point`).
pub fn unit_suspicion(structure: &ModalModel, slider_mass_kg: f64, point: &str) -> Option<String> {
    let file = structure.unstated_units.as_ref()?;
    let s2: f64 = structure
        .points
        .get(point)
        .map_or(0.0, |psi| psi.iter().map(|v| v * v).sum());
    let ratio = slider_mass_kg * s2;
    (s2 > 0.0 && ratio > UNIT_SUSPICION_RATIO).then(|| {
        format!(
            "structure.modes: the modes of {file} give the struck point '{point}' an effective mass 1/Σψ² = {:.4e} kg, {ratio:.3e} times lighter than the {} kg slider, and neither the file (no UFF dataset 164) nor the model (structure.modes.units) states their units: a file in mm-t-s read as SI has every effective mass 1e9 times too small. If the FE model was in mm, tonne, s, give units = \"mm-t-s\"",
            1.0 / s2,
            crate::num(slider_mass_kg)
        )
    })
}

/// Reads `[structure.modes]`'s file (relative to the model file) and builds the modal model.
pub fn modal_model(spec: &ModesFileSpec, src: &Source) -> Result<ModalModel> {
    let dir = Path::new(&src.name)
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let path: PathBuf = dir.join(&spec.file);
    let format = format_of(spec, &path, src)?;
    if !path.is_file() {
        return Err(src.error(
            "structure.modes.file",
            format!(
                "structure.modes.file: {} is not a file (the path is relative to the model file's directory)",
                path.display()
            ),
        ));
    }
    let (modes, skipped) = match format {
        "frd" => {
            let f = frd::read_frd(&path)?;
            (modes_from_frd(&f), f.skipped)
        }
        _ => {
            let f = uff::read_uff(&path)?;
            (modes_from_uff(&f), f.skipped)
        }
    };
    if modes.is_empty() {
        let what = if format == "frd" {
            "no DISP results of a frequency step (*FREQUENCY with *NODE FILE U)"
        } else {
            "no dataset 55 with real normal modes (analysis type 2)"
        };
        let mut msg = format!("structure.modes.file: {} holds {what}", path.display());
        if !skipped.is_empty() {
            msg.push_str(&format!("; passed over: {}", skipped.join("; ")));
        }
        return Err(src.error("structure.modes.file", msg));
    }
    build(&modes, spec, &path.display().to_string(), src)
}

/// The unit system of an import: where it came from and what it does to the shapes.
struct UnitChoice {
    /// From the file's shape units (length per √mass) to m/√kg.
    scale: f64,
    /// Where the units came from, when they are not SI.
    note: Option<String>,
    /// `units` in the model or a dataset 164 in the file says what they are (else: read as SI).
    stated: bool,
}

/// The units of an import: `units` in the model, else the file's dataset 164, else SI. A
/// `units` that contradicts the file's dataset 164, or modes of one file under different
/// datasets 164, are refused.
fn unit_scale(
    modes: &[FileMode],
    spec: &ModesFileSpec,
    file: &str,
    src: &Source,
) -> Result<UnitChoice> {
    let given = match spec.units.as_deref() {
        None => None,
        Some("m-kg-s") | Some("SI") => Some(uff::Units::si()),
        Some("mm-t-s") => Some(uff::Units {
            code: 9,
            description: "mm-t-s".into(),
            length: 1e3,
            force: 1.0,
        }),
        Some(other) => {
            return Err(src.error(
                &format!("{BASE}.units"),
                format!("{BASE}.units: unknown unit system '{other}'; valid: \"m-kg-s\" (SI, default), \"mm-t-s\" (mm, tonne, s, N); leave it out to use the file's dataset 164"),
            ))
        }
    };
    if let Some(m) = modes
        .iter()
        .find(|m| m.units.as_ref().is_some_and(|u| !u.known()))
    {
        return Err(src.error(
            &format!("{BASE}.file"),
            format!(
                "{file}: mode {} follows the {}, which meid could not read, so its units are unknown: correct that dataset 164 (records 1-2: unit code, then length, force and temperature factors), or remove it and give {BASE}.units",
                m.number,
                m.units.as_ref().map_or(String::new(), |u| u.description.clone())
            ),
        ));
    }
    // The file's: one unit system for all its modes (a mode before any dataset 164 is SI).
    let declared = modes.iter().find_map(|m| m.units.as_ref().map(|u| (m, u)));
    if let Some((first, fu)) = declared {
        let si = uff::Units::si();
        if let Some(m) = modes
            .iter()
            .find(|m| !fu.same_factors(m.units.as_ref().unwrap_or(&si)))
        {
            let describe = |u: Option<&uff::Units>| {
                u.map_or("no dataset 164 (SI)".to_string(), uff::Units::describe)
            };
            return Err(src.error(
                &format!("{BASE}.file"),
                format!(
                    "{file}: mode {} follows {} and mode {} {}: meid reads one unit system per file; export all modes in one",
                    first.number,
                    describe(Some(fu)),
                    m.number,
                    describe(m.units.as_ref())
                ),
            ));
        }
    }
    let from_file = declared.map(|(_, u)| u);
    let stated = given.is_some() || from_file.is_some();
    let (units, whence) = match (given, from_file) {
        (Some(g), Some(f)) if !g.same_factors(f) => {
            return Err(src.error(
                &format!("{BASE}.units"),
                format!(
                    "{BASE}.units = \"{}\" (length factor {}, force factor {} per SI unit) contradicts {file}'s {}: leave units out to use the file's, or correct the file",
                    spec.units.as_deref().unwrap_or(""),
                    crate::num(g.length),
                    crate::num(g.force),
                    f.describe()
                ),
            ))
        }
        (Some(g), _) => (
            g,
            format!("{BASE}.units = \"{}\"", spec.units.as_deref().unwrap_or("")),
        ),
        (None, Some(f)) => (f.clone(), format!("{file}'s {}", f.describe())),
        (None, None) => (uff::Units::si(), String::new()),
    };
    // ψ in file length per √(file mass): ψ_SI = ψ · √(mass factor) / length factor.
    let scale = units.mass().sqrt() / units.length;
    let note = (scale != 1.0).then(|| {
        format!(
            "{BASE}: shapes converted from the file's units to m/√kg (× {scale:e}), as {whence} says"
        )
    });
    Ok(UnitChoice {
        scale,
        note,
        stated,
    })
}

/// The modal model of `modes` (read from `file`) as `spec` maps them (module docs). When
/// neither the model (`units`) nor the file (UFF dataset 164) states the units, its
/// `unstated_units` names the file ([`unit_suspicion`]).
pub fn build(
    modes: &[FileMode],
    spec: &ModesFileSpec,
    file: &str,
    src: &Source,
) -> Result<ModalModel> {
    // Unit system (module docs): `units`, else the file's dataset 164, else SI.
    let units = unit_scale(modes, spec, file, src)?;
    let scale = units.scale;
    let d = impact_direction(spec, src)?;
    if spec.points.is_empty() {
        return Err(src.error(
            &format!("{BASE}.points"),
            format!("{BASE}.points: map meid's points to node labels of the file, e.g. points = {{ O_b = 12, B = 7 }}"),
        ));
    }
    let mut kept = kept_modes(modes, spec, file, src)?;
    let mut notes = Vec::new();
    if kept
        .windows(2)
        .any(|w| w[1].frequency_hz < w[0].frequency_hz)
    {
        kept.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
        notes.push(format!(
            "{BASE}: the modes of {file} were not in ascending frequency; meid sorted them"
        ));
    }
    let n = kept.len();
    let divisor = mass_divisors(&kept, spec, file, src, &mut notes)?;
    notes.extend(units.note);
    let zeta = damping_ratios(&kept, spec, file, src, &mut notes)?;
    let omega: Vec<f64> = kept
        .iter()
        .map(|m| 2.0 * std::f64::consts::PI * m.frequency_hz)
        .collect();
    let mut model = ModalModel::with_damping_ratios(omega, &zeta)?;
    model.unstated_units = (!units.stated).then(|| file.to_string());
    // Shapes at the points.
    for (point, node) in &spec.points {
        let shape = Shape {
            scale,
            direction: d,
            divisor: &divisor,
        };
        let values = point_shape(&kept, point, *node, &shape, file, src)?;
        model.points.insert(point.clone(), values);
    }
    model.labels = kept
        .iter()
        .map(|m| format!("mode {} ({:.4} Hz)", m.number, m.frequency_hz))
        .collect();
    model.mode_numbers = kept
        .iter()
        .map(|m| usize::try_from(m.number).unwrap_or(0))
        .collect();
    notes.insert(
        0,
        format!(
            "{BASE}: {n} modes ({:.4} to {:.4} Hz) from {file}",
            kept[0].frequency_hz,
            kept[n - 1].frequency_hz
        ),
    );
    model.notes = notes;
    model.warnings.extend(repeated_warnings(modes, &kept, file));
    model.validate().map_err(|e| match e {
        Error::InvalidValue { field, message } => {
            src.error(BASE, format!("{BASE}: {field}: {message}"))
        }
        other => other,
    })?;
    Ok(model)
}

/// The unit impact direction `d/|d|` (default `[0, 0, −1]`); a zero or non-finite vector is
/// refused.
fn impact_direction(spec: &ModesFileSpec, src: &Source) -> Result<[f64; 3]> {
    let d = spec.impact_direction.unwrap_or([0.0, 0.0, -1.0]);
    let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(src.error(
            &format!("{BASE}.impact_direction"),
            format!(
                "{BASE}.impact_direction: must be a nonzero finite vector [x, y, z] (got {d:?})"
            ),
        ));
    }
    Ok([d[0] / norm, d[1] / norm, d[2] / norm])
}

/// The file's modes the model keeps: `select` (file mode numbers, in its order, none twice),
/// then those up to `max_hz`; at least one, each with a finite frequency ≥ 0 Hz.
fn kept_modes<'a>(
    modes: &'a [FileMode],
    spec: &ModesFileSpec,
    file: &str,
    src: &Source,
) -> Result<Vec<&'a FileMode>> {
    let mut kept: Vec<&FileMode> = match &spec.select {
        None => modes.iter().collect(),
        Some(sel) => {
            let mut out = Vec::new();
            for (i, n) in sel.iter().enumerate() {
                if sel[..i].contains(n) {
                    return Err(src.error(
                        &format!("{BASE}.select"),
                        format!("{BASE}.select: mode {n} is given twice"),
                    ));
                }
                match modes.iter().find(|m| m.number == *n) {
                    Some(m) => out.push(m),
                    None => {
                        let numbers: Vec<String> =
                            modes.iter().map(|m| m.number.to_string()).collect();
                        return Err(src.error(
                            &format!("{BASE}.select"),
                            format!(
                                "{BASE}.select: {file} has no mode {n}; its modes: {}",
                                numbers.join(", ")
                            ),
                        ));
                    }
                }
            }
            out
        }
    };
    if let Some(max) = spec.max_hz {
        if !(max.is_finite() && max > 0.0) {
            return Err(src.error(
                &format!("{BASE}.max_hz"),
                format!(
                    "{BASE}.max_hz: must be a finite number > 0 Hz (got {})",
                    crate::num(max)
                ),
            ));
        }
        kept.retain(|m| m.frequency_hz <= max);
    }
    if kept.is_empty() {
        return Err(src.error(
            BASE,
            format!("{BASE}: no mode of {file} is kept by select/max_hz"),
        ));
    }
    for m in &kept {
        if !(m.frequency_hz.is_finite() && m.frequency_hz >= 0.0) {
            return Err(src.error(
                &format!("{BASE}.file"),
                format!(
                    "{file}: mode {} has the frequency {} Hz: meid needs finite frequencies >= 0 (leave it out with {BASE}.select or max_hz)",
                    m.number, m.frequency_hz
                ),
            ));
        }
    }
    Ok(kept)
}

/// Mass normalisation (module docs): the divisor √(modal mass) of each kept mode's shape, 1
/// for a mode without modal mass when `mass_normalised = true` states it; notes what was
/// assumed and what was divided.
fn mass_divisors(
    kept: &[&FileMode],
    spec: &ModesFileSpec,
    file: &str,
    src: &Source,
    notes: &mut Vec<String>,
) -> Result<Vec<f64>> {
    let mut divisor = Vec::with_capacity(kept.len());
    let mut assumed = Vec::new();
    for m in kept {
        match (m.modal_mass, spec.mass_normalised) {
            (Some(mm), Some(true)) if (mm - 1.0).abs() > MASS_TOLERANCE => {
                return Err(src.error(
                    &format!("{BASE}.mass_normalised"),
                    format!(
                        "{BASE}.mass_normalised = true, but {file} gives mode {} the modal mass {mm:e} (not 1 within {MASS_TOLERANCE:e}): remove mass_normalised and meid divides the shapes by √(modal mass)",
                        m.number
                    ),
                ));
            }
            (Some(mm), _) => divisor.push(mm.sqrt()),
            (None, Some(true)) => {
                assumed.push(m.number.to_string());
                divisor.push(1.0);
            }
            (None, _) => {
                return Err(src.error(
                    &format!("{BASE}.mass_normalised"),
                    format!(
                        "{file}: mode {} has no modal mass (UFF 55 record 8 gives 0, or a .frd step has no 1PGM), so meid cannot check that its shapes are mass-normalised (ψᵀMψ = 1): give {BASE}.mass_normalised = true if they are, or export the modes with their modal masses",
                        m.number
                    ),
                ));
            }
        }
    }
    if !assumed.is_empty() {
        notes.push(format!(
            "{BASE}: {file} gives no modal mass for mode(s) {}: their shapes are taken as mass-normalised, as {BASE}.mass_normalised = true states",
            assumed.join(", ")
        ));
    }
    let masses: Vec<f64> = kept.iter().filter_map(|m| m.modal_mass).collect();
    if masses.iter().any(|mm| *mm != 1.0) {
        let lo = masses.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = masses.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        notes.push(format!(
            "{BASE}: shapes divided by √(modal mass) given in {file} (modal masses {lo:e} to {hi:e}) to make them mass-normalised"
        ));
    }
    Ok(divisor)
}

/// The modal damping ratios ζ: `damping_ratios` as given, else the file's (UFF 55 record 8;
/// 0 where it has none), each in [0, 1).
fn damping_ratios(
    kept: &[&FileMode],
    spec: &ModesFileSpec,
    file: &str,
    src: &Source,
    notes: &mut Vec<String>,
) -> Result<Vec<f64>> {
    if spec.damping_ratios.is_some() {
        return super::lumped::ratios(
            &spec.damping_ratios,
            kept.len(),
            &format!("{BASE}.damping_ratios"),
            src,
        );
    }
    let z: Vec<f64> = kept
        .iter()
        .map(|m| m.damping_ratio.unwrap_or(0.0))
        .collect();
    if let Some((m, z)) = kept
        .iter()
        .zip(&z)
        .find(|(_, z)| !(z.is_finite() && **z >= 0.0 && **z < 1.0))
    {
        return Err(src.error(
            &format!("{BASE}.damping_ratios"),
            format!(
                "{file}: mode {} has the damping ratio {z}, outside [0, 1): give {BASE}.damping_ratios",
                m.number
            ),
        ));
    }
    if z.iter().any(|z| *z > 0.0) {
        notes.push(format!(
            "{BASE}: modal damping ratios from {file} (UFF 55 record 8)"
        ));
    }
    Ok(z)
}

/// How a file shape becomes a modal coordinate value: ψ_SI = `scale` · (d · u) / `divisor[k]`.
struct Shape<'a> {
    scale: f64,
    direction: [f64; 3],
    divisor: &'a [f64],
}

/// The mass-normalised shape of every kept mode at `point` (file node `node`) along the impact
/// direction, in m/√kg.
fn point_shape(
    kept: &[&FileMode],
    point: &str,
    node: i64,
    shape: &Shape,
    file: &str,
    src: &Source,
) -> Result<Vec<f64>> {
    let (scale, d) = (shape.scale, shape.direction);
    let mut values = Vec::with_capacity(kept.len());
    for (k, m) in kept.iter().enumerate() {
        let Some((_, u)) = m.shapes.iter().find(|(label, _)| *label == node) else {
            return Err(src.error(
                &format!("{BASE}.points.{point}"),
                format!(
                    "{BASE}.points.{point}: node {node} is not among the {} nodes of mode {} in {file}{}",
                    m.shapes.len(),
                    m.number,
                    label_range(&m.shapes)
                ),
            ));
        };
        let v = scale * (d[0] * u[0] + d[1] * u[1] + d[2] * u[2]) / shape.divisor[k];
        if !v.is_finite() {
            return Err(src.error(
                &format!("{BASE}.points.{point}"),
                format!(
                    "{BASE}.points.{point}: the shape of mode {} at node {node} is not finite after normalisation",
                    m.number
                ),
            ));
        }
        values.push(v);
    }
    Ok(values)
}

/// A warning for each kept mode without a file mode of the same frequency (to
/// [`REPEATED_TOLERANCE`]) left out: one direction of a repeated eigenvalue, whose basis the
/// FE program chose.
fn repeated_warnings(modes: &[FileMode], kept: &[&FileMode], file: &str) -> Vec<String> {
    let mut warnings = Vec::new();
    for m in kept {
        let partners: Vec<String> = modes
            .iter()
            .filter(|o| {
                o.number != m.number
                    && !kept.iter().any(|k| k.number == o.number)
                    && (o.frequency_hz - m.frequency_hz).abs()
                        <= REPEATED_TOLERANCE * m.frequency_hz.abs()
            })
            .map(|o| o.number.to_string())
            .collect();
        if !partners.is_empty() {
            warnings.push(format!(
                "{BASE}.select keeps mode {} of {file} but not mode(s) {} at the same frequency \
                 ({:.6} Hz, within {REPEATED_TOLERANCE:e}): a repeated eigenvalue, whose basis \
                 (which direction each mode takes) is the FE program's choice, not a property of \
                 the structure; keep all of them",
                m.number,
                partners.join(", "),
                m.frequency_hz
            ));
        }
    }
    warnings
}

/// `" (labels 1 to 248)"` for messages.
fn label_range(shapes: &[(i64, [f64; 3])]) -> String {
    let lo = shapes.iter().map(|s| s.0).min();
    let hi = shapes.iter().map(|s| s.0).max();
    match (lo, hi) {
        (Some(lo), Some(hi)) => format!(" (labels {lo} to {hi})"),
        _ => String::new(),
    }
}
