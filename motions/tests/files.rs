//! Model and AMASS files written by the test with known content: conversion (SMPL-24 from
//! poses[:, :66], z-up to y-up, time resampling) and clear errors for malformed files.

use std::path::Path;

use motions::npz::{Npz, write_array, write_text};
use motions::{BodyModel, Error};
use npyz::WriterBuilder;
use npyz::npz::NpzWriter;

enum Value<'a> {
    F64(&'a [usize], Vec<f64>),
    F32(&'a [usize], Vec<f32>),
    Text(&'a str),
}

fn write_npz(path: &Path, arrays: &[(&str, Value)]) {
    let mut npz = NpzWriter::create(path).unwrap();
    let dims = |shape: &[usize]| shape.iter().map(|&s| s as u64).collect::<Vec<u64>>();
    for (name, value) in arrays {
        match value {
            Value::F64(shape, data) => write_array(&mut npz, name, &dims(shape), data),
            Value::F32(shape, data) => write_array(&mut npz, name, &dims(shape), data),
            Value::Text(text) => write_text(&mut npz, name, text),
        }
        .unwrap();
    }
    npz.zip_writer().finish().unwrap();
}

fn amass_file(path: &Path, frames: usize, fps: f64, rate_key: &str) -> Vec<f64> {
    let mut poses = vec![0.0; frames * 156];
    for k in 0..frames {
        let t = k as f64 / fps;
        poses[k * 156] = 0.5 * t; // root about x (z-up frame)
        poses[k * 156 + 3 * 18] = t; // left elbow about x
        poses[k * 156 + 66] = 9.0; // a finger joint: must not leak into the SMPL hands
    }
    let trans: Vec<f64> = (0..frames)
        .flat_map(|k| [0.1 * k as f64 / fps, 0.2, 1.0])
        .collect();
    write_npz(
        path,
        &[
            ("poses", Value::F64(&[frames, 156], poses.clone())),
            (
                "trans",
                Value::F32(&[frames, 3], trans.iter().map(|&v| v as f32).collect()),
            ),
            ("betas", Value::F64(&[16], vec![0.1; 16])),
            ("gender", Value::Text("female")),
            (rate_key, Value::F64(&[], vec![fps])),
        ],
    );
    poses
}

#[test]
fn amass_motion_is_converted_and_resampled_by_time() {
    let dir = tempfile::tempdir().unwrap();
    for (fps, key) in [
        (120.0, "mocap_framerate"),
        (100.0, "mocap_frame_rate"),
        (60.0, "mocap_framerate"),
    ] {
        let path = dir.path().join(format!("seq_{fps}.npz"));
        amass_file(&path, (2.0 * fps) as usize + 1, fps, key);
        let j0 = [0.0, -0.2, 0.03];
        let raw = motions::amass::load(&path, j0).unwrap();
        assert_eq!(raw.fps, fps);
        assert_eq!(raw.gender.as_deref(), Some("female"));
        assert_eq!(raw.betas.as_ref().map(Vec::len), Some(16));
        let m = raw.resample(30.0).unwrap();
        assert_eq!(m.len(), 61, "{fps} fps: 2 s at 30 fps");
        for (k, f) in m.frames.iter().enumerate() {
            let t = k as f64 / 30.0;
            // Root: Rx(-90) * Rx(0.5 t) = Rx(0.5 t - pi/2).
            assert!(
                (f.pose[0] - (0.5 * t - std::f64::consts::FRAC_PI_2)).abs() < 1e-6,
                "{fps} fps frame {k}: root {:?}",
                &f.pose[..3]
            );
            assert!((f.pose[54] - t).abs() < 1e-6, "elbow");
            assert!(
                f.pose[66..].iter().all(|&v| v == 0.0),
                "SMPL hands must be zero, not fingers"
            );
            // trans' = R (trans + J0) - J0 with R = Rx(-90): (x, y, z) -> (x, z, -y).
            let src = [0.1 * t, 0.2, 1.0];
            let want = [src[0], src[2] + j0[2] - j0[1], -(src[1] + j0[1]) - j0[2]];
            for (c, (got, want)) in f.transl.iter().zip(want).enumerate() {
                assert!(
                    (got - want).abs() < 1e-5,
                    "{fps} fps frame {k} axis {c}: {got} vs {want}"
                );
            }
        }
    }
}

#[test]
fn malformed_amass_files_get_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let no_rate = dir.path().join("no_rate.npz");
    write_npz(
        &no_rate,
        &[
            ("poses", Value::F64(&[2, 156], vec![0.0; 312])),
            ("trans", Value::F64(&[2, 3], vec![0.0; 6])),
        ],
    );
    let err = motions::amass::load(&no_rate, [0.0; 3])
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("no_rate.npz") && err.contains("mocap_framerate"),
        "{err}"
    );

    let empty = dir.path().join("empty.npz");
    write_npz(
        &empty,
        &[
            ("poses", Value::F64(&[0, 156], vec![])),
            ("trans", Value::F64(&[0, 3], vec![])),
            ("mocap_framerate", Value::F64(&[], vec![120.0])),
        ],
    );
    let err = motions::amass::load(&empty, [0.0; 3])
        .unwrap_err()
        .to_string();
    assert!(err.contains("empty"), "{err}");

    let nan = dir.path().join("nan.npz");
    let mut poses = vec![0.0; 312];
    poses[7] = f64::NAN;
    write_npz(
        &nan,
        &[
            ("poses", Value::F64(&[2, 156], poses)),
            ("trans", Value::F64(&[2, 3], vec![0.0; 6])),
            ("mocap_framerate", Value::F64(&[], vec![120.0])),
        ],
    );
    let err = motions::amass::load(&nan, [0.0; 3])
        .unwrap_err()
        .to_string();
    assert!(err.contains("non-finite"), "{err}");

    let bad_rate = dir.path().join("bad_rate.npz");
    write_npz(
        &bad_rate,
        &[
            ("poses", Value::F64(&[2, 156], vec![0.0; 312])),
            ("trans", Value::F64(&[2, 3], vec![0.0; 6])),
            ("mocap_framerate", Value::F64(&[], vec![0.0])),
        ],
    );
    assert!(motions::amass::load(&bad_rate, [0.0; 3]).is_err());
}

