//! BVH files written by the test with known angles, paths, rotation orders and frame times
//! come back as those SMPL rotations and translations; damaged files are refused naming the
//! line. CMU's real clips are in `bvh_captures.rs`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use motions::bvh::{Bvh, JointMap, retarget};
use motions::rotation::axis_angle_to_quat;
use motions::{BodyModel, MotionSource, ShapedBody};
use nalgebra::{UnitQuaternion, Vector3};

/// CMU's names for the SMPL joints, and each one's SMPL joint (children after parents).
const SKELETON: [(&str, usize); 24] = [
    ("Hips", 0),
    ("LeftUpLeg", 1),
    ("LeftLeg", 4),
    ("LeftFoot", 7),
    ("LeftToeBase", 10),
    ("RightUpLeg", 2),
    ("RightLeg", 5),
    ("RightFoot", 8),
    ("RightToeBase", 11),
    ("LowerBack", 3),
    ("Spine", 6),
    ("Spine1", 9),
    ("Neck", 12),
    ("Head", 15),
    ("LeftShoulder", 13),
    ("LeftArm", 16),
    ("LeftForeArm", 18),
    ("LeftHand", 20),
    ("LFingers", 22),
    ("RightShoulder", 14),
    ("RightArm", 17),
    ("RightForeArm", 19),
    ("RightHand", 21),
    ("RFingers", 23),
];

/// A BVH of the SMPL skeleton itself (offsets from the default body's rest joints, metres),
/// CMU names, every joint with `order` rotation channels; `rows` gives each frame's values
/// (root position, then three angles per joint in file order).
fn smpl_skeleton_bvh(
    shaped: &ShapedBody,
    order: &str,
    frame_time: f64,
    rows: &[Vec<f64>],
) -> String {
    let parents = motions::SMPL_PARENTS;
    let mut text = String::from("HIERARCHY\n");
    // Depth-first in SKELETON's order, closing braces when the next joint is not a child.
    let mut open: Vec<usize> = Vec::new();
    for (name, j) in SKELETON {
        while let Some(&top) = open.last() {
            if Some(top) == parents[j] {
                break;
            }
            open.pop();
            writeln!(text, "{}}}", "  ".repeat(open.len())).unwrap();
        }
        let indent = "  ".repeat(open.len());
        let offset = match parents[j] {
            Some(p) => {
                std::array::from_fn::<f64, 3, _>(|c| shaped.joints[j][c] - shaped.joints[p][c])
            }
            None => [0.0; 3],
        };
        let keyword = if j == 0 { "ROOT" } else { "JOINT" };
        writeln!(text, "{indent}{keyword} {name}\n{indent}{{").unwrap();
        writeln!(
            text,
            "{indent}  OFFSET {} {} {}",
            offset[0], offset[1], offset[2]
        )
        .unwrap();
        let rotations: Vec<String> = order.chars().map(|a| format!("{a}rotation")).collect();
        if j == 0 {
            writeln!(
                text,
                "{indent}  CHANNELS 6 Xposition Yposition Zposition {}",
                rotations.join(" ")
            )
            .unwrap();
        } else {
            writeln!(text, "{indent}  CHANNELS 3 {}", rotations.join(" ")).unwrap();
        }
        open.push(j);
    }
    while open.pop().is_some() {
        writeln!(text, "{}}}", "  ".repeat(open.len())).unwrap();
    }
    writeln!(
        text,
        "MOTION\nFrames: {}\nFrame Time: {frame_time}",
        rows.len()
    )
    .unwrap();
    for row in rows {
        let values: Vec<String> = row.iter().map(|v| v.to_string()).collect();
        writeln!(text, "{}", values.join(" ")).unwrap();
    }
    text
}

