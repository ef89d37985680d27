//! `[structure.fem.machine]` written out as the general model it generates
//! (`meid model expand`): the paper's machine as a `[structure.fem.model]` a user can edit.
//!
//! The machine section is a generator ([`crate::structure::MachineSpec::generate`]): it emits
//! a [`GeneralSpec`] and the general model's builder makes the mesh. [`expand_text`] writes
//! the model file with `[structure.fem.machine]` replaced by that `[structure.fem.model]`;
//! every other value is kept (after the `--set` overrides), comments are not. Numbers are
//! written in Rust's shortest round-trip form, so the written file reads back to the same
//! `GeneralSpec` bit for bit, and therefore to the same K, M and modes.

use std::fmt::Write;
use std::path::Path;

use super::general::GeneralSpec;
use super::{fem, source, spec_from_table, Source};
use crate::{Error, Result};

/// The model file `name` (text `text`, with `--set` `overrides` applied) with its
/// `[structure.fem.machine]` replaced by the `[structure.fem.model]` it generates. The model
/// is loaded first, with every check [`super::Model::from_text`] makes: a model meid refuses
/// is refused here too, with the same error.
pub fn expand_text(name: &str, text: &str, overrides: &[String]) -> Result<String> {
    let mut table: toml::Table =
        toml::from_str(text).map_err(|e| source::toml_error(name, text, &e))?;
    let mut src = Source {
        name: name.to_string(),
        text: text.to_string(),
        overrides: Vec::new(),
    };
    for o in overrides {
        let applied = source::apply_override(&mut table, o)?;
        src.overrides.push(applied);
    }
    let spec = spec_from_table(table.clone(), &src)?;
    let Some(machine) = spec.structure.fem.as_ref().and_then(|f| f.machine.as_ref()) else {
        return Err(src.error(
            "structure",
            format!("{name}: has no [structure.fem.machine] to expand (only the parametric machine is a generator; [structure.fem.model] is already the general model)"),
        ));
    };
    // Every check of a model load (values, structure, contacts, damper), with the same
    // messages: an expanded file is never written from a model meid refuses (a negative
    // stiffness or a NaN mass given through `--set`).
    super::Model::from_text(name, text.to_string(), overrides)?;
    let general = fem::machine_general(machine, &src)?;
    if let Some(fem) = table
        .get_mut("structure")
        .and_then(|s| s.as_table_mut())
        .and_then(|s| s.get_mut("fem"))
        .and_then(|f| f.as_table_mut())
    {
        fem.remove("machine");
    }
    let rest = toml::to_string(&table)
        .map_err(|e| Error::invalid("model", format!("cannot write the model as TOML: {e}")))?;
    let mut out = format!(
        "# {name} with [structure.fem.machine] expanded into the general model it generates\n\
         # (meid model expand): {} nodes, inline node i is mesh node i. Units: SI.\n\n",
        general.nodes.len()
    );
    out.push_str(&rest);
    out.push('\n');
    out.push_str(&general_to_toml(&general, "structure.fem.model")?);
    // The file must read back as a model (its own check: never write what meid refuses).
    super::spec_from_text(name, &out)?;
    Ok(out)
}

/// [`expand_text`] on a file.
pub fn expand_file(path: &Path, overrides: &[String]) -> Result<String> {
    let text = crate::input::read_text(path)?;
    expand_text(&path.display().to_string(), &text, overrides)
}

/// A general model as the TOML table `[<path>]`: scalars and small arrays on one line, arrays
/// of arrays one element per line (nodes with their index as a comment), arrays of tables as
/// `[[<path>.<key>]]`.
pub fn general_to_toml(spec: &GeneralSpec, path: &str) -> Result<String> {
    let v = toml::Value::try_from(spec).map_err(|e| {
        Error::invalid(
            "structure.fem.model",
            format!("cannot write the model as TOML: {e}"),
        )
    })?;
    let mut out = String::new();
    match v {
        toml::Value::Table(t) => {
            let _ = writeln!(out, "[{path}]");
            write_table(&mut out, path, &t);
        }
        other => {
            return Err(Error::invalid(
                "structure.fem.model",
                format!("is not a table: {other}"),
            ))
        }
    }
    Ok(out)
}

fn is_table_array(v: &toml::Value) -> bool {
    matches!(v, toml::Value::Array(a) if !a.is_empty() && a.iter().all(|e| e.is_table()))
}

fn key(k: &str) -> String {
    if !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        k.to_string()
    } else {
        toml::Value::String(k.to_string()).to_string()
    }
}

/// Order of the arrays of tables: elements, then discrete elements, then supports.
const TABLE_ORDER: [&str; 7] = [
    "shells",
    "frames",
    "springs",
    "dashpots",
    "masses",
    "rigid_links",
    "constraints",
];

fn is_multiline(v: &toml::Value) -> bool {
    matches!(v, toml::Value::Array(a) if a.len() > 1 && a.iter().all(|e| e.is_array()))
}

fn write_table(out: &mut String, path: &str, t: &toml::Table) {
    // One-line values first, then the long arrays (nodes, quadrangles), then sub-tables.
    for (k, v) in t
        .iter()
        .filter(|(_, v)| !is_table_array(v) && !is_multiline(v))
    {
        let _ = writeln!(out, "{} = {v}", key(k));
    }
    for (k, v) in t.iter().filter(|(_, v)| is_multiline(v)) {
        if let toml::Value::Array(a) = v {
            let _ = writeln!(out, "{} = [", key(k));
            for (i, e) in a.iter().enumerate() {
                if k == "nodes" {
                    let _ = writeln!(out, "    {e},  # {i}");
                } else {
                    let _ = writeln!(out, "    {e},");
                }
            }
            out.push_str("]\n");
        }
    }
    let mut arrays: Vec<(&String, &toml::Value)> =
        t.iter().filter(|(_, v)| is_table_array(v)).collect();
    arrays.sort_by_key(|(k, _)| {
        TABLE_ORDER
            .iter()
            .position(|o| o == k)
            .unwrap_or(TABLE_ORDER.len())
    });
    for (k, v) in arrays {
        if let toml::Value::Array(a) = v {
            let sub = format!("{path}.{}", key(k));
            for e in a {
                if let toml::Value::Table(et) = e {
                    let _ = writeln!(out, "\n[[{sub}]]");
                    write_table(out, &sub, et);
                }
            }
        }
    }
}
