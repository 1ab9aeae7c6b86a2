//! From pattern to mesh: each panel's outline is sampled at the target edge length (stitched
//! edges share one vertex count), triangulated with spade's constrained Delaunay refinement
//! (30-degree angle limit, area bound of an equilateral triangle of the target edge, outline
//! edges kept), placed in 3D, oriented to face away from the body, and the stitched vertex
//! pairs listed. The panels stay separate until [`SewnMesh::merged`], so that the engine can
//! pull the seams closed with springs first.

use std::collections::{BTreeMap, HashSet};

use spade::handles::FixedVertexHandle;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

use super::{Pattern, uv};
use crate::check::{outward_score, remove_unreferenced};
use crate::error::{Error, Result};
use crate::mesh::Garment;

/// Default target edge length, m (GarmentCode meshes at about 1 cm; 1.5 cm keeps templates
/// at 3k-8k vertices).
pub const DEFAULT_EDGE_LENGTH_M: f64 = 0.015;

/// A meshed pattern, panels not yet joined.
#[derive(Debug, Clone, PartialEq)]
pub struct SewnMesh {
    /// All panels' vertices (placed, metres, in the pattern's frame), triangles, UVs (one UV
    /// per vertex: uv_triangles equal triangles), panel labels and edge-label vertex sets.
    pub garment: Garment,
    /// Vertex pairs the stitches join (each pair distinct).
    pub stitch_pairs: Vec<[u32; 2]>,
}

/// The most vertices a pattern may mesh into (the library's templates have 3,000 to 8,000 at
/// the default edge length).
pub const MAX_PATTERN_VERTICES: usize = 100_000;

impl Pattern {
    /// The largest extent of any panel's corners, m (for errors).
    fn extent_m(&self) -> String {
        let extent = self
            .panels
            .iter()
            .flat_map(|p| {
                let (lo, hi) =
                    p.vertices
                        .iter()
                        .fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), v| {
                            (
                                [lo[0].min(v[0]), lo[1].min(v[1])],
                                [hi[0].max(v[0]), hi[1].max(v[1])],
                            )
                        });
                [hi[0] - lo[0], hi[1] - lo[1]]
            })
            .fold(0.0f64, f64::max);
        format!("{:.3}", extent * self.metres_per_unit)
    }

    /// Meshes every panel at `edge_length_m` and lists the stitched vertex pairs.
    pub fn mesh(&self, edge_length_m: f64) -> Result<SewnMesh> {
        if !(edge_length_m.is_finite() && edge_length_m > 0.0) {
            return Err(Error::Pattern(format!(
                "edge length {edge_length_m} m is not positive"
            )));
        }
        let target = edge_length_m / self.metres_per_unit;
        self.check_size(edge_length_m, target)?;
        let counts = self.edge_counts(target);
        let mut garment = Garment {
            name: self.name.clone(),
            panels: self.panels.iter().map(|p| p.name.clone()).collect(),
            ..Garment::default()
        };
        let mut islands = Vec::new();
        // Global vertex indices of every edge's samples, start to end.
        let mut edge_vertices: Vec<Vec<Vec<u32>>> = Vec::new();
        let mut labels: BTreeMap<String, Vec<u32>> = BTreeMap::new();
        for (pi, panel) in self.panels.iter().enumerate() {
            let mut outline = Vec::new();
            let mut edge_local = Vec::new();
            for (e, edge) in panel.edges.iter().enumerate() {
                let (s, t) = panel.edge_ends(e);
                let points = edge.curve.resample(s, t, counts[pi][e]);
                let first = outline.len();
                outline.extend_from_slice(&points[..points.len() - 1]);
                edge_local.push((first..first + points.len()).collect::<Vec<usize>>());
            }
            let total = outline.len();
            for local in &mut edge_local {
                if let Some(last) = local.last_mut() {
                    *last %= total;
                }
            }
            let (points, triangles) = triangulate(&panel.name, &outline, target)?;
            let offset = garment.positions.len() as u32;
            garment.positions.extend(
                points
                    .iter()
                    .map(|&p| panel.place(p).map(|c| c * self.metres_per_unit)),
            );
            garment
                .triangles
                .extend(triangles.iter().map(|t| t.map(|v| v + offset)));
            garment
                .triangle_panels
                .extend(std::iter::repeat_n(pi as u32, triangles.len()));
            islands.push(
                points
                    .iter()
                    .map(|p| p.map(|c| c * self.metres_per_unit))
                    .collect::<Vec<_>>(),
            );
            let globals: Vec<Vec<u32>> = edge_local
                .iter()
                .map(|l| l.iter().map(|&v| v as u32 + offset).collect())
                .collect();
            for (edge, vs) in panel.edges.iter().zip(&globals) {
                if let Some(label) = &edge.label {
                    labels.entry(label.clone()).or_default().extend(vs);
                }
            }
            edge_vertices.push(globals);
        }
        orient_panels(&mut garment);
        garment.uvs = uv::pack(&islands).into_iter().flatten().collect();
        garment.uv_triangles = garment.triangles.clone();
        for vs in labels.values_mut() {
            vs.sort();
            vs.dedup();
        }
        garment.vertex_labels = labels;
        let stitch_pairs = self.stitch_pairs(&edge_vertices);
        garment.validate()?;
        Ok(SewnMesh {
            garment,
            stitch_pairs,
        })
    }

    /// Refuses a meshing whose size, estimated before anything is allocated, passes
    /// MAX_PATTERN_VERTICES: a pattern in the wrong units, a wild curvature or a tiny edge
    /// length would otherwise mesh for hours. `target` is the edge length in pattern units.
    fn check_size(&self, edge_length_m: f64, target: f64) -> Result<()> {
        let max_area = 3f64.sqrt() / 4.0 * target * target;
        let estimate: f64 = self
            .panels
            .iter()
            .map(|p| {
                let outline: f64 = (0..p.edges.len()).map(|e| p.edge_length(e) / target).sum();
                outline + signed_area(&p.vertices).abs() / max_area
            })
            .sum();
        if estimate.is_nan() || estimate > MAX_PATTERN_VERTICES as f64 {
            return Err(Error::Pattern(format!(
                "meshing at {edge_length_m} m would make about {estimate:.3e} vertices, more \
                 than {MAX_PATTERN_VERTICES}: the pattern is {} m across (its units or \
                 curvatures are wrong) or the edge length is too small",
                self.extent_m()
            )));
        }
        Ok(())
    }

    /// Vertex count per edge of every panel; stitched edges take the larger of the two.
    fn edge_counts(&self, target: f64) -> Vec<Vec<usize>> {
        let mut counts: Vec<Vec<usize>> = self
            .panels
            .iter()
            .map(|p| {
                (0..p.edges.len())
                    .map(|e| ((p.edge_length(e) / target).ceil() as usize + 1).max(2))
                    .collect()
            })
            .collect();
        for s in &self.stitches {
            let n = counts[s.a.panel][s.a.edge].max(counts[s.b.panel][s.b.edge]);
            counts[s.a.panel][s.a.edge] = n;
            counts[s.b.panel][s.b.edge] = n;
        }
        counts
    }

    /// The stitch pairs from every edge's global vertex indices (start to end), matched along
    /// each stitch (reversed unless the stitch is right side to wrong side).
    fn stitch_pairs(&self, edge_vertices: &[Vec<Vec<u32>>]) -> Vec<[u32; 2]> {
        let mut stitch_pairs = Vec::new();
        for s in &self.stitches {
            let a = &edge_vertices[s.a.panel][s.a.edge];
            let b = &edge_vertices[s.b.panel][s.b.edge];
            let n = a.len();
            for k in 0..n {
                let other = if s.right_wrong { b[k] } else { b[n - 1 - k] };
                if a[k] != other {
                    stitch_pairs.push([a[k], other]);
                }
            }
        }
        stitch_pairs
    }
}

