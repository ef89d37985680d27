//! The integration tests of `meid`, one test binary: every file in this directory is a
//! module of it (`autotests = false` in Cargo.toml), so the tests link once instead of once
//! per file. A new test file is declared below; `every_test_file_is_declared` fails otherwise.
//! Run one file's tests with `cargo test --release -p meid --test suite -- FILE::`.

mod fuzz_support;
mod lanczos_support;

mod accumulation;
mod added_mass_point;
mod compare_checks;
mod compare_montecarlo;
mod correlate_checks;
mod docs_links;
mod dopri5_contact_laws;
mod ema_interop;
mod esd_checks;
mod exact_peaks;
mod fem_bad_input;
mod fem_beams;
mod fem_discrete;
mod fem_errors;
mod fem_general;
mod fem_gmsh;
mod fem_gmsh_formats;
mod fem_junction;
mod fem_kirchhoff_ritz;
mod fem_machine;
mod fem_machine_generator;
mod fem_paper_machine;
mod fem_patch;
mod fem_plates;
mod fem_releases;
mod fem_thread_determinism;
mod fem_tri;
mod forced_long_runs;
mod foundation_checks;
mod frf_files;
mod function_length;
mod fuzz_measure_readers;
mod fuzz_parsers;
mod held_contact;
mod identify_checks;
mod impact_closed_forms;
mod impact_conservation;
mod impact_events;
mod lanczos_closed_forms;
mod lanczos_large;
mod lanczos_robustness;
mod layering;
mod long_runs;
mod measure_calibrate;
mod measure_processing;
mod measure_validate;
mod modal_never_lies;
mod modal_update_fe;
mod model_input;
mod model_sketch;
mod modes_import;
mod modes_truncation;
mod network_blows;
mod network_dopri5;
mod network_engine;
mod network_model;
mod network_studies;
mod optimize_checks;
mod output_sets;
mod paper_impacts;
mod plot_checks;
mod plot_pictures;
mod propagator_taylor;
mod reference_mode;
mod report_measured;
mod restitution_contacts;
mod rigid_contacts;
mod small_eig;
mod spectrum_checks;
mod steady_examples;
mod stiff_inputs;
mod structure_cache;
mod sweep_cases;
mod sweep_checks;
mod sweep_fields;
mod sweep_optimize;
mod testlab_checks;
mod trust3_inputs;
mod typed_fields;
mod uff_interop;

/// Every `tests/*.rs` file of the library and of the CLI is a module of its crate's `suite.rs`
/// binary: with `autotests = false`, an undeclared file would silently never run. (One test
/// checks both crates.)
#[test]
fn every_test_file_is_declared() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut missing = Vec::new();
    for dir in [root.join("tests"), root.join("../meid-cli/tests")] {
        let suite = std::fs::read_to_string(dir.join("suite.rs")).expect("tests/suite.rs");
        for entry in std::fs::read_dir(&dir).expect("tests/") {
            let path = entry.expect("entry").path();
            let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
                continue;
            };
            if path.extension().is_some_and(|e| e == "rs")
                && stem != "suite"
                && !suite.lines().any(|l| l.trim() == format!("mod {stem};"))
            {
                missing.push(dir.join(format!("{stem}.rs")).display().to_string());
            }
        }
    }
    assert!(
        missing.is_empty(),
        "declare these in their crate's tests/suite.rs: {missing:?}"
    );
}
