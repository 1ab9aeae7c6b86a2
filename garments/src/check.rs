//! Mesh validation with documented repairs, for files users bring.
//!
//! [`check`] lists every problem it finds; [`repair`] applies the repairs below and refuses
//! what cannot be repaired:
//!
//! | problem | repair |
//! |---|---|
//! | more than 50,000 vertices, or a vertex in more than 64 triangles (a fan) | none: refused |
//! | non-finite positions or UVs, indices out of range | none: refused |
//! | missing UVs | none: refused (templates need UVs for the surrogate) |
//! | UVs outside [0, 1] | all UVs moved and scaled uniformly into [0, 1] |
//! | degenerate triangles (a repeated vertex, or area < 1e-12 m^2) | removed |
//! | duplicate triangles (same three vertices) | the copies removed |
//! | unreferenced vertices | removed, the rest renumbered |
//! | non-manifold edges (three or more triangles) | none: refused |
//! | inconsistent orientation between neighbours | flipped to agree with the first triangle of each connected piece; refused when no consistent orientation exists |
//! | orientation pointing into the body (normals towards the piece's vertical axis) | the piece flipped |
//! | implausible scale (largest extent over 3 m or under 5 cm, e.g. a file in cm) | refused (`garments check FILE --scale 0.01` tells whether a scale fixes it) |

use std::collections::{BTreeMap, HashMap, HashSet};

use crate::error::{Error, Result};
use crate::mesh::Garment;

/// Largest plausible garment extent, m.
pub const MAX_EXTENT_M: f64 = 3.0;
/// Smallest plausible garment extent, m.
pub const MIN_EXTENT_M: f64 = 0.05;
/// The most vertices a template may have: six times the largest library design; past it the
/// engine's self-contact and intersection counts take minutes a frame.
pub const MAX_TEMPLATE_VERTICES: usize = 50_000;
/// The most triangles one vertex may be in (cloth meshes have 4 to 12): a vertex in more is
/// the apex of a fan from a triangulated polygon, whose slivers no solver handles.
pub const MAX_VERTEX_TRIANGLES: usize = 64;

/// One kind of problem found, with how many and an example.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    /// What is wrong (stable wording, e.g. "non-manifold edges").
    pub problem: &'static str,
    /// How many elements have it.
    pub count: usize,
    /// The first one, in words.
    pub example: String,
    /// What [`repair`] does about it; `None` when the mesh is refused.
    pub repair: Option<&'static str>,
}

/// What [`check`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckReport {
    /// Vertex count.
    pub vertices: usize,
    /// Triangle count.
    pub triangles: usize,
    /// Panel count.
    pub panels: usize,
    /// Bounding-box size, m.
    pub extent_m: [f64; 3],
    /// Problems, in the order of the table in the module docs.
    pub findings: Vec<Finding>,
}

impl CheckReport {
    /// True when nothing needs refusing (repairs may still apply).
    pub fn repairable(&self) -> bool {
        self.findings.iter().all(|f| f.repair.is_some())
    }

    /// One line per finding.
    pub fn lines(&self) -> Vec<String> {
        self.findings
            .iter()
            .map(|f| {
                format!(
                    "{}: {} (e.g. {}) -> {}",
                    f.problem,
                    f.count,
                    f.example,
                    f.repair.unwrap_or("cannot be repaired")
                )
            })
            .collect()
    }
}

/// Lists every problem of the mesh (see the module docs).
pub fn check(g: &Garment) -> CheckReport {
    check_numbered(g, None)
}

