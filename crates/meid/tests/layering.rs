//! The crate's layers (crates/meid/src/lib.rs, "Layers"): every `crate::STAGE` a module's code
//! names is a stage its layer may import, so no module imports one that imports it back. Read
//! from the source text: comment lines are left out, `crate::NAME` paths in code are counted
//! (in `use` lines and inline), and the two upward imports the crate doc names are allowed in
//! their one file each. Within a stage, the pairs that once tied circles are checked one way:
//! measure's processing does not name its mapping, the general model and the model file's
//! sections do not name the FE reduction, and the CLI's shard handling names no study.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Stages every module may import.
const BASE: [&str; 5] = ["error", "input", "limits", "rng", "num"];

/// Stage → the stages (besides [`BASE`]) its code may name.
fn allowed() -> BTreeMap<&'static str, Vec<&'static str>> {
    BTreeMap::from([
        ("record", vec![]),
        ("identify", vec![]),
        ("modal", vec![]),
        ("plot", vec![]),
        ("structure", vec!["modal"]),
        ("io", vec!["structure", "modal", "record"]),
        ("impact", vec!["modal"]),
        ("integrate", vec!["impact", "modal"]),
        (
            "model",
            vec!["integrate", "impact", "io", "structure", "modal"],
        ),
        (
            "analysis",
            vec!["model", "integrate", "impact", "io", "modal", "plot"],
        ),
        (
            "measure",
            vec![
                "analysis", "model", "io", "record", "plot", "impact", "identify",
            ],
        ),
        (
            "foundation",
            vec!["analysis", "model", "integrate", "modal"],
        ),
    ])
}

/// The two upward imports the crate doc names: (file under src/, stage, the only paths it may
/// name there).
const UPWARD: [(&str, &str, &[&str]); 2] = [
    (
        "structure/machine.rs",
        "model",
        &["model::general", "model::material", "model::source"],
    ),
    ("model/spec.rs", "measure", &["measure::mapping"]),
];

/// Every `.rs` file under `dir`, recursively (also used by the function-length guard).
pub(crate) fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The lines of a file that are not comments (test modules included: a test may not import
/// upwards either).
fn code_lines(text: &str) -> Vec<&str> {
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect()
}

/// Every `crate::PATH` (up to two segments) named in `line`.
fn crate_paths(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = line;
    while let Some(i) = rest.find("crate::") {
        let before = rest[..i].chars().last();
        rest = &rest[i + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // e.g. `meid_crate::`
        }
        let seg: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
            .collect();
        let parts: Vec<&str> = seg.split("::").filter(|s| !s.is_empty()).collect();
        if let Some(first) = parts.first() {
            let mut p = first.to_string();
            if let Some(second) = parts.get(1) {
                p = format!("{p}::{second}");
            }
            out.push(p);
        }
    }
    out
}

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

#[test]
fn every_stage_imports_only_the_stages_below_it() {
    let allowed = allowed();
    let root = src();
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    let mut faults = BTreeSet::new();
    for f in &files {
        let rel = f
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let stage = rel.split(['/', '.']).next().unwrap().to_string();
        let Some(may) = allowed.get(stage.as_str()) else {
            continue; // report, lib.rs and the base are not limited
        };
        let text = std::fs::read_to_string(f).unwrap();
        for (n, line) in code_lines(&text).into_iter().enumerate() {
            for path in crate_paths(line) {
                let top = path.split("::").next().unwrap();
                if top == stage
                    || BASE.contains(&top)
                    || top.chars().next().is_some_and(|c| c.is_uppercase())
                    || may.contains(&top)
                {
                    continue;
                }
                let upward_ok = UPWARD.iter().any(|(file, to, paths)| {
                    *file == rel && *to == top && paths.iter().any(|p| path == *p)
                });
                if !upward_ok {
                    faults.insert(format!("{rel} (code line {}): crate::{path}", n + 1));
                }
            }
        }
    }
    assert!(
        faults.is_empty(),
        "imports against the layers of lib.rs:\n{}",
        faults.into_iter().collect::<Vec<_>>().join("\n")
    );
}

/// `file` (under `dir`) names none of `names` in its code.
fn names_none(dir: &Path, file: &str, names: &[&str]) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join(file)).unwrap();
    code_lines(&text)
        .into_iter()
        .filter(|l| names.iter().any(|n| l.contains(n)))
        .map(|l| format!("{file}: {}", l.trim()))
        .collect()
}

#[test]
fn the_former_circles_run_one_way() {
    let root = src();
    let cli = Path::new(env!("CARGO_MANIFEST_DIR")).join("../meid-cli/src");
    let mut faults = Vec::new();
    faults.extend(names_none(&root, "measure/process.rs", &["mapping::"]));
    faults.extend(names_none(&root, "model/general.rs", &["fem::"]));
    faults.extend(names_none(
        &root,
        "model/material.rs",
        &["fem::", "general::"],
    ));
    faults.extend(names_none(&root, "model/spec.rs", &["fem::"]));
    faults.extend(names_none(
        &root,
        "structure/machine.rs",
        &["model::fem", "model::Source", "model::BED_PART"],
    ));
    for f in ["record/mod.rs", "record/units.rs"] {
        faults.extend(names_none(&root, f, &["crate::measure", "crate::io"]));
    }
    faults.extend(names_none(
        &cli,
        "shard.rs",
        &["crate::sweep", "crate::montecarlo"],
    ));
    assert!(faults.is_empty(), "{}", faults.join("\n"));
}
