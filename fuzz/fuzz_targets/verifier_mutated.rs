//! `Program::from_parts` on a compiled program with up to 8 mutations decoded from the bytes; the VM runs what it accepts.
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fuzz_checks::verifier(fuzz_checks::mutated_from_bytes(data));
});
