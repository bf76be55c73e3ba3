//! `read_layered` (PSD and OpenRaster) on arbitrary bytes.
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fuzz_checks::layered_reader(data);
});
