//! The documentation's paths resolve: every relative link of every markdown file of the
//! repository (`[text](path)`, `[text](path#anchor)`) names a file or folder that exists, and
//! every `docs/….md` path named anywhere in the repository's sources, tests, examples, scripts
//! and pages (error messages and doc comments too) names a page that exists. Read from the
//! files' text; build outputs (`target/`), fuzzing corpora and crash inputs (`corpus/`,
//! `artifacts/`) and hidden folders other than `.ci` are left out.

use std::path::{Path, PathBuf};

/// The repository's root (this crate is `crates/meid`).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every file under `dir`, skipping build outputs and hidden folders (except `.ci`).
fn files_under(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            let hidden = name.starts_with('.') && name != ".ci";
            // Fuzzing corpora and crash inputs are generated (mutated copies of the examples).
            let generated = [
                "target",
                "node_modules",
                "__pycache__",
                "corpus",
                "artifacts",
            ];
            if !hidden && !generated.contains(&name.as_str()) {
                files_under(&path, out);
            }
        } else {
            out.push(path);
        }
    }
}

/// The targets of the inline markdown links of `text` (`](target)`), without their
/// `#anchor` and title, that are relative paths (not URLs, not `#anchor` alone). Links inside
/// fenced code blocks and inline code spans are not links.
fn relative_links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Drop inline code spans: `a](b)` in code is not a link.
        let prose: String = line
            .split('`')
            .enumerate()
            .filter(|(i, _)| i % 2 == 0)
            .map(|(_, s)| s)
            .collect::<Vec<_>>()
            .join(" ");
        let mut rest = prose.as_str();
        while let Some(at) = rest.find("](") {
            rest = &rest[at + 2..];
            let Some(end) = rest.find(')') else { break };
            let target = rest[..end].split_whitespace().next().unwrap_or("");
            let path = target.split('#').next().unwrap_or("");
            let external = target.contains("://") || target.starts_with("mailto:");
            if !path.is_empty() && !external {
                out.push(path.to_string());
            }
            rest = &rest[end..];
        }
    }
    out
}

/// Every `docs/….md` path named in `text` (not the tail of a longer path such as
/// `crates/x/docs/y.md`).
fn docs_paths(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let bytes = text.as_bytes();
    let path_char = |b: u8| b.is_ascii_alphanumeric() || matches!(b, b'/' | b'-' | b'_' | b'.');
    let mut from = 0;
    while let Some(at) = text[from..].find("docs/") {
        let start = from + at;
        from = start + 5;
        if start > 0 && path_char(bytes[start - 1]) {
            continue;
        }
        let mut end = start + 5;
        while end < bytes.len() && path_char(bytes[end]) {
            end += 1;
        }
        let candidate = text[start..end].trim_end_matches('.');
        if let Some(stem) = candidate.strip_suffix(".md") {
            out.push(format!("{stem}.md"));
        }
    }
    out
}

#[test]
fn the_link_readers_find_what_a_page_names() {
    let page = "See [the model](reference/model-file.md#units), [web](https://x.org/a.md), \
                [here](#top), `[code](not/a/link.md)` and [two](../b.md \"title\").\n\
                ```\n[fenced](c.md)\n```\n";
    assert_eq!(relative_links(page), ["reference/model-file.md", "../b.md"]);
    let source = "// docs/explanations/fem.md, \"Repeated eigenvalues\"; crates/x/docs/y.md; \
                  see docs/guide.md. and docs/reference/";
    assert_eq!(
        docs_paths(source),
        ["docs/explanations/fem.md", "docs/guide.md"]
    );
}

