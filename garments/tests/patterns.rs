//! Sewing patterns written here: every edge type, stitches both ways, and every refusal.

use garments::Pattern;
use serde_json::{Value, json};

/// Two 40 x 30 cm rectangles facing each other, sewn along both sides; the front's top edge
/// is a quadratic, its hem a cubic, the back's top a circle arc; the back runs clockwise.
fn tube() -> Value {
    json!({
        "pattern": {
            "panels": {
                "front": {
                    "translation": [0.0, 100.0, 15.0], "rotation": [0.0, 0.0, 0.0],
                    "vertices": [[-20.0, 0.0], [20.0, 0.0], [20.0, 30.0], [-20.0, 30.0]],
                    "edges": [
                        {"endpoints": [0, 1], "curvature": {"type": "cubic", "params": [[0.3, 0.05], [0.7, -0.05]]}},
                        {"endpoints": [1, 2]},
                        {"endpoints": [2, 3], "curvature": {"type": "quadratic", "params": [[0.5, 0.1]]}, "label": "collar"},
                        {"endpoints": [3, 0]}
                    ]
                },
                "back": {
                    "translation": [0.0, 100.0, -15.0], "rotation": [0.0, 0.0, 0.0],
                    "vertices": [[-20.0, 0.0], [20.0, 0.0], [20.0, 30.0], [-20.0, 30.0]],
                    "edges": [
                        {"endpoints": [0, 3]},
                        {"endpoints": [3, 2], "curvature": {"type": "circle", "params": [40.0, 0, 1]}},
                        {"endpoints": [2, 1]},
                        {"endpoints": [1, 0]}
                    ]
                }
            },
            "stitches": [
                [{"panel": "front", "edge": 1}, {"panel": "back", "edge": 2}],
                [{"panel": "front", "edge": 3}, {"panel": "back", "edge": 0}]
            ]
        },
        "properties": {"curvature_coords": "relative", "units_in_meter": 100}
    })
}

fn parse(v: &Value) -> garments::Result<Pattern> {
    Pattern::parse("tube", &v.to_string())
}

#[test]
fn a_tube_meshes_stitches_and_merges() {
    let p = parse(&tube()).unwrap();
    assert_eq!(p.panels.len(), 2);
    let m = p.mesh(0.015).unwrap();
    let g = &m.garment;
    // Stitched edges are 30 cm: 21 samples each, all 21 pairs distinct vertices.
    assert_eq!(m.stitch_pairs.len(), 2 * 21);
    // Pairs join the same heights (end of the front edge to the start of the back's).
    for &[a, b] in &m.stitch_pairs {
        let (pa, pb) = (g.positions[a as usize], g.positions[b as usize]);
        assert!((pa[1] - pb[1]).abs() < 1e-9 && (pa[0] - pb[0]).abs() < 1e-9);
        assert!((pa[2] - pb[2]).abs() > 0.29);
    }
    // Near-equilateral triangles at about the target edge length.
    let mut lengths = Vec::new();
    for t in &g.triangles {
        for k in 0..3 {
            let (a, b) = (
                g.positions[t[k] as usize],
                g.positions[t[(k + 1) % 3] as usize],
            );
            lengths.push(
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt(),
            );
        }
    }
    let mean = lengths.iter().sum::<f64>() / lengths.len() as f64;
    assert!((0.010..0.018).contains(&mean), "mean edge {mean}");
    // Labels become vertex sets; UVs are two islands inside [0, 1].
    assert_eq!(g.vertex_labels["collar"].len(), 28);
    assert!(
        g.uvs
            .iter()
            .all(|uv| uv.iter().all(|c| (0.0..=1.0).contains(c)))
    );
    // Both panels face outward (away from the axis between them).
    for (t, tri) in g.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|v| g.positions[v as usize]);
        let nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        assert!(nz * a[2] > 0.0, "triangle {t} faces inward");
    }
    // Pulled together, the seams merge into one closed tube with consistent orientation.
    let mut closed = g.positions.clone();
    for p in &mut closed {
        p[2] *= 0.01;
    }
    let merged = m.merged(&closed).unwrap();
    assert_eq!(merged.positions.len(), g.positions.len() - 2 * 21);
    assert_eq!(merged.triangles.len(), g.triangles.len());
    let report = garments::check(&merged);
    assert!(
        report
            .findings
            .iter()
            .all(|f| f.problem != "inconsistent orientation"),
        "{:?}",
        report.lines()
    );
}

