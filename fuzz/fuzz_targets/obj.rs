//! A garment OBJ of any bytes: read, checked and repaired, or refused.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok((garment, numbers)) = garments::parse_obj(data, "fuzz.obj", "fuzz") {
        let _ = garments::check_numbered(&garment, Some(&numbers));
        let _ = garments::repair_numbered(&garment, 1.0, Some(&numbers));
    }
});
