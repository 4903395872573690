//! `shadowlab view` used as a person uses it: under a virtual X server (Xvfb), drawing
//! with the GPU (lavapipe where there is no GPU), a scripted session switches techniques,
//! turns and flies the camera, drags the light, raises a parameter and turns the overlays
//! on; each screenshot's view must equal, outside the overlays' rectangles, the image of
//! the `render` command line the viewer wrote for it, and the error it shows must be
//! `compare`'s for that view. The panel is driven as a pointer drives it: by a script's
//! clicks on its widgets by label, and by a real click through xdotool.

mod support;

use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use support::{quiet, read_json, refused, tmp, Capture};

/// A virtual X server on a display it chose itself, stopped when dropped.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    /// Starts Xvfb, or `None` when it is not installed.
    fn start() -> Option<Xvfb> {
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1024x768x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .ok()?;
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let n: u32 = line.trim().parse().expect("Xvfb names its display");
        Some(Xvfb {
            child,
            display: format!(":{n}"),
        })
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `shadowlab view` in `dir`, without a display unless `display` names one.
fn view(dir: &Path, display: Option<&str>, args: &[&str]) -> support::Ran {
    let mut c = quiet();
    c.current_dir(dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY");
    if let Some(d) = display {
        c.env("DISPLAY", d);
    }
    c.arg("view").args(args).ran()
}

/// Runs the `render` command line of screenshot `shot` (in `dir`); returns its image.
fn reproduce(dir: &Path, shot: &Value) -> image::RgbImage {
    let args: Vec<String> = shot["command"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap().to_string())
        .collect();
    let r = quiet().current_dir(dir).args(&args).ran();
    support::ok(&r);
    let out = dir.join(shot["render_output"].as_str().unwrap());
    image::open(out).unwrap().to_rgb8()
}

/// The screenshot `name` of `dir` and its JSON.
fn screenshot(dir: &Path, name: &str) -> (image::RgbImage, Value) {
    let img = image::open(dir.join(format!("{name}.png")))
        .unwrap()
        .to_rgb8();
    (img, read_json(&dir.join(format!("{name}.json"))))
}

/// True when a GPU adapter is there (the viewer draws with it). Without one, under
/// `CI=true` the test fails (CI installs lavapipe); elsewhere it is skipped.
fn have_gpu(test: &str) -> bool {
    match shadowlab_gpu::device::shared() {
        Ok(_) => true,
        Err(e) if std::env::var("CI").as_deref() == Ok("true") => {
            panic!("{test}: no GPU adapter under CI: {e}")
        }
        Err(e) => {
            eprintln!("{test}: skipped: {e}");
            false
        }
    }
}

/// The view's part of the screenshot `img` (the window holds the panel beside it).
fn view_of(img: &image::RgbImage, shot: &Value) -> image::RgbImage {
    let v = &shot["view"];
    let n = |k: &str| v[k].as_u64().unwrap() as u32;
    image::imageops::crop_imm(img, n("x0"), n("y0"), n("x1") - n("x0"), n("y1") - n("y0"))
        .to_image()
}

/// Whether pixel (x, y) lies under one of the overlays of `shot`.
fn covered(shot: &Value, x: u32, y: u32) -> bool {
    shot["overlays"].as_array().unwrap().iter().any(|r| {
        let v = |k: &str| r[k].as_u64().unwrap() as u32;
        x >= v("x0") && x < v("x1") && y >= v("y0") && y < v("y1")
    })
}

/// The screenshot equals the rendered image outside the overlays; returns how many
/// pixels the overlays changed.
fn assert_same_outside_overlays(
    what: &str,
    shot: &image::RgbImage,
    json: &Value,
    render: &image::RgbImage,
) -> usize {
    let shot = &view_of(shot, json);
    assert_eq!(shot.dimensions(), render.dimensions(), "{what}");
    let mut inside = 0;
    for (x, y, p) in shot.enumerate_pixels() {
        if p == render.get_pixel(x, y) {
            continue;
        }
        assert!(
            covered(json, x, y),
            "{what}: pixel {x},{y} is {p:?} in the screenshot and {:?} in render's image, outside every overlay",
            render.get_pixel(x, y)
        );
        inside += 1;
    }
    inside
}

fn arg_after<'a>(shot: &'a Value, flag: &str) -> &'a str {
    let a = shot["command"].as_array().unwrap();
    let i = a.iter().position(|v| v == flag).unwrap();
    a[i + 1].as_str().unwrap()
}

