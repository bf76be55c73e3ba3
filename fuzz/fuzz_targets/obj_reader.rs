//! `parse_obj` on arbitrary bytes (read as a file is, lossy UTF-8).
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fuzz_checks::reader_bytes(data, fuzz_checks::Format::Obj);
});
