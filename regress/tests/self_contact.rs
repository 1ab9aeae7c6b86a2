//! Cloth-cloth contact (the scenes of `regress::self_contact`): layers dropped on each
//! other keep the self-contact distance, a sheet folded over itself on the ground does not
//! pass through, and friction between layers follows Coulomb's law. The first two scenes are
//! also run with self-contact off, to show the checks can fail.

use regress::self_contact::{LAYER_FRICTION, folded_strip, patch_on_tilted_sheet, two_sheets};
use sim::SolverParams;

#[test]
fn two_sheets_dropped_on_each_other_stay_the_contact_distance_apart() {
    let distance = SolverParams::default().self_contact_distance;
    let (gap, crossings) = two_sheets(true).unwrap();
    eprintln!(
        "self-contact on: gap {:.2} mm, crossings {crossings}",
        gap * 1e3
    );
    assert!(
        (gap - distance).abs() < 0.25 * distance,
        "gap {gap} m, expected about {distance} m"
    );
    assert_eq!(crossings, 0);
    let (gap, _) = two_sheets(false).unwrap();
    eprintln!("self-contact off: gap {:.2} mm", gap * 1e3);
    assert!(
        gap < 0.25 * distance,
        "without self-contact the layers merge"
    );
}

#[test]
fn a_sheet_folded_over_itself_on_the_ground_does_not_pass_through() {
    let distance = SolverParams::default().self_contact_distance;
    let (gap, crossings) = folded_strip(true).unwrap();
    eprintln!(
        "self-contact on: gap {:.2} mm, crossings {crossings}",
        gap * 1e3
    );
    assert!(gap > 0.25 * distance, "layers {gap} m apart");
    assert_eq!(crossings, 0);
    let (gap, crossings) = folded_strip(false).unwrap();
    eprintln!(
        "self-contact off: gap {:.2} mm, crossings {crossings}",
        gap * 1e3
    );
    assert!(
        gap < 0.0 && crossings > 0,
        "without self-contact the layers cross"
    );
}

#[test]
fn friction_between_layers_sticks_iff_the_slope_is_within_the_cone() {
    let mu = LAYER_FRICTION;
    let stick = patch_on_tilted_sheet((mu - 0.05).atan(), mu).unwrap();
    eprintln!("tan(theta) = mu - 0.05: moved {stick:e} m in 1 s");
    assert!(stick.abs() < 1e-6, "drift {stick} m");
    let theta = (mu + 0.05).atan();
    let slide = patch_on_tilted_sheet(theta, mu).unwrap();
    let expected = 0.5 * 9.81 * (theta.sin() - mu * theta.cos());
    eprintln!("tan(theta) = mu + 0.05: moved {slide} m in 1 s, expected {expected} m");
    assert!(
        (slide - expected).abs() < 0.02 * expected,
        "{slide} vs {expected}"
    );
}
