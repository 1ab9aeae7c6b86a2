//! The evaluation report: per-sequence rows and their means, the paper's tables beside ours
//! (`README.md` and a self-contained `index.html`), and pictures of the median and the worst
//! sequence of each split (simulated | predicted | error sheets, a side-by-side viewer page).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use base64::Engine;
use indicatif::ProgressBar;
use motions::BodyModel;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use sim::recording::{Recording, TemplateArrays};
use surrogate::data::Sequence;
use surrogate::evaluate::{Method, MethodScores};
use surrogate::predict::{BodySequence, Predictor, Settings};

use crate::output::write_atomic;
use crate::pictures::{comparison_sheet, write_view};
use crate::prediction::{Recorded, record_prediction};

/// One sequence's rows, as cached and as listed in the JSON.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SequenceResult {
    pub id: String,
    pub split: String,
    pub garment: String,
    pub motion: String,
    pub file: String,
    /// The settings the rows were made with (a cached result is reused only under equal ones).
    pub settings: Value,
    pub methods: BTreeMap<Method, MethodScores>,
    /// The simulation's own jitter, stretch and inside figures.
    pub simulation: MethodScores,
}

/// Per split: the mean row of every method.
pub type SplitRows = BTreeMap<String, BTreeMap<Method, MethodScores>>;

/// The mean rows of every split and method, and the simulation's per split.
pub fn aggregate(results: &[SequenceResult]) -> (SplitRows, BTreeMap<String, MethodScores>) {
    let mut rows: BTreeMap<String, BTreeMap<Method, Vec<MethodScores>>> = BTreeMap::new();
    let mut simulation: BTreeMap<String, Vec<MethodScores>> = BTreeMap::new();
    for r in results {
        for (m, s) in &r.methods {
            let split = rows.entry(r.split.clone()).or_default();
            split.entry(*m).or_default().push(*s);
        }
        simulation
            .entry(r.split.clone())
            .or_default()
            .push(r.simulation);
    }
    let mean = |v: Vec<MethodScores>| MethodScores::mean(&v);
    let splits = rows
        .into_iter()
        .map(|(s, m)| (s, m.into_iter().map(|(k, v)| (k, mean(v))).collect()))
        .collect();
    let simulation = simulation.into_iter().map(|(k, v)| (k, mean(v))).collect();
    (splits, simulation)
}

/// The paper's published numbers (METRICS.md), measured on other data.
pub fn paper_numbers() -> Value {
    json!({
        "source": "DiT-Garment paper (via METRICS.md); measured on the paper's data, not ours",
        "table2_unseen_garment_motion_shape": [
            {"method": "DiT-Garment full (patch 1, guidance, 100 steps)", "E_v": 5.20, "E_CD": 0.17, "E_n": 0.38, "E_c": 0.62, "E_b": 0.51, "E_s": 1.32, "E_d": 2.66, "fps": "0.4 (GPU)"},
            {"method": "DiT-Garment patch 1, no guidance, 20 steps", "E_v": 5.38, "E_CD": 0.20, "E_n": 0.38, "E_c": 0.62, "E_b": 0.50, "E_s": 0.62, "E_d": 2.99, "fps": "2.6"},
            {"method": "DiT-Garment patch 2, no guidance", "E_v": 5.67, "E_CD": 0.18, "E_n": 0.39, "E_c": 0.63, "E_b": 0.50, "E_s": 0.64, "E_d": 3.38, "fps": "6.1"},
            {"method": "DiT-Garment patch 8, no guidance", "E_v": 5.99, "E_CD": 0.25, "E_n": 0.44, "E_c": 0.64, "E_b": 0.51, "E_s": 1.17, "E_d": 2.89, "fps": "11.9"},
            {"method": "DPF (point-based)", "E_v": 6.95, "E_CD": 0.18, "E_n": 0.42, "E_c": 0.64, "E_b": 0.49, "E_s": 0.22, "E_d": 3.94, "fps": "0.05"},
            {"method": "ContourCraft (graph network)", "E_v": 15.35, "E_CD": 1.21, "E_n": 0.51, "E_c": 0.49, "E_b": 0.53, "E_s": 14.44, "E_d": 11.33, "fps": "1.7"}
        ],
        "one_factor_E_v": {"test_garment": 4.30, "test_motion": 3.40, "test_shape": 2.07, "test_material": 0.94},
        "seen_templates_full_model": {"E_v": 3.02, "E_CD": 0.09, "E_n": 0.28, "E_c": 0.64, "E_b": 0.48, "E_s": 0.13, "E_d": 1.33}
    })
}

