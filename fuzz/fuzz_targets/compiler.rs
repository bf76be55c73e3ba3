//! The compiler on 1 to 12 vertices and up to 24 faces decoded from the bytes, then the VM.
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (positions, faces) = fuzz_checks::mesh_from_bytes(data);
    fuzz_checks::compile_and_run(&positions, &faces);
});
