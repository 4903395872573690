//! The text forms of flag values: `K=V` pairs, `X,Y,Z` vectors, `T.K=V` technique
//! parameters, and a technique made with its parameters (which it checks itself).

use crate::failure::{bad_input, InputContext};
use anyhow::Result;
use shadowlab::math::{vec3, Vec3};
use shadowlab::techniques::{self, ShadowTechnique};
use std::collections::BTreeMap;

/// Splits one `K=V` of `flag`.
pub fn parse_kv(s: &str, flag: &str) -> Result<(String, String)> {
    match s.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.trim().to_string())),
        _ => Err(bad_input(format!(
            "{flag} {s:?} is not of the form KEY=VALUE"
        ))),
    }
}

/// Parses repeated `K=V` flags.
pub fn parse_kvs(items: &[String], flag: &str) -> Result<BTreeMap<String, String>> {
    items.iter().map(|s| parse_kv(s, flag)).collect()
}

/// Parses `X,Y,Z`.
pub fn parse_vec3(s: &str, what: &str) -> Result<Vec3> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .input_context(|| format!("{what} {s:?} is not three comma-separated numbers"))?;
    if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
        return Err(bad_input(format!(
            "{what} {s:?} is not three finite comma-separated numbers"
        )));
    }
    Ok(vec3(v[0], v[1], v[2]))
}

/// `T.K=V` technique parameters of `compare`, grouped by technique.
pub fn parse_prefixed_params(items: &[String]) -> Result<BTreeMap<String, Vec<(String, String)>>> {
    let mut out: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    for s in items {
        let (k, v) = parse_kv(s, "--param")?;
        let Some((t, key)) = k.split_once('.') else {
            return Err(bad_input(format!(
                "--param {s:?} in compare must name its technique: TECHNIQUE.KEY=VALUE, e.g. sm.resolution=4096"
            )));
        };
        out.entry(t.to_string())
            .or_default()
            .push((key.to_string(), v));
    }
    Ok(out)
}

/// Makes a technique with `params` applied.
pub fn make_technique(name: &str, params: &[(String, String)]) -> Result<Box<dyn ShadowTechnique>> {
    let mut t = techniques::create(name)?;
    for (k, v) in params {
        t.set_param(k, v)?;
    }
    Ok(t)
}
