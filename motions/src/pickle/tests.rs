//! The pickle machine on files NumPy wrote (tools/make_pickle_fixtures.py) and on damage.

use super::*;

fn fixture(name: &str) -> Vec<u8> {
    let path = format!(
        "{}/tests/fixtures/pickle/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The formula of tools/make_pickle_fixtures.py, frame 0.
fn expect_frame(v: &Value, tolerance: f64) {
    let array = |key: &str| match v.get(key) {
        Some(Value::Array(a)) => a.clone(),
        other => panic!("{key}: {other:?}"),
    };
    let close = |a: &[f64], b: &[f64]| {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= tolerance, "{x} against {y}");
        }
    };
    let s = 0.01;
    let orient: Vec<f64> = (1..4).map(|i| i as f64 * s).collect();
    close(&array("global_orient").data, &orient);
    let pose: Vec<f64> = (1..70).map(|i| i as f64 * s * 0.1).collect();
    close(&array("body_pose").data, &pose);
    close(&array("transl").data, &[0.11, 0.91, -0.19]);
    let betas = array("betas");
    assert_eq!(betas.shape, vec![1, 10]);
    close(
        &betas.data,
        &(1..11).map(|i| i as f64 * -0.1).collect::<Vec<_>>(),
    );
}

#[test]
fn numpy_arrays_of_every_protocol_and_numpy_version_are_read() {
    for name in [
        "frame_p2_f64.pkl",
        "frame_p2_numpy1.pkl",
        "frame_p5_f64.pkl",
    ] {
        expect_frame(&read(&fixture(name)).unwrap(), 1e-12);
    }
    let f32 = read(&fixture("take/SMPL/mesh-f00011_smpl.pkl")).unwrap();
    expect_frame(&f32, 1e-6);
}

#[test]
fn a_fortran_ordered_array_comes_back_in_c_order() {
    let mesh = read(&fixture("mesh_fortran.pkl")).unwrap();
    let Some(Value::Array(v)) = mesh.get("vertices") else {
        panic!("{mesh:?}")
    };
    assert_eq!(v.shape, vec![4, 3]);
    let expected: Vec<f64> = (0..12).map(|i| i as f64 * 0.5).collect();
    assert_eq!(v.data, expected);
    let Some(Value::Array(f)) = mesh.get("faces") else {
        panic!("{mesh:?}")
    };
    assert_eq!(f.data, vec![0.0, 1.0, 2.0, 0.0, 2.0, 3.0]);
}

#[test]
fn code_is_refused_naming_what_it_would_call() {
    let e = read(&fixture("hostile_system.pkl")).unwrap_err();
    assert!(e.contains("calls os.system"), "{e}");
    let e = read(&fixture("hostile_torch.pkl")).unwrap_err();
    assert!(e.contains("calls torch._utils._rebuild_tensor_v2"), "{e}");
}

#[test]
fn damaged_files_are_errors_not_panics() {
    let good = fixture("frame_p5_f64.pkl");
    for cut in [0, 1, 5, 40, 100, good.len() - 1] {
        assert!(read(&good[..cut]).is_err(), "cut at {cut}");
    }
    // A length announcing far more than the file holds.
    let e = read(b"\x80\x04\x8e\xff\xff\xff\xff\xff\xff\xff\x7f.").unwrap_err();
    assert!(e.contains("announced"), "{e}");
    // Deep nesting is bounded, when read out and when built.
    let nested = |n: usize| {
        let mut deep = b"\x80\x02".to_vec();
        deep.extend(std::iter::repeat_n(b']', n));
        deep.extend(std::iter::repeat_n(b'a', n - 1));
        deep.push(b'.');
        read(&deep).unwrap_err()
    };
    assert!(nested(200).contains("nested deeper"));
    assert!(nested(1_000_000).contains("more than 4096 lists"));
    // Every single-byte change either reads or errs; none panics.
    for at in 0..good.len() {
        let mut bad = good.clone();
        bad[at] ^= 0x5a;
        let _ = read(&bad);
    }
}
