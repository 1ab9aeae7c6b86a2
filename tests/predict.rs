//! End-to-end: `predict` and `evaluate` as a user runs them with a model trained here on a
//! tiny dataset. A prediction's recording reads back through `sim::recording` and every tool
//! (`compare` scores it against the simulation of the same inputs, `render` draws it); the same
//! seed gives the same bytes; the JSON has its keys; bad inputs are named, exit 1, and leave
//! nothing at `--out`. `evaluate` ranks the UV floor below every other baseline, scores the
//! ground truth zero, writes its report and reuses its cache.

mod common;

use std::path::Path;
use std::sync::OnceLock;

use common::{TinyRun, fails, json, ok, tiny_config, tiny_run};
use sim::recording::Recording;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The dataset, its tensors (32 x 32, lbs_residual) and a trained run, made once.
fn fixture() -> &'static TinyRun {
    static FIXTURE: OnceLock<TinyRun> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        tiny_run(
            "predict-test",
            &["--body-nearest"],
            &tiny_config("body_nearest = true\n", ""),
        )
    })
}

fn predict(out: &Path, extra: &[&str]) -> String {
    let f = fixture();
    let mut args = vec![
        "predict",
        "--model",
        s(&f.run),
        "--config-from",
        s(&f.truth),
        "--out",
        s(out),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    ok(&args)
}

#[test]
fn a_prediction_is_a_recording_every_tool_reads_and_the_same_seed_gives_the_same_bytes() {
    let f = fixture();
    let dir = tempfile::tempdir().unwrap();
    let (out, report) = (dir.path().join("p.mcap"), dir.path().join("p.json"));
    let printed = predict(
        &out,
        &["--json", s(&report), "--steps", "3", "--batch", "5"],
    );
    assert!(printed.contains("predict: 'skirt'"), "{printed}");
    let j = json(&report);
    for key in [
        "frames",
        "finite",
        "frames_per_s",
        "wall_s",
        "steps",
        "guidance",
        "batch",
        "E_c_percent",
        "max_penetration_m",
        "vertices",
        "model",
    ] {
        assert!(!j[key].is_null(), "{key} missing from {j}");
    }
    assert_eq!(j["frames"], 12);
    assert_eq!(j["steps"], 3);
    assert_eq!(j["finite"], true);
    assert_eq!(j["template_seen_in_training"], true);

    // It reads back with the simulation's template and body poses, and the metadata says
    // what made it.
    let predicted = Recording::read(&out).unwrap();
    let truth = Recording::read(&f.truth).unwrap();
    assert_eq!(predicted.garment.len(), 12);
    assert_eq!(predicted.template.triangles, truth.template.triangles);
    assert_eq!(predicted.poses, truth.poses);
    let meta = predicted.meta.unwrap();
    assert_eq!(meta.garment, "skirt");
    let cmp = dir.path().join("cmp.json");
    ok(&["compare", s(&f.truth), s(&out), "--json", s(&cmp)]);
    let scores = json(&cmp);
    assert!(scores["E_v"].as_f64().unwrap() > 0.0, "{scores}");
    assert!(scores["jitter"].as_f64().unwrap().is_finite(), "{scores}");
    let pictures = dir.path().join("pictures");
    ok(&[
        "render",
        s(&out),
        "--out",
        s(&pictures),
        "--frames",
        "0,6",
        "--size",
        "96",
    ]);
    assert!(std::fs::read_dir(&pictures).unwrap().count() > 0);

    // Same seed and settings, same bytes; another seed, another garment.
    let again = dir.path().join("again.mcap");
    predict(&again, &["--steps", "3", "--batch", "5"]);
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
    let other = dir.path().join("other.mcap");
    predict(&other, &["--steps", "3", "--batch", "5", "--seed", "1"]);
    let other = Recording::read(&other).unwrap();
    assert_ne!(other.garment[8], predicted.garment[8]);
}

#[test]
fn per_frame_noise_and_the_push_out_change_what_they_should() {
    let dir = tempfile::tempdir().unwrap();
    let shared = dir.path().join("shared.mcap");
    predict(&shared, &["--steps", "2", "--guidance", "0"]);
    let per_frame = dir.path().join("per_frame.mcap");
    predict(
        &per_frame,
        &["--steps", "2", "--guidance", "0", "--per-frame-noise"],
    );
    let (a, b) = (
        Recording::read(&shared).unwrap(),
        Recording::read(&per_frame).unwrap(),
    );
    // Frame 0's noise is the shared one's only by chance; later frames differ.
    assert_ne!(a.garment[5], b.garment[5]);

    let pushed = dir.path().join("pushed.json");
    let out = dir.path().join("pushed.mcap");
    predict(
        &out,
        &[
            "--steps",
            "2",
            "--guidance",
            "0",
            "--resolve-penetration",
            "--json",
            s(&pushed),
        ],
    );
    let plain = dir.path().join("plain.json");
    predict(
        &dir.path().join("plain.mcap"),
        &["--steps", "2", "--guidance", "0", "--json", s(&plain)],
    );
    let (with, without) = (json(&pushed), json(&plain));
    // The push-out moves exactly the vertices that were inside, and only then.
    let inside = without["max_verts_inside"].as_u64().unwrap();
    assert_eq!(without["pushed_vertices"], 0);
    assert_eq!(with["pushed_vertices"].as_u64().unwrap() > 0, inside > 0);
}

#[test]
fn bad_inputs_are_named_and_leave_nothing() {
    let f = fixture();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.mcap");
    let base = |extra: &[&str]| -> String {
        let mut args = vec!["predict", "--out", s(&out), "--quiet"];
        args.extend_from_slice(extra);
        let e = fails(&args);
        assert!(!out.exists(), "{} was written", out.display());
        e
    };
    let run = s(&f.run);
    let truth = s(&f.truth);
    let e = base(&["--model", s(&dir.path().join("nowhere"))]);
    assert!(e.contains("not a run or ensemble folder"), "{e}");
    let e = base(&["--model", run, "--config-from", truth, "--steps", "0"]);
    assert!(e.contains("steps = 0"), "{e}");
    let e = base(&["--model", run, "--config-from", truth, "--guidance", "-1"]);
    assert!(e.contains("guidance weight = -1"), "{e}");
    let e = base(&[
        "--model",
        run,
        "--motion",
        "walk:duration=0.04",
        "--blend-frames",
        "0",
        "--settle-frames",
        "0",
    ]);
    assert!(e.contains("pose window needs at least 3"), "{e}");

    // A template without UVs.
    let obj = dir.path().join("flat.obj");
    std::fs::write(
        &obj,
        "v -0.2 1.0 0.2\nv 0.2 1.0 0.2\nv 0.2 1.2 0.2\nv -0.2 1.2 0.2\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let e = base(&["--model", run, "--garment", s(&obj), "--frames", "4"]);
    assert!(e.contains("UVs") && e.contains("flat.obj"), "{e}");

    // A model whose weights are missing, and one whose data manifest does not fit it.
    let broken = f.dir.join("broken-run");
    let _ = std::fs::remove_dir_all(&broken);
    std::fs::create_dir_all(&broken).unwrap();
    for file in ["config.toml", "tensors.json"] {
        std::fs::copy(f.run.join(file), broken.join(file)).unwrap();
    }
    let e = base(&["--model", s(&broken), "--config-from", truth]);
    assert!(
        e.contains("model.safetensors") && e.contains("missing"),
        "{e}"
    );
    std::fs::copy(
        f.run.join("model.safetensors"),
        broken.join("model.safetensors"),
    )
    .unwrap();
    let manifest = std::fs::read_to_string(broken.join("tensors.json")).unwrap();
    std::fs::write(
        broken.join("tensors.json"),
        manifest.replace("\"resolution\": 32", "\"resolution\": 64"),
    )
    .unwrap();
    let e = base(&["--model", s(&broken), "--config-from", truth]);
    assert!(
        e.contains("tensors.json") && e.contains("resolution 64"),
        "{e}"
    );
}

/// The ground truth's spread: the same configuration simulated again gives the same frames
/// (zero but for the recording's f32 rounding), 1% stiffer cloth gives a small non-zero difference, scored with evaluate's keys.
#[test]
fn dataset_spread_is_zero_unperturbed_and_small_with_stiffer_cloth() {
    let f = fixture();
    let data = f.data.clone();
    let dir = tempfile::tempdir().unwrap();
    let e_v = |perturb: &str| {
        let out = dir.path().join(format!("{perturb}.json"));
        let args = ["dataset", "spread", s(&data), "--splits", "test_motion"];
        ok(&[
            &args[..],
            &["--perturb", perturb, "--json", s(&out), "--quiet"],
        ]
        .concat());
        let j = json(&out);
        let row = &j["splits"]["test_motion"]["resimulated"];
        assert_eq!(row["sequences"], 1, "{j}");
        assert!(j["families"]["test_motion"].is_object() && j["units"]["E_v"].is_string());
        row["E_v"].as_f64().unwrap()
    };
    // The engine is deterministic; the recording keeps positions as f32 (1e-7 m).
    let same = e_v("none");
    assert!(same < 1e-4, "{same} cm");
    let stiffer = e_v("k_s");
    assert!(stiffer > 0.0 && stiffer < 2.0, "{stiffer} cm");
    let e = common::fails(&["dataset", "spread", s(&data), "--perturb", "gravity"]);
    assert!(e.contains("--perturb gravity"), "{e}");
}

#[test]
fn evaluate_ranks_the_baselines_per_family_and_motion() {
    let f = fixture();
    let data = f.data.clone();
    let dir = tempfile::tempdir().unwrap();
    let scores = dir.path().join("baselines.json");
    ok(&[
        "evaluate",
        "--model",
        "none",
        "--data",
        s(&data),
        "--splits",
        "test_motion",
        "--json",
        s(&scores),
        "--quiet",
    ]);
    let j = json(&scores);
    let rows = &j["splits"]["test_motion"];
    let keys = [
        "E_v",
        "E_CD",
        "E_CD_cm",
        "E_n",
        "E_c",
        "E_c_vertex",
        "E_b",
        "E_s",
        "E_d",
        "jitter",
        "stretch_p99",
        "inside_percent",
        "inside_overlap_percent",
        "max_penetration_m",
        "max_penetration_overlap_m",
        "fps",
        "sequences",
        "frames_scored",
    ];
    for method in ["lbs", "lbs_nearest", "floor", "rest"] {
        for key in keys {
            assert!(
                rows[method][key].is_number(),
                "{method}.{key} missing: {rows}"
            );
            assert!(j["units"][key].is_string(), "no unit for {key}");
        }
        assert_eq!(rows[method]["sequences"], 1);
    }
    // Per garment family and per motion: one sequence, so each group's row is the split's.
    for group in ["families", "motions"] {
        let groups = j[group]["test_motion"].as_object().unwrap();
        assert_eq!(groups.len(), 1, "{group}: {groups:?}");
        let row = groups.values().next().unwrap();
        assert_eq!(row["lbs"]["E_v"], rows["lbs"]["E_v"], "{group}");
    }
    let garment = j["sequences"][0]["garment"].as_str().unwrap();
    let family = j["family_of_garment"][garment].as_str().unwrap();
    assert_eq!(family, "dress_or_skirt");
    assert!(j["families"]["test_motion"][family].is_object(), "{family}");
    let simulation = &j["simulation"]["test_motion"];
    for key in [
        "inside_percent",
        "inside_overlap_percent",
        "max_penetration_m",
        "max_penetration_overlap_m",
    ] {
        assert!(
            simulation[key].is_number(),
            "simulation.{key}: {simulation}"
        );
    }
    assert!(
        simulation["inside_overlap_percent"].as_f64() <= simulation["inside_percent"].as_f64(),
        "{simulation}"
    );
    assert!(rows["model"].is_null(), "no model was asked for");
    let e_v = |m: &str| rows[m]["E_v"].as_f64().unwrap();
    for other in ["lbs", "lbs_nearest", "rest"] {
        assert!(
            e_v("floor") < e_v(other),
            "floor {} >= {other} {}",
            e_v("floor"),
            e_v(other)
        );
    }
    assert_eq!(j["sequences"].as_array().unwrap().len(), 1);
}

#[test]
fn the_ground_truth_scored_as_a_prediction_scores_zero() {
    let f = fixture();
    let seq = surrogate::data::Sequence::read(&f.truth).unwrap();
    let body = motions::BodyModel::default_body();
    let truth = surrogate::evaluate::Truth::new(&seq, &body, 0).unwrap();
    let perfect = truth.score(&truth.ground_truth(), 1.0);
    let sc = perfect.scores;
    for (name, v) in [
        ("E_v", sc.E_v),
        ("E_CD", sc.E_CD),
        ("E_n", sc.E_n),
        ("E_b", sc.E_b),
    ] {
        assert!(v.abs() < 1e-9, "{name} = {v} for the ground truth");
    }
    assert!(sc.E_s.abs() < 1e-9 && sc.E_d.abs() < 1e-9, "{sc:?}");
}

#[test]
fn evaluate_scores_the_model_writes_its_report_and_reuses_its_cache() {
    let f = fixture();
    let data = f.data.clone();
    let dir = tempfile::tempdir().unwrap();
    let scores = dir.path().join("model.json");
    let report = dir.path().join("report");
    let args = [
        "evaluate",
        "--model",
        s(&f.run),
        "--data",
        s(&data),
        "--splits",
        "test_motion",
        "--steps",
        "2",
        "--baselines",
        "lbs,floor",
        "--json",
        s(&scores),
        "--report",
        s(&report),
        "--quiet",
    ];
    let first = ok(&args);
    assert!(first.contains("(0 reused"), "{first}");
    let j = json(&scores);
    for method in ["model", "model_no_guidance", "lbs", "floor"] {
        assert!(
            j["splits"]["test_motion"][method]["E_v"].is_number(),
            "{method}: {j}"
        );
    }
    assert!(j["splits"]["test_motion"]["rest"].is_null());
    let md = std::fs::read_to_string(report.join("README.md")).unwrap();
    assert!(
        md.contains("Guidance ablation") && md.contains("One unseen factor"),
        "{md}"
    );
    let html = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(html.contains("<table>") && html.contains("data:image/png;base64,"));
    assert!(
        report
            .join("pictures/test_motion_median/sheet.png")
            .is_file()
    );
    assert!(
        report
            .join("pictures/test_motion_median/view.html")
            .is_file()
    );
    let again = ok(&args);
    assert!(again.contains("(1 reused"), "{again}");
    assert_eq!(json(&scores)["splits"], j["splits"]);
}

#[test]
fn evaluate_refuses_unknown_baselines_splits_and_damaged_manifests() {
    let f = fixture();
    let data = f.data.clone();
    let dir = tempfile::tempdir().unwrap();
    let scores = dir.path().join("refused.json");
    let e = fails(&[
        "evaluate",
        "--model",
        "none",
        "--data",
        s(&data),
        "--baselines",
        "knn",
        "--json",
        s(&scores),
    ]);
    assert!(e.contains("--baselines = knn: unknown baseline"), "{e}");
    let e = fails(&[
        "evaluate",
        "--model",
        "none",
        "--data",
        s(&data),
        "--splits",
        "nope",
        "--json",
        s(&scores),
    ]);
    assert!(e.contains("no finished sequences"), "{e}");

    // A manifest whose label disagrees with the recording, or that lists a sequence twice, is
    // refused naming the sequence.
    let copy = dir.path().join("relabelled");
    let status = std::process::Command::new("cp")
        .args(["-r", s(&data), s(&copy)])
        .status()
        .unwrap();
    assert!(status.success());
    let manifest = copy.join("manifest.jsonl");
    let text = std::fs::read_to_string(&manifest).unwrap();
    let mut lines: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let k = lines.iter().position(|l| l["status"] == "ok").unwrap();
    let id = lines[k]["id"].as_str().unwrap().to_string();
    lines[k]["motion"] = "kick".into();
    let write = |lines: &[serde_json::Value]| {
        let body: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        std::fs::write(&manifest, body.join("\n") + "\n").unwrap();
    };
    write(&lines);
    let evaluate_copy = || {
        fails(&[
            "evaluate",
            "--model",
            "none",
            "--data",
            s(&copy),
            "--baselines",
            "lbs",
            "--splits",
            lines[k]["split"].as_str().unwrap(),
            "--json",
            s(&scores),
        ])
    };
    let e = evaluate_copy();
    assert!(
        e.contains(&format!("the manifest's line for sequence {id} says")) && e.contains("'kick'"),
        "{e}"
    );
    let original: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let mut twice = original.clone();
    twice.push(original[k].clone());
    write(&twice);
    let e = evaluate_copy();
    assert!(
        e.contains(&format!("sequence '{id}' is listed 2 times")),
        "{e}"
    );
}

/// The network's inputs are the same whether they come from the training tensors or from
/// the predictor (position map, body inputs with the nearest body points, scaled conditions),
/// frame by frame.
#[test]
fn training_tensors_and_prediction_give_the_network_the_same_inputs() {
    use surrogate::burn::prelude::Device;
    use surrogate::data::{Sequence, TrainingTensors};
    use surrogate::predict::{BodySequence, Predictor};
    use surrogate::run::TrainedModel;

    let f = fixture();
    let tensors = TrainingTensors::open(&f.dir.join("tensors")).unwrap();
    let frames = tensors.frames("test_motion").unwrap();
    assert!(!frames.bodies.is_empty(), "the tensors hold body inputs");
    let trained = TrainedModel::load(&f.run, &Device::flex()).unwrap();
    assert!(trained.config.model.body_inputs && trained.config.model.body_nearest);
    let body = motions::BodyModel::default_body();
    let predictor = Predictor::new(&trained, &body).unwrap();
    let sequence = Sequence::read(&f.truth).unwrap();
    let motion = sequence.motion().unwrap();
    let seq = BodySequence {
        motion: &motion,
        betas: &sequence.betas,
        material: sequence.meta.material,
    };
    let garment = predictor.garment(&sequence.template).unwrap();
    let inputs = predictor
        .network_inputs(&garment, &seq, &frames.frame)
        .unwrap();
    let (r, d) = (tensors.resolution(), tensors.manifest.condition_dim);
    let plane = r * r;
    let g = frames.template[0];
    let mut expected = Vec::new();
    for i in 0..frames.len() {
        expected.extend_from_slice(&tensors.position_maps[g * 3 * plane..(g + 1) * 3 * plane]);
        expected.extend_from_slice(&frames.bodies[i * 12 * plane..(i + 1) * 12 * plane]);
    }
    let worst = |a: &[f32], b: &[f32]| {
        assert_eq!(a.len(), b.len());
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max)
    };
    // Plane by plane: the nearest-body channels (9-14 of each frame's 15) come from
    // parry3d's f32 queries on a body surface refit from another pose in one path and built
    // fresh in the other, so they agree to about 1e-6 m (up to 5e-5 normalized, measured);
    // every other channel to f32 rounding.
    for (c, (a, b)) in inputs
        .texels
        .chunks(plane)
        .zip(expected.chunks(plane))
        .enumerate()
    {
        let tolerance = if c % 15 >= 9 { 2e-4 } else { 1e-5 };
        assert!(worst(a, b) < tolerance, "texel plane {c} differs");
    }
    // A training batch takes the first body channels the model asks for: 6 for a model
    // without the nearest-body inputs, all 12 with them.
    for channels in [6, 12] {
        let recipe = surrogate::train::Recipe {
            inside_weight: 1.0,
            prediction: surrogate::model::Prediction::Data,
            zero_outside: true,
            body_channels: channels,
            previous_noise: None,
            condition_noise: 0.0,
        };
        let mut rng = surrogate::noise::generator(0, 0, 0);
        let batch =
            surrogate::train::Batch::new(&tensors, &frames, &[1, 0], &[1.0; 2], recipe, &mut rng);
        let per = (3 + channels) * plane;
        for (slot, f) in [1, 0].into_iter().enumerate() {
            assert_eq!(
                batch.position[slot * per..(slot + 1) * per],
                expected[f * 15 * plane..f * 15 * plane + per],
                "{channels} body channels, frame {f}"
            );
        }
    }
    // Condition noise (`training.condition_noise`) moves every condition value of a training
    // batch by about its spread and leaves the texel inputs as they were (it is drawn from the
    // batch's stream after each frame's, so the noise of later frames' noisy targets moves
    // too); validation batches are given none.
    let recipe = |noise: f32| surrogate::train::Recipe {
        inside_weight: 1.0,
        prediction: surrogate::model::Prediction::Data,
        zero_outside: true,
        body_channels: 6,
        previous_noise: None,
        condition_noise: noise,
    };
    let batch = |noise: f32| {
        let mut rng = surrogate::noise::generator(0, 0, 0);
        surrogate::train::Batch::new(
            &tensors,
            &frames,
            &[1, 0],
            &[1.0; 2],
            recipe(noise),
            &mut rng,
        )
    };
    let (plain, noisy) = (batch(0.0), batch(0.5));
    assert_eq!(plain.position, noisy.position);
    assert_eq!(plain.conditions[..d], frames.conditions[d..2 * d]);
    let moved = plain.conditions.iter().zip(&noisy.conditions);
    let rms = (moved.map(|(a, b)| (a - b).powi(2)).sum::<f32>() / (2 * d) as f32).sqrt();
    assert!((0.4..0.6).contains(&rms), "condition noise rms {rms}");
    let training = surrogate::run::TrainConfig {
        condition_noise: 0.5,
        val_frames: 2,
        ..Default::default()
    };
    let validation =
        surrogate::train::validation_batches(&tensors, &frames, &training, recipe(0.5));
    let first = frames.len() / 2;
    assert_eq!(validation[0].conditions[..d], frames.conditions[..d]);
    assert_eq!(
        validation[0].conditions[d..],
        frames.conditions[first * d..(first + 1) * d]
    );
    assert_eq!(inputs.conditions.len(), frames.len() * d);
    assert!(
        worst(&inputs.conditions, &frames.conditions) < 1e-5,
        "conditions differ"
    );
    // The body inputs move with the body: two frames apart, they differ.
    let n = 15 * plane;
    assert!(worst(&inputs.texels[..n], &inputs.texels[n..2 * n]) > 1e-3);
    // So do the nearest-body offsets alone (channels 9 to 11 of the body inputs).
    let offsets = |i: usize| &inputs.texels[i * n + 9 * plane..i * n + 12 * plane];
    assert!(worst(offsets(0), offsets(1)) > 1e-3);
}
