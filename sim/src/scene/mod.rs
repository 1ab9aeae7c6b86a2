//! A garment on a moving body: the scene runner.
//!
//! The template is draped on the default shape (betas = 0) in the canonical A-pose with no
//! root translation. The sequence starts there (plus the motion's first root translation);
//! during the blend-in the body morphs from betas = 0 to the scene's betas and turns from the
//! canonical pose to the motion's first frame, while the cloth follows physically, then holds
//! that frame for the settle frames, then plays the motion. Body keyframes are 30 fps poses;
//! every substep interpolates them.

mod simulation;

use std::time::Instant;

use motions::{BlendIn, BodyModel, FramePose, Motion, PosedBody, canonical_a_pose};
use serde::{Deserialize, Serialize};

use crate::cloth::{ClothMesh, ClothState, Vec3, closest_on_triangle};
use crate::config::ValidSceneConfig;
use crate::error::{Error, Result};
use crate::obstacles::{AnimatedMesh, Obstacles};
use crate::params::{Material, SolverParams};
use crate::recording::{FrameRecord, FrameStats, RecordedScene, SequenceMeta, UNITS};
use crate::solver::{ClothSetup, FrameReport, Solver, StageTimes};
use simulation::Simulation;

/// Output frame rate, frames per second.
pub const FPS: f64 = 30.0;

/// A garment sequence ready to run: its configuration (checked: [`ValidSceneConfig`]) and what
/// the configuration names, loaded: the template, its body attachments and the motion.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The configuration (material, friction, frames, blend-in, solver settings).
    pub config: ValidSceneConfig,
    /// Template rest positions (draped on the canonical body), m.
    pub template: Vec<[f64; 3]>,
    /// Template triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Body shape, as many coefficients as the body model has.
    pub betas: Vec<f64>,
    /// The motion at 30 fps (the blend-in is added by the runner).
    pub motion: Motion,
    /// Cloth vertices held to body surface points (an elastic waistband), see
    /// [`attach_to_body`].
    pub attachments: Vec<BodyAttachment>,
}

/// A cloth vertex held by a spring to a point on the body surface: a body triangle, the
/// barycentric position on it, and the height above it along its normal. The point follows
/// the body as it moves and changes shape.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BodyAttachment {
    /// Cloth vertex.
    pub vertex: u32,
    /// Body triangle.
    pub triangle: u32,
    /// Barycentric coordinates on the triangle.
    pub barycentric: [f64; 3],
    /// Height above the triangle along its normal, m.
    pub height: f64,
    /// Spring stiffness, N/m.
    pub stiffness: f64,
}

impl BodyAttachment {
    /// Where the attached point is on a posed body.
    pub fn target(&self, vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec3 {
        let [a, b, c] = faces[self.triangle as usize].map(|v| {
            let p = vertices[v as usize];
            Vec3::new(p[0], p[1], p[2])
        });
        let normal = (b - a)
            .cross(&(c - a))
            .try_normalize(1e-20)
            .unwrap_or_else(Vec3::y);
        a * self.barycentric[0]
            + b * self.barycentric[1]
            + c * self.barycentric[2]
            + normal * self.height
    }
}

/// The body templates are made on: default shape (betas = 0), canonical A-pose, no root
/// translation.
pub fn canonical_body(model: &BodyModel) -> Result<PosedBody> {
    let shaped = model.shape(&[])?;
    let canonical = FramePose {
        pose: canonical_a_pose(),
        transl: [0.0; 3],
    };
    Ok(model.pose(&shaped, &canonical)?)
}

/// Attaches the given cloth vertices (template positions on the canonical body) to their
/// closest body surface points, with `stiffness` N/m each.
pub fn attach_to_body(
    model: &BodyModel,
    template: &[[f64; 3]],
    vertices: &[u32],
    stiffness: f64,
) -> Result<Vec<BodyAttachment>> {
    let body = canonical_body(model)?;
    let faces = model.faces();
    let mut out = Vec::with_capacity(vertices.len());
    for &v in vertices {
        let p = template.get(v as usize).ok_or_else(|| Error::Constraint {
            kind: "attachment",
            index: out.len(),
            problem: format!("vertex {v} does not exist ({} vertices)", template.len()),
        })?;
        let p = Vec3::new(p[0], p[1], p[2]);
        let mut best = (f64::INFINITY, 0u32, [0.0; 3]);
        for (t, f) in faces.iter().enumerate() {
            let [a, b, c] = f.map(|i| {
                let q = body.vertices[i as usize];
                Vec3::new(q[0], q[1], q[2])
            });
            let (q, bary) = closest_on_triangle(p, a, b, c);
            let d = (p - q).norm_squared();
            if d < best.0 {
                best = (d, t as u32, bary);
            }
        }
        let mut attachment = BodyAttachment {
            vertex: v,
            triangle: best.1,
            barycentric: best.2,
            height: 0.0,
            stiffness,
        };
        let on_surface = attachment.target(&body.vertices, faces);
        let [a, b, c] = faces[best.1 as usize].map(|i| {
            let q = body.vertices[i as usize];
            Vec3::new(q[0], q[1], q[2])
        });
        let normal = (b - a)
            .cross(&(c - a))
            .try_normalize(1e-20)
            .unwrap_or_else(Vec3::y);
        attachment.height = (p - on_surface).dot(&normal);
        out.push(attachment);
    }
    Ok(out)
}

fn cloth_setup(mesh: ClothMesh, material: Material, attachments: &[BodyAttachment]) -> ClothSetup {
    let mut setup = ClothSetup::new(mesh, material);
    setup.attachments = attachments
        .iter()
        .map(|a| crate::constraints::Attachment {
            vertex: a.vertex,
            stiffness: a.stiffness,
        })
        .collect();
    setup
}

fn attachment_targets(
    attachments: &[BodyAttachment],
    body: &[[f64; 3]],
    faces: &[[u32; 3]],
) -> Vec<Vec3> {
    attachments.iter().map(|a| a.target(body, faces)).collect()
}

/// One output frame handed to the caller.
#[derive(Debug)]
pub struct FrameOutput<'a> {
    /// Frame index.
    pub index: usize,
    /// Garment vertex positions, m.
    pub garment: &'a [[f64; 3]],
    /// Body pose of the frame (after blend-in).
    pub pose: &'a FramePose,
    /// Body shape of the frame (ramped during the blend-in).
    pub betas: &'a [f64],
    /// Posed body.
    pub body: &'a PosedBody,
    /// Statistics.
    pub stats: &'a FrameStats,
}

