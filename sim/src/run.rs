//! A garment run as every command shares it: a scene with the body model and garment it was
//! built from ([`Prepared`]), run frame by frame into an MCAP recording, with a hook for what
//! a caller does beside it per frame (OBJ export, progress) and an optional deadline. Where
//! the recording goes (a temporary file renamed into place) is the caller's.

use std::io::{Seek, Write};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use motions::{BodyModel, Motion};

use crate::ValidSceneConfig;
use crate::error::{Error, Result};
use crate::recording::{Channels, SequenceWriter, TemplateArrays};
use crate::scene::{BodyAttachment, FPS, FrameOutput, RunSummary, Scene};

/// A scene with its body model and garment template (shared between a dataset's sequences).
pub struct Prepared {
    /// The body model the scene poses.
    pub model: Arc<BodyModel>,
    /// The garment template.
    pub garment: Arc<garments::Garment>,
    /// The scene.
    pub scene: Scene,
}

impl Prepared {
    /// The scene of `config` on a loaded model, template and motion (the configuration's
    /// garment, model and motion keys name what was loaded; its shape and settings apply).
    pub fn new(
        model: Arc<BodyModel>,
        garment: Arc<garments::Garment>,
        attachments: Vec<BodyAttachment>,
        motion: Motion,
        config: ValidSceneConfig,
    ) -> Result<Self> {
        let template = (garment.positions.clone(), garment.triangles.clone());
        let scene = Scene::new(config, template, attachments, motion, &model)?;
        Ok(Self {
            model,
            garment,
            scene,
        })
    }

    /// The scene `config` names, everything loaded ([`crate::sources`]): its body model, its
    /// garment (a library design's template made on first use in `cache`, `making` called with
    /// its path first) and its motion.
    pub fn load(
        config: ValidSceneConfig,
        cache: &Path,
        making: impl FnOnce(&Path),
    ) -> Result<Self> {
        let model = Arc::new(crate::sources::body_model(
            config.model.as_deref().map(Path::new),
        )?);
        let (garment, attachments) =
            crate::sources::garment(&config.garment, &model, cache, making)?;
        Self::with_motion_of(model, Arc::new(garment), attachments, config)
    }

    /// The scene of `config` on a loaded model and template, its motion loaded by the
    /// configuration's `motion` key ([`crate::sources::motion`]) for its shape.
    pub fn with_motion_of(
        model: Arc<BodyModel>,
        garment: Arc<garments::Garment>,
        attachments: Vec<BodyAttachment>,
        config: ValidSceneConfig,
    ) -> Result<Self> {
        let shaped = model.shape(&config.betas)?;
        let motion = crate::sources::motion(&config.motion, &model, &shaped)?;
        Self::new(model, garment, attachments, motion, config)
    }

    /// [`Self::record`] into the file at `path` (its folder made if missing), atomically:
    /// nothing is there unless the run finishes.
    pub fn record_file(
        &self,
        path: &Path,
        software: &str,
        deadline: Option<Instant>,
        each_frame: impl FnMut(&FrameOutput) -> Result<()>,
    ) -> Result<RunSummary> {
        files::create_folder_of(path)?;
        let mut summary = None;
        files::write_fallible(path, |w| {
            summary = Some(self.record(w, software, deadline, each_frame)?);
            Ok::<(), Error>(())
        })?;
        Ok(summary.expect("set by a fill that succeeded"))
    }

    /// Runs the scene and writes its recording to `out` (template, frames, statistics, and
    /// the body or Foxglove channels the configuration's `record` asks for), calling
    /// `each_frame` after each frame is written. `software` is recorded as the writer's name.
    /// Stops with [`Error::Deadline`] when the run is still going at `deadline`.
    pub fn record<W: Write + Seek>(
        &self,
        out: W,
        software: &str,
        deadline: Option<Instant>,
        mut each_frame: impl FnMut(&FrameOutput) -> Result<()>,
    ) -> Result<RunSummary> {
        let meta = self
            .scene
            .sequence_meta(&self.garment.name, self.model.name(), software);
        let template = TemplateArrays::from(&*self.garment);
        let recorded = self.scene.config.record;
        let channels = Channels {
            template: Some(&template),
            body_faces: recorded.body_vertices.then(|| self.model.faces()),
            joints: false,
            stats: true,
        };
        let mut rec = SequenceWriter::new(out, &meta, channels, FPS)?;
        if recorded.foxglove {
            rec = rec.with_foxglove_scene(&template.triangles, Some(self.model.faces()))?;
        }
        let summary = self.scene.run(&self.model, |frame| {
            if deadline.is_some_and(|d| Instant::now() > d) {
                return Err(Error::Deadline { frame: frame.index });
            }
            rec.write_frame(&frame.record())?;
            each_frame(frame)
        })?;
        rec.finish()?;
        Ok(summary)
    }
}

