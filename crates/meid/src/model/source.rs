//! Where a value came from: file positions for error messages, `--set` overrides.

use std::ops::Range;

use toml::de::{DeTable, DeValue};

use crate::{Error, Result};

/// The text of a model file and the overrides applied to it.
#[derive(Debug, Clone)]
pub struct Source {
    /// File name as the user gave it.
    pub name: String,
    pub text: String,
    /// `(path, raw value)` from `--set PATH=VALUE`.
    pub overrides: Vec<(String, String)>,
}

impl Source {
    /// "file:line:col" of the value at a dotted path (`a.b[2].c`), or of the deepest table found;
    /// `--set PATH=VALUE` when an override set it.
    pub fn locate(&self, path: &str) -> String {
        if let Some((p, v)) = self
            .overrides
            .iter()
            .rev()
            .find(|(p, _)| path_within(path, p))
        {
            return format!("--set {p}={v}");
        }
        let Ok(doc) = DeTable::parse(&self.text) else {
            return self.name.clone();
        };
        let mut span: Option<Range<usize>> = None;
        let mut table: Option<&DeTable<'_>> = Some(doc.get_ref());
        let mut value: Option<&DeValue<'_>> = None;
        for seg in split_path(path) {
            let (key, index) = seg;
            let found = if let Some(t) = table {
                t.iter()
                    .find(|(k, _)| k.get_ref().as_ref() == key)
                    .map(|(_, v)| v)
            } else if let Some(DeValue::Table(t)) = value {
                t.iter()
                    .find(|(k, _)| k.get_ref().as_ref() == key)
                    .map(|(_, v)| v)
            } else {
                None
            };
            let Some(v) = found else { break };
            span = Some(v.span());
            let mut cur = v.get_ref();
            if let Some(i) = index {
                if let DeValue::Array(a) = cur {
                    if let Some(item) = a.get(i) {
                        span = Some(item.span());
                        cur = item.get_ref();
                    }
                }
            }
            table = None;
            value = Some(cur);
        }
        match span {
            Some(s) => {
                let (line, col) = line_col(&self.text, s.start);
                format!("{}:{}:{}", self.name, line, col)
            }
            None => self.name.clone(),
        }
    }

    /// The byte range of the value at the dotted path `path` (`a.b[2].c`) in [`Self::text`],
    /// when the file writes that value itself (every key found, every index within its array);
    /// `None` otherwise (a default, a value set by an override, a path through an array of
    /// tables). Used to write a file with one value replaced and everything else kept.
    pub fn value_span(&self, path: &str) -> Option<Range<usize>> {
        let doc = DeTable::parse(&self.text).ok()?;
        let mut table: &DeTable<'_> = doc.get_ref();
        let segs = split_path(path);
        let last = segs.len().checked_sub(1)?;
        for (i, (key, index)) in segs.into_iter().enumerate() {
            let v = table
                .iter()
                .find(|(k, _)| k.get_ref().as_ref() == key)
                .map(|(_, v)| v)?;
            let item = match index {
                Some(j) => match v.get_ref() {
                    DeValue::Array(a) => a.get(j)?,
                    _ => return None,
                },
                None => v,
            };
            if i == last {
                return match item.get_ref() {
                    DeValue::Table(_) | DeValue::Array(_) => None,
                    _ => Some(item.span()),
                };
            }
            match item.get_ref() {
                DeValue::Table(t) => table = t,
                _ => return None,
            }
        }
        None
    }

    /// An input error at a path.
    pub fn error(&self, path: &str, message: impl Into<String>) -> Error {
        Error::Input {
            location: self.locate(path),
            message: message.into(),
        }
    }
}

/// True when the dotted path `path` is `within` or inside it (`a.b[1].c` is within `a.b`,
/// `a.b[1]` and itself).
pub fn path_within(path: &str, within: &str) -> bool {
    if within.is_empty() {
        return true;
    }
    path == within
        || path
            .strip_prefix(within)
            .is_some_and(|rest| rest.starts_with('.') || rest.starts_with('['))
}

/// `a.b[2].c` → [("a",None),("b",Some(2)),("c",None)].
fn split_path(path: &str) -> Vec<(&str, Option<usize>)> {
    path.split('.')
        .map(|seg| match seg.find('[') {
            Some(i) => (&seg[..i], seg[i + 1..].trim_end_matches(']').parse().ok()),
            None => (seg, None),
        })
        .collect()
}

/// 1-based line and column of a byte offset.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Turns a toml/serde error into a positioned message with a did-you-mean for unknown keys.
pub fn toml_error(name: &str, text: &str, e: &toml::de::Error) -> Error {
    let mut message = e.message().trim().to_string();
    if let Some(hint) = did_you_mean(&message) {
        message.push_str(&hint);
    }
    toml_error_message(name, text, e, message)
}

/// [`toml_error`] with the message given (the error supplies the position).
pub fn toml_error_message(name: &str, text: &str, e: &toml::de::Error, message: String) -> Error {
    let mut message = message;
    let location = match e.span() {
        Some(s) => {
            let (l, c) = line_col(text, s.start);
            format!("{name}:{l}:{c}")
        }
        None => name.to_string(),
    };
    if let Some(s) = e.span() {
        let (l, _) = line_col(text, s.start);
        if let Some(line) = text.lines().nth(l - 1) {
            message.push_str(&format!("\n  | {}", crate::input::clip(line)));
        }
    }
    Error::Input { location, message }
}

