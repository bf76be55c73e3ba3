//! `decode_image` on arbitrary bytes (PNG, JPEG), small pictures meshed by `mesh_picture`.
#![no_main]

#[path = "../../tests/fuzz_checks/mod.rs"]
mod fuzz_checks;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    fuzz_checks::picture_mesher(data);
});
