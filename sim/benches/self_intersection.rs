//! Cost of counting self-intersections (run every frame for the statistics): a 5,040-vertex
//! sheet flat (no crossing) and folded back through itself (a crossing line), and the same
//! sheet crumpled by noise. Figures go to docs/BENCHMARKS.md.

use criterion::{Criterion, criterion_group, criterion_main};
use sim::{Vec3, count_self_intersections};

fn sheet(fold: bool, noise: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (nx, nz) = (70usize, 72usize);
    let mut p = Vec::new();
    for j in 0..nz {
        for i in 0..nx {
            let (x, z) = (i as f64 / (nx - 1) as f64, j as f64 / (nz - 1) as f64);
            let (x, y) = if fold && x > 0.5 {
                (1.0 - x, 0.05 - (x - 0.5) * 0.4)
            } else {
                (x, 0.0)
            };
            let wobble = noise * ((i * 7 + j * 13) as f64).sin();
            p.push(Vec3::new(x, y + wobble, z));
        }
    }
    let mut t = Vec::new();
    for j in 0..nz - 1 {
        for i in 0..nx - 1 {
            let a = (j * nx + i) as u32;
            let (b, c, d) = (a + 1, a + nx as u32, a + nx as u32 + 1);
            t.push([a, b, d]);
            t.push([a, d, c]);
        }
    }
    (p, t)
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("self_intersections_5040v");
    for (name, fold, noise) in [
        ("flat", false, 0.0),
        ("folded_through", true, 0.0),
        ("crumpled", false, 0.02),
    ] {
        let (p, t) = sheet(fold, noise);
        group.bench_function(name, |b| b.iter(|| count_self_intersections(&p, &t)));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
