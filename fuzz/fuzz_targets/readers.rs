//! Fuzz target: the measured-data and mode-file readers (UFF, CSV, CalculiX .frd) on the same
//! bytes, and the modes import of what they accept.
#![no_main]

#[path = "../../crates/meid/tests/fuzz_support/readers.rs"]
mod readers;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    readers::check_uff(data);
    readers::check_uff_import(data);
    readers::check_csv(data);
    readers::check_frd(data);
});
