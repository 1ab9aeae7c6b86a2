//! Two `evaluate` results of the same recordings compared sequence by sequence
//! (`dit-garment paired A.json B.json`).
//!
//! Why paired: sequences differ from each other far more than two models differ on one
//! sequence, so the mean of the per-sequence differences has a standard error several times
//! smaller than the two means' own spreads. Choosing between arms, or telling a seed's luck
//! from a recipe's gain, is read from that difference, its standard error and how many
//! sequences each side wins; per split, garment family, motion and garment.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;
use serde_json::Value;

use crate::error::{Result, bad_value, file_error};

/// One sequence's score in one evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Scored {
    /// The sequence's id in the dataset.
    pub id: String,
    /// The recording's SHA-256 as the evaluation read it (`settings.sha256`), if recorded.
    pub recording: Option<String>,
    /// Split, family, motion and garment, the groups it is reported under.
    pub split: String,
    /// Garment family (`fitted_top`, `loose_top`, `dress_or_skirt`).
    pub family: String,
    /// Motion label.
    pub motion: String,
    /// Garment name (a library design and its variant, `boatneck_top~1`).
    pub garment: String,
    /// The metric's value for the method asked for.
    pub value: f64,
}

/// Reads `method`'s `metric` for every sequence of an `evaluate --json` file.
pub fn read(path: &Path, method: &str, metric: &str) -> Result<Vec<Scored>> {
    let text = std::fs::read_to_string(path).map_err(|e| file_error(path, e))?;
    let document: Value = serde_json::from_str(&text).map_err(|e| file_error(path, e))?;
    let sequences = document
        .get("sequences")
        .and_then(Value::as_array)
        .ok_or_else(|| file_error(path, "no `sequences` list: not an `evaluate --json` file"))?;
    let text_of = |s: &Value, key: &str| s.get(key).and_then(Value::as_str).map(str::to_string);
    sequences
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let id = text_of(s, "id")
                .ok_or_else(|| file_error(path, format!("sequence {k} has no `id`")))?;
            let methods = s.get("methods").and_then(Value::as_object);
            let value = methods
                .and_then(|m| m.get(method))
                .and_then(|m| m.get(metric))
                .and_then(Value::as_f64)
                .ok_or_else(|| {
                    let known: Vec<&str> = methods
                        .map(|m| m.keys().map(String::as_str).collect())
                        .unwrap_or_default();
                    file_error(
                        path,
                        format!(
                            "sequence {id}: no `{metric}` of method `{method}` (methods: {})",
                            known.join(", ")
                        ),
                    )
                })?;
            let unknown = || "-".to_string();
            Ok(Scored {
                recording: s
                    .get("settings")
                    .and_then(|t| t.get("sha256"))
                    .and_then(Value::as_str)
                    .map(str::to_string),
                split: text_of(s, "split").unwrap_or_else(unknown),
                family: text_of(s, "family").unwrap_or_else(unknown),
                motion: text_of(s, "motion").unwrap_or_else(unknown),
                garment: text_of(s, "garment").unwrap_or_else(unknown),
                id,
                value,
            })
        })
        .collect()
}

/// One group's paired comparison: B minus A over the group's sequences.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairedRow {
    /// `all`, or `split NAME`, `family NAME`, `motion NAME`, `garment NAME` (a motion file
    /// named without its folders, [`motions::short_label`]).
    pub group: String,
    /// Sequences in the group.
    pub sequences: usize,
    /// Mean of A.
    pub a: f64,
    /// Mean of B.
    pub b: f64,
    /// Mean of B - A per sequence.
    pub difference: f64,
    /// Standard deviation of the per-sequence differences (0 for one sequence).
    pub sd: f64,
    /// Standard error of the mean difference, sd / sqrt(n).
    pub standard_error: f64,
    /// Sequences where B is lower than A (lower is better for every error metric).
    pub b_lower: usize,
}

