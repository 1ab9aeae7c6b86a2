//! Pictures of the engine's recordings (sim's MCAP) with their bodies: PNG frames, contact
//! sheets and GIFs, coloured by stretch, depth in the body or error against a reference; the
//! self-contained viewer page; and the simulation-against-prediction sheets and GIFs of the
//! surrogate's reports. Every file is written atomically.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::time::Instant;

use motions::BodyModel;
use sim::obstacles::AnimatedMesh;
use sim::recording::Recording;

use crate::viewer::{BODY_COLOUR, GARMENT_COLOURS, Track, ViewerSequence};
use crate::{Bounds, Camera, ColourScale, Error, Layer, P3, Renderer, RgbImage, View};

type Result<T> = std::result::Result<T, Error>;

/// What the garment's vertices are coloured by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColourBy {
    /// Largest stretch of the vertex's edges against the template (length / rest length).
    Stretch,
    /// Depth inside the body, mm.
    Penetration,
    /// Distance to the same vertex in a reference recording, cm.
    Error,
}

/// An error about the input, as text.
fn input(message: impl Into<String>) -> Error {
    Error::Input(message.into())
}

/// Writes `path` through `fill` atomically, its folder made if missing.
fn save(path: &Path, fill: impl FnOnce(&mut BufWriter<File>) -> Result<()>) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    files::write_fallible(path, fill)
}

/// Reach of the penetration query, m: deeper points are found by the unbounded query.
const PENETRATION_REACH_M: f64 = 0.05;

/// A recording with what drawing it needs: its body model and body triangles.
struct Sequence<'a> {
    path: &'a Path,
    recording: Recording,
    model: &'a BodyModel,
    body_faces: Vec<[u32; 3]>,
    with_body: bool,
}

/// One frame's meshes as `f32` points.
struct FrameMeshes {
    garment: Vec<P3>,
    body: Vec<P3>,
}

fn to_f32(points: &[[f64; 3]]) -> Vec<P3> {
    points.iter().map(|p| p.map(|c| c as f32)).collect()
}

impl<'a> Sequence<'a> {
    fn open(path: &'a Path, model: &'a BodyModel, with_body: bool) -> Result<Self> {
        let recording = Recording::read(path)?;
        if recording.garment.is_empty() {
            return Err(input(format!(
                "{}: the recording has no garment frames",
                path.display()
            )));
        }
        let body_faces = if with_body {
            recording.body_at(model, 0, path)?.faces
        } else {
            Vec::new()
        };
        Ok(Self {
            path,
            recording,
            model,
            body_faces,
            with_body,
        })
    }

    fn frames(&self) -> usize {
        self.recording.garment.len()
    }

    fn meshes(&self, k: usize) -> Result<FrameMeshes> {
        let body = if self.with_body {
            to_f32(&self.recording.body_at(self.model, k, self.path)?.vertices)
        } else {
            Vec::new()
        };
        Ok(FrameMeshes {
            garment: self.recording.garment[k].clone(),
            body,
        })
    }
}

/// Per-vertex values the garment is coloured by.
enum Colouring {
    Stretch { edges: Vec<(usize, usize, f32)> },
    Penetration,
    Error { reference: Box<Recording> },
}

