//! The licence-free default body: loads with no file, follows SMPL's conventions, is a closed
//! surface, and poses plausibly through every built-in motion.

use motions::library::{MOTIONS, MotionSpec};
use motions::{
    BodyModel, FramePose, JOINT_NAMES, NUM_JOINTS, POSE_DIM, boundary_edges, canonical_a_pose,
    mirror_joint,
};

#[test]
fn default_body_is_closed_smpl_like_and_upright() {
    let model = BodyModel::default_body();
    assert!(
        model.num_vertices() <= 14_000,
        "{} vertices",
        model.num_vertices()
    );
    assert_eq!(model.boundary_edge_count(), 0, "the body must be closed");
    assert!(model.num_betas() >= 8);
    assert_eq!(model.beta_names().len(), model.num_betas());
    let shaped = model.shape(&[]).unwrap();
    let ys: Vec<f64> = shaped.vertices.iter().map(|v| v[1]).collect();
    let height =
        ys.iter().cloned().fold(f64::MIN, f64::max) - ys.iter().cloned().fold(f64::MAX, f64::min);
    assert!((1.5..2.0).contains(&height), "height {height} m");
    // SMPL conventions: pelvis where SMPL's is, +x = the body's left, facing +z.
    let j = shaped.joints;
    assert!(
        (j[0][1] + 0.223).abs() < 0.005 && j[0][0].abs() < 1e-6,
        "pelvis {:?}",
        j[0]
    );
    assert!(
        j[16][0] > 0.1 && j[17][0] < -0.1,
        "left shoulder must be at +x"
    );
    assert!(j[10][2] > j[7][2] + 0.05, "toes must point to +z");
    assert!(
        j[15][1] > j[12][1] && j[12][1] > j[0][1],
        "head above neck above pelvis"
    );
    // T-pose: wrists level with the shoulders.
    assert!((j[20][1] - j[16][1]).abs() < 0.02 && j[20][0] > 0.5);
    // Outward-facing triangles: positive enclosed volume.
    let v = &shaped.vertices;
    let volume: f64 = model
        .faces()
        .iter()
        .map(|f| {
            let (a, b, c) = (v[f[0] as usize], v[f[1] as usize], v[f[2] as usize]);
            a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0])
        })
        .sum::<f64>()
        / 6.0;
    assert!(
        (0.04..0.12).contains(&volume),
        "enclosed volume {volume} m^3"
    );
}

#[test]
fn shape_directions_change_the_body() {
    let model = BodyModel::default_body();
    let height = |betas: &[f64]| {
        let s = model.shape(betas).unwrap();
        let ys = s.vertices.iter().map(|v| v[1]);
        ys.clone().fold(f64::MIN, f64::max) - ys.fold(f64::MAX, f64::min)
    };
    let base = height(&[]);
    let taller = height(&[1.0]);
    assert!(
        (taller - base - 0.07).abs() < 0.005,
        "stature beta: +{} m",
        taller - base
    );
    assert_eq!(boundary_edges(model.faces()), 0);
}

#[test]
fn a_pose_lowers_the_arms_forty_degrees() {
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    let posed = model
        .pose(
            &shaped,
            &FramePose {
                pose: canonical_a_pose(),
                transl: [0.0; 3],
            },
        )
        .unwrap();
    let (s, w) = (posed.joints[16], posed.joints[20]);
    let angle = ((s[1] - w[1]) / (w[0] - s[0])).atan().to_degrees();
    assert!(
        (angle - 40.0).abs() < 2.0,
        "left arm {angle} deg below horizontal"
    );
}

#[test]
fn every_builtin_motion_poses_the_default_body_plausibly() {
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    for info in MOTIONS {
        let motion = MotionSpec::parse(info.name)
            .unwrap()
            .generate(&model, &shaped)
            .unwrap();
        assert_eq!(motion.fps, 30.0);
        let posed = model.pose_batch(&shaped, &motion.frames).unwrap();
        let mut previous: Option<[[f64; 3]; 24]> = None;
        let mut velocity: Option<Vec<[f64; 3]>> = None;
        let mut worst = (0.0f64, 0.0f64);
        for (k, p) in posed.iter().enumerate() {
            assert!(
                p.vertices.iter().flatten().all(|v| v.is_finite()),
                "{}: NaN at frame {k}",
                info.name
            );
            let ys = p.vertices.iter().map(|v| v[1]);
            let extent = ys.clone().fold(f64::MIN, f64::max) - ys.fold(f64::MAX, f64::min);
            assert!(
                (0.8..2.6).contains(&extent),
                "{}: vertical extent {extent} at frame {k}",
                info.name
            );
            if let Some(q) = previous {
                // Continuity: no joint faster than 12 m/s (40 cm per frame; a jogging swing foot
                // peaks near 8 m/s), and no joint velocity jump above 12 cm/frame (108 m/s^2;
                // running swing feet reach 100-200 m/s^2).
                let v: Vec<[f64; 3]> = p
                    .joints
                    .iter()
                    .zip(&q)
                    .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
                    .collect();
                let norm = |d: &[f64; 3]| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let jump = v.iter().map(norm).fold(0.0, f64::max);
                assert!(
                    jump < 0.40,
                    "{}: a joint jumped {jump} m at frame {k}",
                    info.name
                );
                if let Some(u) = &velocity {
                    let accel = v
                        .iter()
                        .zip(u)
                        .map(|(a, b)| norm(&[a[0] - b[0], a[1] - b[1], a[2] - b[2]]))
                        .fold(0.0, f64::max);
                    assert!(
                        accel < 0.12,
                        "{}: velocity jump {accel} m/frame at frame {k}",
                        info.name
                    );
                    worst.1 = worst.1.max(accel);
                }
                worst.0 = worst.0.max(jump);
                velocity = Some(v);
            }
            previous = Some(p.joints);
        }
        // The root, moved by foot planting, must be smoother still: a stance defect once jerked
        // it 10 cm back in one frame.
        let root: Vec<[f64; 3]> = motion.frames.iter().map(|f| f.transl).collect();
        for k in 2..root.len() {
            let jerk = (0..3)
                .map(|c| (root[k][c] - 2.0 * root[k - 1][c] + root[k - 2][c]).abs())
                .fold(0.0, f64::max);
            assert!(
                jerk < 0.03,
                "{}: root velocity jump {jerk} m/frame at frame {k}",
                info.name
            );
        }
        println!(
            "{}: max joint step {:.3} m/frame, max velocity change {:.4} m/frame",
            info.name, worst.0, worst.1
        );
        assert!(motion.frames.iter().all(|f| f.pose.len() == POSE_DIM));
    }
}

