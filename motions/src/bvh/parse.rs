//! The BVH text format: a joint hierarchy (offsets and per-joint channel lists) and a motion
//! block of one line of channel values per frame.
//!
//! Written by hand: the Rust BVH crates on crates.io (`bvh_anim`, `bvh`) are unmaintained or
//! panic on damaged input, and the format is small. Every refusal names the file and the line.

use std::path::{Path, PathBuf};

use nalgebra::{UnitQuaternion, Vector3};

use crate::amass::{MAX_SOURCE_FPS, MIN_SOURCE_FPS};
use crate::error::{Error, Result};
use crate::motion::MAX_MOTION_FRAMES;

/// The most joints a skeleton may have (a full-body capture with fingers has about 70).
pub const MAX_JOINTS: usize = 1024;

/// A coordinate axis of a channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// x.
    X,
    /// y.
    Y,
    /// z.
    Z,
}

impl Axis {
    fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// One animated value of a joint: a translation (in the file's units) or a rotation
/// (degrees) along or about an axis of the parent's frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    /// `Xposition`, `Yposition`, `Zposition`.
    Position(Axis),
    /// `Xrotation`, `Yrotation`, `Zrotation`.
    Rotation(Axis),
}

/// A joint of the hierarchy.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Name as written in the file.
    pub name: String,
    /// Parent joint (`None` for the root).
    pub parent: Option<usize>,
    /// Offset from the parent in the parent's frame, file units.
    pub offset: [f64; 3],
    /// Channels in file order: rotations compose in this order (the first is outermost).
    pub channels: Vec<Channel>,
    /// Index of this joint's first value within a frame's values.
    pub first_value: usize,
    /// The `End Site` offset, if the joint ends a chain.
    pub end_site: Option<[f64; 3]>,
}

/// A parsed BVH file.
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh {
    /// The file.
    pub path: PathBuf,
    /// Joints, parents before children (file order).
    pub joints: Vec<Joint>,
    /// Seconds per frame.
    pub frame_time: f64,
    /// Values per frame (the sum of every joint's channels).
    pub values_per_frame: usize,
    /// Every frame's values, frame after frame.
    pub values: Vec<f64>,
}

impl Bvh {
    /// Reads and parses a BVH file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = files::read_to_string(path, files::limits::TEXT, "BVH motion")?;
        Self::parse(&text, path)
    }

    /// Parses BVH text; `path` names the file in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        Parser::new(text, path).file()
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.values.len() / self.values_per_frame.max(1)
    }

    /// Frames per second.
    pub fn fps(&self) -> f64 {
        1.0 / self.frame_time
    }

    /// Index of a joint by name.
    pub fn joint(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Joint positions in the rest pose (every channel zero), file units, world frame.
    pub fn rest_positions(&self) -> Vec<Vector3<f64>> {
        let mut out: Vec<Vector3<f64>> = Vec::with_capacity(self.joints.len());
        for joint in &self.joints {
            let offset = Vector3::from(joint.offset);
            out.push(match joint.parent {
                Some(p) => out[p] + offset,
                None => offset,
            });
        }
        out
    }

    /// Global rotations and positions of every joint at `frame` (world frame, file units).
    ///
    /// A joint's local rotation is the product of its rotation channels in file order
    /// (`Zrotation Yrotation Xrotation` is Rz * Ry * Rx acting on column vectors); a joint with
    /// position channels takes them as its translation from the parent in place of its offset.
    pub fn pose(&self, frame: usize) -> (Vec<UnitQuaternion<f64>>, Vec<Vector3<f64>>) {
        let row = &self.values[frame * self.values_per_frame..(frame + 1) * self.values_per_frame];
        let mut rotations: Vec<UnitQuaternion<f64>> = Vec::with_capacity(self.joints.len());
        let mut positions: Vec<Vector3<f64>> = Vec::with_capacity(self.joints.len());
        for joint in &self.joints {
            let mut local = UnitQuaternion::identity();
            let mut translation = Vector3::from(joint.offset);
            let mut translated = false;
            for (k, channel) in joint.channels.iter().enumerate() {
                let value = row[joint.first_value + k];
                match channel {
                    Channel::Rotation(axis) => {
                        let mut a = Vector3::zeros();
                        a[axis.index()] = 1.0;
                        local *= UnitQuaternion::from_axis_angle(
                            &nalgebra::Unit::new_unchecked(a),
                            value.to_radians(),
                        );
                    }
                    Channel::Position(axis) => {
                        if !translated {
                            translation = Vector3::zeros();
                            translated = true;
                        }
                        translation[axis.index()] = value;
                    }
                }
            }
            let (rotation, position) = match joint.parent {
                Some(p) => (
                    rotations[p] * local,
                    positions[p] + rotations[p] * translation,
                ),
                None => (local, translation),
            };
            rotations.push(rotation);
            positions.push(position);
        }
        (rotations, positions)
    }
}

