//! Build script: the git commit the binary is built from, for `meid --version`.
//!
//! Sets `MEID_GIT_COMMIT` to `git rev-parse --short HEAD`, with `-dirty` appended when the
//! working tree has uncommitted changes to tracked files, or to `unknown` when git or the
//! repository is not available (a `cargo install` from a source tarball).

use std::path::{Path, PathBuf};
use std::process::Command;

/// `git ARGS` run in `dir`: its trimmed standard output, or `None` when git is missing or fails.
fn git(dir: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    Some(String::from_utf8(out.stdout).ok()?.trim().to_string())
}

fn main() {
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    println!("cargo:rerun-if-env-changed=MEID_GIT_COMMIT");
    // An explicit value (packagers building without git) wins.
    let commit = if let Some(c) = std::env::var("MEID_GIT_COMMIT")
        .ok()
        .filter(|c| !c.is_empty())
    {
        c
    } else if let Some(hash) = git(&manifest, &["ls-files", "--error-unmatch", "build.rs"])
        // The repository must be meid's own (this file tracked in it), not one that merely
        // contains the unpacked package (a home directory under git, a vendoring project).
        .and_then(|_| git(&manifest, &["rev-parse", "--short", "HEAD"]))
    {
        // Rerun when HEAD moves (a commit, a checkout) or the index changes (a staged edit).
        // The git directory of a worktree is not `.git/` itself: ask git where things are.
        let mut watched = Vec::new();
        if let Some(head) = git(&manifest, &["rev-parse", "--git-path", "HEAD"]) {
            watched.push(head);
        }
        if let Some(index) = git(&manifest, &["rev-parse", "--git-path", "index"]) {
            watched.push(index);
        }
        if let Some(r) = git(&manifest, &["symbolic-ref", "-q", "HEAD"]) {
            if let Some(p) = git(&manifest, &["rev-parse", "--git-path", &r]) {
                watched.push(p);
            }
            if let Some(p) = git(&manifest, &["rev-parse", "--git-path", "packed-refs"]) {
                watched.push(p);
            }
        }
        for w in watched {
            // `--git-path` answers relative to the directory git ran in.
            let p = Path::new(&w);
            let p = if p.is_absolute() {
                p.to_path_buf()
            } else {
                manifest.join(p)
            };
            if p.exists() {
                println!("cargo:rerun-if-changed={}", p.display());
            }
        }
        // The sources of the workspace: an edit changes the dirty flag.
        if let Some(top) = git(&manifest, &["rev-parse", "--show-toplevel"]) {
            let crates = Path::new(&top).join("crates");
            if crates.is_dir() {
                println!("cargo:rerun-if-changed={}", crates.display());
            }
        }
        let dirty = git(
            &manifest,
            &["status", "--porcelain", "--untracked-files=no"],
        )
        .is_some_and(|s| !s.is_empty());
        if dirty {
            format!("{hash}-dirty")
        } else {
            hash
        }
    } else {
        // No git: nothing to watch but the package itself.
        println!("cargo:rerun-if-changed=build.rs");
        "unknown".to_string()
    };
    println!("cargo:rustc-env=MEID_GIT_COMMIT={commit}");
}
