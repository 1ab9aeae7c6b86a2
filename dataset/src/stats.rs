//! What `dataset stats` reports: counts per split, garment, motion and failed gate, material
//! histograms, frames, hours and the simulation's speed, over a dataset's manifest records.

use std::collections::BTreeMap;
use std::fmt;

use serde::Serialize;

use super::{ManifestRecord, Split};

/// Ten equal bins over the values' range (of log10 of the values when `log10`).
#[derive(Debug, Clone, Serialize)]
pub struct Histogram {
    /// Smallest value (infinite, written null, when there are none).
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Whether the bins are over log10 of the values.
    pub log10: bool,
    /// Values per bin.
    pub counts: Vec<usize>,
}

impl Histogram {
    fn of(values: impl Iterator<Item = f64>, log10: bool) -> Self {
        let values: Vec<f64> = values
            .map(|v| if log10 { v.log10() } else { v })
            .filter(|v| v.is_finite())
            .collect();
        let min = values.iter().copied().fold(f64::INFINITY, f64::min);
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let bins = 10;
        let mut counts = vec![0usize; bins];
        if max > min {
            for v in &values {
                counts[(((v - min) / (max - min) * bins as f64) as usize).min(bins - 1)] += 1;
            }
        } else if !values.is_empty() {
            counts[0] = values.len();
        }
        Self {
            min,
            max,
            log10,
            counts,
        }
    }
}

/// Counts, histograms and totals over manifest records.
#[derive(Debug, Clone, Serialize)]
pub struct Stats {
    /// Sequences in the manifest.
    pub sequences: usize,
    /// Sequences that failed their gates.
    pub failed: usize,
    /// Sequences that needed a retry.
    pub retried: usize,
    /// Frames of every sequence.
    pub frames: usize,
    /// Frames of the sequences that passed.
    pub frames_ok: usize,
    /// `frames` in hours of motion.
    pub hours: f64,
    /// Sequences per split (every split listed).
    pub splits: BTreeMap<String, usize>,
    /// Sequences per garment.
    pub garments: BTreeMap<String, usize>,
    /// Sequences per motion.
    pub motions: BTreeMap<String, usize>,
    /// Failed sequences per gate.
    pub failures: BTreeMap<String, usize>,
    /// `k_s_n_per_m`, `rho_kg_per_m2` and `k_b_n_m` (log10).
    pub material_histograms: BTreeMap<&'static str, Histogram>,
    /// Wall time of every simulation, s.
    pub simulation_wall_s: f64,
    /// Frames over that time.
    pub simulated_frames_per_s: f64,
}

/// The [`Stats`] of `records` at `fps` frames per second.
pub fn stats(records: &[ManifestRecord], fps: f64) -> Stats {
    let mut splits: BTreeMap<String, usize> = Split::ALL
        .iter()
        .map(|s| (s.name().to_string(), 0))
        .collect();
    let (mut garments, mut motions, mut failures) =
        (BTreeMap::new(), BTreeMap::new(), BTreeMap::new());
    let (mut frames, mut frames_ok) = (0, 0);
    for r in records {
        *splits
            .entry(r.sequence.split.name().to_string())
            .or_default() += 1;
        *garments.entry(r.sequence.garment.clone()).or_default() += 1;
        *motions.entry(r.sequence.motion.clone()).or_default() += 1;
        frames += r.frames;
        if r.ok() {
            frames_ok += r.frames;
        } else {
            let reason = r.reason.clone().unwrap_or_else(|| "unknown".into());
            // Group by the gate, not its measured value.
            let gate = reason
                .split(|c: char| c.is_ascii_digit())
                .next()
                .unwrap_or("")
                .trim()
                .to_string();
            *failures
                .entry(if gate.is_empty() { reason } else { gate })
                .or_default() += 1;
        }
    }
    let material = |f: fn(&ManifestRecord) -> f64| records.iter().map(f);
    let material_histograms = BTreeMap::from([
        (
            "k_s_n_per_m",
            Histogram::of(material(|r| r.sequence.material.stretch), false),
        ),
        (
            "rho_kg_per_m2",
            Histogram::of(material(|r| r.sequence.material.density), false),
        ),
        (
            "k_b_n_m",
            Histogram::of(material(|r| r.sequence.material.bending), true),
        ),
    ]);
    let wall: f64 = records.iter().map(|r| r.wall_s).sum();
    Stats {
        sequences: records.len(),
        failed: records.iter().filter(|r| !r.ok()).count(),
        retried: records.iter().filter(|r| r.attempts.len() > 1).count(),
        frames,
        frames_ok,
        hours: frames as f64 / fps / 3600.0,
        splits,
        garments,
        motions,
        failures,
        material_histograms,
        simulation_wall_s: wall,
        simulated_frames_per_s: if wall > 0.0 {
            frames as f64 / wall
        } else {
            0.0
        },
    }
}

/// The report as `dataset stats` prints it, after its first line.
impl fmt::Display for Stats {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let counts = [
            ("splits", &self.splits),
            ("garments", &self.garments),
            ("motions", &self.motions),
            ("failures", &self.failures),
        ];
        for (key, map) in counts {
            let row: Vec<String> = map.iter().map(|(k, v)| format!("{k} {v}")).collect();
            let row = if row.is_empty() {
                "-".into()
            } else {
                row.join(", ")
            };
            writeln!(f, "  {key:<9} {row}")?;
        }
        for (name, h) in &self.material_histograms {
            let counts: Vec<String> = h.counts.iter().map(|c| c.to_string()).collect();
            let log = if h.log10 { " (log10)" } else { "" };
            let (min, max) = (h.min, h.max);
            writeln!(
                f,
                "  {name:<14} {min:>10.4} .. {max:<10.4} {}{log}",
                counts.join(" ")
            )?;
        }
        writeln!(
            f,
            "  simulation: {:.0} s of wall time in all, {:.1} frames/s per sequence worker",
            self.simulation_wall_s, self.simulated_frames_per_s
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn histograms_bin_over_the_range_and_skip_what_log10_cannot_take() {
        let h = Histogram::of([1.0, 10.0, 100.0, 0.0].into_iter(), true);
        assert_eq!((h.min, h.max), (0.0, 2.0));
        assert_eq!(h.counts.iter().sum::<usize>(), 3, "log10(0) is left out");
        assert_eq!((h.counts[0], h.counts[5], h.counts[9]), (1, 1, 1));
        let one = Histogram::of([3.0, 3.0].into_iter(), false);
        assert_eq!(one.counts[0], 2);
        let none = Histogram::of(std::iter::empty(), false);
        assert!(none.min.is_infinite() && none.counts.iter().all(|&c| c == 0));
        let text = stats(&[], 30.0).to_string();
        assert!(
            text.contains("splits    test 0,") && text.contains("train 0"),
            "{text}"
        );
    }
}
