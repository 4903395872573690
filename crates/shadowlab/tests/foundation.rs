//! The ground every technique is measured on: the camera pass against ray casts, the
//! standard shadow map's convergence, and thread-count independence.

mod support;

use shadowlab::camera::Camera;
use shadowlab::compare::compare;
use shadowlab::light::Light;
use shadowlab::math::{vec2, vec3, Vec3};
use shadowlab::reference::Reference;
use shadowlab::scene::{self, Material, Scene};
use shadowlab::techniques::{self, Frame};
use shadowlab::view::{ViewLayers, ViewSamples};
use support::{assert_same_visibility, data};

fn bunny() -> (Scene, Camera, Light) {
    let s = scene::load(data("bunny.obj").to_str().unwrap(), &Default::default()).unwrap();
    let mut c = s.camera.unwrap();
    c.width = 320;
    c.height = 240;
    c.fit_depth_range(&s.bounds);
    let l = Light::Directional {
        to_light: vec3(-0.6, 0.7, 0.4).normalize(),
    };
    (s, c, l)
}

#[test]
fn camera_pass_depth_agrees_with_ray_cast_at_pixel_centres() {
    let (s, c, _) = bunny();
    let view = ViewSamples::render(&s, &c);
    let r = Reference::build(&s);
    let (mut disagree, mut covered) = (0, 0);
    for y in 0..c.height {
        for x in 0..c.width {
            let k = (y * c.width + x) as usize;
            let hit = r.closest_hit(c.eye, c.ray_direction(x as f32 + 0.5, y as f32 + 0.5));
            match (view.covered(k), hit) {
                (true, Some(h)) => {
                    covered += 1;
                    // The ray's direction has unit length along the view axis, so t is depth.
                    let rel = (h.t - view.depth[k]).abs() / h.t;
                    assert!(
                        rel < 1e-4,
                        "pixel {x},{y}: raster depth {} vs ray {}",
                        view.depth[k],
                        h.t
                    );
                    let p = c.eye + c.ray_direction(x as f32 + 0.5, y as f32 + 0.5) * h.t;
                    assert!((p - view.position[k]).length() < 1e-3 * s.bounds.diagonal());
                }
                (false, None) => {}
                // Silhouette pixels whose centre lies within the 1/256-pixel snapping of an edge.
                _ => disagree += 1,
            }
        }
    }
    assert!(covered > 10_000);
    assert!(
        (disagree as f64) < 0.001 * (c.width * c.height) as f64,
        "{disagree} pixels disagree on coverage"
    );
}

/// Every per-pixel field of two camera passes, bit for bit.
fn assert_same_pass(a: &ViewSamples, b: &ViewSamples) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    assert_eq!(a.triangle, b.triangle);
    let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
        v.iter()
            .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect()
    };
    for (x, y) in [
        (&a.position, &b.position),
        (&a.position_error, &b.position_error),
        (&a.normal, &b.normal),
        (&a.dpdx, &b.dpdx),
        (&a.dpdy, &b.dpdy),
    ] {
        assert_eq!(bits(x), bits(y));
    }
    let depth = |v: &[f32]| -> Vec<u32> { v.iter().map(|d| d.to_bits()).collect() };
    assert_eq!(depth(&a.depth), depth(&b.depth));
}

#[test]
fn camera_pass_into_kept_buffers_equals_a_fresh_pass() {
    let (s, c, _) = bunny();
    // Another view first, so every kept buffer holds stale values where the next view
    // shows other surfaces or none; then a size change, then back.
    let mut other = c;
    other.eye += vec3(0.3, 0.5, -0.2);
    other.fit_depth_range(&s.bounds);
    let mut kept = ViewSamples::render(&s, &other);
    kept.render_into(&s, &c).unwrap();
    assert_same_pass(&kept, &ViewSamples::render(&s, &c));
    let mut small = c;
    (small.width, small.height) = (97, 61);
    kept.render_into(&s, &small).unwrap();
    assert_same_pass(&kept, &ViewSamples::render(&s, &small));
    kept.render_into(&s, &other).unwrap();
    assert_same_pass(&kept, &ViewSamples::render(&s, &other));
}

