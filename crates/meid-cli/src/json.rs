//! The shape every command's `--json` shares: one JSON object whose `warnings` and `notes`
//! members carry the model's diagnostics (the same warnings the terminal shows on stderr) and
//! the command's own notes (docs/reference/json.md).
//!
//! A command loads at most one model, so the diagnostics are recorded once per run
//! ([`record`], called where the model's warnings are shown) and added when the object is
//! printed ([`print`]).

use std::sync::Mutex;

use anyhow::Result;

use serde_json::Value;

/// The run's model diagnostics: (warnings, notes).
static DIAGNOSTICS: Mutex<(Vec<String>, Vec<String>)> = Mutex::new((Vec::new(), Vec::new()));

/// Records the model's warnings and notes for the `--json` object of this run.
pub fn record(diag: &meid::model::Diagnostics) {
    if let Ok(mut d) = DIAGNOSTICS.lock() {
        d.0 = diag.warnings.clone();
        d.1 = diag.notes.clone();
    }
}

/// `value` (which must serialise to an object) with `warnings` and `notes` members: the
/// object's own entries first, then the recorded model diagnostics not already among them.
pub fn object(value: &impl serde::Serialize) -> Result<Value> {
    let mut v = serde_json::to_value(value)?;
    let Value::Object(o) = &mut v else {
        anyhow::bail!("internal: a command's JSON output must be an object");
    };
    let (warnings, notes) = DIAGNOSTICS.lock().map(|d| d.clone()).unwrap_or_default();
    for (key, recorded) in [("warnings", warnings), ("notes", notes)] {
        let entry = o.entry(key).or_insert_with(|| Value::Array(Vec::new()));
        if let Value::Array(list) = entry {
            for r in recorded {
                let r = Value::String(r);
                if !list.contains(&r) {
                    list.push(r);
                }
            }
        }
    }
    Ok(v)
}

/// Prints [`object`] of `value`, pretty, on stdout.
pub fn print(value: &impl serde::Serialize) -> Result<()> {
    println!("{}", serde_json::to_string_pretty(&object(value)?)?);
    Ok(())
}
