//! The statistics a recording keeps of each frame (its `/sim/stats` channel), as the scene
//! measures them.

use serde::{Deserialize, Serialize};

use crate::solver::FrameReport;

/// Statistics of one output frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameStats {
    /// Frame index (0 = the template on the canonical body).
    pub frame: usize,
    /// Solver report of the frame's steps.
    #[serde(flatten)]
    pub solver: FrameReport,
    /// Deepest cloth vertex inside the body at the end of the frame, away from where the
    /// body overlaps itself, m (0 if none).
    pub max_penetration_m: f64,
    /// Cloth vertices inside the body at the end of the frame, away from body overlaps.
    pub vertices_inside: usize,
    /// Deepest cloth vertex inside the body where the body overlaps itself, m (0 if none;
    /// `sim::obstacles::split_penetration`).
    #[serde(default)]
    pub max_penetration_overlap_m: f64,
    /// Cloth vertices inside the body where the body overlaps itself.
    #[serde(default)]
    pub vertices_inside_overlap: usize,
    /// Largest edge length / rest length.
    pub max_edge_stretch: f64,
    /// Mean edge length / rest length.
    pub mean_edge_stretch: f64,
    /// Pairs of garment triangles (sharing no vertex) that cross each other.
    #[serde(default)]
    pub self_intersections: usize,
    /// Kinetic energy, J.
    pub kinetic_energy_j: f64,
    /// Wall time of the frame, s. Not recorded: a recording holds only what the inputs
    /// determine, so simulating its configuration again gives the same bytes.
    #[serde(default, skip_serializing)]
    pub wall_s: f64,
}
