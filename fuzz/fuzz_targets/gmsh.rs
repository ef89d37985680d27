//! Fuzz target: a Gmsh 4.1 ASCII mesh through `parse_msh`, then onto a shell mesh.
#![no_main]

#[path = "../../crates/meid/tests/fuzz_support/mod.rs"]
mod fuzz_support;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        fuzz_support::check_gmsh(text);
    }
});
