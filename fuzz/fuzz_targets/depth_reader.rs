//! `parse_depth` on arbitrary bytes (lossy UTF-8, as a file is read).
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fuzz_checks::depth_reader(data);
});