/// For serde's "unknown field `x`, expected one of `a`, `b`" adds "; did you mean `a`?".
pub fn did_you_mean(message: &str) -> Option<String> {
    let rest = message.strip_prefix("unknown field `")?;
    let end = rest.find('`')?;
    let bad = &rest[..end];
    let expected: Vec<&str> = rest[end..].split('`').skip(2).step_by(2).collect();
    let best = expected
        .iter()
        .map(|c| (strsim::jaro_winkler(bad, c), *c))
        .filter(|(s, _)| *s > 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))?;
    Some(format!("; did you mean `{}`?", best.1))
}

/// Applies `PATH=VALUE` to a TOML table. VALUE is parsed as a TOML value (number, string in
/// quotes, boolean, array), falling back to a bare string.
pub fn apply_override(table: &mut toml::Table, spec: &str) -> Result<(String, String)> {
    let (path, raw) = spec.split_once('=').ok_or_else(|| Error::Input {
        location: format!("--set {spec}"),
        message: "expected PATH=VALUE, e.g. contact.bed_damper.stiffness=1.26e8".into(),
    })?;
    let path = path.trim();
    let raw = raw.trim();
    if path.is_empty() {
        return Err(Error::Input {
            location: format!("--set {spec}"),
            message: "empty PATH".into(),
        });
    }
    let value: toml::Value = match toml::from_str::<toml::Table>(&format!("v = {raw}")) {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or(toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.to_string()),
    };
    let segs = split_set_path(path).map_err(|message| Error::Input {
        location: format!("--set {spec}"),
        message,
    })?;
    set_path(table, &segs, value, spec, "")?;
    Ok((path.to_string(), raw.to_string()))
}

/// A `--set` path split strictly: `a.b[2].c` → [("a", None), ("b", Some("2")), ("c", None)].
/// Each segment is a key, optionally followed by one `[index]` and nothing after it.
fn split_set_path(path: &str) -> std::result::Result<Vec<(&str, Option<&str>)>, String> {
    let form = "give PATH as dotted keys with optional [index] after a key, e.g. structure.lumped.masses[1].mass";
    path.split('.')
        .map(|seg| {
            let (key, index) = match seg.find('[') {
                Some(i) => {
                    let rest = &seg[i + 1..];
                    let Some(close) = rest.find(']') else {
                        return Err(format!("`{seg}` has an unclosed `[`; {form}"));
                    };
                    if close + 1 != rest.len() {
                        return Err(format!(
                            "`{seg}`: nothing may follow `[{}]` (found `{}`); {form}",
                            &rest[..close],
                            &rest[close + 1..]
                        ));
                    }
                    (&seg[..i], Some(&rest[..close]))
                }
                None => (seg, None),
            };
            if key.is_empty() {
                return Err(format!("empty key in `{path}`; {form}"));
            }
            if key.contains(']') {
                return Err(format!("`{seg}` has a `]` without `[`; {form}"));
            }
            Ok((key, index))
        })
        .collect()
}

fn set_path(
    table: &mut toml::Table,
    segs: &[(&str, Option<&str>)],
    value: toml::Value,
    spec: &str,
    parent: &str,
) -> Result<()> {
    let err = |message: String| Error::Input {
        location: format!("--set {spec}"),
        message,
    };
    let Some(((key, index), rest)) = segs.split_first() else {
        return Ok(());
    };
    let here = if parent.is_empty() {
        key.to_string()
    } else {
        format!("{parent}.{key}")
    };
    match index {
        None if rest.is_empty() => {
            table.insert(key.to_string(), value);
            Ok(())
        }
        None => {
            let entry = table
                .entry(key.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            let sub = entry.as_table_mut().ok_or_else(|| {
                err(format!(
                    "{here}: is not a table, so `{here}.{}` cannot be set",
                    rest[0].0
                ))
            })?;
            set_path(sub, rest, value, spec, &here)
        }
        Some(raw) => {
            let arr = table
                .get_mut(*key)
                .and_then(|v| v.as_array_mut())
                .ok_or_else(|| {
                    err(format!(
                        "{here}: is not an array in the model, so `{here}[{raw}]` cannot be set; set the whole value instead (--set '{here}=...')"
                    ))
                })?;
            let len = arr.len();
            let valid = if len == 0 {
                "the array is empty: set the whole array instead".to_string()
            } else {
                format!(
                    "valid indices are 0 to {} (the array has {len} entries)",
                    len - 1
                )
            };
            let idx: usize = raw.trim().parse().map_err(|_| {
                err(format!(
                    "{here}: index `{raw}` is not a whole number >= 0; {valid}"
                ))
            })?;
            let item = arr
                .get_mut(idx)
                .ok_or_else(|| err(format!("{here}: index {idx} is out of range; {valid}")))?;
            let here = format!("{here}[{idx}]");
            if rest.is_empty() {
                *item = value;
                Ok(())
            } else {
                let sub = item.as_table_mut().ok_or_else(|| {
                    err(format!(
                        "{here}: is not a table, so `{here}.{}` cannot be set",
                        rest[0].0
                    ))
                })?;
                set_path(sub, rest, value, spec, &here)
            }
        }
    }
}
