//! The design library: a parametric generator of upper-body sewing patterns (tops and
//! dresses) that writes GarmentCode specification JSON, and the named designs made with it.
//!
//! Every design has a front and a back torso panel (the back's outline runs clockwise, as
//! GarmentCode's do, so stitches join end to start) and, when it has sleeves, a front and a
//! back panel per sleeve, rotated like GarmentCode's for an A-pose with the arms 40 degrees
//! down and placed, as GarmentCode places its sleeves, a little out along the arm from the
//! torso's armhole (so the arm runs inside the sleeve before the seams close). Measurements are in cm on GarmentCode's average body (feet at y = 0, facing +z):
//! `sim::sewing` fits them to our body.

use serde_json::{Value, json};

mod family;
mod summary;
mod variants;
pub use family::Family;
pub use summary::DesignSummary;
pub use variants::{MAX_INDEX, NamedDesign, VariantKind, naming, resolve, variant_name};

use crate::error::Result;
use crate::pattern::{Curve, Pattern, SpecFile};

/// Neckline shape.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Neckline {
    /// A round neck (circle arcs).
    Round,
    /// A V neck (straight edges).
    V,
    /// A scooped neck (quadratic curves).
    Scoop,
}

use serde::Serialize;

/// The parameters of one design, cm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DesignParams {
    /// Hem height above the feet.
    pub hem_height: f64,
    /// Half-width of a torso panel at the armpit.
    pub chest_half_width: f64,
    /// Half-width of a torso panel at the hem.
    pub hem_half_width: f64,
    /// Armhole drop below the standard armpit (loose and dropped-shoulder fits).
    pub armhole_drop: f64,
    /// Shoulder point distance from the centre line.
    pub shoulder_half_width: f64,
    /// Neck point distance from the centre line.
    pub neck_half_width: f64,
    /// Front neck depth below the neck points.
    pub front_neck_depth: f64,
    /// Back neck depth.
    pub back_neck_depth: f64,
    /// Neckline shape.
    pub neckline: Neckline,
    /// Sleeve length along the top of the arm (0: sleeveless).
    pub sleeve_length: f64,
    /// Half-circumference of the sleeve at the cuff (capped by the armhole).
    pub cuff_half_width: f64,
}

/// A named design.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Design {
    /// Name.
    pub name: &'static str,
    /// What it is.
    pub description: &'static str,
    /// "train" or "test" (held out, as the seed paper's 3 unseen designs).
    pub split: &'static str,
    /// Parameters.
    pub params: DesignParams,
}

/// A regular fit: t-shirt proportions of GarmentCode's `shirt_mean` on its average body.
pub const REGULAR: DesignParams = DesignParams {
    hem_height: 94.6,
    chest_half_width: 27.0,
    hem_half_width: 27.5,
    armhole_drop: 0.0,
    shoulder_half_width: 17.5,
    neck_half_width: 10.0,
    front_neck_depth: 10.0,
    back_neck_depth: 3.0,
    neckline: Neckline::Round,
    sleeve_length: 22.0,
    cuff_half_width: 17.0,
};

const fn top(
    hem: f64,
    chest: f64,
    hem_w: f64,
    drop: f64,
    shoulder: f64,
    sleeve: f64,
    cuff: f64,
) -> DesignParams {
    DesignParams {
        hem_height: hem,
        chest_half_width: chest,
        hem_half_width: hem_w,
        armhole_drop: drop,
        shoulder_half_width: shoulder,
        sleeve_length: sleeve,
        cuff_half_width: cuff,
        ..REGULAR
    }
}

const fn neck(
    mut p: DesignParams,
    line: Neckline,
    half: f64,
    front: f64,
    back: f64,
) -> DesignParams {
    p.neckline = line;
    p.neck_half_width = half;
    p.front_neck_depth = front;
    p.back_neck_depth = back;
    p
}

