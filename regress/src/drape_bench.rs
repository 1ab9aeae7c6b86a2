//! The standard drape scene of PHYSICS.md, the same as the peer scripts in ../shared/peers:
//! a 1 m x 1 m cloth (n x n grid) flat at 1.0 m falls for 2 s onto a static sphere of radius
//! 0.3 m centred 0.5 m high; rho 0.2 kg/m^2, mu 0.3, E h ~ 990 N/m, weak bending B ~ 9.9e-6 N m,
//! 5 mm contact radius, 60 frames at 30 fps, no ground. The measures are the peers'
//! (`scene_metrics.py`), computed in their z-up frame.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use crate::error::{Error, Result};
use sim::constraints::bending::RIGIDITY_PER_KB;
use sim::obstacles::{Obstacles, Sphere};
use sim::{ClothMesh, ClothState, Vec3};
use sim::{ClothSetup, Solver, StageTimes};
use sim::{Material, SolverParams};

/// Scene constants (peers' `scene_metrics.py`).
pub const SPHERE_CENTER_HEIGHT: f64 = 0.5;
/// Sphere radius, m.
pub const SPHERE_RADIUS: f64 = 0.3;
/// Initial cloth height, m.
pub const CLOTH_HEIGHT: f64 = 1.0;
/// Membrane stiffness E h, N/m.
pub const MEMBRANE_EH: f64 = 990.0;
/// Bending rigidity B, N m.
pub const BENDING_B: f64 = 9.9e-6;

/// The most vertices per side of the cloth (262,144 vertices; the published runs use 32 to
/// 128): more would size allocations past any machine's memory.
pub const MAX_GRID_N: usize = 512;

/// Settings of one drape-bench run.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct DrapeBench {
    /// Vertices per side.
    pub n: usize,
    /// Solver settings.
    pub params: SolverParams,
}

impl DrapeBench {
    /// The scene at `n` x `n` with the benchmark's solver settings.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            params: SolverParams {
                substeps: 8,
                max_iterations: 5,
                tolerance: 1e-4,
                contact_tolerance: 0.01,
                contact_offset: 0.005,
                ..SolverParams::default()
            },
        }
    }

    /// Material: k_s = E h (on this right-triangle grid the axis-aligned Young's modulus of
    /// the spring lattice equals k_s), k_b = B / (2 sqrt 3), rho 0.2.
    pub fn material() -> Material {
        Material {
            stretch: MEMBRANE_EH,
            density: 0.2,
            bending: BENDING_B / RIGIDITY_PER_KB,
        }
    }

    /// Runs the 2 s scene (its solver settings are validated first, naming a bad one).
    pub fn run(&self) -> Result<DrapeResult> {
        self.params.validate()?;
        let n = self.n;
        if !(2..=MAX_GRID_N).contains(&n) {
            return Err(Error::value(
                "n",
                n,
                &format!("must be 2 to {MAX_GRID_N} vertices per side"),
            ));
        }
        let mesh = ClothMesh::grid(n, 1.0, CLOTH_HEIGHT)?;
        let setup_started = Instant::now();
        let mut solver = Solver::new(
            ClothSetup::new(mesh.clone(), Self::material()),
            self.params,
            1.0 / 30.0,
        )?;
        let setup_s = setup_started.elapsed().as_secs_f64();
        let sphere = Sphere::new(
            Vec3::new(0.0, SPHERE_CENTER_HEIGHT, 0.0),
            SPHERE_RADIUS,
            0.3,
        );
        let mut obstacles = Obstacles::props(vec![Box::new(sphere)]);
        let mut state = ClothState::at_rest(mesh.rest().to_vec());
        let mut trajectory = Vec::with_capacity(60);
        let mut iterations = 0;
        let started = Instant::now();
        for frame in 0..60 {
            let report =
                solver.advance_frame(&mut state, &mut obstacles, frame as f64 / 30.0, frame)?;
            iterations += report.iterations;
            trajectory.push(state.positions.clone());
        }
        let wall = started.elapsed().as_secs_f64();
        let times = solver.take_times();
        let measures = DrapeMeasures::of(&state.positions, mesh.rest(), n);
        Ok(DrapeResult {
            sim: "dit-garment projective dynamics + exact Coulomb contact",
            n,
            t_sim_2s_wall_s: wall,
            setup_s,
            realtime_factor: 2.0 / wall,
            substeps_per_frame: self.params.substeps,
            max_iterations: self.params.max_iterations,
            mean_iterations: iterations as f64 / (60 * self.params.substeps) as f64,
            self_contact: self.params.self_contact,
            measures,
            stages: times,
            final_positions: state.positions,
            trajectory,
        })
    }
}

