//! A pickle of any bytes: read by the restricted pickle machine (no code runs), then taken as
//! SMPL fits and as a capture frame's mesh, or refused.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = motions::pickle::read(data);
    let dir = std::env::temp_dir().join(format!("fuzz-pickle-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let file = dir.join("frame.pkl");
    if std::fs::write(&file, data).is_ok() {
        let _ = motions::fits::load(&file, 30.0);
        let _ = sim::metrics::read_capture_frame(&file, Some("upper"));
    }
});