impl Colouring {
    fn new(by: ColourBy, seq: &Sequence, against: Option<&Path>) -> Result<Self> {
        Ok(match by {
            ColourBy::Stretch => {
                let t = &seq.recording.template;
                let mut edges: Vec<(usize, usize)> = t
                    .triangles
                    .iter()
                    .flat_map(|f| [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])])
                    .map(|(a, b)| (a.min(b) as usize, a.max(b) as usize))
                    .collect();
                edges.sort_unstable();
                edges.dedup();
                let edges = edges
                    .into_iter()
                    .filter_map(|(a, b)| {
                        let (p, q) = (t.positions.get(a)?, t.positions.get(b)?);
                        let rest = (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>().sqrt();
                        (rest > 0.0).then_some((a, b, rest as f32))
                    })
                    .collect();
                Colouring::Stretch { edges }
            }
            ColourBy::Penetration => {
                if !seq.with_body {
                    return Err(input(
                        "colouring by penetration needs the body (drop --no-body)",
                    ));
                }
                Colouring::Penetration
            }
            ColourBy::Error => {
                let path = against.ok_or_else(|| {
                    input("colouring by error needs a reference (--against REFERENCE.mcap)")
                })?;
                let reference = Recording::read(path)?;
                if reference.template.positions.len() != seq.recording.template.positions.len() {
                    return Err(input(format!(
                        "{} has {} garment vertices, {} has {}: --against needs the same template",
                        path.display(),
                        reference.template.positions.len(),
                        seq.path.display(),
                        seq.recording.template.positions.len()
                    )));
                }
                Colouring::Error {
                    reference: Box::new(reference),
                }
            }
        })
    }

    fn default_scale(&self) -> ColourScale {
        match self {
            Colouring::Stretch { .. } => ColourScale { min: 0.9, max: 1.2 },
            Colouring::Penetration => ColourScale {
                min: 0.0,
                max: 10.0,
            },
            Colouring::Error { .. } => ColourScale { min: 0.0, max: 5.0 },
        }
    }

    fn label(&self) -> &'static str {
        match self {
            Colouring::Stretch { .. } => "stretch",
            Colouring::Penetration => "depth mm",
            Colouring::Error { .. } => "error cm",
        }
    }

    fn values(&self, seq: &Sequence, k: usize, frame: &FrameMeshes) -> Result<Vec<f32>> {
        let g = &frame.garment;
        Ok(match self {
            Colouring::Stretch { edges } => {
                let mut v = vec![0.0f32; g.len()];
                for &(a, b, rest) in edges {
                    let s = render_distance(g[a], g[b]) / rest;
                    v[a] = v[a].max(s);
                    v[b] = v[b].max(s);
                }
                v
            }
            Colouring::Penetration => {
                let vec3 = |p: &P3| sim::Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                let body: Vec<sim::Vec3> = frame.body.iter().map(vec3).collect();
                let mut mesh = AnimatedMesh::new(&body, &seq.body_faces, 0.0)?;
                let points: Vec<sim::Vec3> = g.iter().map(vec3).collect();
                mesh.measure(&points, PENETRATION_REACH_M)
                    .into_iter()
                    .map(|d| (-d).max(0.0) as f32 * 1e3)
                    .collect()
            }
            Colouring::Error { reference } => {
                let r = reference
                    .garment
                    .get(k)
                    .ok_or_else(|| input(format!("the --against recording has no frame {k}")))?;
                g.iter()
                    .zip(r)
                    .map(|(&p, &q)| render_distance(p, q) * 100.0)
                    .collect()
            }
        })
    }
}

fn render_distance(a: P3, b: P3) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// One framing size for a set of frames (the largest), centred on each frame in turn.
fn framing_size(frames: &[&FrameMeshes]) -> Option<Bounds> {
    frames
        .iter()
        .filter_map(|f| frame_bounds(f))
        .reduce(|a, b| a.with_size_of(&b))
}

fn frame_bounds(f: &FrameMeshes) -> Option<Bounds> {
    Bounds::of(f.garment.iter().chain(&f.body))
}

/// Where the camera looks: the vertices' mean across, the middle of their height up, so a
/// swinging arm does not shake a sequence's pictures.
fn steady_centre(frame: &FrameMeshes, bounds: &Bounds) -> P3 {
    let points = frame.body.iter().chain(&frame.garment);
    let n = (frame.body.len() + frame.garment.len()).max(1) as f32;
    let (x, z) = points.fold((0.0, 0.0), |(x, z), p| (x + p[0], z + p[2]));
    [x / n, bounds.center()[1], z / n]
}

/// Draws one frame from one view; the garment is layer 0 (so `coverage(0)` counts it).
fn picture(
    renderer: &mut Renderer,
    view: View,
    seq: &Sequence,
    frame: &FrameMeshes,
    size: &Bounds,
    colours: Option<(&[f32], ColourScale, &str)>,
) -> RgbImage {
    let bounds = frame_bounds(frame).map_or(*size, |b| size.recentred(steady_centre(frame, &b)));
    let camera = Camera::framing(view, &bounds, renderer.aspect());
    let mut layers = vec![Layer {
        positions: &frame.garment,
        triangles: &seq.recording.template.triangles,
        colour: GARMENT_COLOURS[0],
        values: colours.map(|(v, s, _)| (v, s)),
    }];
    if seq.with_body {
        layers.push(Layer {
            positions: &frame.body,
            triangles: &seq.body_faces,
            colour: BODY_COLOUR,
            values: None,
        });
    }
    let mut image = renderer.render(&camera, &layers).clone();
    if let Some((_, scale, label)) = colours {
        crate::draw_colour_bar(&mut image, &scale, label);
    }
    image
}

