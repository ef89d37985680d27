//! `meid model expand` end to end: the paper's machine written as the general model it
//! generates; `meid modes` and `meid simulate` on the written file print what they print on
//! the machine file (every JSON field equal); bad input exits 2 naming the file.

mod common;

use common::{example_file as example, meid, ok, ok_json, stderr, tmpdir};

const COARSE: &str = "structure.fem.machine.elements_per_side=6";

#[test]
fn expanded_file_gives_the_machines_modes_and_summary() {
    let d = tmpdir("model", "expand");
    for file in ["paper-soft-base.toml", "paper-no-base.toml"] {
        let src = example(file);
        let out = d.join(file);
        let printed = ok(meid()
            .args(["model", "expand"])
            .arg(&src)
            .args(["--set", COARSE, "-o"])
            .arg(&out)
            .output()
            .unwrap());
        assert!(printed.is_empty(), "{printed}");
        let written = std::fs::read_to_string(&out).unwrap();
        assert!(
            written.contains("\n[structure.fem.model]\n")
                && !written.contains("\n[structure.fem.machine]")
        );
        // Without -o: the same text on stdout.
        let stdout = ok(meid()
            .args(["model", "expand"])
            .arg(&src)
            .args(["--set", COARSE])
            .output()
            .unwrap());
        assert_eq!(stdout, written);
        for cmd in [vec!["modes", "--json"], vec!["simulate", "--json"]] {
            let a = ok_json(
                meid()
                    .args(&cmd)
                    .arg(&src)
                    .args(["--set", COARSE])
                    .output()
                    .unwrap(),
            );
            let b = ok_json(meid().args(&cmd).arg(&out).output().unwrap());
            assert_eq!(a, b, "{file}: meid {}", cmd[0]);
        }
    }
}

#[test]
fn expand_refuses_what_it_cannot_expand() {
    let out = meid()
        .args(["model", "expand"])
        .arg(example("paper-lumped.toml"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("no [structure.fem.machine]"),
        "{}",
        stderr(&out)
    );
    let out = meid()
        .args(["model", "expand"])
        .arg(example("paper-soft-base.toml"))
        .args(["--set", "structure.fem.machine.bed.thickness=-1.0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("structure.fem.machine.bed.thickness"),
        "{}",
        stderr(&out)
    );
}