/// The split a paper table row stands for.
fn one_factor(split: &str) -> Option<f64> {
    paper_numbers()["one_factor_E_v"][split].as_f64()
}

const COLUMNS: [&str; 16] = [
    "E_v",
    "E_CD",
    "E_CD_cm",
    "E_n",
    "E_c",
    "E_c_vertex",
    "E_b",
    "E_s",
    "E_d",
    "jitter",
    "stretch_p99",
    "inside_percent",
    "inside_overlap_percent",
    "max_penetration_m",
    "max_penetration_overlap_m",
    "fps",
];

/// The columns the simulation's own row fills (plausibility, not error against itself).
const SIMULATION_COLUMNS: [&str; 6] = [
    "jitter",
    "stretch_p99",
    "inside_percent",
    "inside_overlap_percent",
    "max_penetration_m",
    "max_penetration_overlap_m",
];

/// A column's value as the report prints it (depths in m to 0.1 mm).
fn cell(s: &MethodScores, key: &str) -> String {
    if key.ends_with("_m") {
        format!("{:.4}", value(s, key))
    } else {
        format!("{:.3}", value(s, key))
    }
}

fn value(s: &MethodScores, key: &str) -> f64 {
    serde_json::to_value(s)
        .ok()
        .and_then(|v| v[key].as_f64())
        .unwrap_or(f64::NAN)
}

fn row(name: &str, values: impl Iterator<Item = String>) -> String {
    format!("| {name} | {} |", values.collect::<Vec<_>>().join(" | "))
}

fn header(first: &str, columns: &[&str]) -> String {
    format!(
        "| {first} | {} |\n|{}",
        columns.join(" | "),
        "---|".repeat(columns.len() + 1)
    )
}

/// The markdown tables of the report.
fn tables(splits: &SplitRows, simulation: &BTreeMap<String, MethodScores>) -> String {
    let mut md = String::new();
    let paper = paper_numbers();
    if let Some(test) = splits.get("test") {
        let _ = writeln!(
            md,
            "## Table 2: unseen garment x motion x shape (split `test`)\n\n{}",
            header(
                "method",
                &["E_v", "E_CD", "E_n", "E_c", "E_b", "E_s", "E_d", "fps"]
            )
        );
        for (m, s) in test {
            let v = ["E_v", "E_CD", "E_n", "E_c", "E_b", "E_s", "E_d", "fps"]
                .map(|k| format!("{:.2}", value(s, k)));
            let _ = writeln!(md, "{}", row(&format!("ours: {}", m.name()), v.into_iter()));
        }
        for p in paper["table2_unseen_garment_motion_shape"]
            .as_array()
            .into_iter()
            .flatten()
        {
            let v =
                ["E_v", "E_CD", "E_n", "E_c", "E_b", "E_s", "E_d", "fps"].map(|k| match &p[k] {
                    Value::String(s) => s.clone(),
                    other => format!("{:.2}", other.as_f64().unwrap_or(f64::NAN)),
                });
            let name = format!("paper: {}", p["method"].as_str().unwrap_or(""));
            let _ = writeln!(md, "{}", row(&name, v.into_iter()));
        }
        let _ = writeln!(
            md,
            "\nThe paper's rows were measured on its data (GarmentCodeData designs, AMASS), not ours.\n"
        );
    }
    let factors: Vec<&String> = splits.keys().filter(|s| one_factor(s).is_some()).collect();
    if !factors.is_empty() {
        let methods: Vec<Method> = Method::ALL
            .into_iter()
            .filter(|m| factors.iter().any(|s| splits[*s].contains_key(m)))
            .collect();
        let mut cols: Vec<&str> = methods.iter().map(|m| m.name()).collect();
        cols.push("paper (full model)");
        let _ = writeln!(
            md,
            "## One unseen factor at a time (E_v, cm)\n\n{}",
            header("split", &cols)
        );
        for s in factors {
            let mut v: Vec<String> = methods
                .iter()
                .map(|m| {
                    splits[s]
                        .get(m)
                        .map_or("".into(), |r| format!("{:.2}", r.scores.E_v))
                })
                .collect();
            v.push(format!("{:.2}", one_factor(s).unwrap_or(f64::NAN)));
            let _ = writeln!(md, "{}", row(s, v.into_iter()));
        }
        let _ = writeln!(md);
    }
    let ablation: Vec<(&String, &MethodScores, &MethodScores)> = splits
        .iter()
        .filter_map(|(s, m)| Some((s, m.get(&Method::Model)?, m.get(&Method::ModelNoGuidance)?)))
        .collect();
    if !ablation.is_empty() {
        let cols = [
            "E_v",
            "E_c",
            "E_c_vertex",
            "inside_percent",
            "stretch_p99",
            "fps",
        ];
        let _ = writeln!(
            md,
            "## Guidance ablation\n\n{}",
            header("split, guidance", &cols)
        );
        for (s, on, off) in ablation {
            for (name, r) in [("on", on), ("off", off)] {
                let v = cols.map(|k| format!("{:.3}", value(r, k)));
                let _ = writeln!(md, "{}", row(&format!("{s}, {name}"), v.into_iter()));
            }
        }
        let _ = writeln!(
            md,
            "| paper, on (100 steps) | 5.20 | 0.62 | | | | 0.4 |\n| paper, off (20 steps) | 5.38 | 0.62 | | | | 2.6 |\n"
        );
    }
    for (s, methods) in splits {
        let _ = writeln!(
            md,
            "## Split `{s}`, every metric\n\n{}",
            header("method", &COLUMNS)
        );
        for (m, r) in methods {
            let v = COLUMNS.map(|k| cell(r, k));
            let _ = writeln!(md, "{}", row(m.name(), v.into_iter()));
        }
        if let Some(sim) = simulation.get(s) {
            let v = COLUMNS.map(|k| {
                if SIMULATION_COLUMNS.contains(&k) {
                    cell(sim, k)
                } else {
                    String::new()
                }
            });
            let _ = writeln!(md, "{}", row("simulation (reference)", v.into_iter()));
        }
        let n = methods.values().next().map_or(0, |r| r.sequences);
        let _ = writeln!(md, "\n{n} sequences.\n");
    }
    md
}