/// [`check`], naming vertices by `numbers` (the 1-based `v` number of each vertex in the OBJ
/// file it was read from, see [`crate::read_obj_numbered`]) rather than by their index here.
pub fn check_numbered(g: &Garment, numbers: Option<&[u32]>) -> CheckReport {
    let vertex = |i: usize| match numbers.and_then(|n| n.get(i)) {
        Some(k) => format!("OBJ vertex {k}"),
        None => format!("vertex {i}"),
    };
    let (lo, hi) = g.bounds();
    let extent = if g.positions.is_empty() {
        [0.0; 3]
    } else {
        [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]]
    };
    let mut findings = Vec::new();
    let n = g.positions.len();
    if n > MAX_TEMPLATE_VERTICES {
        add(
            &mut findings,
            "too many vertices",
            vec![format!("{n} vertices, at most {MAX_TEMPLATE_VERTICES}")],
            None,
        );
    }
    let mut triangles_of = vec![0usize; n];
    for v in g.triangles.iter().flatten().filter(|&&v| (v as usize) < n) {
        triangles_of[*v as usize] += 1;
    }
    add(
        &mut findings,
        "vertices in too many triangles",
        (0..n)
            .filter(|&i| triangles_of[i] > MAX_VERTEX_TRIANGLES)
            .map(|i| {
                format!(
                    "{} in {} triangles, at most {MAX_VERTEX_TRIANGLES} (a fan of a large polygon)",
                    vertex(i),
                    triangles_of[i]
                )
            })
            .collect(),
        None,
    );
    add(
        &mut findings,
        "non-finite positions",
        (0..n)
            .filter(|&i| !g.positions[i].iter().all(|c| c.is_finite()))
            .map(vertex)
            .collect(),
        None,
    );
    add(
        &mut findings,
        "indices out of range",
        (0..g.triangles.len())
            .filter(|&t| g.triangles[t].iter().any(|&v| v as usize >= n))
            .map(|t| format!("triangle {t}"))
            .collect(),
        None,
    );
    let uv_ok = g.uv_triangles.len() == g.triangles.len()
        && g.uv_triangles
            .iter()
            .all(|t| t.iter().all(|&i| (i as usize) < g.uvs.len()));
    if !uv_ok {
        add(
            &mut findings,
            "missing UVs",
            vec![format!(
                "{} UV triangles for {} triangles",
                g.uv_triangles.len(),
                g.triangles.len()
            )],
            None,
        );
    } else {
        add(
            &mut findings,
            "non-finite UVs",
            (0..g.uvs.len())
                .filter(|&i| !g.uvs[i].iter().all(|c| c.is_finite()))
                .map(|i| format!("UV {i}"))
                .collect(),
            None,
        );
        add(
            &mut findings,
            "UVs outside [0, 1]",
            (0..g.uvs.len())
                .filter(|&i| {
                    g.uvs[i]
                        .iter()
                        .any(|c| c.is_finite() && !(-1e-9..=1.0 + 1e-9).contains(c))
                })
                .map(|i| format!("UV {i} {:?}", g.uvs[i]))
                .collect(),
            Some("moved and scaled uniformly into [0, 1]"),
        );
    }
    if findings.iter().any(|f| f.repair.is_none()) {
        // Topology checks need valid indices and positions.
        return CheckReport {
            vertices: n,
            triangles: g.triangles.len(),
            panels: g.panels.len(),
            extent_m: extent,
            findings,
        };
    }
    let degenerate = degenerate_triangles(g);
    add(
        &mut findings,
        "degenerate triangles",
        degenerate.iter().map(|t| format!("triangle {t}")).collect(),
        Some("removed"),
    );
    let duplicates = duplicate_triangles(g, &degenerate);
    add(
        &mut findings,
        "duplicate triangles",
        duplicates.iter().map(|t| format!("triangle {t}")).collect(),
        Some("removed"),
    );
    let mut used = vec![false; n];
    for t in &g.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    add(
        &mut findings,
        "unreferenced vertices",
        (0..n).filter(|&v| !used[v]).map(vertex).collect(),
        Some("removed"),
    );
    let kept: Vec<usize> = (0..g.triangles.len())
        .filter(|t| !degenerate.contains(t) && !duplicates.contains(t))
        .collect();
    let edges = edge_triangles(&g.triangles, &kept);
    add(
        &mut findings,
        "non-manifold edges",
        edges
            .iter()
            .filter(|(_, ts)| ts.len() > 2)
            .map(|(e, ts)| format!("edge {e:?} in {} triangles", ts.len()))
            .collect(),
        None,
    );
    if findings.iter().all(|f| f.repair.is_some()) {
        match orient(&g.triangles, &kept, &edges) {
            Some(flips) => {
                add(
                    &mut findings,
                    "inconsistent orientation",
                    flips.iter().map(|t| format!("triangle {t}")).collect(),
                    Some("flipped to agree with their neighbours"),
                );
                let mut oriented = g.triangles.clone();
                for &t in &flips {
                    oriented[t].swap(1, 2);
                }
                let inward = inward_pieces(&g.positions, &oriented, &kept, &edges);
                add(
                    &mut findings,
                    "orientation pointing into the body",
                    inward
                        .iter()
                        .map(|piece| format!("a piece of {} triangles", piece.len()))
                        .collect(),
                    Some("the piece flipped"),
                );
            }
            None => add(
                &mut findings,
                "no consistent orientation",
                vec!["a non-orientable piece (Moebius-like)".into()],
                None,
            ),
        }
    }
    // The scale of what the triangles use (a stray vertex is reported above).
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for (p, _) in g.positions.iter().zip(&used).filter(|(_, u)| **u) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let largest = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    if !(MIN_EXTENT_M..=MAX_EXTENT_M).contains(&largest) {
        add(
            &mut findings,
            "implausible scale",
            vec![format!(
                "largest extent {largest:.3} (expected metres, {MIN_EXTENT_M}-{MAX_EXTENT_M}; \
                 a file in cm must be rescaled to metres: `garments check FILE --scale 0.01` \
                 tells whether that is enough)"
            )],
            None,
        );
    }
    CheckReport {
        vertices: n,
        triangles: g.triangles.len(),
        panels: g.panels.len(),
        extent_m: extent,
        findings,
    }
}

