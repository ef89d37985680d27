//! Issue 27 ("trust3"), the library side: errors that name the field or point and what would
//! be valid; the study fingerprint covers the files a model reads; `model expand` refuses what
//! a model load refuses. (Special files given to every reader: `fuzz_measure_readers.rs`.)

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use meid::model::Model;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn examples(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// Item 15: "invalid mode selection: select at least one mode" named neither the file nor the
/// field. An empty `select` is refused at `structure.fem.select`, with what is valid.
#[test]
fn an_empty_mode_selection_names_the_field_and_what_is_valid() {
    let e = Model::from_file(
        &data("eb_cantilever.toml"),
        &["structure.fem.select=[]".into()],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("structure.fem.select keeps no mode"), "{e}");
    assert!(e.contains("1..=6"), "{e}");
    assert!(e.starts_with("--set structure.fem.select=[]"), "{e}");
}

/// Item 15: "invalid point B: needs 1 finite mode-shape values (got 1)" said neither which
/// value was bad nor of which mode. The message names the point, the mode, its frequency and
/// the value.
#[test]
fn a_non_finite_shape_value_names_point_mode_and_value() {
    let mut m = meid::modal::ModalModel {
        omega_rad_per_s: vec![10.0, 20.0],
        damping: vec![0.0; 4],
        ..Default::default()
    };
    m.points = BTreeMap::from([("B".to_string(), vec![0.5, f64::NAN])]);
    let e = m.validate().unwrap_err().to_string();
    assert!(
        e.contains("point B")
            && e.contains("mode 2")
            && e.contains("is NaN")
            && e.contains("finite"),
        "{e}"
    );
    m.points = BTreeMap::from([("B".to_string(), vec![0.5])]);
    let e = m.validate().unwrap_err().to_string();
    assert!(e.contains("1 mode-shape values for the 2 modes"), "{e}");
}

/// A modes file (UFF 2411 + 55) and a model that reads it, in `dir`.
fn imported(dir: &Path, bed_mass: f64) -> PathBuf {
    let lumped = Model::from_file(
        &examples("paper-lumped.toml"),
        &[format!("structure.lumped.masses[0].mass={bed_mass}")],
    )
    .unwrap();
    let bytes = meid::io::uff::modes_uff_points(&lumped.structure).unwrap();
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("modes.uff"), bytes).unwrap();
    let src = std::fs::read_to_string(examples("paper-lumped.toml")).unwrap();
    let (a, b) = (
        src.find("[structure]").unwrap(),
        src.find("[points]").unwrap(),
    );
    let text = format!(
        "{}[structure]\nreference_mode = 1\n[structure.modes]\nfile = \"modes.uff\"\npoints = {{ base = 1, bed = 2 }}\nimpact_direction = [0, 0, 1]\n\n{}",
        &src[..a],
        &src[b..]
    );
    let p = dir.join("imported.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// Item 3: a model records the size and FNV-1a 64 of every file it reads, and a sweep's and
/// a Monte Carlo's fingerprint change with the file's content (the model text unchanged);
/// a model without such files keeps the fingerprint it had.
#[test]
fn the_study_fingerprint_covers_the_files_a_model_reads() {
    use meid::analysis::montecarlo::MonteCarlo;
    use meid::analysis::sweep::{Sweep, Vary};
    let d = std::env::temp_dir().join(format!("meid-trust3-fp-{}", std::process::id()));
    let fingerprints = |bed: f64| {
        let p = imported(&d, bed);
        let m = Model::from_file(&p, &[]).unwrap();
        assert_eq!(m.files.len(), 1);
        assert_eq!(m.files[0].path, d.join("modes.uff"));
        assert_eq!(
            m.files[0].bytes,
            std::fs::metadata(d.join("modes.uff")).unwrap().len()
        );
        let s = Sweep::new(m.clone(), vec![Vary::parse("damper.mass=2,3").unwrap()])
            .unwrap()
            .fingerprint_text();
        let mc = MonteCarlo {
            model: m,
            inputs: vec![
                meid::analysis::montecarlo::Uncertain::parse("damper.mass=uniform(2,3)").unwrap(),
            ],
            samples: 10,
            seed: 7,
        }
        .fingerprint();
        (s, mc)
    };
    let (s10, m10) = fingerprints(10.0);
    let (s8, m8) = fingerprints(8.0);
    assert_ne!(s10, s8);
    assert_ne!(m10, m8);
    assert_eq!(fingerprints(10.0), (s10, m10));
    let lumped = Model::from_file(&examples("paper-lumped.toml"), &[]).unwrap();
    assert!(lumped.files.is_empty());
    assert_eq!(lumped.files_fingerprint(), "");
    std::fs::remove_dir_all(&d).ok();
}

/// Item 8: `model expand` refuses exactly what a model load refuses, with the load's message:
/// a negative stiffness and a NaN mass given through `--set` (before: written out).
#[test]
fn expand_refuses_what_a_load_refuses() {
    let base = examples("paper-soft-base.toml");
    for set in [
        "contact.slider_bed.stiffness=-1",
        "damper.mass=nan",
        "slider.mass=0",
        "damper.stiffness=inf",
    ] {
        let sets = vec![set.to_string()];
        let load = Model::from_file(&base, &sets)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        let expand = meid::model::expand::expand_file(&base, &sets)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert_eq!(expand, load, "{set}");
    }
}
