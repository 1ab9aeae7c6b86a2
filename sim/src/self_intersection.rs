//! Counting a cloth mesh's self-intersections: pairs of triangles that share no vertex and
//! cross (an edge of one passes through the other). GarmentCode rejects drapes with more than
//! 300 of them; the frame statistics report the count.
//!
//! Broad phase: a uniform grid over the triangles' bounding boxes, built by sorting (cell,
//! triangle) entries; a pair is tested only in the cell holding the lowest corner of the two
//! boxes' overlap, so no pair is tested twice. Narrow phase: segment-triangle tests
//! (Moller-Trumbore). Hand-written before the self-contact detector adopted parry3d's `Bvh`;
//! whether that tree's self-traversal (`traverse_bvtt_single_tree`) counts faster is not
//! measured yet.

use rayon::prelude::*;

use crate::cloth::Vec3;

/// Triangle pairs (sharing no vertex) that intersect.
pub fn count_self_intersections(positions: &[Vec3], triangles: &[[u32; 3]]) -> usize {
    self_intersecting_pairs(positions, triangles).len()
}

/// The triangle pairs (sharing no vertex) that intersect, each once, lower index first,
/// sorted.
pub fn self_intersecting_pairs(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let n = positions.len() as u32;
    let valid: Vec<usize> = (0..triangles.len())
        .filter(|&t| triangles[t].iter().all(|&i| i < n))
        .collect();
    if valid.len() < 2 {
        return Vec::new();
    }
    let boxes: Vec<(Vec3, Vec3)> = triangles
        .iter()
        .map(|t| {
            if t.iter().any(|&i| i >= n) {
                return (Vec3::repeat(f64::NAN), Vec3::repeat(f64::NAN));
            }
            let [a, b, c] = t.map(|i| positions[i as usize]);
            (a.inf(&b).inf(&c), a.sup(&b).sup(&c))
        })
        .collect();
    // Cells about twice the mean box size: each triangle lands in a few cells.
    let mean_size = valid
        .iter()
        .map(|&t| (boxes[t].1 - boxes[t].0).max())
        .sum::<f64>()
        / valid.len() as f64;
    let cell = (2.0 * mean_size).max(1e-6);
    let coord = |x: f64| (x / cell).floor() as i64;
    let key = |i: i64, j: i64, k: i64| -> u64 {
        let m = |v: i64| (v + (1 << 20)) as u64 & ((1 << 21) - 1);
        (m(i) << 42) | (m(j) << 21) | m(k)
    };
    let mut entries: Vec<(u64, u32)> = Vec::with_capacity(valid.len() * 4);
    for &t in &valid {
        let (lo, hi) = boxes[t];
        if !(lo.iter().chain(hi.iter()).all(|c| c.is_finite())) {
            continue;
        }
        for i in coord(lo.x)..=coord(hi.x) {
            for j in coord(lo.y)..=coord(hi.y) {
                for k in coord(lo.z)..=coord(hi.z) {
                    entries.push((key(i, j, k), t as u32));
                }
            }
        }
    }
    entries.sort_unstable();
    let groups: Vec<&[(u64, u32)]> = entries.chunk_by(|a, b| a.0 == b.0).collect();
    let mut pairs: Vec<[u32; 2]> = groups
        .par_iter()
        .flat_map_iter(|group| {
            let mut hits = Vec::new();
            for (x, &(cell_key, a)) in group.iter().enumerate() {
                for &(_, b) in &group[x + 1..] {
                    let (ta, tb) = (triangles[a as usize], triangles[b as usize]);
                    if ta.iter().any(|v| tb.contains(v)) {
                        continue;
                    }
                    let (la, ha) = boxes[a as usize];
                    let (lb, hb) = boxes[b as usize];
                    let lo = la.sup(&lb);
                    let hi = ha.inf(&hb);
                    if lo.x > hi.x || lo.y > hi.y || lo.z > hi.z {
                        continue;
                    }
                    // Tested only in the cell of the overlap's lowest corner.
                    if key(coord(lo.x), coord(lo.y), coord(lo.z)) != cell_key {
                        continue;
                    }
                    let pa = ta.map(|i| positions[i as usize]);
                    let pb = tb.map(|i| positions[i as usize]);
                    if triangles_cross(&pa, &pb) {
                        hits.push([a.min(b), a.max(b)]);
                    }
                }
            }
            hits
        })
        .collect();
    pairs.sort_unstable();
    pairs
}