#[test]
fn sm_mismatch_falls_as_resolution_rises() {
    let (s, c, l) = bunny();
    let view = ViewSamples::render(&s, &c);
    let frame = Frame::new(&s, &c, &l, &view);
    let reference = Reference::build(&s).visibility(&frame, &[vec2(0.5, 0.5)]);
    let mut last = f64::INFINITY;
    for res in [128, 512, 2048] {
        let mut sm = techniques::create("sm").unwrap();
        sm.set_param("resolution", &res.to_string()).unwrap();
        let m = compare(&view, &sm.render(&frame).unwrap().visibility, &reference);
        assert!(
            m.mismatch_rate < last,
            "resolution {res}: mismatch {} did not fall below {last}",
            m.mismatch_rate
        );
        last = m.mismatch_rate;
    }
    assert!(last < 0.01, "sm at 2048² still mismatches {last}");
}

#[test]
fn shadow_maps_agree_with_reference_for_every_light_kind() {
    let (s, c, _) = bunny();
    let view = ViewSamples::render(&s, &c);
    let b = s.bounds;
    let top = b.center() + vec3(0.3, 1.5, 0.4) * b.diagonal() * 0.6;
    for l in [
        Light::Directional {
            to_light: vec3(0.3, 1.0, -0.2).normalize(),
        },
        Light::Point { position: top },
        Light::Spot {
            position: top,
            target: b.center(),
            fov_deg: 70.0,
        },
    ] {
        let frame = Frame::new(&s, &c, &l, &view);
        let reference = Reference::build(&s).visibility(&frame, &[vec2(0.5, 0.5)]);
        let lit = reference
            .value
            .iter()
            .enumerate()
            .filter(|(k, v)| view.covered(*k) && v.x > 0.5)
            .count();
        let dark = view.covered_count() - lit;
        assert!(
            lit > 1000 && dark > 1000,
            "{}: the frame must show light and shadow",
            l.kind()
        );
        let mut sm = techniques::create("pcf").unwrap();
        let m = compare(&view, &sm.render(&frame).unwrap().visibility, &reference);
        assert!(
            m.mismatch_rate < 0.02,
            "{}: pcf mismatch {}",
            l.kind(),
            m.mismatch_rate
        );
    }
}

/// An opaque floor (quad at y = 0, half-side 4) under a red sheet (y = 1, half-side 1) and
/// a blue one (y = 2, half-side 0.5) with the given transmittances and colours, two
/// triangles each (so triangle / 2 is the quad); a camera looking straight down and a
/// light straight above.
fn sheets(floor: Vec3, transmittance: [Vec3; 2], color: [Vec3; 2]) -> (Scene, Camera, Light) {
    let mut s = Scene::new("sheets");
    let mut m = vec![s.add_material(Material::opaque("floor", floor))];
    for (i, name) in ["red", "blue"].into_iter().enumerate() {
        m.push(s.add_material(Material {
            name: name.into(),
            color: color[i],
            transmittance: transmittance[i],
            alpha_mask: None,
        }));
    }
    for (i, (y, h)) in [(0.0, 4.0), (1.0, 1.0), (2.0, 0.5)].into_iter().enumerate() {
        s.push([vec3(-h, y, -h), vec3(h, y, h), vec3(h, y, -h)], m[i]);
        s.push([vec3(-h, y, -h), vec3(-h, y, h), vec3(h, y, h)], m[i]);
    }
    let mut c = Camera::look_at(vec3(0.0, 8.0, 0.01), Vec3::ZERO, 40.0, 64, 64);
    c.fit_depth_range(&s.bounds);
    (s, c, Light::Directional { to_light: Vec3::Y })
}

