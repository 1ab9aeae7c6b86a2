//! A dataset spec of any text: parsed and planned, or refused.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = std::path::Path::new("fuzz.toml");
    if let Ok(spec) = dataset::DatasetSpec::parse(text, path) {
        let motions: Vec<_> = spec
            .motions
            .iter()
            .map(|m| (m.source.clone(), m.split))
            .collect();
        let _ = dataset::plan(&spec, &motions);
    }
});
