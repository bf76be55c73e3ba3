//! Studio project files: `Project::from_json` on any bytes; what it accepts must pass the
//! checks a session makes, or be refused by them, and open as a session when it passes.
#![no_main]

use bdmorph::studio::project::Project;
use bdmorph::studio::session::Session;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(project) = Project::from_json(data) else {
        return;
    };
    if project.check().is_err() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("bdmorph-fuzz-project-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let _ = Session::new(project, dir, None, None);
});