/// A frame's values: the root at `root`, every angle zero but `set` ((joint name, three
/// angles in file order, degrees)).
fn row(root: [f64; 3], set: &[(&str, [f64; 3])]) -> Vec<f64> {
    let mut values = root.to_vec();
    for (name, _) in SKELETON {
        let angles = set
            .iter()
            .find(|(n, _)| *n == name)
            .map_or([0.0; 3], |s| s.1);
        values.extend(angles);
    }
    values
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn rotation_of(pose: &[f64; 72], joint: usize) -> UnitQuaternion<f64> {
    axis_angle_to_quat([pose[3 * joint], pose[3 * joint + 1], pose[3 * joint + 2]])
}

fn axis_rotation(axis: char, degrees: f64) -> UnitQuaternion<f64> {
    let a = match axis {
        'X' => Vector3::x_axis(),
        'Y' => Vector3::y_axis(),
        _ => Vector3::z_axis(),
    };
    UnitQuaternion::from_axis_angle(&a, degrees.to_radians())
}

#[test]
fn known_angles_and_root_path_come_back_exactly() {
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    let dir = tempfile::tempdir().unwrap();
    // 60 fps, 2 s: the left elbow bent 90 degrees about y, the right knee 40 about x, and
    // the root walking 0.5 m/s along z while bobbing.
    let fps = 60.0;
    let rows: Vec<Vec<f64>> = (0..=120)
        .map(|k| {
            let t = k as f64 / fps;
            row(
                [0.1, 0.9 + 0.02 * (3.0 * t).sin(), 0.5 * t],
                &[
                    ("LeftForeArm", [0.0, 90.0, 0.0]),
                    ("RightLeg", [0.0, 0.0, 40.0]),
                ],
            )
        })
        .collect();
    let path = write(
        dir.path(),
        "known.bvh",
        &smpl_skeleton_bvh(&shaped, "ZYX", 1.0 / fps, &rows),
    );
    let loaded = MotionSource::parse(path.to_str().unwrap())
        .unwrap()
        .load(&model, &shaped)
        .unwrap();
    let report = loaded.retarget.unwrap();
    assert_eq!(report.map, "cmu");
    assert_eq!(report.mapped.len(), 24);
    assert!(report.dropped.is_empty() && !report.reference_frame_dropped);
    assert!(
        (report.metres_per_unit - 1.0).abs() < 1e-12,
        "{}",
        report.metres_per_unit
    );
    assert_eq!(
        (report.up_axis.as_str(), report.forward_axis.as_str()),
        ("+y", "+z")
    );
    let motion = loaded.motion;
    assert_eq!((motion.len(), motion.fps), (61, 30.0));
    let elbow = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
    let knee = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 40f64.to_radians());
    for (k, frame) in motion.frames.iter().enumerate() {
        assert!(
            rotation_of(&frame.pose, 18).angle_to(&elbow) < 1e-9,
            "frame {k}: left elbow"
        );
        assert!(
            rotation_of(&frame.pose, 5).angle_to(&knee) < 1e-9,
            "frame {k}: right knee"
        );
        for j in [0, 1, 3, 16, 19, 20] {
            assert!(
                rotation_of(&frame.pose, j).angle() < 1e-9,
                "frame {k}: joint {j} moved"
            );
        }
        // The root path, relative to the first frame (placement moves the whole path).
        let t = k as f64 / 30.0;
        let expected = [0.0, 0.02 * (3.0 * t).sin(), 0.5 * t];
        for (c, want) in expected.into_iter().enumerate() {
            let moved = frame.transl[c] - motion.frames[0].transl[c];
            // Resampling 60 -> 30 fps lands on source frames: exact but for rounding.
            assert!(
                (moved - want).abs() < 1e-9,
                "frame {k} axis {c}: {moved} vs {want}"
            );
        }
    }
    // Placed on the floor: lowest point at y = 0 and the pelvis over the origin, frame 0.
    let first = model.pose(&shaped, &motion.frames[0]).unwrap();
    let lowest = first
        .vertices
        .iter()
        .map(|v| v[1])
        .fold(f64::INFINITY, f64::min);
    assert!(lowest.abs() < 1e-9, "lowest point {lowest}");
    assert!(first.joints[0][0].abs() < 1e-9 && first.joints[0][2].abs() < 1e-9);
}

#[test]
fn another_rotation_order_and_frame_time() {
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    let dir = tempfile::tempdir().unwrap();
    // 25 fps, XYZ order: the left shoulder's three angles compose as Rx Ry Rz.
    let angles = [30.0, -20.0, 10.0];
    let rows = vec![row([0.0, 0.9, 0.0], &[("LeftArm", angles)]); 26];
    let path = write(
        dir.path(),
        "xyz.bvh",
        &smpl_skeleton_bvh(&shaped, "XYZ", 0.04, &rows),
    );
    let source = format!("{}:start=0.2,duration=0.5", path.display());
    let motion = MotionSource::parse(&source)
        .unwrap()
        .load(&model, &shaped)
        .unwrap()
        .motion;
    assert_eq!(motion.len(), 15, "0.5 s at 30 fps");
    assert_eq!(motion.name, source);
    let expected = axis_rotation('X', angles[0])
        * axis_rotation('Y', angles[1])
        * axis_rotation('Z', angles[2]);
    for frame in &motion.frames {
        assert!(rotation_of(&frame.pose, 16).angle_to(&expected) < 1e-9);
    }
    let bvh = Bvh::load(&path).unwrap();
    assert_eq!(bvh.frames(), 26);
    assert!((bvh.fps() - 25.0).abs() < 1e-12);
    // A stretch past the end is refused, naming the file.
    let past = format!("{}:start=0.9,duration=0.5", path.display());
    let err = MotionSource::parse(&past)
        .unwrap()
        .load(&model, &shaped)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("xyz.bvh") && err.contains("past the end"),
        "{err}"
    );
}