#[test]
fn semi_transparent_casters_multiply_their_transmittance() {
    // Two tinted sheets over a floor: the floor under both gets the product of the tints.
    let (s, c, l) = sheets(
        Vec3::ONE,
        [vec3(0.9, 0.2, 0.2), vec3(0.3, 0.3, 0.8)],
        [Vec3::ONE, Vec3::ONE],
    );
    let view = ViewSamples::render(&s, &c);
    let frame = Frame::new(&s, &c, &l, &view);
    let v = Reference::build(&s).visibility(&frame, &[vec2(0.5, 0.5)]);
    // The centre pixel sees the blue sheet (top), which only the light reaches: lit.
    let centre = (32 * 64 + 32) as usize;
    assert_eq!(view.triangle[centre] / 2, 2);
    assert_eq!(v.value[centre], Vec3::ONE);
    // Look at the floor from below the sheets' edge: a point under both, traced directly.
    let r = Reference::build(&s);
    let t = r.occlusion(vec3(0.1, 0.0, 0.3), Vec3::Y, f32::INFINITY, 0);
    assert_eq!(t, vec3(0.9, 0.2, 0.2) * vec3(0.3, 0.3, 0.8));
}

#[test]
fn layers_behind_semi_transparent_surfaces_composite_front_to_back() {
    // A red sheet over a floor with a blue sheet above it, seen from above; the light
    // shines from straight above.
    let (s, c, l) = sheets(
        vec3(0.8, 0.8, 0.8),
        [vec3(0.6, 0.3, 0.3), vec3(0.2, 0.2, 0.7)],
        [vec3(1.0, 0.1, 0.1), vec3(0.1, 0.1, 1.0)],
    );
    let view = ViewSamples::render(&s, &c);
    let layers = ViewLayers::render(&s, &c, &view).unwrap();
    let frame = Frame::new(&s, &c, &l, &view).with_layers(&layers);
    // A pixel near the centre (off the quads' diagonals, where a ray through the shared
    // edge would count both triangles) sees blue, then red, then the floor.
    let centre = (29 * 64 + 36) as usize;
    assert_eq!(view.triangle[centre] / 2, 2);
    let behind: Vec<u32> = layers
        .of_pixel(centre)
        .map(|i| layers.triangle[i] / 2)
        .collect();
    assert_eq!(behind, [1, 0]);
    // Pixels whose nearest surface is the opaque floor have no layers.
    let corner = 0usize;
    assert_eq!(view.triangle[corner] / 2, 0);
    assert!(layers.of_pixel(corner).is_empty());
    // Shadow terms of the layers: red is under blue, the floor under both.
    let shadows = techniques::create("afsm").unwrap().render(&frame).unwrap();
    let lv = shadows.layers.unwrap();
    let first = layers.of_pixel(centre).start;
    assert_eq!(lv[first], vec3(0.2, 0.2, 0.7));
    assert_eq!(lv[first + 1], vec3(0.2, 0.2, 0.7) * vec3(0.6, 0.3, 0.3));
    // The composite: each surface lit straight on (n·l = 1), weighted by its opacity and
    // by the transmittance in front of it.
    let img = shadowlab::shade::shade_layers(&s, &view, &layers, &l, &shadows.visibility, &lv);
    let shaded = |albedo: Vec3, v: Vec3| {
        albedo * (shadowlab::shade::AMBIENT + (1.0 - shadowlab::shade::AMBIENT) * v)
    };
    let tb = vec3(0.2, 0.2, 0.7);
    let tr = vec3(0.6, 0.3, 0.3);
    let expected = (Vec3::ONE - tb) * shaded(vec3(0.1, 0.1, 1.0), Vec3::ONE)
        + tb * (Vec3::ONE - tr) * shaded(vec3(1.0, 0.1, 0.1), tb)
        + tb * tr * shaded(vec3(0.8, 0.8, 0.8), tb * tr);
    let to_srgb = |x: f32| {
        let s = if x <= 0.0031308 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0 + 0.5) as u8
    };
    let px = img.get_pixel(36, 29).0;
    for ch in 0..3 {
        assert!(
            (px[ch] as i32 - to_srgb(expected[ch]) as i32).abs() <= 1,
            "channel {ch}: {px:?} vs {expected}"
        );
    }
    // Without layers to composite, an opaque scene shades exactly as before.
    let (b, mut bc, bl) = bunny();
    bc.width = 96;
    bc.height = 72;
    let bview = ViewSamples::render(&b, &bc);
    let blayers = ViewLayers::render(&b, &bc, &bview).unwrap();
    assert!(blayers.is_empty());
    let bframe = Frame::new(&b, &bc, &bl, &bview);
    let bvis = Reference::build(&b).visibility(&bframe, &[vec2(0.5, 0.5)]);
    assert_eq!(
        shadowlab::shade::shade_layers(&b, &bview, &blayers, &bl, &bvis, &[]),
        shadowlab::shade::shade(&b, &bview, &bl, &bvis)
    );
    // Layers and their shadow terms do not depend on the thread count.
    let per_threads: Vec<_> = [1, 4]
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
                .install(|| {
                    let hair = scene::load(
                        "hairball",
                        &[("hairs".to_string(), "400".to_string())].into(),
                    )
                    .unwrap();
                    let mut hc = hair.camera.unwrap();
                    hc.width = 160;
                    hc.height = 120;
                    hc.fit_depth_range(&hair.bounds);
                    let hv = ViewSamples::render(&hair, &hc);
                    let hl = ViewLayers::render(&hair, &hc, &hv).unwrap();
                    let hlight = hair.light.unwrap();
                    let f = Frame::new(&hair, &hc, &hlight, &hv).with_layers(&hl);
                    let out = techniques::create("afsm").unwrap().render(&f).unwrap();
                    (hl.triangle.clone(), hl.offsets.clone(), out.layers.unwrap())
                })
        })
        .collect();
    assert!(!per_threads[0].0.is_empty());
    assert_eq!(per_threads[0], per_threads[1]);
}

