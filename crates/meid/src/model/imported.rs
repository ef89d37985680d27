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
//! (`units = "mm-t-s"`: a displacement in mm per √t is 1e-3 m per √(1e3 kg)). Dividing by
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
//! Units are not in the files meid reads here: they are the file's (SI unless
//! `units = "mm-t-s"`). The force to the floor and the static flexibility are not in the
//! files either: an imported model has no floor force and no truncation table (unknown
//! flexibility).

use std::path::{Path, PathBuf};

use super::source::Source;
use super::spec::ModesFileSpec;
use crate::io::{frd, uff};
use crate::modal::ModalModel;
use crate::{Error, Result};

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
        })
        .collect()
}

/// The file's format: `format`, else the extension.
fn format_of(spec: &ModesFileSpec, path: &Path, src: &Source) -> Result<&'static str> {
    const BASE: &str = "structure.modes";
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

/// The modal model of `modes` (read from `file`) as `spec` maps them (module docs).
pub fn build(
    modes: &[FileMode],
    spec: &ModesFileSpec,
    file: &str,
    src: &Source,
) -> Result<ModalModel> {
    const BASE: &str = "structure.modes";
    // Unit system.
    let scale = match spec.units.as_deref() {
        None | Some("m-kg-s") | Some("SI") => 1.0,
        Some("mm-t-s") => 1e-3 / 1e3f64.sqrt(),
        Some(other) => {
            return Err(src.error(
                &format!("{BASE}.units"),
                format!("{BASE}.units: unknown unit system '{other}'; valid: \"m-kg-s\" (SI, default), \"mm-t-s\" (mm, tonne, s, N)"),
            ))
        }
    };
    // Direction.
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
    let d = [d[0] / norm, d[1] / norm, d[2] / norm];
    if spec.points.is_empty() {
        return Err(src.error(
            &format!("{BASE}.points"),
            format!("{BASE}.points: map meid's points to node labels of the file, e.g. points = {{ O_b = 12, B = 7 }}"),
        ));
    }
    // Which modes: `select` (file mode numbers), then `max_hz`.
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
    // Mass normalisation (module docs).
    let mut divisor = Vec::with_capacity(n);
    let mut assumed = Vec::new();
    for m in &kept {
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
    if scale != 1.0 {
        notes.push(format!(
            "{BASE}: shapes converted from mm/√t to m/√kg (× {scale:e}), units = \"mm-t-s\""
        ));
    }
    // Damping.
    let zeta = match &spec.damping_ratios {
        Some(_) => super::lumped::ratios(
            &spec.damping_ratios,
            n,
            &format!("{BASE}.damping_ratios"),
            src,
        )?,
        None => {
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
            z
        }
    };
    let omega: Vec<f64> = kept
        .iter()
        .map(|m| 2.0 * std::f64::consts::PI * m.frequency_hz)
        .collect();
    let mut model = ModalModel::with_damping_ratios(omega, &zeta)?;
    // Shapes at the points.
    for (point, node) in &spec.points {
        let mut values = Vec::with_capacity(n);
        for (k, m) in kept.iter().enumerate() {
            let Some((_, u)) = m.shapes.iter().find(|(label, _)| label == node) else {
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
            let v = scale * (d[0] * u[0] + d[1] * u[1] + d[2] * u[2]) / divisor[k];
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
        model.points.insert(point.clone(), values);
    }
    model.labels = kept
        .iter()
        .map(|m| format!("mode {} ({:.4} Hz)", m.number, m.frequency_hz))
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
    // A mode kept without a file mode of the same frequency (to the file's precision): one
    // direction of a repeated eigenvalue, whose basis the FE program chose.
    for m in &kept {
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
            model.warnings.push(format!(
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
    model.validate().map_err(|e| match e {
        Error::InvalidValue { field, message } => {
            src.error(BASE, format!("{BASE}: {field}: {message}"))
        }
        other => other,
    })?;
    Ok(model)
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
