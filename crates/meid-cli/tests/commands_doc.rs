//! docs/reference/commands.md against the command line itself: every command `meid --help`
//! lists (and every subcommand of `meid model`) has a section headed `` ### `meid NAME` ``,
//! and the options table of that section names exactly the long options `meid NAME --help`
//! prints — none missing, none invented. The global options (`--max-memory`, `--color`,
//! `--help`, `--version`) are documented once, in the section "Every command".

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use crate::common::{meid, ok};

/// Options every command has, documented once.
const GLOBAL: [&str; 4] = ["--help", "--version", "--max-memory", "--color"];

/// The names under the heading `Commands:` of a clap help text (`help` left out).
fn commands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|name| *name != "help")
        .map(str::to_string)
        .collect()
}

/// The long options of a clap help text: the first `--name` of each option line. Option
/// lines start `  -x, --name` or `      --name` (two or six spaces); description lines are
/// indented further, so a `--name` quoted at the start of a wrapped description is not one.
fn help_options(help: &str) -> BTreeSet<String> {
    help.lines()
        .filter_map(|l| {
            let flags = if let Some(short) = l.strip_prefix("  -") {
                if short.starts_with('-') || short.starts_with(' ') {
                    return None;
                }
                short.split_once(", ")?.1
            } else {
                l.strip_prefix("      --").map(|_| &l[6..])?
            };
            let name: String = flags
                .strip_prefix("--")?
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                .collect();
            (!name.is_empty()).then(|| format!("--{name}"))
        })
        .filter(|o| !GLOBAL.contains(&o.as_str()))
        .collect()
}

/// Per `` ### `meid NAME` `` section of the page, the `--options` in the first cell of its
/// table rows.
fn doc_options(page: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mut out = BTreeMap::new();
    let mut current: Option<String> = None;
    for line in page.lines() {
        if let Some(h) = line.strip_prefix("### `meid ") {
            let name = h.trim_end().trim_end_matches('`').to_string();
            out.insert(name.clone(), BTreeSet::new());
            current = Some(name);
        } else if line.starts_with("## ") {
            current = None;
        } else if let (Some(name), Some(row)) = (&current, line.strip_prefix('|')) {
            let first = row.split('|').next().unwrap_or("");
            let set = out.get_mut(name).expect("section inserted");
            for part in first.split("--").skip(1) {
                let opt: String = part
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                    .collect();
                if opt.starts_with(|c: char| c.is_ascii_alphabetic()) {
                    set.insert(format!("--{opt}"));
                }
            }
        }
    }
    out
}

#[test]
fn the_readers_find_commands_and_options() {
    let help = "Usage: meid <COMMAND>\n\nCommands:\n  simulate  One blow\n  help  Print\n\n\
                Options:\n  -o, --output <DIR>  Write\n      --json  Print\n          --not-an-option in a\n  -h, --help  Help\n";
    assert_eq!(commands(help), ["simulate"]);
    let opts: Vec<_> = help_options(help).into_iter().collect();
    assert_eq!(opts, ["--json", "--output"]);
    let page = "### `meid simulate`\n\n| option | what |\n|---|---|\n\
                | `-o, --output DIR` | x --not-this |\n| `--json` | y |\n## Other\n| `--no` | z |\n";
    let docs = doc_options(page);
    let got: Vec<_> = docs["simulate"].iter().cloned().collect();
    assert_eq!(got, ["--json", "--output"]);
}

#[test]
fn every_command_and_option_is_in_the_reference() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/reference/commands.md");
    let page = std::fs::read_to_string(&path).expect("docs/reference/commands.md");
    let documented = doc_options(&page);
    let top = ok(meid().arg("--help").output().unwrap());
    let mut names = Vec::new();
    for name in commands(&top) {
        let help = ok(meid().args([name.as_str(), "--help"]).output().unwrap());
        let subs = commands(&help);
        if subs.is_empty() {
            names.push(name);
        } else {
            names.extend(subs.into_iter().map(|s| format!("{name} {s}")));
        }
    }
    assert!(
        names.len() >= 19,
        "only {} commands in `meid --help`",
        names.len()
    );
    let mut problems = Vec::new();
    for name in &names {
        let args: Vec<&str> = name.split(' ').chain(["--help"]).collect();
        let help = ok(meid().args(&args).output().unwrap());
        let expected = help_options(&help);
        let Some(got) = documented.get(name) else {
            problems.push(format!("`meid {name}`: no section ### `meid {name}`"));
            continue;
        };
        for missing in expected.difference(got) {
            problems.push(format!(
                "`meid {name}`: {missing} is not in the options table"
            ));
        }
        for invented in got.difference(&expected) {
            problems.push(format!(
                "`meid {name}`: {invented} is documented but not an option"
            ));
        }
    }
    for name in documented.keys() {
        if !names.contains(name) {
            problems.push(format!("section `meid {name}` names no command"));
        }
    }
    assert!(
        problems.is_empty(),
        "docs/reference/commands.md against `meid COMMAND --help`:\n{}",
        problems.join("\n")
    );
}