/// The library: 19 designs from tight tank tops to loose dresses; 3 held out for testing
/// (a v-neck tee, an elbow-sleeve top and a loose maxi dress).
pub const DESIGNS: [Design; 19] = [
    Design {
        name: "tank_tight",
        description: "tight tank top, narrow straps, scoop neck",
        split: "train",
        params: neck(
            top(94.6, 24.5, 25.5, 2.0, 15.0, 0.0, 0.0),
            Neckline::Scoop,
            11.0,
            13.0,
            5.0,
        ),
    },
    Design {
        name: "tank_loose",
        description: "loose tank top, wide straps",
        split: "train",
        params: neck(
            top(92.0, 30.0, 31.0, 4.0, 17.0, 0.0, 0.0),
            Neckline::Scoop,
            10.5,
            12.0,
            4.0,
        ),
    },
    Design {
        name: "camisole_long",
        description: "hip-long camisole, round neck",
        split: "train",
        params: neck(
            top(82.0, 26.0, 29.0, 3.0, 15.5, 0.0, 0.0),
            Neckline::Round,
            11.0,
            12.0,
            4.0,
        ),
    },
    Design {
        name: "tshirt_fitted",
        description: "fitted t-shirt, short sleeves",
        split: "train",
        params: top(94.6, 25.5, 26.0, 0.0, 17.0, 18.0, 15.0),
    },
    Design {
        name: "tshirt_regular",
        description: "regular t-shirt",
        split: "train",
        params: REGULAR,
    },
    Design {
        name: "tshirt_oversized",
        description: "oversized t-shirt, dropped armholes",
        split: "train",
        params: top(90.0, 32.0, 32.0, 3.0, 20.0, 24.0, 19.0),
    },
    Design {
        name: "tshirt_cropped",
        description: "cropped t-shirt",
        split: "train",
        params: top(106.0, 27.0, 27.5, 0.0, 17.5, 20.0, 16.0),
    },
    Design {
        name: "cap_sleeve_top",
        description: "top with cap sleeves",
        split: "train",
        params: top(94.6, 26.0, 26.5, 0.0, 17.5, 9.0, 18.0),
    },
    Design {
        name: "elbow_sleeve_top",
        description: "elbow-length sleeves, relaxed fit",
        split: "test",
        params: top(93.0, 28.0, 28.5, 1.0, 18.0, 38.0, 14.0),
    },
    Design {
        name: "longsleeve_fitted",
        description: "fitted long-sleeve top",
        split: "train",
        params: top(94.6, 25.5, 26.0, 0.0, 17.0, 55.0, 9.0),
    },
    Design {
        name: "longsleeve_loose",
        description: "loose long-sleeve top",
        split: "train",
        params: top(92.0, 31.0, 31.5, 4.0, 19.0, 57.0, 12.0),
    },
    Design {
        name: "tunic_longsleeve",
        description: "tunic, long sleeves, thigh length",
        split: "train",
        params: top(76.0, 28.0, 31.0, 1.0, 18.0, 55.0, 10.0),
    },
    Design {
        name: "vneck_tee",
        description: "v-neck t-shirt",
        split: "test",
        params: neck(REGULAR, Neckline::V, 10.5, 18.0, 3.0),
    },
    Design {
        name: "boatneck_top",
        description: "boat neck, short sleeves",
        split: "train",
        params: neck(
            top(94.6, 27.0, 27.5, 0.0, 18.5, 16.0, 16.0),
            Neckline::Round,
            14.0,
            4.0,
            2.5,
        ),
    },
    Design {
        name: "tunic_sleeveless",
        description: "loose sleeveless tunic",
        split: "train",
        params: top(74.0, 31.0, 34.0, 4.0, 17.5, 0.0, 0.0),
    },
    Design {
        name: "dress_tank_aline",
        description: "sleeveless A-line dress, knee length",
        split: "train",
        params: neck(
            top(55.0, 26.5, 38.0, 2.0, 16.0, 0.0, 0.0),
            Neckline::Scoop,
            11.0,
            12.0,
            5.0,
        ),
    },
    Design {
        name: "dress_tshirt",
        description: "t-shirt dress, above the knee",
        split: "train",
        params: top(62.0, 28.0, 31.0, 0.0, 17.5, 20.0, 16.0),
    },
    Design {
        name: "dress_longsleeve_midi",
        description: "long-sleeve midi dress",
        split: "train",
        params: top(45.0, 27.0, 40.0, 0.0, 17.5, 55.0, 10.0),
    },
    Design {
        name: "dress_loose_maxi",
        description: "loose sleeveless maxi dress",
        split: "test",
        params: neck(
            top(40.0, 31.0, 44.0, 4.0, 17.0, 0.0, 0.0),
            Neckline::Round,
            11.0,
            11.0,
            4.0,
        ),
    },
];

