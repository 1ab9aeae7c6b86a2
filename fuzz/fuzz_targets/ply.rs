//! A garment PLY of any bytes (ASCII or binary): read, then the import's cleaning steps
//! (welding, UV overlap, checks and repairs), or refused.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mut garment) = garments::parse_ply(data, "fuzz.ply", "fuzz") {
        let _ = garments::uv_overlap(&garment);
        garments::weld(&mut garment, 1e-6);
        let _ = garments::check(&garment);
        let _ = garments::repair(&garment, 1.0);
    }
});