#[test]
fn right_wrong_joins_start_to_start() {
    let mut v = tube();
    v["pattern"]["stitches"][0] =
        json!([{"panel": "front", "edge": 1}, {"panel": "back", "edge": 2}, "right_wrong"]);
    let p = parse(&v).unwrap();
    let m = p.mesh(0.015).unwrap();
    let g = &m.garment;
    // The first stitch now pairs the bottom of one side with the top of the other.
    let [a, b] = m.stitch_pairs[0];
    assert!((g.positions[a as usize][1] - g.positions[b as usize][1]).abs() > 0.29);
}

fn refused(edit: impl Fn(&mut Value), expect: &str) {
    let mut v = tube();
    edit(&mut v);
    let message = parse(&v).unwrap_err().to_string();
    assert!(
        message.contains(expect),
        "'{message}' does not say '{expect}'"
    );
}

#[test]
fn malformed_patterns_are_refused_with_the_reason() {
    refused(
        |v| v["properties"]["units_in_meter"] = json!(0),
        "units_in_meter",
    );
    refused(|v| v["pattern"]["panels"] = json!({}), "panels is empty");
    refused(
        |v| v["pattern"]["stitches"][0][1]["panel"] = json!("sleeve"),
        "panel 'sleeve' does not exist",
    );
    refused(
        |v| v["pattern"]["stitches"][0][1]["edge"] = json!(9),
        "no edge 9",
    );
    refused(
        |v| v["pattern"]["stitches"][1][0]["edge"] = json!(1),
        "already stitched",
    );
    refused(
        |v| v["pattern"]["panels"]["front"]["vertices"][2] = json!([20.0, 60.0]),
        "differ in length",
    );
    refused(
        |v| {
            v["pattern"]["stitches"][0]
                .as_array_mut()
                .unwrap()
                .push(json!("inside_out"))
        },
        "right_wrong",
    );
}

#[test]
fn malformed_edges_are_refused_with_the_reason() {
    refused(
        |v| v["pattern"]["panels"]["front"]["edges"][0]["endpoints"] = json!([0, 7]),
        "endpoints [0, 7]",
    );
    refused(
        |v| v["pattern"]["panels"]["front"]["edges"][1]["endpoints"] = json!([2, 3]),
        "not a closed loop",
    );
    refused(
        |v| {
            v["pattern"]["panels"]["front"]["edges"][2]["curvature"] =
                json!({"type": "spline", "params": []})
        },
        "unknown type 'spline'",
    );
    refused(
        |v| {
            v["pattern"]["panels"]["back"]["edges"][1]["curvature"] =
                json!({"type": "circle", "params": [-1, 0, 1]})
        },
        "radius > 0",
    );
    refused(
        |v| v["pattern"]["panels"]["front"]["vertices"][0] = json!([1, "x"]),
        "not a GarmentCode specification",
    );
    assert!(
        Pattern::parse("x", "{ not json")
            .unwrap_err()
            .to_string()
            .contains("specification")
    );
}

#[test]
fn self_crossing_outlines_are_refused_when_meshing() {
    let mut v = tube();
    // A bow tie: corners 2 and 3 swapped.
    v["pattern"]["panels"]["front"]["vertices"] =
        json!([[-20.0, 0.0], [20.0, 0.0], [-20.0, 30.0], [20.0, 30.0]]);
    v["pattern"]["stitches"] = json!([]);
    let p = parse(&v).unwrap();
    let message = p.mesh(0.015).unwrap_err().to_string();
    assert!(
        ["crosses itself", "coincides", "no area"]
            .iter()
            .any(|m| message.contains(m)),
        "{message}"
    );
}

#[test]
fn reading_a_file_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken_specification.json");
    std::fs::write(&path, "{\"pattern\": 3}").unwrap();
    let message = Pattern::read(&path).unwrap_err().to_string();
    assert!(message.contains("broken_specification.json"), "{message}");
    let missing = Pattern::read(&dir.path().join("none.json"))
        .unwrap_err()
        .to_string();
    assert!(missing.contains("none.json"), "{missing}");
}

#[test]
fn shared_garmentcode_examples_mesh_when_present() {
    let dir =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/testdata/garmentcode");
    if !testkit::available(
        "patterns::shared_garmentcode_examples_mesh_when_present",
        "SHARED",
        dir.exists(),
        "../shared/testdata/garmentcode not found",
    ) {
        return;
    }
    for name in ["shirt_mean", "dress_pencil"] {
        let p = Pattern::read(&dir.join(format!("{name}_specification.json"))).unwrap();
        let m = p.mesh(0.015).unwrap();
        let merged = m.merged(&m.garment.positions).unwrap();
        assert!(garments::check(&merged).findings.is_empty(), "{name}");
        assert!(m.stitch_pairs.len() > 200, "{name}");
    }
}
