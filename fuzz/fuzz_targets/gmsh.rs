//! Fuzz target: any bytes through the Gmsh reader (MSH 4.1 ASCII and binary, 2.2 ASCII), then
//! onto a shell mesh.
#![no_main]

#[path = "../../crates/meid/tests/fuzz_support/mod.rs"]
mod fuzz_support;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fuzz_support::check_gmsh_bytes(data);
});