/// The default body's arrays written as a plain SMPL-style npz, optionally spoiled.
fn write_model(path: &Path, spoil: &str) {
    let mut src = Npz::from_reader(
        std::io::Cursor::new(include_bytes!("../assets/default_body.npz").to_vec()),
        Path::new("default"),
    )
    .unwrap();
    let mut arrays = Vec::new();
    for key in [
        "v_template",
        "f",
        "shapedirs",
        "posedirs",
        "J_regressor",
        "weights",
        "kintree_table",
    ] {
        if key == spoil {
            continue;
        }
        let mut a = src.numeric(key).unwrap().unwrap();
        if spoil == "nan" && key == "weights" {
            a.data[5] = f64::NAN;
        }
        if spoil == "shape" && key == "J_regressor" {
            a.shape = vec![23, a.data.len() / 23];
            a.data.truncate(23 * (a.data.len() / 24));
            a.shape[1] = a.data.len() / 23;
        }
        arrays.push((key, a));
    }
    let values: Vec<(&str, Value)> = arrays
        .iter()
        .map(|(k, a)| (*k, Value::F64(&a.shape, a.data.clone())))
        .collect();
    write_npz(path, &values);
}

#[test]
fn model_file_round_trip_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("model.npz");
    write_model(&good, "");
    let loaded = BodyModel::load(&good).unwrap();
    let default = BodyModel::default_body();
    assert_eq!(loaded.num_vertices(), default.num_vertices());
    assert_eq!(loaded.template(), default.template());

    let missing = dir.path().join("missing.npz");
    write_model(&missing, "weights");
    let err = BodyModel::load(&missing).unwrap_err();
    assert!(
        matches!(err, Error::MissingKey { ref key, .. } if key == "weights"),
        "{err}"
    );
    assert!(err.to_string().contains("missing.npz"));

    let nan = dir.path().join("nan.npz");
    write_model(&nan, "nan");
    let err = BodyModel::load(&nan).unwrap_err().to_string();
    assert!(
        err.contains("weights") && err.contains("non-finite"),
        "{err}"
    );

    let shape = dir.path().join("shape.npz");
    write_model(&shape, "shape");
    let err = BodyModel::load(&shape).unwrap_err().to_string();
    assert!(
        err.contains("J_regressor") && err.contains("shape"),
        "{err}"
    );

    let pickle = dir.path().join("SMPL_NEUTRAL.pkl");
    std::fs::write(&pickle, [0x80, 0x02, b'}', b'q']).unwrap();
    let err = BodyModel::load(&pickle).unwrap_err().to_string();
    assert!(err.contains("pickle") && err.contains(".npz"), "{err}");

    let garbage = dir.path().join("garbage.npz");
    std::fs::write(&garbage, b"not a zip").unwrap();
    assert!(
        BodyModel::load(&garbage)
            .unwrap_err()
            .to_string()
            .contains("garbage.npz")
    );
}

/// Issue 27, item 4: a Fortran-order array (`np.asfortranarray`) was read as C order. Written
/// column-major, it must read back in C order: the 2 x 3 x 2 array a[i][j][k] = 100 i + 10 j + k.
#[test]
fn fortran_order_arrays_read_in_c_order() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fortran.npz");
    let value = |i: usize, j: usize, k: usize| (100 * i + 10 * j + k) as f64;
    // Column-major: the first index fastest.
    let mut column_major = Vec::new();
    for k in 0..2 {
        for j in 0..3 {
            for i in 0..2 {
                column_major.push(value(i, j, k));
            }
        }
    }
    {
        let mut npz = NpzWriter::create(&path).unwrap();
        npz.array::<f64>("a", Default::default())
            .unwrap()
            .default_dtype()
            .order(npyz::Order::Fortran)
            .shape(&[2, 3, 2])
            .begin_nd()
            .unwrap()
            .extend(column_major.iter().copied())
            .unwrap();
    }
    let mut npz = motions::npz::Npz::open(&path).unwrap();
    let a = npz.numeric("a").unwrap().unwrap();
    assert_eq!(a.shape, vec![2, 3, 2]);
    let mut expected = Vec::new();
    for i in 0..2 {
        for j in 0..3 {
            for k in 0..2 {
                expected.push(value(i, j, k));
            }
        }
    }
    assert_eq!(a.data, expected, "read as {:?}", a.data);
}

/// A frame rate that would size the resampled motion past memory (1e-6 fps: 342 GB at 30
/// fps) is refused by name, as is a resample to more frames than a motion may have.
#[test]
fn frame_rates_that_would_exhaust_memory_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("slow.npz");
    amass_file(&path, 3, 1e-6, "mocap_framerate");
    let err = motions::amass::load(&path, [0.0; 3])
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("slow.npz") && err.contains("mocap_framerate") && err.contains("1 to 1000"),
        "{err}"
    );
    let fine = dir.path().join("fine.npz");
    amass_file(&fine, 3, 1.0, "mocap_framerate");
    let motion = motions::amass::load(&fine, [0.0; 3]).unwrap();
    let err = motion.resample(1e6).unwrap_err().to_string();
    assert!(err.contains("more than the 108000"), "{err}");
}
