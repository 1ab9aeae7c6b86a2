//! A scene's simulation between its frames, as stages over plain data: the start
//! ([`Simulation::start`]), the body of a frame ([`Simulation::pose`]), one frame advanced
//! with its retries ([`Simulation::advance`]), the frame handed on
//! ([`Simulation::output`]) and the summary ([`Simulation::finish`]).

use std::time::Instant;

use motions::{BodyModel, Motion, PosedBody, ShapedBody};

use super::{
    FrameOutput, RunSummary, Scene, accumulate, attachment_targets, cloth_setup, scene_body,
    to_vec3,
};
use crate::cloth::{ClothMesh, ClothState, Vec3};
use crate::error::Result;
use crate::obstacles::{AnimatedMesh, Obstacles, Plane};
use crate::recording::FrameStats;
use crate::solver::{FrameReport, Solver};

/// What the stages share: the cloth, its solver and obstacles, the body of the frame before,
/// and the counters of the summary.
pub(super) struct Simulation<'a> {
    scene: &'a Scene,
    model: &'a BodyModel,
    motion: Motion,
    /// The body at the scene's shape (every frame after the blend-in).
    shaped: ShapedBody,
    mesh: ClothMesh,
    solver: Solver,
    state: ClothState,
    obstacles: Obstacles,
    /// Body vertices of the frame before.
    previous: Vec<Vec3>,
    stats: FrameStats,
    /// The cloth's positions as handed on, m.
    garment: Vec<[f64; 3]>,
    summary: RunSummary,
    steps: usize,
    iterations: usize,
    posing_s: f64,
}

impl<'a> Simulation<'a> {
    /// The cloth at rest on frame 0's body (the template, moved by the motion's first root
    /// translation), its solver and obstacles; with frame 0's shape values and body.
    pub(super) fn start(
        scene: &'a Scene,
        model: &'a BodyModel,
    ) -> Result<(Self, Vec<f64>, PosedBody)> {
        let motion = scene.body_motion();
        let transl = motion.frames[0].transl;
        let start: Vec<Vec3> = scene
            .template
            .iter()
            .map(|p| Vec3::new(p[0] + transl[0], p[1] + transl[1], p[2] + transl[2]))
            .collect();
        let mesh = ClothMesh::new(to_vec3(&scene.template), scene.triangles.clone())?;
        let config = &scene.config;
        let solver = Solver::new(
            cloth_setup(mesh.clone(), config.material, &scene.attachments),
            config.solver,
            1.0 / super::FPS,
        )?;
        let state = ClothState::at_rest(start);
        let mut sim = Self {
            scene,
            model,
            motion,
            shaped: model.shape(&scene.betas)?,
            mesh,
            solver,
            state,
            obstacles: Obstacles::default(),
            previous: Vec::new(),
            stats: FrameStats::default(),
            garment: Vec::new(),
            summary: RunSummary::default(),
            steps: 0,
            iterations: 0,
            posing_s: 0.0,
        };
        let (betas, body) = sim.pose(0)?;
        sim.solver.set_attachment_targets(&attachment_targets(
            &scene.attachments,
            &body.vertices,
            model.faces(),
        ));
        let body_vertices = to_vec3(&body.vertices);
        let floor = body_vertices.iter().fold(f64::INFINITY, |a, p| a.min(p.y));
        let mut animated = AnimatedMesh::new(&body_vertices, model.faces(), config.friction)?;
        sim.stats = scene.measure(
            &sim.mesh,
            &sim.state,
            &sim.solver,
            &mut animated,
            0,
            FrameReport::default(),
            0.0,
        );
        sim.garment = sim
            .state
            .positions
            .iter()
            .map(|p| [p.x, p.y, p.z])
            .collect();
        sim.obstacles = Obstacles {
            ground: Some(Plane::ground(floor, config.friction)),
            ..Obstacles::body(animated)
        };
        sim.summary = RunSummary {
            vertices: sim.mesh.num_vertices(),
            finite: true,
            ..RunSummary::default()
        };
        sim.previous = body_vertices;
        accumulate(&mut sim.summary, &sim.stats);
        Ok((sim, betas, body))
    }