#[test]
fn results_are_identical_for_one_two_and_four_threads() {
    let (s, mut c, l) = bunny();
    c.width = 160;
    c.height = 120;
    let mut outputs = Vec::new();
    for threads in [1, 2, 4] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let out = pool.install(|| {
            let view = ViewSamples::render(&s, &c);
            let frame = Frame::new(&s, &c, &l, &view);
            let mut per = Vec::new();
            for name in techniques::ALL {
                let mut t = techniques::create(name).unwrap();
                let r = t.render(&frame).unwrap_or_else(|e| panic!("{name}: {e}"));
                per.push((name.to_string(), r.visibility));
            }
            (view.depth.clone(), view.triangle.clone(), per)
        });
        outputs.push(out);
    }
    for (i, o) in outputs.iter().enumerate().skip(1) {
        assert!(
            o.0.iter()
                .zip(&outputs[0].0)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "camera pass depth differs"
        );
        assert_eq!(o.1, outputs[0].1, "camera pass ids differ");
        for ((name, a), (_, b)) in o.2.iter().zip(&outputs[0].2) {
            let what = format!("foundation-{name}-threads-{}", [1, 2, 4][i]);
            assert_same_visibility(&what, a, b);
        }
    }
}

#[test]
fn a_failed_shadow_term_comparison_leaves_its_error_image() {
    use shadowlab::frame::Visibility;
    let a = Visibility::lit(6, 4);
    let mut b = a.clone();
    b.value[9] = Vec3::ZERO;
    assert_same_visibility("foundation-error-image-same", &a, &a.clone());
    let failed = std::panic::catch_unwind(|| {
        assert_same_visibility("foundation-error-image-check", &a, &b);
    });
    let msg = failed.expect_err("the shadow terms differ");
    let msg = msg.downcast_ref::<String>().cloned().unwrap_or_default();
    let written = support::failures_dir().join("foundation-error-image-check.png");
    assert!(msg.contains(&written.display().to_string()), "{msg}");
    let img = image::open(&written).unwrap().to_rgb8();
    assert_eq!(
        img.get_pixel(3, 1).0,
        [255, 0, 0],
        "a is lighter there: red"
    );
    assert_eq!(img.get_pixel(0, 0).0, [0, 0, 0]);
}
