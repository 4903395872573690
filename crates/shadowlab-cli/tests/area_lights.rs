//! Area lights on the command line: every shape parses and renders, a sized punctual light
//! becomes its area light, `compare` states the reference's standard error beside every
//! verdict and writes its standard-error image, and bad area-light input exits 2 naming
//! the flag.

mod support;

use support::{metrics, ok, quiet, refused, tmp, Capture};

/// A small, fast render of `scene` with `extra` flags.
fn render(name: &str, scene: &str, extra: &[&str]) -> support::Ran {
    let dir = tmp(name);
    let out = dir.join("out.png");
    let mut c = quiet();
    c.args(["render", "--scene", scene, "--technique", "raytrace"])
        .args(["--width", "32", "--height", "24", "--light-samples", "16"])
        .arg("--output")
        .arg(&out)
        .args(extra);
    c.ran()
}

#[test]
fn every_area_light_shape_renders() {
    for light in [
        "rect:0,8,0:2,0,0:0,0,1",
        "disk:0,8,0:0,-1,0:0.5",
        "sphere:1,8,0:0.4",
    ] {
        ok(&render("shapes", "bunny", &["--light", light]));
    }
    for sized in [
        "point:0,8,0",
        "spot:0,8,0:0,0,0:60",
        "directional:0.3,1,0.2",
    ] {
        ok(&render(
            "sized",
            "bunny",
            &["--light", sized, "--light-size", "2"],
        ));
    }
}

#[test]
fn bad_area_lights_exit_2_naming_the_flag() {
    let cases: &[(&[&str], &str)] = &[
        (&["--light", "rect:0,8,0:1,0,0:2,0,0"], "--light"),
        (&["--light", "disk:0,8,0:0,0,0:1"], "--light"),
        (&["--light", "sphere:0,8,0:-1"], "--light"),
        (&["--light", "sphere:0,8,0:nan"], "--light"),
        (&["--light", "sphere:0,8,0"], "--light"),
        (&["--light-size", "-1"], "--light-size"),
        (&["--light-size", "inf"], "--light-size"),
        (
            &["--light", "directional:0,1,0", "--light-size", "120"],
            "--light-size",
        ),
        (
            &["--light", "sphere:0,8,0:1", "--light-size", "1"],
            "--light-size",
        ),
        (&["--light-samples", "0"], "--light-samples"),
        (&["--light-samples", "100000000"], "--light-samples"),
    ];
    for (args, flag) in cases {
        refused(&render("bad", "bunny", args), &[flag]);
    }
}

#[test]
fn compare_states_the_reference_standard_error() {
    let dir = tmp("compare-soft");
    let out = dir.join("report");
    let r = quiet()
        .args(["compare", "--scene", "penumbra", "--techniques", "sm,pcf"])
        .args(["--width", "64", "--height", "48", "--light-samples", "64"])
        .arg("--out")
        .arg(&out)
        .ran();
    ok(&r);
    let m = metrics(&out);
    assert_eq!(m["area_light"]["kind"], "rect");
    assert_eq!(m["area_light"]["light_samples"], 64);
    for run in m["results"].as_array().unwrap() {
        let se = run["reference_std_error"]
            .as_f64()
            .expect("a standard error");
        assert!(se > 0.0 && se < 0.05, "{se}");
    }
    for r in m["references"].as_array().unwrap() {
        let img = r["std_error_image"].as_str().unwrap();
        assert!(out.join(img).is_file(), "{img}");
    }
}
