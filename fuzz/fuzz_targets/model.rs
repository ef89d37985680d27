//! Fuzz target: a model file (TOML) through `Model::from_text` (parse, validate, build).
#![no_main]

#[path = "../../crates/meid/tests/fuzz_support/mod.rs"]
mod fuzz_support;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        fuzz_support::check_model("fuzz.toml", text, &[]);
    }
});
