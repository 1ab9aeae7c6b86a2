//! The fast regression suite: every scenario of the `regress` crate passes within its tolerance
//! (measured vs expected printed on failure).

use regress::run;

fn check(filter: &str) {
    let outcomes = run(false, filter).expect("scenario runs");
    assert!(!outcomes.is_empty(), "no scenario matches '{filter}'");
    for o in outcomes {
        assert!(
            o.pass,
            "{}: measured {} {}, expected {} +/- {}",
            o.name, o.measured, o.unit, o.expected, o.tolerance
        );
    }
}

#[test]
fn free_fall() {
    check("free_fall");
}
#[test]
fn momentum() {
    check("momentum");
}
#[test]
fn energy() {
    check("energy");
}
#[test]
fn incline() {
    check("incline");
}
#[test]
fn ly2020_drop() {
    check("ly2020");
}
#[test]
fn accelerating_plate() {
    check("accelerating_plate");
}
#[test]
fn hanging_sheet() {
    check("hanging_sheet");
}
#[test]
fn catenary() {
    check("catenary");
}
#[test]
fn sphere_drape() {
    check("sphere_drape");
}
#[test]
fn convergence() {
    check("convergence");
}
#[test]
fn determinism() {
    check("determinism");
}
#[test]
fn goldens() {
    check("golden");
}

/// The goldens catch a deliberately perturbed parameter: k_s 5% higher moves the skirt by more
/// than the golden tolerance.
#[test]
fn goldens_catch_a_perturbed_stretch_stiffness() {
    let g = &regress::GOLDENS[0];
    let frames = regress::simulate_golden(g, 1.05).unwrap();
    let d = regress::golden_distance(g, &frames).unwrap();
    assert!(
        d > regress::GOLDEN_TOLERANCE_CM,
        "k_s x 1.05 moved the skirt by only {d} cm"
    );
}
#[test]
fn cantilever() {
    check("cantilever");
}
#[test]
fn hanging_chain() {
    check("hanging_chain");
}
#[test]
fn self_contact() {
    check("self_contact");
}
