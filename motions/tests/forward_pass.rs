//! The forward pass on a small model built in code, against results worked out by hand, so the
//! suite checks it without ../shared; plus the model file loader's round trip.

use motions::{BodyModel, FramePose, ModelArrays, NUM_JOINTS, POSE_DIM, SMPL_PARENTS};

/// A stick body: one vertex on each joint's rest position, plus one vertex 10 cm beyond the left
/// elbow along +x, every vertex bound rigidly to one joint.
fn stick_model(with_posedirs: bool) -> (ModelArrays, [[f64; 3]; NUM_JOINTS]) {
    let mut joints = [[0.0; 3]; NUM_JOINTS];
    for (j, p) in joints.iter_mut().enumerate() {
        *p = [0.1 * j as f64 - 1.0, 0.05 * j as f64, 0.01 * (j % 3) as f64];
    }
    let mut v_template: Vec<[f64; 3]> = joints.to_vec();
    v_template.push([joints[18][0] + 0.1, joints[18][1], joints[18][2]]);
    let nv = v_template.len();
    let mut weights = vec![0.0; nv * NUM_JOINTS];
    for j in 0..NUM_JOINTS {
        weights[j * NUM_JOINTS + j] = 1.0;
    }
    weights[NUM_JOINTS * NUM_JOINTS + 18] = 1.0;
    let mut j_regressor = vec![0.0; NUM_JOINTS * nv];
    for j in 0..NUM_JOINTS {
        j_regressor[j * nv + j] = 1.0;
    }
    // Shape direction 0 moves every vertex +1 cm in y per unit beta.
    let mut shapedirs = vec![0.0; nv * 3 * 2];
    for v in 0..nv {
        shapedirs[(v * 3 + 1) * 2] = 0.01;
    }
    let mut posedirs = vec![0.0; nv * 3 * 207];
    if with_posedirs {
        // The extra vertex moves +1 mm in z per unit of (R_18 - I)[0][0] (feature 17*9).
        posedirs[((nv - 1) * 3 + 2) * 207 + 17 * 9] = 0.001;
    }
    let faces = vec![[0, 1, 2], [24, 18, 20]];
    (
        ModelArrays {
            v_template,
            faces,
            shapedirs,
            num_betas: 2,
            posedirs,
            j_regressor,
            weights,
            parents: SMPL_PARENTS,
            beta_names: vec![],
        },
        joints,
    )
}

#[test]
fn elbow_rotation_moves_the_forearm_vertex_as_worked_out_by_hand() {
    let (arrays, joints) = stick_model(true);
    let model = BodyModel::from_arrays(arrays).unwrap();
    let shaped = model.shape(&[2.0]).unwrap();
    // Betas shift everything 2 cm up; joints follow (the regressor picks joint vertices).
    assert!((shaped.joints[18][1] - joints[18][1] - 0.02).abs() < 1e-15);
    let mut pose = [0.0; POSE_DIM];
    pose[18 * 3 + 2] = std::f64::consts::FRAC_PI_2; // left elbow: +90 deg about z
    let transl = [0.5, -0.25, 1.0];
    let posed = model.pose(&shaped, &FramePose { pose, transl }).unwrap();
    let elbow = shaped.joints[18];
    // (R - I)[0][0] = cos 90 - 1 = -1, so the pose blend shape moves the vertex -1 mm in z
    // before skinning; the 10 cm lever along +x turns to +y.
    let want = [
        elbow[0] + transl[0],
        elbow[1] + 0.1 + transl[1],
        elbow[2] - 0.001 + transl[2],
    ];
    let got = posed.vertices[24];
    for c in 0..3 {
        assert!(
            (got[c] - want[c]).abs() < 1e-12,
            "axis {c}: got {} want {}",
            got[c],
            want[c]
        );
    }
    // Joints below the elbow did not move; the wrist swung with it.
    assert!((posed.joints[16][0] - shaped.joints[16][0] - transl[0]).abs() < 1e-12);
    let wrist_offset: Vec<f64> = (0..3).map(|c| shaped.joints[20][c] - elbow[c]).collect();
    assert!((posed.joints[20][0] - (elbow[0] - wrist_offset[1] + transl[0])).abs() < 1e-12);
    assert!((posed.joints[20][1] - (elbow[1] + wrist_offset[0] + transl[1])).abs() < 1e-12);
}

#[test]
fn zero_pose_gives_the_shaped_template_plus_translation() {
    let (arrays, _) = stick_model(true);
    let model = BodyModel::from_arrays(arrays).unwrap();
    let shaped = model.shape(&[0.5, -1.0, 7.0]).unwrap(); // a third beta is ignored
    let posed = model
        .pose(
            &shaped,
            &FramePose {
                pose: [0.0; POSE_DIM],
                transl: [1.0, 2.0, 3.0],
            },
        )
        .unwrap();
    for (p, s) in posed.vertices.iter().zip(&shaped.vertices) {
        for c in 0..3 {
            assert!((p[c] - [1.0, 2.0, 3.0][c] - s[c]).abs() < 1e-12);
        }
    }
}

#[test]
fn batch_equals_frame_by_frame() {
    let model = BodyModel::default_body();
    let shaped = model.shape(&[0.3, -0.2]).unwrap();
    let frames: Vec<FramePose> = (0..8)
        .map(|k| {
            let mut pose = [0.0; POSE_DIM];
            for (i, p) in pose.iter_mut().enumerate() {
                *p = 0.3 * ((i * 7 + k * 3) as f64).sin();
            }
            FramePose {
                pose,
                transl: [0.1 * k as f64, 0.0, 0.0],
            }
        })
        .collect();
    let batch = model.pose_batch(&shaped, &frames).unwrap();
    for (f, b) in frames.iter().zip(&batch) {
        assert_eq!(model.pose(&shaped, f).unwrap().vertices, b.vertices);
    }
}

#[test]
fn non_finite_inputs_are_errors_not_panics() {
    let model = BodyModel::default_body();
    assert!(model.shape(&[f64::NAN]).is_err());
    let shaped = model.shape(&[]).unwrap();
    let mut pose = [0.0; POSE_DIM];
    pose[5] = f64::INFINITY;
    assert!(
        model
            .pose(
                &shaped,
                &FramePose {
                    pose,
                    transl: [0.0; 3]
                }
            )
            .is_err()
    );
}

#[test]
fn model_arrays_are_validated() {
    let (mut arrays, _) = stick_model(false);
    arrays.weights[0] = 0.5; // row 0 no longer sums to 1
    let err = BodyModel::from_arrays(arrays).unwrap_err().to_string();
    assert!(err.contains("sum to"), "{err}");
    let (mut arrays, _) = stick_model(false);
    arrays.faces.push([0, 1, 99]);
    assert!(BodyModel::from_arrays(arrays).is_err());
    let (mut arrays, _) = stick_model(false);
    arrays.parents[3] = Some(5);
    assert!(BodyModel::from_arrays(arrays).is_err());
}