#[test]
fn every_relative_link_and_docs_path_resolves() {
    let root = root();
    let mut files = Vec::new();
    for dir in ["crates", "docs", "examples", "bench", "fuzz", ".ci"] {
        files_under(&root.join(dir), &mut files);
    }
    files.push(root.join("README.md"));
    let mut broken = Vec::new();
    let mut pages = 0;
    for file in &files {
        let Ok(text) = std::fs::read_to_string(file) else {
            continue; // not text
        };
        let shown = file
            .strip_prefix(&root)
            .unwrap_or(file)
            .display()
            .to_string();
        if file.extension().is_some_and(|e| e == "md") {
            pages += 1;
            let dir = file.parent().unwrap_or(&root);
            for link in relative_links(&text) {
                if !dir.join(&link).exists() {
                    broken.push(format!("{shown}: link ({link})"));
                }
            }
        }
        for path in docs_paths(&text) {
            if !root.join(&path).is_file() {
                broken.push(format!("{shown}: names {path}"));
            }
        }
    }
    assert!(
        pages >= 10,
        "only {pages} markdown files found under {}",
        root.display()
    );
    assert!(
        broken.is_empty(),
        "paths that do not exist:\n{}",
        broken.join("\n")
    );
}

/// The words inside the inline code spans (`` `…` ``) and fenced blocks of a page: the names
/// it documents.
fn code_words(page: &str) -> std::collections::BTreeSet<String> {
    let mut words = std::collections::BTreeSet::new();
    let mut fenced = false;
    for line in page.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        let spans: Vec<&str> = if fenced {
            vec![line]
        } else {
            line.split('`').skip(1).step_by(2).collect()
        };
        for span in spans {
            let is_word = |c: char| c.is_ascii_alphanumeric() || c == '_';
            words.extend(span.split(|c: char| !is_word(c)).map(str::to_string));
        }
    }
    words
}

/// Every key of `value` (tables, and tables inside arrays), as dotted paths. The children of
/// tables whose keys are the user's own names (`bed_points`, `sets`, `points`) are not keys.
fn toml_keys(value: &toml::Value, path: &str, out: &mut Vec<String>) {
    match value {
        toml::Value::Table(t) => {
            for (k, v) in t {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                out.push(p.clone());
                if !matches!(k.as_str(), "bed_points" | "sets" | "points") {
                    toml_keys(v, &p, out);
                }
            }
        }
        toml::Value::Array(a) => a.iter().for_each(|v| toml_keys(v, path, out)),
        _ => {}
    }
}

#[test]
fn the_key_readers_find_keys_and_documented_words() {
    let v: toml::Value =
        toml::from_str("a = 1\n[b]\nc = [{ d = 2 }]\n[b.sets]\nmine = [1]\n").expect("toml");
    let mut keys = Vec::new();
    toml_keys(&v, "", &mut keys);
    assert_eq!(keys, ["a", "b", "b.c", "b.c.d", "b.sets"]);
    let words = code_words("`length_x = 1` and `{ d, e }`, not f\n```toml\ng = 2\n```\n");
    for w in ["length_x", "d", "e", "g"] {
        assert!(words.contains(w), "{w}");
    }
    assert!(!words.contains("f"));
}

/// Every key the examples use is named in the model-file reference.
#[test]
fn every_key_of_the_examples_is_in_the_model_file_reference() {
    let root = root();
    let page = std::fs::read_to_string(root.join("docs/reference/model-file.md"))
        .expect("docs/reference/model-file.md");
    let words = code_words(&page);
    let mut missing = Vec::new();
    let mut examples = 0;
    for entry in std::fs::read_dir(root.join("examples")).expect("examples/") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        examples += 1;
        let text = std::fs::read_to_string(&path).expect("example");
        let value: toml::Value = toml::from_str(&text).expect("example parses");
        let mut keys = Vec::new();
        toml_keys(&value, "", &mut keys);
        for key in keys {
            let last = key.rsplit('.').next().unwrap_or(&key);
            if !words.contains(last) {
                let name = path.file_name().unwrap_or_default().to_string_lossy();
                missing.push(format!("examples/{name}: {key}"));
            }
        }
    }
    assert!(examples >= 5, "only {examples} examples");
    missing.sort();
    missing.dedup();
    assert!(
        missing.is_empty(),
        "keys of the examples not named in docs/reference/model-file.md:\n{}",
        missing.join("\n")
    );
}
