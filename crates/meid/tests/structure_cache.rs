//! FE studies at lumped-model speed (issue 14, point 5): a study's points reuse the base
//! model's structure unless they change its structural part ([`meid::model::StructureKey`]),
//! and what they get is, bit for bit, the model `Model::from_text` builds from the file with
//! the point's values as `--set` overrides.
//!
//! * `with_fields` equals a fresh read (spec and modal model) for contact, damper and
//!   structural fields, on the lumped and the FE soft-base example; the cache builds a
//!   structure only for a structural change, once per distinct structure.
//! * With `select = "auto"` and no `auto_max_hz`, the cutoff is 3 ω_c: a contact stiffness
//!   changes the retained modes, so the key must carry ω_c (a sweep over the stiffness used to
//!   keep the base model's modes there).
//! * Monte Carlo samples are keyed by (seed, index): any split into ranges and any thread
//!   count gives the same samples, and each sample equals the single run of its values.

use std::path::{Path, PathBuf};

use meid::analysis::montecarlo::{MonteCarlo, Sample, Uncertain};
use meid::analysis::simulate;
use meid::analysis::sweep::{Sweep, Vary};
use meid::model::{Case, Model, StructureCache};

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

fn read(name: &str, overrides: &[String]) -> Model {
    Model::from_file(&example(name), overrides).unwrap()
}

const COARSE: &str = "structure.fem.machine.elements_per_side=6";

fn same_model(a: &Model, b: &Model) {
    assert_eq!(a.spec, b.spec);
    assert_eq!(a.structure, b.structure);
    assert_eq!(a.structure_key(), b.structure_key());
}

#[test]
fn with_fields_is_a_fresh_read() {
    for (file, base_ov) in [
        ("paper-lumped.toml", vec![]),
        ("paper-soft-base.toml", vec![COARSE.to_string()]),
    ] {
        let base = read(file, &base_ov);
        let cache = StructureCache::new();
        for fields in [
            vec!["contact.slider_bed.stiffness=2.5e7"],
            vec!["damper.mass=5.25", "damper.damping=350.0"],
            vec!["slider.velocity=0.8"],
        ] {
            let fields: Vec<String> = fields.iter().map(|s| s.to_string()).collect();
            let derived = base.with_fields(&fields, Some(&cache)).unwrap();
            let mut ov = base_ov.clone();
            ov.extend(fields.iter().cloned());
            same_model(&derived, &read(file, &ov));
        }
        if file == "paper-soft-base.toml" {
            // None of those touched the FE structure: nothing was built.
            assert_eq!(cache.builds(), 0, "{file}");
        }
    }
    // A structural field rebuilds once; the same structure again comes from the cache.
    let base = read("paper-soft-base.toml", &[COARSE.to_string()]);
    let cache = StructureCache::new();
    let f = vec!["structure.fem.damping_ratios=0.02".to_string()];
    let a = base.with_fields(&f, Some(&cache)).unwrap();
    assert_eq!(cache.builds(), 1);
    let mut f2 = f.clone();
    f2.push("damper.mass=4.0".into());
    let b = base.with_fields(&f2, Some(&cache)).unwrap();
    assert_eq!(
        cache.builds(),
        1,
        "the second point's structure is the cached one"
    );
    let fresh = read(
        "paper-soft-base.toml",
        &[COARSE.to_string(), f2[0].clone(), f2[1].clone()],
    );
    same_model(&b, &fresh);
    assert_ne!(a.structure, base.structure, "ζ changed the modal damping");
}

