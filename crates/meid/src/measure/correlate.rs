//! Correlation of identified modes with the model's (`meid correlate`): measured points mapped
//! to the model's named points, the modal assurance criterion (MAC), paired modes, frequency
//! errors, the auto-MAC of the model's modes at the measured points, and the test geometry a
//! test-lab viewer animates.
//!
//! # Identified modes
//!
//! [`read_identified`] reads what `meid identify` writes: its JSON (`--json`, or
//! `identification.json`: an object with `points`, the measured points' labels
//! `ENTITY:NODE ±DIR`, and `modes`, each with `frequency_hz`, `damping_ratio` and `shape`, the
//! real-normalised shape at the points), its `modes.csv` (columns `shape_<label>`), or a UFF
//! file of datasets 55 (every node and axis with a value in any mode is a point, `NODE ±AXIS`).
//!
//! # Points, directions and signs
//!
//! meid's model moves along one axis, the impact direction (vertical, +Z). A measured point's
//! direction `+Z` maps with sign +1, `−Z` with sign −1 (its shape values are negated before the
//! comparison), no direction (0) is read as `+Z` (a note says so); `±X`, `±Y` and rotations are
//! refused (the model predicts no motion there). A measured point maps to a model point
//! ([`map_points`]):
//!
//! * **by name** (default), in this order: an explicit `--map LABEL=POINT` (LABEL the point's
//!   label or its entity), its entity equal to a named point of the model, its node number
//!   equal to a named point;
//! * **by coordinates** (`--geometry FILE --tolerance T`): the node's coordinates in the file
//!   (UFF dataset 15 or 2411, m) within `T` (m) of a model point: an FE model's named point
//!   at the mean of its nodes, a lumped or tabulated model's point `k` (name order) at
//!   `x = k − 1` m, the coordinates of the geometry meid writes ([`geometry_uff`]); the nearest.
//!
//! A point that maps to nothing is an error naming the file, the point and the model's points.
//!
//! # MAC, pairing, blind points
//!
//! With `φ_a` an identified shape and `φ_b` a model shape (mass-normalised `ψ` times the sign)
//! at the mapped points,
//!
//! ```text
//! MAC(a, b) = |φ_aᴴ φ_b|² / ((φ_aᴴ φ_a)(φ_bᴴ φ_b))
//! ```
//!
//! (Allemang & Brown, "A correlation coefficient for modal vector analysis", IMAC I, 1982;
//! Allemang, "The modal assurance criterion — twenty years of use and abuse", Sound and
//! Vibration 37 (2003) 14-23). **Pairing rule**: the largest MAC of the matrix among the
//! identified modes and model modes not yet paired is paired (ties: the smaller frequency
//! error), repeatedly, while it is at least `min_mac` (default 0.5); each model mode is used
//! once. The frequency error is `100 (f_identified − f_model)/f_model` %.
//!
//! The **auto-MAC** is the MAC of the model's modes with one another at the mapped points. The
//! points make the MAC **blind** (warnings) when an off-diagonal auto-MAC exceeds `blind_mac`
//! (0.9: two model modes look alike there), when there are fewer distinct mapped points than
//! model modes compared (the shapes cannot all be told apart), or when three or more points
//! with known coordinates lie on one line (modes that turn about that line look alike).

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::identify::mac_real;
use crate::model::Model;
use crate::{Error, Result};

/// A measured point of identified modes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeasuredPoint {
    /// As the identified file writes it, e.g. `bed:1 +Z`.
    pub label: String,
    pub entity: String,
    pub node: i64,
    /// ±1, ±2, ±3 (X, Y, Z), ±4..6 rotations, 0 none.
    pub direction: i64,
}

/// One identified mode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IdentifiedMode {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    /// Real-normalised shape, one value per point.
    pub shape: Vec<f64>,
}

impl From<&crate::identify::Mode> for IdentifiedMode {
    /// What correlation needs of a mode `meid identify` found: its frequency, damping ratio
    /// (the window's decay removed) and real-normalised shape.
    fn from(m: &crate::identify::Mode) -> Self {
        Self {
            frequency_hz: m.frequency_hz,
            damping_ratio: m.damping_ratio,
            shape: m.shape.clone(),
        }
    }
}

/// Identified modes read from a file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IdentifiedModes {
    pub file: String,
    pub points: Vec<MeasuredPoint>,
    pub modes: Vec<IdentifiedMode>,
}

fn direction_of(tok: &str) -> Option<i64> {
    Some(match tok {
        "+X" => 1,
        "+Y" => 2,
        "+Z" => 3,
        "-X" => -1,
        "-Y" => -2,
        "-Z" => -3,
        "+RX" => 4,
        "+RY" => 5,
        "+RZ" => 6,
        "-RX" => -4,
        "-RY" => -5,
        "-RZ" => -6,
        _ => return None,
    })
}