/// A token and the line it is on.
struct Token<'a> {
    text: &'a str,
    line: usize,
}

struct Parser<'a> {
    path: &'a Path,
    lines: Vec<&'a str>,
    /// Tokens of the hierarchy (everything before `MOTION`).
    tokens: Vec<Token<'a>>,
    next: usize,
    /// Line index (0-based) of the `MOTION` keyword, if any.
    motion_line: Option<usize>,
}

impl<'a> Parser<'a> {
    fn new(text: &'a str, path: &'a Path) -> Self {
        let lines: Vec<&str> = text.lines().collect();
        let motion_line = lines.iter().position(|l| l.trim() == "MOTION");
        let tokens = lines[..motion_line.unwrap_or(lines.len())]
            .iter()
            .enumerate()
            .flat_map(|(i, l)| {
                l.split_whitespace()
                    .map(move |text| Token { text, line: i + 1 })
            })
            .collect();
        Self {
            path,
            lines,
            tokens,
            next: 0,
            motion_line,
        }
    }

    fn error(&self, line: usize, problem: impl Into<String>) -> Error {
        Error::Bvh {
            path: self.path.to_path_buf(),
            line,
            problem: problem.into(),
        }
    }

    /// The line of the current token (or the last line of the hierarchy at its end).
    fn here(&self) -> usize {
        self.tokens
            .get(self.next)
            .or(self.tokens.last())
            .map_or(1, |t| t.line)
    }

