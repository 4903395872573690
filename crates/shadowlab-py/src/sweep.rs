//! `Scene.compare`'s runs: the techniques, each with its parameters and, for a swept one,
//! one run per value of the sweep, labelled as the command line's `--sweep` labels them.

use crate::compare::RunSpec;
use crate::convert::bad;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::BTreeMap;

/// The most values one sweep may list (as `--sweep`).
const MAX_SWEEP_VALUES: usize = 64;

/// The most runs one comparison may plan (as `compare`).
const MAX_RUNS: usize = 128;

/// The most frames one comparison may render (as `--frames`).
pub(crate) const MAX_FRAMES: usize = 100_000;

/// One sweep: technique, key and values.
pub(crate) type Sweep = (String, String, Vec<String>);

/// The sweeps of a `{"technique.key": [values]}` mapping (values as `str()` gives them),
/// each naming one of `names`.
pub(crate) fn sweeps_of(d: Option<&Bound<'_, PyDict>>, names: &[String]) -> PyResult<Vec<Sweep>> {
    let mut out = Vec::new();
    let Some(d) = d else {
        return Ok(out);
    };
    for (k, v) in d.iter() {
        let tk = k.str()?.to_string();
        let Some((t, key)) = tk.split_once('.') else {
            return Err(bad(format!(
                "sweep {tk:?} must name its technique: \"technique.key\""
            )));
        };
        if !names.iter().any(|n| n == t) {
            return Err(bad(format!(
                "sweep {tk} names technique {t}, which is not among techniques {}",
                names.join(",")
            )));
        }
        if v.is_instance_of::<pyo3::types::PyString>() {
            return Err(bad(format!("sweep {tk} must be a list of values")));
        }
        let mut vals = Vec::new();
        let iter = v
            .try_iter()
            .map_err(|_| bad(format!("sweep {tk} must be a list of values")))?;
        for item in iter {
            if vals.len() == MAX_SWEEP_VALUES {
                return Err(bad(format!(
                    "sweep {tk} lists more values than the limit of {MAX_SWEEP_VALUES}"
                )));
            }
            vals.push(item?.str()?.to_string());
        }
        if vals.is_empty() {
            return Err(bad(format!("sweep {tk} lists no values")));
        }
        out.push((t.to_string(), key.to_string(), vals));
    }
    Ok(out)
}

/// Expands the techniques and sweeps into labelled runs, in the command line's order:
/// each technique in turn, a swept one once per value of each of its sweeps.
pub(crate) fn plan_runs(
    names: &[String],
    params: &BTreeMap<String, Vec<(String, String)>>,
    sweeps: &[Sweep],
) -> PyResult<Vec<RunSpec>> {
    let mut runs = Vec::new();
    for n in names {
        let base = params.get(n).cloned().unwrap_or_default();
        let mine: Vec<_> = sweeps.iter().filter(|s| &s.0 == n).collect();
        if mine.is_empty() {
            runs.push(RunSpec {
                name: n.clone(),
                label: n.clone(),
                params: base.clone(),
                sweep: None,
            });
        }
        for (_, k, vals) in mine {
            for v in vals {
                let mut p = base.clone();
                p.push((k.clone(), v.clone()));
                runs.push(RunSpec {
                    name: n.clone(),
                    label: format!("{n}.{k}={v}"),
                    params: p,
                    sweep: Some((k.clone(), v.clone())),
                });
            }
        }
        if runs.len() > MAX_RUNS {
            return Err(bad(format!(
                "techniques and sweeps plan more runs than the limit of {MAX_RUNS}"
            )));
        }
    }
    Ok(runs)
}
