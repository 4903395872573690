//! Every result records what it was computed from, and another renderer can check it:
//! here the library's own reference, fed only the exported files.

mod support;

use shadowlab::camera::{Camera, Projection};
use shadowlab::light::Light;
use shadowlab::math::{vec2, Vec3};
use shadowlab::reference::Reference;
use shadowlab::techniques::Frame;
use shadowlab::view::ViewSamples;
use support::{data, quiet, read_json, run_ok, tmp};

fn v3(v: &serde_json::Value) -> Vec3 {
    Vec3::from_array(support::xyz(v))
}

fn render(args: &[String]) {
    run_ok(quiet().arg("render").args(args));
}

fn light_from_json(l: &serde_json::Value) -> Light {
    match l["kind"].as_str().unwrap() {
        "directional" => Light::Directional {
            to_light: v3(&l["to_light"]),
        },
        "point" => Light::Point {
            position: v3(&l["position"]),
        },
        "spot" => Light::Spot {
            position: v3(&l["position"]),
            target: v3(&l["target"]),
            fov_deg: l["fov_deg"].as_f64().unwrap() as f32,
        },
        k => panic!("unknown light kind {k}"),
    }
}

#[test]
fn exported_scene_retraced_from_recorded_camera_and_light_gives_the_same_shadow_term() {
    let bunny = data("bunny.obj");
    for (i, spec) in [
        "directional:-0.5,0.8,0.3",
        "point:3,14,4",
        "spot:4,15,5:0,3,0:80",
    ]
    .iter()
    .enumerate()
    {
        let d = tmp(&format!("retrace{i}"));
        let p = |n: &str| d.join(n).to_str().unwrap().to_string();
        render(&[
            "--scene".into(),
            bunny.to_str().unwrap().into(),
            "--technique".into(),
            "raytrace".into(),
            "--light".into(),
            spec.to_string(),
            "--width".into(),
            "200".into(),
            "--height".into(),
            "150".into(),
            "--output".into(),
            p("out.png"),
            "--visibility".into(),
            p("vis.exr"),
            "--stats".into(),
            p("stats.json"),
            "--export-scene".into(),
            p("scene.obj"),
        ]);
        // Only the files from here on.
        let stats = read_json(&d.join("stats.json"));
        let c = &stats["camera"];
        let camera = Camera {
            eye: v3(&c["eye"]),
            target: v3(&c["target"]),
            up: v3(&c["up"]),
            fov_y_deg: c["fov_y_deg"].as_f64().unwrap() as f32,
            projection: match c["projection"].as_str().unwrap() {
                "orthographic" => Projection::Orthographic {
                    xmag: c["xmag"].as_f64().unwrap() as f32,
                    ymag: c["ymag"].as_f64().unwrap() as f32,
                },
                _ => Projection::Perspective,
            },
            near: c["near"].as_f64().unwrap() as f32,
            far: c["far"].as_f64().unwrap() as f32,
            width: c["width"].as_u64().unwrap() as u32,
            height: c["height"].as_u64().unwrap() as u32,
        };
        let light = light_from_json(&stats["light"]);
        let scene = shadowlab::scene::obj::load(&d.join("scene.obj")).unwrap();
        assert_eq!(scene.len() as u64, stats["triangles"].as_u64().unwrap());
        let (recorded, covered) =
            shadowlab::shade::read_visibility_exr(&d.join("vis.exr")).unwrap();
        let view = ViewSamples::render(&scene, &camera);
        let frame = Frame::new(&scene, &camera, &light, &view);
        let ours = Reference::build(&scene).visibility(&frame, &[vec2(0.5, 0.5)]);
        let mut compared = 0;
        let mut pair = (Vec::new(), Vec::new());
        for (k, &c) in covered.iter().enumerate() {
            assert_eq!(c, view.covered(k), "{spec}: coverage differs at pixel {k}");
            // Uncovered pixels hold no shadow term to compare.
            let (a, b) = if c {
                compared += 1;
                (ours.value[k], recorded.value[k])
            } else {
                (Vec3::ONE, Vec3::ONE)
            };
            pair.0.push(a.to_array());
            pair.1.push(b.to_array());
        }
        support::assert_same_pixels(
            &format!("provenance-retrace-{i}"),
            camera.width,
            camera.height,
            &pair.0,
            &pair.1,
        );
        assert!(compared > 5000, "{spec}: only {compared} covered pixels");
        let shadowed = (0..covered.len())
            .filter(|&k| covered[k] && recorded.value[k].x < 0.5)
            .count();
        assert!(shadowed > 500, "{spec}: the frame should show shadow");
    }
}

#[test]
fn recorded_parameters_fed_back_reproduce_the_frame_bit_for_bit() {
    let bunny = data("bunny.obj");
    let d = tmp("replay");
    let p = |n: &str| d.join(n).to_str().unwrap().to_string();
    render(&[
        "--scene".into(),
        bunny.to_str().unwrap().into(),
        "--technique".into(),
        "pcf".into(),
        "--param".into(),
        "kernel=5".into(),
        "--width".into(),
        "160".into(),
        "--height".into(),
        "120".into(),
        "--output".into(),
        p("a.png"),
        "--visibility".into(),
        p("a.exr"),
        "--stats".into(),
        p("a.json"),
    ]);
    let stats = read_json(&d.join("a.json"));
    let c = &stats["camera"];
    let list = |v: &serde_json::Value| {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(",")
    };
    let l = &stats["light"];
    let light = match l["kind"].as_str().unwrap() {
        "directional" => format!("directional:{}", list(&l["to_light"])),
        "point" => format!("point:{}", list(&l["position"])),
        _ => format!(
            "spot:{}:{}:{}",
            list(&l["position"]),
            list(&l["target"]),
            l["fov_deg"]
        ),
    };
    let mut args: Vec<String> = vec![
        "--scene".into(),
        stats["scene_source"].as_str().unwrap().into(),
        "--technique".into(),
        stats["technique"].as_str().unwrap().into(),
        "--camera".into(),
        format!(
            "{}:{}:{}",
            list(&c["eye"]),
            list(&c["target"]),
            c["fov_y_deg"]
        ),
        "--light".into(),
        light,
        "--width".into(),
        c["width"].to_string(),
        "--height".into(),
        c["height"].to_string(),
        "--output".into(),
        p("b.png"),
        "--visibility".into(),
        p("b.exr"),
    ];
    for (k, v) in stats["params"].as_object().unwrap() {
        args.push("--param".into());
        args.push(format!("{k}={v}"));
    }
    render(&args);
    support::assert_same_files(
        "provenance-replay-visibility",
        &d.join("a.exr"),
        &d.join("b.exr"),
    );
    support::assert_same_files(
        "provenance-replay-image",
        &d.join("a.png"),
        &d.join("b.png"),
    );
}
