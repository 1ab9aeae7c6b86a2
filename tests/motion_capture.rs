//! CMU's real motion capture (Debian's assimp-testmodels) through the command line: `motions
//! show` and `export`, `body --motion --frame`, and a library top simulated through a stretch
//! of `01_01`. Skipped with a printed reason where the clips are not installed; `.ci/run`
//! installs them and then requires these tests.

mod common;

use std::path::{Path, PathBuf};

use common::{json, ok};

fn cmu_clip(test: &str) -> Option<PathBuf> {
    testkit::cmu_clip(test, "01_01.bvh")
}

#[test]
fn cmu_01_01_shows_poses_an_upright_body_and_exports_as_amass() {
    let Some(clip) =
        cmu_clip("motion_capture::cmu_01_01_shows_poses_an_upright_body_and_exports_as_amass")
    else {
        return;
    };
    let clip = clip.to_str().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let shown = dir.path().join("show.json");
    let text = ok(&["motions", "show", clip, "--json", shown.to_str().unwrap()]);
    assert!(
        text.contains("mapped") && text.contains("dropped"),
        "{text}"
    );
    let j = json(&shown);
    assert_eq!(j["frames"], 688);
    assert_eq!(j["fps"], 30.0);
    assert!(
        (j["duration_s"].as_f64().unwrap() - 22.9).abs() < 0.01,
        "{j}"
    );
    assert_eq!(j["source"]["frames"], 2752);
    assert_eq!(j["mapped_joints"].as_object().unwrap().len(), 24);
    assert_eq!(j["mapped_joints"]["left_elbow"], "LeftForeArm");
    let dropped: Vec<&str> = j["dropped_joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    for joint in ["LHipJoint", "Neck1", "LThumb"] {
        assert!(dropped.contains(&joint), "{joint}: {dropped:?}");
    }

    an_upright_body_at_every_tenth_frame(clip, dir.path());
    a_stretch_exported_as_amass_reads_back_the_same(clip, dir.path());
}

/// An upright person at every tenth frame of the clip, the last included: posed here the way
/// `body --motion --frame` poses it (the last frame through the command too, which must agree);
/// a frame past the end is refused.
fn an_upright_body_at_every_tenth_frame(clip: &str, dir: &Path) {
    let model = sim::sources::body_model(None).unwrap();
    let shaped = model.shape(&[]).unwrap();
    let motion = sim::sources::motion(clip, &model, &shaped).unwrap();
    assert_eq!(motion.len(), 688);
    for frame in (0..688).step_by(10).chain([687]) {
        let posed = model.pose(&shaped, &motion.frames[frame]).unwrap();
        let y = |j: usize| posed.joints[j][1];
        let feet = [7, 8, 10, 11]
            .map(y)
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        assert!(
            y(15) > y(0) && y(0) > feet,
            "frame {frame}: head {} pelvis {} feet {feet}",
            y(15),
            y(0)
        );
        let height = posed.height();
        assert!((1.2..=2.1).contains(&height), "frame {frame}: {height} m");
    }

    let out = dir.join("body_687.json");
    ok(&[
        "body",
        "--motion",
        clip,
        "--frame",
        "687",
        "--json",
        out.to_str().unwrap(),
    ]);
    let b = json(&out);
    let posed = model.pose(&shaped, &motion.frames[687]).unwrap();
    for (j, joint) in posed.joints.iter().enumerate() {
        for (k, value) in joint.iter().enumerate() {
            let written = b["joints"][j][k].as_f64().unwrap();
            assert!(
                (written - value).abs() < 1e-9,
                "joint {j}[{k}]: {written} vs {value}"
            );
        }
    }
    assert!((b["posed_height_m"].as_f64().unwrap() - posed.height()).abs() < 1e-9);
    let past = common::fails(&[
        "body", "--motion", clip, "--frame", "688", "--json", "x.json",
    ]);
    assert!(past.contains("past the end"), "{past}");
}

/// A stretch exported as AMASS-style .npz reads back as the same motion.
fn a_stretch_exported_as_amass_reads_back_the_same(clip: &str, dir: &Path) {
    let stretch = format!("{clip}:start=5,duration=2");
    let npz = dir.join("stretch.npz");
    ok(&[
        "motions",
        "export",
        &stretch,
        "--out",
        npz.to_str().unwrap(),
    ]);
    let (a, b) = (dir.join("a.json"), dir.join("b.json"));
    ok(&["motions", "show", &stretch, "--json", a.to_str().unwrap()]);
    ok(&[
        "motions",
        "show",
        npz.to_str().unwrap(),
        "--json",
        b.to_str().unwrap(),
    ]);
    let (a, b) = (json(&a), json(&b));
    assert_eq!(
        (a["frames"].clone(), b["frames"].clone()),
        (60.into(), 60.into())
    );
    for k in 0..3 {
        let (ta, tb) = (
            a["root_travel_m"][k].as_f64().unwrap(),
            b["root_travel_m"][k].as_f64().unwrap(),
        );
        assert!((ta - tb).abs() < 1e-9, "axis {k}: {ta} vs {tb}");
    }
    for j in 0..22 {
        let (ra, rb) = (
            a["max_joint_angle_deg"][j].as_f64().unwrap(),
            b["max_joint_angle_deg"][j].as_f64().unwrap(),
        );
        assert!((ra - rb).abs() < 1e-6, "joint {j}: {ra} vs {rb}");
    }
}