#[test]
fn a_reference_first_frame_and_unknown_joints_are_dropped() {
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut rows = vec![row([0.0, 0.9, 0.0], &[("LeftArm", [0.0, 0.0, -60.0])]); 5];
    rows.insert(0, row([0.0, 0.9, 0.0], &[]));
    let text = smpl_skeleton_bvh(&shaped, "ZYX", 1.0 / 60.0, &rows);
    let path = write(dir.path(), "reference.bvh", &text);
    let retargeted = motions::bvh::load(&path, None, &shaped).unwrap();
    assert!(retargeted.report.reference_frame_dropped);
    assert_eq!(retargeted.motion.len(), 5);

    // A finger joint with no SMPL counterpart is listed as dropped.
    let bvh = Bvh::parse(&text, &path).unwrap();
    let map = JointMap::builtin_for(&bvh).unwrap();
    let mut names = map.bvh_joint;
    names[22] = None;
    let partial = JointMap {
        bvh_joint: names,
        ..map
    };
    let report = retarget(&bvh, &partial, &shaped).unwrap().report;
    assert_eq!(report.dropped, vec!["LFingers".to_string()]);
    assert_eq!(report.unmapped, vec!["left_hand"]);
}

#[test]
fn a_joint_map_file_drives_any_skeleton_and_bad_maps_are_refused() {
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let rows = vec![row([0.0, 90.0, 0.0], &[("LeftForeArm", [0.0, 45.0, 0.0])]); 3];
    // The same skeleton with made-up names, in centimetres.
    let mut text = smpl_skeleton_bvh(&shaped, "ZYX", 1.0 / 30.0, &rows);
    let mut map = String::from("metres_per_unit = 0.01\n[joints]\n");
    for (k, (name, j)) in SKELETON.iter().enumerate() {
        text = text.replace(&format!("JOINT {name}\n"), &format!("JOINT bone{k}\n"));
        text = text.replace(&format!("ROOT {name}\n"), &format!("ROOT bone{k}\n"));
        writeln!(map, "{} = \"bone{k}\"", motions::JOINT_NAMES[*j]).unwrap();
    }
    let bvh_path = write(dir.path(), "custom.bvh", &text);
    let err = MotionSource::parse(bvh_path.to_str().unwrap())
        .unwrap()
        .load(&model, &shaped)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("no built-in joint map") && err.contains("map=FILE.toml"),
        "{err}"
    );
    let map_path = write(dir.path(), "custom.toml", &map);
    let source = format!("{}:map={}", bvh_path.display(), map_path.display());
    let loaded = MotionSource::parse(&source)
        .unwrap()
        .load(&model, &shaped)
        .unwrap();
    assert_eq!(loaded.retarget.unwrap().metres_per_unit, 0.01);
    let bent = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_4);
    assert!(rotation_of(&loaded.motion.frames[0].pose, 18).angle_to(&bent) < 1e-9);

    let bvh = Bvh::load(&bvh_path).unwrap();
    for (name, body, expected) in [
        (
            "unknown_smpl.toml",
            "[joints]\npelvis = \"bone0\"\nelbow = \"bone1\"\n",
            "joints.elbow: not an SMPL joint",
        ),
        (
            "unknown_bvh.toml",
            "[joints]\npelvis = \"Hips\"\n",
            "has no such joint",
        ),
        (
            "twice.toml",
            "[joints]\npelvis = \"bone0\"\nleft_hip = \"bone0\"\n",
            "already drives",
        ),
        (
            "missing.toml",
            "[joints]\npelvis = \"bone0\"\n",
            "joints.left_hip is missing",
        ),
        (
            "unit.toml",
            "metres_per_unit = -1\n[joints]\n",
            "metres_per_unit = -1",
        ),
        ("syntax.toml", "[joints\n", "line 1: "),
    ] {
        let path = write(dir.path(), name, body);
        let err = JointMap::load(&path, &bvh).unwrap_err().to_string();
        assert!(
            err.contains(name) && err.contains(expected),
            "{name}: {err}"
        );
    }
    // A map whose hierarchy disagrees with the file's: the left knee under the right hip.
    let crossed = map
        .replace("left_knee = \"bone2\"", "left_knee = \"bone6\"")
        .replace("right_knee = \"bone6\"", "right_knee = \"bone2\"");
    let path = write(dir.path(), "crossed.toml", &crossed);
    let err = JointMap::load(&path, &bvh).unwrap_err().to_string();
    assert!(err.contains("is not below"), "{err}");
}

