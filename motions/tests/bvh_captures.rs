//! CMU's real motion-capture clips (Debian's assimp-testmodels) retarget to an upright body
//! on the floor whose bones point where the capture's do, and a clip of another skeleton
//! retargets through the Biovision joint map.

use motions::bvh::{Bvh, JointMap, retarget};
use motions::{BodyModel, MotionSource, ShapedBody};
use nalgebra::Vector3;
use testkit::cmu_clip;

/// A clip of Debian's assimp-testmodels loaded as a motion on the default body (`None`, the
/// skip recorded, where the package is not installed).
fn load_clip(test: &str, name: &str) -> Option<(BodyModel, ShapedBody, motions::LoadedMotion)> {
    let path = cmu_clip(test, name)?;
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    let loaded = MotionSource::parse(path.to_str().unwrap())
        .unwrap()
        .load(&model, &shaped)
        .unwrap();
    Some((model, shaped, loaded))
}

#[test]
fn cmu_01_01_retargets_to_an_upright_body_on_the_floor() {
    let Some((model, shaped, loaded)) = load_clip(
        "cmu_01_01_retargets_to_an_upright_body_on_the_floor",
        "01_01.bvh",
    ) else {
        return;
    };
    let (motion, report) = (&loaded.motion, loaded.retarget.as_ref().unwrap());
    assert_eq!(motion.len(), 688);
    assert!(
        (motion.duration() - 22.9).abs() < 0.01,
        "{}",
        motion.duration()
    );
    assert_eq!((report.source_frames, report.map.as_str()), (2752, "cmu"));
    assert!((report.source_fps - 120.0).abs() < 0.01);
    assert!(
        report.reference_frame_dropped,
        "cgspeed's first frame is a T-pose"
    );
    assert_eq!(report.mapped.len(), 24);
    for dropped in ["LHipJoint", "RHipJoint", "Neck1", "LThumb", "RThumb"] {
        assert!(
            report.dropped.iter().any(|d| d == dropped),
            "{dropped}: {:?}",
            report.dropped
        );
    }
    // Near CMU's nominal 0.056444 m per unit, scaled to the default body's legs.
    assert!(
        (0.045..0.065).contains(&report.metres_per_unit),
        "{}",
        report.metres_per_unit
    );
    let posed = model.pose_batch(&shaped, &motion.frames).unwrap();
    for (k, body) in posed.iter().enumerate() {
        let y = |j: usize| body.joints[j][1];
        let feet = [7, 8, 10, 11]
            .map(y)
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        assert!(
            y(15) > y(0) && y(0) > feet,
            "frame {k}: head {} pelvis {} feet {feet}",
            y(15),
            y(0)
        );
        let (lo, hi) = body
            .vertices
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), v| {
                (lo.min(v[1]), hi.max(v[1]))
            });
        assert!(
            (1.2..=2.1).contains(&(hi - lo)),
            "frame {k}: {} m tall",
            hi - lo
        );
        let lowest_joint = (0..24).min_by(|&a, &b| y(a).total_cmp(&y(b))).unwrap();
        assert!(
            [7, 8, 10, 11].contains(&lowest_joint),
            "frame {k}: lowest joint {lowest_joint}"
        );
    }
    let first_lowest = posed[0]
        .vertices
        .iter()
        .map(|v| v[1])
        .fold(f64::INFINITY, f64::min);
    assert!(first_lowest.abs() < 1e-9);
}

/// In every frame at the capture's rate, each SMPL limb bone points where the capture's bone
/// points (so no limb is folded beyond what the capture shows): within 0.01 degrees where no
/// dropped joint sits between the two ends, within 30 where one does (the palm, through
/// `LeftFingerBase`'s parent). The trunk is aligned as a whole (SMPL's spine curves and its
/// neck-to-head bone leans about 38 degrees forward at rest; CMU's are straight and upright),
/// so its bones follow the capture's more loosely: within 45 degrees.
#[test]
fn cmu_bones_point_where_the_capture_points() {
    let model = BodyModel::default_body();
    let shaped = model.shape(&[]).unwrap();
    for name in ["01_01.bvh", "01_03.bvh"] {
        let Some(path) = cmu_clip("cmu_bones_point_where_the_capture_points", name) else {
            return;
        };
        let bvh = Bvh::load(&path).unwrap();
        let map = JointMap::builtin_for(&bvh).unwrap();
        let retargeted = retarget(&bvh, &map, &shaped).unwrap();
        let k = map.bvh_joint;
        // The bones that fix each joint's rest alignment (joint, its child along the limb).
        const BONES: [(usize, usize); 18] = [
            (1, 4),
            (2, 5),
            (3, 6),
            (4, 7),
            (5, 8),
            (6, 9),
            (7, 10),
            (8, 11),
            (9, 12),
            (12, 15),
            (13, 16),
            (14, 17),
            (16, 18),
            (17, 19),
            (18, 20),
            (19, 21),
            (20, 22),
            (21, 23),
        ];
        const TRUNK: [usize; 4] = [3, 6, 9, 12];
        let bones: Vec<(usize, usize, f64)> = BONES
            .into_iter()
            .filter_map(|(j, d)| {
                let (a, b) = (k[j]?, k[d]?);
                let limit = match (TRUNK.contains(&j), bvh.joints[b].parent == Some(a)) {
                    (true, _) => 45.0,
                    (false, true) => 0.01,
                    (false, false) => 30.0,
                };
                (bvh.rest_positions()[b] - bvh.rest_positions()[a])
                    .norm()
                    .gt(&1e-9)
                    .then_some((j, d, limit))
            })
            .collect();
        assert!(bones.len() >= 17, "{name}: {} bones", bones.len());
        let skipped = usize::from(retargeted.report.reference_frame_dropped);
        let mut worst = [0.0f64; 24];
        for (f, frame) in retargeted.motion.frames.iter().enumerate().step_by(7) {
            let (_, capture) = bvh.pose(f + skipped);
            let body = model.pose(&shaped, frame).unwrap();
            for &(j, d, limit) in &bones {
                let smpl = Vector3::from(body.joints[d]) - Vector3::from(body.joints[j]);
                let cap = capture[k[d].unwrap()] - capture[k[j].unwrap()];
                let angle = smpl.angle(&cap).to_degrees();
                assert!(
                    angle < limit,
                    "{name} frame {f}: bone {j}->{d} off by {angle:.3} deg"
                );
                worst[j] = worst[j].max(angle);
            }
        }
        eprintln!("{name}: worst bone direction difference per joint {worst:.2?} deg");
    }
}

/// The package's BioVision-style clip (`LeftShoulder` is the upper arm there; one frame more
/// than its header announces) retargets through the `biovision` map to an upright body.
#[test]
fn boxing_toes_retargets_through_the_biovision_map() {
    let Some((model, shaped, loaded)) = load_clip(
        "boxing_toes_retargets_through_the_biovision_map",
        "Boxing_Toes.bvh",
    ) else {
        return;
    };
    let report = loaded.retarget.unwrap();
    assert_eq!(
        (
            report.map.as_str(),
            report.mapped.len(),
            report.source_frames
        ),
        ("biovision", 21, 3069)
    );
    assert!(
        report
            .mapped
            .contains(&("left_shoulder", "LeftShoulder".to_string()))
    );
    for frame in loaded.motion.frames.iter().step_by(50) {
        let body = model.pose(&shaped, frame).unwrap();
        let y = |j: usize| body.joints[j][1];
        assert!(y(15) > y(0) && y(0) > y(7).min(y(8)));
    }
}
