//! The model-folder targets' input: files of a folder joined by a separator line, written into
//! a fresh temporary folder under fixed names (a part the input lacks is a file that is not
//! there), so one input mutates every file of a run, an ensemble or a checkpoint at once.

/// What separates two files in an input (`fuzz/run.sh` joins the seeds with it).
pub const SEPARATOR: &[u8] = b"\n@@next-file@@\n";

/// Writes `data`'s parts into a new temporary folder as `names` (in order; sub-folders made).
pub fn folder(data: &[u8], names: &[&str]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("a temporary folder");
    for (name, part) in names.iter().zip(parts(data)) {
        let path = dir.path().join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).expect("a sub-folder");
        }
        std::fs::write(&path, part).expect("a temporary file");
    }
    dir
}

fn parts(data: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut rest = data;
    while let Some(at) = rest
        .windows(SEPARATOR.len())
        .position(|w| w == SEPARATOR)
    {
        out.push(&rest[..at]);
        rest = &rest[at + SEPARATOR.len()..];
    }
    out.push(rest);
    out
}

/// One forward pass of a loaded model on zero inputs of its configuration's shapes: a model
/// that loads must also run (weights of another dtype used to load, then panic here).
pub fn forward_once(trained: &surrogate::run::TrainedModel) {
    use surrogate::burn::prelude::*;
    let m = &trained.config.model;
    let device = &trained.device;
    let r = m.resolution;
    let zeros = |c: usize| Tensor::<4>::zeros([1, c, r, r], device);
    let out = trained.model.forward(
        zeros(3),
        zeros(m.texel_channels()),
        zeros(1),
        Tensor::<1>::ones([1], device),
        Tensor::<2>::zeros([1, m.condition_dim], device),
    );
    assert_eq!(out.dims(), [1, 3, r, r]);
}