/// A point label `ENTITY:NODE ±DIR` (as [`crate::record::PointRef::label`] writes it; the
/// direction and the node are optional).
pub fn parse_point_label(label: &str) -> MeasuredPoint {
    let label = label.trim();
    let (head, direction) = match label.rsplit_once([' ', '_']) {
        Some((h, d)) if direction_of(d).is_some() => (h, direction_of(d).unwrap_or(0)),
        _ => (label, 0),
    };
    let (entity, node) = match head.rsplit_once(':') {
        Some((e, n)) if n.parse::<i64>().is_ok() => (e, n.parse().unwrap_or(0)),
        _ => match head.parse::<i64>() {
            Ok(n) => ("", n),
            Err(_) => (head, 0),
        },
    };
    MeasuredPoint {
        label: label.to_string(),
        entity: entity.to_string(),
        node,
        direction,
    }
}

fn bad(file: &str, field: &str, message: impl Into<String>) -> Error {
    Error::Input {
        location: format!("{file}: {field}"),
        message: message.into(),
    }
}

/// Reads identified modes (module docs): `.json`, `.csv`, else UFF.
pub fn read_identified(path: &Path) -> Result<IdentifiedModes> {
    let file = path.display().to_string();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let out = match ext.as_str() {
        "json" => from_json(&file, &crate::input::read_text(path)?)?,
        "csv" | "txt" => from_csv(&file, &crate::input::read_text(path)?)?,
        _ => from_uff(&file, &crate::io::uff::read_uff(path)?)?,
    };
    check_identified(&out)?;
    Ok(out)
}

const VALID: &str = "give meid identify's output: its JSON (--json or identification.json, with `points` and `modes[].shape`), modes.csv, or modes.uff (datasets 55)";

fn check_identified(m: &IdentifiedModes) -> Result<()> {
    if m.modes.is_empty() {
        return Err(bad(&m.file, "modes", format!("no mode: {VALID}")));
    }
    if m.points.is_empty() {
        return Err(bad(
            &m.file,
            "points",
            format!("no measured point: {VALID}"),
        ));
    }
    for (i, mode) in m.modes.iter().enumerate() {
        if mode.shape.is_empty() {
            return Err(bad(
                &m.file,
                &format!("modes[{i}].shape"),
                format!(
                    "mode {} has no shape: correlation needs the shape at every point; {VALID}",
                    i + 1
                ),
            ));
        }
        if mode.shape.len() != m.points.len() {
            return Err(bad(
                &m.file,
                &format!("modes[{i}].shape"),
                format!(
                    "{} values for {} points: one value per point of `points`",
                    mode.shape.len(),
                    m.points.len()
                ),
            ));
        }
        if !(mode.frequency_hz.is_finite() && mode.frequency_hz > 0.0)
            || mode.shape.iter().any(|v| !v.is_finite())
        {
            return Err(bad(
                &m.file,
                &format!("modes[{i}]"),
                "frequency_hz must be finite and > 0 and the shape finite",
            ));
        }
    }
    Ok(())
}

fn from_json(file: &str, text: &str) -> Result<IdentifiedModes> {
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|e| bad(file, "JSON", format!("{e}: {VALID}")))?;
    let points = v
        .get("points")
        .and_then(|p| p.as_array())
        .ok_or_else(|| {
            bad(
                file,
                "points",
                format!("missing (a list of point labels): {VALID}"),
            )
        })?
        .iter()
        .map(|p| p.as_str().map(parse_point_label))
        .collect::<Option<Vec<_>>>()
        .ok_or_else(|| bad(file, "points", "every entry must be a label (text)"))?;
    let modes = v
        .get("modes")
        .and_then(|m| m.as_array())
        .ok_or_else(|| bad(file, "modes", format!("missing (a list of modes): {VALID}")))?;
    let mut out = Vec::new();
    for (i, m) in modes.iter().enumerate() {
        let num = |k: &str| m.get(k).and_then(|x| x.as_f64());
        let frequency_hz = num("frequency_hz").ok_or_else(|| {
            bad(
                file,
                &format!("modes[{i}].frequency_hz"),
                "missing or not a number",
            )
        })?;
        let shape = match m.get("shape") {
            None | Some(serde_json::Value::Null) => Vec::new(),
            Some(s) => s
                .as_array()
                .and_then(|a| a.iter().map(|x| x.as_f64()).collect::<Option<Vec<f64>>>())
                .ok_or_else(|| {
                    bad(
                        file,
                        &format!("modes[{i}].shape"),
                        "must be a list of numbers",
                    )
                })?,
        };
        out.push(IdentifiedMode {
            frequency_hz,
            damping_ratio: num("damping_ratio").unwrap_or(f64::NAN),
            shape,
        });
    }
    Ok(IdentifiedModes {
        file: file.into(),
        points,
        modes: out,
    })
}

