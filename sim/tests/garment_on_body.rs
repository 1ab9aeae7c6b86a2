//! A garment rides a walking and a jumping body without falling through or falling off: the
//! built-in skirt (waistband attached) on the default body, penetration at most 1 cm.

use motions::BodyModel;
use motions::library::MotionSpec;
use sim::scene::{Scene, builtin_template};
use sim::{SceneConfig, SolverParams};

/// The built-in skirt with `skirt` proportions on the default body through `motion`.
fn skirt_scene(
    model: &BodyModel,
    skirt: &garments::SkirtParams,
    motion: &str,
    betas: &[f64],
    params: SolverParams,
) -> Scene {
    let (garment, attachments) = builtin_template(model, "skirt", skirt).unwrap();
    let shaped = model.shape(betas).unwrap();
    let motion = MotionSpec::parse(motion)
        .unwrap()
        .generate(model, &shaped)
        .unwrap();
    let config = SceneConfig {
        garment: "skirt".into(),
        motion: motion.name.clone(),
        betas: betas.to_vec(),
        blend_frames: 15,
        settle_frames: 5,
        solver: params,
        ..SceneConfig::default()
    };
    let template = (garment.positions, garment.triangles);
    Scene::new(
        config.validated().unwrap(),
        template,
        attachments,
        motion,
        model,
    )
    .unwrap()
}

fn ride(motion: &str, betas: &[f64]) -> (f64, f64, f64) {
    let model = BodyModel::default_body();
    let params = garments::SkirtParams::default();
    let solver = SolverParams {
        substeps: 2,
        max_iterations: 10,
        ..SolverParams::default()
    };
    let scene = skirt_scene(&model, &params, motion, betas, solver);
    let mut lowest_top: f64 = f64::INFINITY;
    let mut waist_drop: f64 = 0.0;
    let summary = scene
        .run(&model, |frame| {
            let top = frame.garment[..params.columns]
                .iter()
                .map(|p| p[1])
                .fold(f64::INFINITY, f64::min);
            lowest_top = lowest_top.min(top - frame.pose.transl[1]);
            let pelvis = frame.body.joints[0][1];
            waist_drop = waist_drop.max(pelvis - top);
            Ok(())
        })
        .unwrap();
    assert!(summary.finite);
    (
        summary.max_penetration_m,
        waist_drop,
        summary.max_edge_stretch,
    )
}

#[test]
fn skirt_rides_a_walk() {
    let (depth, drop, stretch) = ride("walk:duration=1.5", &[]);
    assert!(
        depth <= 0.01,
        "max penetration {:.1} mm (limit 10 mm)",
        depth * 1e3
    );
    assert!(
        drop < 0.15,
        "waistband {drop:.3} m below the pelvis joint: the skirt slid off"
    );
    assert!(stretch < 1.3, "max edge stretch {stretch:.3}");
}

#[test]
fn skirt_rides_jumping_jacks_on_a_larger_body() {
    let (depth, drop, stretch) = ride("jumping_jacks:duration=1.5", &[1.5, 1.0]);
    assert!(
        depth <= 0.01,
        "max penetration {:.1} mm (limit 10 mm)",
        depth * 1e3
    );
    assert!(
        drop < 0.15,
        "waistband {drop:.3} m below the pelvis joint: the skirt slid off"
    );
    assert!(stretch < 1.3, "max edge stretch {stretch:.3}");
}

/// An ankle-length skirt (85 cm, the legs swing inside it) on one second of walking (one walk
/// cycle) at the garment default 4 x 16: the most crossing triangle pairs of a frame, with self-contact on or off.
fn long_skirt_walk(self_contact: bool) -> usize {
    let model = BodyModel::default_body();
    let params = garments::SkirtParams {
        length: 0.85,
        rings: 77,
        ..garments::SkirtParams::default()
    };
    let solver = SolverParams {
        substeps: 4,
        max_iterations: 16,
        self_contact,
        ..SolverParams::default()
    };
    let scene = skirt_scene(&model, &params, "walk:duration=1", &[], solver);
    scene
        .run(&model, |_| Ok(()))
        .unwrap()
        .max_self_intersections
}

/// The target is (near) zero. Measured over two walk cycles: 6 crossing pairs (of 17,000
/// triangles) with self-contact against 245 without (docs/PHYSICS.md, self-contact); over the
/// one cycle here 0 against 254 (half a cycle crosses nothing either way); without the extra
/// iterations for steps whose layers would cross it was 58: the legs pinch the panels between
/// them and the unconverged iteration lets them through.
#[test]
fn self_contact_keeps_a_long_skirt_on_a_walking_body_from_passing_through_itself() {
    let on = long_skirt_walk(true);
    let off = long_skirt_walk(false);
    eprintln!("most crossing triangle pairs in a frame: {on} with self-contact, {off} without");
    assert!(
        on <= 20 && 10 * on < off,
        "{on} with self-contact, {off} without"
    );
}

/// One frame of a run: the garment's vertices, its deepest penetration (m), its retries.
type FrameRecord = (Vec<[f64; 3]>, f64, usize);

/// Every frame of the skirt on a short walk and the frames the run retried.
fn walk_frames(max_penetration_jump: f64) -> (Vec<FrameRecord>, usize) {
    let model = BodyModel::default_body();
    let solver = SolverParams {
        substeps: 1,
        max_iterations: 6,
        max_retries: 1,
        max_penetration_jump,
        ..SolverParams::default()
    };
    let skirt = garments::SkirtParams::default();
    let scene = skirt_scene(&model, &skirt, "walk:duration=1", &[], solver);
    let mut frames = Vec::new();
    let summary = scene
        .run(&model, |f| {
            let depth = f.stats.max_penetration_m;
            frames.push((f.garment.to_vec(), depth, f.stats.solver.retries));
            Ok(())
        })
        .unwrap();
    (frames, summary.retried_frames)
}

/// A frame that takes the cloth deeper into the body than `max_penetration_jump` allows is
/// run again with twice the substeps, and the shallower attempt is kept (the soft-cloth
/// blow-up's fix, docs/BENCHMARKS.md). A 0.1 mm limit makes any deepening frame a retry:
/// everything before the first kept retry is the same as with the check off, and that frame
/// is shallower than the unchecked one.
#[test]
fn a_frame_that_deepens_the_penetration_too_much_is_run_again_finer() {
    let (off, off_retried) = walk_frames(0.0);
    let (on, on_retried) = walk_frames(1e-4);
    assert_eq!(off_retried, 0, "frames retried with the check off");
    assert!(on_retried > 0, "no frame was retried under a 0.1 mm limit");
    let changed = (0..on.len())
        .find(|&k| on[k] != off[k])
        .expect("no retry was kept");
    assert_eq!(on[changed].2, 1, "frame {changed} changed without a retry");
    assert!(
        on[changed].1 < off[changed].1,
        "frame {changed}: the kept retry is {:.2} mm deep, the first attempt {:.2} mm",
        on[changed].1 * 1e3,
        off[changed].1 * 1e3
    );
}
