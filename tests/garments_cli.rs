//! End-to-end: `garments` as a user runs it (list, make with its report, check) and a
//! GarmentCode pattern file wherever a garment name is taken.

mod common;

use std::path::Path;

use common::{fails, json, ok, run_with};
use serde_json::Value;

#[test]
fn garments_list_make_and_check() {
    let dir = tempfile::tempdir().unwrap();
    let list = dir.path().join("list.json");
    ok(&["garments", "list", "--json", list.to_str().unwrap()]);
    let rows: Value = serde_json::from_str(&std::fs::read_to_string(&list).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    assert!(rows.len() >= 16);
    assert!(
        rows.iter()
            .all(|r| r["name"].is_string() && r["vertices"].as_u64().unwrap() > 1000)
    );
    assert!(rows.iter().filter(|r| r["split"] == "test").count() >= 3);

    // The smallest design is sewn and draped on the default body with every gate passed.
    let out = dir.path().join("tank.obj");
    let report = dir.path().join("tank.json");
    ok(&[
        "garments",
        "make",
        "tank_tight",
        "--out",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    for key in [
        "gates_passed",
        "vertices",
        "triangles",
        "verts_inside",
        "max_seam_gap_m",
        "moving_fraction",
        "self_intersections",
        "crossings_closed",
        "crossings_untangled",
        "wall_s",
    ] {
        assert!(r.get(key).is_some(), "report lacks {key}: {r}");
    }
    assert_eq!(r["gates_passed"], true, "{r}");
    assert!(r["verts_inside"].as_u64().unwrap() <= 35);
    assert!(r["max_seam_gap_m"].as_f64().unwrap() < 0.002);
    let checked = ok(&["garments", "check", out.to_str().unwrap()]);
    assert!(checked.contains("no problems found"), "{checked}");

    // A mesh in centimetres is refused without --scale and accepted with it.
    let cm = dir.path().join("cm.obj");
    let text = std::fs::read_to_string(&out).unwrap();
    let scaled: String = text
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(rest) => {
                let c: Vec<f64> = rest
                    .split_whitespace()
                    .map(|x| x.parse().unwrap())
                    .collect();
                format!("v {} {} {}\n", c[0] * 100.0, c[1] * 100.0, c[2] * 100.0)
            }
            None => format!("{l}\n"),
        })
        .collect();
    std::fs::write(&cm, scaled).unwrap();
    let e = fails(&["garments", "check", cm.to_str().unwrap()]);
    assert!(e.contains("cannot be used"), "{e}");
    ok(&["garments", "check", cm.to_str().unwrap(), "--scale", "0.01"]);

    // Broken patterns and unknown names fail with the reason, and nothing is written.
    let bad = dir.path().join("bad_specification.json");
    std::fs::write(
        &bad,
        "{\"pattern\": {\"panels\": {}}, \"properties\": {\"units_in_meter\": 100}}",
    )
    .unwrap();
    let never = dir.path().join("never.obj");
    let e = fails(&[
        "garments",
        "make",
        bad.to_str().unwrap(),
        "--out",
        never.to_str().unwrap(),
    ]);
    assert!(
        e.contains("bad_specification.json") && e.contains("panels is empty"),
        "{e}"
    );
    assert!(!never.exists());
    let e = fails(&["garments", "show", "poncho"]);
    assert!(e.contains("unknown design"), "{e}");
}

/// A sewing pattern file is a garment wherever a design name is: the library's own pattern,
/// written out by `garments show --pattern-out` and named as a file, is sewn to the same
/// template; a pattern file that does not parse is refused naming it.
#[test]
fn a_pattern_file_is_a_garment() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let pattern = dir.path().join("tank_tight_copy.json");
    ok(&[
        "garments",
        "show",
        "tank_tight",
        "--pattern-out",
        pattern.to_str().unwrap(),
    ]);
    let simulate = |garment: &str, json: &Path| {
        let out = json.with_extension("mcap");
        run_with(
            &[
                "simulate",
                "--garment",
                garment,
                "--frames",
                "2",
                "--json",
                json.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            &[("DIT_GARMENT_CACHE", cache.to_str().unwrap())],
        )
    };
    let (from_file, from_name) = (dir.path().join("file.json"), dir.path().join("name.json"));
    for (garment, json) in [
        (pattern.to_str().unwrap(), &from_file),
        ("tank_tight", &from_name),
    ] {
        let out = simulate(garment, json);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let vertices = |path: &Path| json(path)["vertices"].clone();
    assert_eq!(vertices(&from_file), vertices(&from_name));
    assert!(vertices(&from_file).as_u64().unwrap() > 1000);
    let broken = dir.path().join("broken.json");
    std::fs::write(&broken, "{\"pattern\": ").unwrap();
    let out = simulate(
        broken.to_str().unwrap(),
        &dir.path().join("broken_run.json"),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("broken.json"), "{stderr}");
}