/// Frame `k`'s garment (`garment`'s mesh at `cloth`) and body (`body` over `faces`) as
/// `garment_<k>.obj` and `body_<k>.obj` in `dir` (made if missing), each written atomically.
pub fn write_objs(
    dir: &Path,
    k: usize,
    garment: &garments::Garment,
    cloth: &[[f64; 3]],
    body: &[[f64; 3]],
    faces: &[[u32; 3]],
) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| files::Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    files::write_with(&dir.join(format!("garment_{k:04}.obj")), |w| {
        garments::write_obj(w, garment, Some(cloth))
    })?;
    files::write_with(&dir.join(format!("body_{k:04}.obj")), |w| {
        garments::write_mesh_obj(w, &format!("body frame {k}"), body, faces)
    })?;
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::SceneConfig;

    /// A coarse built-in skirt (24 x 8) fitted to `model` and draped, with its attachments.
    pub(crate) fn coarse_skirt(model: &BodyModel) -> (garments::Garment, Vec<BodyAttachment>) {
        let params = garments::SkirtParams {
            columns: 24,
            rings: 8,
            ..garments::SkirtParams::default()
        };
        crate::scene::builtin_template(model, "skirt", &params).unwrap()
    }

    /// The coarse skirt on the default body walking, `frames` frames.
    pub(crate) fn skirt(frames: usize) -> Prepared {
        let model = BodyModel::default_body();
        let (garment, attachments) = coarse_skirt(&model);
        let config = SceneConfig {
            frames: Some(frames),
            blend_frames: 2,
            settle_frames: 1,
            ..SceneConfig::default()
        };
        let shaped = model.shape(&config.betas).unwrap();
        let motion = motions::library::MotionSpec::parse("walk")
            .unwrap()
            .generate(&model, &shaped)
            .unwrap();
        let (model, garment) = (Arc::new(model), Arc::new(garment));
        Prepared::new(
            model,
            garment,
            attachments,
            motion,
            config.validated().unwrap(),
        )
        .unwrap()
    }

    /// A finished run's file holds what `record` writes; a run stopped by its deadline
    /// leaves nothing at the path, not even in a new folder.
    #[test]
    fn a_recorded_file_is_whole_or_absent() {
        let p = skirt(3);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("new/run.mcap");
        let summary = p.record_file(&path, "test", None, |_| Ok(())).unwrap();
        assert_eq!(summary.frames, 3);
        let mut bytes = std::io::Cursor::new(Vec::new());
        p.record(&mut bytes, "test", None, |_| Ok(())).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), bytes.into_inner());
        let stopped = dir.path().join("stopped/run.mcap");
        let e = p.record_file(&stopped, "test", Some(Instant::now()), |_| Ok(()));
        assert!(matches!(e, Err(Error::Deadline { .. })), "{e:?}");
        assert!(!stopped.exists());
        let left: Vec<_> = std::fs::read_dir(dir.path().join("stopped"))
            .unwrap()
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }

    #[test]
    fn a_run_records_the_same_bytes_twice_and_calls_the_hook_per_frame() {
        let p = skirt(4);
        let mut frames = Vec::new();
        let mut first = std::io::Cursor::new(Vec::new());
        let summary = p
            .record(&mut first, "test", None, |f| {
                frames.push(f.index);
                Ok(())
            })
            .unwrap();
        assert_eq!(frames, [0, 1, 2, 3]);
        assert_eq!(summary.frames, 4);
        let mut second = std::io::Cursor::new(Vec::new());
        p.record(&mut second, "test", None, |_| Ok(())).unwrap();
        let (first, second) = (first.into_inner(), second.into_inner());
        assert!(first == second, "same scene, same bytes");
        let back =
            crate::recording::Recording::from_bytes(&first, std::path::Path::new("t")).unwrap();
        assert_eq!(back.garment.len(), 4);
    }

    #[test]
    fn a_run_past_its_deadline_stops_with_the_frame_it_reached() {
        let p = skirt(3);
        let past = Instant::now();
        let out = std::io::Cursor::new(Vec::new());
        let stopped = p.record(out, "test", Some(past), |_| Ok(()));
        assert!(
            matches!(stopped, Err(Error::Deadline { frame: 0 })),
            "{stopped:?}"
        );
    }
}
