//! Alpha-masked casters (glTF `alphaMode: MASK`): the leaf quad of `masked/leaf.gltf`
//! (written by `scripts/make-leaf-fixture.py`) casts a leaf-shaped shadow, not its
//! rectangle, in the reference and in every technique; the exact techniques equal the
//! reference on every pixel.

mod support;

use shadowlab::camera::Camera;
use shadowlab::compare::compare;
use shadowlab::math::{vec2, Vec2, Vec3};
use shadowlab::reference::Reference;
use shadowlab::scene::{LoadOptions, Scene};
use shadowlab::techniques::{self, Frame, Visibility};
use shadowlab::view::ViewSamples;
use support::{assert_same_visibility, data};

/// Texels a side of the leaf texture.
const SIDE: usize = 64;

/// The generator's leaf outline, restated here: 1 inside, 0 outside, at a texel centre.
fn leaf_alpha(u: f32, v: f32) -> u8 {
    if !(0.05 < u && u < 0.95) {
        return 0;
    }
    let half = 0.38 * (std::f32::consts::PI * (u - 0.05) / 0.9).sin();
    u8::from((v - 0.5).abs() < half)
}

/// The texel of the leaf texture under texture coordinates `uv` (clamped, as its sampler).
fn texel(uv: Vec2) -> u8 {
    let i = ((uv.x * SIDE as f32).floor() as i64).clamp(0, SIDE as i64 - 1) as f32;
    let j = ((uv.y * SIDE as f32).floor() as i64).clamp(0, SIDE as i64 - 1) as f32;
    leaf_alpha((i + 0.5) / SIDE as f32, (j + 0.5) / SIDE as f32)
}

/// Whether every texel within `margin` (in texture coordinates) of `uv` has alpha `a`.
fn clearly(uv: Vec2, a: u8, margin: f32) -> bool {
    let steps = 4;
    (-steps..=steps).all(|i| {
        (-steps..=steps).all(|j| {
            let o = vec2(i as f32, j as f32) * (margin / steps as f32);
            texel(uv + o) == a
        })
    })
}

struct Leaf {
    scene: Scene,
    camera: Camera,
    view: ViewSamples,
}

impl Leaf {
    fn new(camera_index: usize, w: u32, h: u32) -> Self {
        let options = LoadOptions {
            camera_index,
            ..Default::default()
        };
        let path = data("masked/leaf.gltf");
        let scene =
            shadowlab::scene::load_with(path.to_str().unwrap(), &Default::default(), &options)
                .unwrap();
        let mut camera = scene.camera.unwrap();
        (camera.width, camera.height) = (w, h);
        let view = ViewSamples::render(&scene, &camera);
        Leaf {
            scene,
            camera,
            view,
        }
    }

    fn frame(&self) -> Frame<'_> {
        Frame::new(
            &self.scene,
            &self.camera,
            self.scene.light.as_ref().unwrap(),
            &self.view,
        )
    }

    fn reference(&self) -> Visibility {
        Reference::build(&self.scene).visibility(&self.frame(), &[vec2(0.5, 0.5)])
    }

    /// The ground pixels whose shadow ray crosses the quad's plane inside the quad, with
    /// the texture coordinates there: `(pixel, uv)`.
    fn under_the_quad(&self) -> Vec<(usize, Vec2)> {
        let light = self.scene.light.unwrap();
        (0..self.view.triangle.len())
            .filter(|&k| self.view.covered(k) && self.view.position[k].y.abs() < 1e-4)
            .filter_map(|k| {
                let p = self.view.position[k];
                let (d, _) = light.shadow_ray(p);
                let q = p + d * ((1.0 - p.y) / d.y);
                let uv = vec2((q.x + 1.0) * 0.5, (q.z + 1.0) * 0.5);
                (uv.min_element() > 0.0 && uv.max_element() < 1.0).then_some((k, uv))
            })
            .collect()
    }
}

