//! Panels for a garment that has no UVs of its own (an imported scan or frame), cut where a
//! tailor would cut them: the torso, each sleeve, each split into a front and a back along the
//! body's sides, and laid out as the library's patterns are, in the plane of the garment
//! unposed to the T-pose (torso upright, sleeves along the arms held out). The UVs themselves
//! are unwrapped by [`garments::unwrap_uvs`] within these panels.

use garments::PanelGuide;
use motions::{BodyModel, FramePose, canonical_a_pose};

use super::skinning::{SMOOTHING_ROUNDS, Skinning};
use crate::error::Result;

/// The joints of each arm, shoulder to hand (SMPL's left is the body's own left, +x).
const LEFT_ARM: [usize; 4] = [16, 18, 20, 22];
const RIGHT_ARM: [usize; 4] = [17, 19, 21, 23];

/// The panels, in the order of their ids: part (torso, left sleeve, right sleeve) times side.
const NAMES: [&str; 6] = [
    "torso_front",
    "torso_back",
    "left_sleeve_front",
    "left_sleeve_back",
    "right_sleeve_front",
    "right_sleeve_back",
];

/// Rounds of majority voting that take specks of one panel inside another (where the body's
/// facing or the weights flip for a triangle or two) into the panel around them.
const VOTING_ROUNDS: usize = 4;

/// Each triangle's label replaced `rounds` times by the most common among itself and the
/// triangles sharing an edge with it (its own where that is a tie).
fn vote(labels: &mut [u32], triangles: &[[u32; 3]], rounds: usize) {
    let mut by_edge: std::collections::HashMap<(u32, u32), Vec<usize>> = Default::default();
    for (i, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            by_edge.entry((a.min(b), a.max(b))).or_default().push(i);
        }
    }
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); triangles.len()];
    for sharing in by_edge.values() {
        for &i in sharing {
            neighbours[i].extend(sharing.iter().filter(|&&j| j != i));
        }
    }
    for _ in 0..rounds {
        let previous = labels.to_vec();
        for (i, label) in labels.iter_mut().enumerate() {
            let count = |l: u32| neighbours[i].iter().filter(|&&j| previous[j] == l).count() + 1;
            let own = count(previous[i]);
            if let Some(best) = neighbours[i]
                .iter()
                .map(|&j| previous[j])
                .filter(|&l| count(l) > own)
                .max_by_key(|&l| count(l))
            {
                *label = best;
            }
        }
    }
}

