//! Untangling: removing a mesh's local self-intersections by smoothing where they are.
//!
//! Sewing pulls panels together without cloth-cloth contact (contact would hold panels that
//! start apart from closing), and where a sleeve meets an armhole the cloth next to the seam
//! folds through the bodice: 76-252 crossing triangle pairs per sleeved library design once
//! the seams have closed (in templates made without this pass, every crossing pair of a top
//! was within six edges of each other). Self-contact cannot undo a crossing it starts with,
//! and it ignores a vertex's own neighbours, so these would stay for the whole simulation.
//! Umbrella smoothing of the crossing triangles' vertices opens such creases: the fold
//! flattens and the two layers part. Crossings between distant parts of the cloth (two skirt
//! panels through each other) are not creases; smoothing them would distort the garment,
//! so the region grows by at most [`MAX_RINGS`] and the pass stops when it stops helping.

use crate::cloth::Vec3;
use crate::self_intersection::self_intersecting_pairs;

/// Most rounds of finding crossings and smoothing around them.
const MAX_ROUNDS: usize = 30;
/// Most rings of neighbours added around the crossing triangles' vertices.
const MAX_RINGS: usize = 3;
/// Smoothing sweeps per round.
const SWEEPS: usize = 3;
/// Each sweep moves a vertex this fraction of the way to its neighbours' mean.
const STEP: f64 = 0.5;

/// What untangling did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UntangleReport {
    /// Crossing triangle pairs before.
    pub before: usize,
    /// Crossing triangle pairs after.
    pub after: usize,
    /// Rounds of smoothing applied.
    pub rounds: usize,
}

/// Smooths `positions` around the crossing pairs of `triangles` until none cross, the region
/// has grown [`MAX_RINGS`] rings without progress, or [`MAX_ROUNDS`] rounds have passed.
/// Vertices no triangle uses are left alone. A round that ends with more crossings than it
/// started with is undone.
pub fn untangle(positions: &mut [Vec3], triangles: &[[u32; 3]]) -> UntangleReport {
    let neighbours = garments::vertex_neighbours(positions.len(), triangles);
    let mut pairs = self_intersecting_pairs(positions, triangles);
    let before = pairs.len();
    let mut rings = 1;
    let mut rounds = 0;
    let mut in_region = vec![false; positions.len()];
    let mut next = positions.to_vec();
    while !pairs.is_empty() && rounds < MAX_ROUNDS && rings <= MAX_RINGS {
        in_region.fill(false);
        let mut region: Vec<u32> = Vec::new();
        for &[a, b] in &pairs {
            for v in triangles[a as usize].iter().chain(&triangles[b as usize]) {
                if !std::mem::replace(&mut in_region[*v as usize], true) {
                    region.push(*v);
                }
            }
        }
        for _ in 0..rings {
            for k in 0..region.len() {
                for &n in &neighbours[region[k] as usize] {
                    if !std::mem::replace(&mut in_region[n as usize], true) {
                        region.push(n);
                    }
                }
            }
        }
        let saved: Vec<Vec3> = region.iter().map(|&v| positions[v as usize]).collect();
        for _ in 0..SWEEPS {
            for &v in &region {
                let around = &neighbours[v as usize];
                let mean = around
                    .iter()
                    .fold(Vec3::zeros(), |s, &n| s + positions[n as usize])
                    / around.len() as f64;
                next[v as usize] = positions[v as usize] + STEP * (mean - positions[v as usize]);
            }
            for &v in &region {
                positions[v as usize] = next[v as usize];
            }
        }
        rounds += 1;
        let found = self_intersecting_pairs(positions, triangles);
        if found.len() > pairs.len() {
            for (&v, p) in region.iter().zip(saved) {
                positions[v as usize] = p;
            }
            rings += 1;
        } else {
            if found.len() == pairs.len() {
                rings += 1;
            }
            pairs = found;
        }
    }
    UntangleReport {
        before,
        after: pairs.len(),
        rounds,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `cols` x 2 squares along x, folded back over itself at x = `fold` so the
    /// part past the fold lies `dip` below the part before it and crosses it.
    fn creased_strip(cols: usize, fold: usize, dip: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let h = 0.01;
        let mut positions = Vec::new();
        for i in 0..=cols {
            for j in 0..=2 {
                let (x, y) = if i <= fold {
                    (i as f64 * h, 0.0)
                } else {
                    // Back past the fold, tilted so it passes through the first part a few
                    // columns from the fold (triangles that share no vertex cross).
                    let back = (i - fold) as f64 * h;
                    (fold as f64 * h - back, dip - 0.35 * back)
                };
                positions.push(Vec3::new(x, y, j as f64 * h));
            }
        }
        let id = |i: usize, j: usize| (i * 3 + j) as u32;
        let mut triangles = Vec::new();
        for i in 0..cols {
            for j in 0..2 {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (positions, triangles)
    }

    #[test]
    fn a_crease_through_itself_is_opened() {
        let (mut positions, triangles) = creased_strip(10, 6, 0.009);
        let start = positions.clone();
        let report = untangle(&mut positions, &triangles);
        assert!(
            report.before > 0,
            "the strip must start crossed: {report:?}"
        );
        assert_eq!(report.after, 0, "{report:?}");
        assert_eq!(self_intersecting_pairs(&positions, &triangles).len(), 0);
        // Only the crease moved, and by less than its size.
        assert!(
            positions
                .iter()
                .zip(&start)
                .all(|(p, q)| (p - q).norm() < 0.03)
        );
    }

    #[test]
    fn a_mesh_without_crossings_is_untouched() {
        let (mut positions, triangles) = creased_strip(6, 6, 0.0);
        let start = positions.clone();
        let report = untangle(&mut positions, &triangles);
        assert_eq!(
            report,
            UntangleReport {
                before: 0,
                after: 0,
                rounds: 0
            }
        );
        assert_eq!(positions, start);
    }
}