fn from_csv(file: &str, text: &str) -> Result<IdentifiedModes> {
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| bad(file, "header", format!("empty file: {VALID}")))?
        .split(',')
        .map(str::trim)
        .collect();
    let col = |name: &str| header.iter().position(|h| *h == name);
    let f_col = col("frequency_hz")
        .ok_or_else(|| bad(file, "header", format!("no column frequency_hz: {VALID}")))?;
    let z_col = col("damping_ratio");
    let shape_cols: Vec<(usize, MeasuredPoint)> = header
        .iter()
        .enumerate()
        .filter_map(|(k, h)| {
            let l = h.strip_prefix("shape_")?;
            (!l.ends_with("_re") && !l.ends_with("_im")).then(|| (k, parse_point_label(l)))
        })
        .collect();
    let mut modes = Vec::new();
    for (r, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let get = |k: usize| -> Result<f64> {
            cells
                .get(k)
                .and_then(|c| c.parse::<f64>().ok())
                .ok_or_else(|| {
                    bad(
                        file,
                        &format!("row {}, column {}", r + 2, header.get(k).unwrap_or(&"?")),
                        "not a number",
                    )
                })
        };
        modes.push(IdentifiedMode {
            frequency_hz: get(f_col)?,
            damping_ratio: z_col.map(get).transpose()?.unwrap_or(f64::NAN),
            shape: shape_cols
                .iter()
                .map(|(k, _)| get(*k))
                .collect::<Result<_>>()?,
        });
    }
    Ok(IdentifiedModes {
        file: file.into(),
        points: shape_cols.into_iter().map(|(_, p)| p).collect(),
        modes,
    })
}

fn from_uff(file: &str, u: &crate::io::uff::UffFile) -> Result<IdentifiedModes> {
    let axes = ["X", "Y", "Z"];
    let mut keys: Vec<(i64, usize)> = Vec::new();
    for m in &u.modes {
        for (node, v) in &m.shapes {
            for (a, x) in v.iter().enumerate() {
                if *x != 0.0 && !keys.contains(&(*node, a)) {
                    keys.push((*node, a));
                }
            }
        }
    }
    let points = keys
        .iter()
        .map(|&(node, a)| MeasuredPoint {
            label: format!("{node} +{}", axes[a]),
            entity: String::new(),
            node,
            direction: a as i64 + 1,
        })
        .collect();
    let modes = u
        .modes
        .iter()
        .map(|m| IdentifiedMode {
            frequency_hz: m.frequency_hz,
            damping_ratio: m.damping_ratio,
            shape: keys
                .iter()
                .map(|&(node, a)| {
                    m.shapes
                        .iter()
                        .find(|s| s.0 == node)
                        .map_or(0.0, |s| s.1[a])
                })
                .collect(),
        })
        .collect();
    Ok(IdentifiedModes {
        file: file.into(),
        points,
        modes,
    })
}

/// The model's modes at its named points, and where the points are.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelModes {
    pub frequencies_hz: Vec<f64>,
    pub labels: Vec<String>,
    /// Mass-normalised shape values along the impact direction, per point, per mode.
    pub points: BTreeMap<String, Vec<f64>>,
    /// Point coordinates (m) for the mapping by coordinates ([`geometry_coordinates`]).
    pub coordinates: BTreeMap<String, [f64; 3]>,
    /// The coordinates are a real geometry (an FE mesh), not the display line of a lumped model.
    pub geometric: bool,
}

/// A lumped or tabulated model's display coordinates: point `k` (1-based, name order) at
/// `x = k − 1` m (as [`crate::io::uff::modes_uff_points`] places them).
pub fn geometry_coordinates(m: &Model) -> BTreeMap<String, [f64; 3]> {
    crate::io::uff::point_node_labels(&m.structure)
        .into_iter()
        .map(|(label, name)| (name, [(label - 1) as f64, 0.0, 0.0]))
        .collect()
}