/// Writes a picture as PNG, atomically.
pub fn save_png(path: &Path, image: &RgbImage) -> Result<()> {
    save(path, |w| crate::write_png(w, image))
}

/// What `render` wrote.
pub struct Rendered {
    /// The PNG pictures, one per frame and view.
    pub images: Vec<PathBuf>,
    /// Pixels the garment covers in the first picture.
    pub pixels_garment: usize,
    /// The contact sheet of every picture.
    pub sheet: PathBuf,
    /// The GIF, if one was asked for.
    pub gif: Option<PathBuf>,
    /// Pictures drawn.
    pub pictures: usize,
    /// Wall time, s.
    pub wall_s: f64,
}

/// Options of one `render` run.
pub struct RenderJob<'a> {
    /// Recording frames to draw (empty: six spread over the sequence).
    pub frames: &'a [usize],
    /// Views of each frame.
    pub views: &'a [View],
    /// Picture size, pixels per side.
    pub size: u32,
    /// Supersampling per side.
    pub ssaa: u32,
    /// Colouring: by what, the reference recording of `Error`, and the scale (default per
    /// kind).
    pub colour_by: Option<(ColourBy, Option<&'a Path>, Option<ColourScale>)>,
    /// A GIF of the whole sequence: every K-th frame, at this size.
    pub gif: Option<(usize, u32)>,
}

/// Draws the chosen frames and views into `out`, with a contact sheet and optionally a GIF
/// (`gif_progress` told the frames done and the total as it is drawn).
pub fn render_recording(
    path: &Path,
    model: &BodyModel,
    with_body: bool,
    job: &RenderJob,
    out: &Path,
    gif_progress: &mut dyn FnMut(usize, usize),
) -> Result<Rendered> {
    let started = Instant::now();
    let seq = Sequence::open(path, model, with_body)?;
    let n = seq.frames();
    let mut frames: Vec<usize> = if job.frames.is_empty() {
        (0..6).map(|i| i * (n - 1) / 5).collect::<Vec<_>>()
    } else {
        job.frames.to_vec()
    };
    // A frame asked for twice (or a short recording's default picks) is drawn once.
    let mut seen = std::collections::HashSet::new();
    frames.retain(|k| seen.insert(*k));
    if let Some(&k) = frames.iter().find(|&&k| k >= n) {
        return Err(input(format!(
            "frame {k} is past the end of {} ({n} frames)",
            path.display()
        )));
    }
    let colouring = match job.colour_by {
        Some((by, against, _)) => Some(Colouring::new(by, &seq, against)?),
        None => None,
    };
    let scale = colouring.as_ref().map(|c| {
        job.colour_by
            .and_then(|(_, _, s)| s)
            .unwrap_or_else(|| c.default_scale())
    });
    let meshes = frames
        .iter()
        .map(|&k| seq.meshes(k))
        .collect::<Result<Vec<_>>>()?;
    let size = framing_size(&meshes.iter().collect::<Vec<_>>())
        .ok_or_else(|| input(format!("{}: no finite vertex to frame", path.display())))?;
    let mut renderer = Renderer::new(job.size, job.size, job.ssaa);
    let mut images = Vec::new();
    let mut tiles = Vec::new();
    let mut pixels_garment = None;
    for (&k, frame) in frames.iter().zip(&meshes) {
        let values = match &colouring {
            Some(c) => Some(c.values(&seq, k, frame)?),
            None => None,
        };
        for &view in job.views {
            let colours = match (&values, &colouring, scale) {
                (Some(v), Some(c), Some(s)) => Some((v.as_slice(), s, c.label())),
                _ => None,
            };
            let image = picture(&mut renderer, view, &seq, frame, &size, colours);
            pixels_garment.get_or_insert(renderer.coverage(0));
            let file = out.join(format!("frame_{k:05}_{}.png", view.name()));
            save_png(&file, &image)?;
            images.push(file);
            tiles.push((image, format!("frame {k} {}", view.name())));
        }
    }
    let columns = if job.views.len() > 1 {
        job.views.len()
    } else {
        (tiles.len() as f64).sqrt().ceil() as usize
    };
    let sheet_image = crate::contact_sheet(&tiles, columns);
    let sheet = out.join("contact_sheet.png");
    save_png(&sheet, &sheet_image)?;
    let gif = match job.gif {
        Some((every, gif_size)) => {
            let file = out.join("sequence.gif");
            let view = job.views.first().copied().unwrap_or(View::ThreeQuarter);
            let shape = (every.max(1), gif_size, job.ssaa);
            write_gif(&seq, &file, view, shape, gif_progress)?;
            Some(file)
        }
        None => None,
    };
    Ok(Rendered {
        images,
        pixels_garment: pixels_garment.unwrap_or(0),
        sheet,
        gif,
        pictures: tiles.len(),
        wall_s: started.elapsed().as_secs_f64(),
    })
}