/// Whether two triangles intersect: an edge of either passes through the other.
fn triangles_cross(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
    (0..3).any(|e| segment_hits_triangle(a[e], a[(e + 1) % 3], b))
        || (0..3).any(|e| segment_hits_triangle(b[e], b[(e + 1) % 3], a))
}

/// Moller-Trumbore: the segment p-q crosses the triangle's interior (closed, with a tiny
/// tolerance against edge-grazing double counts; parallel segments never count).
fn segment_hits_triangle(p: Vec3, q: Vec3, t: &[Vec3; 3]) -> bool {
    let dir = q - p;
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let h = dir.cross(&e2);
    let det = e1.dot(&h);
    if det.abs() < 1e-14 * (e1.norm_squared() * e2.norm_squared()).sqrt().max(1e-30) * dir.norm() {
        return false;
    }
    let inv = 1.0 / det;
    let s = p - t[0];
    let u = inv * s.dot(&h);
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let qv = s.cross(&e1);
    let v = inv * dir.dot(&qv);
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let along = inv * e2.dot(&qv);
    (0.0..=1.0).contains(&along)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize, fold: Option<f64>) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (x, z) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                // Folded: the far half is bent back down through the near half.
                let (x, y) = match fold {
                    Some(h) if x > 0.5 => (1.0 - x, h - (x - 0.5) * 0.4),
                    _ => (x, 0.0),
                };
                p.push(Vec3::new(x, y, z));
            }
        }
        let mut t = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = (j * n + i) as u32;
                let (b, c, d) = (a + 1, a + n as u32, a + n as u32 + 1);
                t.push([a, b, d]);
                t.push([a, d, c]);
            }
        }
        (p, t)
    }

    #[test]
    fn crossing_pairs_are_counted_and_neighbours_are_not() {
        let tri = |o: Vec3| {
            [
                o,
                o + Vec3::new(1.0, 0.0, 0.0),
                o + Vec3::new(0.0, 1.0, 0.0),
            ]
        };
        let a = tri(Vec3::zeros());
        let b = [
            Vec3::new(0.2, 0.2, -0.5),
            Vec3::new(0.2, 0.2, 0.5),
            Vec3::new(0.3, -0.5, 0.0),
        ];
        assert!(triangles_cross(&a, &b));
        let far = b.map(|p| p + Vec3::new(5.0, 0.0, 0.0));
        assert!(!triangles_cross(&a, &far));
        let positions: Vec<Vec3> = a.iter().chain(b.iter()).copied().collect();
        assert_eq!(
            count_self_intersections(&positions, &[[0, 1, 2], [3, 4, 5]]),
            1
        );
        // Sharing a vertex never counts, bad indices are skipped.
        assert_eq!(
            count_self_intersections(&positions, &[[0, 1, 2], [0, 4, 5], [0, 1, 9]]),
            0
        );
    }

    #[test]
    fn flat_sheet_has_none_and_a_sheet_folded_through_itself_has_many() {
        let (p, t) = grid(20, None);
        assert_eq!(count_self_intersections(&p, &t), 0);
        // Fold the far half back so it passes through the near half: the fold line
        // crosses about one row of triangles per column.
        let (p, t) = grid(20, Some(0.05));
        let crossing = count_self_intersections(&p, &t);
        assert!(crossing > 19, "{crossing}");
        // Lifted well clear of the near half, the fold has none.
        let (p, t) = grid(20, Some(0.5));
        assert_eq!(count_self_intersections(&p, &t), 0);
    }
}
