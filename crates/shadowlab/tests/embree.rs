//! Intel Embree's occlusion rays (cargo feature `embree`) against the reference: the same
//! shadow rays must find the same blockers, up to numerical ties, on opaque built-in scenes
//! with directional, spot and point lights.
//!
//! Run with `cargo test --release -p shadowlab --features embree --test embree`.
#![cfg(feature = "embree")]

mod support;

use shadowlab::compare::compare;
use shadowlab::embree::EmbreeScene;
use shadowlab::math::{vec2, vec3};
use shadowlab::reference::Reference;
use shadowlab::scene::{self, Scene};
use shadowlab::techniques::Frame;
use shadowlab::view::ViewSamples;
use std::collections::BTreeMap;
use support::lights_for;

/// Share of covered pixels allowed to differ: Embree's triangle test is not the watertight
/// one and it does not skip the receiver's own triangle, so rays grazing an edge or leaving
/// a surface at a grazing angle may differ.
const MISMATCH_LIMIT: f64 = 1e-3;

#[test]
fn embree_agrees_with_the_reference() {
    for (name, params) in [
        ("bunny", vec![]),
        ("chessboard", vec![]),
        ("random-triangles", vec![("count", "20000")]),
        ("cage", vec![]),
    ] {
        let params: BTreeMap<String, String> = params
            .into_iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let scene = scene::load(name, &params).unwrap();
        let mut camera = scene.camera.unwrap();
        camera.width = 320;
        camera.height = 240;
        camera.fit_depth_range(&scene.bounds);
        let view = ViewSamples::render(&scene, &camera);
        let reference = Reference::build(&scene);
        let embree = EmbreeScene::build(&scene, 2).unwrap();
        let mut lights = lights_for(&scene);
        lights.extend(scene.light);
        for light in &lights {
            let frame = Frame::new(&scene, &camera, light, &view);
            let truth = reference.visibility(&frame, &[vec2(0.5, 0.5)]);
            let ours = embree.visibility(&frame);
            let m = compare(&view, &ours, &truth);
            let shadowed = truth
                .value
                .iter()
                .enumerate()
                .filter(|&(k, v)| frame.receiver_lit(k) && v.max_element() < 0.5)
                .count();
            eprintln!(
                "{name} {}: mismatch {:.5}% over {} pixels, {shadowed} shadowed",
                light.kind(),
                m.mismatch_rate * 100.0,
                m.covered_pixels
            );
            assert!(
                m.covered_pixels > 1000 && shadowed > 100,
                "{name}: shadows in view"
            );
            assert!(
                m.mismatch_rate <= MISMATCH_LIMIT,
                "{name} with a {} light: Embree mismatch {} above {MISMATCH_LIMIT}",
                light.kind(),
                m.mismatch_rate
            );
        }
    }
}

#[test]
fn empty_scene_builds_and_misses() {
    let scene = Scene::new("empty");
    let e = EmbreeScene::build(&scene, 1).unwrap();
    assert!(!e.occluded(vec3(0.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0), 10.0));
}

#[test]
fn a_quad_blocks_rays_through_it_only() {
    let mut s = Scene::new("quad");
    let m = s.add_material(Default::default());
    s.push(
        [
            vec3(-1.0, 1.0, -1.0),
            vec3(1.0, 1.0, -1.0),
            vec3(1.0, 1.0, 1.0),
        ],
        m,
    );
    s.push(
        [
            vec3(-1.0, 1.0, -1.0),
            vec3(1.0, 1.0, 1.0),
            vec3(-1.0, 1.0, 1.0),
        ],
        m,
    );
    let e = EmbreeScene::build(&s, 1).unwrap();
    let up = vec3(0.0, 1.0, 0.0);
    assert!(e.occluded(vec3(0.2, 0.0, 0.3), up, 5.0));
    assert!(
        !e.occluded(vec3(0.2, 0.0, 0.3), up, 0.5),
        "segment ends below"
    );
    assert!(!e.occluded(vec3(1.5, 0.0, 0.3), up, 5.0), "beside the quad");
    assert!(!e.occluded(vec3(0.2, 2.0, 0.3), up, 5.0), "above the quad");
}
