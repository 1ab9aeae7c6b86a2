//! What a motion argument names, everywhere a motion is accepted: a built-in motion
//! (`walk`, `random:seed=3,speed=1.2`, [`crate::library`]), an AMASS `.npz` file, a BVH
//! file, or SMPL fits in pickles ([`crate::fits`]: a `.pkl` file, or a folder of one per frame
//! such as a 4D-Dress take's `SMPL/`). A file may be followed by `:start=S,duration=D`
//! (seconds: a stretch of a long clip), for BVH by `map=FILE.toml` (a joint map for a skeleton
//! no built-in map fits), for fits by `fps=F` (their frame rate, 30 by default):
//! `01_01.bvh:start=4,duration=6,map=skeleton.toml`, `Take9/SMPL:fps=30,start=1`.

use std::path::{Path, PathBuf};

use crate::body_model::BodyModel;
use crate::bvh;
use crate::error::{Error, Result};
use crate::forward::ShapedBody;
use crate::library::MotionSpec;
use crate::motion::{Motion, OUTPUT_FPS};

/// The longest start offset or stretch a file motion may ask for, seconds (a day): beyond it
/// a number is a typo.
const MAX_STRETCH_SECONDS: f64 = 86_400.0;

/// A file format a motion may come in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileFormat {
    /// AMASS `.npz` (SMPL+H or SMPL-X poses, z up).
    Amass,
    /// BVH motion capture, retargeted to SMPL.
    Bvh,
    /// SMPL fits in Python pickles (y up, SMPL's own frame), one file or a folder of frames.
    SmplFits,
}

/// A motion file and the stretch of it to use.
#[derive(Debug, Clone, PartialEq)]
pub struct FileMotion {
    /// The file.
    pub path: PathBuf,
    /// Its format.
    pub format: FileFormat,
    /// Where the stretch starts, seconds from the file's first frame.
    pub start: f64,
    /// How long the stretch lasts, seconds (`None`: to the end).
    pub duration: Option<f64>,
    /// A BVH joint map file (`None`: the built-in map that fits).
    pub map: Option<PathBuf>,
    /// The frame rate of SMPL fits (`None`: [`crate::fits::DEFAULT_FPS`]).
    pub fps: Option<f64>,
}

/// A parsed motion argument.
#[derive(Debug, Clone, PartialEq)]
pub enum MotionSource {
    /// A built-in procedural motion.
    Library(MotionSpec),
    /// A motion file.
    File(FileMotion),
}

/// A motion's name as tables show it: a file motion without its folders
/// (`01_01.bvh:start=19,duration=2.5`), which differ between machines and crowd a table out;
/// any other name as it is.
pub fn short_label(name: &str) -> &str {
    let path_end = name.find(':').unwrap_or(name.len());
    match name[..path_end].rfind('/') {
        Some(slash) => &name[slash + 1..],
        None => name,
    }
}

/// A motion at 30 fps and, for BVH, what retargeting did.
#[derive(Debug, Clone)]
pub struct LoadedMotion {
    /// The motion.
    pub motion: Motion,
    /// The retargeting report of a BVH file.
    pub retarget: Option<bvh::Report>,
}

impl MotionSource {
    /// Parses a motion argument (see the module documentation).
    pub fn parse(text: &str) -> Result<Self> {
        let lower = text.to_ascii_lowercase();
        let formats = [
            (".bvh", FileFormat::Bvh),
            (".npz", FileFormat::Amass),
            (".pkl", FileFormat::SmplFits),
        ];
        for (extension, format) in formats {
            if lower.ends_with(extension) {
                return FileMotion::with_parameters(text, format, "").map(Self::File);
            }
            if let Some(at) = lower.rfind(&format!("{extension}:")) {
                let (path, parameters) = text.split_at(at + extension.len());
                return FileMotion::with_parameters(path, format, &parameters[1..]).map(Self::File);
            }
        }
        let path = Path::new(text);
        if path.is_dir() {
            return FileMotion::with_parameters(text, FileFormat::SmplFits, "").map(Self::File);
        }
        if let Some((folder, parameters)) = text.rsplit_once(':')
            && Path::new(folder).is_dir()
        {
            return FileMotion::with_parameters(folder, FileFormat::SmplFits, parameters)
                .map(Self::File);
        }
        if path.exists() {
            let (mut file, _) = files::open(path)?;
            let mut head = [0u8; 9];
            let read = std::io::Read::read(&mut file, &mut head).unwrap_or(0);
            let format = if &head[..read] == b"HIERARCHY" {
                FileFormat::Bvh
            } else {
                FileFormat::Amass
            };
            return FileMotion::with_parameters(text, format, "").map(Self::File);
        }
        MotionSpec::parse(text).map(Self::Library)
    }

