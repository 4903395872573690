//! What `compare` will run, planned before anything is loaded: the runs that
//! `--techniques`, `--param` and `--sweep` ask for, each a technique with its parameters
//! and a label, and the ray-traced references their verdicts need.

use super::parse::{make_technique, parse_prefixed_params};
use crate::args::CompareArgs;
use crate::failure::bad_input;
use crate::output::slug;
use anyhow::Result;
use shadowlab::math::Vec2;
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::techniques::{self, ShadowTechnique};
use std::collections::BTreeMap;

/// The most values one `--sweep` may list.
pub const MAX_SWEEP_VALUES: usize = 64;

/// The most runs one `compare` may plan (techniques times sweep values): each keeps its
/// result for the report until the end.
pub use shadowlab::limits::MAX_RUNS;

/// Techniques whose shadow terms are filtered or anti-aliased (soft or fractional at
/// edges): by default `compare` judges them against a supersampled reference.
pub const FILTERED: &[&str] = &["pcf", "subpixel", "csm", "vsm", "evsm", "msm", "pcss"];

/// Samples per pixel of the default reference for [`FILTERED`] techniques: a 4×4 grid,
/// whose own error on an edge pixel is at most 1/32 of the pixel's area.
pub const FILTERED_REFERENCE_SPP: u32 = 16;

/// The reference samples per pixel that a technique's verdict uses.
pub fn reference_spp_for(technique: &str, asked: Option<u32>) -> u32 {
    // A `gpu:` technique is judged as its CPU twin.
    let technique = technique.strip_prefix("gpu:").unwrap_or(technique);
    match asked {
        Some(n) => n,
        None if FILTERED.contains(&technique) => FILTERED_REFERENCE_SPP,
        None => 1,
    }
}

/// One technique run to make: the technique with its parameters set, and its label
/// (`sm`, or `sm.resolution=512` for one value of a sweep).
pub struct RunPlan {
    /// The technique.
    pub technique: Box<dyn ShadowTechnique>,
    /// Its label in the report and the terminal table.
    pub label: String,
}

/// The ray-traced references the verdicts need.
pub struct ReferencePlan {
    /// Samples per pixel of each, the highest first.
    pub spps: Vec<u32>,
    /// The sub-pixel positions of each.
    pub samples: Vec<Vec<Vec2>>,
    /// The pattern's name as given (`--reference-pattern`).
    pub pattern: String,
    /// `--reference-spp`, when given: one count for every verdict.
    pub asked: Option<u32>,
}

impl ReferencePlan {
    /// The reference samples per pixel that `technique`'s verdict uses.
    pub fn spp_for(&self, technique: &str) -> u32 {
        reference_spp_for(technique, self.asked)
    }
}

/// The runs and references of `compare`, in the order their errors are reported.
pub fn plan(a: &CompareArgs) -> Result<(Vec<RunPlan>, ReferencePlan)> {
    let planned = plan_runs(a)?;
    let kind: PatternKind = a.reference_pattern.parse()?;
    let mut runs = Vec::new();
    for (name, swept, params) in &planned {
        let technique = make_technique(name, params)?;
        let label = match swept {
            None => name.clone(),
            Some((k, v)) => format!("{name}.{k}={}", swept_value(technique.as_ref(), k, v)),
        };
        runs.push(RunPlan { technique, label });
    }
    let mut files = BTreeMap::new();
    for RunPlan { label, .. } in &runs {
        if let Some(other) = files.insert(slug(label), label) {
            return Err(bad_input(format!(
                "runs {other} and {label} would write the same report files; give them distinct values"
            )));
        }
    }
    let references = plan_references(&runs, a, kind)?;
    Ok((runs, references))
}

/// One planned run before its technique is made: technique name, the key and value
/// text of its `--sweep` (if it is one value of a sweep), parameters.
type Planned = (String, Option<(String, String)>, Vec<(String, String)>);

/// A swept value as the run's label shows it: a number as the technique holds it, in
/// the shortest form every table prints (`0.1` for `0.10`, `512` for `0512`); a word as
/// written (`auto`, `none`).
fn swept_value(t: &dyn ShadowTechnique, key: &str, text: &str) -> String {
    match t.params().get(key) {
        Some(v) if v.is_number() && text.trim().parse::<f64>().is_ok() => techniques::param_text(v),
        _ => text.to_string(),
    }
}

