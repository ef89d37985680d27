//! Helpers shared by the `meid` CLI tests (each test binary uses a subset).
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// The `meid` binary under test.
pub fn meid() -> Command {
    Command::new(env!("CARGO_BIN_EXE_meid"))
}

/// A file in the workspace's `examples/`.
pub fn example_file(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// The lumped paper example (`examples/paper-lumped.toml`).
pub fn paper_example() -> PathBuf {
    example_file("paper-lumped.toml")
}

/// A fresh, empty directory `meid-{group}-{tag}-{pid}` in the system temp dir.
pub fn tmpdir(group: &str, tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("meid-{group}-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The command's stderr as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// Asserts success (showing stderr otherwise) and returns stdout.
pub fn ok(o: Output) -> String {
    assert!(o.status.success(), "stderr: {}", stderr(&o));
    String::from_utf8(o.stdout).unwrap()
}

/// Asserts success (showing stderr otherwise) and parses stdout as JSON.
pub fn ok_json(o: Output) -> serde_json::Value {
    serde_json::from_str(&ok(o)).unwrap()
}