impl ModelModes {
    /// From the model's modes (the structure's: static-correction pseudo-modes are not modes
    /// a test can measure, and are left out); `coordinates` of an FE model's points (the means
    /// of their nodes), or `None` for the display line ([`geometry_coordinates`]).
    pub fn new(model: &Model, coordinates: Option<BTreeMap<String, [f64; 3]>>) -> Self {
        let geometric = coordinates.is_some();
        let m = &model.structure;
        let keep: Vec<usize> = (0..m.len()).filter(|&i| !m.is_pseudo(i)).collect();
        ModelModes {
            frequencies_hz: keep
                .iter()
                .map(|&i| m.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI))
                .collect(),
            labels: keep
                .iter()
                .map(|&i| m.labels.get(i).cloned().unwrap_or_default())
                .collect(),
            points: m
                .points
                .iter()
                .map(|(k, v)| (k.clone(), keep.iter().map(|&i| v[i]).collect()))
                .collect(),
            coordinates: coordinates.unwrap_or_else(|| geometry_coordinates(model)),
            geometric,
        }
    }

    /// The lowest `n` modes.
    pub fn lowest(&self, n: usize) -> ModelModes {
        let mut out = self.clone();
        out.frequencies_hz.truncate(n);
        out.labels.truncate(n);
        for v in out.points.values_mut() {
            v.truncate(n);
        }
        out
    }

    fn names(&self) -> String {
        self.points.keys().cloned().collect::<Vec<_>>().join(", ")
    }
}

/// How measured points map to the model's (module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mapping {
    /// `--map LABEL=POINT`: measured label or entity → model point.
    pub explicit: BTreeMap<String, String>,
    /// `--geometry`: node label → coordinates (m), with the file's name and the tolerance (m).
    pub geometry: Option<(String, BTreeMap<i64, [f64; 3]>, f64)>,
}

/// A measured point mapped to a model point.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MappedPoint {
    pub measured: String,
    pub model_point: String,
    /// +1 or −1 (module docs).
    pub sign: f64,
    /// How: "map", "name", "node", or "coordinates".
    pub rule: String,
    /// Distance to the model point (m), by coordinates.
    pub distance_m: Option<f64>,
    /// The measured point's coordinates (by coordinates).
    #[serde(skip)]
    pub xyz: Option<[f64; 3]>,
}

/// Maps every measured point (module docs); unmapped points are an error naming them.
pub fn map_points(
    ident: &IdentifiedModes,
    model: &ModelModes,
    mapping: &Mapping,
) -> Result<(Vec<MappedPoint>, Vec<String>)> {
    let mut out = Vec::new();
    let mut notes = Vec::new();
    let mut unmapped = Vec::new();
    for p in &ident.points {
        let sign = match p.direction {
            3 => 1.0,
            -3 => -1.0,
            0 => {
                notes.push(format!("point '{}' has no direction: read as +Z", p.label));
                1.0
            }
            d => {
                return Err(bad(
                    &ident.file,
                    &format!("point '{}'", p.label),
                    format!("direction {d} is not the model's axis: meid's model moves along the impact direction (Z) only; valid directions are +Z and -Z (sign flipped); leave other directions out of the identification"),
                ))
            }
        };
        let found = map_one(ident, p, model, mapping)?;
        match found {
            Some((point, rule, distance_m, xyz)) => out.push(MappedPoint {
                measured: p.label.clone(),
                model_point: point,
                sign,
                rule: rule.into(),
                distance_m,
                xyz,
            }),
            None => unmapped.push(p.label.clone()),
        }
    }
    if !unmapped.is_empty() {
        let how = if mapping.geometry.is_some() {
            "no model point lies within the tolerance of their nodes"
        } else {
            "neither their entity nor their node names a model point"
        };
        return Err(bad(
            &ident.file,
            "points",
            format!(
                "unmapped point(s) {}: {how}; the model's points are {} (map with --map LABEL=POINT, or by coordinates with --geometry FILE --tolerance M)",
                unmapped.join(", "),
                model.names()
            ),
        ));
    }
    Ok((out, notes))
}