#[test]
fn a_scripted_session_shows_what_render_draws() {
    let Some(x) = Xvfb::start() else {
        eprintln!("skipping the viewer's session: Xvfb is not installed (.ci/run installs it)");
        return;
    };
    if !have_gpu("the viewer's session") {
        return;
    }
    let d = tmp("session");
    std::fs::write(
        d.join("session.txt"),
        "key h               # the view alone\n\
         screenshot hidden.png\n\
         key h\n\
         key tab             # sm -> pcf\n\
         drag left 40 -20    # turn the camera\n\
         hold w 5            # fly forward\n\
         drag right 30 10    # turn the light\n\
         key ]               # resolution 2048 -> 4096\n\
         wait-reference\n\
         key m               # the shadow map\n\
         screenshot shown.png\n",
    )
    .unwrap();
    let size = ["--width", "320", "--height", "240"];
    let mut args = vec![
        "--scene",
        "bunny",
        "--technique",
        "sm",
        "--script",
        "session.txt",
    ];
    args.extend(size);
    let r = view(&d, Some(&x.display), &args);
    support::ok(&r);

    // With the overlays off the window is render's image, every pixel.
    let (hidden, hj) = screenshot(&d, "hidden");
    assert!(hj["overlays"].as_array().unwrap().is_empty());
    assert_eq!(
        view_of(&hidden, &hj),
        reproduce(&d, &hj),
        "the screenshot without overlays"
    );

    // After the session: another technique, parameter, camera and light.
    let (shown, sj) = screenshot(&d, "shown");
    assert_eq!(arg_after(&sj, "--technique"), "pcf");
    assert_eq!(arg_after(&sj, "--param"), "resolution=4096");
    assert_ne!(arg_after(&sj, "--camera"), arg_after(&hj, "--camera"));
    assert_ne!(arg_after(&sj, "--light"), arg_after(&hj, "--light"));
    let names: Vec<&str> = sj["overlays"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["panel", "error"]);
    let changed =
        assert_same_outside_overlays("the session's screenshot", &shown, &sj, &reproduce(&d, &sj));
    assert!(changed > 0, "the overlays are drawn");

    // The error it shows is compare's against the same reference.
    let out = d.join("report");
    let mut c = quiet();
    c.current_dir(&d)
        .args(["compare", "--scene", "bunny", "--techniques", "pcf"]);
    c.args(size);
    c.args([
        "--camera",
        arg_after(&sj, "--camera"),
        "--light",
        arg_after(&sj, "--light"),
    ]);
    c.args(["--param", "pcf.resolution=4096", "--out"])
        .arg(&out);
    support::ok(&c.ran());
    let m = support::metrics(&out);
    let result = &m["results"][0];
    let shown_error = &sj["error"];
    assert_eq!(shown_error["reference_spp"], 16);
    for k in ["mismatch_rate", "mean_abs_error"] {
        let (a, b) = (
            shown_error[k].as_f64().unwrap(),
            result[k].as_f64().unwrap(),
        );
        assert!(
            (a - b).abs() <= 1e-9 * b.abs().max(1.0),
            "{k}: viewer {a}, compare {b}"
        );
    }
}

