//! A sequence recording (MCAP) of any bytes: read back or refused, never a panic or abort.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = sim::recording::Recording::from_bytes(data, std::path::Path::new("fuzz.mcap"));
});
