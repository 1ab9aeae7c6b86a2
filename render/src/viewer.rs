//! The web viewer: one self-contained HTML file (WebGL 2, no network) that plays one or more
//! sequences side by side.
//!
//! Vertex tracks are quantized to 16-bit integers around their centre, delta-coded between
//! frames (wrapping, so decoding is exact), gzip-compressed and embedded as base64; the page
//! inflates them with the browser's own `DecompressionStream`. Smooth motion compresses about
//! 3-6x this way, which keeps a 300-frame garment-plus-body sequence to a few megabytes.

use std::io::Write;

use base64::Engine;
use flate2::Compression;
use flate2::write::GzEncoder;
use serde_json::{Value, json};

use crate::{Error, P3};

/// Page template; `{{MANIFEST}}` and `{{PAYLOAD}}` are replaced.
const PAGE: &str = include_str!("viewer.html");

/// Garment colour of the first sequence (the renderer's default too), then the second.
pub const GARMENT_COLOURS: [[u8; 3]; 2] = [[62, 110, 205], [214, 120, 52]];
/// Body colour.
pub const BODY_COLOUR: [u8; 3] = [206, 182, 166];

/// A triangle mesh moving through frames.
#[derive(Debug, Clone, Default)]
pub struct Track {
    /// Triangles (vertex indices).
    pub triangles: Vec<[u32; 3]>,
    /// Vertex positions per frame, all frames the same length.
    pub frames: Vec<Vec<P3>>,
}

/// One sequence shown in the viewer.
#[derive(Debug, Clone, Default)]
pub struct ViewerSequence {
    /// Heading shown above the sequence.
    pub title: String,
    /// Rows of metadata (name, value) shown under the heading.
    pub info: Vec<(String, String)>,
    /// Playback rate, frames per second.
    pub fps: f32,
    /// The garment.
    pub garment: Track,
    /// The body (no frames: no body).
    pub body: Track,
}

/// Writes the viewer page for the sequences (at least one, each with garment frames).
pub fn write_viewer(out: &mut impl Write, sequences: &[ViewerSequence]) -> Result<(), Error> {
    if sequences.is_empty() {
        return Err(Error::Input("no sequence to show".into()));
    }
    let mut payload = Vec::new();
    let mut manifest = Vec::new();
    for (k, s) in sequences.iter().enumerate() {
        if s.garment.frames.is_empty() {
            return Err(Error::Input(format!(
                "sequence '{}' has no frames",
                s.title
            )));
        }
        let colour = GARMENT_COLOURS[k % GARMENT_COLOURS.len()];
        let garment = encode_track(&s.garment, colour, &mut payload)?;
        let body = if s.body.frames.is_empty() {
            Value::Null
        } else {
            encode_track(&s.body, BODY_COLOUR, &mut payload)?
        };
        manifest.push(json!({
            "title": s.title, "info": s.info, "fps": s.fps,
            "frames": s.garment.frames.len(), "garment": garment, "body": body,
        }));
    }
    let mut gz = GzEncoder::new(Vec::new(), Compression::default());
    gz.write_all(&payload)?;
    let compressed = gz.finish()?;
    let encoded = base64::engine::general_purpose::STANDARD.encode(compressed);
    // `<` inside JSON strings is escaped so no value can close the script element.
    let manifest = json!({ "sequences": manifest })
        .to_string()
        .replace('<', "\\u003c");
    let page = PAGE
        .replacen("{{MANIFEST}}", &manifest, 1)
        .replacen("{{PAYLOAD}}", &encoded, 1);
    out.write_all(page.as_bytes())?;
    Ok(())
}