/// A triangulated panel: 2D points and counter-clockwise triangles.
type PanelTriangulation = (Vec<[f64; 2]>, Vec<[u32; 3]>);

/// Triangulates a closed outline (no repeated end point): the outline points come first, in
/// order, then the interior points. Triangles are counter-clockwise in 2D.
fn triangulate(panel: &str, outline: &[[f64; 2]], target: f64) -> Result<PanelTriangulation> {
    let bad = |m: &str| Error::Pattern(format!("panel '{panel}': {m}"));
    if outline.len() < 3 {
        return Err(bad("the outline has fewer than 3 points"));
    }
    if signed_area(outline).abs() < 1e-12 * target * target {
        return Err(bad("the outline encloses no area"));
    }
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    for (i, p) in outline.iter().enumerate() {
        let handle = cdt
            .insert(Point2::new(p[0], p[1]))
            .map_err(|e| bad(&format!("outline point {i} {p:?}: {e:?}")))?;
        if handle.index() != i {
            return Err(bad(&format!(
                "outline point {i} {p:?} coincides with point {}",
                handle.index()
            )));
        }
    }
    let n = outline.len();
    for (i, point) in outline.iter().enumerate() {
        let (a, b) = (
            FixedVertexHandle::from_index(i),
            FixedVertexHandle::from_index((i + 1) % n),
        );
        if !cdt.can_add_constraint(a, b) {
            return Err(bad(&format!(
                "the outline crosses itself near point {i} {point:?}"
            )));
        }
        cdt.add_constraint(a, b);
    }
    if cdt.num_constraints() != n {
        return Err(bad("an outline point lies on another outline edge"));
    }
    let max_area = 3f64.sqrt() / 4.0 * target * target;
    let result = cdt.refine(
        RefinementParameters::<f64>::new()
            .exclude_outer_faces(true)
            .keep_constraint_edges()
            .with_angle_limit(AngleLimit::from_deg(28.0))
            .with_max_allowed_area(max_area)
            .with_max_additional_vertices(
                20 * n + (signed_area(outline).abs() / max_area) as usize * 4,
            ),
    );
    let excluded: HashSet<_> = result.excluded_faces.iter().copied().collect();
    let mut map = vec![u32::MAX; cdt.num_vertices()];
    for (i, m) in map.iter_mut().enumerate().take(n) {
        *m = i as u32;
    }
    let mut points: Vec<[f64; 2]> = outline.to_vec();
    let mut triangles = Vec::new();
    for face in cdt.inner_faces() {
        if excluded.contains(&face.fix()) {
            continue;
        }
        let tri = face.vertices().map(|v| {
            let i = v.fix().index();
            if map[i] == u32::MAX {
                map[i] = points.len() as u32;
                let p = v.position();
                points.push([p.x, p.y]);
            }
            map[i]
        });
        triangles.push(tri);
    }
    if triangles.is_empty() {
        return Err(bad("triangulation produced no triangles"));
    }
    Ok((points, triangles))
}

