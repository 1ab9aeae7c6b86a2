//! Pinhole cameras and automatic framing from named views.

use crate::P3;

/// A named viewpoint around a body standing with y up and facing +z.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// From the front (+z), slightly above.
    Front,
    /// From the body's left (+x), slightly above.
    Side,
    /// Halfway between front and side, slightly above: shows depth and folds best.
    ThreeQuarter,
}

impl View {
    /// Every view, in the order contact sheets use.
    pub const ALL: [View; 3] = [View::Front, View::ThreeQuarter, View::Side];

    /// The name used in file names and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            View::Front => "front",
            View::Side => "side",
            View::ThreeQuarter => "three-quarter",
        }
    }

    /// Parses `front`, `side` or `three-quarter`.
    pub fn parse(name: &str) -> Option<View> {
        View::ALL.into_iter().find(|v| v.name() == name)
    }

    /// Unit vector from the subject towards the camera.
    fn towards_camera(self) -> P3 {
        let elevation = 8f32.to_radians();
        let azimuth = match self {
            View::Front => 0f32,
            View::ThreeQuarter => 40f32.to_radians(),
            View::Side => 90f32.to_radians(),
        };
        [
            azimuth.sin() * elevation.cos(),
            elevation.sin(),
            azimuth.cos() * elevation.cos(),
        ]
    }
}

/// Axis-aligned bounds of a point set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Smallest coordinates.
    pub min: P3,
    /// Largest coordinates.
    pub max: P3,
}

impl Bounds {
    /// Bounds of the finite points (`None` if there are none).
    pub fn of<'a>(points: impl IntoIterator<Item = &'a P3>) -> Option<Bounds> {
        let mut b: Option<Bounds> = None;
        for p in points
            .into_iter()
            .filter(|p| p.iter().all(|c| c.is_finite()))
        {
            b = Some(match b {
                None => Bounds { min: *p, max: *p },
                Some(b) => Bounds {
                    min: std::array::from_fn(|i| b.min[i].min(p[i])),
                    max: std::array::from_fn(|i| b.max[i].max(p[i])),
                },
            });
        }
        b
    }

    /// The smallest bounds holding both.
    pub fn union(self, other: Bounds) -> Bounds {
        Bounds {
            min: std::array::from_fn(|i| self.min[i].min(other.min[i])),
            max: std::array::from_fn(|i| self.max[i].max(other.max[i])),
        }
    }

    /// Centre point.
    pub fn center(&self) -> P3 {
        std::array::from_fn(|i| 0.5 * (self.min[i] + self.max[i]))
    }

    /// The same size moved to a new centre: a sequence keeps one framing size while the
    /// camera follows the body.
    pub fn recentred(&self, center: P3) -> Bounds {
        Bounds {
            min: std::array::from_fn(|i| center[i] - 0.5 * (self.max[i] - self.min[i])),
            max: std::array::from_fn(|i| center[i] + 0.5 * (self.max[i] - self.min[i])),
        }
    }

    /// Bounds with each side grown to the largest of both (centred on `self`).
    pub fn with_size_of(&self, other: &Bounds) -> Bounds {
        let size: P3 =
            std::array::from_fn(|i| (self.max[i] - self.min[i]).max(other.max[i] - other.min[i]));
        let c = self.center();
        Bounds {
            min: std::array::from_fn(|i| c[i] - 0.5 * size[i]),
            max: std::array::from_fn(|i| c[i] + 0.5 * size[i]),
        }
    }
}

/// A pinhole camera: position, orthonormal frame and focal length (1 / tan(fov_y / 2)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: P3,
    /// Image right, world units.
    pub right: P3,
    /// Image up.
    pub up: P3,
    /// Viewing direction (into the picture).
    pub forward: P3,
    /// 1 / tan(fov_y / 2).
    pub focal: f32,
}

/// Vertical field of view of framed cameras: a moderate telephoto, so bodies are not distorted.
const FRAMING_FOV_DEG: f32 = 30.0;
/// Fraction of the half-image the framed subject may fill.
const FRAMING_FILL: f32 = 0.9;

impl Camera {
    /// A camera at `eye` looking at `target`, with `up` as the approximate up direction.
    pub fn look_at(eye: P3, target: P3, up: P3, fov_y_deg: f32) -> Camera {
        let forward = normalize(sub(target, eye));
        let right = normalize(cross(forward, up));
        let up = cross(right, forward);
        Camera {
            eye,
            right,
            up,
            forward,
            focal: 1.0 / (0.5 * fov_y_deg.to_radians()).tan(),
        }
    }

    /// A camera looking from `view` at `bounds`, close enough that the box just fills the image
    /// (with a margin) for the given width / height ratio.
    pub fn framing(view: View, bounds: &Bounds, aspect: f32) -> Camera {
        let towards = view.towards_camera();
        let center = bounds.center();
        let probe = Camera::look_at(
            add(center, towards),
            center,
            [0.0, 1.0, 0.0],
            FRAMING_FOV_DEG,
        );
        let mut distance = 0.0f32;
        for corner in 0..8 {
            let p: P3 = std::array::from_fn(|i| {
                if corner >> i & 1 == 0 {
                    bounds.min[i]
                } else {
                    bounds.max[i]
                }
            });
            let rel = sub(p, center);
            let half = (dot(rel, probe.right).abs() / aspect).max(dot(rel, probe.up).abs());
            distance = distance.max(dot(rel, towards) + half * probe.focal / FRAMING_FILL);
        }
        let distance = distance.max(1e-3);
        Camera {
            eye: add(center, scale(towards, distance)),
            ..probe
        }
    }

    /// Camera-space coordinates of a world point: (right, up, depth along the view).
    #[inline]
    pub fn to_camera(&self, p: P3) -> P3 {
        let d = sub(p, self.eye);
        [dot(d, self.right), dot(d, self.up), dot(d, self.forward)]
    }
}

#[inline]
pub(crate) fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub(crate) fn add(a: P3, b: P3) -> P3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub(crate) fn scale(a: P3, s: f32) -> P3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline]
pub(crate) fn dot(a: P3, b: P3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
pub(crate) fn normalize(a: P3) -> P3 {
    let n = dot(a, a).sqrt();
    if n > 0.0 { scale(a, 1.0 / n) } else { a }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_keeps_every_corner_inside_the_image() {
        let b = Bounds {
            min: [-0.4, 0.0, -0.2],
            max: [0.4, 1.7, 0.3],
        };
        for view in View::ALL {
            let c = Camera::framing(view, &b, 1.0);
            for corner in 0..8 {
                let p: P3 = std::array::from_fn(|i| {
                    if corner >> i & 1 == 0 {
                        b.min[i]
                    } else {
                        b.max[i]
                    }
                });
                let q = c.to_camera(p);
                assert!(q[2] > 0.0, "{view:?}: corner behind the camera");
                let (x, y) = (q[0] / q[2] * c.focal, q[1] / q[2] * c.focal);
                assert!(
                    x.abs() <= 1.0 && y.abs() <= 1.0,
                    "{view:?}: corner {p:?} at {x},{y}"
                );
            }
        }
    }

    #[test]
    fn views_parse_from_their_names() {
        for v in View::ALL {
            assert_eq!(View::parse(v.name()), Some(v));
        }
        assert_eq!(View::parse("top"), None);
    }
}