/// Scales the positions by `scale`, then applies the documented repairs; refuses what cannot
/// be repaired with an error listing every such problem. Returns the repaired garment and one
/// line per repair made.
pub fn repair(g: &Garment, scale: f64) -> Result<(Garment, Vec<String>)> {
    repair_numbered(g, scale, None)
}

/// [`repair`], naming vertices in a refusal by their OBJ `v` numbers (see [`check_numbered`]).
pub fn repair_numbered(
    g: &Garment,
    scale: f64,
    numbers: Option<&[u32]>,
) -> Result<(Garment, Vec<String>)> {
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::Invalid(format!("scale {scale} is not positive")));
    }
    let mut g = g.clone();
    for p in &mut g.positions {
        for c in p.iter_mut() {
            *c *= scale;
        }
    }
    let report = check_numbered(&g, numbers);
    if !report.repairable() {
        let refused: Vec<String> = report
            .findings
            .iter()
            .filter(|f| f.repair.is_none())
            .map(|f| format!("{} ({}, e.g. {})", f.problem, f.count, f.example))
            .collect();
        return Err(Error::Invalid(format!(
            "'{}': {}",
            g.name,
            refused.join("; ")
        )));
    }
    let done = report.lines();
    if report
        .findings
        .iter()
        .any(|f| f.problem == "UVs outside [0, 1]")
    {
        normalize_uvs(&mut g.uvs);
    }
    let degenerate = degenerate_triangles(&g);
    let duplicates = duplicate_triangles(&g, &degenerate);
    let kept: Vec<usize> = (0..g.triangles.len())
        .filter(|t| !degenerate.contains(t) && !duplicates.contains(t))
        .collect();
    let edges = edge_triangles(&g.triangles, &kept);
    let flips = orient(&g.triangles, &kept, &edges).unwrap_or_default();
    for &t in &flips {
        g.triangles[t].swap(1, 2);
        g.uv_triangles[t].swap(1, 2);
    }
    for piece in inward_pieces(&g.positions, &g.triangles, &kept, &edges) {
        for t in piece {
            g.triangles[t].swap(1, 2);
            g.uv_triangles[t].swap(1, 2);
        }
    }
    keep_triangles(&mut g, &kept);
    remove_unreferenced(&mut g);
    g.validate()?;
    Ok((g, done))
}

