//! The evaluation report: per-sequence rows and their means, the paper's tables beside ours
//! (`README.md` and a self-contained `index.html`), and pictures of the median and the worst
//! sequence of each split (simulated | predicted | error sheets, a side-by-side viewer page).

use std::fmt::Write as _;
use std::path::Path;

use base64::Engine;
use motions::BodyModel;
use render::recording::{comparison_sheet, write_view};
use serde_json::{Value, json};
use sim::recording::{Recording, TemplateArrays};

use super::Method;
use super::tables::{SequenceResult, aggregate, tables};
use crate::data::Sequence;
use crate::error::{Result, file_error};
use crate::predict::{BodySequence, Predictor, Recorded, Settings, record_prediction};

/// What the pictures need: the dataset, the body model and the model to predict with.
pub struct Pictures<'a> {
    /// The dataset folder.
    pub data: &'a Path,
    /// The body model.
    pub body: &'a BodyModel,
    /// The model (no pictures without one).
    pub predictor: Option<&'a Predictor<'a>>,
    /// The sampler's settings.
    pub settings: Settings,
}

/// The median and the worst sequence of a split by the model's E_v.
fn picked<'a>(
    results: &'a [SequenceResult],
    split: &str,
) -> Vec<(&'static str, &'a SequenceResult)> {
    let mut of: Vec<&SequenceResult> = results
        .iter()
        .filter(|r| r.split == split && r.methods.contains_key(&Method::Model))
        .collect();
    of.sort_by(|a, b| {
        a.methods[&Method::Model]
            .scores
            .E_v
            .total_cmp(&b.methods[&Method::Model].scores.E_v)
    });
    match of.len() {
        0 => vec![],
        1 => vec![("median", of[0])],
        n => vec![("median", of[n / 2]), ("worst", of[n - 1])],
    }
}

/// Predicts the sequence `r` with the model into `out` (every frame, as recorded).
fn predict_recording(
    p: &Pictures,
    predictor: &Predictor,
    r: &SequenceResult,
    out: &Path,
) -> Result<()> {
    let truth = p.data.join(&r.file);
    let recording = Recording::read(&truth)?;
    let seq = Sequence::from_recording(recording, &truth)?;
    let template: &TemplateArrays = &seq.template;
    let mut garment = predictor.garment(template)?;
    let motion = seq.motion()?;
    let predicted = json!({"model": "evaluated model", "settings": p.settings});
    let recorded = Recorded {
        predictor,
        garment: &mut garment,
        template,
        body: BodySequence {
            motion: &motion,
            betas: &seq.betas,
            material: seq.meta.material,
        },
        frames: 0..seq.len(),
        settings: &p.settings,
        meta: &seq.meta,
        predicted: &predicted,
        faces: p.body.faces(),
        body_vertices: false,
        obj: None,
        tick: &mut || {},
    };
    record_prediction(out, recorded)?;
    Ok(())
}

