//! Cost of the geometry-image hot paths on a real template (the library's tshirt_regular,
//! meshed from its pattern: 6 UV charts): building the atlas and the readback at 32, 64 and
//! 128, and at 64 encoding a frame, reading it back and the readback's transpose (run per
//! frame by training-data export and per denoising step by guidance). Figures go to
//! docs/BENCHMARKS.md.

use criterion::{Criterion, criterion_group, criterion_main};
use surrogate::geometry::GeometryImage;

fn bench(c: &mut Criterion) {
    let design = garments::library::find("tshirt_regular").expect("a library design");
    let mesh = design
        .pattern()
        .expect("its pattern")
        .mesh(garments::pattern::DEFAULT_EDGE_LENGTH_M)
        .expect("its mesh");
    let g = &mesh.garment;
    let n = g.positions.len();
    let mut group = c.benchmark_group(format!("geometry_image_tshirt_{n}v"));
    for r in [32, 64, 128] {
        group.bench_function(format!("build_{r}"), |b| {
            b.iter(|| GeometryImage::new(n, &g.triangles, &g.uvs, &g.uv_triangles, r).unwrap())
        });
    }
    let image = GeometryImage::new(n, &g.triangles, &g.uvs, &g.uv_triangles, 64).unwrap();
    let map = image.encode(&g.positions).unwrap();
    group.bench_function("encode_64", |b| {
        b.iter(|| image.encode(&g.positions).unwrap())
    });
    group.bench_function("read_64", |b| b.iter(|| image.read(&map).unwrap()));
    group.bench_function("read_transpose_64", |b| {
        b.iter(|| image.read_transpose(&g.positions).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
