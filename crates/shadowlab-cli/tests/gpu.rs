//! `gpu:` techniques on the command line: named wherever a technique is, side by side with
//! their CPU twins in `compare` with the adapter recorded, and refused in one sentence
//! when the adapter or a parameter cannot be had.

mod support;

use support::{metrics, quiet, refused, run_ok, shadowlab, tmp, Capture};

/// True when a GPU adapter is there; under `CI=true` its absence fails the test, elsewhere
/// the test is skipped with the reason.
fn have_gpu(test: &str, dir: &std::path::Path) -> bool {
    let r = quiet()
        .args([
            "render",
            "--scene",
            "chessboard",
            "--width",
            "16",
            "--height",
            "12",
        ])
        .args(["--technique", "gpu:raytrace", "--output"])
        .arg(dir.join("probe.png"))
        .ran();
    if r.success() {
        return true;
    }
    assert!(r.stderr.contains("no GPU adapter"), "{test}: {}", r.stderr);
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "{test}: no GPU adapter under CI: {}",
        r.stderr
    );
    eprintln!("{test}: skipped: {}", r.stderr.trim());
    false
}

#[test]
fn compare_puts_cpu_and_gpu_side_by_side_with_the_adapter() {
    let dir = tmp("gpu-compare");
    if !have_gpu(
        "compare_puts_cpu_and_gpu_side_by_side_with_the_adapter",
        &dir,
    ) {
        return;
    }
    let out = dir.join("report");
    // Not quiet: the table's line naming the adapter is checked.
    let r = run_ok(
        shadowlab()
            .args([
                "compare",
                "--scene",
                "chessboard",
                "--width",
                "96",
                "--height",
                "72",
            ])
            .args(["--techniques", "sm,gpu:sm,raytrace,gpu:raytrace"])
            .args([
                "--param",
                "gpu:sm.resolution=1024",
                "--param",
                "sm.resolution=1024",
            ])
            .arg("--out")
            .arg(&out),
    );
    assert!(r.stdout.contains("GPU runs on"), "{}", r.stdout);
    let m = metrics(&out);
    let results = m["results"].as_array().unwrap();
    let names: Vec<&str> = results
        .iter()
        .map(|r| r["technique"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["sm", "gpu:sm", "raytrace", "gpu:raytrace"]);
    for r in results {
        let gpu = r["technique"].as_str().unwrap().starts_with("gpu:");
        assert_eq!(r["device"].is_string(), gpu, "{r}");
    }
    // The GPU reference is the reference: no covered pixel differs.
    assert_eq!(results[3]["mismatch_rate"].as_f64(), Some(0.0));
    assert_eq!(results[1]["params"]["resolution"].as_u64(), Some(1024));
}

#[test]
fn gpu_names_work_wherever_a_technique_is_named() {
    let dir = tmp("gpu-names");
    let r = run_ok(quiet().args(["techniques", "gpu:pcf"]));
    assert!(
        r.stdout.contains("gpu:pcf") && r.stdout.contains("kernel"),
        "{}",
        r.stdout
    );
    let r = quiet()
        .args(["render", "--scene", "chessboard", "--technique", "gpu:sm"])
        .args(["--param", "resolution=99999", "--output"])
        .arg(dir.join("x.png"))
        .ran();
    refused(&r, &["gpu:sm.resolution", "99999"]);
    let r = quiet().args(["techniques", "gpu:nope"]).ran();
    refused(&r, &["gpu:nope", "gpu:sm", "gpu:raytrace"]);
}

#[test]
fn an_adapter_that_is_not_there_is_named() {
    let dir = tmp("gpu-adapter");
    let r = quiet()
        .args([
            "--adapter",
            "no-such-adapter-anywhere",
            "render",
            "--scene",
            "chessboard",
        ])
        .args([
            "--width",
            "16",
            "--height",
            "12",
            "--technique",
            "gpu:sm",
            "--output",
        ])
        .arg(dir.join("x.png"))
        .ran();
    // Either the adapters here are listed, or there are none and the sentence says what
    // to install.
    refused(&r, &["adapter"]);
    assert!(
        r.stderr.contains("no-such-adapter-anywhere") || r.stderr.contains("mesa-vulkan-drivers"),
        "{}",
        r.stderr
    );
}

#[test]
fn all_and_gpu_all_put_each_pair_side_by_side() {
    let dir = tmp("gpu-all");
    if !have_gpu("all_and_gpu_all_put_each_pair_side_by_side", &dir) {
        return;
    }
    let out = dir.join("report");
    run_ok(
        quiet()
            .args(["compare", "--scene", "chessboard", "--width", "40"])
            .args(["--height", "30", "--techniques", "all,gpu:all", "--out"])
            .arg(&out),
    );
    let m = metrics(&out);
    let names: Vec<String> = m["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["technique"].as_str().unwrap().to_string())
        .collect();
    for n in ["sm", "psm", "lispsm", "cascaded", "raytrace", "afsm"] {
        let at = names
            .iter()
            .position(|x| x == n)
            .unwrap_or_else(|| panic!("{n}: {names:?}"));
        assert_eq!(names.get(at + 1), Some(&format!("gpu:{n}")), "{names:?}");
    }
    // Every GPU name follows its CPU twin when the twin ran, and each name runs once.
    for (i, n) in names.iter().enumerate() {
        if let Some(base) = n.strip_prefix("gpu:") {
            if names.iter().any(|x| x == base) {
                assert_eq!(names[i - 1], base, "{names:?}");
            }
        }
        assert_eq!(names.iter().filter(|x| *x == n).count(), 1, "{names:?}");
    }
    // `techniques` lists what `all` and `gpu:all` stand for: every one of them ran.
    let listed = run_ok(quiet().args(["techniques", "gpu:all"])).stdout;
    for n in names.iter().filter(|n| n.starts_with("gpu:")) {
        assert!(listed.contains(n.as_str()), "{n}: {listed}");
    }
    assert!(!listed.contains("\nsm"), "{listed}");
}

#[test]
fn bench_engines_on_the_gpu_times_every_gpu_technique() {
    let dir = tmp("gpu-bench-engines");
    if !have_gpu("bench_engines_on_the_gpu_times_every_gpu_technique", &dir) {
        return;
    }
    let json = dir.join("engines.json");
    let r = run_ok(
        shadowlab()
            .args(["bench", "engines", "--backend", "gpu", "--quick", "--json"])
            .arg(&json)
            .arg("--plots")
            .arg(dir.join("plots")),
    );
    assert!(r.stdout.contains("adapter:"), "{}", r.stdout);
    let rows = support::read_json(&json)["rows"]
        .as_array()
        .unwrap()
        .clone();
    let ran = |n: &str, goal: bool| {
        rows.iter()
            .any(|r| r["technique"] == n && r["frame_goal"].as_bool().unwrap_or(false) == goal)
    };
    // Every GPU technique is measured at the budget, or said not to fit it (gpu:subpixel's
    // facets take 288 bytes a pixel of the frame, over 4 MiB at 512×384), and timed for
    // the frame goal.
    for &n in shadowlab_gpu::techniques::ALL {
        let left_out = r
            .stdout
            .lines()
            .any(|l| l.trim_start().starts_with(n) && l.contains("does not fit"));
        assert!(
            (ran(n, false) || left_out) && ran(n, true),
            "{n}: {rows:?}\n{}",
            r.stdout
        );
    }
    for r in &rows {
        assert!(
            r["adapter"].is_string() && r["cpu_emulated"].is_boolean(),
            "{r}"
        );
        assert!(r["time_ms"].as_f64().is_some_and(|t| t >= 0.0), "{r}");
        if r["budget_mib"] == 4 {
            assert!(r["memory_bytes"].as_u64().unwrap() <= 4 << 20, "{r}");
        }
    }
    // The goal ratios of the paper's pairs.
    for pair in [
        "gpu:csm/gpu:pcf",
        "gpu:psm/gpu:sm",
        "gpu:msm/gpu:vsm",
        "gpu:cascaded/gpu:sm",
    ] {
        assert!(r.stdout.contains(&format!("time {pair}")), "{}", r.stdout);
    }
    assert!(dir
        .join("plots/engines-gpu-street-error-vs-time.svg")
        .exists());
    let r = quiet()
        .args(["bench", "csm-table", "--backend", "gpu"])
        .ran();
    refused(&r, &["--backend gpu", "engines"]);
    let r = quiet().args(["bench", "engines", "--backend", "tpu"]).ran();
    refused(&r, &["--backend", "tpu"]);
}

#[test]
fn render_on_the_gpus_camera_pass_draws_what_the_cpu_pass_draws() {
    let dir = tmp("gpu-camera-pass");
    if !have_gpu(
        "render_on_the_gpus_camera_pass_draws_what_the_cpu_pass_draws",
        &dir,
    ) {
        return;
    }
    let image_of = |pass: &str, technique: &str| {
        let out = dir.join(format!("{technique}-{pass}.png").replace(':', "-"));
        run_ok(
            quiet()
                .args(["render", "--scene", "chessboard", "--width", "160"])
                .args(["--height", "120", "--technique", technique])
                .args(["--camera-pass", pass, "--output"])
                .arg(&out),
        );
        image::open(&out).unwrap().to_rgb8()
    };
    // The two passes differ only where the rasterizers round an edge differently: a CPU
    // technique (afsm, exact) and a GPU one (gpu:sm) each shade all but a few pixels the
    // same on both.
    for technique in ["afsm", "gpu:sm"] {
        let (cpu, gpu) = (image_of("cpu", technique), image_of("gpu", technique));
        let apart = cpu
            .pixels()
            .zip(gpu.pixels())
            .filter(|(a, b)| a != b)
            .count();
        eprintln!("{technique}: {apart} of 19200 pixels differ between the camera passes");
        assert!(
            apart <= 160 * 120 / 200,
            "{technique}: {apart} pixels differ between the camera passes"
        );
    }
    let r = quiet()
        .args(["render", "--scene", "chessboard", "--camera-pass", "tpu"])
        .ran();
    refused(&r, &["tpu", "--camera-pass"]);
    let r = quiet()
        .args(["--adapter", "no-such-adapter-anywhere", "render"])
        .args(["--scene", "chessboard", "--width", "16", "--height", "12"])
        .args(["--technique", "afsm", "--camera-pass", "gpu", "--output"])
        .arg(dir.join("x.png"))
        .ran();
    refused(&r, &["--camera-pass gpu", "no-such-adapter-anywhere"]);
}
