//! The command line as scripts use it: exit codes, one-sentence errors, outputs.

mod support;

use std::path::Path;
use support::{data, quiet as bin, refused, tmp, Capture, Ran};

/// The `metrics.json` of the report `compare` wrote into `dir`, after checking it succeeded.
fn report_metrics(out: &Ran, dir: &Path) -> serde_json::Value {
    support::ok(out);
    support::metrics(dir)
}

fn render(dir: &Path, args: &[&str]) -> Ran {
    bin()
        .arg("render")
        .args(args)
        .arg("--output")
        .arg(dir.join("out.png"))
        .ran()
}

/// Bad input: exit code 2, one line on stderr that starts with `error:` and mentions
/// `needle`, and no panic.
fn assert_bad_input(out: &Ran, needle: &str) {
    refused(out, &[needle]);
}

#[test]
fn bad_flags_and_parameters_exit_with_2_and_one_sentence() {
    let d = tmp("flags");
    let bunny = data("bunny.obj");
    let b = bunny.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--scene", b, "--technique", "nope"], "unknown technique"),
        (
            &["--scene", b, "--technique", "sm", "--param", "colour=3"],
            "resolution",
        ),
        (
            &["--scene", b, "--technique", "sm", "--param", "resolution=0"],
            "resolution",
        ),
        (
            &[
                "--scene",
                b,
                "--technique",
                "sm",
                "--param",
                "resolution=1000000",
            ],
            "resolution",
        ),
        (
            &[
                "--scene",
                b,
                "--technique",
                "sm",
                "--param",
                "resolution=abc",
            ],
            "resolution",
        ),
        (
            &["--scene", b, "--technique", "sm", "--width", "0"],
            "width",
        ),
        (
            &["--scene", b, "--technique", "sm", "--width", "100000"],
            "limit",
        ),
        (
            &[
                "--scene",
                b,
                "--technique",
                "sm",
                "--light",
                "sideways:1,2,3",
            ],
            "--light",
        ),
        (
            &[
                "--scene",
                b,
                "--technique",
                "sm",
                "--light",
                "directional:0,0,0",
            ],
            "direction",
        ),
        (
            &["--scene", b, "--technique", "sm", "--camera", "1,2:3"],
            "--camera",
        ),
        (
            &["--scene", b, "--technique", "sm", "--camera-distance", "-1"],
            "--camera-distance",
        ),
        (
            &["--scene", b, "--technique", "sm", "--frames", "0"],
            "--frames",
        ),
        (
            &["--scene", "/nonexistent/mesh.obj", "--technique", "sm"],
            "mesh.obj",
        ),
        (
            &["--scene", "no-such-scene", "--technique", "sm"],
            "no-such-scene",
        ),
    ];
    for (args, needle) in cases {
        let out = render(&d, args);
        assert_bad_input(&out, needle);
    }
}

#[test]
fn malformed_meshes_exit_with_2_naming_the_file() {
    let d = tmp("meshes");
    let write = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let nan = write("nan.obj", "v 0 0 0\nv 1 0 0\nv NaN 1 0\nf 1 2 3\n");
    let inf = write("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n");
    let empty = write("empty.obj", "# nothing here\n");
    let range = write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    let ply = write(
        "trunc.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n",
    );
    let toml = write("bad.toml", "[camera]\neye = [0, 0, 5]\nwobble = 3\n");
    for p in [&nan, &inf, &empty, &range, &ply, &toml] {
        let out = render(&d, &["--scene", p.to_str().unwrap(), "--technique", "sm"]);
        let name = p.file_name().unwrap().to_str().unwrap();
        assert_bad_input(&out, name);
    }
}

#[test]
fn files_in_the_bad_folder_never_panic() {
    let d = tmp("bad");
    let mut files = Vec::new();
    let mut stack = vec![data("bad")];
    while let Some(p) = stack.pop() {
        for e in std::fs::read_dir(&p).unwrap() {
            let e = e.unwrap().path();
            if e.is_dir() {
                stack.push(e);
            } else if matches!(e.extension().and_then(|x| x.to_str()), Some("gltf" | "glb")) {
                files.push(e);
            }
        }
    }
    assert!(files.len() >= 4);
    for f in files {
        let out = render(
            &d,
            &[
                "--scene",
                f.to_str().unwrap(),
                "--technique",
                "sm",
                "--width",
                "64",
                "--height",
                "48",
                "--force",
            ],
        );
        let err = &out.stderr;
        assert!(!err.contains("panicked"), "{}: {err}", f.display());
        match out.code {
            Some(0) => {}
            Some(2) => assert_bad_input(&out, f.file_name().unwrap().to_str().unwrap()),
            c => panic!("{}: exit {c:?}: {err}", f.display()),
        }
    }
}

