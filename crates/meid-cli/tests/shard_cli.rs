//! `--shard K/N` and `meid merge` (issue 14, point 2): the shards of a sweep or a Monte Carlo,
//! run with different thread counts, merge into the same bytes as the unsharded run (every
//! file of its manifest); a missing or repeated shard is refused (exit code 2). Monte Carlo
//! output on the FE example is byte-identical for RAYON_NUM_THREADS = 1 and 2.

use crate::common;

use std::path::Path;

use common::{example_file, meid, ok, stderr, tmpdir};

fn same_files(a: &Path, b: &Path) {
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("manifest.json")).unwrap()).unwrap();
    let files = manifest["files"].as_array().expect("manifest lists files");
    assert!(!files.is_empty());
    for f in files {
        let name = f["name"].as_str().unwrap();
        assert_eq!(
            std::fs::read(a.join(name)).unwrap(),
            std::fs::read(b.join(name)).unwrap(),
            "{name} differs"
        );
    }
    assert_eq!(
        std::fs::read(a.join("manifest.json")).unwrap(),
        std::fs::read(b.join("manifest.json")).unwrap()
    );
}

#[test]
fn sweep_shards_merge_to_the_unsharded_files() {
    let d = tmpdir("shard", "sweep");
    let model = example_file("paper-lumped.toml");
    let args = |cmd: &mut std::process::Command| {
        cmd.arg("sweep").arg(&model).args([
            "--vary",
            "wd/ws=0.5..2:5",
            "--vary",
            "damper.mass=2,3.5",
        ]);
    };
    for (k, threads) in [(1, "1"), (2, "2"), (3, "1")] {
        let mut c = meid();
        args(&mut c);
        ok(c.args([
            "--shard",
            &format!("{k}/3"),
            "--threads",
            threads,
            "-q",
            "-o",
        ])
        .arg(d.join(format!("s{k}")))
        .output()
        .unwrap());
    }
    let mut c = meid();
    args(&mut c);
    ok(c.arg("-q").arg("-o").arg(d.join("whole")).output().unwrap());
    ok(meid()
        .arg("merge")
        .args([d.join("s3"), d.join("s1"), d.join("s2")])
        .arg("-q")
        .arg("-o")
        .arg(d.join("merged"))
        .output()
        .unwrap());
    same_files(&d.join("whole"), &d.join("merged"));
    // Missing and repeated shards.
    let o = meid()
        .arg("merge")
        .args([d.join("s1"), d.join("s3")])
        .arg("-o")
        .arg(d.join("bad"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("in no shard"), "{}", stderr(&o));
    let o = meid()
        .arg("merge")
        .args([d.join("s1"), d.join("s2"), d.join("s2"), d.join("s3")])
        .arg("-o")
        .arg(d.join("bad"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("overlaps"), "{}", stderr(&o));
    let o = meid()
        .arg("merge")
        .arg(&d)
        .arg("-o")
        .arg(d.join("bad"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not a shard"), "{}", stderr(&o));
}

#[test]
fn montecarlo_shards_merge_to_the_unsharded_files() {
    let d = tmpdir("shard", "mc");
    let model = example_file("paper-soft-base.toml");
    let args_seed = |cmd: &mut std::process::Command, seed: &str| {
        cmd.arg("montecarlo").arg(&model).args([
            "--set",
            "structure.fem.machine.elements_per_side=6",
            "--vary",
            "contact.slider_bed.stiffness=lognormal(4.3e7,0.3)",
            "--vary",
            "damper.mass=uniform(2,5)",
            "--samples",
            "23",
            "--seed",
            seed,
        ]);
    };
    let args = |cmd: &mut std::process::Command| args_seed(cmd, "5");
    for (k, threads) in [(1, "2"), (2, "1")] {
        let mut c = meid();
        args(&mut c);
        ok(c.args([
            "--shard",
            &format!("{k}/2"),
            "--threads",
            threads,
            "-q",
            "-o",
        ])
        .arg(d.join(format!("m{k}")))
        .output()
        .unwrap());
    }
    for threads in ["1", "2"] {
        let mut c = meid();
        args(&mut c);
        ok(c.env("RAYON_NUM_THREADS", threads)
            .arg("-q")
            .arg("-o")
            .arg(d.join(format!("whole{threads}")))
            .output()
            .unwrap());
    }
    same_files(&d.join("whole1"), &d.join("whole2"));
    ok(meid()
        .arg("merge")
        .args([d.join("m2"), d.join("m1")])
        .arg("-q")
        .arg("-o")
        .arg(d.join("merged"))
        .output()
        .unwrap());
    same_files(&d.join("whole1"), &d.join("merged"));
    // A shard of another study (other seed) is refused.
    let mut c = meid();
    args_seed(&mut c, "6");
    ok(c.args(["--shard", "2/2", "-q", "-o"])
        .arg(d.join("other"))
        .output()
        .unwrap());
    let o = meid()
        .arg("merge")
        .args([d.join("m1"), d.join("other")])
        .arg("-o")
        .arg(d.join("bad"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("different studies"), "{}", stderr(&o));
}

#[test]
fn shard_arguments_are_checked() {
    for bad in ["0/3", "4/3", "1/0", "x", "1-3"] {
        let o = meid()
            .arg("sweep")
            .arg(example_file("paper-lumped.toml"))
            .args(["--vary", "wd/ws=1,2", "--shard", bad, "-o", "/tmp/never"])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(stderr(&o).contains("K/N"), "{bad}: {}", stderr(&o));
    }
    let o = meid()
        .arg("montecarlo")
        .arg(example_file("paper-lumped.toml"))
        .args(["--vary", "damper.mass=uniform(2,5)", "--shard", "1/2"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("needs -o DIR"), "{}", stderr(&o));
}
