//! `paired`: two `evaluate` results of the tiny dataset compared sequence by sequence.

mod common;

use std::path::Path;

use common::{fails, json, ok, tiny_dataset};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn paired_compares_two_evaluations_sequence_by_sequence() {
    let data = tiny_dataset();
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.json");
    ok(&[
        "evaluate",
        "--model",
        "none",
        "--data",
        s(&data),
        "--baselines",
        "lbs,rest",
        "--splits",
        "train,test_motion",
        "--json",
        s(&a),
        "--quiet",
    ]);
    let document = json(&a);
    let sequences = document["sequences"].as_array().unwrap();
    let n = sequences.len();
    assert!(n >= 2, "{n} sequences");

    // An evaluation against itself: no difference, no sequence lower.
    let same = dir.path().join("same.json");
    let out = ok(&[
        "paired",
        s(&a),
        s(&a),
        "--method",
        "lbs",
        "--json",
        s(&same),
    ]);
    assert!(out.contains(&format!("| all ({n}) |")), "{out}");
    let rows = json(&same)["rows"].as_array().unwrap().clone();
    assert_eq!(rows[0]["group"], "all");
    assert_eq!(rows[0]["difference"].as_f64(), Some(0.0));
    assert_eq!(rows[0]["b_lower"].as_u64(), Some(0));

    // B: the first sequence's lbs E_v 0.3 cm lower, and the sequences in reverse order.
    let mut other = document.clone();
    let list = other["sequences"].as_array_mut().unwrap();
    let first = list[0]["methods"]["lbs"]["E_v"].as_f64().unwrap();
    list[0]["methods"]["lbs"]["E_v"] = (first - 0.3).into();
    list.reverse();
    let b = dir.path().join("b.json");
    std::fs::write(&b, other.to_string()).unwrap();
    let out_json = dir.path().join("paired.json");
    ok(&[
        "paired",
        s(&a),
        s(&b),
        "--method",
        "lbs",
        "--json",
        s(&out_json),
    ]);
    let result = json(&out_json);
    assert_eq!(
        (result["method"].as_str(), result["metric"].as_str()),
        (Some("lbs"), Some("E_v"))
    );
    let all = &result["rows"][0];
    let expected = -0.3 / n as f64;
    assert!(
        (all["difference"].as_f64().unwrap() - expected).abs() < 1e-9,
        "{all}"
    );
    assert_eq!(all["b_lower"].as_u64(), Some(1));
    assert_eq!(all["sequences"].as_u64(), Some(n as u64));
    // The same, in the rest baseline: untouched.
    let out = ok(&["paired", s(&a), s(&b), "--method", "rest"]);
    assert!(out.contains("| +0.000 | 0.000 | 0 of"), "{out}");

    // Refused, naming the fault: another recording of a sequence, a method the files do not
    // hold, a sequence missing from one side, a file that is not an evaluation.
    let mut edited = document.clone();
    let id = edited["sequences"][1]["id"].as_str().unwrap().to_string();
    edited["sequences"][1]["settings"]["sha256"] = "0000".into();
    std::fs::write(&b, edited.to_string()).unwrap();
    let e = fails(&["paired", s(&a), s(&b), "--method", "lbs"]);
    assert!(e.contains(&id) && e.contains("SHA-256 differs"), "{e}");
    let e = fails(&["paired", s(&a), s(&a), "--method", "model"]);
    assert!(
        e.contains("a.json") && e.contains("no `E_v` of method `model`"),
        "{e}"
    );
    let mut fewer = document.clone();
    fewer["sequences"].as_array_mut().unwrap().truncate(n - 1);
    std::fs::write(&b, fewer.to_string()).unwrap();
    let e = fails(&["paired", s(&a), s(&b), "--method", "lbs"]);
    assert!(e.contains("the same sequences in both evaluations"), "{e}");
    std::fs::write(&b, "[1, 2]").unwrap();
    let e = fails(&["paired", s(&a), s(&b), "--method", "lbs"]);
    assert!(
        e.contains("b.json") && e.contains("not an `evaluate --json` file"),
        "{e}"
    );
    assert!(!dir.path().join("refused.json").exists());
}