#[test]
fn render_writes_image_visibility_and_stats_and_refuses_to_overwrite() {
    let d = tmp("render");
    let bunny = data("bunny.obj");
    let (vis, stats) = (d.join("vis.exr"), d.join("stats.json"));
    let args = [
        "--scene",
        bunny.to_str().unwrap(),
        "--technique",
        "pcf",
        "--width",
        "96",
        "--height",
        "72",
        "--visibility",
        vis.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ];
    support::ok(&render(&d, &args));
    let png = image::open(d.join("out.png")).unwrap();
    assert_eq!((png.width(), png.height()), (96, 72));
    let stats = support::read_json(&d.join("stats.json"));
    assert_eq!(stats["technique"], "pcf");
    assert_eq!(stats["params"]["kernel"], 3);
    assert_eq!(stats["camera"]["width"], 96);
    assert!(stats["light"]["kind"].is_string());
    // A second run must not overwrite what the first wrote.
    let again = render(&d, &args);
    assert_bad_input(&again, "already exists");
}

#[test]
fn compare_writes_metrics_and_refuses_foreign_folders() {
    let d = tmp("compare");
    let bunny = data("bunny.obj");
    let out_dir = d.join("report");
    let run = |extra: &[&str]| {
        bin()
            .args([
                "compare",
                "--scene",
                bunny.to_str().unwrap(),
                "--techniques",
                "sm,pcf",
                "--width",
                "96",
                "--height",
                "72",
            ])
            .args(["--sweep", "sm.resolution=256,1024"])
            .arg("--out")
            .arg(&out_dir)
            .args(extra)
            .ran()
    };
    let out = run(&[]);
    let m = report_metrics(&out, &out_dir);
    assert_eq!(m["width"], 96);
    let results = m["results"].as_array().unwrap();
    assert_eq!(results.len(), 3, "two sweep values of sm and one pcf");
    for r in results {
        for key in [
            "technique",
            "params",
            "time_ms",
            "stages_ms",
            "memory_bytes",
            "mismatch_rate",
            "mean_abs_error",
            "counters",
        ] {
            assert!(!r[key].is_null(), "result lacks {key}: {r}");
        }
        assert!(out_dir.join(r["image"].as_str().unwrap()).is_file());
    }
    assert!(m["reference"]["time_ms"].as_f64().unwrap() > 0.0);
    // Writing again into an earlier report is fine.
    support::ok(&run(&[]));
    // A folder that holds something else is refused unless --force.
    let foreign = d.join("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("thesis.tex"), "precious").unwrap();
    let out = bin()
        .args([
            "compare",
            "--scene",
            bunny.to_str().unwrap(),
            "--techniques",
            "sm",
            "--width",
            "32",
            "--height",
            "24",
            "--out",
        ])
        .arg(&foreign)
        .ran();
    assert_bad_input(&out, "--force");
    assert_eq!(
        std::fs::read_to_string(foreign.join("thesis.tex")).unwrap(),
        "precious"
    );
}

#[test]
fn layers_behind_semi_transparent_surfaces_are_shaded_and_measured() {
    let d = tmp("layers");
    let out_dir = d.join("report");
    let out = bin()
        .args([
            "compare",
            "--scene",
            "hairball",
            "--scene-param",
            "hairs=600",
            "--techniques",
            "afsm,sm",
            "--width",
            "128",
            "--height",
            "96",
            "--layers",
        ])
        .arg("--out")
        .arg(&out_dir)
        .ran();
    let m = report_metrics(&out, &out_dir);
    assert!(m["layer_samples"].as_u64().unwrap() > 1000);
    let results = m["results"].as_array().unwrap();
    let afsm = results.iter().find(|r| r["technique"] == "afsm").unwrap();
    assert_eq!(afsm["layer_samples"], m["layer_samples"]);
    assert!(afsm["layer_mismatch_rate"].as_f64().unwrap() <= 1e-4);
    assert!(afsm["layer_mean_abs_error_rgb"].as_f64().unwrap() <= 1e-3);
    // sm shades the nearest surfaces only: no layer metrics.
    let sm = results.iter().find(|r| r["technique"] == "sm").unwrap();
    assert!(sm.get("layer_samples").is_none());
    // The composited picture differs from the nearest-surface one.
    let layered = d.join("layered.png");
    let front = d.join("front.png");
    for (p, extra) in [(&layered, &["--layers"][..]), (&front, &[][..])] {
        let o = bin()
            .args([
                "render",
                "--scene",
                "hairball",
                "--scene-param",
                "hairs=600",
            ])
            .args(["--technique", "afsm", "--width", "128", "--height", "96"])
            .arg("--output")
            .arg(p)
            .args(extra)
            .ran();
        support::ok(&o);
    }
    assert_ne!(
        std::fs::read(&layered).unwrap(),
        std::fs::read(&front).unwrap()
    );
}

#[test]
fn loader_warnings_reach_stderr_stats_and_metrics() {
    let d = tmp("warnings");
    let edges = data("lenient/edges.obj");
    let stats = d.join("stats.json");
    let out = render(
        &d,
        &[
            "--scene",
            edges.to_str().unwrap(),
            "--technique",
            "sm",
            "--width",
            "64",
            "--height",
            "48",
            "--stats",
            stats.to_str().unwrap(),
        ],
    );
    let err = &out.stderr;
    support::ok(&out);
    // One line per kind: short faces, `l`, `p`, statements not read.
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 4, "{err}");
    assert!(
        lines
            .iter()
            .all(|l| l.starts_with("warning: edges.obj: skipped ")),
        "{err}"
    );
    let stats = support::read_json(&stats);
    let said: Vec<String> = lines
        .iter()
        .map(|l| l.trim_start_matches("warning: ").to_string())
        .collect();
    assert_eq!(stats["warnings"], serde_json::json!(said));
    let rep = d.join("report");
    let out = bin()
        .args([
            "compare",
            "--scene",
            data("lenient/lines.gltf").to_str().unwrap(),
        ])
        .args([
            "--techniques",
            "sm,raytrace",
            "--width",
            "64",
            "--height",
            "48",
            "--out",
        ])
        .arg(&rep)
        .ran();
    let m = report_metrics(&out, &rep);
    let w: Vec<&str> = m["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(w.len(), 3, "{w:?}");
    assert!(w.iter().any(|s| s.contains("LINES")), "{w:?}");
    // A scene with nothing to say has an empty list.
    let rep = d.join("bunny");
    let out = bin()
        .args(["compare", "--scene", data("bunny.obj").to_str().unwrap()])
        .args([
            "--techniques",
            "sm",
            "--width",
            "64",
            "--height",
            "48",
            "--out",
        ])
        .arg(&rep)
        .ran();
    assert_eq!(
        report_metrics(&out, &rep)["warnings"],
        serde_json::json!([])
    );
}

#[test]
fn camera_index_picks_a_gltf_camera_and_is_checked() {
    let d = tmp("camera-index");
    let cams = data("gltf/Cameras.gltf");
    let run = |i: &str, stats: &Path| {
        render(
            &d,
            &[
                "--scene",
                cams.to_str().unwrap(),
                "--technique",
                "sm",
                "--width",
                "64",
                "--height",
                "48",
                "--force",
                "--camera-index",
                i,
                "--stats",
                stats.to_str().unwrap(),
            ],
        )
    };
    let (s0, s1) = (d.join("s0.json"), d.join("s1.json"));
    support::ok(&run("0", &s0));
    support::ok(&run("1", &s1));
    let (c0, c1) = (
        support::read_json(&s0)["camera"].clone(),
        support::read_json(&s1)["camera"].clone(),
    );
    assert_ne!(c0, c1);
    assert!((c0["fov_y_deg"].as_f64().unwrap() - 0.7f64.to_degrees()).abs() < 1e-3);
    assert_eq!(c0["projection"], "perspective");
    assert_eq!(c1["projection"], "orthographic");
    // The file's ymag kept; --width/--height keep its pixels square.
    assert_eq!(c1["ymag"].as_f64(), Some(1.0));
    assert!((c1["xmag"].as_f64().unwrap() - 64.0 / 48.0).abs() < 1e-6);
    assert_bad_input(&run("2", &d.join("s2.json")), "has 2 cameras");
    assert_bad_input(&run("x", &d.join("s3.json")), "--camera-index");
}

#[test]
fn an_output_that_cannot_be_written_is_an_internal_failure_not_bad_input() {
    // The checks before any work pass (the folder exists, the file is new); then the
    // write fails: here because the file size limit is one 512-byte block, as a full
    // disk would. That is no fault of the input: exit 1, one sentence naming the file.
    let d = tmp("unwritable");
    let args = |output: &'static str| {
        [
            "render",
            "--scene",
            "bunny",
            "--technique",
            "sm",
            "--width",
            "256",
            "--height",
            "192",
            "--output",
            output,
        ]
    };
    let limit = std::time::Duration::from_secs(60);
    let r = support::run_limited(&d, "trap '' XFSZ; ulimit -f 1", limit, &args("out.png"));
    support::failed_with(&r, 1, &["cannot write", "out.png"]);
    // The same run without the limit succeeds.
    let r = support::run_limited(&d, "true", limit, &args("ok.png"));
    support::ok(&r);
}

