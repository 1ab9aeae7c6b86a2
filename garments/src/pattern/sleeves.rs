//! Sleeves seated on this project's body. GarmentCode places a sleeve panel for its own body:
//! rotated about z (the frontal plane) to that body's arm, about 50.5 degrees below the
//! horizontal. The canonical body here holds its arms [`ARM_ANGLE_DEG`] below it
//! (`motions::canonical_a_pose`), so a long GarmentCode sleeve placed as written runs below
//! the arm: its upper seam closes through the forearm and traps cloth inside it (`js_mean_all`,
//! a jumpsuit with 54 cm sleeves: 36 vertices inside the body after the drape, 3 with the
//! sleeves turned to the arm). [`Pattern::seat_sleeves`] turns every such panel to the arm
//! about its highest corner (the top of the armhole), in the panels and in the specification
//! written back, so a seated pattern is a pattern of its own (and its own template cache key).

use super::{Pattern, rotation_matrix};

/// The canonical body's arms below the horizontal, degrees (`motions::canonical_a_pose`:
/// both shoulders rotated 40 degrees down from the T-pose).
pub const ARM_ANGLE_DEG: f64 = 40.0;

impl Pattern {
    /// Reads a specification file ([`Pattern::read`]) with its sleeves seated on this
    /// project's body: how a pattern from outside the library is sewn.
    pub fn read_seated(path: &std::path::Path) -> crate::error::Result<Self> {
        let mut pattern = Self::read(path)?;
        pattern.seat_sleeves(ARM_ANGLE_DEG);
        Ok(pattern)
    }

    /// Turns every panel placed by a rotation about z alone (GarmentCode's sleeves) to
    /// `arm_deg` below the horizontal, keeping the side it hangs to and the panel's highest
    /// placed corner where it was. Returns the panels turned. Library designs are made for this
    /// body already and are not seated.
    pub fn seat_sleeves(&mut self, arm_deg: f64) -> Vec<String> {
        let mut turned = Vec::new();
        for panel in &mut self.panels {
            let [rx, ry, rz] = panel.rotation;
            if rx != 0.0 || ry != 0.0 || rz == 0.0 || panel.vertices.is_empty() {
                continue;
            }
            let target = arm_deg.copysign(rz);
            if (target - rz).abs() < 1e-9 {
                continue;
            }
            let pivot = panel
                .vertices
                .iter()
                .copied()
                .max_by(|a, b| panel.place(*a)[1].total_cmp(&panel.place(*b)[1]))
                .expect("a panel with corners");
            let at = panel.place(pivot);
            let r = rotation_matrix([0.0, 0.0, target]);
            panel.rotation = [0.0, 0.0, target];
            for (i, t) in panel.translation.iter_mut().enumerate() {
                *t = at[i] - (r[i][0] * pivot[0] + r[i][1] * pivot[1]);
            }
            if let Some(spec) = self.spec.pattern.panels.get_mut(&panel.name) {
                spec.rotation = panel.rotation;
                spec.translation = panel.translation;
            }
            turned.push(panel.name.clone());
        }
        turned
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A GarmentCode-like sleeve: a 54 x 18.7 cm panel rotated `rz` degrees about z, on the
    /// body's right for a positive angle, its left (mirrored) for a negative one.
    fn pattern_with_sleeve(rz: f64) -> Pattern {
        let (x, m) = (-63.1f64.copysign(rz), rz.signum());
        let json = format!(
            r#"{{"pattern": {{"panels": {{
                "sleeve": {{"translation": [{x}, 93.9, 17.5], "rotation": [0, 0, {rz}],
                    "vertices": [[0, 0], [0, -18.7], [{a}, -18.7], [{b}, 0]],
                    "edges": [{{"endpoints": [0, 1]}}, {{"endpoints": [1, 2]}},
                              {{"endpoints": [2, 3]}}, {{"endpoints": [3, 0]}}]}},
                "front": {{"translation": [0, 98, 25], "rotation": [0, 0, 0],
                    "vertices": [[0, 0], [20, 0], [20, 40], [0, 40]],
                    "edges": [{{"endpoints": [0, 1]}}, {{"endpoints": [1, 2]}},
                              {{"endpoints": [2, 3]}}, {{"endpoints": [3, 0]}}]}}
            }}, "stitches": []}}, "properties": {{"units_in_meter": 100}}}}"#,
            a = 38.3 * m,
            b = 54.0 * m,
        );
        Pattern::parse("p", &json).unwrap()
    }

    #[test]
    fn a_sleeve_turns_to_the_arm_about_its_highest_corner() {
        for rz in [50.48, -50.48] {
            let mut p = pattern_with_sleeve(rz);
            let before = p.clone();
            let panel =
                |p: &Pattern, name: &str| p.panels.iter().find(|q| q.name == name).unwrap().clone();
            let end = 54.0 * rz.signum();
            let top = |p: &Pattern| panel(p, "sleeve").place([end, 0.0]);
            assert_eq!(p.seat_sleeves(ARM_ANGLE_DEG), ["sleeve"]);
            assert_eq!(
                panel(&p, "sleeve").rotation,
                [0.0, 0.0, 40.0f64.copysign(rz)]
            );
            // The armhole's top corner stays; the cuff comes up to the arm.
            let (a, b) = (top(&before), top(&p));
            assert!((0..3).all(|i| (a[i] - b[i]).abs() < 1e-9), "{a:?} {b:?}");
            let axis = |p: &Pattern| {
                let sleeve = panel(p, "sleeve");
                let (c, t) = (sleeve.place([0.0, 0.0]), sleeve.place([end, 0.0]));
                ((t[1] - c[1]) / (t[0] - c[0]).abs()).atan().to_degrees()
            };
            assert!((axis(&p) - 40.0).abs() < 1e-9, "{}", axis(&p));
            assert!(axis(&before) > 50.0);
            // Torso panels stay; the specification written back is the seated one.
            assert_eq!(panel(&p, "front"), panel(&before, "front"));
            assert_ne!(p.to_json(), before.to_json());
            assert_eq!(Pattern::parse("p", &p.to_json()).unwrap().panels, p.panels);
            // Seating twice changes nothing more.
            assert!(p.seat_sleeves(ARM_ANGLE_DEG).is_empty());
        }
    }
}