#[test]
fn with_fields_errors_name_the_field() {
    let base = read("paper-lumped.toml", &[]);
    let e = base
        .with_fields(&["damper.mass=-1.0".to_string()], None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--set damper.mass=-1.0"), "{e}");
    let e = base
        .with_fields(&["contact.slider_bed.stifness=1.0".to_string()], None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("stifness"), "{e}");
}

#[test]
fn auto_cutoff_follows_the_contact_stiffness() {
    let auto = [
        COARSE.to_string(),
        "structure.fem.select=\"auto\"".to_string(),
        "structure.fem.auto_count=0".to_string(),
    ];
    let base = Model::from_text(
        "auto.toml",
        std::fs::read_to_string(example("paper-soft-base.toml"))
            .unwrap()
            .replace("auto_max_hz = 600.0", ""),
        &auto,
    )
    .unwrap();
    let stiff = "contact.slider_bed.stiffness=4.3e9".to_string();
    let derived = base
        .with_fields(std::slice::from_ref(&stiff), None)
        .unwrap();
    assert!(
        derived.structure.len() > base.structure.len(),
        "precondition: a 10x higher contact frequency keeps more modes ({} vs {})",
        derived.structure.len(),
        base.structure.len()
    );
    let mut ov = auto.to_vec();
    ov.push(stiff);
    let fresh = Model::from_text("auto.toml", base.source.text.clone(), &ov).unwrap();
    same_model(&derived, &fresh);
    // Through a sweep: the point's modes are those of the single run.
    let sweep = Sweep::new(
        base.clone(),
        vec![Vary::parse("contact.slider_bed.stiffness=4.3e7,4.3e9").unwrap()],
    )
    .unwrap();
    let pm = sweep.point_model(1).unwrap();
    assert_eq!(pm.model.structure, fresh.structure);
}

/// A sample as bits: index, inputs, metrics, error.
type SampleBits = (usize, Vec<u64>, Option<Vec<u64>>, Option<String>);

fn bits(s: &[Sample]) -> Vec<SampleBits> {
    s.iter()
        .map(|s| {
            (
                s.index,
                s.inputs.iter().map(|x| x.to_bits()).collect(),
                s.metrics.map(|m| m.iter().map(|x| x.to_bits()).collect()),
                s.error.clone(),
            )
        })
        .collect()
}

#[test]
fn montecarlo_samples_do_not_depend_on_split_or_threads() {
    let study = MonteCarlo {
        model: read("paper-soft-base.toml", &[COARSE.to_string()]),
        inputs: vec![
            Uncertain::parse("contact.slider_bed.stiffness=lognormal(4.3e7,0.3)").unwrap(),
            Uncertain::parse("damper.mass=uniform(2,5)").unwrap(),
        ],
        samples: 9,
        seed: 7,
    };
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let whole = pool(1).install(|| study.run_range(0..9, &|_, _| {}));
    let mut split = pool(2).install(|| study.run_range(5..9, &|_, _| {}));
    let head = pool(2).install(|| study.run_range(0..2, &|_, _| {}));
    let mid = pool(1).install(|| study.run_range(2..5, &|_, _| {}));
    let mut parts = head;
    parts.extend(mid);
    parts.append(&mut split);
    assert_eq!(bits(&whole), bits(&parts));
    // finish() over the pieces is run()'s result.
    let run = pool(2).install(|| study.run()).unwrap();
    assert_eq!(bits(&run.samples), bits(&whole));
    let fin = study.finish(parts).unwrap();
    assert_eq!(
        serde_json::to_string(&fin.metric_stats).unwrap(),
        serde_json::to_string(&run.metric_stats).unwrap()
    );
    // Each sample is the single run of the file with its values set.
    for s in whole.iter().take(3) {
        let ov = vec![
            COARSE.to_string(),
            format!("contact.slider_bed.stiffness={:e}", s.inputs[0]),
            format!("damper.mass={:e}", s.inputs[1]),
        ];
        let m = read("paper-soft-base.toml", &ov);
        let r = simulate(
            &m.impact_system(Case::AsSpecified).unwrap(),
            &m.options(),
            false,
        )
        .unwrap()
        .summary;
        let got = s.metrics.unwrap();
        assert_eq!(got[0].to_bits(), r.energy_ratio.unwrap().to_bits());
        assert_eq!(got[1].to_bits(), r.peak_bed_acceleration_m_per_s2.to_bits());
        assert_eq!(got[2].to_bits(), r.peak_floor_force_n.to_bits());
    }
    // The drawn inputs depend on (seed, index) only.
    assert_eq!(study.draw(4), whole[4].inputs);
    let other = MonteCarlo {
        samples: 1000,
        ..study.clone()
    };
    assert_eq!(other.draw(4), study.draw(4));
}

#[test]
fn sweep_shards_equal_the_whole_grid() {
    let sweep = Sweep::new(
        read("paper-lumped.toml", &[]),
        vec![
            Vary::parse("wd/ws=0.5..2:4").unwrap(),
            Vary::parse("damper.mass=2,4").unwrap(),
        ],
    )
    .unwrap();
    let whole = sweep.run(&|_, _| {});
    let mut pts = sweep.run_range(5..8, &|_, _| {}).unwrap();
    pts.extend(sweep.run_range(0..5, &|_, _| {}).unwrap());
    let merged = sweep.result_from(pts.clone()).unwrap();
    assert_eq!(merged.csv(), whole.csv());
    // Rows read back from their text are the same rows.
    let back: Vec<_> = pts
        .iter()
        .map(|p| sweep.parse_row(sweep.row(p).trim_end()).unwrap())
        .collect();
    assert_eq!(sweep.result_from(back).unwrap().csv(), whole.csv());
    // A missing or repeated point is refused.
    let e = sweep
        .result_from(pts[..7].to_vec())
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing"), "{e}");
    let mut twice = pts.clone();
    twice.push(pts[0].clone());
    let e = sweep.result_from(twice).unwrap_err().to_string();
    assert!(e.contains("twice"), "{e}");
}
