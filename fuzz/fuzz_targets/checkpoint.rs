//! A training run's resume state of any bytes (`checkpoint.json`, the checkpoint folder's
//! `config.toml`, `state.json` and burnpack files, `log.jsonl`, and the checkpoint's
//! `checksums.json` where the input has that many parts): loaded
//! for a resume, or refused.
#![no_main]

mod folder;

use libfuzzer_sys::fuzz_target;
use surrogate::burn::prelude::Device;

fuzz_target!(|data: &[u8]| {
    let dir = folder::folder(
        data,
        &[
            "checkpoint.json",
            "checkpoint-00000010/config.toml",
            "checkpoint-00000010/state.json",
            "checkpoint-00000010/model.bpk",
            "checkpoint-00000010/optim.bpk",
            "checkpoint-00000010/ema.bpk",
            "log.jsonl",
            // Last, so an input of one part fewer has none: such a checkpoint is refused before
            // burn reads it.
            "checkpoint-00000010/checksums.json",
        ],
    );
    let run = dir.path();
    let _ = files::read_json_lines::<surrogate::train::LogLine>(
        &run.join("log.jsonl"),
        "training log",
    );
    let Ok(config) = surrogate::run::RunConfig::load_saved(&run.join("checkpoint-00000010/config.toml"))
    else {
        return;
    };
    if config.validate().is_err() {
        return;
    }
    let device = Device::flex().autodiff();
    let _ = surrogate::train::load_checkpoint(run, &config, &device);
});
