//! UV layout: every panel is one island, kept at its true shape and orientation (one common
//! scale, no rotation) and packed on shelves into [0, 1]^2 with a margin.

/// Margin around and between islands, in UV units.
pub const UV_MARGIN: f64 = 0.01;

/// Packs islands (2D points each, any units) into [0, 1]^2; returns the UVs, island by island.
pub fn pack(islands: &[Vec<[f64; 2]>]) -> Vec<Vec<[f64; 2]>> {
    let boxes: Vec<([f64; 2], [f64; 2])> = islands
        .iter()
        .map(|pts| {
            let mut lo = [f64::INFINITY; 2];
            let mut hi = [f64::NEG_INFINITY; 2];
            for p in pts {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            (lo, [hi[0] - lo[0], hi[1] - lo[1]])
        })
        .collect();
    let area: f64 = boxes.iter().map(|(_, s)| s[0] * s[1]).sum();
    let gap = 2.0 * UV_MARGIN * area.sqrt().max(1e-9);
    let mut order: Vec<usize> = (0..islands.len()).collect();
    order.sort_by(|&a, &b| boxes[b].1[1].total_cmp(&boxes[a].1[1]).then(a.cmp(&b)));
    // Try shelf widths from the widest island to all in one row; keep the squarest layout.
    let widest = boxes.iter().map(|(_, s)| s[0]).fold(0.0, f64::max) + gap;
    let all: f64 = boxes.iter().map(|(_, s)| s[0] + gap).sum();
    let mut best: Option<(f64, Vec<[f64; 2]>)> = None;
    for k in 0..=64 {
        let width = widest + (all - widest) * k as f64 / 64.0;
        let (side, offsets) = shelves(&order, &boxes, width, gap);
        if best.as_ref().is_none_or(|(s, _)| side < *s) {
            best = Some((side, offsets));
        }
    }
    let (side, offsets) = best.unwrap_or((1.0, vec![[0.0; 2]; islands.len()]));
    let scale = (1.0 - 2.0 * UV_MARGIN) / side.max(1e-12);
    islands
        .iter()
        .enumerate()
        .map(|(i, pts)| {
            let (lo, _) = boxes[i];
            pts.iter()
                .map(|p| {
                    [0, 1].map(|k| {
                        (UV_MARGIN + (offsets[i][k] + p[k] - lo[k]) * scale).clamp(0.0, 1.0)
                    })
                })
                .collect()
        })
        .collect()
}

/// Shelf layout at a given width: the side of the bounding square and every island's offset.
fn shelves(
    order: &[usize],
    boxes: &[([f64; 2], [f64; 2])],
    width: f64,
    gap: f64,
) -> (f64, Vec<[f64; 2]>) {
    let mut offsets = vec![[0.0; 2]; boxes.len()];
    let (mut x, mut y, mut shelf_height, mut used_width) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for &i in order {
        let size = boxes[i].1;
        if x > 0.0 && x + size[0] > width {
            y += shelf_height + gap;
            x = 0.0;
            shelf_height = 0.0;
        }
        offsets[i] = [x, y];
        x += size[0] + gap;
        used_width = used_width.max(x - gap);
        shelf_height = shelf_height.max(size[1]);
    }
    (used_width.max(y + shelf_height), offsets)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn islands_keep_shape_and_do_not_overlap() {
        let rect = |w: f64, h: f64| vec![[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]];
        let islands = vec![
            rect(0.5, 0.7),
            rect(0.4, 0.2),
            rect(0.3, 0.3),
            rect(0.6, 0.1),
        ];
        let uvs = pack(&islands);
        let mut boxes = Vec::new();
        for (island, uv) in islands.iter().zip(&uvs) {
            for p in uv {
                assert!(
                    p.iter()
                        .all(|c| (UV_MARGIN - 1e-12..=1.0 - UV_MARGIN + 1e-12).contains(c))
                );
            }
            // Same scale on both axes for every island.
            let su = (uv[1][0] - uv[0][0]) / (island[1][0] - island[0][0]);
            let sv = (uv[2][1] - uv[1][1]) / (island[2][1] - island[1][1]);
            assert!((su - sv).abs() < 1e-12 && su > 0.0);
            boxes.push((uv[0], uv[2]));
        }
        let scales: Vec<f64> = islands
            .iter()
            .zip(&uvs)
            .map(|(i, u)| (u[1][0] - u[0][0]) / (i[1][0] - i[0][0]))
            .collect();
        assert!(scales.iter().all(|s| (s - scales[0]).abs() < 1e-12));
        for a in 0..boxes.len() {
            for b in a + 1..boxes.len() {
                let (la, ha) = boxes[a];
                let (lb, hb) = boxes[b];
                let apart = ha[0] <= lb[0] || hb[0] <= la[0] || ha[1] <= lb[1] || hb[1] <= la[1];
                assert!(apart, "islands {a} and {b} overlap");
            }
        }
    }
}
