//! Which way the triangles face: every manifold edge traversed in opposite directions by
//! its two triangles (inconsistent ones flipped, a non-orientable piece refused), and each
//! connected piece facing away from its vertical axis, out from the body (a piece facing in is
//! flipped).

use std::collections::{BTreeMap, HashMap};

use super::topology::{Topology, doubled_normal};
use super::{Finding, add};
use crate::mesh::Garment;

/// Appends the orientation findings of the kept triangles.
pub(super) fn orientation_findings(g: &Garment, topology: &Topology, findings: &mut Vec<Finding>) {
    let (kept, edges) = (&topology.kept, &topology.edges);
    match orient(&g.triangles, kept, edges) {
        Some(flips) => {
            add(
                findings,
                "inconsistent orientation",
                flips.iter().map(|t| format!("triangle {t}")).collect(),
                Some("flipped to agree with their neighbours"),
            );
            let mut oriented = g.triangles.clone();
            for &t in &flips {
                oriented[t].swap(1, 2);
            }
            let inward = inward_pieces(&g.positions, &oriented, kept, edges);
            add(
                findings,
                "orientation pointing into the body",
                inward
                    .iter()
                    .map(|piece| format!("a piece of {} triangles", piece.len()))
                    .collect(),
                Some("the piece flipped"),
            );
        }
        None => add(
            findings,
            "no consistent orientation",
            vec!["a non-orientable piece (Moebius-like)".into()],
            None,
        ),
    }
}

fn directed(tri: [u32; 3], a: u32, b: u32) -> bool {
    (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b)
}

/// Triangles to flip so that every manifold edge is traversed in opposite directions by its
/// two triangles; `None` when impossible.
pub(super) fn orient(
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
pub(super) fn inward_pieces(
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