/// A small well-formed file: a root and one joint, two frames.
const GOOD: &str = "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n  JOINT Leg\n  {\n    OFFSET 0 -1 0\n    CHANNELS 3 Zrotation Yrotation Xrotation\n    End Site\n    {\n      OFFSET 0 -1 0\n    }\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n0 1 0 0 0 0 0 0 0\n0 1 0 0 0 0 10 0 0\n";

/// Damaged versions of [`GOOD`]: (what, the text, the line named, words of the error).
fn damaged_versions() -> Vec<(&'static str, String, usize, &'static str)> {
    let good = GOOD;
    vec![
        (
            "no header",
            good.replace("HIERARCHY", "HIERARCHIE"),
            1,
            "expected 'HIERARCHY'",
        ),
        (
            "bad offset",
            good.replace("OFFSET 0 -1 0\n    CHANNELS", "OFFSET 0 x 0\n    CHANNELS"),
            8,
            "'x' is not a finite number",
        ),
        (
            "channel",
            good.replace(
                "Zrotation Yrotation Xrotation\n    End",
                "Zrotation Yrotation Wrotation\n    End",
            ),
            9,
            "unknown channel 'Wrotation'",
        ),
        (
            "repeated channel",
            good.replace(
                "Zrotation Yrotation Xrotation\n    End",
                "Zrotation Zrotation Xrotation\n    End",
            ),
            9,
            "listed twice",
        ),
        (
            "count",
            good.replace("CHANNELS 3", "CHANNELS 7"),
            9,
            "0 to 6",
        ),
        (
            "brace",
            good.replace("  }\n}\nMOTION", "  }\nMOTION"),
            14,
            "inside a joint's braces",
        ),
        (
            "two roots",
            good.replace(
                "MOTION",
                "ROOT Other\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nMOTION",
            ),
            16,
            "a second ROOT",
        ),
        (
            "twice",
            good.replace("JOINT Leg", "JOINT Hips"),
            6,
            "named twice",
        ),
        (
            "no motion",
            good[..good.find("MOTION").unwrap()].to_string(),
            15,
            "no MOTION block",
        ),
        (
            "frames",
            good.replace("Frames: 2", "Frames: two"),
            17,
            "Frames: 'two' is not a number",
        ),
        ("time", good.replace("0.0333333", "0"), 18, "not a rate"),
        (
            "short row",
            good.replace("0 1 0 0 0 0 10 0 0", "0 1 0 0 0 0 10 0"),
            20,
            "has 8 values",
        ),
        (
            "nan",
            good.replace("0 1 0 0 0 0 10 0 0", "0 1 0 0 0 0 nan 0 0"),
            20,
            "'nan' is not a finite number",
        ),
        (
            "a bad line past the frames",
            good.replace("Frames: 2", "Frames: 1") + "0 1 0\n",
            21,
            "frame 3 has 3 values",
        ),
        (
            "fewer frames",
            good.replace("Frames: 2", "Frames: 3"),
            20,
            "after 2 of the 3 frames",
        ),
    ]
}

#[test]
fn damaged_files_are_refused_naming_the_line() {
    let good = GOOD;
    let bvh = Bvh::parse(good, Path::new("good.bvh")).unwrap();
    assert_eq!(
        (bvh.frames(), bvh.joints.len(), bvh.values_per_frame),
        (2, 2, 9)
    );
    // A frame past the announced count (an exporter's off-by-one) is read and kept out.
    let one = Bvh::parse(
        &good.replace("Frames: 2", "Frames: 1"),
        Path::new("one.bvh"),
    )
    .unwrap();
    assert_eq!(one.frames(), 1);
    for (what, text, line, expected) in damaged_versions() {
        let err = Bvh::parse(&text, Path::new("damaged.bvh"))
            .unwrap_err()
            .to_string();
        let head = format!("damaged.bvh: line {line}: ");
        assert!(
            err.starts_with(&head) && err.contains(expected),
            "{what}: {err}"
        );
    }
}

#[test]
fn damaged_and_missing_motion_files_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let good = GOOD;
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    let damaged = write(dir.path(), "cut.bvh", &good[..200]);
    for path in [damaged, dir.path().join("missing.bvh")] {
        let err = MotionSource::parse(path.to_str().unwrap())
            .unwrap()
            .load(&model, &shaped)
            .unwrap_err();
        assert!(
            err.to_string()
                .contains(path.file_name().unwrap().to_str().unwrap()),
            "{err}"
        );
    }
    let err = MotionSource::parse("clip.bvh:speed=2")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("unknown parameter 'speed' (start, duration, map)"),
        "{err}"
    );
    let err = MotionSource::parse("clip.npz:map=x.toml")
        .unwrap_err()
        .to_string();
    assert!(err.contains("(start, duration)"), "{err}");
}