impl FrameOutput<'_> {
    /// The frame as the recording writer takes it: garment, pose, shape, body vertices and
    /// statistics.
    pub fn record(&self) -> FrameRecord<'_> {
        FrameRecord {
            index: self.index,
            garment: Some(self.garment),
            pose: &self.pose.pose,
            transl: self.pose.transl,
            betas: self.betas,
            body_vertices: Some(&self.body.vertices),
            joints: None,
            stats: Some(self.stats),
        }
    }
}

/// Summary of a run.
#[derive(Debug, Clone, Default, Serialize)]
pub struct RunSummary {
    /// Output frames (frame 0 included).
    pub frames: usize,
    /// Whether every output value was finite (always true for a finished run).
    pub finite: bool,
    /// Wall time of the simulation, s.
    pub wall_s: f64,
    /// Output frames per second of wall time.
    pub frames_per_s: f64,
    /// Largest penetration over the frames away from body overlaps, m.
    pub max_penetration_m: f64,
    /// Largest count of vertices inside the body over the frames, away from body overlaps.
    pub max_verts_inside: usize,
    /// Largest penetration over the frames where the body overlaps itself, m.
    pub max_penetration_overlap_m: f64,
    /// Largest count of vertices inside the body where it overlaps itself, over the frames.
    pub max_verts_inside_overlap: usize,
    /// Largest edge stretch over the frames.
    pub max_edge_stretch: f64,
    /// Largest count of crossing garment triangle pairs over the frames.
    pub max_self_intersections: usize,
    /// Garment vertices.
    pub vertices: usize,
    /// Mean iterations per step.
    pub mean_iterations: f64,
    /// Deep contacts (vertices found inside deeper than the band and brought out), total.
    pub deep_contacts: usize,
    /// Frames that needed smaller steps.
    pub retried_frames: usize,
    /// Where the time went, s per stage.
    #[serde(rename = "stages_s")]
    pub stages: StageTimes,
    /// Time spent posing the body (forward pass), s.
    pub posing_s: f64,
}

/// What a run's quality figures were, in one line: penetration (apart from and inside the
/// body's own overlaps), stretch and self-intersections.
impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let (depth, inside) = (self.max_penetration_m * 1e3, self.max_verts_inside);
        let overlap = self.max_penetration_overlap_m * 1e3;
        let inside_overlap = self.max_verts_inside_overlap;
        let (stretch, crossings) = (self.max_edge_stretch, self.max_self_intersections);
        write!(
            f,
            "max penetration {depth:.1} mm, at most {inside} vertices inside (where the body \
             overlaps itself: {overlap:.1} mm, {inside_overlap}), max edge stretch {stretch:.3}, \
             at most {crossings} self-intersections"
        )
    }
}

fn to_vec3(p: &[[f64; 3]]) -> Vec<Vec3> {
    p.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect()
}

