//! Named paths of a general machine's fields ([`super::network`]), translated to the index
//! form before the file's `--set` overrides are applied.
//!
//! **Named paths.** An entry of the `[[impactor]]`, `[[damper]]` and `[[contact]]` arrays is
//! named by its `name`: `--set` (and `meid sweep --vary`) take
//!
//! ```text
//! impactor.NAME.FIELD   (mass, velocity, force)
//! damper.NAME.FIELD     (mass, stiffness, damping, dashpot, point, anchor)
//! contact.NAME.FIELD    (gap, stiffness, damping, restitution, law, release, between)
//! ```
//!
//! each the same as the index form `damper[i].FIELD` of the entry so named. Moving a damper,
//! `damper.NAME.point=P`, also moves the end of every contact that joins the damper to its old
//! point (`between = [old, NAME]` becomes `[P, NAME]`), so the damper keeps touching the point
//! it sits on. Every other path (`structure.…`, `simulation.…`, the index forms) is set as
//! written.
//!

use crate::{Error, Result};

/// The arrays whose entries are named, and the fields a named path may set.
const ARRAYS: [(&str, &[&str]); 3] = [
    ("impactor", &["mass", "velocity", "force"]),
    (
        "damper",
        &["mass", "stiffness", "damping", "dashpot", "point", "anchor"],
    ),
    (
        "contact",
        &[
            "gap",
            "stiffness",
            "damping",
            "restitution",
            "law",
            "release",
            "between",
            "exponent",
            "alpha",
        ],
    ),
];

/// The best match of `name` among `known`: "; did you mean 'x'?" for the closest name
/// (Jaro-Winkler) among those above 0.8 or one edit away (a letter changed, added, removed, or
/// two swapped: optimal string alignment distance 1, which short names need).
pub(crate) fn did_you_mean(name: &str, known: &[&str]) -> String {
    known
        .iter()
        .map(|c| {
            (
                strsim::jaro_winkler(name, c),
                strsim::osa_distance(name, c),
                *c,
            )
        })
        .filter(|(s, d, _)| *s > 0.8 || *d <= 1)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, _, c)| format!("; did you mean '{c}'?"))
        .unwrap_or_default()
}

/// The `name`s of the entries of array `key` in `table`.
fn entry_names<'t>(table: &'t toml::Table, key: &str) -> Vec<&'t str> {
    table
        .get(key)
        .and_then(|v| v.as_array())
        .map(|a| {
            a.iter()
                .map(|e| e.get("name").and_then(|n| n.as_str()).unwrap_or(""))
                .collect()
        })
        .unwrap_or_default()
}

/// The overrides (`PATH=VALUE`, index form) that `--set spec` stands for in `table` (module
/// docs): itself unless its path is a named path `ARRAY.NAME.FIELD`.
pub fn translate(table: &toml::Table, spec: &str) -> Result<Vec<String>> {
    let Some((path, raw)) = spec.split_once('=') else {
        return Ok(vec![spec.to_string()]);
    };
    let segs: Vec<&str> = path.trim().split('.').collect();
    let Some(&(array, fields)) = ARRAYS.iter().find(|(a, _)| segs.first() == Some(a)) else {
        return Ok(vec![spec.to_string()]);
    };
    if segs.len() < 2 || !matches!(table.get(array), Some(toml::Value::Array(_))) {
        return Ok(vec![spec.to_string()]);
    }
    let err = |message: String| Error::Input {
        location: format!("--set {spec}"),
        message,
    };
    let names = entry_names(table, array);
    let name = segs[1];
    let Some(i) = names.iter().position(|n| *n == name) else {
        return Err(err(format!(
            "{array}.{name}: no [[{array}]] is named '{name}'{} (valid: {}; a path names an entry as {array}.NAME.FIELD)",
            did_you_mean(name, &names),
            names.join(", ")
        )));
    };
    if segs.len() != 3 {
        return Err(err(format!(
            "{path}: give {array}.{name}.FIELD with FIELD one of {}",
            fields.join(", ")
        )));
    }
    let field = segs[2];
    if !fields.contains(&field) {
        return Err(err(format!(
            "{array}.{name}.{field}: unknown field '{field}'{} (valid: {})",
            did_you_mean(field, fields),
            fields.join(", ")
        )));
    }
    let mut out = vec![format!("{array}[{i}].{field}={raw}")];
    if array == "damper" && field == "point" {
        out.extend(moved_contacts(table, name, i, raw.trim()));
    }
    Ok(out)
}

/// The `contact[j].between=[…]` overrides that move the ends of damper `name`'s (entry `i`)
/// contacts with its old point to the point of TOML value `raw`.
fn moved_contacts(table: &toml::Table, name: &str, i: usize, raw: &str) -> Vec<String> {
    let old = table
        .get("damper")
        .and_then(|d| d.as_array())
        .and_then(|d| d.get(i))
        .and_then(|d| d.get("point"))
        .and_then(|p| p.as_str())
        .unwrap_or("");
    let new = toml::from_str::<toml::Table>(&format!("v = {raw}"))
        .ok()
        .and_then(|t| t.get("v").and_then(|v| v.as_str()).map(str::to_string))
        .unwrap_or_else(|| raw.to_string());
    let quoted = |s: &str| toml::Value::String(s.to_string()).to_string();
    let contacts = table.get("contact").and_then(|c| c.as_array());
    let mut out = Vec::new();
    for (j, c) in contacts.into_iter().flatten().enumerate() {
        let ends: Vec<&str> = c
            .get("between")
            .and_then(|b| b.as_array())
            .map(|b| b.iter().filter_map(|e| e.as_str()).collect())
            .unwrap_or_default();
        if let [a, b] = ends[..] {
            let moved = match (a == old && b == name, b == old && a == name) {
                (true, _) => Some([new.as_str(), b]),
                (_, true) => Some([a, new.as_str()]),
                _ => None,
            };
            if let Some([a, b]) = moved {
                out.push(format!(
                    "contact[{j}].between=[{}, {}]",
                    quoted(a),
                    quoted(b)
                ));
            }
        }
    }
    out
}