type Found = Option<(String, &'static str, Option<f64>, Option<[f64; 3]>)>;

fn map_one(
    ident: &IdentifiedModes,
    p: &MeasuredPoint,
    model: &ModelModes,
    mapping: &Mapping,
) -> Result<Found> {
    let known = |name: &str| model.points.contains_key(name);
    for key in [&p.label, &p.entity] {
        if let Some(target) = mapping.explicit.get(key) {
            if !known(target) {
                return Err(bad(
                    "--map",
                    key,
                    format!(
                        "'{target}' is not a point of the model; its points are {}",
                        model.names()
                    ),
                ));
            }
            return Ok(Some((target.clone(), "map", None, None)));
        }
    }
    if let Some((file, nodes, tol)) = &mapping.geometry {
        let xyz = *nodes.get(&p.node).ok_or_else(|| {
            bad(
                file,
                &format!("node {}", p.node),
                format!(
                    "point '{}' of {} is at node {}, which the geometry file does not list (UFF dataset 15 or 2411)",
                    p.label, ident.file, p.node
                ),
            )
        })?;
        let nearest = model
            .coordinates
            .iter()
            .map(|(name, c)| {
                let d =
                    ((c[0] - xyz[0]).powi(2) + (c[1] - xyz[1]).powi(2) + (c[2] - xyz[2]).powi(2))
                        .sqrt();
                (name, d)
            })
            .min_by(|a, b| a.1.total_cmp(&b.1));
        return Ok(match nearest {
            Some((name, d)) if d <= *tol => Some((name.clone(), "coordinates", Some(d), Some(xyz))),
            _ => None,
        });
    }
    if known(&p.entity) {
        return Ok(Some((p.entity.clone(), "name", None, None)));
    }
    let node = p.node.to_string();
    if p.node != 0 && known(&node) {
        return Ok(Some((node, "node", None, None)));
    }
    Ok(None)
}

/// Correlation settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Settings {
    /// Pairs need at least this MAC.
    pub min_mac: f64,
    /// Off-diagonal auto-MAC above which the points are blind.
    pub blind_mac: f64,
    /// The lowest model modes compared (`None`: all the model retains).
    pub model_modes: Option<usize>,
    /// Pair by frequency instead: among the pairs with MAC ≥ `min_mac`, the smallest
    /// frequency error first, repeatedly (for one measured point, where the MAC of any two
    /// shapes is 1 and says nothing).
    pub by_frequency: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            min_mac: 0.5,
            blind_mac: 0.9,
            model_modes: None,
            by_frequency: false,
        }
    }
}

/// A paired mode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Pair {
    /// 1-based.
    pub identified_mode: usize,
    pub model_mode: usize,
    pub identified_frequency_hz: f64,
    pub model_frequency_hz: f64,
    pub error_percent: f64,
    pub mac: f64,
}

/// The correlation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Correlation {
    pub file: String,
    pub points: Vec<MappedPoint>,
    pub identified_frequencies_hz: Vec<f64>,
    pub model_frequencies_hz: Vec<f64>,
    pub model_labels: Vec<String>,
    pub pairs: Vec<Pair>,
    /// 1-based numbers of the modes left unpaired.
    pub unpaired_identified: Vec<usize>,
    pub unpaired_model: Vec<usize>,
    /// `mac[i][j]`: identified mode i, model mode j.
    pub mac: Vec<Vec<f64>>,
    pub auto_mac: Vec<Vec<f64>>,
    pub settings: Settings,
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
}

/// MAC of every `a` with every `b` (real shapes).
pub fn mac_matrix(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    a.iter()
        .map(|x| b.iter().map(|y| mac_real(x, y)).collect())
        .collect()
}

/// The pairing rule (module docs): `(row, column)` pairs, 0-based, by row. `freq_error(i, j)`
/// breaks ties.
pub fn pair_modes(
    mac: &[Vec<f64>],
    min_mac: f64,
    freq_error: impl Fn(usize, usize) -> f64,
) -> Vec<(usize, usize)> {
    let rows = mac.len();
    let cols = mac.first().map_or(0, Vec::len);
    let (mut used_r, mut used_c) = (vec![false; rows], vec![false; cols]);
    let mut out = Vec::new();
    loop {
        let mut best: Option<(usize, usize)> = None;
        for i in (0..rows).filter(|&i| !used_r[i]) {
            for j in (0..cols).filter(|&j| !used_c[j]) {
                let better = match best {
                    None => true,
                    Some((bi, bj)) => {
                        mac[i][j] > mac[bi][bj]
                            || (mac[i][j] == mac[bi][bj]
                                && freq_error(i, j).abs() < freq_error(bi, bj).abs())
                    }
                };
                if better {
                    best = Some((i, j));
                }
            }
        }
        match best {
            Some((i, j)) if mac[i][j] >= min_mac => {
                used_r[i] = true;
                used_c[j] = true;
                out.push((i, j));
            }
            _ => break,
        }
    }
    out.sort();
    out
}

/// Whether points lie on one line (to `tol` times their extent); fewer than 3: false.
pub fn collinear(points: &[[f64; 3]], tol: f64) -> bool {
    if points.len() < 3 {
        return false;
    }
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let norm = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let p0 = points[0];
    let Some(far) = points
        .iter()
        .copied()
        .max_by(|a, b| norm(sub(*a, p0)).total_cmp(&norm(sub(*b, p0))))
    else {
        return false;
    };
    let d = sub(far, p0);
    let len = norm(d);
    if len == 0.0 {
        return true;
    }
    points.iter().all(|&p| {
        let v = sub(p, p0);
        let c = [
            v[1] * d[2] - v[2] * d[1],
            v[2] * d[0] - v[0] * d[2],
            v[0] * d[1] - v[1] * d[0],
        ];
        norm(c) / len <= tol * len
    })
}