/// The whole sequence (every `every`-th frame) as a looping GIF at the recording's speed;
/// `shape` is (every, size, supersampling).
fn write_gif(
    seq: &Sequence,
    file: &Path,
    view: View,
    (every, size, ssaa): (usize, u32, u32),
    progress: &mut dyn FnMut(usize, usize),
) -> Result<()> {
    let keep: Vec<usize> = (0..seq.frames()).step_by(every).collect();
    // Framing from a few frames spread over the sequence: one size for the whole loop.
    let probes = (0..8)
        .map(|i| seq.meshes(keep[i * (keep.len() - 1) / 7]))
        .collect::<Result<Vec<_>>>()?;
    let frame_size = framing_size(&probes.iter().collect::<Vec<_>>())
        .ok_or_else(|| input(format!("{}: no finite vertex to frame", seq.path.display())))?;
    let fps = seq.recording.meta.as_ref().map_or(30.0, |m| m.fps) as f32 / every as f32;
    let mut renderer = Renderer::new(size, size, ssaa);
    save(file, |w| {
        let mut gif = crate::GifWriter::new(w, size, size, fps)?;
        for (done, &k) in keep.iter().enumerate() {
            let frame = seq.meshes(k)?;
            gif.push(&picture(
                &mut renderer,
                view,
                seq,
                &frame,
                &frame_size,
                None,
            ))?;
            progress(done + 1, keep.len());
        }
        gif.finish()?;
        Ok(())
    })
}

/// The viewer's rows of metadata for a recording.
fn info_rows(recording: &Recording, path: &Path) -> Vec<(String, String)> {
    let mut rows = vec![("file".to_string(), path.display().to_string())];
    if let Some(m) = &recording.meta {
        let betas = m
            .betas
            .iter()
            .map(|b| format!("{b:.2}"))
            .collect::<Vec<_>>()
            .join(" ");
        rows.extend([
            ("garment".into(), m.garment.clone()),
            ("motion".into(), m.motion.clone()),
            (
                "material".into(),
                format!(
                    "k_s {} N/m, rho {} kg/m^2, k_b {:e} N m",
                    m.material.stretch, m.material.density, m.material.bending
                ),
            ),
            ("friction".into(), m.friction.to_string()),
            ("shape (betas)".into(), betas),
            ("body".into(), m.body_model.clone()),
            (
                "frames".into(),
                format!(
                    "{} at {} fps ({} blend-in, {} settle)",
                    m.frames, m.fps, m.blend_frames, m.settle_frames
                ),
            ),
            ("software".into(), m.software.clone()),
        ]);
    }
    rows
}

/// Writes the viewer page for one or two recordings.
pub fn write_view(
    paths: &[PathBuf],
    model: &BodyModel,
    with_body: bool,
    every: usize,
    out: &Path,
) -> Result<()> {
    let every = every.max(1);
    let mut sequences = Vec::new();
    for path in paths {
        let seq = Sequence::open(path, model, with_body)?;
        let keep: Vec<usize> = (0..seq.frames()).step_by(every).collect();
        let mut garment = Vec::with_capacity(keep.len());
        let mut body = Vec::new();
        for &k in &keep {
            let m = seq.meshes(k)?;
            garment.push(m.garment);
            if with_body {
                body.push(m.body);
            }
        }
        let fps = seq.recording.meta.as_ref().map_or(30.0, |m| m.fps) as f32 / every as f32;
        sequences.push(ViewerSequence {
            title: path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into(),
            ),
            info: info_rows(&seq.recording, path),
            fps,
            garment: Track {
                triangles: seq.recording.template.triangles.clone(),
                frames: garment,
            },
            body: Track {
                triangles: seq.body_faces.clone(),
                frames: body,
            },
        });
    }
    save(out, |w| crate::viewer::write_viewer(w, &sequences))
}