fn signed_area(outline: &[[f64; 2]]) -> f64 {
    let n = outline.len();
    (0..n)
        .map(|i| {
            let (a, b) = (outline[i], outline[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        / 2.0
}

/// Flips panels whose normals face the garment's vertical axis (through the mean of all
/// vertices) so that every panel faces outward.
fn orient_panels(g: &mut Garment) {
    let count = g.positions.len() as f64;
    let centre = [
        g.positions.iter().map(|p| p[0]).sum::<f64>() / count,
        g.positions.iter().map(|p| p[2]).sum::<f64>() / count,
    ];
    for panel in 0..g.panels.len() {
        let members: Vec<usize> = (0..g.triangles.len())
            .filter(|&t| g.triangle_panels[t] as usize == panel)
            .collect();
        if outward_score(&g.positions, &g.triangles, &members, Some(centre)) < 0.0 {
            for t in members {
                g.triangles[t].swap(1, 2);
            }
        }
    }
}

impl SewnMesh {
    /// The largest distance between stitched vertices at `positions`, m.
    pub fn max_seam_gap(&self, positions: &[[f64; 3]]) -> f64 {
        self.stitch_pairs
            .iter()
            .map(|&[a, b]| {
                let (p, q) = (positions[a as usize], positions[b as usize]);
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
            })
            .fold(0.0, f64::max)
    }

    /// Each vertex's representative once stitched vertices are joined (see [`joined_roots`]).
    pub fn stitched_roots(&self) -> Vec<u32> {
        joined_roots(self.garment.positions.len(), &self.stitch_pairs)
    }

    /// Joins the stitched vertices into one (at the mean of their `positions`), drops the
    /// triangles that collapse (dart tips) and renumbers: the template. Seam vertices keep one
    /// UV per panel.
    pub fn merged(&self, positions: &[[f64; 3]]) -> Result<Garment> {
        let n = self.garment.positions.len();
        if positions.len() != n {
            return Err(Error::BadParameter {
                parameter: "positions",
                problem: format!("{} positions for {n} vertices", positions.len()),
            });
        }
        let root = self.stitched_roots();
        let mut sum = vec![[0.0; 3]; n];
        let mut count = vec![0usize; n];
        for (v, p) in positions.iter().enumerate() {
            let r = root[v] as usize;
            for k in 0..3 {
                sum[r][k] += p[k];
            }
            count[r] += 1;
        }
        let mut g = self.garment.clone();
        for (p, &r) in g.positions.iter_mut().zip(&root) {
            *p = sum[r as usize].map(|c| c / count[r as usize] as f64);
        }
        for t in &mut g.triangles {
            for v in t.iter_mut() {
                *v = root[*v as usize];
            }
        }
        for vs in g.vertex_labels.values_mut() {
            for v in vs.iter_mut() {
                *v = root[*v as usize];
            }
        }
        let mut seen = HashSet::new();
        let keep: Vec<usize> = (0..g.triangles.len())
            .filter(|&t| {
                let [a, b, c] = g.triangles[t];
                let mut key = [a, b, c];
                key.sort();
                a != b && b != c && a != c && seen.insert(key)
            })
            .collect();
        g.triangles = keep.iter().map(|&t| g.triangles[t]).collect();
        g.uv_triangles = keep.iter().map(|&t| g.uv_triangles[t]).collect();
        g.triangle_panels = keep.iter().map(|&t| g.triangle_panels[t]).collect();
        remove_unreferenced(&mut g);
        g.validate()?;
        Ok(g)
    }
}

/// Each of `num_vertices` vertices' representative once every pair in `pairs` is joined: the
/// lowest index of the vertices the pairs connect it to (itself when in no pair).
pub fn joined_roots(num_vertices: usize, pairs: &[[u32; 2]]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..num_vertices as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for &[a, b] in pairs {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    (0..num_vertices as u32)
        .map(|v| root(&mut parent, v))
        .collect()
}