/// The identified shapes and the model's at the mapped points (signs applied to the model's).
fn shapes(
    ident: &IdentifiedModes,
    model: &ModelModes,
    mapped: &[MappedPoint],
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let idx: Vec<usize> = mapped
        .iter()
        .map(|m| {
            ident
                .points
                .iter()
                .position(|p| p.label == m.measured)
                .unwrap_or(0)
        })
        .collect();
    let a = ident
        .modes
        .iter()
        .map(|m| {
            idx.iter()
                .map(|&k| m.shape.get(k).copied().unwrap_or(0.0))
                .collect()
        })
        .collect();
    let b = (0..model.frequencies_hz.len())
        .map(|j| {
            mapped
                .iter()
                .map(|m| {
                    m.sign
                        * model
                            .points
                            .get(&m.model_point)
                            .and_then(|v| v.get(j))
                            .copied()
                            .unwrap_or(0.0)
                })
                .collect()
        })
        .collect();
    (a, b)
}

/// Correlates identified modes with the model's (module docs).
pub fn correlate(
    ident: &IdentifiedModes,
    model: &ModelModes,
    mapping: &Mapping,
    settings: &Settings,
) -> Result<Correlation> {
    let retained = model.frequencies_hz.len();
    let model = match settings.model_modes {
        Some(n) if n == 0 || n > retained => {
            return Err(Error::invalid(
                "--model-modes",
                format!("{n}: the model retains {retained} mode(s); give 1..={retained}"),
            ))
        }
        Some(n) => model.lowest(n),
        None => model.clone(),
    };
    let (mapped, mut notes) = map_points(ident, &model, mapping)?;
    let distinct: std::collections::BTreeSet<&str> =
        mapped.iter().map(|m| m.model_point.as_str()).collect();
    let n_model = model.frequencies_hz.len();
    if settings.model_modes.is_some() && distinct.len() < n_model {
        return Err(bad(
            &ident.file,
            "points",
            format!(
                "{} measured point(s) map to {} model point(s), fewer than the {n_model} modes asked (--model-modes): at most as many modes as points can be told apart; measure more points or ask fewer modes",
                mapped.len(),
                distinct.len()
            ),
        ));
    }
    let (a, b) = shapes(ident, &model, &mapped);
    let mac = mac_matrix(&a, &b);
    let auto_mac = mac_matrix(&b, &b);
    let fi: Vec<f64> = ident.modes.iter().map(|m| m.frequency_hz).collect();
    let fm = model.frequencies_hz.clone();
    let err = |i: usize, j: usize| 100.0 * (fi[i] - fm[j]) / fm[j];
    // By frequency: every admissible pair scores alike, so the tie-break (the smaller
    // frequency error) decides.
    let score: Vec<Vec<f64>> = if settings.by_frequency {
        mac.iter()
            .map(|r| {
                r.iter()
                    .map(|&m| if m >= settings.min_mac { 1.0 } else { 0.0 })
                    .collect()
            })
            .collect()
    } else {
        mac.clone()
    };
    let pairs: Vec<Pair> = pair_modes(&score, settings.min_mac, err)
        .into_iter()
        .map(|(i, j)| Pair {
            identified_mode: i + 1,
            model_mode: j + 1,
            identified_frequency_hz: fi[i],
            model_frequency_hz: fm[j],
            error_percent: err(i, j),
            mac: mac[i][j],
        })
        .collect();
    let mut warnings = blind_warnings(
        &auto_mac,
        settings.blind_mac,
        distinct.len(),
        &model,
        &mapped,
    );
    for b in b
        .iter()
        .enumerate()
        .filter(|(_, v)| v.iter().all(|x| *x == 0.0))
    {
        warnings.push(format!(
            "model mode {} does not move any mapped point: its MAC is 0 with every shape",
            b.0 + 1
        ));
    }
    notes.push(if settings.by_frequency {
        format!(
            "pairing: by frequency, the smallest error among unpaired modes with MAC ≥ {}, repeatedly; each model mode once",
            settings.min_mac
        )
    } else {
        format!(
            "pairing: the largest MAC among unpaired modes, repeatedly, while ≥ {}; each model mode once",
            settings.min_mac
        )
    });
    Ok(Correlation {
        file: ident.file.clone(),
        unpaired_identified: (1..=fi.len())
            .filter(|i| !pairs.iter().any(|p| p.identified_mode == *i))
            .collect(),
        unpaired_model: (1..=fm.len())
            .filter(|j| !pairs.iter().any(|p| p.model_mode == *j))
            .collect(),
        points: mapped,
        identified_frequencies_hz: fi,
        model_frequencies_hz: fm,
        model_labels: model.labels.clone(),
        pairs,
        mac,
        auto_mac,
        settings: *settings,
        warnings,
        notes,
    })
}