    /// Frame `k`'s shape values (ramped over the blend-in) and posed body.
    pub(super) fn pose(&mut self, k: usize) -> Result<(Vec<f64>, PosedBody)> {
        let t = Instant::now();
        let betas = self.scene.frame_betas(k);
        let shaped = if k >= self.scene.blend().blend_frames {
            self.shaped.clone()
        } else {
            self.model.shape(&betas)?
        };
        let posed = self.model.pose(&shaped, &self.motion.frames[k])?;
        self.posing_s += t.elapsed().as_secs_f64();
        Ok((betas, posed))
    }

    /// Advances the cloth to frame `k`, whose posed body is `body`: the body obstacle moves
    /// from the frame before to it, the attachments follow, and a frame that took the cloth
    /// deeper into the body than the solver's jump allows runs again with finer steps (the
    /// shallowest attempt is kept).
    pub(super) fn advance(&mut self, k: usize, body: &PosedBody, started: Instant) -> Result<()> {
        let next = to_vec3(&body.vertices);
        let t0 = (k - 1) as f64 / super::FPS;
        scene_body(&mut self.obstacles)?.set_keyframes(
            &self.previous,
            &next,
            t0,
            t0 + 1.0 / super::FPS,
        )?;
        self.solver.set_attachment_targets(&attachment_targets(
            &self.scene.attachments,
            &body.vertices,
            self.model.faces(),
        ));
        let deepest_before = self.stats.max_penetration_m;
        let solver_params = self.scene.config.solver;
        let jump = solver_params.max_penetration_jump;
        let saved = self.state.clone();
        let mut report = self
            .solver
            .advance_frame(&mut self.state, &mut self.obstacles, t0, k)?;
        // The attempt kept so far when the frame took the cloth too deep (the shallowest).
        let mut kept: Option<(ClothState, FrameStats)> = None;
        loop {
            self.steps += report.steps;
            self.iterations += report.iterations;
            self.summary.deep_contacts += report.deep_contacts;
            let wall = started.elapsed().as_secs_f64();
            let body_obstacle = scene_body(&mut self.obstacles)?;
            self.stats = self.scene.measure(
                &self.mesh,
                &self.state,
                &self.solver,
                body_obstacle,
                k,
                report,
                wall,
            );
            let depth = self.stats.max_penetration_m;
            if let Some(shallower) = kept.take_if(|(_, s)| s.max_penetration_m <= depth) {
                // Finer steps did not help: keep the shallower attempt and stop.
                (self.state, self.stats) = shallower;
                break;
            }
            let deepened = jump > 0.0 && depth - deepest_before > jump;
            if !deepened || report.retries >= solver_params.max_retries {
                break;
            }
            // A limb swept the cloth inside within this frame: run it again, finer.
            kept = Some((
                std::mem::replace(&mut self.state, saved.clone()),
                self.stats,
            ));
            let finer = report.retries + 1;
            report = self.solver.advance_frame_from(
                &mut self.state,
                &mut self.obstacles,
                t0,
                k,
                finer,
            )?;
        }
        // The last attempt's retry count (any frame-level retry makes it positive).
        self.summary.retried_frames += (report.retries > 0) as usize;
        accumulate(&mut self.summary, &self.stats);
        for (g, p) in self.garment.iter_mut().zip(&self.state.positions) {
            *g = [p.x, p.y, p.z];
        }
        self.previous = next;
        Ok(())
    }

    /// Frame `k` as handed on.
    pub(super) fn output<'o>(
        &'o self,
        k: usize,
        betas: &'o [f64],
        body: &'o PosedBody,
    ) -> FrameOutput<'o> {
        FrameOutput {
            index: k,
            garment: &self.garment,
            pose: &self.motion.frames[k],
            betas,
            body,
            stats: &self.stats,
        }
    }

    /// The run's summary after `frames` frames.
    pub(super) fn finish(mut self, frames: usize, started: Instant) -> RunSummary {
        let summary = &mut self.summary;
        summary.frames = frames;
        summary.wall_s = started.elapsed().as_secs_f64();
        summary.frames_per_s = frames as f64 / summary.wall_s;
        summary.mean_iterations = self.iterations as f64 / self.steps.max(1) as f64;
        summary.stages = self.solver.take_times();
        summary.posing_s = self.posing_s;
        self.summary
    }
}