/// Writes `dir/README.md`, `dir/index.html` and the pictures; `output` is the evaluation's
/// JSON (its `settings` and `model` head the report).
pub fn write(dir: &Path, output: &Value, results: &[SequenceResult], p: &Pictures) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| file_error(dir, e))?;
    let (splits, simulation) = aggregate(results);
    let mut md = String::from("# Evaluation report\n\n");
    let s = &output["settings"];
    let _ = writeln!(
        md,
        "Model: `{}`. Data: `{}`. Sampler: {} steps, guidance {} from {} of the steps, seed {}, batch {}, {} threads. Protocol: {}.\n\nUnits: E_v, E_CD_cm, E_d and jitter in cm; E_CD in 100 m^2; E_c, E_c_vertex and inside_percent in %; E_b in rad; E_s x 1e5; fps in frames/s (preparation excluded). `floor` is the ground truth through the UV maps (the best any UV model can do); `rest` the template carried by the root; `lbs` the template skinned with the project's skinning, `lbs_nearest` with plain nearest-vertex weights.\n",
        output["model"]["run"]
            .as_str()
            .unwrap_or("none (baselines only)"),
        s["data"].as_str().unwrap_or(""),
        s["steps"],
        s["guidance"],
        s["guidance_start"],
        s["seed"],
        s["batch"],
        s["threads"],
        s["protocol"].as_str().unwrap_or("")
    );
    md.push_str(&tables(&splits, &simulation));
    let mut html_pictures = String::new();
    if let Some(predictor) = p.predictor {
        let _ = writeln!(
            md,
            "## Pictures: the median and the worst sequence of each split (by the model's E_v)\n"
        );
        for split in splits.keys() {
            for (which, r) in picked(results, split) {
                let folder = format!("pictures/{split}_{which}");
                let out = dir.join(&folder);
                std::fs::create_dir_all(&out).map_err(|e| file_error(&out, e))?;
                let predicted = out.join("predicted.mcap");
                predict_recording(p, predictor, r, &predicted)
                    .map_err(|e| file_error(&predicted, format!("predicting {}: {e}", r.id)))?;
                let truth = p.data.join(&r.file);
                let n = Recording::read(&truth)?.garment.len();
                let first = n / 3;
                let frames: Vec<usize> = (0..4).map(|i| first + i * (n - 1 - first) / 3).collect();
                let sheet = out.join("sheet.png");
                comparison_sheet(&truth, &predicted, p.body, &frames, 256, &sheet)?;
                write_view(
                    &[truth.clone(), predicted.clone()],
                    p.body,
                    true,
                    2,
                    &out.join("view.html"),
                )?;
                let e_v = r.methods[&Method::Model].scores.E_v;
                let title = format!(
                    "{split}, {which}: {} on {} ({}), E_v {e_v:.2} cm",
                    r.garment,
                    motions::short_label(&r.motion),
                    r.id
                );
                let _ = writeln!(
                    md,
                    "### {title}\n\nRows: simulated, predicted, error (cm). [Side by side viewer]({folder}/view.html)\n\n![{title}]({folder}/sheet.png)\n"
                );
                let png = std::fs::read(&sheet).map_err(|e| file_error(&sheet, e))?;
                let _ = writeln!(
                    html_pictures,
                    "<h3>{title}</h3><p>Rows: simulated, predicted, error. <a href=\"{folder}/view.html\">Side by side viewer</a></p><img src=\"data:image/png;base64,{}\" style=\"max-width:100%\">",
                    base64::engine::general_purpose::STANDARD.encode(png)
                );
            }
        }
    }
    let _ = writeln!(
        md,
        "Per-sequence rows are in the JSON (`sequences`) and in `sequences/<id>.json`."
    );
    files::write_atomic(&dir.join("README.md"), md.as_bytes())?;
    let html = format!(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>Evaluation report</title><style>body{{font-family:sans-serif;max-width:1200px;margin:auto}}table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}</style></head><body>{}{}</body></html>\n",
        markdown_tables_to_html(&md),
        html_pictures
    );
    files::write_atomic(&dir.join("index.html"), html.as_bytes())?;
    Ok(())
}

/// The report's markdown as HTML: headings, paragraphs and pipe tables (no pictures: the page
/// embeds those itself).
fn markdown_tables_to_html(md: &str) -> String {
    let mut html = String::new();
    let mut in_table = false;
    for line in md.lines() {
        if line.starts_with('|') {
            if line.starts_with("|---") {
                continue;
            }
            if !in_table {
                html.push_str("<table>");
                in_table = true;
            }
            let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
            let _ = write!(
                html,
                "<tr>{}</tr>",
                cells
                    .iter()
                    .map(|c| format!("<td>{}</td>", escape(c)))
                    .collect::<String>()
            );
            continue;
        }
        if in_table {
            html.push_str("</table>");
            in_table = false;
        }
        if let Some(h) = line.strip_prefix("## ") {
            let _ = write!(html, "<h2>{}</h2>", escape(h));
        } else if let Some(h) = line.strip_prefix("# ") {
            let _ = write!(html, "<h1>{}</h1>", escape(h));
        } else if line.starts_with("### ") || line.starts_with("![") || line.starts_with("Rows:") {
            continue;
        } else if !line.is_empty() {
            let _ = write!(html, "<p>{}</p>", escape(line));
        }
    }
    if in_table {
        html.push_str("</table>");
    }
    html
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
