//! `shadowlab techniques [NAME]`: every technique (or the one named) with its parameters —
//! key, default, range and one line of meaning — read from the technique itself, so the
//! listing is what `--param` is checked against.
//!
//! The flow: make each technique with its defaults, read its parameters
//! ([`parameters`]), print them as a table.

use crate::config::TechniquesConfig;
use anyhow::Result;
use shadowlab::techniques::{self, ShadowTechnique};

/// Runs `techniques`.
pub fn run(cfg: TechniquesConfig) -> Result<()> {
    for (i, name) in cfg.names.iter().enumerate() {
        let t = techniques::create(name)?;
        if i > 0 {
            println!();
        }
        print_technique(t.as_ref());
    }
    Ok(())
}

/// One parameter as the listing shows it.
struct Parameter {
    key: String,
    default: String,
    range: String,
    meaning: String,
}

/// What the technique says of its parameters: every key `params()` lists with its
/// default, and the range and meaning of its parameter table (`param_specs()`, the table
/// `set_param` validates against; every technique's table names exactly its `params()`
/// keys, and "-" shows a key it would lack).
fn parameters(t: &dyn ShadowTechnique) -> Vec<Parameter> {
    let specs = t.param_specs();
    t.params()
        .into_iter()
        .map(|(key, default)| {
            let spec = specs.iter().find(|s| s.key == key);
            Parameter {
                default: techniques::param_text(&default),
                range: spec.map_or("-".to_string(), |s| s.range.to_string()),
                meaning: spec.map_or("-".to_string(), |s| s.meaning.to_string()),
                key,
            }
        })
        .collect()
}

/// The technique's name, then a table of its parameters with a header line.
fn print_technique(t: &dyn ShadowTechnique) {
    println!("{}", t.name());
    let params = parameters(t);
    if params.is_empty() {
        println!("  (no parameters)");
        return;
    }
    let width = |f: &dyn Fn(&Parameter) -> usize, head: &str| {
        params.iter().map(f).chain([head.len()]).max().unwrap_or(0)
    };
    let wk = width(&|p| p.key.len(), "key");
    let wd = width(&|p| p.default.len(), "default");
    let wr = width(&|p| p.range.len(), "range");
    println!(
        "  {:<wk$}  {:<wd$}  {:<wr$}  meaning",
        "key", "default", "range"
    );
    for p in &params {
        println!(
            "  {:<wk$}  {:<wd$}  {:<wr$}  {}",
            p.key, p.default, p.range, p.meaning
        );
    }
}
