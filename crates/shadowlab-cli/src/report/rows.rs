//! What the report reads off the metrics beyond single fields: the reference sample
//! counts the verdicts used, and which runs are values of one `--sweep`.

use crate::metrics::{Metrics, RunResult};

/// The reference sample counts of a report: "16 samples or 1 sample (…)" when the
/// verdicts used more than one reference.
pub fn reference_samples(metrics: &Metrics) -> String {
    let counts: Vec<u32> = if metrics.references.is_empty() {
        vec![metrics.reference.samples_per_pixel]
    } else {
        metrics
            .references
            .iter()
            .map(|r| r.samples_per_pixel)
            .collect()
    };
    let each: Vec<String> = counts
        .iter()
        .map(|&n| format!("{n} sample{}", if n == 1 { "" } else { "s" }))
        .collect();
    if each.len() > 1 {
        format!(
            "{} (each technique's row says which its verdict used)",
            each.join(" or ")
        )
    } else {
        each.join("")
    }
}

/// The swept parameter and its value, when `r` is one value of a `--sweep`: as recorded,
/// else read off its label (`sm.resolution=512`).
pub fn sweep_of(r: &RunResult) -> Option<(String, String)> {
    if let Some(s) = &r.sweep {
        return Some((s.key.clone(), s.value.clone()));
    }
    let rest = r.label.strip_prefix(&r.technique)?.strip_prefix('.')?;
    let (k, v) = rest.split_once('=')?;
    Some((k.to_string(), v.to_string()))
}

/// One swept (technique, parameter) and its runs, values in the order given.
pub struct SweepGroup<'m> {
    /// The technique.
    pub technique: String,
    /// The swept parameter.
    pub key: String,
    /// Each value with its run.
    pub runs: Vec<(String, &'m RunResult)>,
}

/// The runs grouped by swept (technique, parameter), in the order they first appear.
pub fn sweeps(results: &[RunResult]) -> Vec<SweepGroup<'_>> {
    let mut groups: Vec<SweepGroup> = Vec::new();
    for r in results {
        if let Some((k, v)) = sweep_of(r) {
            match groups
                .iter_mut()
                .find(|g| g.technique == r.technique && g.key == k)
            {
                Some(g) => g.runs.push((v, r)),
                None => groups.push(SweepGroup {
                    technique: r.technique.clone(),
                    key: k,
                    runs: vec![(v, r)],
                }),
            }
        }
    }
    groups
}
