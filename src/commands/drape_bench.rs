//! `dit-garment drape-bench`: the peers' drape scene, timed and measured with their measures;
//! the final vertices are written in their layout (z-up, grid order) for side-by-side checks.

use anyhow::Result;
use serde_json::json;
use sim::drape_bench::DrapeBench;

use crate::cli::DrapeBenchArgs;
use files::write_json;

pub fn run(args: &DrapeBenchArgs) -> Result<()> {
    let max = sim::drape_bench::MAX_GRID_N;
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
    let result = json!({
        "sim": "dit-garment projective dynamics + exact Coulomb contact",
        "n": r.n, "t_sim_2s_wall_s": r.t_sim_2s_wall_s, "realtime_factor": r.realtime_factor,
        "setup_s": r.setup_s, "substeps_per_frame": r.substeps_per_frame,
        "iterations_per_substep": r.max_iterations, "mean_iterations": r.mean_iterations,
        "self_contact": args.self_contact,
        "finite": m.finite, "verts_inside_sphere": m.verts_inside_sphere,
        "min_dist_to_sphere_surface_m": m.min_dist_to_sphere_surface_m,
        "max_edge_stretch": m.max_edge_stretch, "p99_edge_stretch": m.p99_edge_stretch,
        "mean_edge_stretch": m.mean_edge_stretch, "drape_proxy": m.drape_proxy,
        "lowest_z_m": m.lowest_z_m,
        "stages_s": r.stages,
    });
    let npy = args.out.join(format!("final_n{}.npy", args.n));
    // Peers' frame: z up, (x, z_ours, y_ours).
    let data: Vec<f64> = r
        .final_positions
        .iter()
        .flat_map(|p| [p.x, p.z, p.y])
        .collect();
    files::create_folder_of(&npy)?;
    files::write_with(&npy, |w| {
        use npyz::WriterBuilder;
        let mut writer = npyz::WriteOptions::<f64>::new()
            .default_dtype()
            .shape(&[r.final_positions.len() as u64, 3])
            .writer(w)
            .begin_nd()?;
        writer.extend(data.iter().copied())?;
        writer.finish()?;
        Ok(())
    })?;
    write_json(&args.out.join(format!("result_n{}.json", args.n)), &result)?;
    if let Some(path) = &args.json {
        write_json(path, &result)?;
    }
    println!(
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
    println!("  wrote {}", npy.display());
    Ok(())
}
