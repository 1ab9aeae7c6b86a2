//! The animated body: a closed mesh given as keyframes (30 fps poses), linearly interpolated
//! to every substep with the keyframe difference as its velocity, so friction carries the
//! cloth along with the body.
//!
//! Detection uses the signed distance (parry3d's inside test), so a vertex that got deeper
//! than the contact band is still found and brought out. To keep queries cheap, each cloth
//! vertex remembers which side of the body it was last seen on and a lower bound on its
//! distance: a vertex known to be far is not queried until it (or the body) could have moved
//! that far, and a bounded query that finds nothing keeps the last known side.

use rayon::prelude::*;

use super::overlap::{Penetration, split_penetration};
use super::trimesh::MeshSurface;
use super::{DetectionInput, Obstacle, SurfacePoint};
use crate::cloth::Vec3;
use crate::contact::Contact;
use crate::error::{Error, Result};

/// Distance a bounded query looks, as a multiple of the contact band (at least 3 cm).
const QUERY_REACH: f64 = 3.0;

/// What the body knows about one cloth vertex between steps.
#[derive(Debug, Clone, Copy)]
struct Track {
    /// Last known side: +1 outside, -1 inside, 0 never seen.
    side: i8,
    /// Lower bound on the vertex's distance to the surface, m (0 = must query).
    clearance: f64,
    /// The predicted position the bound was computed at.
    at: Vec3,
}

/// The animated body obstacle.
pub struct AnimatedMesh {
    surface: MeshSurface,
    friction: f64,
    start: Vec<Vec3>,
    end: Vec<Vec3>,
    times: (f64, f64),
    current: Vec<Vec3>,
    velocity: Vec<Vec3>,
    moved: f64,
    tracks: Vec<Track>,
    dirty: bool,
    /// Whether both keyframes are the same pose (blend-in settle, sewing): nothing to
    /// interpolate, so the surface is refit once, not every substep.
    still: bool,
    /// Whether every substep interpolates the body between its keyframes and refits the BVH
    /// (exact in time, one refit per substep; the default), or the surface moves to the end
    /// keyframe at the first substep of each frame (one refit per keyframe). Jumping a whole
    /// frame at once lets a fast limb sweep past cloth in one substep, and the cloth found
    /// inside is pushed out the far side: on `run` a fitted sleeve slid off the forearm
    /// (44.5 mm deep, 507 vertices inside; 12.4 mm and 118 interpolated, docs/PHYSICS.md).
    pub interpolate_substeps: bool,
}

impl AnimatedMesh {
    /// A body at rest at `vertices` (closed, outward-oriented).
    pub fn new(vertices: &[Vec3], faces: &[[u32; 3]], friction: f64) -> Result<Self> {
        let surface = MeshSurface::new("body", vertices, faces)?;
        Ok(Self {
            surface,
            friction,
            start: vertices.to_vec(),
            end: vertices.to_vec(),
            times: (0.0, 1.0),
            current: vertices.to_vec(),
            velocity: vec![Vec3::zeros(); vertices.len()],
            moved: 0.0,
            tracks: Vec::new(),
            dirty: true,
            still: true,
            interpolate_substeps: true,
        })
    }