fn add(
    findings: &mut Vec<Finding>,
    problem: &'static str,
    items: Vec<String>,
    repair: Option<&'static str>,
) {
    if let Some(first) = items.first() {
        findings.push(Finding {
            problem,
            count: items.len(),
            example: first.clone(),
            repair,
        });
    }
}

/// (b - a) x (c - a): the triangle's normal scaled by twice its area.
pub(crate) fn doubled_normal(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ]
}

fn area(g: &Garment, t: [u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| g.positions[v as usize]);
    let n = doubled_normal(a, b, c);
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

fn degenerate_triangles(g: &Garment) -> HashSet<usize> {
    (0..g.triangles.len())
        .filter(|&t| {
            let [a, b, c] = g.triangles[t];
            a == b || b == c || a == c || area(g, g.triangles[t]) < 1e-12
        })
        .collect()
}

fn duplicate_triangles(g: &Garment, skip: &HashSet<usize>) -> HashSet<usize> {
    let mut seen = HashSet::new();
    (0..g.triangles.len())
        .filter(|t| !skip.contains(t))
        .filter(|&t| {
            let mut key = g.triangles[t];
            key.sort();
            !seen.insert(key)
        })
        .collect()
}

/// Undirected edge -> the triangles (of `kept`) using it.
fn edge_triangles(triangles: &[[u32; 3]], kept: &[usize]) -> BTreeMap<[u32; 2], Vec<usize>> {
    let mut edges: BTreeMap<[u32; 2], Vec<usize>> = BTreeMap::new();
    for &t in kept {
        let tri = triangles[t];
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edges.entry([a.min(b), a.max(b)]).or_default().push(t);
        }
    }
    edges
}

fn directed(tri: [u32; 3], a: u32, b: u32) -> bool {
    (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b)
}

/// Triangles to flip so that every manifold edge is traversed in opposite directions by its
/// two triangles; `None` when impossible.
fn orient(
    triangles: &[[u32; 3]],
    kept: &[usize],
    edges: &BTreeMap<[u32; 2], Vec<usize>>,
) -> Option<Vec<usize>> {
    let mut flipped: HashMap<usize, bool> = HashMap::new();
    let neighbours = |t: usize| {
        let tri = triangles[t];
        (0..3).filter_map(move |k| {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let ts = &edges[&[a.min(b), a.max(b)]];
            (ts.len() == 2).then(|| (if ts[0] == t { ts[1] } else { ts[0] }, a, b))
        })
    };
    for &seed in kept {
        if flipped.contains_key(&seed) {
            continue;
        }
        flipped.insert(seed, false);
        let mut stack = vec![seed];
        while let Some(t) = stack.pop() {
            let t_flip = flipped[&t];
            for (u, a, b) in neighbours(t) {
                // t traverses a -> b (reversed if flipped); u must traverse it the other way.
                let (a, b) = if t_flip { (b, a) } else { (a, b) };
                let u_flip = directed(triangles[u], a, b);
                match flipped.get(&u) {
                    Some(&f) if f != u_flip => return None,
                    Some(_) => {}
                    None => {
                        flipped.insert(u, u_flip);
                        stack.push(u);
                    }
                }
            }
        }
    }
    let mut flips: Vec<usize> = flipped
        .into_iter()
        .filter_map(|(t, f)| f.then_some(t))
        .collect();
    flips.sort();
    Some(flips)
}

