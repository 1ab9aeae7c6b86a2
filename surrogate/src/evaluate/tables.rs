//! The evaluation's tables: sequences' rows averaged per split and method, and the report's
//! markdown tables beside the paper's published numbers (METRICS.md).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::{Method, MethodScores};

/// One sequence's rows, as cached and as listed in the JSON.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SequenceResult {
    /// The sequence's id in the dataset.
    pub id: String,
    /// Its split.
    pub split: String,
    /// Its garment.
    pub garment: String,
    /// Its garment's family (`fitted_top`, `loose_top`, `dress_or_skirt`), set for every
    /// result, cached ones included, by [`super::family::fill_families`].
    #[serde(default)]
    pub family: String,
    /// Its motion.
    pub motion: String,
    /// Its recording, relative to the dataset folder.
    pub file: String,
    /// The settings the rows were made with (a cached result is reused only under equal ones).
    pub settings: Value,
    /// Each method's scores.
    pub methods: BTreeMap<Method, MethodScores>,
    /// The simulation's own jitter, stretch and inside figures.
    pub simulation: MethodScores,
}

/// Per split: the mean row of every method.
pub type SplitRows = BTreeMap<String, BTreeMap<Method, MethodScores>>;

/// The rows of every split and method, and the simulation's per split ([`aggregate`]).
pub type Rows = (SplitRows, BTreeMap<String, MethodScores>);

/// The short table `evaluate` prints: one line per split and method.
pub fn text_table(splits: &SplitRows) -> String {
    grouped_text_table("split", &BTreeMap::from([(String::new(), splits.clone())]))
}

