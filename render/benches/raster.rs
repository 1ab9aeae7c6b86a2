//! Rendering speed: one 512 x 512 picture of a 5,040-vertex garment on the 13,380-vertex
//! default body (walking pose), on one core, with and without 2 x 2 supersampling; plus the
//! GIF frame encoding. Figures go to docs/BENCHMARKS.md.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use motions::BodyModel;
use motions::library::MotionSpec;
use render::viewer::{BODY_COLOUR, GARMENT_COLOURS};
use render::{Bounds, Camera, GifWriter, Layer, P3, Renderer, View};

/// A pleated tube around the hips: 70 vertices around, 72 down (5,040 vertices).
fn skirt() -> (Vec<P3>, Vec<[u32; 3]>) {
    let (around, down) = (70usize, 72usize);
    let mut positions = Vec::with_capacity(around * down);
    for j in 0..down {
        let t = j as f32 / (down - 1) as f32;
        let y = 1.0 - 0.55 * t;
        for i in 0..around {
            let a = i as f32 / around as f32 * std::f32::consts::TAU;
            let r = 0.17 + 0.12 * t + 0.02 * t * (8.0 * a).sin();
            positions.push([r * a.sin(), y, r * a.cos()]);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..down - 1 {
        for i in 0..around {
            let (a, b) = (j * around + i, j * around + (i + 1) % around);
            let (c, d) = (a + around, b + around);
            triangles.push([a as u32, c as u32, b as u32]);
            triangles.push([b as u32, c as u32, d as u32]);
        }
    }
    (positions, triangles)
}

fn raster(c: &mut Criterion) {
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    let motion = MotionSpec::parse("walk:duration=2")
        .unwrap()
        .generate(&model, &shaped)
        .unwrap();
    let posed = model.pose(&shaped, &motion.frames[20]).unwrap();
    let body: Vec<P3> = posed.vertices.iter().map(|p| p.map(|c| c as f32)).collect();
    let (mut garment, triangles) = skirt();
    for p in &mut garment {
        p[0] += body.iter().map(|b| b[0]).sum::<f32>() / body.len() as f32;
        p[2] += body.iter().map(|b| b[2]).sum::<f32>() / body.len() as f32;
    }
    let layers = [
        Layer {
            positions: &garment,
            triangles: &triangles,
            colour: GARMENT_COLOURS[0],
            values: None,
        },
        Layer {
            positions: &body,
            triangles: model.faces(),
            colour: BODY_COLOUR,
            values: None,
        },
    ];
    let bounds = Bounds::of(body.iter().chain(&garment)).unwrap();
    let camera = Camera::framing(View::ThreeQuarter, &bounds, 1.0);
    let mut group = c.benchmark_group("render_512_garment_5040v_body_13380v_1_core");
    group.throughput(Throughput::Elements(1));
    group.sample_size(20);
    for ssaa in [1, 2] {
        let mut renderer = Renderer::new(512, 512, ssaa);
        group.bench_function(format!("ssaa_{ssaa}"), |b| {
            b.iter(|| renderer.render(&camera, &layers).width())
        });
    }
    let mut small = Renderer::new(320, 320, 2);
    let picture = small.render(&camera, &layers).clone();
    group.bench_function("gif_frame_320", |b| {
        let mut gif = GifWriter::new(std::io::sink(), 320, 320, 15.0).unwrap();
        b.iter(|| gif.push(&picture).unwrap())
    });
    group.bench_function("png_512", |b| {
        let mut renderer = Renderer::new(512, 512, 2);
        let image = renderer.render(&camera, &layers).clone();
        b.iter(|| {
            let mut out = Vec::new();
            render::write_png(&mut out, &image).unwrap();
            out.len()
        })
    });
    group.finish();
}

criterion_group!(benches, raster);
criterion_main!(benches);
