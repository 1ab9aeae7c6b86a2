//! Sewing patterns into templates on the default body, with GarmentCode's gates.
//!
//! The fast test sews one sleeved design (sleeves are the hard part: the arm must end up
//! inside the sleeve, and the cloth next to the armhole must not end up through itself). The whole library and the two shared GarmentCode examples are behind
//! `--ignored` (about 4 minutes in release on 2 cores):
//! `cargo test --release -p sim --test sewing -- --ignored`.

use std::path::Path;

use garments::library::{DESIGNS, find};
use motions::BodyModel;
use sim::sewing::{SewingOptions, SewingReport, sew};

fn sew_pattern(pattern: &garments::Pattern) -> SewingReport {
    let sewn = pattern.mesh(0.015).unwrap();
    let (template, report) =
        sew(&BodyModel::default_body(), &sewn, &SewingOptions::default()).unwrap();
    assert_eq!(template.positions.len(), report.vertices);
    let findings = garments::check(&template).lines();
    assert!(findings.is_empty(), "{}: {findings:?}", pattern.name);
    report
}

#[test]
fn a_sleeved_design_drapes_with_every_gate_passed() {
    let report = sew_pattern(&find("cap_sleeve_top").unwrap().pattern().unwrap());
    assert!(report.gates_passed, "{report:?}");
    assert!(report.max_edge_stretch < 1.3, "{report:?}");
    // Closing folds the cloth next to the armholes through the bodice (76 crossing pairs
    // measured); untangling opens those creases and settling with self-contact keeps them
    // open (0 and 0 measured).
    assert!(report.crossings_closed > 0, "{report:?}");
    assert!(
        report.crossings_untangled * 10 <= report.crossings_closed,
        "{report:?}"
    );
    assert!(report.self_intersections <= 5, "{report:?}");
}

/// The sleeves of a pattern from outside the library are seated at the angle the canonical
/// body holds its arms: shoulder to wrist, ARM_ANGLE_DEG below the horizontal, both sides.
#[test]
fn the_seated_sleeve_angle_is_the_canonical_bodys_arm() {
    let body = sim::scene::canonical_body(&BodyModel::default_body()).unwrap();
    for (shoulder, wrist) in [(16, 20), (17, 21)] {
        let (s, w) = (body.joints[shoulder], body.joints[wrist]);
        let below = (s[1] - w[1]).atan2((w[0] - s[0]).abs()).to_degrees();
        assert!(
            (below - garments::pattern::ARM_ANGLE_DEG).abs() < 0.01,
            "joint {shoulder} to {wrist}: {below} degrees"
        );
    }
}

/// GarmentCode's jumpsuit (54 cm sleeves, placed for GarmentCode's body): seated on this
/// body's arms it drapes with every gate passed (3 vertices inside); as written, its sleeves
/// run below the arm and the drape traps cloth in the forearms (36 inside, over the gate's 35).
#[test]
#[ignore = "drapes a 15k-vertex jumpsuit: about a minute in release"]
fn garmentcode_jumpsuit_drapes_with_its_sleeves_seated() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/js_mean_all_specification.json");
    let mut pattern = garments::Pattern::read(&path).unwrap();
    let turned = pattern.seat_sleeves(garments::pattern::ARM_ANGLE_DEG);
    assert_eq!(turned.len(), 4, "{turned:?}");
    let report = sew_pattern(&pattern);
    eprintln!("js_mean_all: {report:?}");
    assert!(report.gates_passed, "{:?}", report.failed);
}

#[test]
#[ignore = "sews all 19 designs and both shared examples: minutes"]
fn every_library_design_and_shared_example_drapes_with_every_gate_passed() {
    let mut failed = Vec::new();
    for design in DESIGNS {
        let report = sew_pattern(&design.pattern().unwrap());
        eprintln!("{}: {report:?}", design.name);
        if !report.gates_passed {
            failed.push((design.name.to_string(), report.failed));
        }
    }
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/testdata/garmentcode");
    for name in ["shirt_mean", "dress_pencil"] {
        let path = shared.join(format!("{name}_specification.json"));
        if !testkit::available(
            "sewing::every_library_design_and_shared_example_drapes_with_every_gate_passed",
            "SHARED",
            path.exists(),
            &format!("{} not found", path.display()),
        ) {
            continue;
        }
        let report = sew_pattern(&garments::Pattern::read_seated(&path).unwrap());
        eprintln!("{name}: {report:?}");
        if !report.gates_passed {
            failed.push((name.to_string(), report.failed));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}