#[test]
fn builtin_motions_keep_joint_angles_within_human_limits() {
    // Largest rotation from the T-pose allowed per joint, degrees (the root is free).
    // Shoulders are measured from the T-pose, so arms hanging down already use ~70 degrees.
    let limits = [
        360.0, 125.0, 125.0, 45.0, 145.0, 145.0, 45.0, 45.0, 45.0, 45.0, 35.0, 35.0, 45.0, 35.0,
        35.0, 45.0, 175.0, 175.0, 150.0, 150.0, 80.0, 80.0, 80.0, 80.0,
    ];
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    for info in MOTIONS {
        let motion = MotionSpec::parse(&format!("{}:amplitude=1.5", info.name))
            .unwrap()
            .generate(&model, &shaped)
            .unwrap();
        let max = motion.max_joint_angles_deg();
        for (j, limit) in limits.iter().enumerate().skip(1) {
            assert!(
                max[j] <= *limit,
                "{} at amplitude 1.5: joint {} turns {:.1} deg (limit {limit})",
                info.name,
                motions::JOINT_NAMES[j],
                max[j]
            );
        }
        // Knees bend only backwards, elbows only forwards.
        for f in &motion.frames {
            assert!(
                f.pose[4 * 3] > -0.05 && f.pose[5 * 3] > -0.05,
                "{}: a knee hyperextends",
                info.name
            );
        }
    }
}

/// The rest body's vertex nearest to the mirror image (x -> -x) of vertex `k`.
fn mirror_vertex(template: &[[f64; 3]], k: usize) -> usize {
    let [x, y, z] = template[k];
    let gap = |v: &[f64; 3]| (v[0] + x).powi(2) + (v[1] - y).powi(2) + (v[2] - z).powi(2);
    (0..template.len())
        .min_by(|&a, &b| gap(&template[a]).total_cmp(&gap(&template[b])))
        .expect("the body has vertices")
}

/// Mirror augmentation rests on this: the default body is symmetric about x = 0, so a
/// mirrored pose on a shaped body gives the mirror image of the posed body, vertex for
/// mirrored vertex, for a pose that bends every joint a different way: to 2 mm, because the
/// joint regressor is not exactly symmetric (the shaped joints below sit up to 1.5 mm from
/// their partners' mirror images; at betas 0 to 0.001 mm).
#[test]
fn a_mirrored_pose_poses_the_mirror_image_of_the_body() {
    let model = BodyModel::default_body();
    let shaped = model.shape(&[1.0, -0.5, 0.3, 0.8, -1.0]).unwrap();
    let mut pose = canonical_a_pose();
    for (i, v) in pose.iter_mut().enumerate() {
        *v += 0.3 * ((i as f64) * 1.7).sin();
    }
    let frame = FramePose {
        pose,
        transl: [0.2, 0.05, -0.1],
    };
    let posed = model.pose(&shaped, &frame).unwrap().vertices;
    let mirrored = model.pose(&shaped, &frame.mirrored()).unwrap().vertices;
    let template = model.template();
    let mut worst: f64 = 0.0;
    for k in (0..template.len()).step_by(67) {
        let m = mirror_vertex(template, k);
        let [x, y, z] = posed[k];
        let gap = ((mirrored[m][0] + x).powi(2)
            + (mirrored[m][1] - y).powi(2)
            + (mirrored[m][2] - z).powi(2))
        .sqrt();
        worst = worst.max(gap);
    }
    assert!(
        worst < 2e-3,
        "a mirrored vertex is {worst} m from its place"
    );
    // Mirroring twice gives the pose back; the canonical A-pose is its own mirror image.
    assert_eq!(frame.mirrored().mirrored(), frame);
    let a = FramePose {
        pose: canonical_a_pose(),
        transl: [0.0; 3],
    };
    assert!(
        a.mirrored()
            .pose
            .iter()
            .zip(&a.pose)
            .all(|(p, q)| (p - q).abs() < 1e-12)
    );
    for j in 0..NUM_JOINTS {
        let partner = JOINT_NAMES[mirror_joint(j)];
        let expected = JOINT_NAMES[j]
            .replace("left_", "RIGHT_")
            .replace("right_", "left_")
            .replace("RIGHT_", "right_");
        assert_eq!(partner, expected);
    }
}