#[test]
fn techniques_lists_every_technique_with_its_parameters() {
    let all = bin().arg("techniques").ran();
    support::ok(&all);
    for t in shadowlab::techniques::ALL {
        assert!(
            all.stdout
                .lines()
                .any(|l| l.split_whitespace().next() == Some(t)),
            "{t} is not listed: {}",
            all.stdout
        );
    }
    let sm = bin().args(["techniques", "sm"]).ran();
    support::ok(&sm);
    let keys: Vec<&str> = sm
        .stdout
        .lines()
        .skip(1)
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    for key in ["resolution", "bias"] {
        assert!(keys.contains(&key), "sm lacks {key}: {}", sm.stdout);
    }
    // Every listed key is one `render --param` accepts, at its listed default.
    for line in sm.stdout.lines().skip(1) {
        let mut cells = line.split_whitespace();
        let (Some(key), Some(default)) = (cells.next(), cells.next()) else {
            continue;
        };
        if key == "key" {
            continue;
        }
        let d = tmp(&format!("techniques-{key}"));
        let r = render(
            &d,
            &[
                "--technique",
                "sm",
                "--param",
                &format!("{key}={default}"),
                "--width",
                "32",
                "--height",
                "24",
            ],
        );
        support::ok(&r);
    }
    let unknown = bin().args(["techniques", "no-such-technique"]).ran();
    refused(&unknown, &["no-such-technique", "known techniques are"]);
}

#[test]
fn a_failed_image_comparison_leaves_its_error_image() {
    let d = tmp("error-image");
    let (a, b) = (d.join("a.png"), d.join("b.png"));
    image::RgbImage::from_pixel(8, 4, image::Rgb([10, 20, 30]))
        .save(&a)
        .unwrap();
    let mut other = image::RgbImage::from_pixel(8, 4, image::Rgb([10, 20, 30]));
    other.put_pixel(3, 2, image::Rgb([200, 20, 30]));
    other.save(&b).unwrap();
    support::assert_same_files("cli-error-image-same", &a, &a);
    let failed = std::panic::catch_unwind(|| {
        support::assert_same_files("cli-error-image-check", &a, &b);
    });
    let msg = failed.expect_err("the images differ");
    let msg = msg.downcast_ref::<String>().cloned().unwrap_or_default();
    let written = support::failures_dir().join("cli-error-image-check.png");
    assert!(msg.contains(&written.display().to_string()), "{msg}");
    let img = image::open(&written).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (8, 4));
    let [r, _, blue] = img.get_pixel(3, 2).0;
    assert!(r == 0 && blue > 200, "b is lighter there: blue");
    assert_eq!(img.get_pixel(0, 0).0, [0, 0, 0]);
}
