//! The forward pass reproduces the public smplx package's outputs (../shared/testdata/
//! smplx_reference, 12 cases, float64) within 1e-7 m. Skipped with a message when ../shared is
//! absent; `forward_pass.rs` covers the pass without it.

use std::path::PathBuf;

use motions::npz::Npz;
use motions::{BodyModel, FramePose};

fn reference_dir() -> Option<PathBuf> {
    let dir =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/testdata/smplx_reference");
    dir.join("smplx_reference.npz").exists().then_some(dir)
}

#[test]
fn forward_pass_matches_smplx_reference_cases() {
    let dir = reference_dir();
    if !testkit::available(
        "smplx_reference::forward_pass_matches_smplx_reference_cases",
        "SHARED",
        dir.is_some(),
        "../shared/testdata/smplx_reference not found",
    ) {
        return;
    }
    let dir = dir.expect("checked above");
    let model = BodyModel::load(&dir.join("SMPL_NEUTRAL.npz")).unwrap();
    let mut reference = Npz::open(&dir.join("smplx_reference.npz")).unwrap();
    let cases = reference.numeric("num_cases").unwrap().unwrap().data[0] as usize;
    assert_eq!(cases, 12);
    let mut worst: f64 = 0.0;
    for k in 0..cases {
        let mut get = |name: &str| {
            reference
                .numeric(&format!("case{k}_{name}"))
                .unwrap()
                .unwrap()
                .data
        };
        let betas = get("betas");
        let full_pose = get("full_pose");
        let transl = get("transl");
        let want_vertices = get("vertices");
        let want_joints = get("joints");
        let want_g = get("G");
        let shaped = model.shape(&betas).unwrap();
        let frame = FramePose {
            pose: full_pose.try_into().unwrap(),
            transl: transl.clone().try_into().unwrap(),
        };
        let posed = model.pose(&shaped, &frame).unwrap();
        let dv = posed
            .vertices
            .iter()
            .flatten()
            .zip(&want_vertices)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let dj = posed
            .joints
            .iter()
            .flatten()
            .zip(&want_joints)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        // G (no translation in smplx's intermediates): rotation and joint position.
        let mut dg: f64 = 0.0;
        for (j, t) in posed.transforms.iter().enumerate() {
            for r in 0..3 {
                for c in 0..3 {
                    dg = dg.max((t.rotation[(r, c)] - want_g[j * 16 + r * 4 + c]).abs());
                }
                dg = dg.max((t.translation[r] - transl[r] - want_g[j * 16 + r * 4 + 3]).abs());
            }
        }
        println!("case {k}: max |dv| {dv:.2e} m, |dj| {dj:.2e} m, |dG| {dg:.2e}");
        assert!(
            dv < 1e-7 && dj < 1e-7 && dg < 1e-7,
            "case {k}: vertices {dv:e}, joints {dj:e}, G {dg:e} (tolerance 1e-7 m)"
        );
        worst = worst.max(dv).max(dj);
    }
    println!("worst deviation over 12 cases: {worst:.2e} m (tolerance 1e-7)");
}