/// Connected pieces whose area-weighted normals point towards the piece's vertical axis.
fn inward_pieces(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    kept: &[usize],
    edges: &BTreeMap<[u32; 2], Vec<usize>>,
) -> Vec<Vec<usize>> {
    let mut piece_of: HashMap<usize, usize> = HashMap::new();
    let mut pieces: Vec<Vec<usize>> = Vec::new();
    for &seed in kept {
        if piece_of.contains_key(&seed) {
            continue;
        }
        let id = pieces.len();
        piece_of.insert(seed, id);
        let mut members = vec![seed];
        let mut stack = vec![seed];
        while let Some(t) = stack.pop() {
            let tri = triangles[t];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                for &u in &edges[&[a.min(b), a.max(b)]] {
                    if let std::collections::hash_map::Entry::Vacant(e) = piece_of.entry(u) {
                        e.insert(id);
                        members.push(u);
                        stack.push(u);
                    }
                }
            }
        }
        pieces.push(members);
    }
    pieces
        .into_iter()
        .filter(|piece| outward_score(positions, triangles, piece, None) < 0.0)
        .collect()
}

/// Sum over triangles of (doubled area-weighted normal) . (centroid - a vertical axis through
/// `axis` (x, z), by default the piece's mean position), horizontal components only: positive
/// when the piece faces out.
pub(crate) fn outward_score(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    piece: &[usize],
    axis: Option<[f64; 2]>,
) -> f64 {
    let centre = axis.unwrap_or_else(|| {
        let mut centre = [0.0; 2];
        for &t in piece {
            for &v in &triangles[t] {
                centre[0] += positions[v as usize][0];
                centre[1] += positions[v as usize][2];
            }
        }
        let count = 3.0 * piece.len() as f64;
        centre.map(|c| c / count)
    });
    piece
        .iter()
        .map(|&t| {
            let [a, b, c] = triangles[t].map(|v| positions[v as usize]);
            let [nx, _, nz] = doubled_normal(a, b, c);
            let mx = (a[0] + b[0] + c[0]) / 3.0 - centre[0];
            let mz = (a[2] + b[2] + c[2]) / 3.0 - centre[1];
            nx * mx + nz * mz
        })
        .sum()
}

fn normalize_uvs(uvs: &mut [[f64; 2]]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for uv in uvs.iter() {
        for k in 0..2 {
            lo[k] = lo[k].min(uv[k]);
            hi[k] = hi[k].max(uv[k]);
        }
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-12);
    for uv in uvs.iter_mut() {
        for k in 0..2 {
            uv[k] = ((uv[k] - lo[k]) / span).clamp(0.0, 1.0);
        }
    }
}

fn keep_triangles(g: &mut Garment, kept: &[usize]) {
    g.triangles = kept.iter().map(|&t| g.triangles[t]).collect();
    g.uv_triangles = kept.iter().map(|&t| g.uv_triangles[t]).collect();
    g.triangle_panels = kept.iter().map(|&t| g.triangle_panels[t]).collect();
}

/// Drops vertices and UVs no triangle uses, renumbering the rest in their order (labels
/// follow).
pub(crate) fn remove_unreferenced(g: &mut Garment) {
    let map = compact(g.positions.len(), &mut g.triangles);
    g.positions = keep_indexed(&g.positions, &map);
    let uv_map = compact(g.uvs.len(), &mut g.uv_triangles);
    g.uvs = keep_indexed(&g.uvs, &uv_map);
    for vertices in g.vertex_labels.values_mut() {
        *vertices = vertices
            .iter()
            .filter_map(|&v| map.get(v as usize).copied().filter(|&m| m != u32::MAX))
            .collect();
        vertices.sort();
        vertices.dedup();
    }
    g.vertex_labels.retain(|_, v| !v.is_empty());
}