/// A library top through two seconds of `01_01` (jumps and a turn): the gates hold and the
/// cloth stays within 10 mm of the body's surface.
#[test]
fn a_top_simulates_through_cmu_01_01() {
    let Some(clip) = cmu_clip("motion_capture::a_top_simulates_through_cmu_01_01") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let stats = dir.path().join("stats.json");
    let motion = format!("{}:start=6,duration=2", clip.display());
    ok(&[
        "simulate",
        "--garment",
        "tank_tight",
        "--motion",
        &motion,
        "--blend-frames",
        "15",
        "--settle-frames",
        "10",
        "--out",
        dir.path().join("seq.mcap").to_str().unwrap(),
        "--json",
        stats.to_str().unwrap(),
        "--quiet",
    ]);
    let j = json(&stats);
    assert_eq!(j["finite"], true, "{j}");
    assert_eq!(j["frames"], 85, "{j}");
    let depth = j["max_penetration_m"].as_f64().unwrap();
    assert!(depth <= 0.010, "{depth} m into the body: {j}");
    assert!(j["max_edge_stretch"].as_f64().unwrap() < 1.5, "{j}");
}

/// A dataset spec that trains on one stretch of `01_01` and holds another out: both
/// synthesize, under their stretch's name, and a stretch past the clip's end is refused
/// before the folder is made.
#[test]
fn stretches_of_a_clip_are_dataset_motions() {
    let Some(clip) = cmu_clip("motion_capture::stretches_of_a_clip_are_dataset_motions") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let spec = |variants: &str| {
        format!(
            r#"
name = "cmu"
seed = 3
[sequence]
frames = 20
blend_frames = 10
settle_frames = 4
shapes_per_motion = 1
draws_per_shape = 1
[solver]
substeps = 2
max_iterations = 8
[[garments]]
name = "skirt"
split = "train"
[[motions]]
source = "{clip}"
variants = [{variants}]
split = "train"
[[motions]]
source = "{clip}:start=12,duration=1"
split = "test"
[splits]
test_motion = 1
"#,
            clip = clip.display()
        )
    };
    let path = dir.path().join("spec.toml");
    std::fs::write(&path, spec(r#""start=0,duration=1""#)).unwrap();
    let out = dir.path().join("data");
    ok(&[
        "synth",
        "--spec",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let lines = common::jsonl(&out.join("manifest.jsonl"));
    assert_eq!(lines.len(), 2);
    let motions: Vec<&str> = lines
        .iter()
        .map(|l| l["motion"].as_str().unwrap())
        .collect();
    assert!(
        motions
            .iter()
            .any(|m| m.ends_with("01_01.bvh:start=0,duration=1")),
        "{motions:?}"
    );
    assert!(
        motions
            .iter()
            .any(|m| m.ends_with("01_01.bvh:start=12,duration=1")),
        "{motions:?}"
    );
    assert!(lines.iter().all(|l| l["status"] == "ok"), "{lines:?}");

    std::fs::write(&path, spec(r#""start=22,duration=3""#)).unwrap();
    let refused = dir.path().join("refused");
    let err = common::fails(&[
        "synth",
        "--spec",
        path.to_str().unwrap(),
        "--out",
        refused.to_str().unwrap(),
    ]);
    assert!(
        err.contains("start=22") && err.contains("past the end"),
        "{err}"
    );
    assert!(!refused.exists());
}

/// The shipped surrogate poses a garment through a stretch of the capture.
#[test]
fn the_shipped_model_predicts_through_cmu_01_01() {
    let Some(clip) = cmu_clip("motion_capture::the_shipped_model_predicts_through_cmu_01_01")
    else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let stats = dir.path().join("predict.json");
    let motion = format!("{}:start=6,duration=0.5", clip.display());
    ok(&[
        "predict",
        "--model",
        "builtin-single",
        "--garment",
        "tank_tight",
        "--motion",
        &motion,
        "--blend-frames",
        "3",
        "--settle-frames",
        "2",
        "--out",
        dir.path().join("p.mcap").to_str().unwrap(),
        "--json",
        stats.to_str().unwrap(),
        "--quiet",
    ]);
    let j = json(&stats);
    assert_eq!(j["frames"], 20, "{j}");
    assert_eq!(j["finite"], true, "{j}");
}

/// 4D-Dress-style SMPL fits (one pickle per frame, written by NumPy) as a motion: shown, posed
/// and exported as AMASS; a pickle that would run a command is refused naming the callable.
#[test]
fn pickled_smpl_fits_are_a_motion_and_code_in_a_pickle_is_refused() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("motions/tests/fixtures/pickle");
    let take = fixtures.join("take/SMPL");
    let dir = tempfile::tempdir().unwrap();
    let shown = dir.path().join("show.json");
    let arg = format!("{}:fps=15", take.display());
    ok(&["motions", "show", &arg, "--json", shown.to_str().unwrap()]);
    let j = json(&shown);
    // Three fits at 15 fps, resampled to 30 fps: five frames.
    assert_eq!(
        (j["frames"].clone(), j["fps"].clone()),
        (5.into(), 30.0.into()),
        "{j}"
    );
    let npz = dir.path().join("fits.npz");
    ok(&["motions", "export", &arg, "--out", npz.to_str().unwrap()]);
    let hostile = fixtures.join("hostile_system.pkl");
    let e = common::fails(&["motions", "show", hostile.to_str().unwrap()]);
    assert!(
        e.contains("hostile_system.pkl") && e.contains("calls os.system"),
        "{e}"
    );
}
