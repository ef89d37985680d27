//! Fuzz target: the command-line specifications: `--vary` (sweep and montecarlo), the
//! distributions, `--bounds`, `--over`, `--objective`, `--case` (each line of the input).
#![no_main]

#[path = "../../crates/meid/tests/fuzz_support/mod.rs"]
mod fuzz_support;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        for line in text.lines().take(8) {
            fuzz_support::check_spec(line);
        }
    }
});
