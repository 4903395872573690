//! Reprojection and temporal error (`shadowlab::temporal`) on a camera that slides
//! parallel to a wall by exactly three pixel footprints: every pixel's predecessor is known
//! in closed form (three pixels over on the wall, six on a square at half the distance,
//! none where the square hid the wall), an error that stays on the surface costs nothing
//! and one that stays on the screen costs its flicker.

use shadowlab::camera::Camera;
use shadowlab::frame::Visibility;
use shadowlab::math::{vec3, Vec3};
use shadowlab::scene::{Material, Scene};
use shadowlab::temporal::{Reprojection, NOT_VISIBLE};
use shadowlab::view::ViewSamples;

const W: u32 = 64;
const H: u32 = 48;
const FOV: f32 = 60.0;
/// Distance from the eye to the wall, and to the square in front of it.
const WALL: f32 = 10.0;
const SQUARE: f32 = 5.0;
/// The sideways shift of the camera between the frames, in pixels at the wall.
const SHIFT_AT_WALL: usize = 3;

/// A wall at z = 0 much larger than the view, and a square halfway to the eye.
fn scene() -> Scene {
    let (a, s) = (100.0f32, 1.5f32);
    let z = WALL - SQUARE;
    Scene::from_triangles(
        vec![
            [vec3(-a, -a, 0.0), vec3(a, -a, 0.0), vec3(a, a, 0.0)],
            [vec3(-a, -a, 0.0), vec3(a, a, 0.0), vec3(-a, a, 0.0)],
            [vec3(-s, -s, z), vec3(s, -s, z), vec3(s, s, z)],
            [vec3(-s, -s, z), vec3(s, s, z), vec3(-s, s, z)],
        ],
        Material::default(),
    )
    .unwrap()
}

/// The camera looking at the wall from `x` along +X.
fn camera(scene: &Scene, x: f32) -> Camera {
    let mut c = Camera::look_at(vec3(x, 0.0, WALL), vec3(x, 0.0, 0.0), FOV, W, H);
    c.fit_depth_range(&scene.bounds);
    c
}

/// The two frames: the second camera three wall pixels to the right of the first, so
/// pixel x of the second frame sees what pixel x + 3 of the first saw on the wall.
fn frames() -> (ViewSamples, ViewSamples) {
    let s = scene();
    let footprint = 2.0 * WALL * (FOV.to_radians() * 0.5).tan() / H as f32;
    let v0 = ViewSamples::render(&s, &camera(&s, 0.0));
    let v1 = ViewSamples::render(&s, &camera(&s, SHIFT_AT_WALL as f32 * footprint));
    (v0, v1)
}

#[test]
fn each_pixel_lands_where_the_slide_puts_it_unless_the_square_hid_it() {
    let (v0, v1) = frames();
    let rp = Reprojection::between(&v0, &v1);
    let mut visible = 0;
    let (mut on_wall, mut on_square, mut hidden) = (0, 0, 0);
    for y in 0..H as usize {
        for x in 0..W as usize {
            let k = y * W as usize + x;
            assert!(v1.covered(k));
            let shift = (SHIFT_AT_WALL as f32 * WALL / v1.depth[k]).round() as usize;
            let kp = y * W as usize + x + shift;
            let expected = if x + shift < W as usize && v0.triangle[kp] == v1.triangle[k] {
                kp as u32
            } else {
                NOT_VISIBLE
            };
            assert_eq!(rp.previous[k], expected, "pixel ({x}, {y}), shift {shift}");
            if expected != NOT_VISIBLE {
                visible += 1;
                if shift == SHIFT_AT_WALL {
                    on_wall += 1;
                } else {
                    on_square += 1;
                }
            } else if x + shift < W as usize {
                hidden += 1;
            }
        }
    }
    assert_eq!(rp.pixels, visible);
    assert!(
        on_wall > 1000 && on_square > 50 && hidden > 20,
        "{on_wall} {on_square} {hidden}"
    );
}

#[test]
fn the_same_view_twice_maps_every_covered_pixel_to_itself() {
    let (v0, _) = frames();
    let rp = Reprojection::between(&v0, &v0);
    assert_eq!(rp.pixels, v0.covered_count());
    for (k, &kp) in rp.previous.iter().enumerate() {
        assert_eq!(kp as usize, k);
    }
}

/// A shadow term of one grey level per pixel.
fn vis(value: impl Fn(usize, &ViewSamples) -> f32, view: &ViewSamples) -> Visibility {
    let mut v = Visibility::lit(W, H);
    for k in 0..v.value.len() {
        v.value[k] = Vec3::splat(value(k, view));
    }
    v
}

#[test]
fn errors_on_the_surface_cost_nothing_and_errors_on_the_screen_cost_their_flicker() {
    let (v0, v1) = frames();
    let rp = Reprojection::between(&v0, &v1);
    // The truth: a shadow over the world half-plane x < 0.3, which moves across the screen.
    let truth = |k: usize, v: &ViewSamples| if v.position[k].x < 0.3 { 0.0 } else { 1.0 };
    let r = [&vis(truth, &v0), &vis(truth, &v1)];
    assert_eq!(
        rp.temporal_error(r, r),
        Some(0.0),
        "the reference against itself"
    );
    // A technique whose shadow edge is wrong by a fixed world offset (a biased map that
    // does not move): wrong in both frames, steady in time.
    let offset = |k: usize, v: &ViewSamples| if v.position[k].x < 0.8 { 0.0 } else { 1.0 };
    let steady = [&vis(offset, &v0), &vis(offset, &v1)];
    let e = rp.temporal_error(steady, r).unwrap();
    assert!(e < 1e-6, "a steady error cost {e}");
    // A technique that darkens image column 20 in the first frame only: it flickers.
    let column = |k: usize| k % W as usize == 20;
    let t0 = vis(|k, v| if column(k) { 0.5 } else { truth(k, v) }, &v0);
    let e = rp.temporal_error([&t0, r[1]], r).unwrap();
    let flickered = rp
        .previous
        .iter()
        .filter(|&&kp| kp != NOT_VISIBLE && column(kp as usize))
        .count();
    // Where the truth is lit the column's change is 0.5, where it is dark 0.5 too.
    let expected = flickered as f64 * 0.5 / rp.pixels as f64;
    assert!(
        flickered > 0 && (e - expected).abs() < 1e-9,
        "{e} vs {expected}"
    );
}
