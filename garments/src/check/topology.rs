//! What the triangles must form: no degenerate or duplicate triangles, no unreferenced
//! vertices (all three repaired by removal, [`remove_unreferenced`] renumbering), and no edge
//! in more than two triangles (refused).

use std::collections::{BTreeMap, HashSet};

use super::{Finding, add};
use crate::mesh::Garment;

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

/// What the topology checks leave for the orientation and scale checks.
pub(super) struct Topology {
    /// Whether a triangle uses each vertex.
    pub used: Vec<bool>,
    /// The triangles neither degenerate nor duplicate.
    pub kept: Vec<usize>,
    /// Undirected edge -> the kept triangles using it.
    pub edges: BTreeMap<[u32; 2], Vec<usize>>,
}

/// Appends the topology findings; `vertex` names a vertex in an example.
pub(super) fn topology_findings(
    g: &Garment,
    vertex: &dyn Fn(usize) -> String,
    findings: &mut Vec<Finding>,
) -> Topology {
    let n = g.positions.len();
    let degenerate = degenerate_triangles(g);
    add(
        findings,
        "degenerate triangles",
        degenerate.iter().map(|t| format!("triangle {t}")).collect(),
        Some("removed"),
    );
    let duplicates = duplicate_triangles(g, &degenerate);
    add(
        findings,
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
        findings,
        "unreferenced vertices",
        (0..n).filter(|&v| !used[v]).map(vertex).collect(),
        Some("removed"),
    );
    let kept: Vec<usize> = (0..g.triangles.len())
        .filter(|t| !degenerate.contains(t) && !duplicates.contains(t))
        .collect();
    let edges = edge_triangles(&g.triangles, &kept);
    add(
        findings,
        "non-manifold edges",
        edges
            .iter()
            .filter(|(_, ts)| ts.len() > 2)
            .map(|(e, ts)| format!("edge {e:?} in {} triangles", ts.len()))
            .collect(),
        None,
    );
    Topology { used, kept, edges }
}

fn area(g: &Garment, t: [u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| g.positions[v as usize]);
    let n = doubled_normal(a, b, c);
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

pub(super) fn degenerate_triangles(g: &Garment) -> HashSet<usize> {
    (0..g.triangles.len())
        .filter(|&t| {
            let [a, b, c] = g.triangles[t];
            a == b || b == c || a == c || area(g, g.triangles[t]) < 1e-12
        })
        .collect()
}

pub(super) fn duplicate_triangles(g: &Garment, skip: &HashSet<usize>) -> HashSet<usize> {
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
pub(super) fn edge_triangles(
    triangles: &[[u32; 3]],
    kept: &[usize],
) -> BTreeMap<[u32; 2], Vec<usize>> {
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

pub(super) fn keep_triangles(g: &mut Garment, kept: &[usize]) {
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