/// Prints the short table of `evaluate`.
pub fn print_table(splits: &SplitRows) {
    println!(
        "{:<14} {:<18} {:>8} {:>8} {:>9} {:>8} {:>8} {:>8}",
        "split", "method", "E_v cm", "E_c %", "inside %", "stretch", "jitter", "fps"
    );
    for (s, methods) in splits {
        for (m, r) in methods {
            println!(
                "{:<14} {:<18} {:>8.3} {:>8.3} {:>9.3} {:>8.3} {:>8.4} {:>8.1}",
                s,
                m.name(),
                r.scores.E_v,
                r.scores.E_c,
                r.inside_percent,
                r.stretch_p99,
                r.jitter,
                r.fps
            );
        }
    }
}

/// What the pictures need: the dataset, the body model and the model to predict with.
pub struct Pictures<'a> {
    pub data: &'a Path,
    pub body: &'a BodyModel,
    pub predictor: Option<&'a Predictor<'a>>,
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
        bar: &ProgressBar::hidden(),
    };
    record_prediction(out, recorded)?;
    Ok(())
}

/// Writes `DIR/README.md`, `DIR/index.html` and the pictures.
pub fn write(dir: &Path, output: &Value, results: &[SequenceResult], p: &Pictures) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
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
                std::fs::create_dir_all(&out)?;
                let predicted = out.join("predicted.mcap");
                predict_recording(p, predictor, r, &predicted)
                    .with_context(|| format!("predicting {}", r.id))?;
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
                    r.garment, r.motion, r.id
                );
                let _ = writeln!(
                    md,
                    "### {title}\n\nRows: simulated, predicted, error (cm). [Side by side viewer]({folder}/view.html)\n\n![{title}]({folder}/sheet.png)\n"
                );
                let png = std::fs::read(&sheet)?;
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
    write_atomic(&dir.join("README.md"), |w| Ok(w.write_all(md.as_bytes())?))?;
    let html = format!(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>Evaluation report</title><style>body{{font-family:sans-serif;max-width:1200px;margin:auto}}table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}</style></head><body>{}{}</body></html>\n",
        markdown_tables_to_html(&md),
        html_pictures
    );
    write_atomic(&dir.join("index.html"), |w| {
        Ok(w.write_all(html.as_bytes())?)
    })?;
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
