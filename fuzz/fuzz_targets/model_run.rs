//! A run folder of any `config.toml`, `tensors.json` and `model.safetensors`: loaded and run
//! once, or refused, never a panic, an abort or an unbounded allocation.
#![no_main]

mod folder;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = folder::folder(data, &["config.toml", "tensors.json", "model.safetensors"]);
    let device = surrogate::burn::prelude::Device::flex();
    if let Ok(trained) = surrogate::run::TrainedModel::load(dir.path(), &device) {
        folder::forward_once(&trained);
    }
});