#[test]
fn without_a_display_view_says_so() {
    let d = tmp("nodisplay");
    let r = view(
        &d,
        None,
        &["--scene", "bunny", "--width", "64", "--height", "48"],
    );
    refused(&r, &["display", "xvfb-run"]);
    // A display that does not answer.
    let r = view(
        &d,
        Some(":4095"),
        &["--scene", "bunny", "--width", "64", "--height", "48"],
    );
    refused(&r, &["\":4095\"", "xvfb-run"]);
}

#[test]
fn without_an_adapter_view_says_so() {
    let Some(x) = Xvfb::start() else {
        eprintln!(
            "skipping the viewer's adapter test: Xvfb is not installed (.ci/run installs it)"
        );
        return;
    };
    let d = tmp("noadapter");
    // The Vulkan loader finds no driver: no adapter at all.
    let r = quiet()
        .current_dir(&d)
        .env("DISPLAY", &x.display)
        .env("VK_ICD_FILENAMES", d.join("none.json"))
        .env("VK_DRIVER_FILES", d.join("none.json"))
        .args([
            "view", "--scene", "bunny", "--width", "64", "--height", "48",
        ])
        .ran();
    refused(&r, &["GPU adapter", "mesa-vulkan-drivers"]);
}

#[test]
fn offscreen_is_for_benchmarks_only() {
    let d = tmp("offscreen");
    let r = view(&d, Some(":4095"), &["--scene", "bunny", "--offscreen"]);
    refused(&r, &["--offscreen", "--benchmark-frames"]);
}

#[test]
fn a_bad_script_is_refused_before_any_window() {
    let d = tmp("badscript");
    std::fs::write(d.join("s.txt"), "key tab\nkey f13\n").unwrap();
    let r = view(
        &d,
        None,
        &[
            "--scene", "bunny", "--width", "64", "--height", "48", "--script", "s.txt",
        ],
    );
    refused(&r, &["s.txt", "line 2", "f13"]);
    std::fs::write(d.join("s.txt"), "screenshot s.txt\n").unwrap();
    let r = view(
        &d,
        None,
        &[
            "--scene", "bunny", "--width", "64", "--height", "48", "--script", "s.txt",
        ],
    );
    refused(&r, &["s.txt"]);
}

/// The rectangle of the panel's widget `label` in screenshot `shot`: x0, y0, x1, y1.
fn widget_rect(shot: &Value, label: &str) -> (u32, u32, u32, u32) {
    let w = shot["widgets"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["name"] == label)
        .unwrap_or_else(|| panic!("no widget {label:?} in {shot}"));
    let n = |k: &str| w[k].as_u64().unwrap() as u32;
    (n("x0"), n("y0"), n("x1"), n("y1"))
}

/// The centre of the panel's widget `label` in screenshot `shot`, as xdotool's arguments.
fn widget_centre(shot: &Value, label: &str) -> (String, String) {
    let (x0, y0, x1, y1) = widget_rect(shot, label);
    (((x0 + x1) / 2).to_string(), ((y0 + y1) / 2).to_string())
}