    /// The canonical text form (`walk:speed=1` and `walk` are both `walk`; a file's
    /// parameters in a fixed order, defaults left out).
    pub fn label(&self) -> String {
        match self {
            Self::Library(spec) => spec.label(),
            Self::File(file) => file.label(),
        }
    }

    /// What the motion is, for telling two spellings of one motion apart from two motions:
    /// [`MotionSource::label`] with a file's path made absolute where the file exists.
    pub fn identity(&self) -> String {
        match self {
            Self::Library(spec) => spec.label(),
            Self::File(file) => {
                let mut file = file.clone();
                if let Ok(path) = std::fs::canonicalize(&file.path) {
                    file.path = path;
                }
                file.label()
            }
        }
    }

    /// Loads the motion at 30 fps for the shaped body `shaped` of `model`.
    ///
    /// A BVH motion is placed on the floor: its first frame's lowest body point at y = 0 and
    /// its pelvis over the origin. An AMASS motion keeps its own placement.
    pub fn load(&self, model: &BodyModel, shaped: &ShapedBody) -> Result<LoadedMotion> {
        let file = match self {
            Self::Library(spec) => {
                return Ok(LoadedMotion {
                    motion: spec.generate(model, shaped)?,
                    retarget: None,
                });
            }
            Self::File(file) => file,
        };
        let (raw, retarget) = match file.format {
            FileFormat::Amass => (crate::amass::load(&file.path, shaped.joints[0])?, None),
            FileFormat::Bvh => {
                let r = bvh::load(&file.path, file.map.as_deref(), shaped)?;
                (r.motion, Some(r.report))
            }
            FileFormat::SmplFits => {
                let fps = file.fps.unwrap_or(crate::fits::DEFAULT_FPS);
                (crate::fits::load(&file.path, fps)?, None)
            }
        };
        let mut motion = file.stretch(raw.resample(OUTPUT_FPS)?)?;
        motion.name = file.label();
        if retarget.is_some() {
            place_on_floor(&mut motion, model, shaped)?;
        }
        Ok(LoadedMotion { motion, retarget })
    }
}

impl FileMotion {
    fn with_parameters(path: &str, format: FileFormat, parameters: &str) -> Result<Self> {
        let bad = |reason: String| Error::UnknownMotion {
            name: format!("{path}:{parameters}"),
            reason,
        };
        let mut file = FileMotion {
            path: PathBuf::from(path),
            format,
            start: 0.0,
            duration: None,
            map: None,
            fps: None,
        };
        for kv in parameters.split(',').filter(|s| !s.trim().is_empty()) {
            let (key, value) = kv
                .split_once('=')
                .ok_or_else(|| bad(format!("'{kv}' is not key=value")))?;
            let (key, value) = (key.trim(), value.trim());
            let seconds = || match value.parse::<f64>() {
                Ok(v) if v.is_finite() && (0.0..=MAX_STRETCH_SECONDS).contains(&v) => Ok(v),
                _ => Err(bad(format!(
                    "{key} = '{value}' is not a number of seconds from 0 to {MAX_STRETCH_SECONDS}"
                ))),
            };
            match key {
                "start" => file.start = seconds()?,
                "duration" => {
                    let d = seconds()?;
                    if d < 1.0 / OUTPUT_FPS {
                        return Err(bad(format!(
                            "duration = {d} s is shorter than one frame at 30 fps"
                        )));
                    }
                    file.duration = Some(d);
                }
                "map" if format == FileFormat::Bvh => file.map = Some(PathBuf::from(value)),
                "fps" if format == FileFormat::SmplFits => match value.parse::<f64>() {
                    Ok(fps) if (1.0..=1000.0).contains(&fps) => file.fps = Some(fps),
                    _ => return Err(bad(format!("fps = '{value}' is not from 1 to 1000"))),
                },
                other => {
                    let keys = match format {
                        FileFormat::Bvh => "start, duration, map",
                        FileFormat::Amass => "start, duration",
                        FileFormat::SmplFits => "start, duration, fps",
                    };
                    return Err(bad(format!("unknown parameter '{other}' ({keys})")));
                }
            }
        }
        Ok(file)
    }

