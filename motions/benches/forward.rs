//! Forward-pass throughput: a batch of 300 frames of the built-in walk on 2 threads, for the
//! default body (13,380 vertices, no pose blend shapes) and an SMPL-sized model (6,890
//! vertices, dense pose blend shapes). Figures go to docs/BENCHMARKS.md.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use motions::library::MotionSpec;
use motions::{BodyModel, ModelArrays, NUM_JOINTS, SMPL_PARENTS};

/// An SMPL-sized model built from the default body's first 6,890 vertices, with non-zero pose
/// blend shapes so the pass does SMPL's full work.
fn smpl_sized(default: &BodyModel) -> BodyModel {
    let nv = 6890;
    let v_template: Vec<[f64; 3]> = default.template()[..nv].to_vec();
    let mut weights = vec![0.0; nv * NUM_JOINTS];
    let mut j_regressor = vec![0.0; NUM_JOINTS * nv];
    for v in 0..nv {
        weights[v * NUM_JOINTS + v % NUM_JOINTS] = 0.75;
        weights[v * NUM_JOINTS + (v + 1) % NUM_JOINTS] = 0.25;
        j_regressor[(v % NUM_JOINTS) * nv + v] = 1.0;
    }
    for row in j_regressor.chunks_mut(nv) {
        let sum: f64 = row.iter().sum();
        row.iter_mut().for_each(|w| *w /= sum);
    }
    let posedirs = (0..nv * 3 * 207)
        .map(|i| 1e-4 * ((i % 97) as f64 - 48.0))
        .collect();
    let shapedirs = (0..nv * 3 * 10)
        .map(|i| 1e-3 * ((i % 13) as f64 - 6.0))
        .collect();
    BodyModel::from_arrays(ModelArrays {
        v_template,
        faces: vec![],
        shapedirs,
        num_betas: 10,
        posedirs,
        j_regressor,
        weights,
        parents: SMPL_PARENTS,
        beta_names: vec![],
    })
    .unwrap()
}

fn forward(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let default = BodyModel::default_body();
    let smpl = smpl_sized(&default);
    let mut group = c.benchmark_group("forward_300_frames_2_threads");
    group.throughput(Throughput::Elements(300));
    group.sample_size(10);
    for (name, model) in [
        ("default_body_13380v", &default),
        ("smpl_sized_6890v_posedirs", &smpl),
    ] {
        let shaped = model.shape(&[0.5, -0.3]).unwrap();
        let motion = MotionSpec::parse("walk:duration=10")
            .unwrap()
            .generate(model, &shaped)
            .unwrap();
        let frames = &motion.frames[..300];
        group.bench_function(name, |b| {
            b.iter(|| pool.install(|| model.pose_batch(&shaped, frames).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(benches, forward);
criterion_main!(benches);
