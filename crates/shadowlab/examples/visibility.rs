//! Hands shadowlab its own triangles, camera and light, and gets a visibility buffer back —
//! no command line, no files. Run with `cargo run --release --example visibility`.

use shadowlab::prelude::*;
use shadowlab::reference::Reference;
use shadowlab::sampling::{pattern, PatternKind};

fn main() -> Result<()> {
    // A floor and a floating box made of triangles, in whatever units the caller uses.
    let mut tris = Vec::new();
    let quad = |tris: &mut Vec<[Vec3; 3]>, a: Vec3, b: Vec3, c: Vec3, d: Vec3| {
        tris.push([a, b, c]);
        tris.push([a, c, d]);
    };
    let s = 10.0;
    quad(
        &mut tris,
        vec3(-s, 0.0, -s),
        vec3(-s, 0.0, s),
        vec3(s, 0.0, s),
        vec3(s, 0.0, -s),
    );
    let (lo, hi) = (vec3(-1.0, 2.0, -1.0), vec3(1.0, 3.0, 1.0));
    let c = |x: bool, y: bool, z: bool| {
        vec3(
            if x { hi.x } else { lo.x },
            if y { hi.y } else { lo.y },
            if z { hi.z } else { lo.z },
        )
    };
    for (a, b, cc, d) in [
        (
            c(false, false, false),
            c(true, false, false),
            c(true, false, true),
            c(false, false, true),
        ),
        (
            c(false, true, false),
            c(false, true, true),
            c(true, true, true),
            c(true, true, false),
        ),
        (
            c(false, false, false),
            c(false, true, false),
            c(true, true, false),
            c(true, false, false),
        ),
        (
            c(false, false, true),
            c(true, false, true),
            c(true, true, true),
            c(false, true, true),
        ),
        (
            c(false, false, false),
            c(false, false, true),
            c(false, true, true),
            c(false, true, false),
        ),
        (
            c(true, false, false),
            c(true, true, false),
            c(true, true, true),
            c(true, false, true),
        ),
    ] {
        quad(&mut tris, a, b, cc, d);
    }
    let scene = Scene::from_triangles(tris, Material::default())?;

    let mut camera = Camera::look_at(vec3(6.0, 7.0, 9.0), vec3(0.0, 1.0, 0.0), 45.0, 320, 240);
    camera.fit_depth_range(&scene.bounds);
    let light = Light::Directional {
        to_light: vec3(0.5, 1.0, 0.3).normalize(),
    };

    // The camera pass once; then any technique, and the reference, read it.
    let view = ViewSamples::render(&scene, &camera);
    let frame = Frame::new(&scene, &camera, &light, &view);
    let mut technique = shadowlab::techniques::create("pcf")?;
    technique.set_param("resolution", "1024")?;
    let shadows = technique.render(&frame)?;
    let reference = Reference::build(&scene).visibility(&frame, &pattern(PatternKind::Grid, 1)?);
    let m = shadowlab::compare::compare(&view, &shadows.visibility, &reference);

    let shadowed = shadows
        .visibility
        .value
        .iter()
        .enumerate()
        .filter(|(k, v)| view.covered(*k) && v.x < 0.5)
        .count();
    println!(
        "{} of {} covered pixels in shadow; pcf vs ray tracing: mismatch {:.3}%, mean error {:.4}",
        shadowed,
        view.covered_count(),
        m.mismatch_rate * 100.0,
        m.mean_abs_error
    );
    for (stage, ms) in &shadows.stats.stages_ms {
        println!("  {stage}: {ms:.2} ms");
    }
    Ok(())
}