    fn take(&mut self, what: &str) -> Result<&'a str> {
        let token = self.tokens.get(self.next).ok_or_else(|| {
            self.error(
                self.here(),
                format!("the hierarchy ends where {what} was expected"),
            )
        })?;
        self.next += 1;
        Ok(token.text)
    }

    fn expect(&mut self, keyword: &str) -> Result<()> {
        let line = self.here();
        let found = self.take(&format!("'{keyword}'"))?;
        if found != keyword {
            return Err(self.error(line, format!("expected '{keyword}', found '{found}'")));
        }
        Ok(())
    }

    fn number(&mut self, what: &str) -> Result<f64> {
        let line = self.here();
        let text = self.take(what)?;
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.error(line, format!("{what}: '{text}' is not a finite number"))),
        }
    }

    fn offset(&mut self) -> Result<[f64; 3]> {
        self.expect("OFFSET")?;
        Ok([
            self.number("OFFSET x")?,
            self.number("OFFSET y")?,
            self.number("OFFSET z")?,
        ])
    }

    fn file(mut self) -> Result<Bvh> {
        self.expect("HIERARCHY")?;
        let mut joints: Vec<Joint> = Vec::new();
        let mut values_per_frame = 0;
        // (joint index, whether its `End Site` block is open) for each open brace.
        let mut open: Vec<Option<usize>> = Vec::new();
        loop {
            let line = self.here();
            if self.next == self.tokens.len() {
                if open.is_empty() && !joints.is_empty() {
                    break;
                }
                return Err(self.error(line, "the hierarchy ends inside a joint's braces"));
            }
            let keyword = self.take("a keyword")?;
            match keyword {
                "ROOT" | "JOINT" => {
                    let is_root = keyword == "ROOT";
                    if is_root != open.is_empty() {
                        return Err(self.error(
                            line,
                            if is_root {
                                "ROOT inside another joint (one root per file)"
                            } else {
                                "JOINT outside the root's braces"
                            },
                        ));
                    }
                    if is_root && !joints.is_empty() {
                        return Err(self.error(line, "a second ROOT: one skeleton per file"));
                    }
                    let parent = match open.last() {
                        Some(Some(p)) => Some(*p),
                        Some(None) => {
                            return Err(self.error(line, "a JOINT inside an End Site"));
                        }
                        None => None,
                    };
                    let name = self.take("a joint name")?.to_string();
                    if joints.iter().any(|j| j.name == name) {
                        return Err(self.error(line, format!("joint '{name}' is named twice")));
                    }
                    if joints.len() == MAX_JOINTS {
                        return Err(self.error(line, format!("more than {MAX_JOINTS} joints")));
                    }
                    self.expect("{")?;
                    let offset = self.offset()?;
                    let channels = self.channels()?;
                    joints.push(Joint {
                        name,
                        parent,
                        offset,
                        first_value: values_per_frame,
                        channels,
                        end_site: None,
                    });
                    values_per_frame += joints.last().map_or(0, |j| j.channels.len());
                    open.push(Some(joints.len() - 1));
                }
                "End" => {
                    self.expect("Site")?;
                    let Some(Some(owner)) = open.last().copied() else {
                        return Err(self.error(line, "End Site outside a joint"));
                    };
                    self.expect("{")?;
                    let offset = self.offset()?;
                    self.expect("}")?;
                    if joints[owner].end_site.replace(offset).is_some() {
                        return Err(self.error(line, "a second End Site in one joint"));
                    }
                }
                "}" => {
                    if open.pop().is_none() {
                        return Err(self.error(line, "a '}' with no joint open"));
                    }
                }
                other => {
                    return Err(self.error(
                        line,
                        format!("expected ROOT, JOINT, End Site or '}}', found '{other}'"),
                    ));
                }
            }
        }
        if values_per_frame == 0 {
            return Err(self.error(self.here(), "no joint has channels: nothing moves"));
        }
        let (frame_time, values) = self.motion(values_per_frame)?;
        Ok(Bvh {
            path: self.path.to_path_buf(),
            joints,
            frame_time,
            values_per_frame,
            values,
        })
    }

    fn channels(&mut self) -> Result<Vec<Channel>> {
        let line = self.here();
        self.expect("CHANNELS")?;
        let count = self.number("the channel count")?;
        if !(count.fract() == 0.0 && (0.0..=6.0).contains(&count)) {
            return Err(self.error(line, format!("CHANNELS {count}: a joint has 0 to 6")));
        }
        let mut channels = Vec::with_capacity(count as usize);
        for _ in 0..count as usize {
            let name = self.take("a channel name")?;
            let channel = match name {
                "Xposition" => Channel::Position(Axis::X),
                "Yposition" => Channel::Position(Axis::Y),
                "Zposition" => Channel::Position(Axis::Z),
                "Xrotation" => Channel::Rotation(Axis::X),
                "Yrotation" => Channel::Rotation(Axis::Y),
                "Zrotation" => Channel::Rotation(Axis::Z),
                other => {
                    return Err(self.error(
                        line,
                        format!("unknown channel '{other}' (X/Y/Z position or rotation)"),
                    ));
                }
            };
            if channels.contains(&channel) {
                return Err(self.error(line, format!("channel '{name}' is listed twice")));
            }
            channels.push(channel);
        }
        Ok(channels)
    }

    /// The motion block: `Frames: N`, `Frame Time: T`, then N lines of values.
    fn motion(&self, values_per_frame: usize) -> Result<(f64, Vec<f64>)> {
        let Some(motion) = self.motion_line else {
            return Err(self.error(self.lines.len().max(1), "no MOTION block"));
        };
        let mut rows = self
            .lines
            .iter()
            .enumerate()
            .skip(motion + 1)
            .filter(|(_, l)| !l.trim().is_empty());
        let mut header = |label: &str| -> Result<(usize, f64)> {
            let (i, line) = rows.next().ok_or_else(|| {
                self.error(self.lines.len(), format!("the file ends before '{label}'"))
            })?;
            let value = line
                .trim()
                .strip_prefix(label)
                .map(str::trim)
                .ok_or_else(|| self.error(i + 1, format!("expected '{label} ...'")))?;
            match value.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok((i + 1, v)),
                _ => Err(self.error(i + 1, format!("{label} '{value}' is not a number"))),
            }
        };
        let (count_line, count) = header("Frames:")?;
        if !(count.fract() == 0.0 && count >= 1.0 && count <= MAX_MOTION_FRAMES as f64 * 40.0) {
            return Err(self.error(
                count_line,
                format!(
                    "Frames: {count} is not a whole number of frames from 1 to {}",
                    MAX_MOTION_FRAMES * 40
                ),
            ));
        }
        let (time_line, frame_time) = header("Frame Time:")?;
        if !(frame_time > 0.0 && (MIN_SOURCE_FPS..=MAX_SOURCE_FPS).contains(&(1.0 / frame_time))) {
            return Err(self.error(
                time_line,
                format!(
                    "Frame Time: {frame_time} s is not a rate from {MIN_SOURCE_FPS} to {MAX_SOURCE_FPS} frames per second"
                ),
            ));
        }
        let count = count as usize;
        let mut values = Vec::with_capacity((count * values_per_frame).min(1 << 24));
        let mut frames = 0;
        for (i, line) in rows {
            // Lines past the announced count are read but kept out (some exporters announce
            // one frame fewer than they write, as Blender's reader does), yet must be frames.
            let before = values.len();
            for text in line.split_whitespace() {
                match text.parse::<f64>() {
                    Ok(v) if v.is_finite() => values.push(v),
                    _ => {
                        return Err(self.error(i + 1, format!("'{text}' is not a finite number")));
                    }
                }
            }
            let found = values.len() - before;
            if found != values_per_frame {
                return Err(self.error(
                    i + 1,
                    format!(
                        "frame {} has {found} values; the hierarchy has {values_per_frame} channels",
                        frames + 1
                    ),
                ));
            }
            frames += 1;
            if frames > count {
                values.truncate(before);
            }
        }
        if frames < count {
            return Err(self.error(
                self.lines.len(),
                format!("the file ends after {frames} of the {count} frames 'Frames:' announces"),
            ));
        }
        Ok((frame_time, values))
    }
}