/// Edge stretch (max, mean) of `positions` against the mesh's rest lengths.
pub fn edge_stretch(mesh: &ClothMesh, positions: &[Vec3]) -> (f64, f64) {
    let rest = mesh.rest();
    let (mut max, mut sum) = (0.0f64, 0.0);
    for &[i, j] in mesh.edges() {
        let (i, j) = (i as usize, j as usize);
        let r = (positions[i] - positions[j]).norm() / (rest[i] - rest[j]).norm();
        max = max.max(r);
        sum += r;
    }
    (max, sum / mesh.edges().len() as f64)
}

impl Scene {
    /// A scene from its checked configuration and what it names, loaded: the template (rest
    /// positions and triangles), its attachments and the motion. Checks the motion and that
    /// the body is closed (the inside test needs it).
    pub fn new(
        config: ValidSceneConfig,
        template: (Vec<[f64; 3]>, Vec<[u32; 3]>),
        attachments: Vec<BodyAttachment>,
        motion: Motion,
        model: &BodyModel,
    ) -> Result<Self> {
        if motion.is_empty() {
            return Err(Error::EmptyMotion {
                motion: motion.name.clone(),
            });
        }
        if let Some(frame) = motion
            .frames
            .iter()
            .position(|f| !f.pose.iter().chain(&f.transl).all(|v| v.is_finite()))
        {
            return Err(Error::NonFiniteMotion {
                motion: motion.name.clone(),
                frame,
            });
        }
        let open = model.boundary_edge_count();
        if open > 0 {
            return Err(Error::Obstacle {
                obstacle: format!("body model '{}'", model.name()),
                problem: format!(
                    "not closed ({open} boundary edges): the inside test needs a closed body"
                ),
            });
        }
        let betas = model.shape(&config.betas)?.betas;
        Ok(Self {
            config,
            template: template.0,
            triangles: template.1,
            betas,
            motion,
            attachments,
        })
    }

    /// Blend-in and settle frames.
    pub fn blend(&self) -> BlendIn {
        BlendIn {
            blend_frames: self.config.blend_frames,
            settle_frames: self.config.settle_frames,
        }
    }

    /// The metadata of this scene's recording.
    pub fn sequence_meta(&self, garment: &str, body_model: &str, software: &str) -> SequenceMeta {
        SequenceMeta {
            software: software.to_string(),
            garment: garment.to_string(),
            motion: self.motion.name.clone(),
            body_model: body_model.to_string(),
            betas: self.betas.clone(),
            fps: FPS,
            frames: self.num_frames(),
            blend_frames: self.config.blend_frames,
            settle_frames: self.config.settle_frames,
            material: self.config.material,
            friction: self.config.friction,
            seed: self.config.seed,
            solver: self.config.solver,
            units: UNITS.into(),
            config: Some(RecordedScene::of(&self.config)),
        }
    }

    /// The full motion the body follows (blend-in and settle prefix included).
    pub fn body_motion(&self) -> Motion {
        self.motion.with_blend_in(&canonical_a_pose(), self.blend())
    }

    /// The body shape of output frame `k`: ramped from zero over the blend-in, then the
    /// scene's.
    pub fn frame_betas(&self, k: usize) -> Vec<f64> {
        let blend = self.config.blend_frames;
        let ramp = if blend == 0 {
            1.0
        } else {
            (k as f64 / blend as f64).min(1.0)
        };
        self.betas.iter().map(|b| b * ramp).collect()
    }

    /// Number of output frames.
    pub fn num_frames(&self) -> usize {
        let all = self.body_motion().len();
        self.config.frames.map_or(all, |f| f.min(all))
    }

    /// Runs the scene, handing every output frame (frame 0 = the template) to `on_frame`.
    /// Stages: the start (cloth at rest on the first frame's body), then per frame the body
    /// posed, the frame advanced (again, finer, where a limb swept the cloth inside) and
    /// handed on, then the summary.
    pub fn run(
        &self,
        model: &BodyModel,
        mut on_frame: impl FnMut(&FrameOutput) -> Result<()>,
    ) -> Result<RunSummary> {
        let started = Instant::now();
        let frames = self.num_frames();
        let (mut sim, betas, body) = Simulation::start(self, model)?;
        on_frame(&sim.output(0, &betas, &body))?;
        for k in 1..frames {
            let frame_started = Instant::now();
            let (betas, body) = sim.pose(k)?;
            sim.advance(k, &body, frame_started)?;
            on_frame(&sim.output(k, &betas, &body))?;
        }
        Ok(sim.finish(frames, started))
    }

