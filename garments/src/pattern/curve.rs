//! Panel edges as curves: straight, quadratic and cubic Bezier with control points relative to
//! the edge (t along it, h across it, as GarmentCode's `rel_to_abs_2d`), and SVG-style circle
//! arcs (radius, large-arc flag, sweep flag `right`). Edges are resampled uniformly by arc
//! length.

/// The shape of one edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Curve {
    /// A straight segment.
    Line,
    /// Quadratic Bezier, one control point in edge coordinates.
    Quadratic([f64; 2]),
    /// Cubic Bezier, two control points in edge coordinates.
    Cubic([[f64; 2]; 2]),
    /// Circle arc (absolute radius in pattern units).
    Circle {
        /// Radius; raised to half the chord when smaller, as SVG does.
        radius: f64,
        /// Take the larger of the two arcs.
        large_arc: bool,
        /// Sweep towards increasing angle.
        right: bool,
    },
}

/// Polyline segments per curved edge used for lengths and resampling.
const SEGMENTS: usize = 512;

fn lerp(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
}

/// A point given in the edge's frame (t along start -> end, h along its left normal).
pub fn relative_to_absolute(start: [f64; 2], end: [f64; 2], rel: [f64; 2]) -> [f64; 2] {
    let d = [end[0] - start[0], end[1] - start[1]];
    [
        start[0] + rel[0] * d[0] - rel[1] * d[1],
        start[1] + rel[0] * d[1] + rel[1] * d[0],
    ]
}

/// Centre, radius, start angle and signed sweep of an SVG arc from `start` to `end`.
fn arc(
    start: [f64; 2],
    end: [f64; 2],
    radius: f64,
    large: bool,
    sweep: bool,
) -> ([f64; 2], f64, f64, f64) {
    let half = [(start[0] - end[0]) / 2.0, (start[1] - end[1]) / 2.0];
    let half_len2 = half[0] * half[0] + half[1] * half[1];
    let r = radius.abs().max(half_len2.sqrt());
    let root = ((r * r - half_len2) / half_len2).max(0.0).sqrt();
    let sign = if large != sweep { 1.0 } else { -1.0 };
    let c_rel = [sign * root * half[1], -sign * root * half[0]];
    let centre = [
        c_rel[0] + (start[0] + end[0]) / 2.0,
        c_rel[1] + (start[1] + end[1]) / 2.0,
    ];
    let a0 = (start[1] - centre[1]).atan2(start[0] - centre[0]);
    let a1 = (end[1] - centre[1]).atan2(end[0] - centre[0]);
    let mut delta = a1 - a0;
    use std::f64::consts::TAU;
    if sweep && delta < 0.0 {
        delta += TAU;
    } else if !sweep && delta > 0.0 {
        delta -= TAU;
    }
    (centre, r, a0, delta)
}

impl Curve {
    /// The point at parameter `t` in [0, 1] (not arc length).
    pub fn point(&self, start: [f64; 2], end: [f64; 2], t: f64) -> [f64; 2] {
        match *self {
            Curve::Line => lerp(start, end, t),
            Curve::Quadratic(c) => {
                let c = relative_to_absolute(start, end, c);
                lerp(lerp(start, c, t), lerp(c, end, t), t)
            }
            Curve::Cubic([c1, c2]) => {
                let (c1, c2) = (
                    relative_to_absolute(start, end, c1),
                    relative_to_absolute(start, end, c2),
                );
                let (a, b, c) = (lerp(start, c1, t), lerp(c1, c2, t), lerp(c2, end, t));
                lerp(lerp(a, b, t), lerp(b, c, t), t)
            }
            Curve::Circle {
                radius,
                large_arc,
                right,
            } => {
                if t <= 0.0 {
                    return start;
                }
                if t >= 1.0 {
                    return end;
                }
                let (c, r, a0, delta) = arc(start, end, radius, large_arc, right);
                let a = a0 + delta * t;
                [c[0] + r * a.cos(), c[1] + r * a.sin()]
            }
        }
    }

    /// A dense polyline along the curve (both ends included).
    pub fn polyline(&self, start: [f64; 2], end: [f64; 2]) -> Vec<[f64; 2]> {
        let segments = if *self == Curve::Line { 1 } else { SEGMENTS };
        (0..=segments)
            .map(|k| self.point(start, end, k as f64 / segments as f64))
            .collect()
    }

