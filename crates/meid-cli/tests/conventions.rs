//! Conventions users expect of a command-line tool: a closed pipe ends quietly, `--color` /
//! `NO_COLOR` are honoured, `-o`/`-q`/`--json` mean the same on every subcommand, shell
//! completions and a manual page, and `--version` names the git commit.

use crate::common;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use common::{meid, paper_example, stderr, tmpdir};

const ESC: &str = "\x1b[";

/// The analysis subcommands with small, fast arguments (each well under a second).
fn subcommands() -> Vec<(&'static str, Vec<String>)> {
    let m = paper_example().display().to_string();
    let v = |a: &[&str]| -> Vec<String> {
        a.iter().map(|s| s.to_string()).chain([m.clone()]).collect()
    };
    vec![
        ("simulate", v(&["simulate"])),
        ("modes", v(&["modes"])),
        ("sweep", v(&["sweep", "--vary", "wd/ws=0.5,1"])),
        ("compare", v(&["compare", "--duration", "0.2"])),
        (
            "optimize",
            v(&[
                "optimize",
                "--over",
                "wd/ws",
                "--grid",
                "9",
                "--max-simulations",
                "12",
            ]),
        ),
        ("blows", v(&["blows", "--blows", "2"])),
        (
            "montecarlo",
            v(&[
                "montecarlo",
                "--vary",
                "contact.slider_bed.stiffness=lognormal(4.3e7,0.2)",
                "--samples",
                "4",
            ]),
        ),
        (
            "report",
            v(&[
                "report",
                "--map-points",
                "5",
                "--blows",
                "2",
                "--duration",
                "0.2",
            ]),
        ),
    ]
}

/// Sweep writes into `./sweep-out` unless told otherwise: run every command in its own
/// directory so nothing lands in the source tree.
fn in_dir(dir: &Path, args: &[String]) -> Command {
    let mut c = meid();
    c.current_dir(dir).args(args);
    c
}