fn blind_warnings(
    auto_mac: &[Vec<f64>],
    blind_mac: f64,
    distinct: usize,
    model: &ModelModes,
    mapped: &[MappedPoint],
) -> Vec<String> {
    let mut w = Vec::new();
    let n = auto_mac.len();
    for i in 0..n {
        for j in i + 1..n {
            if auto_mac[i][j] > blind_mac {
                w.push(format!(
                    "blind points: the auto-MAC of model modes {} and {} at the measured points is {:.3} > {blind_mac}: the MAC cannot tell them apart; add points where they differ",
                    i + 1,
                    j + 1,
                    auto_mac[i][j]
                ));
            }
        }
    }
    if distinct < n {
        w.push(format!(
            "blind points: {distinct} distinct model point(s) for {n} model modes: at most {distinct} shapes can be told apart (fewer points than modes)"
        ));
    }
    let coords: Vec<[f64; 3]> = mapped
        .iter()
        .filter_map(|m| {
            m.xyz.or_else(|| {
                model
                    .geometric
                    .then(|| model.coordinates.get(&m.model_point).copied())
                    .flatten()
            })
        })
        .collect();
    if coords.len() == mapped.len() && collinear(&coords, 1e-6) {
        w.push(format!(
            "blind points: all {} measured points lie on one line: modes that turn about it (rocking, torsion) look alike there",
            coords.len()
        ));
    }
    w
}

impl Correlation {
    /// The report as text: the mapping, the paired modes, the MAC and auto-MAC matrices, the
    /// notes (the warnings are for the caller to show).
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(s, "identified modes: {}", self.file);
        for p in &self.points {
            let _ = writeln!(
                s,
                "  {:<20} -> {:<12} sign {:+} ({}{})",
                p.measured,
                p.model_point,
                p.sign,
                p.rule,
                p.distance_m
                    .map_or(String::new(), |d| format!(", {d:.3e} m"))
            );
        }
        let _ = writeln!(
            s,
            "\n{:>10} {:>10} {:>14} {:>14} {:>10} {:>8}",
            "identified", "model", "f_test (Hz)", "f_model (Hz)", "error (%)", "MAC"
        );
        for p in &self.pairs {
            let _ = writeln!(
                s,
                "{:>10} {:>10} {:>14.4} {:>14.4} {:>10.3} {:>8.4}",
                p.identified_mode,
                p.model_mode,
                p.identified_frequency_hz,
                p.model_frequency_hz,
                p.error_percent,
                p.mac
            );
        }
        if !self.unpaired_identified.is_empty() {
            let _ = writeln!(
                s,
                "unpaired identified modes: {:?}",
                self.unpaired_identified
            );
        }
        if !self.unpaired_model.is_empty() {
            let _ = writeln!(s, "unpaired model modes: {:?}", self.unpaired_model);
        }
        let matrix = |s: &mut String, title: &str, m: &[Vec<f64>]| {
            let _ = writeln!(s, "\n{title}");
            for (i, row) in m.iter().enumerate() {
                let cells: Vec<String> = row.iter().map(|v| format!("{v:6.3}")).collect();
                let _ = writeln!(s, "{:>4} {}", i + 1, cells.join(" "));
            }
        };
        matrix(
            &mut s,
            "MAC (rows: identified, columns: model modes)",
            &self.mac,
        );
        matrix(
            &mut s,
            "auto-MAC of the model modes at the measured points",
            &self.auto_mac,
        );
        for n in &self.notes {
            let _ = writeln!(s, "note: {n}");
        }
        s
    }

    /// `pairs.csv`: `identified_mode,model_mode,identified_frequency_hz,model_frequency_hz,error_percent,mac`.
    pub fn pairs_csv(&self) -> String {
        let mut s = String::from(
            "identified_mode,model_mode,identified_frequency_hz,model_frequency_hz,error_percent,mac\n",
        );
        for p in &self.pairs {
            s.push_str(&format!(
                "{},{},{},{},{},{}\n",
                p.identified_mode,
                p.model_mode,
                p.identified_frequency_hz,
                p.model_frequency_hz,
                p.error_percent,
                p.mac
            ));
        }
        s
    }

    /// A matrix as CSV (`mac.csv`, `auto_mac.csv`): a header `mode,model_1,…`, one row per mode.
    pub fn matrix_csv(m: &[Vec<f64>], row: &str) -> String {
        let cols = m.first().map_or(0, Vec::len);
        let mut s = format!("{row}_mode");
        for j in 1..=cols {
            s.push_str(&format!(",model_{j}"));
        }
        s.push('\n');
        for (i, r) in m.iter().enumerate() {
            s.push_str(&format!("{}", i + 1));
            for v in r {
                s.push_str(&format!(",{v}"));
            }
            s.push('\n');
        }
        s
    }

    /// `mac.png/.svg` and `auto_mac.png/.svg` (matrices of at least 2 × 2; the others get a
    /// note instead). Returns the notes.
    pub fn plots(&self, dir: &Path) -> Result<Vec<String>> {
        let mut notes = Vec::new();
        for (stem, m, y_label) in [
            ("mac", &self.mac, "identified mode"),
            ("auto_mac", &self.auto_mac, "model mode"),
        ] {
            let (ny, nx) = (m.len(), m.first().map_or(0, Vec::len));
            if nx < 2 || ny < 2 {
                notes.push(format!(
                    "{stem}.png: a {ny} × {nx} matrix is not drawn (needs 2 × 2 or more)"
                ));
                continue;
            }
            crate::plot::heat_map(
                dir.join(stem),
                &crate::plot::HeatMap {
                    title: if stem == "mac" {
                        "MAC: identified against model modes".into()
                    } else {
                        "auto-MAC of the model modes at the measured points".into()
                    },
                    x_label: "model mode".into(),
                    y_label: y_label.into(),
                    x: (1..=nx).map(|k| k as f64).collect(),
                    y: (1..=ny).map(|k| k as f64).collect(),
                    z: m.iter().flatten().copied().collect(),
                    colorbar_label: "MAC".into(),
                    ..Default::default()
                },
            )?;
        }
        Ok(notes)
    }
}

