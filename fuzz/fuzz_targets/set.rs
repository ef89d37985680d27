//! Fuzz target: `--set PATH=VALUE` overrides (one per line of the input) on the lumped paper
//! example.
#![no_main]

#[path = "../../crates/meid/tests/fuzz_support/mod.rs"]
mod fuzz_support;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let sets: Vec<String> = text.lines().take(8).map(str::to_string).collect();
        fuzz_support::check_model("paper-lumped.toml", fuzz_support::LUMPED, &sets);
    }
});