fn files_in(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .map(|r| r.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default()
}

// ---------------------------------------------------------------------------------------------
// 1. A closed pipe (`meid … | head -1`).

/// Every subcommand, its stdout a pipe whose reading end is closed before it writes: each write
/// fails with EPIPE. It used to panic in `println!` ("failed printing to stdout: Broken pipe",
/// exit 101). Now: exit 0, no panic message, and the run's files are still written whole
/// (the output is dropped, the run is not cut short).
#[test]
fn closed_pipe_ends_quietly_on_every_subcommand() {
    let d = tmpdir("conv", "pipe");
    for (name, args) in subcommands() {
        for extra in [&[][..], &["--json"][..]] {
            // A directory per run: a second sweep into the first one's directory would be
            // refused (its journal needs --resume or --force).
            let out_dir = d.join(format!("{name}{}", extra.len()));
            let mut child = in_dir(&d, &args)
                .args(extra)
                .arg("-o")
                .arg(&out_dir)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap();
            // Close the only reading end before the child can write.
            drop(child.stdout.take());
            let out = child.wait_with_output().unwrap();
            let err = stderr(&out);
            assert!(!err.contains("panicked"), "{name} {extra:?}: {err}");
            assert_ne!(out.status.code(), Some(101), "{name} {extra:?}: {err}");
            assert!(out.status.success(), "{name} {extra:?}: {err}");
            assert!(err.is_empty(), "{name} {extra:?}: nothing on stderr: {err}");
            assert!(
                !files_in(&out_dir).is_empty(),
                "{name}: -o files written despite the closed pipe"
            );
        }
    }
}

/// `meid completions bash | head -1` with an output larger than the pipe's buffer (64 KiB):
/// the reader takes one line and goes while meid is still writing.
#[test]
fn pipe_closed_after_one_line_ends_quietly() {
    // 300 sweep points as JSON (≈ 0.5 MB): meid blocks on the full pipe, then meets EPIPE.
    let d = tmpdir("conv", "head");
    let mut child = meid()
        .current_dir(&d)
        .args(["sweep", "--vary", "wd/ws=0.2..3:300", "--json", "-o", "out"])
        .arg(paper_example())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert_eq!(first.trim(), "{");
    let out = child.wait_with_output().unwrap();
    let err = stderr(&out);
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.status.success(), "{:?}: {err}", out.status);
    // The sweep's own files are whole: sweep.json is the complete JSON document.
    let text = std::fs::read_to_string(d.join("out/sweep.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["points"].as_array().unwrap().len(), 300);
}

/// A failure to write stdout other than a closed pipe (a full disk behind `> file`) is an
/// error with exit code 2, not a panic and not a silent success.
#[test]
fn stdout_write_error_is_reported() {
    let full = Path::new("/dev/full");
    if !full.exists() {
        eprintln!("no /dev/full on this system: test not applicable");
        return;
    }
    let out = meid()
        .arg("simulate")
        .arg(paper_example())
        .stdout(std::fs::File::create(full).unwrap())
        .output()
        .unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("cannot write to standard output") && err.contains("No space left"),
        "{err}"
    );
}

// ---------------------------------------------------------------------------------------------
// 2. Colour.

/// Runs `meid ARGS` with the environment's colour variables removed and `env` set; stderr.
fn stderr_with(args: &[&str], env: &[(&str, &str)]) -> (Option<i32>, String) {
    let mut c = meid();
    c.args(args)
        .env_remove("NO_COLOR")
        .env_remove("CLICOLOR_FORCE");
    for (k, v) in env {
        c.env(k, v);
    }
    let out = c.output().unwrap();
    (out.status.code(), stderr(&out))
}

#[test]
fn color_always_colours_error_and_warning() {
    let (code, err) = stderr_with(
        &["--color", "always", "simulate", "no-such-model.toml"],
        &[],
    );
    assert_eq!(code, Some(2));
    assert!(err.starts_with("\x1b[1;31merror:\x1b[0m "), "{err:?}");
    // The flag is global: after the subcommand too, and it wins over NO_COLOR.
    let (_, err) = stderr_with(
        &["simulate", "no-such-model.toml", "--color=always"],
        &[("NO_COLOR", "1")],
    );
    assert!(err.starts_with("\x1b[1;31merror:\x1b[0m "), "{err:?}");
    // A warning (the clamped plate's three modes carry < 95 % of the static flexibility
    // without the static correction).
    let plate = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/clamped_plate.toml");
    let (code, err) = stderr_with(
        &[
            "--color",
            "always",
            "modes",
            plate.to_str().unwrap(),
            "--set",
            "structure.fem.static_correction=false",
        ],
        &[],
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(err.starts_with("\x1b[1;33mwarning:\x1b[0m "), "{err:?}");
    // clap's own usage errors follow the flag too.
    let (code, err) = stderr_with(&["--color", "always", "simulate"], &[]);
    assert_eq!(code, Some(2));
    assert!(err.contains(ESC), "{err:?}");
}

#[test]
fn no_color_and_pipes_are_plain() {
    // Piped stderr, auto: plain.
    let (code, err) = stderr_with(&["simulate", "no-such-model.toml"], &[]);
    assert_eq!(code, Some(2));
    assert!(err.starts_with("error: "), "{err:?}");
    assert!(!err.contains(ESC), "{err:?}");
    // CLICOLOR_FORCE makes auto colour a pipe ...
    let (_, err) = stderr_with(
        &["--color", "auto", "simulate", "no-such-model.toml"],
        &[("CLICOLOR_FORCE", "1")],
    );
    assert!(err.contains(ESC), "{err:?}");
    // ... unless NO_COLOR is set (any non-empty value) ...
    for v in ["1", "0", "yes"] {
        let (_, err) = stderr_with(
            &["--color", "auto", "simulate", "no-such-model.toml"],
            &[("CLICOLOR_FORCE", "1"), ("NO_COLOR", v)],
        );
        assert!(!err.contains(ESC), "NO_COLOR={v}: {err:?}");
    }
    // ... or --color never.
    let (_, err) = stderr_with(
        &["--color", "never", "simulate", "no-such-model.toml"],
        &[("CLICOLOR_FORCE", "1")],
    );
    assert!(!err.contains(ESC), "{err:?}");
    // An empty NO_COLOR is unset.
    let (_, err) = stderr_with(
        &["simulate", "no-such-model.toml"],
        &[("CLICOLOR_FORCE", "1"), ("NO_COLOR", "")],
    );
    assert!(err.contains(ESC), "{err:?}");
    // A bad --color value is a usage error naming the valid ones.
    let (code, err) = stderr_with(&["--color", "sometimes", "simulate", "x.toml"], &[]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("auto") && err.contains("always") && err.contains("never"),
        "{err}"
    );
}

/// On a real terminal (a pseudo-terminal from util-linux `script`), auto colours `error:`
/// and NO_COLOR turns it off.
#[test]
fn terminal_auto_colours_unless_no_color() {
    let has_script = Command::new("script")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_script {
        eprintln!("util-linux `script` not found: terminal test not run (CLICOLOR_FORCE tests cover the logic)");
        return;
    }
    let cmd = format!("{} simulate no-such-model.toml", env!("CARGO_BIN_EXE_meid"));
    let run = |no_color: Option<&str>| {
        let mut c = Command::new("script");
        c.args(["-qec", &cmd, "/dev/null"])
            .env_remove("NO_COLOR")
            .env_remove("CLICOLOR_FORCE")
            .stdin(Stdio::null());
        if let Some(v) = no_color {
            c.env("NO_COLOR", v);
        }
        let out = c.output().unwrap();
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let tty = run(None);
    assert!(tty.contains("\x1b[1;31merror:\x1b[0m"), "{tty:?}");
    let plain = run(Some("1"));
    assert!(
        plain.contains("error:") && !plain.contains(ESC),
        "{plain:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// 3. -o/--output, -q/--quiet and --json on every subcommand.

#[test]
fn every_subcommand_has_output_quiet_and_json() {
    let d = tmpdir("conv", "flags");
    for (name, args) in subcommands() {
        // -q: nothing at all but errors.
        let out = in_dir(&d, &args).arg("-q").output().unwrap();
        assert!(out.status.success(), "{name} -q: {}", stderr(&out));
        assert!(out.stdout.is_empty(), "{name} -q printed on stdout");
        assert!(out.stderr.is_empty(), "{name} -q printed on stderr");
        let out = in_dir(&d, &args).arg("--quiet").output().unwrap();
        assert!(
            out.status.success() && out.stdout.is_empty(),
            "{name} --quiet"
        );

        // --json: stdout is exactly one JSON document.
        let out = in_dir(&d, &args).arg("--json").output().unwrap();
        assert!(out.status.success(), "{name} --json: {}", stderr(&out));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout)
            .unwrap_or_else(|e| panic!("{name} --json: not JSON: {e}"));
        assert!(v.is_object(), "{name} --json: an object");

        // -o DIR and --output DIR: the run's files in DIR.
        for flag in ["-o", "--output"] {
            let dir = d.join(format!("{name}{flag}"));
            let out = in_dir(&d, &args)
                .args([flag, dir.to_str().unwrap(), "-q"])
                .output()
                .unwrap();
            assert!(out.status.success(), "{name} {flag}: {}", stderr(&out));
            assert!(out.stdout.is_empty(), "{name} {flag} -q: stdout empty");
            assert!(
                files_in(&dir).iter().any(|f| f.extension().is_some()),
                "{name} {flag}: files in {}",
                dir.display()
            );
        }

        // --json and -q exclude each other: a usage error, exit 2.
        let out = in_dir(&d, &args).args(["--json", "-q"]).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{name} --json -q");
        assert!(
            stderr(&out).contains("cannot be used with"),
            "{name}: {}",
            stderr(&out)
        );
    }
}

/// `optimize -o DIR` writes optimize.json, the same report as `--json`.
#[test]
fn optimize_output_is_its_json_report() {
    let d = tmpdir("conv", "opt");
    let args = &subcommands()[4].1;
    let printed: serde_json::Value = serde_json::from_slice(
        &in_dir(&d, args)
            .args(["--json", "-o", "out"])
            .output()
            .unwrap()
            .stdout,
    )
    .unwrap();
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/optimize.json")).unwrap())
            .unwrap();
    assert_eq!(printed, written);
    assert!(written["optimum"].is_array());
}

// ---------------------------------------------------------------------------------------------
// 4. Completions and manual pages.

const SUBCOMMANDS: [&str; 19] = [
    "simulate",
    "modes",
    "model",
    "sweep",
    "compare",
    "optimize",
    "blows",
    "montecarlo",
    "report",
    "merge",
    "paper",
    "measure",
    "frf",
    "identify",
    "correlate",
    "validate",
    "calibrate",
    "completions",
    "man",
];

fn stdout_of(args: &[&str]) -> String {
    common::ok(meid().args(args).output().unwrap())
}

#[test]
fn completions_name_every_subcommand() {
    let bash = stdout_of(&["completions", "bash"]);
    assert!(bash.contains("_meid()"), "defines the completion function");
    assert!(bash.contains("complete -F _meid"), "registers it");
    let zsh = stdout_of(&["completions", "zsh"]);
    assert!(zsh.starts_with("#compdef meid"));
    let fish = stdout_of(&["completions", "fish"]);
    assert!(fish.contains("complete -c meid"));
    for s in SUBCOMMANDS {
        for (shell, text) in [("bash", &bash), ("zsh", &zsh), ("fish", &fish)] {
            assert!(text.contains(s), "{shell} completion names `{s}`");
        }
    }
    // Options of a subcommand and the global --color with its values.
    assert!(bash.contains("--duration") && bash.contains("--color"));
    assert!(fish.contains("always") && fish.contains("never"));
    let out = meid().args(["completions", "tcsh"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn man_page_is_roff_with_every_subcommand() {
    let man = stdout_of(&["man"]);
    assert!(
        man.contains("\n.TH meid 1 "),
        "{}",
        &man[..200.min(man.len())]
    );
    assert!(man.contains(".SH NAME") && man.contains(".SH SYNOPSIS"));
    assert!(man.contains(env!("CARGO_PKG_VERSION")));
    for s in SUBCOMMANDS {
        assert!(man.contains(s), "meid(1) lists `{s}`");
    }
    let sim = stdout_of(&["man", "simulate"]);
    assert!(sim.contains(".TH meid\\-simulate 1") || sim.contains(".TH meid-simulate 1"));
    assert!(
        sim.contains("duration"),
        "meid-simulate(1) lists its options"
    );
    let out = meid().args(["man", "simulat"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("valid: simulate"), "{}", stderr(&out));

    // -o DIR: one page per command.
    let d = tmpdir("conv", "man");
    common::ok(meid().args(["man", "-q", "-o"]).arg(&d).output().unwrap());
    let mut pages: Vec<String> = files_in(&d)
        .iter()
        .filter_map(|p| p.file_name().map(|f| f.to_string_lossy().to_string()))
        .collect();
    pages.sort();
    let mut want: Vec<String> = std::iter::once("meid.1".to_string())
        .chain(SUBCOMMANDS.iter().map(|s| format!("meid-{s}.1")))
        .collect();
    want.sort();
    assert_eq!(pages, want);
    let page = std::fs::read_to_string(d.join("meid-sweep.1")).unwrap();
    assert!(page.contains(".TH") && page.contains("vary"));
}

// ---------------------------------------------------------------------------------------------
// 5. --version.

#[test]
fn version_names_crate_version_and_commit() {
    let v = stdout_of(&["--version"]);
    let v = v.trim();
    let want = format!("meid {} (commit ", env!("CARGO_PKG_VERSION"));
    assert!(v.starts_with(&want) && v.ends_with(')'), "{v}");
    let commit = &v[want.len()..v.len() - 1];
    // The build script read the repository this test is built from (when git is here).
    let head = Command::new("git")
        .args([
            "-C",
            env!("CARGO_MANIFEST_DIR"),
            "rev-parse",
            "--short",
            "HEAD",
        ])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    match head {
        Some(h) => {
            let rest = commit.strip_prefix(&h);
            assert!(
                rest == Some("") || rest == Some("-dirty"),
                "commit `{commit}` vs HEAD `{h}`"
            );
        }
        None => assert!(
            commit == "unknown" || commit.chars().all(|c| c.is_ascii_hexdigit() || c == '-'),
            "{commit}"
        ),
    }
}

/// The model's warnings (here: the no-base machine's retained modes, without static
/// correction, carry 65.23 % of the static flexibility at B) are printed on stderr by every study subcommand, once, before its
/// run — not only by `simulate` after a successful one — and not with `-q`.
#[test]
fn every_study_prints_the_models_warnings() {
    let d = tmpdir("conv", "warnings");
    let no_base = common::example_file("paper-no-base.toml")
        .display()
        .to_string();
    let paper = paper_example().display().to_string();
    for (name, args) in subcommands() {
        if name == "modes" {
            continue;
        }
        // Without the static correction (which restores B's share and so silences the
        // warning these runs must print).
        let mut args: Vec<String> = args
            .into_iter()
            .map(|a| if a == paper { no_base.clone() } else { a })
            .collect();
        args.splice(
            1..1,
            [
                "--set".to_string(),
                "structure.fem.static_correction=false".to_string(),
            ],
        );
        let out = in_dir(&d, &args).output().unwrap();
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        let e = stderr(&out);
        assert_eq!(
            e.matches("65.23 % of the static flexibility at point 'B'")
                .count(),
            1,
            "{name}: {e}"
        );
        let out = in_dir(&d, &args).arg("-q").output().unwrap();
        assert!(out.stderr.is_empty(), "{name} -q: {}", stderr(&out));
    }
}