/// The peers' quality measures of a final state.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct DrapeMeasures {
    /// Whether every coordinate is finite.
    pub finite: bool,
    /// Vertices closer to the sphere centre than its radius.
    pub verts_inside_sphere: usize,
    /// Smallest distance to the sphere surface, m.
    pub min_dist_to_sphere_surface_m: f64,
    /// Largest current/rest length ratio over the grid's structural edges.
    pub max_edge_stretch: f64,
    /// 99th percentile of that ratio.
    pub p99_edge_stretch: f64,
    /// Mean of that ratio.
    pub mean_edge_stretch: f64,
    /// Area of the cloth's projection on the ground / 1 m^2 (rasterized at 2 mm).
    pub drape_proxy: f64,
    /// Lowest point, m.
    pub lowest_z_m: f64,
}

impl DrapeMeasures {
    /// Measures `positions` (y-up, grid order) against the rest grid.
    pub fn of(positions: &[Vec3], rest: &[Vec3], n: usize) -> Self {
        let center = Vec3::new(0.0, SPHERE_CENTER_HEIGHT, 0.0);
        let distances: Vec<f64> = positions.iter().map(|p| (p - center).norm()).collect();
        let mut ratios = Vec::with_capacity(2 * n * (n - 1));
        let id = |i: usize, j: usize| i * n + j;
        for i in 0..n {
            for j in 0..n {
                for (a, b) in [(i + 1, j), (i, j + 1)] {
                    if a < n && b < n {
                        let (p, q) = (id(i, j), id(a, b));
                        ratios.push(
                            (positions[p] - positions[q]).norm() / (rest[p] - rest[q]).norm(),
                        );
                    }
                }
            }
        }
        let mut sorted = ratios.clone();
        sorted.sort_by(f64::total_cmp);
        // numpy's default percentile: linear interpolation between closest ranks.
        let rank = 0.99 * (sorted.len() - 1) as f64;
        let (lo, frac) = (rank.floor() as usize, rank - rank.floor());
        let p99 = sorted[lo] + frac * (sorted[(lo + 1).min(sorted.len() - 1)] - sorted[lo]);
        Self {
            finite: positions.iter().all(|p| p.iter().all(|c| c.is_finite())),
            verts_inside_sphere: distances.iter().filter(|&&d| d < SPHERE_RADIUS).count(),
            min_dist_to_sphere_surface_m: distances
                .iter()
                .fold(f64::INFINITY, |a, &d| a.min(d - SPHERE_RADIUS)),
            max_edge_stretch: sorted[sorted.len() - 1],
            p99_edge_stretch: p99,
            mean_edge_stretch: ratios.iter().sum::<f64>() / ratios.len() as f64,
            drape_proxy: projected_area(positions, n, 0.002, 0.8),
            lowest_z_m: positions.iter().fold(f64::INFINITY, |a, p| a.min(p.y)),
        }
    }
}

/// Area of the union of the grid's triangles projected on the ground (x, z), by rasterizing
/// at `res` m over [-extent, extent]^2 (the peers' `projected_area`).
pub fn projected_area(positions: &[Vec3], n: usize, res: f64, extent: f64) -> f64 {
    let m = (2.0 * extent / res).round() as usize;
    let mut mask = vec![false; m * m];
    let id = |i: usize, j: usize| i * n + j;
    let mut triangles = Vec::with_capacity(2 * (n - 1) * (n - 1));
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    for t in triangles {
        let p = t.map(|k| (positions[k].x, positions[k].z));
        let (x0, y0) = p[0];
        let (x1, y1) = p[1];
        let (x2, y2) = p[2];
        let det = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
        if det.abs() < 1e-14 {
            continue;
        }
        let cell = |v: f64| ((v + extent) / res).floor().clamp(0.0, (m - 1) as f64) as usize;
        let cell_hi = |v: f64| ((v + extent) / res).ceil().clamp(0.0, m as f64) as usize;
        let (lo_x, hi_x) = (cell(x0.min(x1).min(x2)), cell_hi(x0.max(x1).max(x2)));
        let (lo_y, hi_y) = (cell(y0.min(y1).min(y2)), cell_hi(y0.max(y1).max(y2)));
        for gx in lo_x..hi_x {
            let x = (gx as f64 + 0.5) * res - extent;
            for gy in lo_y..hi_y {
                let y = (gy as f64 + 0.5) * res - extent;
                let l1 = ((x - x0) * (y2 - y0) - (x2 - x0) * (y - y0)) / det;
                let l2 = ((x1 - x0) * (y - y0) - (x - x0) * (y1 - y0)) / det;
                if l1 >= 0.0 && l2 >= 0.0 && l1 + l2 <= 1.0 {
                    mask[gx * m + gy] = true;
                }
            }
        }
    }
    mask.iter().filter(|&&b| b).count() as f64 * res * res
}