/// Runs xdotool on the display of `x`; returns what it printed.
fn xdotool(x: &Xvfb, args: &[&str]) -> String {
    let out = Command::new("xdotool")
        .env("DISPLAY", &x.display)
        .args(args)
        .output()
        .expect("xdotool runs");
    assert!(
        out.status.success(),
        "xdotool {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

/// Waits (at most a minute) until `p` exists.
fn wait_for(p: &Path, child: &mut Child) {
    let t0 = std::time::Instant::now();
    while !p.exists() {
        if let Some(s) = child.try_wait().unwrap() {
            panic!("the viewer ended ({s}) before writing {}", p.display());
        }
        assert!(
            t0.elapsed().as_secs() < 60,
            "no {} after a minute",
            p.display()
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
}

#[test]
fn a_person_at_the_keyboard_and_mouse_is_answered() {
    let Some(x) = Xvfb::start() else {
        eprintln!("skipping the viewer's person test: Xvfb is not installed (.ci/run installs it)");
        return;
    };
    if !have_gpu("the viewer's person test") {
        return;
    }
    if Command::new("xdotool").arg("version").output().is_err() {
        eprintln!(
            "skipping the viewer's person test: xdotool is not installed (.ci/run installs it)"
        );
        return;
    }
    let d = tmp("person");
    let mut child = quiet()
        .current_dir(&d)
        .env("DISPLAY", &x.display)
        .args([
            "view",
            "--scene",
            "bunny",
            "--technique",
            "sm",
            "--width",
            "320",
            "--height",
            "240",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let id = xdotool(&x, &["search", "--sync", "--name", "shadowlab view"]);
    let id = id.lines().next().unwrap().to_string();
    // The window gets the keyboard (there is no window manager to give it), the pointer
    // goes over it; P photographs the start.
    xdotool(&x, &["windowfocus", "--sync", &id]);
    xdotool(&x, &["mousemove", "--window", &id, "100", "100"]);
    xdotool(&x, &["key", "p"]);
    let first = d.join("shadowlab-view-0001.json");
    wait_for(&first, &mut child);
    // A real click on the panel's error overlay box, where the first screenshot says it is.
    let (_, start) = screenshot(&d, "shadowlab-view-0001");
    let (cx, cy) = widget_centre(&start, "error overlay");
    xdotool(
        &x,
        &[
            "mousemove",
            "--window",
            &id,
            &cx,
            &cy,
            "click",
            "1",
            "mousemove",
            "--window",
            &id,
            "100",
            "100",
        ],
    );
    // Tab: the next technique; a left drag turns the camera, a right one the light;
    // ] doubles the resolution; P again; Escape quits.
    xdotool(&x, &["key", "Tab"]);
    xdotool(
        &x,
        &[
            "mousedown",
            "1",
            "mousemove",
            "--window",
            &id,
            "140",
            "90",
            "mouseup",
            "1",
        ],
    );
    xdotool(
        &x,
        &[
            "mousedown",
            "3",
            "mousemove",
            "--window",
            &id,
            "120",
            "110",
            "mouseup",
            "3",
        ],
    );
    xdotool(&x, &["key", "bracketright"]);
    xdotool(&x, &["key", "p", "Escape"]);
    let status = child.wait().unwrap();
    assert!(status.success(), "the viewer ended with {status}");

    let (after, aj) = screenshot(&d, "shadowlab-view-0002");
    assert_eq!(start["error_overlay"], false);
    assert_eq!(
        aj["error_overlay"], true,
        "the click turned the error overlay on"
    );
    assert_eq!(arg_after(&start, "--technique"), "sm");
    assert_eq!(arg_after(&aj, "--technique"), "pcf");
    assert_eq!(arg_after(&aj, "--param"), "resolution=4096");
    assert_ne!(arg_after(&aj, "--camera"), arg_after(&start, "--camera"));
    assert_ne!(arg_after(&aj, "--light"), arg_after(&start, "--light"));
    assert_same_outside_overlays("a person's screenshot", &after, &aj, &reproduce(&d, &aj));
}

#[test]
fn the_panel_switches_technique_sets_a_parameter_and_shows_the_error() {
    let Some(x) = Xvfb::start() else {
        eprintln!("skipping the viewer's panel test: Xvfb is not installed (.ci/run installs it)");
        return;
    };
    if !have_gpu("the viewer's panel test") {
        return;
    }
    let d = tmp("panel");
    // Every change goes through the panel, clicked where the last frame drew its widgets.
    std::fs::write(
        d.join("panel.txt"),
        "click gpu technique   # open the GPU picker\n\
         click gpu:afsm\n\
         click error overlay\n\
         wait-reference\n\
         screenshot afsm-on.png\n\
         click error overlay\n\
         screenshot afsm-off.png\n\
         click gpu technique\n\
         click gpu:sm\n\
         click resolution      # the field of gpu:sm's resolution\n\
         type 256\n\
         click error overlay\n\
         wait-reference\n\
         screenshot sm-on.png\n\
         click error overlay\n\
         screenshot sm-off.png\n\
         click copy command line\n\
         click technique view\n\
         click view shadow map 0\n\
         screenshot map.png\n\
         click gpu technique   # a map drawn on the device through another technique\n\
         click gpu:cascaded\n\
         click directional\n\
         click technique view\n\
         click view shadow map 3 # its farthest cascade, a layer of its texture array\n\
         screenshot cascade.png\n",
    )
    .unwrap();
    let r = view(
        &d,
        Some(&x.display),
        &[
            "--scene",
            "bunny",
            "--technique",
            "sm",
            "--width",
            "160",
            "--height",
            "120",
            "--script",
            "panel.txt",
        ],
    );
    support::ok(&r);
    // "copy command line" prints what it puts on the clipboard: the view's render command.
    let copied = r
        .stdout
        .lines()
        .find(|l| l.starts_with("shadowlab render"))
        .unwrap_or_else(|| panic!("no command line printed: {}", r.stdout));
    assert!(
        copied.contains("--technique gpu:sm --param resolution=256"),
        "{copied}"
    );
    let shot = |n: &str| {
        let (img, j) = screenshot(&d, n);
        (view_of(&img, &j), j)
    };
    let (afsm_on, aj) = shot("afsm-on");
    let (afsm_off, _) = shot("afsm-off");
    let (sm_on, sj) = shot("sm-on");
    let (sm_off, sj_off) = shot("sm-off");
    assert_eq!(arg_after(&aj, "--technique"), "gpu:afsm");
    assert_eq!(arg_after(&sj, "--technique"), "gpu:sm");
    assert_eq!(arg_after(&sj, "--param"), "resolution=256");
    assert_eq!(aj["error_overlay"], true);
    assert_eq!(sj["error_overlay"], true);
    assert_eq!(sj_off["error_overlay"], false);
    // gpu:sm draws on the GPU's own camera pass, and says so in its command line.
    assert_eq!(arg_after(&sj_off, "--camera-pass"), "gpu");
    // The alias-free map is exact: no pixel differs from the reference, the overlay is
    // empty. A 256-texel shadow map is not: its overlay marks pixels, and only those.
    assert_eq!(aj["error"]["mismatch_rate"], 0.0, "{aj}");
    assert_eq!(afsm_on, afsm_off, "the error overlay of gpu:afsm is empty");
    assert!(sj["error"]["mismatch_rate"].as_f64().unwrap() > 0.0, "{sj}");
    let marked = sm_on
        .pixels()
        .zip(sm_off.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        marked > 0,
        "the error overlay of gpu:sm at 256 texels marks pixels"
    );
    // The map's layer, drawn from the device: near casters darker than the far ground, in
    // many grey levels.
    let (map_shot, mj) = screenshot(&d, "map");
    let (x0, y0, x1, y1) = widget_rect(&mj, "shadow map picture");
    let mut levels = std::collections::BTreeSet::new();
    for y in y0..y1 {
        for x in x0..x1 {
            let p = map_shot.get_pixel(x, y).0;
            assert!(
                p[0] == p[1] && p[1] == p[2],
                "the map is grey: {p:?} at {x},{y}"
            );
            levels.insert(p[0]);
        }
    }
    assert!(levels.len() > 16, "the map shows depths: {levels:?}");
    // gpu:cascaded leaves its four cascades on the device too, each a layer to show.
    let (_, cj) = screenshot(&d, "cascade");
    assert_eq!(arg_after(&cj, "--technique"), "gpu:cascaded");
    widget_rect(&cj, "shadow map picture");
    // Without the overlay the view is render's image of the command line shown.
    assert_eq!(
        sm_off,
        reproduce(&d, &sj_off),
        "gpu:sm at 256 as render draws it"
    );
}

#[test]
fn the_panel_gives_the_light_an_area_as_render_does() {
    let Some(x) = Xvfb::start() else {
        eprintln!("skipping the viewer's area light: Xvfb is not installed (.ci/run installs it)");
        return;
    };
    if !have_gpu("the viewer's area light") {
        return;
    }
    let d = tmp("view-area");
    // A point light, then a disk of the panel's size where it is: the same stand-in.
    std::fs::write(
        d.join("area.txt"),
        "click point\n\
         screenshot point.png\n\
         click area            # a disk facing the scene's centre\n\
         screenshot area.png\n\
         wait-reference\n\
         screenshot area-error.png\n\
         click sun             # a directional light given a size\n\
         screenshot sun.png\n\
         click gpu technique   # traces punctual lights only: refused, as render refuses it\n\
         click gpu:raytrace\n\
         frames 1\n",
    )
    .unwrap();
    let r = view(
        &d,
        Some(&x.display),
        &[
            "--scene",
            "chessboard",
            "--technique",
            "raytrace",
            "--light-samples",
            "16",
            "--width",
            "160",
            "--height",
            "120",
            "--script",
            "area.txt",
        ],
    );
    refused(&r, &["gpu:raytrace traces punctual lights only"]);
    let (point, pj) = screenshot(&d, "point");
    let (area, aj) = screenshot(&d, "area");
    assert!(arg_after(&pj, "--light").starts_with("point:"), "{pj}");
    assert!(arg_after(&aj, "--light").starts_with("disk:"), "{aj}");
    assert_eq!(arg_after(&aj, "--light-samples"), "16");
    let (point, area) = (view_of(&point, &pj), view_of(&area, &aj));
    // The view is render's image of the command line shown, every pixel.
    assert_eq!(area, reproduce(&d, &aj), "raytrace under the disk light");
    // The penumbra: around each shadow's edge the hard shadow's pixels brighten (part of
    // the disk is seen) and the lit ones beside it darken.
    let (mut lighter, mut darker) = (0, 0);
    for (a, p) in area.pixels().zip(point.pixels()) {
        let sum = |p: &image::Rgb<u8>| p.0.iter().map(|&c| u32::from(c)).sum::<u32>();
        let (a, p) = (sum(a), sum(p));
        lighter += usize::from(a > p + 6);
        darker += usize::from(a + 6 < p);
    }
    assert!(
        lighter > 100 && darker > 100,
        "a soft shadow: {lighter} pixels lighter and {darker} darker than under the point light"
    );
    // The reference is the soft one, as compare traces it: raytrace matches it exactly.
    let (_, ej) = screenshot(&d, "area-error");
    assert_eq!(ej["error"]["mismatch_rate"], 0.0, "{ej}");
    assert_eq!(ej["error"]["mean_abs_error"], 0.0, "{ej}");
    // A sun is a directional light given an angular size, as --light-size makes it.
    let (sun, sj) = screenshot(&d, "sun");
    assert!(
        arg_after(&sj, "--light").starts_with("directional:"),
        "{sj}"
    );
    assert_eq!(arg_after(&sj, "--light-size"), "2");
    assert_same_outside_overlays("the sun", &sun, &sj, &reproduce(&d, &sj));
}

#[test]
fn a_small_window_scrolls_the_panel_to_its_last_widget() {
    let Some(x) = Xvfb::start() else {
        eprintln!("skipping the viewer's scrolling: Xvfb is not installed (.ci/run installs it)");
        return;
    };
    if !have_gpu("the viewer's scrolling") {
        return;
    }
    let d = tmp("view-scroll");
    std::fs::write(
        d.join("scroll.txt"),
        "screenshot top.png\n\
         click technique view  # below the window's edge: scrolled to\n\
         click view shadow map 0\n\
         screenshot bottom.png\n",
    )
    .unwrap();
    // A 480 × 360 window.
    let r = view(
        &d,
        Some(&x.display),
        &[
            "--scene",
            "chessboard",
            "--technique",
            "gpu:sm",
            "--width",
            "140",
            "--height",
            "360",
            "--script",
            "scroll.txt",
        ],
    );
    support::ok(&r);
    let (_, top) = screenshot(&d, "top");
    let (bottom_img, bottom) = screenshot(&d, "bottom");
    let seen = |shot: &Value, label: &str| {
        shot["widgets"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["name"] == label)
    };
    assert_eq!(bottom_img.height(), 360, "the window is 360 pixels high");
    assert!(seen(&top, "cpu technique"), "{top}");
    assert!(
        !seen(&top, "technique view"),
        "the panel is taller than the window: {top}"
    );
    assert!(
        !seen(&bottom, "cpu technique"),
        "the panel scrolled: {bottom}"
    );
    // The click reached the last widget: the map's picture is shown, inside the window.
    let (x0, y0, x1, y1) = widget_rect(&bottom, "shadow map picture");
    assert!(y1 <= 360 && y0 < y1, "{bottom}");
    let mut levels = std::collections::BTreeSet::new();
    for y in y0..y1 {
        for x in x0..x1 {
            levels.insert(bottom_img.get_pixel(x, y).0[0]);
        }
    }
    assert!(levels.len() > 16, "the map shows depths: {levels:?}");
}

#[test]
fn benchmark_frames_time_every_stage_with_the_gpus_own() {
    let Some(x) = Xvfb::start() else {
        eprintln!("skipping the viewer's benchmark: Xvfb is not installed (.ci/run installs it)");
        return;
    };
    if !have_gpu("the viewer's benchmark") {
        return;
    }
    let d = tmp("benchmark");
    let bench_with = |technique: &str, extra: &[&str]| {
        let mut args = vec![
            "--scene",
            "chessboard",
            "--width",
            "160",
            "--height",
            "120",
            "--technique",
            technique,
            "--error-overlay",
            "--benchmark-frames",
            "3",
        ];
        args.extend(extra);
        let r = view(&d, Some(&x.display), &args);
        support::ok(&r);
        r.stdout
    };
    let bench = |technique: &str| bench_with(technique, &[]);
    // A gpu: technique on the device: the GPU's camera pass, each frame drawn anew (the
    // camera turns), its two stages timed by timestamp queries, the error traced there.
    let out = bench("gpu:sm");
    let first = out.lines().next().unwrap_or_default();
    assert!(
        first.starts_with("gpu:sm: 3 frames after a warm-up frame, "),
        "{out}"
    );
    // lavapipe presents to Xvfb: into the window.
    assert!(!out.contains("drawn offscreen"), "{out}");
    let fps: f64 = first
        .split(", ")
        .find_map(|p| p.strip_suffix(" frames per second"))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no frame rate: {first}"));
    assert!(fps > 0.0, "{first}");
    for stage in [
        "camera pass (GPU)",
        "shade (GPU)",
        "error vs gpu:raytrace",
        "panel, present",
        "adapter: ",
    ] {
        assert!(out.contains(stage), "no {stage:?} in {out}");
    }
    if out.contains("GPU stages") {
        for stage in ["gpu gbuffer", "gpu samples", "gpu shadow_map", "gpu lookup"] {
            assert!(out.contains(stage), "no {stage:?} in {out}");
        }
    }
    // Offscreen (as on a GPU that cannot present to Xvfb): the same stages, and the report
    // says where the frames went.
    let out = bench_with("gpu:sm", &["--offscreen"]);
    assert!(
        out.contains("drawn offscreen") && out.contains("error vs gpu:raytrace"),
        "{out}"
    );
    // A CPU technique: the library's camera pass and the image uploaded.
    let out = bench("sm");
    assert!(
        out.starts_with("sm: 3 frames after a warm-up frame, "),
        "{out}"
    );
    assert!(
        out.contains("camera pass ") && !out.contains("camera pass (GPU)"),
        "{out}"
    );
}
