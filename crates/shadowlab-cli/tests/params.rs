//! Parameter values as a person would write them: the listing, the sweep labels and
//! `metrics.json` print each value in its shortest form, and the values `metrics.json`
//! records, given back as `--param`, reproduce the run's images bit for bit.

mod support;

use serde_json::Value;
use support::{assert_same_files, data, metrics, quiet, run_ok, tmp};

/// The size every image here is rendered at: small, the check is exact at any size.
const SIZE: [&str; 4] = ["--width", "64", "--height", "48"];

/// A recorded value as `--param` takes it, copied from `metrics.json` as written: the
/// JSON number's text, a word without its quotes.
fn as_written(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Renders the bunny with `technique` and `params`, writing its shaded image and its
/// shadow term into `dir` under `name`.
fn render(dir: &std::path::Path, name: &str, technique: &str, params: &[String]) {
    let mut cmd = quiet();
    cmd.args(["render", "--scene"])
        .arg(data("bunny.obj"))
        .args(["--technique", technique])
        .args(SIZE)
        .arg("--output")
        .arg(dir.join(format!("{name}.png")))
        .arg("--visibility")
        .arg(dir.join(format!("{name}.exr")));
    for p in params {
        cmd.args(["--param", p]);
    }
    run_ok(&mut cmd);
}

#[test]
fn the_listing_shows_single_precision_defaults_in_their_shortest_form() {
    for (technique, key, value) in [
        ("msm", "depth-bias", "0.0005"),
        ("cascaded", "blend", "0.1"),
    ] {
        let r = run_ok(quiet().args(["techniques", technique]));
        let line = r
            .stdout
            .lines()
            .find(|l| l.split_whitespace().next() == Some(key))
            .unwrap_or_else(|| panic!("no {key} line in:\n{}", r.stdout));
        assert_eq!(line.split_whitespace().nth(1), Some(value), "{line}");
    }
    let every = run_ok(quiet().arg("techniques"));
    assert!(every.stdout.contains("msm"), "{}", every.stdout);
    let defaults = every
        .stdout
        .lines()
        .filter(|l| l.starts_with("  ") && !l.trim_start().starts_with("key "))
        .filter_map(|l| l.split_whitespace().nth(1));
    for d in defaults {
        assert!(!d.contains("00000") && !d.contains("99999"), "default {d}");
    }
}

/// A compare of techniques with real parameters (defaults, one set by `--param` to a
/// value no `f32` holds exactly, and a sweep written with a trailing zero); every run's
/// recorded parameters, fed back to `render`, give the run's own shaded image and the
/// same shadow term as the values the compare was given.
#[test]
fn metrics_parameters_fed_back_reproduce_every_run_bit_for_bit() {
    let dir = tmp("feedback");
    let out = dir.join("report");
    run_ok(
        quiet()
            .args(["compare", "--scene"])
            .arg(data("bunny.obj"))
            .args(["--techniques", "sm,msm,cascaded,csm,evsm,pcss"])
            .args(SIZE)
            .args([
                "--param",
                "msm.depth-bias=0.0003",
                "--param",
                "csm.alpha=0.07",
            ])
            .args(["--sweep", "cascaded.blend=0.15,0.30"])
            .arg("--out")
            .arg(&out),
    );
    let m = metrics(&out);
    let results = m["results"].as_array().unwrap();
    let labels: Vec<&str> = results
        .iter()
        .map(|r| r["label"].as_str().unwrap())
        .collect();
    assert!(labels.contains(&"cascaded.blend=0.3"), "{labels:?}");
    let text = std::fs::read_to_string(out.join("metrics.json")).unwrap();
    for long in ["0.0005000000", "0.00030000", "0.100000001", "0.07000000"] {
        assert!(!text.contains(long), "metrics.json records {long}…");
    }
    // The values the compare was given, by label: the fed-back values must agree with them.
    let given = |label: &str| -> Vec<String> {
        match label {
            "msm" => vec!["depth-bias=0.0003".into()],
            "csm" => vec!["alpha=0.07".into()],
            "cascaded.blend=0.15" => vec!["blend=0.15".into()],
            "cascaded.blend=0.3" => vec!["blend=0.30".into()],
            _ => vec![],
        }
    };
    for r in results {
        let (technique, label) = (
            r["technique"].as_str().unwrap(),
            r["label"].as_str().unwrap(),
        );
        let recorded: Vec<String> = r["params"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(k, v)| format!("{k}={}", as_written(v)))
            .collect();
        for p in &recorded {
            let digits = p.split('=').nth(1).unwrap();
            assert!(
                !digits.contains("00000"),
                "{label}: {p} is not its shortest form"
            );
        }
        let file = label.replace(['.', '='], "-");
        render(&dir, &format!("{file}-recorded"), technique, &recorded);
        render(&dir, &format!("{file}-given"), technique, &given(label));
        let recorded_png = dir.join(format!("{file}-recorded.png"));
        let shown = out.join(r["image"].as_str().unwrap());
        assert_same_files(&format!("{label} image"), &recorded_png, &shown);
        assert_same_files(
            &format!("{label} shadow term"),
            &dir.join(format!("{file}-recorded.exr")),
            &dir.join(format!("{file}-given.exr")),
        );
    }
}