/// The design of that name.
pub fn find(name: &str) -> Option<&'static Design> {
    DESIGNS.iter().find(|d| d.name == name)
}

/// Names of all designs.
pub fn design_names() -> Vec<&'static str> {
    DESIGNS.iter().map(|d| d.name).collect()
}

/// Armpit height on GarmentCode's average body, cm.
const ARMPIT_Y: f64 = 120.8;
/// Shoulder point and neck point heights, cm.
const SHOULDER_Y: f64 = 138.8;
const NECK_Y: f64 = 140.6;
/// Torso panels' distance in front of and behind the body, cm.
const FRONT_Z: f64 = 25.0;
const BACK_Z: f64 = -20.0;
/// Sleeve panels' z, cm.
const SLEEVE_FRONT_Z: f64 = 17.5;
const SLEEVE_BACK_Z: f64 = -12.5;
/// Sleeve rotation about z for the arm 40 degrees down (GarmentCode's), degrees.
const SLEEVE_ANGLE: f64 = 50.483;
/// How far out along the arm the sleeve's armhole starts from the torso's, cm.
const SLEEVE_OFFSET: f64 = 7.0;

/// Point to edge coordinates (GarmentCode's `abs_to_rel_2d`).
fn relative(start: [f64; 2], end: [f64; 2], p: [f64; 2]) -> [f64; 2] {
    let d = [end[0] - start[0], end[1] - start[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let v = [p[0] - start[0], p[1] - start[1]];
    [
        (v[0] * d[0] + v[1] * d[1]) / len2,
        (d[0] * v[1] - d[1] * v[0]) / len2,
    ]
}

fn edge(a: usize, b: usize, curvature: Option<Value>) -> Value {
    match curvature {
        Some(c) => json!({"endpoints": [a, b], "curvature": c}),
        None => json!({"endpoints": [a, b]}),
    }
}

fn quadratic(s: [f64; 2], e: [f64; 2], control: [f64; 2]) -> Value {
    json!({"type": "quadratic", "params": [relative(s, e, control)]})
}

impl Design {
    /// The design as a checked pattern.
    pub fn pattern(&self) -> Result<Pattern> {
        self.params.pattern(self.name)
    }

    /// The design as GarmentCode specification JSON.
    pub fn spec(&self) -> SpecFile {
        self.params.spec()
    }
}

/// An armhole from `a` to `b`, curving in towards the corner (inner x, lower y).
fn armhole_scoop(a: [f64; 2], b: [f64; 2]) -> Value {
    let corner = [a[0].abs().min(b[0].abs()) * a[0].signum(), a[1].min(b[1])];
    let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    quadratic(
        a,
        b,
        [(corner[0] + mid[0]) / 2.0, (corner[1] + mid[1]) / 2.0],
    )
}

impl DesignParams {
    /// These measurements as a checked pattern named `name`.
    pub fn pattern(&self, name: &str) -> Result<Pattern> {
        Pattern::from_spec(name, self.spec())
    }

    /// These measurements as GarmentCode specification JSON.
    pub fn spec(&self) -> SpecFile {
        let p = self;
        let mut panels = serde_json::Map::new();
        let mut stitches = Vec::new();
        for (front, depth) in [(true, p.front_neck_depth), (false, p.back_neck_depth)] {
            let (name, panel) = self.bodice_panel(front, depth);
            panels.insert(name.into(), panel);
        }
        let st = |a: &str, ea: usize, b: &str, eb: usize| json!([{"panel": a, "edge": ea}, {"panel": b, "edge": eb}]);
        // Front edges: 1 side +x, 3 shoulder +x, 6 shoulder -x, 8 side -x, 2 / 7 armholes.
        // Back edges (clockwise from the hem corner at -x): 0 side -x, 1 armhole -x,
        // 2 shoulder -x, 5 shoulder +x, 6 armhole +x, 7 side +x.
        stitches.push(st("front", 1, "back", 7));
        stitches.push(st("front", 8, "back", 0));
        stitches.push(st("front", 3, "back", 5));
        stitches.push(st("front", 6, "back", 2));
        if p.sleeve_length > 0.0 {
            let v = self.bodice_corners(p.front_neck_depth);
            self.add_sleeves(&mut panels, &mut stitches, v[2], v[3]);
        }
        SpecFile {
            pattern: crate::pattern::PatternJson {
                panels: serde_json::from_value(Value::Object(panels)).unwrap_or_default(),
                stitches: stitches
                    .into_iter()
                    .map(|s| s.as_array().cloned().unwrap_or_default())
                    .collect(),
                panel_order: None,
            },
            parameters: serde_json::to_value(p).unwrap_or(Value::Null),
            parameter_order: json!([]),
            properties: crate::pattern::PropertiesJson {
                curvature_coords: "relative".into(),
                normalize_panel_translation: false,
                normalized_edge_loops: true,
                units_in_meter: 100.0,
            },
        }
    }

    /// The bodice's nine corners, counter-clockwise for the front: hem, +x side, armhole,
    /// shoulder, neck, centre of the neckline (`depth` below the neck points), then the -x
    /// side.
    fn bodice_corners(&self, depth: f64) -> [[f64; 2]; 9] {
        let p = self;
        let ya = ARMPIT_Y - p.armhole_drop - p.hem_height;
        let ys = SHOULDER_Y - p.hem_height;
        let yn = NECK_Y - p.hem_height;
        let (wh, wc, xs, xn) = (
            p.hem_half_width,
            p.chest_half_width,
            p.shoulder_half_width,
            p.neck_half_width,
        );
        [
            [-wh, 0.0],
            [wh, 0.0],
            [wc, ya],
            [xs, ys],
            [xn, yn],
            [0.0, yn - depth],
            [-xn, yn],
            [-xs, ys],
            [-wc, ya],
        ]
    }

    /// The neckline's curve from `a` to `b` (one of them its centre), by neckline kind.
    fn neck_curve(&self, a: [f64; 2], b: [f64; 2]) -> Option<Value> {
        match self.neckline {
            Neckline::V => None,
            Neckline::Scoop => {
                // Horizontal at the centre, falling steeply from the neck point.
                let centre = if a[0] == 0.0 { a } else { b };
                let side = if a[0] == 0.0 { b } else { a };
                Some(quadratic(a, b, [side[0], centre[1]]))
            }
            Neckline::Round => {
                // The circle through both ends that is horizontal at the centre of the
                // neckline: r = (dx^2 + dy^2) / (2 dy), its centre above the neckline.
                let (dx, dy) = ((a[0] - b[0]).abs(), (a[1] - b[1]).abs().max(1e-6));
                let radius = (dx * dx + dy * dy) / (2.0 * dy);
                Some(json!({"type": "circle", "params": [radius, false, a[0] < b[0]]}))
            }
        }
    }

    /// The front (edges counter-clockwise) or back (clockwise) bodice panel as GarmentCode
    /// JSON, with its name.
    fn bodice_panel(&self, front: bool, depth: f64) -> (&'static str, Value) {
        let v = self.bodice_corners(depth);
        let (name, z, edges) = if front {
            let curves: [Option<Value>; 9] = [
                None,
                None,
                Some(armhole_scoop(v[2], v[3])),
                None,
                self.neck_curve(v[4], v[5]),
                self.neck_curve(v[5], v[6]),
                None,
                Some(armhole_scoop(v[7], v[8])),
                None,
            ];
            let edges: Vec<Value> = (0..9)
                .map(|i| edge(i, (i + 1) % 9, curves[i].clone()))
                .collect();
            ("front", FRONT_Z, edges)
        } else {
            // Clockwise: the same corners in reverse order; reversed curves keep their shape
            // when their control points are recomputed for the reversed direction.
            let edges: Vec<Value> = (0..9)
                .map(|k| {
                    let (a, b) = ((9 - k) % 9, (17 - k) % 9);
                    let c = match b {
                        2 => Some(armhole_scoop(v[3], v[2])),
                        7 => Some(armhole_scoop(v[8], v[7])),
                        4 => self.neck_curve(v[5], v[4]),
                        5 => self.neck_curve(v[6], v[5]),
                        _ => None,
                    };
                    edge(a, b, c)
                })
                .collect();
            ("back", BACK_Z, edges)
        };
        let panel = json!({
            "translation": [0.0, self.hem_height, z],
            "rotation": [0.0, 0.0, 0.0],
            "vertices": v,
            "edges": edges,
        });
        (name, panel)
    }

    fn add_sleeves(
        &self,
        panels: &mut serde_json::Map<String, Value>,
        stitches: &mut Vec<Value>,
        armpit: [f64; 2],
        shoulder: [f64; 2],
    ) {
        let p = self;
        // The armhole's length on the torso sets the sleeve's width there.
        let corner = [shoulder[0], armpit[1]];
        let mid = [
            (armpit[0] + shoulder[0]) / 2.0,
            (armpit[1] + shoulder[1]) / 2.0,
        ];
        let control = relative(
            armpit,
            shoulder,
            [(corner[0] + mid[0]) / 2.0, (corner[1] + mid[1]) / 2.0],
        );
        let armhole = Curve::Quadratic(control).length(armpit, shoulder);
        let width = 0.92 * armhole;
        let slope = (armhole * armhole - width * width).max(0.0).sqrt();
        let top = p.sleeve_length;
        let bottom = (top - slope).max(2.0);
        let cuff = p.cuff_half_width.min(width);
        let st = |a: &str, ea: usize, b: &str, eb: usize| json!([{"panel": a, "edge": ea}, {"panel": b, "edge": eb}]);
        for side in [1.0f64, -1.0] {
            // Cuff top at the origin, the arm's top edge along -x (mirrored for -x).
            let pts = [
                [0.0, 0.0],
                [-side * top, 0.0],
                [-side * bottom, -width],
                [0.0, -cuff],
            ];
            let angle = -side * SLEEVE_ANGLE;
            let (sin, cos) = angle.to_radians().sin_cos();
            // Translation puts the middle of the sleeve's armhole a little out along the arm
            // from the middle of the torso's armhole, as GarmentCode places its sleeves
            // (shirt_mean: 7 cm): the arm then runs inside the sleeve from the start.
            let rotate = |q: [f64; 2]| [cos * q[0] - sin * q[1], sin * q[0] + cos * q[1]];
            let sleeve_mid = rotate([-side * (top + bottom) / 2.0, -width / 2.0]);
            let torso_mid = [
                side * (armpit[0] + shoulder[0]) / 2.0,
                (armpit[1] + shoulder[1]) / 2.0 + p.hem_height,
            ];
            let along = rotate([side * SLEEVE_OFFSET, 0.0]);
            let t = [
                torso_mid[0] + along[0] - sleeve_mid[0],
                torso_mid[1] + along[1] - sleeve_mid[1],
            ];
            let tag = if side > 0.0 { "left" } else { "right" };
            for (front, z) in [(true, SLEEVE_FRONT_Z), (false, SLEEVE_BACK_Z)] {
                // Counter-clockwise order 0 1 2 3 for the +x front and the -x back.
                let ccw = front == (side > 0.0);
                let order: [usize; 4] = if ccw { [0, 1, 2, 3] } else { [0, 3, 2, 1] };
                let edges: Vec<Value> = (0..4)
                    .map(|i| edge(order[i], order[(i + 1) % 4], None))
                    .collect();
                let name = format!("{tag}_sleeve_{}", if front { "f" } else { "b" });
                panels.insert(
                    name,
                    json!({
                        "translation": [t[0], t[1], z],
                        "rotation": [0.0, 0.0, angle],
                        "vertices": pts,
                        "edges": edges,
                    }),
                );
            }
            // Edge k joins order[k] -> order[k + 1]: with [0,1,2,3]: 0 top, 1 armhole,
            // 2 underarm, 3 cuff; with [0,3,2,1]: 0 cuff, 1 underarm, 2 armhole, 3 top.
            let (f, b) = (format!("{tag}_sleeve_f"), format!("{tag}_sleeve_b"));
            if side > 0.0 {
                stitches.push(st(&f, 0, &b, 3));
                stitches.push(st(&f, 2, &b, 1));
                stitches.push(st(&f, 1, "front", 2));
                stitches.push(st(&b, 2, "back", 6));
            } else {
                stitches.push(st(&f, 3, &b, 0));
                stitches.push(st(&f, 1, &b, 2));
                stitches.push(st(&f, 2, "front", 7));
                stitches.push(st(&b, 1, "back", 1));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_design_is_a_valid_pattern_that_round_trips() {
        let mut kinds = std::collections::BTreeSet::new();
        for d in DESIGNS {
            let p = d.pattern().unwrap_or_else(|e| panic!("{}: {e}", d.name));
            let back = Pattern::parse(d.name, &p.to_json()).unwrap();
            assert_eq!(back.panels, p.panels, "{}", d.name);
            assert_eq!(back.stitches, p.stitches, "{}", d.name);
            for panel in &p.panels {
                for e in &panel.edges {
                    kinds.insert(match e.curve {
                        Curve::Line => "line",
                        Curve::Quadratic(_) => "quadratic",
                        Curve::Cubic(_) => "cubic",
                        Curve::Circle { .. } => "circle",
                    });
                }
            }
            // Every stitch joins edges of (nearly) the same length.
            for s in &p.stitches {
                let la = p.panels[s.a.panel].edge_length(s.a.edge);
                let lb = p.panels[s.b.panel].edge_length(s.b.edge);
                assert!((la / lb - 1.0).abs() < 0.02, "{}: {la} vs {lb}", d.name);
            }
        }
        assert!(kinds.contains("line") && kinds.contains("quadratic") && kinds.contains("circle"));
        assert!(DESIGNS.len() >= 16);
        let tests: Vec<&str> = DESIGNS
            .iter()
            .filter(|d| d.split == "test")
            .map(|d| d.name)
            .collect();
        assert!(
            tests.len() >= 3 && tests.iter().any(|n| n.starts_with("dress")),
            "{tests:?}"
        );
    }

    #[test]
    fn necklines_dip_below_their_chords_and_armholes_curve_in() {
        for d in DESIGNS {
            let p = d.pattern().unwrap();
            for panel in &p.panels {
                for (e, edge) in panel.edges.iter().enumerate() {
                    if edge.curve == Curve::Line {
                        continue;
                    }
                    let (s, t) = panel.edge_ends(e);
                    let mid = edge.curve.point(s, t, 0.5);
                    assert!(
                        mid[1] < (s[1] + t[1]) / 2.0 + 1e-9,
                        "{} {} edge {e}: {mid:?} above the chord {s:?}-{t:?}",
                        d.name,
                        panel.name
                    );
                }
            }
        }
    }

    #[test]
    fn meshes_are_typical_template_sizes() {
        for name in ["tank_tight", "tshirt_regular", "dress_loose_maxi"] {
            let m = find(name).unwrap().pattern().unwrap().mesh(0.015).unwrap();
            let merged = m.merged(&m.garment.positions).unwrap();
            let n = merged.positions.len();
            assert!((1_500..=12_000).contains(&n), "{name}: {n} vertices");
            assert!(
                crate::check(&merged).findings.is_empty(),
                "{name}: {:?}",
                crate::check(&merged)
            );
        }
    }
}