    /// The canonical text form: the path, then the parameters that differ from the defaults.
    pub fn label(&self) -> String {
        let mut parts = Vec::new();
        if self.start != 0.0 {
            parts.push(format!("start={}", self.start));
        }
        if let Some(d) = self.duration {
            parts.push(format!("duration={d}"));
        }
        if let Some(map) = &self.map {
            parts.push(format!("map={}", map.display()));
        }
        if let Some(fps) = self.fps {
            parts.push(format!("fps={fps}"));
        }
        match parts.is_empty() {
            true => self.path.display().to_string(),
            false => format!("{}:{}", self.path.display(), parts.join(",")),
        }
    }

    /// The stretch of a 30 fps motion this file motion asks for.
    fn stretch(&self, mut motion: Motion) -> Result<Motion> {
        if self.start == 0.0 && self.duration.is_none() {
            return Ok(motion);
        }
        let first = (self.start * OUTPUT_FPS).round() as usize;
        let available = motion.len().saturating_sub(first);
        let count = self
            .duration
            .map_or(available, |d| (d * OUTPUT_FPS).round().max(1.0) as usize);
        if available == 0 || count > available {
            return Err(Error::UnknownMotion {
                name: self.path.display().to_string(),
                reason: format!(
                    "start = {} s{} runs past the end of the motion ({:.2} s)",
                    self.start,
                    self.duration
                        .map_or(String::new(), |d| format!(" with duration = {d} s")),
                    motion.duration()
                ),
            });
        }
        motion.frames.truncate(first + count);
        motion.frames.drain(..first);
        Ok(motion)
    }
}

/// Moves a motion so its first frame stands on the floor: the body's lowest point at y = 0
/// and the pelvis over the origin (x = z = 0).
pub fn place_on_floor(motion: &mut Motion, model: &BodyModel, shaped: &ShapedBody) -> Result<()> {
    let first = model.pose(shaped, &motion.frames[0])?;
    let lowest = first
        .vertices
        .iter()
        .fold(f64::INFINITY, |low, v| low.min(v[1]));
    let pelvis = first.joints[0];
    for frame in &mut motion.frames {
        frame.transl[0] -= pelvis[0];
        frame.transl[1] -= lowest;
        frame.transl[2] -= pelvis[2];
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::short_label;

    #[test]
    fn short_labels_drop_a_files_folders_and_keep_its_stretch() {
        assert_eq!(
            short_label("/usr/share/assimp/models/BVH/01_01.bvh:start=19,duration=2.5"),
            "01_01.bvh:start=19,duration=2.5"
        );
        // A joint map's folder is a parameter's, not the motion's: kept.
        assert_eq!(
            short_label("data/01_01.bvh:map=maps/skeleton.toml"),
            "01_01.bvh:map=maps/skeleton.toml"
        );
        assert_eq!(
            short_label("random:seed=3,speed=1.2"),
            "random:seed=3,speed=1.2"
        );
        assert_eq!(short_label("01_01.bvh"), "01_01.bvh");
    }
}
