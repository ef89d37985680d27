//! Input handling of model files and `--set` overrides (issue 15): what used to be read
//! silently wrong, or refused in Rust's terms, is refused naming the field and what it takes.

use meid::model::{Model, ModelSpec, Ratios};

fn example() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/paper-lumped.toml"
    ))
    .unwrap()
}

/// The error of reading the lumped example with `overrides`.
fn set_err(overrides: &[&str]) -> String {
    let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    match Model::from_text("model.toml", example(), &ov) {
        Ok(_) => panic!("{overrides:?} was accepted"),
        Err(e) => e.to_string(),
    }
}

/// The error of reading the lumped example with `from` replaced by `to` in its text.
fn text_err(from: &str, to: &str) -> String {
    let text = example();
    assert!(text.contains(from), "{from}");
    match Model::from_text("model.toml", text.replacen(from, to, 1), &[]) {
        Ok(_) => panic!("{to} was accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn set_index_that_is_not_a_whole_number_in_range_is_refused() {
    // Each used to drop the index and set the whole array to 0.02.
    for bad in ["-1", "abc", "99999999999999999999999", " 1x"] {
        let e = set_err(&[&format!("structure.lumped.damping_ratios[{bad}]=0.02")]);
        assert!(
            e.contains(&format!(
                "--set structure.lumped.damping_ratios[{bad}]=0.02"
            )) && e.contains(&format!("index `{bad}`"))
                && e.contains("valid indices are 0 to 1 (the array has 2 entries)"),
            "{e}"
        );
    }
    let e = set_err(&["structure.lumped.damping_ratios[2]=0.02"]);
    assert!(
        e.contains("index 2 is out of range; valid indices are 0 to 1"),
        "{e}"
    );
    let e = set_err(&["structure.lumped.damping_ratios[0]x=0.02"]);
    assert!(e.contains("nothing may follow `[0]` (found `x`)"), "{e}");
    let e = set_err(&["structure.lumped.damping_ratios[0=0.02"]);
    assert!(e.contains("unclosed `[`"), "{e}");
    let e = set_err(&["slider[0]=1"]);
    assert!(e.contains("slider: is not an array in the model"), "{e}");
    // A good index sets that entry only.
    let m = Model::from_text(
        "model.toml",
        example(),
        &["structure.lumped.damping_ratios[1]=0.03".to_string()],
    )
    .unwrap();
    assert_eq!(
        m.spec.structure.lumped.unwrap().damping_ratios,
        Some(Ratios::PerMode(vec![0.01, 0.03]))
    );
}

#[test]
fn a_table_given_as_an_array_is_refused_naming_its_fields() {
    // serde used to read `slider = [1.2, 5.0]` by field order (mass 1.2 kg, 5 m/s).
    let e = set_err(&["slider=[1.2, 5.0]"]);
    assert!(
        e.starts_with("--set slider=[1.2, 5.0]: slider: expected a table")
            && e.contains("`mass`, `velocity`")
            && e.contains("got an array"),
        "{e}"
    );
    // The same in a file.
    let text = example();
    let start = text.find("[slider]").unwrap();
    let end = start + text[start..].find("\n\n").unwrap();
    let text = format!("slider = [1.2, 1.2]\n{}{}", &text[..start], &text[end..]);
    let e = Model::from_text("model.toml", text, &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("model.toml:1:10: slider: expected a table"),
        "{e}"
    );
    let e = text_err("{ name = \"bed\", mass = 10.0 }", "[\"bed\", 10.0]");
    assert!(
        e.starts_with("model.toml:18:3: structure.lumped.masses[0]: expected a table")
            && e.contains("`name`, `mass`"),
        "{e}"
    );
}

#[test]
fn a_fixed_size_array_with_extra_entries_is_refused() {
    // A spring's `nodes` used to take 4 names in a file (the last two ignored).
    let e = text_err(
        "nodes = [\"bed\", \"base\"]",
        "nodes = [\"bed\", \"base\", \"ground\", \"bed\"]",
    );
    assert!(
        e.starts_with("model.toml:22:31: structure.lumped.springs[0].nodes: expected an array of exactly 2 values; got 4 values"),
        "{e}"
    );
    let e = set_err(&["structure.lumped.springs[1].nodes=[\"base\"]"]);
    assert!(
        e.contains(
            "structure.lumped.springs[1].nodes: expected an array of exactly 2 values; got 1"
        ),
        "{e}"
    );
}

#[test]
fn messages_speak_the_model_s_terms_not_rust_s() {
    // Was "data did not match any variant of untagged enum Ratios".
    let e = text_err("damping_ratios = [0.01, 0.01]", "damping_ratios = \"2%\"");
    assert!(
        e.contains("structure.lumped.damping_ratios: expected a number (fraction of critical, e.g. 0.02) or a list of numbers, one per mode; got the string \"2%\""),
        "{e}"
    );
    // Was "expected struct MassSpec".
    let e = set_err(&["structure.lumped.masses[0]=10.0"]);
    assert!(
        e.contains("structure.lumped.masses[0]: expected a table")
            && e.contains("got the number 10.0")
            && !e.contains("MassSpec"),
        "{e}"
    );
    // Was "expected f64" / "expected usize" / "wanted string or table".
    let e = set_err(&["slider.mass=\"heavy\""]);
    assert!(
        e.contains("slider.mass: expected a number; got the string \"heavy\""),
        "{e}"
    );
    let e = set_err(&["structure.reference_mode=1.5"]);
    assert!(
        e.contains("structure.reference_mode: expected a whole number >= 0; got the number 1.5"),
        "{e}"
    );
    let e = text_err("law = \"linear\"", "law = 3");
    assert!(
        e.contains("contact.slider_bed.law: expected one of `linear`, `hertz`, `hunt-crossley`"),
        "{e}"
    );
    // Unknown keys keep their did-you-mean, now with the table's path.
    let e = set_err(&["damper.mas=3"]);
    assert!(
        e.contains("damper: unknown field `mas`") && e.contains("did you mean `mass`?"),
        "{e}"
    );
    for msg in [
        set_err(&["structure.lumped.damping_ratios=true"]),
        set_err(&["structure.lumped.masses=5"]),
        set_err(&["points=3"]),
    ] {
        for rust in ["struct ", "enum ", "untagged", "usize", "f64", "Spec"] {
            assert!(!msg.contains(rust), "{msg}");
        }
    }
}

#[test]
fn the_untagged_forms_still_read() {
    // The hand-written readers of the one-or-many fields accept every documented form.
    let mut text = example();
    text = text.replace("damping_ratios = [0.01, 0.01]", "damping_ratios = 0.02");
    let m = Model::from_text("model.toml", text, &[]).unwrap();
    assert_eq!(
        m.spec.structure.lumped.as_ref().unwrap().damping_ratios,
        Some(Ratios::All(0.02))
    );
    let m = Model::from_text(
        "model.toml",
        example(),
        &["structure.lumped.damping_ratios=[0, 1e-2]".to_string()],
    )
    .unwrap();
    assert_eq!(
        m.spec.structure.lumped.as_ref().unwrap().damping_ratios,
        Some(Ratios::PerMode(vec![0.0, 0.01]))
    );
    let fem = |s: &str| -> meid::model::fem::FemSpec {
        let spec: ModelSpec = toml::from_str(&format!(
            "[structure.fem]\n{s}\n[points]\nbed_contact = \"O_b\"\nmeasurement = \"B\"\n[slider]\nmass = 1.0\nvelocity = 1.0\n[contact.slider_bed]\nstiffness = 1e7\n"
        ))
        .unwrap();
        spec.structure.fem.unwrap()
    };
    use meid::model::fem::{PerDirection, SelectSpec};
    assert_eq!(
        fem("select = [6, 10]").select,
        Some(SelectSpec::Indices(vec![6, 10]))
    );
    assert_eq!(
        fem("select = \"auto\"").select,
        Some(SelectSpec::Keyword("auto".into()))
    );
    assert_eq!(
        fem("select = { band_hz = [1, 400.5] }").select,
        Some(SelectSpec::Band {
            band_hz: [1.0, 400.5]
        })
    );
    let m = fem("[structure.fem.machine]\nspring_stiffness = [1, 2, 3.5]")
        .machine
        .unwrap();
    assert_eq!(m.spring_stiffness, Some(PerDirection::Xyz([1.0, 2.0, 3.5])));
    let m = fem("[structure.fem.machine]\nspring_stiffness = 7")
        .machine
        .unwrap();
    assert_eq!(m.spring_stiffness, Some(PerDirection::All(7.0)));
}

#[test]
fn duplicate_floor_names_are_refused() {
    // Used to count the support springs twice (peak floor force 69 N -> 138 N).
    let e = set_err(&["structure.lumped.floor=[\"supports\", \"supports\"]"]);
    assert!(
        e.starts_with("--set structure.lumped.floor=[\"supports\", \"supports\"]: structure.lumped.floor[1]: 'supports' is already listed as structure.lumped.floor[0]"),
        "{e}"
    );
}

fn tabulated(floor: &str) -> String {
    format!(
        "[structure.modal]\nfrequencies_hz = [10.0, 100.0]\nshapes = {{ bed = [0.3, 0.1] }}\n{floor}\n\
         [points]\nbed_contact = \"bed\"\nmeasurement = \"bed\"\n\
         [slider]\nmass = 1.0\nvelocity = 1.0\n\
         [contact.slider_bed]\nstiffness = 1e6\n"
    )
}

#[test]
fn non_finite_numbers_in_tables_are_refused_naming_field_and_index() {
    // A tabulated floor force of NaN used to print 0.000 N.
    assert!(Model::from_text(
        "m.toml",
        tabulated("floor_force = { stiffness = [1e3, 2e3] }"),
        &[]
    )
    .is_ok());
    for (floor, field) in [
        (
            "floor_force = { stiffness = [1e3, nan] }",
            "structure.modal.floor_force.stiffness[1]",
        ),
        (
            "floor_force = { stiffness = [1e3, 2e3], damping = [inf, 0] }",
            "structure.modal.floor_force.damping[0]",
        ),
    ] {
        let e = Model::from_text("m.toml", tabulated(floor), &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("{field} must be a finite number")),
            "{e}"
        );
    }
    let e = Model::from_text(
        "m.toml",
        tabulated("").replace("[0.3, 0.1]", "[0.3, -inf]"),
        &[],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("structure.modal.shapes.bed"), "{e}");
    let e = Model::from_text(
        "m.toml",
        tabulated("").replace("[10.0, 100.0]", "[10.0, nan]"),
        &[],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("structure.modal.frequencies_hz[1]"), "{e}");
}

#[test]
fn numbers_beyond_what_double_precision_can_multiply_are_refused_naming_the_field() {
    // A mass of 1e-308 used to fail with "mode 1 frequency: must be finite (got NaN)" or a
    // "non-finite matrix" in the propagator, naming no field.
    for (set, field) in [
        (
            "structure.lumped.masses[1].mass=1e-308",
            "structure.lumped.masses[1].mass",
        ),
        ("slider.mass=1e-308", "slider.mass"),
        ("damper.mass=1e-308", "damper.mass"),
        (
            "structure.lumped.springs[0].stiffness=1e308",
            "structure.lumped.springs[0].stiffness",
        ),
    ] {
        let e = set_err(&[set]);
        assert!(
            e.starts_with(&format!("--set {set}: {field} = "))
                && e.contains("out of the range meid computes with")
                && e.contains("between 1e-100 and 1e100"),
            "{e}"
        );
    }
    // 0 and the edges of the range are numbers like any other.
    let ok = |s: &str| Model::from_text("m.toml", example(), &[s.to_string()]);
    assert!(ok("damper.damping=0").is_ok());
    assert!(ok("simulation.atol=1e-100").is_ok());
    // The blow's energy is bounded too (a velocity of 1e80 m/s is in range by itself).
    let e = set_err(&["slider.velocity=1e80"]);
    assert!(
        e.contains("slider.velocity") && e.contains("½ m_s v_s²") && e.contains("1e100 J"),
        "{e}"
    );
}