    /// Arc length.
    pub fn length(&self, start: [f64; 2], end: [f64; 2]) -> f64 {
        polyline_length(&self.polyline(start, end))
    }

    /// `count` >= 2 points spaced uniformly by arc length, both ends included.
    pub fn resample(&self, start: [f64; 2], end: [f64; 2], count: usize) -> Vec<[f64; 2]> {
        let line = self.polyline(start, end);
        let mut cumulative = vec![0.0];
        for w in line.windows(2) {
            let last = *cumulative.last().unwrap_or(&0.0);
            cumulative.push(last + dist(w[0], w[1]));
        }
        let total = *cumulative.last().unwrap_or(&0.0);
        let mut out = Vec::with_capacity(count);
        let mut seg = 0;
        for k in 0..count {
            if k == 0 {
                out.push(start);
                continue;
            }
            if k == count - 1 {
                out.push(end);
                continue;
            }
            let s = total * k as f64 / (count - 1) as f64;
            while seg + 1 < line.len() - 1 && cumulative[seg + 1] < s {
                seg += 1;
            }
            let span = (cumulative[seg + 1] - cumulative[seg]).max(1e-300);
            out.push(lerp(line[seg], line[seg + 1], (s - cumulative[seg]) / span));
        }
        out
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn polyline_length(line: &[[f64; 2]]) -> f64 {
    line.windows(2).map(|w| dist(w[0], w[1])).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn edge_frame_matches_garmentcode() {
        // t along, h across the left normal (-dy, dx).
        let p = relative_to_absolute([1.0, 1.0], [3.0, 1.0], [0.5, 0.25]);
        assert!((p[0] - 2.0).abs() < 1e-12 && (p[1] - 1.5).abs() < 1e-12);
    }

    #[test]
    fn lengths_of_every_edge_type() {
        let (s, e) = ([0.0, 0.0], [2.0, 0.0]);
        assert!((Curve::Line.length(s, e) - 2.0).abs() < 1e-12);
        // A half circle of radius 1 either way; a quarter with the small arc of radius sqrt 2.
        for right in [false, true] {
            let half = Curve::Circle {
                radius: 1.0,
                large_arc: false,
                right,
            };
            assert!((half.length(s, e) - PI).abs() < 1e-4);
            let mid = half.point(s, e, 0.5);
            assert!((mid[0] - 1.0).abs() < 1e-9 && (mid[1].abs() - 1.0).abs() < 1e-9);
            // Sweep towards increasing angle from (0,0) about (1,0) goes below the x axis.
            assert_eq!(mid[1] < 0.0, right);
        }
        let small = Curve::Circle {
            radius: 2f64.sqrt(),
            large_arc: false,
            right: true,
        };
        let large = Curve::Circle {
            radius: 2f64.sqrt(),
            large_arc: true,
            right: true,
        };
        let r = 2f64.sqrt();
        assert!((small.length(s, e) - r * PI / 2.0).abs() < 1e-4);
        assert!((large.length(s, e) - r * 3.0 * PI / 2.0).abs() < 1e-4);
        // Quadratic with its control point on the chord is the chord; a raised one is longer
        // and passes through half the height at t = 1/2.
        assert!((Curve::Quadratic([0.5, 0.0]).length(s, e) - 2.0).abs() < 1e-9);
        let q = Curve::Quadratic([0.5, 0.5]);
        let top = q.point(s, e, 0.5);
        assert!((top[1] - 0.5).abs() < 1e-12);
        assert!(q.length(s, e) > 2.0);
        // A cubic with controls at thirds of the chord is the chord.
        let c = Curve::Cubic([[1.0 / 3.0, 0.0], [2.0 / 3.0, 0.0]]);
        assert!((c.length(s, e) - 2.0).abs() < 1e-9);
    }

    #[test]
    fn resampling_is_uniform_in_arc_length() {
        let (s, e) = ([0.0, 0.0], [2.0, 0.0]);
        let curve = Curve::Cubic([[0.1, 0.6], [0.7, -0.4]]);
        let points = curve.resample(s, e, 21);
        assert_eq!(points.len(), 21);
        assert_eq!(points[0], s);
        assert_eq!(points[20], e);
        let steps: Vec<f64> = points.windows(2).map(|w| dist(w[0], w[1])).collect();
        let mean = steps.iter().sum::<f64>() / steps.len() as f64;
        for step in steps {
            assert!((step / mean - 1.0).abs() < 0.02, "{step} vs {mean}");
        }
    }
}