#[test]
fn the_leaf_material_reads_its_texture_alpha_and_cutoff() {
    let leaf = Leaf::new(0, 64, 48);
    let s = &leaf.scene;
    let m = s
        .materials
        .iter()
        .find_map(|m| m.alpha_mask.as_ref())
        .expect("the leaf material has an alpha mask");
    assert_eq!(m.cutoff, 0.5);
    assert_eq!(
        (m.texture.width, m.texture.height),
        (SIDE as u32, SIDE as u32)
    );
    for j in 0..SIDE {
        for i in 0..SIDE {
            let want = 255
                * leaf_alpha(
                    (i as f32 + 0.5) / SIDE as f32,
                    (j as f32 + 0.5) / SIDE as f32,
                );
            assert_eq!(m.texture.alpha[j * SIDE + i], want, "texel ({i}, {j})");
        }
    }
    assert!(
        !s.warnings.iter().any(|w| w.contains("MASK")),
        "{:?}",
        s.warnings
    );
    assert_eq!(s.uv.len(), s.len());
}

#[test]
fn the_reference_shadow_is_the_leaf_not_the_quad() {
    let leaf = Leaf::new(0, 320, 240);
    let reference = leaf.reference();
    let (mut lit, mut dark) = (0, 0);
    for (k, uv) in leaf.under_the_quad() {
        let v = reference.value[k];
        if clearly(uv, 0, 0.02) {
            assert_eq!(
                v,
                Vec3::ONE,
                "pixel {k} under a cut-out part (uv {uv}) is lit"
            );
            lit += 1;
        } else if clearly(uv, 1, 0.02) {
            assert_eq!(
                v,
                Vec3::ZERO,
                "pixel {k} under the leaf (uv {uv}) is shadowed"
            );
            dark += 1;
        }
    }
    assert!(
        lit > 300 && dark > 1000,
        "{lit} lit and {dark} dark pixels under the quad"
    );
    // The cut-out parts of the quad are not seen either: the camera looks through them
    // to the ground, and sees the quad only where the leaf is.
    let eye = leaf.camera.eye;
    let (mut through, mut on_leaf) = (0, 0);
    for k in (0..leaf.view.triangle.len()).filter(|&k| leaf.view.covered(k)) {
        let p = leaf.view.position[k];
        let q = eye + (p - eye) * ((1.0 - eye.y) / (p.y - eye.y));
        let uv = vec2((q.x + 1.0) * 0.5, (q.z + 1.0) * 0.5);
        let on_quad = leaf.view.triangle[k] >= 2;
        if clearly(uv, 0, 0.02) && uv.min_element() > 0.0 && uv.max_element() < 1.0 {
            assert!(
                !on_quad,
                "pixel {k} sees the quad where it is cut out (uv {uv})"
            );
            through += 1;
        } else if clearly(uv, 1, 0.02) {
            assert!(on_quad, "pixel {k} does not see the leaf (uv {uv})");
            on_leaf += 1;
        }
    }
    assert!(
        through > 300 && on_leaf > 1000,
        "{through} pixels through, {on_leaf} on the leaf"
    );
}

#[test]
fn every_technique_casts_the_leaf_shaped_shadow() {
    let leaf = Leaf::new(0, 320, 240);
    let reference = leaf.reference();
    let under = leaf.under_the_quad();
    for &name in techniques::ALL {
        let vis = techniques::create(name)
            .unwrap()
            .render(&leaf.frame())
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .visibility;
        if matches!(name, "raytrace" | "afsm") {
            assert_same_visibility(&format!("alpha-mask-{name}"), &vis, &reference);
            continue;
        }
        // Away from the leaf's outline (by the margin filtering and map resolution need),
        // every technique agrees with the texture.
        let mut wrong = Vec::new();
        for &(k, uv) in &under {
            let l = vis.luminance(k);
            if (clearly(uv, 0, 0.05) && l < 0.5) || (clearly(uv, 1, 0.05) && l > 0.5) {
                wrong.push((k, uv, l));
            }
        }
        assert!(
            wrong.is_empty(),
            "{name}: {} pixels disagree with the leaf, e.g. {:?}",
            wrong.len(),
            &wrong[..wrong.len().min(4)]
        );
        let m = compare(&leaf.view, &vis, &reference);
        assert!(
            m.mismatch_rate < 0.01,
            "{name}: mismatch {}",
            m.mismatch_rate
        );
    }
}
