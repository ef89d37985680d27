//! The integration tests of `meid-cli`, one test binary: every file in this directory is a
//! module of it (`autotests = false` in Cargo.toml), so the tests link once instead of once
//! per file. A new test file is declared below; the library suite's `every_test_file_is_declared`
//! checks this crate's files too.
//! Run one file's tests with `cargo test --release -p meid-cli --test suite -- FILE::`.

mod common;

mod audit_s11_cli;
mod blows_general_cli;
mod calibrate_cli;
mod cli;
mod commands_doc;
mod compare_cli;
mod conventions;
mod correlate_cli;
mod fem_threads_cli;
mod foundation_cli;
mod frf_cli;
mod impacts_cli;
mod input_cli;
mod json_shape;
mod measure_cli;
mod model_cli;
mod modes_cli;
mod mutations;
mod network_cli;
mod network_study_cli;
mod outputs_cli;
mod paper_cli;
mod pictures_cli;
mod production_cli;
mod report_cli;
mod restitution_cli;
mod run_checks_cli;
mod shard_cli;
mod study_audit_s12_cli;
mod sweep_cli;
mod trust3_cli;