/// The table of a split's groups (families or motions): one line per split, group and
/// method; `label` names the group column, as wide as its longest name.
pub fn grouped_text_table(label: &str, groups: &GroupRows) -> String {
    let width = groups
        .values()
        .flat_map(|rows| rows.keys())
        .map(String::len)
        .fold(18, usize::max);
    let mut text = format!(
        "{:<14} {:<width$} {:<18} {:>8} {:>8} {:>9} {:>8} {:>8} {:>8}\n",
        "split", label, "method", "E_v cm", "E_c %", "inside %", "stretch", "jitter", "fps"
    );
    if groups.keys().all(String::is_empty) {
        text = text.replacen(&format!("{:<14} ", "split"), "", 1);
    }
    for (split, rows) in groups {
        for (group, methods) in rows {
            for (m, r) in methods {
                if !split.is_empty() {
                    text += &format!("{split:<14} ");
                }
                text += &format!(
                    "{:<width$} {:<18} {:>8.3} {:>8.3} {:>9.3} {:>8.3} {:>8.4} {:>8.1}\n",
                    group,
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
    text
}

/// Per split, then per group (a family or a motion): the mean row of every method.
pub type GroupRows = BTreeMap<String, SplitRows>;

/// The mean rows of every method per split and per group of `key` within it.
pub fn aggregate_by(
    results: &[SequenceResult],
    key: impl Fn(&SequenceResult) -> String,
) -> GroupRows {
    let mut rows: BTreeMap<String, BTreeMap<String, BTreeMap<Method, Vec<MethodScores>>>> =
        BTreeMap::new();
    for r in results {
        let group = rows
            .entry(r.split.clone())
            .or_default()
            .entry(key(r))
            .or_default();
        for (m, s) in &r.methods {
            group.entry(*m).or_default().push(*s);
        }
    }
    rows.into_iter()
        .map(|(split, groups)| {
            let groups = groups
                .into_iter()
                .map(|(g, methods)| {
                    let means = methods
                        .into_iter()
                        .map(|(m, v)| (m, MethodScores::mean(&v)))
                        .collect();
                    (g, means)
                })
                .collect();
            (split, groups)
        })
        .collect()
}

/// The mean rows of every split and method, and the simulation's per split.
pub fn aggregate(results: &[SequenceResult]) -> Rows {
    let mut simulation: BTreeMap<String, Vec<MethodScores>> = BTreeMap::new();
    for r in results {
        simulation
            .entry(r.split.clone())
            .or_default()
            .push(r.simulation);
    }
    let splits = aggregate_by(results, |_| String::new())
        .into_iter()
        .map(|(split, mut groups)| (split, groups.remove("").unwrap_or_default()))
        .collect();
    let mean = |v: Vec<MethodScores>| MethodScores::mean(&v);
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

/// The markdown tables of the report: the paper's Table 2 layout for `test`, one unseen
/// factor at a time, the guidance ablation, and every metric of every split.
pub fn tables(splits: &SplitRows, simulation: &BTreeMap<String, MethodScores>) -> String {
    let mut md = String::new();
    if let Some(test) = splits.get("test") {
        table2(&mut md, test);
    }
    one_factor_table(&mut md, splits);
    guidance_table(&mut md, splits);
    every_metric(&mut md, splits, simulation);
    md
}

/// The paper's Table 2 layout for the `test` split, with the paper's rows.
fn table2(md: &mut String, test: &BTreeMap<Method, MethodScores>) {
    let paper = paper_numbers();
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
        let v = ["E_v", "E_CD", "E_n", "E_c", "E_b", "E_s", "E_d", "fps"].map(|k| match &p[k] {
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

/// E_v of every method on the one-unseen-factor splits, beside the paper's full model.
fn one_factor_table(md: &mut String, splits: &SplitRows) {
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
}

/// With and without guidance, on the splits scored both ways.
fn guidance_table(md: &mut String, splits: &SplitRows) {
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
}

/// Every metric of every split, with the simulation's own row.
fn every_metric(md: &mut String, splits: &SplitRows, simulation: &BTreeMap<String, MethodScores>) {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(split: &str, lbs_e_v: f64, model_e_v: f64) -> SequenceResult {
        let scores = |e_v: f64| {
            let mut s = MethodScores {
                fps: 10.0,
                frames_predicted: 10,
                sequences: 1,
                ..MethodScores::default()
            };
            s.scores.E_v = e_v;
            s
        };
        SequenceResult {
            id: format!("{split}-{lbs_e_v}"),
            split: split.into(),
            garment: "skirt".into(),
            family: "dress_or_skirt".into(),
            motion: "walk".into(),
            file: "sequences/x.mcap".into(),
            settings: json!({}),
            methods: [
                (Method::Lbs, scores(lbs_e_v)),
                (Method::Model, scores(model_e_v)),
            ]
            .into_iter()
            .collect(),
            simulation: MethodScores {
                stretch_p99: 1.25,
                ..MethodScores::default()
            },
        }
    }

    #[test]
    fn rows_are_averaged_per_split_and_method_and_tabled_beside_the_paper() {
        let results = [
            result("test", 4.0, 2.0),
            result("test", 6.0, 3.0),
            result("test_motion", 1.0, 0.5),
        ];
        let (splits, simulation) = aggregate(&results);
        assert_eq!(splits["test"][&Method::Lbs].scores.E_v, 5.0);
        assert_eq!(splits["test"][&Method::Model].scores.E_v, 2.5);
        assert_eq!(splits["test"][&Method::Model].sequences, 2);
        assert_eq!(splits["test_motion"][&Method::Lbs].scores.E_v, 1.0);
        assert_eq!(simulation["test"].stretch_p99, 1.25);
        let md = tables(&splits, &simulation);
        assert!(md.contains("## Table 2: unseen garment x motion x shape (split `test`)"));
        assert!(md.contains("| ours: model | 2.50 |"), "{md}");
        assert!(md.contains("| paper: DiT-Garment full (patch 1, guidance, 100 steps) | 5.20 |"));
        // One factor: test_motion, the model then lbs (Method::ALL's order), the paper's 3.40.
        assert!(md.contains("| test_motion | 0.50 | 1.00 | 3.40 |"), "{md}");
        assert!(md.contains("| simulation (reference) |"));
    }

    #[test]
    fn a_group_column_is_as_wide_as_its_longest_name() {
        let mut capture = result("test", 4.0, 2.0);
        capture.motion = "01_01.bvh:start=19,duration=2.5".into();
        let results = [capture, result("test", 6.0, 3.0)];
        let text = grouped_text_table("motion", &aggregate_by(&results, |r| r.motion.clone()));
        assert!(text.contains("01_01.bvh:start=19,duration=2.5"), "{text}");
        // Two motions, two methods: one line each, columns aligned with the header.
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 5, "{text}");
        let method_column = lines[0].find("method").unwrap();
        assert!(
            lines[1..]
                .iter()
                .all(|l| l[method_column..].starts_with("lbs")
                    || l[method_column..].starts_with("model")),
            "{text}"
        );
    }
}