/// Result of a drape-bench run; it serializes with the keys the peers' runs report.
#[derive(Debug, Clone, Serialize)]
pub struct DrapeResult {
    /// The simulator, in words.
    pub sim: &'static str,
    /// Vertices per side.
    pub n: usize,
    /// Wall time of the 2 s simulation, s (factorization excluded).
    pub t_sim_2s_wall_s: f64,
    /// Setup time (analysis and factorization), s.
    pub setup_s: f64,
    /// Simulated time / wall time.
    pub realtime_factor: f64,
    /// Substeps per frame.
    pub substeps_per_frame: usize,
    /// Iteration cap per substep.
    #[serde(rename = "iterations_per_substep")]
    pub max_iterations: usize,
    /// Mean iterations per substep.
    pub mean_iterations: f64,
    /// Whether cloth-cloth contact was on.
    pub self_contact: bool,
    /// Quality measures of the final frame.
    #[serde(flatten)]
    pub measures: DrapeMeasures,
    /// Where the time went.
    #[serde(rename = "stages_s")]
    pub stages: StageTimes,
    /// Final positions (y-up, grid order).
    #[serde(skip)]
    pub final_positions: Vec<Vec3>,
    /// Positions of each of the 60 frames.
    #[serde(skip)]
    pub trajectory: Vec<Vec<Vec3>>,
}

impl DrapeResult {
    /// Writes the final vertices as the peers' runs do: `.npy`, float64 `[n * n, 3]`, z up
    /// (x, z, y of ours), grid order; atomically, its folder made if missing.
    pub fn write_final_npy(&self, path: &Path) -> Result<()> {
        use npyz::WriterBuilder;
        let data = self.final_positions.iter().flat_map(|p| [p.x, p.z, p.y]);
        files::create_folder_of(path)?;
        files::write_with(path, |w| {
            let mut writer = npyz::WriteOptions::<f64>::new()
                .default_dtype()
                .shape(&[self.final_positions.len() as u64, 3])
                .writer(w)
                .begin_nd()?;
            writer.extend(data)?;
            writer.finish()
        })?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The final vertices go out z-up as `[n * n, 3]` float64, readable by npyz (as NumPy
    /// reads them), and the JSON carries the peers' keys.
    #[test]
    fn the_result_is_written_in_the_peers_layout() {
        let r = DrapeBench::new(4).run().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("new/final_n4.npy");
        r.write_final_npy(&path).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
        assert_eq!(npy.shape(), &[16, 3]);
        let values: Vec<f64> = npy.into_vec().unwrap();
        let p = r.final_positions[5];
        assert_eq!(&values[15..18], &[p.x, p.z, p.y]);
        let json = serde_json::to_value(&r).unwrap();
        for key in [
            "iterations_per_substep",
            "stages_s",
            "drape_proxy",
            "self_contact",
            "sim",
        ] {
            assert!(json.get(key).is_some(), "{key}: {json}");
        }
    }

    #[test]
    fn flat_grid_measures() {
        let mesh = ClothMesh::grid(11, 1.0, 1.0).unwrap();
        let m = DrapeMeasures::of(mesh.rest(), mesh.rest(), 11);
        assert!((m.drape_proxy - 1.0).abs() < 0.01, "{}", m.drape_proxy);
        assert_eq!(m.verts_inside_sphere, 0);
        assert!((m.max_edge_stretch - 1.0).abs() < 1e-12);
        assert_eq!(m.lowest_z_m, 1.0);
    }
}