/// Appends a track's triangles (u32) and quantized frames (i16 deltas) to the payload and
/// returns where they are.
fn encode_track(track: &Track, colour: [u8; 3], payload: &mut Vec<u8>) -> Result<Value, Error> {
    let n = track.frames[0].len();
    if let Some(k) = track.frames.iter().position(|f| f.len() != n) {
        return Err(Error::Input(format!(
            "frame {k} has {} vertices, frame 0 has {n}",
            track.frames[k].len()
        )));
    }
    if track.triangles.iter().flatten().any(|&i| i as usize >= n) {
        return Err(Error::Input(format!(
            "a triangle refers to a vertex past the {n} vertices"
        )));
    }
    let bounds = crate::Bounds::of(track.frames.iter().flatten())
        .ok_or_else(|| Error::Input("no finite vertex".into()))?;
    let origin = bounds.center();
    let half = (0..3)
        .map(|i| 0.5 * (bounds.max[i] - bounds.min[i]))
        .fold(0.0f32, f32::max);
    // 32,000 steps either side of the centre; at most 0.1 mm unless the track spans > 6.4 m.
    let step = (half / 32000.0).max(1e-4);
    let triangles_at = payload.len();
    for i in track.triangles.iter().flatten() {
        payload.extend_from_slice(&i.to_le_bytes());
    }
    let frames_at = payload.len();
    let mut previous = vec![0i16; 3 * n];
    for frame in &track.frames {
        for (v, p) in frame.iter().enumerate() {
            for c in 0..3 {
                let q = if p[c].is_finite() {
                    ((p[c] - origin[c]) / step).round().clamp(-32767.0, 32767.0) as i16
                } else {
                    0
                };
                let delta = q.wrapping_sub(previous[3 * v + c]);
                previous[3 * v + c] = q;
                payload.extend_from_slice(&delta.to_le_bytes());
            }
        }
    }
    while !payload.len().is_multiple_of(4) {
        payload.push(0);
    }
    Ok(json!({
        "triangles": {"offset": triangles_at, "count": track.triangles.len()},
        "track": {"offset": frames_at, "frames": track.frames.len(), "vertices": n,
                  "origin": origin, "step": step},
        "colour": colour,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use flate2::read::GzDecoder;
    use std::io::Read;

    fn sequence() -> ViewerSequence {
        let frames = (0..5)
            .map(|f| {
                vec![
                    [0.0, 0.0, 0.0],
                    [1.0, f as f32 * 0.01, 0.0],
                    [0.0, 1.0, -3.0],
                ]
            })
            .collect();
        ViewerSequence {
            title: "a</script>".into(),
            info: vec![("motion".into(), "walk".into())],
            fps: 30.0,
            garment: Track {
                triangles: vec![[0, 1, 2]],
                frames,
            },
            body: Track::default(),
        }
    }

    /// Decodes the page's payload the way the page's script does.
    fn decode(page: &str) -> (Value, Vec<u8>) {
        let manifest = page.split("type=\"application/json\">").nth(1).unwrap();
        let manifest: Value = serde_json::from_str(manifest.split("</script>").next().unwrap())
            .expect("manifest is JSON");
        let b64 = page
            .split("type=\"application/octet-stream\">")
            .nth(1)
            .unwrap();
        let b64 = b64.split("</script>").next().unwrap().trim();
        let gz = base64::engine::general_purpose::STANDARD
            .decode(b64)
            .unwrap();
        let mut raw = Vec::new();
        GzDecoder::new(&gz[..]).read_to_end(&mut raw).unwrap();
        (manifest, raw)
    }

    #[test]
    fn tracks_decode_to_within_half_a_step() {
        let s = sequence();
        let mut page = Vec::new();
        write_viewer(&mut page, std::slice::from_ref(&s)).unwrap();
        let page = String::from_utf8(page).unwrap();
        assert!(!page.contains("{{"), "placeholders left in the page");
        let (m, raw) = decode(&page);
        let seq = &m["sequences"][0];
        assert_eq!(seq["title"], "a</script>");
        let t = &seq["garment"]["track"];
        let (offset, n) = (t["offset"].as_u64().unwrap() as usize, 9);
        let step = t["step"].as_f64().unwrap() as f32;
        let origin: Vec<f32> = serde_json::from_value(t["origin"].clone()).unwrap();
        let mut q = vec![0i16; n];
        for (f, frame) in s.garment.frames.iter().enumerate() {
            for (i, q) in q.iter_mut().enumerate() {
                let at = offset + 2 * (f * n + i);
                *q = q.wrapping_add(i16::from_le_bytes([raw[at], raw[at + 1]]));
                let decoded = origin[i % 3] + *q as f32 * step;
                assert!((decoded - frame[i / 3][i % 3]).abs() <= 0.5 * step + 1e-6);
            }
        }
    }

    #[test]
    fn bad_tracks_are_refused() {
        let mut s = sequence();
        s.garment.triangles = vec![[0, 1, 7]];
        assert!(write_viewer(&mut Vec::new(), &[s]).is_err());
        assert!(write_viewer(&mut Vec::new(), &[]).is_err());
    }
}
