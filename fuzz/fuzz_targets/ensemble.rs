//! An ensemble folder of any `ensemble.toml` beside two run folders `a/` and `b/` of any
//! files: loaded and run once, or refused.
#![no_main]

mod folder;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = folder::folder(
        data,
        &[
            "ensemble.toml",
            "a/config.toml",
            "a/tensors.json",
            "a/model.safetensors",
            "b/config.toml",
            "b/tensors.json",
            "b/model.safetensors",
        ],
    );
    let device = surrogate::burn::prelude::Device::flex();
    if let Ok(trained) = surrogate::run::TrainedModel::load(dir.path(), &device) {
        folder::forward_once(&trained);
    }
});
