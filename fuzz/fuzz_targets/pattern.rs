//! A GarmentCode sewing pattern of any text: parsed and meshed, or refused.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(pattern) = garments::Pattern::parse("fuzz", text) {
        let _ = pattern.mesh(garments::pattern::DEFAULT_EDGE_LENGTH_M);
    }
});