/// Pairs the two evaluations' sequences and compares them per group: the whole set, then each
/// split, family, motion and garment (a kind of group only where it has more than one value).
/// Refused when the two did not score the same sequences, or scored a sequence's recording
/// with other bytes (another synthesis of the data).
pub fn compare(a: &[Scored], b: &[Scored]) -> Result<Vec<PairedRow>> {
    let by_id: BTreeMap<&str, &Scored> = b.iter().map(|s| (s.id.as_str(), s)).collect();
    let missing: Vec<&str> = a
        .iter()
        .map(|s| s.id.as_str())
        .filter(|id| !by_id.contains_key(id))
        .collect();
    if !missing.is_empty() || a.len() != b.len() {
        return Err(bad_value(
            "sequences",
            format!("{} in A, {} in B", a.len(), b.len()),
            &format!(
                "the same sequences in both evaluations (only in A: {})",
                if missing.is_empty() {
                    "none; B has others".to_string()
                } else {
                    missing.join(", ")
                }
            ),
        ));
    }
    let mut pairs = Vec::with_capacity(a.len());
    for x in a {
        let y = by_id[x.id.as_str()];
        if let (Some(p), Some(q)) = (&x.recording, &y.recording)
            && p != q
        {
            return Err(bad_value(
                "recording",
                &x.id,
                "the same recording in both evaluations (its SHA-256 differs: the data was \
                 synthesized again with other bytes)",
            ));
        }
        pairs.push((x, y.value));
    }
    let mut groups: Vec<(String, Vec<(f64, f64)>)> = vec![(
        "all".into(),
        pairs.iter().map(|(x, v)| (x.value, *v)).collect(),
    )];
    let kinds: [(&str, GroupKey); 4] = [
        ("split", |s| &s.split),
        ("family", |s| &s.family),
        ("motion", |s| motions::short_label(&s.motion)),
        ("garment", |s| &s.garment),
    ];
    for (kind, key) in kinds {
        let mut members: BTreeMap<&str, Vec<(f64, f64)>> = BTreeMap::new();
        for (x, v) in &pairs {
            members.entry(key(x)).or_default().push((x.value, *v));
        }
        if members.len() > 1 {
            groups.extend(
                members
                    .into_iter()
                    .map(|(name, values)| (format!("{kind} {name}"), values)),
            );
        }
    }
    Ok(groups
        .into_iter()
        .map(|(group, values)| row(group, &values))
        .collect())
}

/// Which group of a kind a sequence belongs to (its split, family, motion or garment).
type GroupKey = fn(&Scored) -> &str;

