//! `dit-garment drape-bench`: the peers' drape scene, timed and measured with their measures;
//! the final vertices are written in their layout (z-up, grid order) for side-by-side checks.

use anyhow::Result;
use regress::drape_bench::DrapeBench;

use crate::cli::DrapeBenchArgs;
use files::write_json;

pub fn run(args: &DrapeBenchArgs) -> Result<()> {
    let max = regress::drape_bench::MAX_GRID_N;
    anyhow::ensure!(
        (2..=max).contains(&args.n),
        "--n {}: must be 2 to {max} vertices per side",
        args.n
    );
    let mut bench = DrapeBench::new(args.n);
    bench.params.substeps = args.substeps;
    bench.params.max_iterations = args.iterations;
    bench.params.self_contact = args.self_contact;
    let r = bench.run()?;
    let m = &r.measures;
    let result = serde_json::to_value(&r)?;
    let npy = args.out.join(format!("final_n{}.npy", args.n));
    r.write_final_npy(&npy)?;
    write_json(&args.out.join(format!("result_n{}.json", args.n)), &result)?;
    if let Some(path) = &args.json {
        write_json(path, &result)?;
    }
    say!(
        "drape-bench n={}: 2 s simulated in {:.2} s wall ({:.2}x real time), {} vertices inside the sphere, max edge stretch {:.4}, p99 {:.4}, drape area ratio {:.3}, lowest point {:.3} m",
        r.n,
        r.t_sim_2s_wall_s,
        r.realtime_factor,
        m.verts_inside_sphere,
        m.max_edge_stretch,
        m.p99_edge_stretch,
        m.drape_proxy,
        m.lowest_z_m
    );
    say!("  wrote {}", npy.display());
    Ok(())
}
