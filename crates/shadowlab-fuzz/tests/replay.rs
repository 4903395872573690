//! Replays the kept fuzz corpus and every crash case found so far through the harnesses,
//! so a fixed bug stays fixed. Fast: each input runs once.

use shadowlab_fuzz::{load, pipeline, Format};
use std::path::PathBuf;

fn inputs(target: &str) -> Vec<PathBuf> {
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fuzz"));
    let mut out = Vec::new();
    for dir in [
        root.join("corpus").join(target),
        root.join("artifacts").join(target),
        root.join("regressions").join(target),
    ] {
        if let Ok(rd) = std::fs::read_dir(&dir) {
            for e in rd.flatten() {
                if e.path().is_file() {
                    out.push(e.path());
                }
            }
        }
    }
    out.sort();
    out
}

fn replay(target: &str, f: impl Fn(&[u8])) {
    let files = inputs(target);
    assert!(!files.is_empty(), "no corpus kept for {target}");
    for p in &files {
        let data = std::fs::read(p).unwrap();
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(&data)));
        assert!(r.is_ok(), "{target}: {} panics", p.display());
    }
    println!("{target}: replayed {} inputs", files.len());
}

#[test]
fn obj_corpus() {
    replay("obj", |d| load(Format::Obj, d));
}

#[test]
fn ply_corpus() {
    replay("ply", |d| load(Format::Ply, d));
}

#[test]
fn gltf_corpus() {
    replay("gltf", |d| load(Format::Gltf, d));
}

#[test]
fn toml_corpus() {
    replay("toml", |d| load(Format::Toml, d));
}

#[test]
fn pipeline_corpus() {
    replay("pipeline", pipeline);
}
