//! `meid model expand` end to end: the paper's machine written as the general model it
//! generates; `meid modes` and `meid simulate` on the written file print what they print on
//! the machine file (every JSON field equal); bad input exits 2 naming the file.

use crate::common;

use common::{example_file as example, meid, ok, ok_json, stderr, tmpdir};

const COARSE: &str = "structure.fem.machine.elements_per_side=6";

/// `meid model expand SRC --set COARSE -o OUT`; what it printed.
fn expand_coarse(src: &std::path::Path, out: &std::path::Path) -> String {
    ok(meid()
        .args(["model", "expand"])
        .arg(src)
        .args(["--set", COARSE, "-o"])
        .arg(out)
        .output()
        .unwrap())
}

#[test]
fn expanded_file_gives_the_machines_modes_and_summary() {
    let d = tmpdir("model", "expand");
    for file in ["paper-soft-base.toml", "paper-no-base.toml"] {
        let src = example(file);
        let out = d.join(file);
        let printed = expand_coarse(&src, &out);
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

/// `md/mb` on the expanded file needs no `--bed-mass`: the bed plate and its added masses are
/// written with `part = "bed"`, so the damper masses of a sweep are those of the machine file
/// (m_d = r·m_b with m_b the plate's element masses against ρ L_x L_y t, to round-off).
#[test]
fn expanded_file_knows_its_bed_mass() {
    let d = tmpdir("model", "bed-mass");
    let src = example("paper-soft-base.toml");
    let out = d.join("expanded.toml");
    expand_coarse(&src, &out);
    let damper_masses = |dir: &std::path::Path| -> Vec<f64> {
        let text = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
        let mut lines = text.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let k = head.iter().position(|h| *h == "damper_mass_kg").unwrap();
        lines
            .map(|l| l.split(',').nth(k).unwrap().parse::<f64>().unwrap())
            .collect()
    };
    ok(meid()
        .arg("sweep")
        .arg(&src)
        .args(["--set", COARSE, "--vary", "md/mb=0.35,0.7", "-q", "-o"])
        .arg(d.join("machine"))
        .output()
        .unwrap());
    ok(meid()
        .arg("sweep")
        .arg(&out)
        .args(["--vary", "md/mb=0.35,0.7", "-q", "-o"])
        .arg(d.join("expanded"))
        .output()
        .unwrap());
    let (a, b) = (
        damper_masses(&d.join("machine")),
        damper_masses(&d.join("expanded")),
    );
    assert_eq!(a.len(), 2);
    for (x, y) in a.iter().zip(&b) {
        assert!(*x > 0.0 && (y / x - 1.0).abs() < 1e-12, "{a:?} vs {b:?}");
    }
    // Unlabelled, the general model cannot tell m_b: the error says how to give it.
    let text = std::fs::read_to_string(&out).unwrap();
    let unlabelled = d.join("unlabelled.toml");
    std::fs::write(
        &unlabelled,
        text.replace("part = \"bed\"", "part = \"plate\""),
    )
    .unwrap();
    let o = meid()
        .arg("sweep")
        .arg(&unlabelled)
        .args(["--vary", "md/mb=0.35,0.7", "-q", "-o"])
        .arg(d.join("unlabelled"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("part = \"bed\"") && e.contains("--bed-mass"),
        "{e}"
    );
}