    #[allow(clippy::too_many_arguments)]
    fn measure(
        &self,
        mesh: &ClothMesh,
        state: &ClothState,
        solver: &Solver,
        body: &mut AnimatedMesh,
        frame: usize,
        report: FrameReport,
        wall: f64,
    ) -> FrameStats {
        let distances = body.measure(&state.positions, 0.03);
        let penetration = body.split_penetration(&state.positions, &distances);
        let (max_stretch, mean_stretch) = edge_stretch(mesh, &state.positions);
        let self_intersections =
            crate::count_self_intersections(&state.positions, mesh.triangles());
        FrameStats {
            frame,
            solver: report,
            max_penetration_m: penetration.depth_m,
            vertices_inside: penetration.inside,
            max_penetration_overlap_m: penetration.overlap_depth_m,
            vertices_inside_overlap: penetration.overlap_inside,
            max_edge_stretch: max_stretch,
            mean_edge_stretch: mean_stretch,
            self_intersections,
            kinetic_energy_j: solver.kinetic_energy(state),
            wall_s: wall,
        }
    }
}

/// The body of a scene's obstacles (always there: the runner puts it in).
fn scene_body(obstacles: &mut Obstacles) -> Result<&mut AnimatedMesh> {
    obstacles.body.as_mut().ok_or_else(|| Error::Obstacle {
        obstacle: "body".into(),
        problem: "the scene has no body".into(),
    })
}

fn accumulate(summary: &mut RunSummary, stats: &FrameStats) {
    summary.max_penetration_m = summary.max_penetration_m.max(stats.max_penetration_m);
    summary.max_verts_inside = summary.max_verts_inside.max(stats.vertices_inside);
    summary.max_penetration_overlap_m = summary
        .max_penetration_overlap_m
        .max(stats.max_penetration_overlap_m);
    summary.max_verts_inside_overlap = summary
        .max_verts_inside_overlap
        .max(stats.vertices_inside_overlap);
    summary.max_edge_stretch = summary.max_edge_stretch.max(stats.max_edge_stretch);
    summary.max_self_intersections = summary.max_self_intersections.max(stats.self_intersections);
}

/// Drapes a garment on the default shape in the canonical A-pose (no root translation):
/// `frames` frames of settling under gravity with air damping, the body still. Returns the
/// draped positions and the fraction of vertices still moving faster than 1 cm/s.
pub fn drape_on_canonical_body(
    model: &BodyModel,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    material: Material,
    friction: f64,
    frames: usize,
    attachments: &[BodyAttachment],
) -> Result<(Vec<[f64; 3]>, f64)> {
    let body = canonical_body(model)?;
    let mesh = ClothMesh::new(to_vec3(positions), triangles.to_vec())?;
    let params = SolverParams {
        substeps: 2,
        max_iterations: 20,
        air_damping: 2.0,
        ..SolverParams::default()
    };
    let mut solver = Solver::new(
        cloth_setup(mesh.clone(), material, attachments),
        params,
        1.0 / FPS,
    )?;
    solver.set_attachment_targets(&attachment_targets(
        attachments,
        &body.vertices,
        model.faces(),
    ));
    let vertices = to_vec3(&body.vertices);
    let mut obstacles = Obstacles::body(AnimatedMesh::new(&vertices, model.faces(), friction)?);
    let mut state = ClothState::at_rest(mesh.rest().to_vec());
    for k in 0..frames {
        solver.advance_frame(&mut state, &mut obstacles, k as f64 / FPS, k)?;
    }
    let moving = state.velocities.iter().filter(|v| v.norm() > 0.01).count() as f64
        / state.velocities.len() as f64;
    Ok((
        state.positions.iter().map(|p| [p.x, p.y, p.z]).collect(),
        moving,
    ))
}

/// Stiffness of each waistband attachment of the built-in skirt, N/m.
pub const WAISTBAND_STIFFNESS: f64 = 20.0;

/// A built-in garment as a template: fitted to `model` in its canonical pose, its waistband
/// (top ring) attached to the body like an elastic band, and draped there for 1.5 s.
pub fn builtin_template(
    model: &BodyModel,
    name: &str,
    params: &garments::SkirtParams,
) -> Result<(garments::Garment, Vec<BodyAttachment>)> {
    let body = canonical_body(model)?;
    let raw = garments::skirt(name, &body.vertices, params).map_err(|e| Error::Garment {
        garment: name.to_string(),
        problem: e.to_string(),
    })?;
    let waist: Vec<u32> = (0..params.columns as u32).collect();
    let attachments = attach_to_body(model, &raw.positions, &waist, WAISTBAND_STIFFNESS)?;
    let (draped, _) = drape_on_canonical_body(
        model,
        &raw.positions,
        &raw.triangles,
        Material::default(),
        0.5,
        45,
        &attachments,
    )?;
    // Heights above the body are those of the draped template.
    let attachments = attach_to_body(model, &draped, &waist, WAISTBAND_STIFFNESS)?;
    Ok((
        garments::Garment {
            positions: draped,
            ..raw
        },
        attachments,
    ))
}