/// A sheet of three rows over `frames`: the simulation, the prediction, and the prediction
/// coloured by its per-vertex error against the simulation (the report's pictures).
pub fn comparison_sheet(
    truth: &Path,
    predicted: &Path,
    model: &BodyModel,
    frames: &[usize],
    size: u32,
    out: &Path,
) -> Result<()> {
    let a = Sequence::open(truth, model, true)?;
    let b = Sequence::open(predicted, model, true)?;
    let n = a.frames().min(b.frames());
    if let Some(&k) = frames.iter().find(|&&k| k >= n) {
        return Err(input(format!(
            "frame {k} is past the end of {} ({n} frames)",
            predicted.display()
        )));
    }
    let colouring = Colouring::new(ColourBy::Error, &b, Some(truth))?;
    let scale = colouring.default_scale();
    let meshes_a = frames
        .iter()
        .map(|&k| a.meshes(k))
        .collect::<Result<Vec<_>>>()?;
    let meshes_b = frames
        .iter()
        .map(|&k| b.meshes(k))
        .collect::<Result<Vec<_>>>()?;
    let all: Vec<&FrameMeshes> = meshes_a.iter().chain(&meshes_b).collect();
    let bounds = framing_size(&all).ok_or_else(|| input("no finite vertex to frame"))?;
    let mut renderer = Renderer::new(size, size, 2);
    let view = View::ThreeQuarter;
    let mut tiles = Vec::new();
    for (&k, m) in frames.iter().zip(&meshes_a) {
        let image = picture(&mut renderer, view, &a, m, &bounds, None);
        tiles.push((image, format!("simulated {k}")));
    }
    for (&k, m) in frames.iter().zip(&meshes_b) {
        let image = picture(&mut renderer, view, &b, m, &bounds, None);
        tiles.push((image, format!("predicted {k}")));
    }
    for (&k, m) in frames.iter().zip(&meshes_b) {
        let values = colouring.values(&b, k, m)?;
        let colours = Some((values.as_slice(), scale, colouring.label()));
        let image = picture(&mut renderer, view, &b, m, &bounds, colours);
        tiles.push((image, format!("error {k}")));
    }
    save_png(out, &crate::contact_sheet(&tiles, frames.len()))
}

/// The simulation, the prediction and its error against the simulation side by side, every
/// `every`-th frame, as a looping GIF at the recordings' speed (tiles of `size` pixels).
pub fn comparison_gif(
    truth: &Path,
    predicted: &Path,
    model: &BodyModel,
    every: usize,
    size: u32,
    out: &Path,
) -> Result<()> {
    let a = Sequence::open(truth, model, true)?;
    let b = Sequence::open(predicted, model, true)?;
    let every = every.max(1);
    let keep: Vec<usize> = (0..a.frames().min(b.frames())).step_by(every).collect();
    let probes = (0..8)
        .map(|i| keep[i * (keep.len() - 1) / 7])
        .flat_map(|k| [a.meshes(k), b.meshes(k)])
        .collect::<Result<Vec<_>>>()?;
    let bounds = framing_size(&probes.iter().collect::<Vec<_>>()).ok_or_else(|| {
        input(format!(
            "{}: no finite vertex to frame",
            predicted.display()
        ))
    })?;
    let colouring = Colouring::new(ColourBy::Error, &b, Some(truth))?;
    let scale = colouring.default_scale();
    let fps = a.recording.meta.as_ref().map_or(30.0, |m| m.fps) as f32 / every as f32;
    let mut renderer = Renderer::new(size, size, 2);
    let view = View::ThreeQuarter;
    let mut sheet = |k: usize| -> Result<RgbImage> {
        let (ma, mb) = (a.meshes(k)?, b.meshes(k)?);
        let values = colouring.values(&b, k, &mb)?;
        let colours = Some((values.as_slice(), scale, colouring.label()));
        let tiles = [
            (
                picture(&mut renderer, view, &a, &ma, &bounds, None),
                "simulated",
            ),
            (
                picture(&mut renderer, view, &b, &mb, &bounds, None),
                "predicted",
            ),
            (
                picture(&mut renderer, view, &b, &mb, &bounds, colours),
                "error",
            ),
        ]
        .map(|(image, label)| (image, format!("{label} {k}")));
        Ok(crate::contact_sheet(&tiles, 3))
    };
    let first = sheet(keep[0])?;
    save(out, |w| {
        let mut gif = crate::GifWriter::new(w, first.width(), first.height(), fps)?;
        gif.push(&first)?;
        for &k in &keep[1..] {
            gif.push(&sheet(k)?)?;
        }
        gif.finish()?;
        Ok(())
    })
}