/// Test geometry for test-lab viewers: dataset 164 (SI), 15 (the model's named points at
/// their coordinates, node `k` the `k`-th point in name order, [`crate::io::uff::point_node_labels`]),
/// 82 (one trace line through the points in that order), 2412 (rods, FE descriptor 11, between
/// consecutive points) and one dataset 55 per mode (the mass-normalised shape along Z at each
/// point, modal mass 1).
pub fn geometry_uff(whole: &Model, model: &ModelModes) -> Result<Vec<u8>> {
    let m = &whole.structure;
    use crate::io::uff::{
        write_15, write_164, write_2412, write_55, write_82, Element, Mode, Node, TraceLine, Units,
    };
    let labels = crate::io::uff::point_node_labels(m);
    let nodes: Vec<Node> = labels
        .iter()
        .map(|(label, name)| Node {
            label: *label,
            xyz: model
                .coordinates
                .get(name)
                .copied()
                .unwrap_or([(*label - 1) as f64, 0.0, 0.0]),
        })
        .collect();
    let io = |e: std::io::Error| Error::io("geometry.uff (in memory)", e);
    let si = Units::si();
    let mut out = Vec::new();
    write_164(&mut out, &si).map_err(io)?;
    write_15(&mut out, &nodes).map_err(io)?;
    write_82(
        &mut out,
        &TraceLine {
            number: 1,
            color: 11,
            name: "meid: the model's named points in name order".into(),
            nodes: labels.iter().map(|l| l.0).collect(),
        },
    )
    .map_err(io)?;
    let rods: Vec<Element> = labels
        .windows(2)
        .enumerate()
        .map(|(k, w)| Element {
            label: k as i64 + 1,
            fe_descriptor: 11,
            color: 11,
            nodes: vec![w[0].0, w[1].0],
        })
        .collect();
    if !rods.is_empty() {
        write_2412(&mut out, &rods).map_err(io)?;
    }
    let n = m.omega_rad_per_s.len();
    for i in 0..n {
        let w = m.omega_rad_per_s[i];
        let d = m.damping.get(i * n + i).copied().unwrap_or(0.0);
        let mode = Mode {
            number: i as i64 + 1,
            frequency_hz: w / (2.0 * std::f64::consts::PI),
            modal_mass: 1.0,
            damping_ratio: if w > 0.0 { d / (2.0 * w) } else { 0.0 },
            name: m
                .labels
                .get(i)
                .cloned()
                .unwrap_or_else(|| format!("mode {}", i + 1)),
            id_lines: vec![
                "meid: mass-normalised shape along Z (the impact direction) at the named points"
                    .into(),
                "node k = the k-th named point in name order".into(),
            ],
            shapes: labels
                .iter()
                .map(|(label, p)| {
                    (
                        *label,
                        [
                            0.0,
                            0.0,
                            m.points
                                .get(p)
                                .and_then(|v| v.get(i))
                                .copied()
                                .unwrap_or(0.0),
                        ],
                    )
                })
                .collect(),
            units: Some(si.clone()),
        };
        write_55(&mut out, &mode).map_err(io)?;
    }
    Ok(out)
}
