//! BVH import: CMU's `01_03` (4,511 frames at 120 fps, 31 joints; Debian's assimp-testmodels)
//! parsed, retargeted onto the default body, and the whole motion argument (parse, retarget,
//! resample to 30 fps, place on the floor). Skipped, with a note, where the clip is not
//! installed. Figures go to docs/BENCHMARKS.md.

use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use motions::bvh::{Bvh, JointMap, retarget};
use motions::{BodyModel, MotionSource};

const CLIP: &str = "/usr/share/assimp/models/BVH/01_03.bvh";

fn bench(c: &mut Criterion) {
    let path = Path::new(CLIP);
    if !path.exists() {
        eprintln!("{CLIP} is not installed (apt-get install assimp-testmodels): nothing to time");
        return;
    }
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    let text = std::fs::read_to_string(path).unwrap();
    let bvh = Bvh::parse(&text, path).unwrap();
    let map = JointMap::builtin_for(&bvh).unwrap();
    let mut group = c.benchmark_group("bvh_01_03");
    group.throughput(Throughput::Elements(bvh.frames() as u64));
    group.sample_size(20);
    group.bench_function("parse", |b| b.iter(|| Bvh::parse(&text, path).unwrap()));
    group.bench_function("retarget", |b| {
        b.iter(|| retarget(&bvh, &map, &shaped).unwrap())
    });
    let source = MotionSource::parse(CLIP).unwrap();
    group.bench_function("load_30fps_on_the_floor", |b| {
        b.iter(|| source.load(&model, &shaped).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
