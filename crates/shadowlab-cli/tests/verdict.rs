//! What a verdict rests on: identical runs give identical bytes at any thread count, each
//! verdict names its reference, progressive techniques run to convergence on a still
//! view, and the automatic light puts shadows where the camera sees them.

mod support;

use serde_json::Value;
use std::path::{Path, PathBuf};
use support::{data, metrics, quiet as bin, run_ok as run, shadowlab, tmp};

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

/// Every file of a report folder, relative to it, but those that show timings:
/// `metrics.json` (compared without them), the HTML and the plots (error against time).
fn files(dir: &Path) -> Vec<String> {
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
                out.push(p.strip_prefix(dir).unwrap().display().to_string());
            }
        }
    }
    out.sort();
    out
}

/// Every report of `reports` holds the files of the first, `expected` among them, with
/// the same bytes, and the same `metrics.json` but for timings.
fn assert_same_reports(what: &str, reports: &[PathBuf], expected: &[&str]) {
    let first_files = files(&reports[0]);
    for f in expected {
        assert!(first_files.iter().any(|n| n == f), "no {f}");
    }
    let first_metrics = without_timings(&metrics(&reports[0]));
    for (i, r) in reports.iter().enumerate().skip(1) {
        assert_eq!(first_files, files(r));
        for f in &first_files {
            let what = format!("verdict-{what}-{i}-{f}");
            support::assert_same_files(&what, &reports[0].join(f), &r.join(f));
        }
        assert_eq!(
            first_metrics,
            without_timings(&metrics(r)),
            "{}",
            r.display()
        );
    }
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
    assert_same_reports("report", &reports, &["asm.png"]);
    for technique in ["asm", "csm", "afsm", "subpixel"] {
        let mut exrs: Vec<PathBuf> = Vec::new();
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
            exrs.push(exr);
        }
        for (i, e) in exrs.iter().enumerate().skip(1) {
            let what = format!("verdict-{technique}-exr-{i}");
            support::assert_same_files(&what, &exrs[0], e);
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
        let o = run(shadowlab()
            .arg("compare")
            .arg("--scene")
            .arg(data(mesh))
            .args(["--techniques", "sm", "--width", "160", "--height", "120"])
            .arg("--out")
            .arg(&out));
        let m = metrics(&out);
        let d = &m["light"]["to_light"];
        let printed = format!(
            "automatic light: directional:{:.4},{:.4},{:.4}",
            d[0].as_f64().unwrap(),
            d[1].as_f64().unwrap(),
            d[2].as_f64().unwrap()
        );
        let said = &o.stdout;
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

#[test]
fn a_sequence_gives_identical_bytes_at_one_and_two_threads_animations_included() {
    let d = tmp("sequence");
    let mut reports = Vec::new();
    for (i, threads) in ["1", "1", "2"].iter().enumerate() {
        let out = d.join(format!("sequence-{i}"));
        run(bin()
            .args(["--threads", threads, "compare", "--scene", "street"])
            .args(["--techniques", "sm,asm,pcf,afsm", "--frames", "3"])
            .args(["--width", "160", "--height", "120"])
            .arg("--out")
            .arg(&out));
        reports.push(out);
    }
    let expected = ["sm-walkthrough.gif", "asm.gif", "frames/pcf-0002.png"];
    assert_same_reports("sequence", &reports, &expected);
}