fn row(group: String, values: &[(f64, f64)]) -> PairedRow {
    let n = values.len() as f64;
    let mean = |f: &dyn Fn(&(f64, f64)) -> f64| values.iter().map(f).sum::<f64>() / n;
    let difference = mean(&|(a, b)| b - a);
    let sd = if values.len() > 1 {
        let squares: f64 = values
            .iter()
            .map(|(a, b)| (b - a - difference).powi(2))
            .sum();
        (squares / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    PairedRow {
        group,
        sequences: values.len(),
        a: mean(&|(a, _)| *a),
        b: mean(&|(_, b)| *b),
        difference,
        sd,
        standard_error: sd / n.sqrt(),
        b_lower: values.iter().filter(|(a, b)| b < a).count(),
    }
}

/// The rows as a Markdown table.
pub fn text_table(rows: &[PairedRow]) -> String {
    let mut out = String::from(
        "| group (sequences) | A | B | B - A | s.e. | B lower in |\n|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out.push_str(&format!(
            "| {} ({}) | {:.3} | {:.3} | {:+.3} | {:.3} | {} of {} |\n",
            r.group, r.sequences, r.a, r.b, r.difference, r.standard_error, r.b_lower, r.sequences
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scored(id: &str, family: &str, motion: &str, value: f64) -> Scored {
        Scored {
            id: id.into(),
            recording: Some(format!("sha-{id}")),
            split: "test_grid".into(),
            family: family.into(),
            motion: motion.into(),
            garment: format!("{family}-design"),
            value,
        }
    }

    #[test]
    fn differences_are_paired_per_sequence_and_grouped() {
        let a = vec![
            scored("s1", "dress", "kick", 5.0),
            scored("s2", "dress", "/clips/sway.bvh:start=1", 3.0),
            scored("s3", "top", "kick", 2.0),
        ];
        // B in another order: pairing is by id.
        let b = vec![
            scored("s3", "top", "kick", 2.5),
            scored("s1", "dress", "kick", 4.0),
            scored("s2", "dress", "/clips/sway.bvh:start=1", 2.0),
        ];
        let rows = compare(&a, &b).unwrap();
        let all = &rows[0];
        assert_eq!(
            (all.group.as_str(), all.sequences, all.b_lower),
            ("all", 3, 2)
        );
        assert!((all.a - 10.0 / 3.0).abs() < 1e-12 && (all.b - 8.5 / 3.0).abs() < 1e-12);
        // Differences -1, -1, +0.5: mean -0.5, sd sqrt(0.75), se 0.5.
        assert!((all.difference + 0.5).abs() < 1e-12);
        assert!((all.sd - 0.75f64.sqrt()).abs() < 1e-12);
        assert!((all.standard_error - 0.5).abs() < 1e-12);
        let names: Vec<&str> = rows.iter().map(|r| r.group.as_str()).collect();
        // One split: no split rows; two families, two motions (a file named without its
        // folders), two garments.
        assert_eq!(
            names,
            [
                "all",
                "family dress",
                "family top",
                "motion kick",
                "motion sway.bvh:start=1",
                "garment dress-design",
                "garment top-design"
            ]
        );
        let dress = &rows[1];
        assert_eq!((dress.sequences, dress.b_lower), (2, 2));
        assert!((dress.difference + 1.0).abs() < 1e-12 && dress.sd == 0.0);
        let top = &rows[2];
        assert!((top.difference - 0.5).abs() < 1e-12 && top.standard_error == 0.0);
        assert!(
            text_table(&rows).contains("| all (3) | 3.333 | 2.833 | -0.500 | 0.500 | 2 of 3 |")
        );
    }

    #[test]
    fn other_sequences_or_other_recordings_are_refused() {
        let a = vec![
            scored("s1", "dress", "kick", 5.0),
            scored("s2", "dress", "kick", 5.0),
        ];
        let mut b = vec![
            scored("s1", "dress", "kick", 4.0),
            scored("s9", "dress", "kick", 4.0),
        ];
        let e = compare(&a, &b).unwrap_err().to_string();
        assert!(e.contains("only in A: s2"), "{e}");
        b[1] = scored("s2", "dress", "kick", 4.0);
        b[1].recording = Some("another".into());
        let e = compare(&a, &b).unwrap_err().to_string();
        assert!(e.contains("s2") && e.contains("SHA-256 differs"), "{e}");
        b[1].recording = None;
        assert!(
            compare(&a, &b).is_ok(),
            "a file without hashes is paired by id"
        );
    }

    #[test]
    fn an_evaluation_file_is_read_and_its_faults_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("eval.json");
        let document = serde_json::json!({"sequences": [
            {"id": "s1", "split": "test_grid", "family": "dress_or_skirt", "motion": "kick",
             "garment": "dress_loose_maxi", "settings": {"sha256": "abc"},
             "methods": {"model": {"E_v": 4.5}, "lbs": {"E_v": 7.0}}}
        ]});
        std::fs::write(&path, document.to_string()).unwrap();
        let read_back = read(&path, "model", "E_v").unwrap();
        assert_eq!(read_back.len(), 1);
        assert_eq!(read_back[0].value, 4.5);
        assert_eq!(read_back[0].recording.as_deref(), Some("abc"));
        assert_eq!(read(&path, "lbs", "E_v").unwrap()[0].value, 7.0);
        let e = read(&path, "floor", "E_v").unwrap_err().to_string();
        assert!(
            e.contains("eval.json") && e.contains("methods: lbs, model"),
            "{e}"
        );
        std::fs::write(&path, "{\"splits\": {}}").unwrap();
        let e = read(&path, "model", "E_v").unwrap_err().to_string();
        assert!(
            e.contains("eval.json") && e.contains("no `sequences`"),
            "{e}"
        );
        std::fs::write(&path, "{not json").unwrap();
        assert!(
            read(&path, "model", "E_v")
                .unwrap_err()
                .to_string()
                .contains("eval.json")
        );
    }
}