    /// Sets the keyframes the body moves between: `start` at time `t0` and `end` at `t1` (s).
    pub fn set_keyframes(&mut self, start: &[Vec3], end: &[Vec3], t0: f64, t1: f64) -> Result<()> {
        let n = self.surface.num_vertices();
        if start.len() != n || end.len() != n {
            return Err(body_error(format!(
                "keyframes have {} and {} vertices, the body has {n}",
                start.len(),
                end.len()
            )));
        }
        if let Some(i) = start
            .iter()
            .chain(end)
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(body_error(format!(
                "keyframe vertex {} is not finite",
                i % n
            )));
        }
        if t1 <= t0 {
            return Err(body_error(format!("keyframe times {t0} >= {t1}")));
        }
        self.start.copy_from_slice(start);
        self.end.copy_from_slice(end);
        self.dirty = true;
        self.still = start == end;
        self.times = (t0, t1);
        let inv = 1.0 / (t1 - t0);
        for ((v, a), b) in self.velocity.iter_mut().zip(start).zip(end) {
            *v = (b - a) * inv;
        }
        Ok(())
    }

    /// Current (interpolated) vertices.
    pub fn vertices(&self) -> &[Vec3] {
        &self.current
    }

    /// Signed distance of each point to the body (bounded by the query reach: points further
    /// than `reach` outside report `reach`), using and refreshing the per-vertex tracks.
    pub fn measure(&mut self, points: &[Vec3], reach: f64) -> Vec<f64> {
        self.ensure_tracks(points.len());
        let surface = &self.surface;
        points
            .par_iter()
            .zip(self.tracks.par_iter())
            .map(|(&p, track)| {
                if track.side > 0 && track.clearance - (p - track.at).norm() > reach {
                    return reach;
                }
                match surface.query(p, reach) {
                    Some(s) => s.distance,
                    None if track.side < 0 => surface
                        .query(p, f64::INFINITY)
                        .map_or(reach, |s| s.distance),
                    None => reach,
                }
            })
            .collect()
    }

    /// The points inside the body (negative `distances`, from [`Self::measure`]) split by
    /// whether the body overlaps itself there.
    pub fn split_penetration(&self, points: &[Vec3], distances: &[f64]) -> Penetration {
        split_penetration(&self.surface, points, distances)
    }

    fn ensure_tracks(&mut self, n: usize) {
        if self.tracks.len() != n {
            self.tracks = vec![
                Track {
                    side: 0,
                    clearance: 0.0,
                    at: Vec3::zeros(),
                };
                n
            ];
        }
    }
}

impl Obstacle for AnimatedMesh {
    fn friction(&self) -> f64 {
        self.friction
    }

    fn advance(&mut self, time: f64) {
        let (t0, t1) = self.times;
        let mut a = ((time - t0) / (t1 - t0)).clamp(0.0, 1.0);
        if !self.interpolate_substeps || self.still {
            // Refit once per keyframe: the surface jumps to the end keyframe at the first
            // substep of the frame and stays there (for a still pose, where it already is).
            if !self.dirty {
                return;
            }
            a = 1.0;
        }
        let interpolating = self.interpolate_substeps && !self.still;
        let keyframes_changed = self.dirty;
        self.dirty = false;
        let mut moved: f64 = 0.0;
        for ((c, s), e) in self.current.iter_mut().zip(&self.start).zip(&self.end) {
            let next = s + (e - s) * a;
            moved = moved.max((next - *c).norm());
            *c = next;
        }
        self.moved = moved;
        if !interpolating {
            self.surface.update(&self.current, &self.velocity);
        } else {
            // Once per frame, the BVH around the frame's whole motion; each substep's pose
            // lies inside it.
            if keyframes_changed {
                self.surface.sweep(&self.start, &self.end, &self.velocity);
            }
            self.surface.place(&self.current);
        }
        // The body may have moved toward every vertex by up to `moved`.
        for t in &mut self.tracks {
            t.clearance = (t.clearance - moved).max(0.0);
        }
    }

    fn surface_point(&self, p: Vec3, max_distance: f64) -> Option<SurfacePoint> {
        self.surface.query(p, max_distance).or_else(|| {
            self.surface
                .query(p, f64::INFINITY)
                .filter(|s| s.distance < 0.0)
        })
    }

