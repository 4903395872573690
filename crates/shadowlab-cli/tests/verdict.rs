//! What a verdict rests on: identical runs give identical bytes at any thread count, each
//! verdict names its reference, progressive techniques run to convergence on a still
//! view, and the automatic light puts shadows where the camera sees them.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_shadowlab"));
    c.arg("--quiet");
    c
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shadowlab/assets")).join(name)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("shadowlab-verdict-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(cmd: &mut Command) {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `metrics.json` without what measures the clock or the machine: times, and the thread
/// count the run was given.
fn without_timings(v: &Value) -> Value {
    match v {
        Value::Object(m) => Value::Object(
            m.iter()
                .filter(|(k, _)| !(k.ends_with("_ms") || *k == "threads"))
                .map(|(k, v)| (k.clone(), without_timings(v)))
                .collect(),
        ),
        Value::Array(a) => Value::Array(a.iter().map(without_timings).collect()),
        _ => v.clone(),
    }
}

/// Every file of a report folder with its bytes, but those that show timings:
/// `metrics.json` (compared without them), the HTML and the plots (error against time).
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                if p.file_name().and_then(|n| n.to_str()) != Some("plots") {
                    stack.push(p);
                }
            } else if !matches!(
                p.file_name().and_then(|n| n.to_str()),
                Some("metrics.json" | "index.html")
            ) {
                let rel = p.strip_prefix(dir).unwrap().display().to_string();
                out.push((rel, std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

fn metrics(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap()).unwrap()
}

#[test]
fn identical_runs_give_identical_bytes_at_one_and_two_threads() {
    let d = tmp("determinism");
    let bunny = data("bunny.obj");
    let mut reports = Vec::new();
    for (i, threads) in ["1", "1", "2", "2"].iter().enumerate() {
        let out = d.join(format!("compare-{i}"));
        run(bin()
            .args(["--threads", threads, "compare", "--scene"])
            .arg(&bunny)
            .args(["--techniques", "all", "--width", "160", "--height", "120"])
            .arg("--out")
            .arg(&out));
        reports.push(out);
    }
    let first_files = files(&reports[0]);
    assert!(first_files.iter().any(|(n, _)| n == "asm.png"));
    let first_metrics = without_timings(&metrics(&reports[0]));
    for r in &reports[1..] {
        let these = files(r);
        assert_eq!(
            first_files.iter().map(|f| &f.0).collect::<Vec<_>>(),
            these.iter().map(|f| &f.0).collect::<Vec<_>>()
        );
        for (a, b) in first_files.iter().zip(&these) {
            assert!(a.1 == b.1, "{} differs in {}", a.0, r.display());
        }
        assert_eq!(
            first_metrics,
            without_timings(&metrics(r)),
            "{}",
            r.display()
        );
    }
    for technique in ["asm", "csm", "afsm", "subpixel"] {
        let mut exrs = Vec::new();
        for (i, threads) in ["1", "1", "2", "2"].iter().enumerate() {
            let exr = d.join(format!("{technique}-{i}.exr"));
            run(bin()
                .args(["--threads", threads, "render", "--scene"])
                .arg(&bunny)
                .args([
                    "--technique",
                    technique,
                    "--width",
                    "160",
                    "--height",
                    "120",
                ])
                .arg("--output")
                .arg(d.join(format!("{technique}-{i}.png")))
                .arg("--visibility")
                .arg(&exr));
            exrs.push(std::fs::read(&exr).unwrap());
        }
        for e in &exrs[1..] {
            assert!(*e == exrs[0], "{technique}: the EXRs differ");
        }
    }
}

#[test]
fn each_verdict_names_its_reference_and_progressive_ones_their_frames() {
    let d = tmp("references");
    let out = d.join("report");
    run(bin()
        .arg("compare")
        .arg("--scene")
        .arg(data("bunny.obj"))
        .args(["--techniques", "sm,asm,pcf,csm"])
        .args(["--width", "160", "--height", "120"])
        .arg("--out")
        .arg(&out));
    let m = metrics(&out);
    let refs: Vec<u64> = m["references"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["samples_per_pixel"].as_u64().unwrap())
        .collect();
    assert_eq!(refs, [16, 1]);
    assert_eq!(m["reference"]["samples_per_pixel"], 16);
    assert!(out.join("reference-1spp.png").is_file());
    for r in m["results"].as_array().unwrap() {
        let t = r["technique"].as_str().unwrap();
        let want = if matches!(t, "pcf" | "csm") { 16 } else { 1 };
        assert_eq!(r["reference_spp"], want, "{t}");
        if t == "asm" {
            assert_eq!(r["converged"], true, "asm converges on a still bunny");
            let n = r["frames_run"].as_u64().unwrap();
            assert!((8..=64).contains(&n), "asm had {n} frames");
        } else {
            assert_eq!(r["frames_run"], 1, "{t}");
            assert!(r["converged"].is_null(), "{t}");
        }
    }
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("vs 16 spp") && html.contains("vs 1 spp"));
    assert!(html.contains("converged in"));

    // Asked for explicitly, one reference serves every verdict.
    let one = d.join("one");
    run(bin()
        .arg("compare")
        .arg("--scene")
        .arg(data("bunny.obj"))
        .args(["--techniques", "sm,pcf", "--reference-spp", "4"])
        .args(["--width", "96", "--height", "72"])
        .arg("--out")
        .arg(&one));
    let m = metrics(&one);
    assert_eq!(m["references"].as_array().unwrap().len(), 1);
    for r in m["results"].as_array().unwrap() {
        assert_eq!(r["reference_spp"], 4);
    }
}

#[test]
fn the_automatic_light_shadows_what_the_camera_sees_and_is_printed() {
    let d = tmp("light");
    for mesh in ["fence/fence.obj", "bunny.obj", "bike/bike.obj"] {
        let out = d.join(mesh.replace('/', "-"));
        let o = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
            .arg("compare")
            .arg("--scene")
            .arg(data(mesh))
            .args(["--techniques", "sm", "--width", "160", "--height", "120"])
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let m = metrics(&out);
        let d = &m["light"]["to_light"];
        let printed = format!(
            "automatic light: directional:{:.4},{:.4},{:.4}",
            d[0].as_f64().unwrap(),
            d[1].as_f64().unwrap(),
            d[2].as_f64().unwrap()
        );
        let said = String::from_utf8_lossy(&o.stdout);
        assert!(
            said.contains(&printed),
            "{mesh}: {said:?} lacks {printed:?}"
        );
        let shadowed = m["reference"]["shadowed_share"].as_f64().unwrap();
        assert!(
            shadowed >= 0.05,
            "{mesh}: {shadowed} of the covered pixels in shadow"
        );
    }
}