/// New index of every used element (u32::MAX for unused), in the old order; rewrites
/// `triangles` to the new indices.
fn compact(count: usize, triangles: &mut [[u32; 3]]) -> Vec<u32> {
    let mut used = vec![false; count];
    for t in triangles.iter() {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut next = 0;
    let map: Vec<u32> = used
        .iter()
        .map(|&u| {
            if u {
                next += 1;
                next - 1
            } else {
                u32::MAX
            }
        })
        .collect();
    for t in triangles.iter_mut() {
        for v in t.iter_mut() {
            *v = map[*v as usize];
        }
    }
    map
}

fn keep_indexed<T: Copy>(items: &[T], map: &[u32]) -> Vec<T> {
    items
        .iter()
        .zip(map)
        .filter(|(_, m)| **m != u32::MAX)
        .map(|(x, _)| *x)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tube() -> Garment {
        crate::builtin::tube_for_tests()
    }

    fn problems(g: &Garment) -> Vec<&'static str> {
        check(g).findings.iter().map(|f| f.problem).collect()
    }

    #[test]
    fn a_clean_tube_has_no_findings() {
        assert!(check(&tube()).findings.is_empty(), "{:?}", check(&tube()));
    }

    #[test]
    fn repairs_degenerate_duplicate_unreferenced_flipped_and_inward() {
        let mut g = tube();
        let n = g.triangles.len();
        g.triangles.push(g.triangles[0]);
        g.uv_triangles.push(g.uv_triangles[0]);
        g.triangle_panels.push(0);
        g.triangles.push([0, 0, 1]);
        g.uv_triangles.push([0, 0, 1]);
        g.triangle_panels.push(0);
        g.positions.push([5.0, 5.0, 5.0]);
        g.triangles[3].swap(1, 2);
        assert_eq!(
            problems(&g),
            [
                "degenerate triangles",
                "duplicate triangles",
                "unreferenced vertices",
                "inconsistent orientation"
            ]
        );
        let (fixed, done) = repair(&g, 1.0).unwrap();
        assert_eq!(done.len(), 4);
        assert_eq!(fixed.triangles.len(), n);
        assert!(check(&fixed).findings.is_empty(), "{:?}", check(&fixed));

        let mut inward = tube();
        for t in &mut inward.triangles {
            t.swap(1, 2);
        }
        assert_eq!(problems(&inward), ["orientation pointing into the body"]);
        let (fixed, _) = repair(&inward, 1.0).unwrap();
        assert_eq!(fixed.triangles, tube().triangles);
    }

    #[test]
    fn refuses_what_cannot_be_repaired() {
        let mut cm = tube();
        for p in &mut cm.positions {
            *p = p.map(|c| c * 100.0);
        }
        assert_eq!(problems(&cm), ["implausible scale"]);
        assert!(
            repair(&cm, 1.0)
                .unwrap_err()
                .to_string()
                .contains("--scale")
        );
        assert!(repair(&cm, 0.01).is_ok());

        let mut fin = tube();
        fin.triangles.push([0, 1, 17]);
        fin.uv_triangles.push([0, 1, 17]);
        fin.triangle_panels.push(0);
        fin.triangles.push([0, 1, 18]);
        fin.uv_triangles.push([0, 1, 18]);
        fin.triangle_panels.push(0);
        assert!(problems(&fin).contains(&"non-manifold edges"));
        assert!(repair(&fin, 1.0).is_err());

        let mut nan = tube();
        nan.positions[4][1] = f64::NAN;
        assert_eq!(problems(&nan), ["non-finite positions"]);
        let mut no_uv = tube();
        no_uv.uv_triangles.clear();
        assert_eq!(problems(&no_uv), ["missing UVs"]);
        let mut far_uv = tube();
        far_uv.uvs[0] = [1.5, 0.0];
        assert_eq!(problems(&far_uv), ["UVs outside [0, 1]"]);
        let (fixed, _) = repair(&far_uv, 1.0).unwrap();
        fixed.validate().unwrap();
        let mut bad_index = tube();
        bad_index.triangles[0][0] = 10_000;
        assert_eq!(problems(&bad_index), ["indices out of range"]);
    }
}
