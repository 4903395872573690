//! `shadowlab scenes`: the built-in scenes, one line each — name, triangles, description.

use anyhow::Result;

/// Runs `scenes`.
pub fn run() -> Result<()> {
    for (name, desc) in shadowlab::scene::builtin::list() {
        let n = shadowlab::scene::builtin::generate(name, &Default::default())
            .map(|s| s.len().to_string())
            .unwrap_or_else(|e| format!("({e})"));
        println!("{name:<18} {n:>10}  {desc}");
    }
    Ok(())
}