/// The technique names of `--techniques`.
fn technique_names(a: &CompareArgs) -> Result<Vec<String>> {
    let names = techniques::expand_names(&[&a.techniques]);
    if names.is_empty() {
        return Err(bad_input(format!(
            "--techniques {:?} names no technique",
            a.techniques
        )));
    }
    Ok(names)
}

/// The `--sweep` flags: technique, key and values of each.
fn parse_sweeps(a: &CompareArgs) -> Result<Vec<(String, String, Vec<String>)>> {
    let mut sweeps = Vec::new();
    for s in &a.sweeps {
        let Some((tk, vals)) = s.split_once('=') else {
            return Err(bad_input(format!(
                "--sweep {s:?} is not TECHNIQUE.KEY=V1,V2,..."
            )));
        };
        let Some((t, k)) = tk.split_once('.') else {
            return Err(bad_input(format!(
                "--sweep {s:?} must name its technique: TECHNIQUE.KEY=V1,V2,..."
            )));
        };
        let vals: Vec<String> = vals
            .split(',')
            .map(|v| v.trim().to_string())
            .filter(|v| !v.is_empty())
            .collect();
        if vals.is_empty() {
            return Err(bad_input(format!("--sweep {s:?} lists no values")));
        }
        if vals.len() > MAX_SWEEP_VALUES {
            return Err(bad_input(format!(
                "--sweep {tk} lists {} values, more than the limit of {MAX_SWEEP_VALUES}",
                vals.len()
            )));
        }
        sweeps.push((t.trim().to_string(), k.trim().to_string(), vals));
    }
    Ok(sweeps)
}

/// Expands `--techniques` and `--sweep` into labelled runs with their parameters.
fn plan_runs(a: &CompareArgs) -> Result<Vec<Planned>> {
    let names = technique_names(a)?;
    let params = parse_prefixed_params(&a.params)?;
    for t in params.keys() {
        if !names.contains(t) {
            return Err(bad_input(format!(
                "--param names technique {t}, which is not among --techniques {}",
                names.join(",")
            )));
        }
    }
    let sweeps = parse_sweeps(a)?;
    let mut runs = Vec::new();
    for n in &names {
        let base = params.get(n).cloned().unwrap_or_default();
        let mine: Vec<_> = sweeps.iter().filter(|s| &s.0 == n).collect();
        if mine.is_empty() {
            runs.push((n.clone(), None, base));
            continue;
        }
        for (_, k, vals) in mine {
            for v in vals {
                let mut p = base.clone();
                p.push((k.clone(), v.clone()));
                runs.push((n.clone(), Some((k.clone(), v.clone())), p));
            }
        }
    }
    for (t, _, _) in &sweeps {
        if !names.contains(t) {
            return Err(bad_input(format!(
                "--sweep names technique {t}, which is not among --techniques {}",
                names.join(",")
            )));
        }
    }
    if runs.len() > MAX_RUNS {
        return Err(bad_input(format!(
            "--techniques and --sweep plan {} runs, more than the limit of {MAX_RUNS}",
            runs.len()
        )));
    }
    Ok(runs)
}

/// The reference sample counts the verdicts of `runs` ask for, the highest first, with
/// their sub-pixel patterns; a note on stderr when `--reference-spp 1` judges a filtering
/// technique.
fn plan_references(runs: &[RunPlan], a: &CompareArgs, kind: PatternKind) -> Result<ReferencePlan> {
    let mut spps: Vec<u32> = runs
        .iter()
        .map(|r| reference_spp_for(r.technique.name(), a.reference_spp))
        .collect();
    spps.sort_unstable_by(|x, y| y.cmp(x));
    spps.dedup();
    let samples = spps
        .iter()
        .map(|&n| pattern(kind, n))
        .collect::<shadowlab::error::Result<Vec<_>>>()?;
    if a.reference_spp == Some(1) && !crate::progress::quiet() {
        let filtered = runs
            .iter()
            .map(|r| r.technique.name())
            .find(|t| FILTERED.contains(t));
        if let Some(t) = filtered {
            eprintln!(
                "note: {t} filters or anti-aliases its shadows, and --reference-spp 1 judges it against one sample per pixel; \
                 the default ({FILTERED_REFERENCE_SPP} samples) judges soft and sub-pixel edges fairly"
            );
        }
    }
    Ok(ReferencePlan {
        spps,
        samples,
        pattern: a.reference_pattern.clone(),
        asked: a.reference_spp,
    })
}
