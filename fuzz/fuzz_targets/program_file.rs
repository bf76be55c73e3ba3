//! `Program::from_bytes` on a program file with a valid length and checksum decoded from the
//! bytes (a base program's file with damaged bytes, or arbitrary sections); the VM runs what
//! it accepts.
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fuzz_checks::program_file(&fuzz_checks::file_from_bytes(data));
});