/// Area-weighted vertex normals of a mesh (unnormalized: only their direction is read).
fn vertex_normals(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let mut normals = vec![[0.0; 3]; vertices.len()];
    for f in faces {
        let [a, b, c] = f.map(|i| vertices[i as usize]);
        let (e, g) = (
            [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
            [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
        );
        let n = [
            e[1] * g[2] - e[2] * g[1],
            e[2] * g[0] - e[0] * g[2],
            e[0] * g[1] - e[1] * g[0],
        ];
        for &i in f {
            for k in 0..3 {
                normals[i as usize][k] += n[k];
            }
        }
    }
    normals
}

/// The panels of a template resting on `model`'s canonical body (`positions`, `triangles`):
/// each triangle goes to the part its vertices' skinning weights favour (the torso, with the
/// legs folded into it, or an arm) and to the front or the back by the facing of its vertices'
/// nearest body vertices; every vertex's layout point is its T-pose (x, y).
pub fn panel_guide(
    model: &BodyModel,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<PanelGuide> {
    let skinning = Skinning::new(model, positions, triangles, SMOOTHING_ROUNDS)?;
    let canonical = FramePose {
        pose: canonical_a_pose(),
        transl: [0.0; 3],
    };
    let body = model.pose(&model.shape(&[])?, &canonical)?;
    let normals = vertex_normals(&body.vertices, model.faces());
    let part_shares: Vec<[f64; 3]> = (0..positions.len())
        .map(|v| {
            let (left, right) = (skinning.share(v, &LEFT_ARM), skinning.share(v, &RIGHT_ARM));
            [1.0 - left - right, left, right]
        })
        .collect();
    let facing: Vec<f64> = skinning
        .body_vertices()
        .iter()
        .map(|&b| normals[b as usize][2].signum())
        .collect();
    let mut triangle_panels: Vec<u32> = triangles
        .iter()
        .map(|t| {
            let mut shares = [0.0; 3];
            let mut front = 0.0;
            for &v in t {
                for (s, x) in shares.iter_mut().zip(part_shares[v as usize]) {
                    *s += x;
                }
                front += facing[v as usize];
            }
            let part = (0..3)
                .max_by(|&a, &b| shares[a].total_cmp(&shares[b]))
                .unwrap_or(0);
            (2 * part + usize::from(front < 0.0)) as u32
        })
        .collect();
    vote(&mut triangle_panels, triangles, VOTING_ROUNDS);
    Ok(PanelGuide {
        names: NAMES.iter().map(|n| n.to_string()).collect(),
        triangle_panels,
        plane: skinning.t_pose().map(|p| [p[0], p[1]]).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_speck_of_one_panel_joins_the_panel_around_it() {
        // A fan of six triangles round vertex 0; triangle 2 alone is labelled 1.
        let triangles: Vec<[u32; 3]> = (0..6).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
        let mut labels = vec![0, 0, 1, 0, 0, 0];
        vote(&mut labels, &triangles, 1);
        assert_eq!(labels, [0; 6]);
        // Two equal halves stay as they are.
        let mut labels = vec![0, 0, 0, 1, 1, 1];
        vote(&mut labels, &triangles, 3);
        assert_eq!(labels, [0, 0, 0, 1, 1, 1]);
    }

    /// A band of points just outside the canonical body's vertices: those on the arms go to
    /// the sleeves, those in front to front panels; laid out in the T-pose, the arms are level.
    #[test]
    fn a_skin_tight_garment_is_cut_at_the_arms_and_the_sides() {
        let model = BodyModel::default_body();
        let canonical = FramePose {
            pose: canonical_a_pose(),
            transl: [0.0; 3],
        };
        let body = model.pose(&model.shape(&[]).unwrap(), &canonical).unwrap();
        let normals = vertex_normals(&body.vertices, model.faces());
        // The body's own triangles, pushed 5 mm out along the normals, as a garment.
        let positions: Vec<[f64; 3]> = body
            .vertices
            .iter()
            .zip(&normals)
            .map(|(p, n)| {
                let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(1e-12);
                [0, 1, 2].map(|k| p[k] + 0.005 * n[k] / l)
            })
            .collect();
        let guide = panel_guide(&model, &positions, model.faces()).unwrap();
        let mut wrong = 0;
        for (f, &panel) in model.faces().iter().zip(&guide.triangle_panels) {
            let c: [f64; 3] =
                [0, 1, 2].map(|k| f.iter().map(|&v| positions[v as usize][k]).sum::<f64>() / 3.0);
            let n: f64 = f.iter().map(|&v| normals[v as usize][2]).sum();
            // Far out on an arm in the A-pose: |x| past 0.35 m, above the hips.
            let part = if c[0] > 0.35 && c[1] > 0.0 {
                1
            } else if c[0] < -0.35 && c[1] > 0.0 {
                2
            } else if c[0].abs() < 0.12 && c[1] > -0.05 {
                0
            } else {
                continue;
            };
            if n.abs() > 1e-3 && panel != (2 * part + usize::from(n < 0.0)) as u32 {
                wrong += 1;
            }
        }
        assert!(wrong < 20, "{wrong} triangles in the wrong panel");
        // Laid out in the T-pose, the left wrist is raised from the A-pose's and held further out.
        let wrist: Vec<usize> = (0..positions.len())
            .filter(|&v| positions[v][0] > 0.55)
            .collect();
        assert!(!wrist.is_empty());
        for v in wrist {
            let (p, q) = (guide.plane[v], positions[v]);
            assert!(p[1] - q[1] > 0.2 && p[0] > q[0], "{p:?} from {q:?}");
        }
    }
}