    fn detect(&mut self, input: &DetectionInput, out: &mut Vec<Contact>) {
        let tolerance = input.params.contact_tolerance;
        let reach = (QUERY_REACH * tolerance).max(0.03);
        self.ensure_tracks(input.predicted.len());
        let surface = &self.surface;
        let friction = self.friction;
        let found: Vec<Vec<Contact>> = input
            .predicted
            .par_chunks(512)
            .zip(self.tracks.par_chunks_mut(512))
            .enumerate()
            .map(|(chunk, (points, tracks))| {
                let mut local = Vec::new();
                for (k, (&p, track)) in points.iter().zip(tracks.iter_mut()).enumerate() {
                    let i = chunk * 512 + k;
                    let travelled = (p - track.at).norm();
                    if track.side > 0 && track.clearance - travelled > tolerance {
                        continue;
                    }
                    let hit = match surface.query(p, reach) {
                        Some(s) => Some(s),
                        None if track.side <= 0 => surface.query(p, f64::INFINITY),
                        None => None,
                    };
                    match hit {
                        Some(s) => {
                            track.side = if s.distance < 0.0 { -1 } else { 1 };
                            track.clearance = s.distance.abs();
                            track.at = p;
                            local.extend(input.contact(i, &s, friction));
                        }
                        None => {
                            track.clearance = reach;
                            track.at = p;
                        }
                    }
                }
                local
            })
            .collect();
        out.extend(found.into_iter().flatten());
    }
}

fn body_error(problem: String) -> Error {
    Error::Obstacle {
        obstacle: "body".into(),
        problem,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obstacles::Obstacles;
    use crate::obstacles::trimesh::tests::cube;
    use crate::{ClothMesh, ClothSetup, ClothState, Material, Solver, SolverParams};

    /// A 30 cm sheet pinned at its edges, with a 4 cm block 1 cm below its middle that jumps
    /// 6 cm up in one frame (1.8 m/s, like a swinging forearm) and then stays: the height of
    /// the sheet's middle after 10 frames. The block's top ends at 5 cm, its bottom at 1 cm.
    fn sheet_middle_after_a_fast_block(interpolate_substeps: bool) -> f64 {
        let n = 21;
        let mesh = ClothMesh::grid(n, 0.3, 0.0).unwrap();
        let mut setup = ClothSetup::new(mesh.clone(), Material::default());
        setup.pins = (0..n * n)
            .filter(|v| [v / n, v % n].iter().any(|&i| i == 0 || i == n - 1))
            .map(|v| v as u32)
            .collect();
        let params = SolverParams {
            substeps: 4,
            max_iterations: 16,
            ..SolverParams::default()
        };
        let frame = 1.0 / 30.0;
        let mut solver = Solver::new(setup, params, frame).unwrap();
        let (unit, faces) = cube();
        let block = |lift: f64| -> Vec<Vec3> {
            unit.iter()
                .map(|p| 0.04 * p + Vec3::new(-0.02, lift - 0.05, -0.02))
                .collect()
        };
        let mut body = AnimatedMesh::new(&block(0.0), &faces, 0.3).unwrap();
        body.interpolate_substeps = interpolate_substeps;
        let mut obstacles = Obstacles::body(body);
        let mut state = ClothState::at_rest(mesh.rest().to_vec());
        for k in 0..10 {
            let (from, to) = if k == 0 { (0.0, 0.06) } else { (0.06, 0.06) };
            let t0 = k as f64 * frame;
            let body = obstacles.body.as_mut().unwrap();
            body.set_keyframes(&block(from), &block(to), t0, t0 + frame)
                .unwrap();
            solver
                .advance_frame(&mut state, &mut obstacles, t0, k)
                .unwrap();
        }
        state.positions[(n / 2) * n + n / 2].y
    }

    #[test]
    fn a_fast_block_lifts_the_sheet_instead_of_jumping_through_it() {
        // Interpolated per substep (1.5 cm each), the block meets the sheet and carries it up
        // to its top; jumping the whole frame at once, it lands above the sheet's middle and
        // the sheet stays under it.
        let interpolated = sheet_middle_after_a_fast_block(true);
        assert!(interpolated > 0.05, "sheet middle at {interpolated} m");
        let jumped = sheet_middle_after_a_fast_block(false);
        eprintln!("sheet middle: interpolated {interpolated} m, jumped {jumped} m");
        assert!(jumped < 0.01, "sheet middle at {jumped} m");
    }
}
