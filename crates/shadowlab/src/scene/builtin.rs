//! The built-in test scenes: the papers' set-ups (random triangles and the hair ball of the
//! alias-free shadow map paper, the chess set and street of the perspective shadow map paper,
//! the fence of the convolution shadow map paper, the room walkthrough of the adaptive shadow
//! map paper) and a few stress scenes (thin bars, a bumpy receiver).
//!
//! Every scene comes with its own camera (1024×768), light and name; generation is
//! deterministic (a seeded SplitMix64 generator, parallel work collected in order). The meshes
//! the scenes use are compiled into the library from `assets/` (see `assets/README.md` for
//! their sources and licences), so nothing outside the library is read at run time.
//!
//! Parameters arrive as text (`--scene-param K=V`); an unknown key is an error that lists the
//! scene's known keys, and every value is range-checked against a named limit.
//!
//! Where the scenes depart from the papers' descriptions, and why:
//! - `random-triangles`: the paper gives only "random triangles whose total area is
//!   approximately constant". Here each triangle joins three random directions from a random
//!   centre (slivers rejected), scaled to exactly [`RANDOM_TRIANGLES_TOTAL_AREA`] / count, and
//!   lifted when it would pierce the ground (a translation, so the area is kept).
//! - `hairball`: a hair is an open tube of triangular cross-section (96 segments × 3 sides ×
//!   2 = 576 triangles, the paper's count); each face lets through 90% (the paper's 10%
//!   opacity), so a shadow ray crossing a hair passes two faces and keeps 81%.
//! - `room`: the paper's 122° is the field of view of the *light* ("a point light with a 122°
//!   field of view ... placed on the room ceiling"), so the light is a 122° spot light hanging
//!   from the ceiling and the camera has an ordinary 60°; `light=point` makes it an
//!   omnidirectional point light at the same place. The paper's robot and sculpture are
//!   replaced by a teapot on a table and a lattice of thin rods; its bunny is the low-resolution
//!   one (3,674 triangles, not 20,000).
//! - `chessboard`: the file's near-black materials are lifted to [`CHESS_MIN_ALBEDO`] so that
//!   shadows show in the shaded image; visibility is unaffected.
//! - `street`: the paper's cars and aeroplanes move; here everything stands still (a still
//!   frame is what the techniques are compared on).
//!
//! The geometry helpers ([`add_quad`], [`add_plane`], [`add_box`], [`add_sphere`],
//! [`add_cylinder`], [`add_scene`]) are public so that other scene builders can use them.

use super::{obj, Material, Scene};
use crate::camera::{Camera, CameraKey, CameraPath};
use crate::error::{Error, Result};
use crate::light::Light;
use crate::math::{vec3, Mat4, Vec3};
use std::collections::BTreeMap;

/// The image size every built-in camera uses.
const WIDTH: u32 = 1024;
/// The image height every built-in camera uses.
const HEIGHT: u32 = 768;

/// The scenes, in the order `shadowlab scenes` lists them: (name, one-line description).
const SCENES: &[(&str, &str)] = &[
    (
        "bunny",
        "Stanford bunny on a ground plane, oblique directional light (the default scene)",
    ),
    (
        "bunny-closeup",
        "the bunny scene with the camera close to the edge of the ear's shadow",
    ),
    (
        "random-triangles",
        "random triangles above a ground plane, total area constant for any count (alias-free shadow maps, Table 1)",
    ),
    (
        "chessboard",
        "chess set with its 32 pieces under a spot light, seen from a player's seat (perspective shadow maps, Fig. 1)",
    ),
    (
        "hairball",
        "ball of curly hairs, 576 triangles each, 10% opaque, over a ground plane (alias-free shadow maps, Fig. 1)",
    ),
    (
        "fence",
        "wrought-iron fence in front of boxes and a wall: fine scrollwork shadows, high depth complexity (convolution shadow maps, Fig. 9)",
    ),
    (
        "fence-far",
        "the fence, boxes and wall on a bounded yard seen from five times as far (minified on screen and in the light's map), with a camera path pulling back (convolution shadow maps, Fig. 10)",
    ),
    (
        "fence-leak",
        "picket fence in front of boxes and columns at staggered depths under a low sun: three depths under one filter, where variance shadow maps leak (convolution shadow maps, Fig. 9)",
    ),
    ("cage", "a cage of thin bars over a plane: thin shadows that alias"),
    (
        "bumpy",
        "densely tessellated bumpy height field with a few casters above it",
    ),
    (
        "room",
        "room with the bunny, a teapot on a table, boxes, a sphere and a rod sculpture; 122° light on the ceiling and a walkthrough (adaptive shadow maps)",
    ),
    (
        "street",
        "long street of buildings, lamp posts and cars to the horizon, sun perpendicular to the view (perspective shadow maps, Fig. 9)",
    ),
];

/// Lists the built-in scenes as (name, one-line description), the default scene first.
pub fn list() -> Vec<(&'static str, &'static str)> {
    SCENES.to_vec()
}

/// Generates the built-in scene `name` with the parameters `params` (values as text).
///
/// Fails with [`Error::Param`] for an unknown scene (listing the known ones), an unknown
/// parameter (listing the scene's known parameters) or a value out of range.
pub fn generate(name: &str, params: &BTreeMap<String, String>) -> Result<Scene> {
    let mut scene = match name {
        "bunny" => bunny(&Params::new(name, params, BUNNY_PARAMS)?, false)?,
        "bunny-closeup" => bunny(&Params::new(name, params, BUNNY_PARAMS)?, true)?,
        "random-triangles" => random_triangles(&Params::new(name, params, &["count", "seed"])?)?,
        "chessboard" => chessboard(&Params::new(name, params, &[])?)?,
        "hairball" => hairball(&Params::new(name, params, &["hairs", "seed"])?)?,
        "fence" => fence(&Params::new(name, params, &["distance"])?, false)?,
        "fence-far" => fence(&Params::new(name, params, &["distance"])?, true)?,
        "fence-leak" => {
            Params::new(name, params, &[])?;
            super::fence_leak::build(WIDTH, HEIGHT)
        }
        "cage" => cage(&Params::new(name, params, &["bars"])?)?,
        "bumpy" => bumpy(&Params::new(name, params, &["resolution"])?)?,
        "room" => room(&Params::new(name, params, &["light"])?)?,
        "street" => street(&Params::new(name, params, &["length", "seed"])?)?,
        _ => {
            let names: Vec<&str> = SCENES.iter().map(|s| s.0).collect();
            return Err(Error::param(format!(
                "unknown scene {name:?}: not a built-in scene ({}) nor a file with a known extension (.obj, .ply, .gltf, .glb, .toml)",
                names.join(", ")
            )));
        }
    };
    scene.name = name.to_string();
    if let Some(cam) = scene.camera.as_mut() {
        cam.fit_depth_range(&scene.bounds);
    }
    Ok(scene)
}

// ---------------------------------------------------------------------------------------
// Parameters

/// A scene's parameters, checked against the keys it knows.
struct Params<'a> {
    scene: &'a str,
    map: &'a BTreeMap<String, String>,
}

impl<'a> Params<'a> {
    /// Fails on any key not in `known`, naming it and listing the known keys.
    fn new(scene: &'a str, map: &'a BTreeMap<String, String>, known: &[&str]) -> Result<Self> {
        if let Some(k) = map.keys().find(|k| !known.contains(&k.as_str())) {
            let list = if known.is_empty() {
                "it has no parameters".to_string()
            } else {
                format!("known parameters: {}", known.join(", "))
            };
            return Err(Error::param(format!(
                "scene {scene} has no parameter {k:?}; {list}"
            )));
        }
        Ok(Params { scene, map })
    }

    /// An integer parameter in `[min, max]`, `default` when absent.
    fn int(&self, key: &str, default: u64, min: u64, max: u64) -> Result<u64> {
        let Some(text) = self.map.get(key) else {
            return Ok(default);
        };
        let v: u64 = text.trim().parse().map_err(|_| {
            Error::param(format!(
                "scene {}: parameter {key}={text:?} is not a whole number",
                self.scene
            ))
        })?;
        if v < min || v > max {
            return Err(Error::param(format!(
                "scene {}: parameter {key}={v} is outside [{min}, {max}]",
                self.scene
            )));
        }
        Ok(v)
    }

    /// A real parameter in `[min, max]`, `default` when absent.
    fn real(&self, key: &str, default: f32, min: f32, max: f32) -> Result<f32> {
        let Some(text) = self.map.get(key) else {
            return Ok(default);
        };
        let v: f32 = text.trim().parse().map_err(|_| {
            Error::param(format!(
                "scene {}: parameter {key}={text:?} is not a number",
                self.scene
            ))
        })?;
        if !(v >= min && v <= max) {
            return Err(Error::param(format!(
                "scene {}: parameter {key}={v} is outside [{min}, {max}]",
                self.scene
            )));
        }
        Ok(v)
    }

    /// A yes/no parameter (`true`/`false`, `yes`/`no`, `1`/`0`), `default` when absent.
    fn flag(&self, key: &str, default: bool) -> Result<bool> {
        let Some(text) = self.map.get(key) else {
            return Ok(default);
        };
        match text.trim().to_ascii_lowercase().as_str() {
            "true" | "yes" | "1" | "on" => Ok(true),
            "false" | "no" | "0" | "off" => Ok(false),
            _ => Err(Error::param(format!(
                "scene {}: parameter {key}={text:?} is not true or false",
                self.scene
            ))),
        }
    }
}

// ---------------------------------------------------------------------------------------
// Deterministic random numbers

/// SplitMix64: a small, fast generator whose streams are fixed by their seed, so every
/// generated scene is the same on every machine and thread count.
#[derive(Clone, Debug)]
struct Rng(u64);

impl Rng {
    /// A generator for stream `stream` of seed `seed` (streams are independent).
    fn new(seed: u64, stream: u64) -> Self {
        let mut r = Rng(seed ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03));
        r.next_u64();
        r
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform in [a, b).
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.unit()
    }

    /// A uniformly distributed unit vector.
    fn direction(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        vec3(r * phi.cos(), r * phi.sin(), z)
    }
}

// ---------------------------------------------------------------------------------------
// Geometry helpers

/// Appends the parallelogram `corner`, `corner + a`, `corner + a + b`, `corner + b` as two
/// triangles of material `material`.
pub fn add_quad(scene: &mut Scene, corner: Vec3, a: Vec3, b: Vec3, material: u32) {
    let (p0, p1, p2, p3) = (corner, corner + a, corner + a + b, corner + b);
    scene.push([p0, p1, p2], material);
    scene.push([p0, p2, p3], material);
}

/// Appends a horizontal rectangle (normal +Y) centred on `center`, `half_x` and `half_z`
/// from the centre to its edges: a ground plane, a floor, a table top.
pub fn add_plane(scene: &mut Scene, center: Vec3, half_x: f32, half_z: f32, material: u32) {
    let corner = center - vec3(half_x, 0.0, -half_z);
    add_quad(
        scene,
        corner,
        vec3(2.0 * half_x, 0.0, 0.0),
        vec3(0.0, 0.0, -2.0 * half_z),
        material,
    );
}

/// Appends an axis-aligned box from `min` to `max` (12 triangles, closed).
pub fn add_box(scene: &mut Scene, min: Vec3, max: Vec3, material: u32) {
    let d = max - min;
    let (x, y, z) = (
        vec3(d.x, 0.0, 0.0),
        vec3(0.0, d.y, 0.0),
        vec3(0.0, 0.0, d.z),
    );
    add_quad(scene, min, y, x, material); // -Z
    add_quad(scene, min + z, x, y, material); // +Z
    add_quad(scene, min, z, y, material); // -X
    add_quad(scene, min + x, y, z, material); // +X
    add_quad(scene, min, x, z, material); // -Y
    add_quad(scene, min + y, z, x, material); // +Y
}

/// Appends a UV sphere of `stacks` (≥ 2) × `slices` (≥ 3) cells: `2 · slices · (stacks − 1)`
/// triangles (the pole cells are single triangles).
pub fn add_sphere(
    scene: &mut Scene,
    center: Vec3,
    radius: f32,
    stacks: u32,
    slices: u32,
    material: u32,
) {
    let (stacks, slices) = (stacks.max(2), slices.max(3));
    let point = |i: u32, j: u32| {
        let theta = std::f32::consts::PI * i as f32 / stacks as f32;
        let phi = std::f32::consts::TAU * (j % slices) as f32 / slices as f32;
        center
            + radius
                * vec3(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                )
    };
    for i in 0..stacks {
        for j in 0..slices {
            let (a, b, c, d) = (
                point(i, j),
                point(i, j + 1),
                point(i + 1, j + 1),
                point(i + 1, j),
            );
            if i != 0 {
                scene.push([a, b, c], material);
            }
            if i != stacks - 1 {
                scene.push([a, c, d], material);
            }
        }
    }
}

/// Appends a cylinder of radius `radius` from `a` to `b` with `sides` (≥ 3) flat sides
/// (`2 · sides` triangles), closed with flat caps (`2 · sides` more) when `caps` is true.
pub fn add_cylinder(
    scene: &mut Scene,
    a: Vec3,
    b: Vec3,
    radius: f32,
    sides: u32,
    caps: bool,
    material: u32,
) {
    let sides = sides.max(3);
    let axis = (b - a).normalize_or(Vec3::Y);
    let (u, v) = axis.any_orthonormal_pair();
    let ring = |k: u32| {
        let t = std::f32::consts::TAU * (k % sides) as f32 / sides as f32;
        radius * (u * t.cos() + v * t.sin())
    };
    for k in 0..sides {
        let (r0, r1) = (ring(k), ring(k + 1));
        scene.push([a + r0, a + r1, b + r1], material);
        scene.push([a + r0, b + r1, b + r0], material);
        if caps {
            scene.push([a, a + r1, a + r0], material);
            scene.push([b, b + r0, b + r1], material);
        }
    }
}

/// Appends every triangle of `src`, moved by `world_from_src`, with its materials (added to
/// `dst`'s list).
pub fn add_scene(dst: &mut Scene, src: &Scene, world_from_src: Mat4) {
    let base = dst.materials.len() as u32;
    dst.materials.extend(src.materials.iter().cloned());
    dst.reserve(src.len());
    for i in 0..src.len() {
        let t = src.triangle(i).map(|p| world_from_src.transform_point3(p));
        dst.push(t, base + src.material[i]);
    }
}

// ---------------------------------------------------------------------------------------
// Meshes compiled into the library

/// The Stanford bunny (3,674 triangles, about 10 units tall, feet at y = 0).
const BUNNY_OBJ: &str = include_str!("../../assets/bunny.obj");
/// The chess set (125,810 triangles, centimetres, Y up, board from y = 0).
const CHESSBOARD_OBJ: &str = include_str!("../../assets/chessboard/chessboard.obj");
/// The chess set's materials.
const CHESSBOARD_MTL: &str = include_str!("../../assets/chessboard/chessboard.mtl");

/// Parses one of the compiled-in meshes.
fn asset(name: &str, obj_text: &str, mtl: Option<&str>) -> Result<Scene> {
    obj::load_from_str(name, obj_text, mtl)
}

/// A camera of the built-in size.
fn camera(eye: Vec3, target: Vec3, fov_y_deg: f32) -> Camera {
    Camera::look_at(eye, target, fov_y_deg, WIDTH, HEIGHT)
}

/// The unit vector towards a light at `elevation_deg` above the horizon and azimuth
/// `azimuth_deg` (0° = +Z, 90° = +X).
fn sky_direction(elevation_deg: f32, azimuth_deg: f32) -> Vec3 {
    let (el, az) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    vec3(el.cos() * az.sin(), el.sin(), el.cos() * az.cos())
}

// ---------------------------------------------------------------------------------------
// bunny

const BUNNY_PARAMS: &[&str] = &["closeup"];

/// Elevation of the bunny scene's sun: low enough for a shadow about as long as the bunny
/// is tall, high enough that the shadow stays whole on screen.
const BUNNY_LIGHT_ELEVATION_DEG: f32 = 35.0;
/// Azimuth of the bunny scene's sun: from the camera's left, so the shadow falls to the
/// right of the bunny, beside it on screen rather than hidden behind it.
const BUNNY_LIGHT_AZIMUTH_DEG: f32 = -75.0;

fn bunny(p: &Params, closeup_scene: bool) -> Result<Scene> {
    let closeup = p.flag("closeup", closeup_scene)?;
    let mesh = asset("bunny.obj", BUNNY_OBJ, None)?;
    let mut s = Scene::new("bunny");
    let fur = s.add_material(Material::opaque("bunny", vec3(0.78, 0.72, 0.62)));
    let ground = s.add_material(Material::opaque("ground", vec3(0.72, 0.74, 0.70)));
    let floor_y = mesh.bounds.min.y;
    for i in 0..mesh.len() {
        s.push(mesh.triangle(i), fur);
    }
    add_plane(&mut s, vec3(0.0, floor_y, 0.0), 60.0, 60.0, ground);
    let to_light = sky_direction(BUNNY_LIGHT_ELEVATION_DEG, BUNNY_LIGHT_AZIMUTH_DEG);
    s.light = Some(Light::Directional { to_light });
    s.camera = Some(if closeup {
        // The shadow of the bunny's highest point (an ear tip) on the ground: the camera
        // looks at it from a little above, close enough that the shadow edge fills the view.
        let top = (0..mesh.len())
            .flat_map(|i| mesh.triangle(i))
            .fold(mesh.bounds.min, |a, b| if b.y > a.y { b } else { a });
        let on_ground = top - to_light * ((top.y - floor_y) / to_light.y);
        camera(on_ground + vec3(1.2, 2.2, 3.0), on_ground, 40.0)
    } else {
        camera(vec3(14.0, 13.0, 26.0), vec3(7.0, 2.0, -1.5), 45.0)
    });
    Ok(s)
}

// ---------------------------------------------------------------------------------------
// random-triangles

/// The most triangles `random-triangles` makes (its memory grows with the count).
pub const MAX_RANDOM_TRIANGLES: u64 = 10_000_000;
/// Total area of the random triangles, whatever their count (world units²; the field they
/// float in is 10 × 10): each triangle's area is this divided by the count.
pub const RANDOM_TRIANGLES_TOTAL_AREA: f32 = 50.0;
/// Half the side of the square field the triangles' centres are drawn from.
const RANDOM_FIELD_HALF: f32 = 5.0;
/// Heights the triangles' centres are drawn from.
const RANDOM_HEIGHTS: (f32, f32) = (1.0, 3.0);
/// Lowest height of any random triangle's vertex: a triangle reaching lower is lifted (which
/// keeps its area), so that none pierces the ground.
const RANDOM_MIN_HEIGHT: f32 = 0.05;

fn random_triangles(p: &Params) -> Result<Scene> {
    let count = p.int("count", 10_000, 1, MAX_RANDOM_TRIANGLES)? as usize;
    let seed = p.int("seed", 1, 0, u64::MAX)?;
    let mut s = Scene::new("random-triangles");
    let ground = s.add_material(Material::opaque("ground", vec3(0.75, 0.75, 0.72)));
    let tri_mat = s.add_material(Material::opaque("triangles", vec3(0.85, 0.45, 0.25)));
    s.reserve(count + 2);
    add_plane(&mut s, Vec3::ZERO, 12.0, 12.0, ground);
    let area = RANDOM_TRIANGLES_TOTAL_AREA / count as f32;
    let mut rng = Rng::new(seed, 0);
    for _ in 0..count {
        let c = vec3(
            rng.range(-RANDOM_FIELD_HALF, RANDOM_FIELD_HALF),
            rng.range(RANDOM_HEIGHTS.0, RANDOM_HEIGHTS.1),
            rng.range(-RANDOM_FIELD_HALF, RANDOM_FIELD_HALF),
        );
        // Three random directions from the centre; reject slivers (area of the unit-sized
        // shape below 0.1) so every triangle is a visible caster, then scale to the area.
        let (a, b, d, unit_area) = loop {
            let (a, b, d) = (rng.direction(), rng.direction(), rng.direction());
            let ua = 0.5 * (b - a).cross(d - a).length();
            if ua > 0.1 {
                break (a, b, d, ua);
            }
        };
        let k = (area / unit_area).sqrt();
        let mut t = [c + a * k, c + b * k, c + d * k];
        let low = t[0].y.min(t[1].y).min(t[2].y);
        if low < RANDOM_MIN_HEIGHT {
            for v in &mut t {
                v.y += RANDOM_MIN_HEIGHT - low;
            }
        }
        s.push(t, tri_mat);
    }
    s.light = Some(Light::Directional {
        to_light: sky_direction(50.0, 75.0),
    });
    s.camera = Some(camera(vec3(0.0, 7.0, 12.0), vec3(0.0, 0.8, 0.0), 50.0));
    Ok(s)
}

// ---------------------------------------------------------------------------------------
// chessboard

/// The darkest albedo a chess-set material keeps: the file's black pieces and squares
/// (albedo ≈ 0.01) would hide every shadow falling on them, so darker colours are lifted to
/// this (the shading only; visibility does not depend on colour).
pub const CHESS_MIN_ALBEDO: f32 = 0.06;

fn chessboard(_p: &Params) -> Result<Scene> {
    let mut mesh = asset("chessboard.obj", CHESSBOARD_OBJ, Some(CHESSBOARD_MTL))?;
    for m in &mut mesh.materials {
        m.color = m.color.max(Vec3::splat(CHESS_MIN_ALBEDO));
    }
    let mut s = Scene::new("chessboard");
    add_scene(&mut s, &mesh, Mat4::IDENTITY);
    let table = s.add_material(Material::opaque("table", vec3(0.55, 0.42, 0.30)));
    add_plane(
        &mut s,
        vec3(0.0, mesh.bounds.min.y - 0.01, 0.0),
        70.0,
        55.0,
        table,
    );
    s.light = Some(Light::Spot {
        position: vec3(-35.0, 75.0, -20.0),
        target: vec3(0.0, 0.0, 0.0),
        fov_deg: 60.0,
    });
    s.camera = Some(camera(vec3(0.0, 38.0, 46.0), vec3(0.0, 1.0, -1.0), 45.0));
    Ok(s)
}

// ---------------------------------------------------------------------------------------
// hairball

/// Segments along one hair.
pub const HAIR_SEGMENTS: usize = 96;
/// Sides of a hair's tube (a triangular prism, open at both ends).
pub const HAIR_SIDES: usize = 3;
/// Triangles per hair: `HAIR_SEGMENTS × HAIR_SIDES × 2` = 576, as in the alias-free shadow
/// map paper's hair ball.
pub const TRIANGLES_PER_HAIR: usize = HAIR_SEGMENTS * HAIR_SIDES * 2;
/// The most hairs `hairball` makes (20,000 hairs are 11.5 M triangles).
pub const MAX_HAIRS: u64 = 20_000;
/// Transmittance of a hair's surface: 10% opacity, as in the paper. Grey, so the RGB
/// channels agree; a ray crossing one hair passes two of its faces.
pub const HAIR_TRANSMITTANCE: f32 = 0.9;
/// Radius of the hair ball (world units).
const BALL_RADIUS: f32 = 1.0;
/// Radius of a hair's tube: thin enough that a hair is one or two pixels wide in the
/// default view, thick enough that 5,000 hairs throw a clearly grey shadow.
const HAIR_RADIUS: f32 = 0.003;

fn hairball(p: &Params) -> Result<Scene> {
    use rayon::prelude::*;
    let hairs = p.int("hairs", 5_000, 1, MAX_HAIRS)? as usize;
    let seed = p.int("seed", 1, 0, u64::MAX)?;
    let center = vec3(0.0, 1.6, 0.0);
    let n = hairs * TRIANGLES_PER_HAIR;
    let mut s = Scene::new("hairball");
    let hair = s.add_material(Material {
        name: "hair".into(),
        color: vec3(0.55, 0.38, 0.22),
        transmittance: Vec3::splat(HAIR_TRANSMITTANCE),
    });
    let ground = s.add_material(Material::opaque("ground", vec3(0.75, 0.75, 0.72)));
    s.v0 = vec![Vec3::ZERO; n];
    s.v1 = vec![Vec3::ZERO; n];
    s.v2 = vec![Vec3::ZERO; n];
    s.v0.par_chunks_mut(TRIANGLES_PER_HAIR)
        .zip(s.v1.par_chunks_mut(TRIANGLES_PER_HAIR))
        .zip(s.v2.par_chunks_mut(TRIANGLES_PER_HAIR))
        .enumerate()
        .for_each(|(i, ((a, b), c))| one_hair(&mut Rng::new(seed, i as u64), center, a, b, c));
    s.material = vec![hair; n];
    s.recompute_bounds();
    add_plane(&mut s, Vec3::ZERO, 8.0, 8.0, ground);
    s.light = Some(Light::Directional {
        to_light: sky_direction(55.0, -60.0),
    });
    s.camera = Some(camera(vec3(1.2, 3.4, 5.6), vec3(0.5, 0.9, -0.3), 45.0));
    Ok(s)
}

/// Writes one curly hair into `v0`, `v1`, `v2` (each `TRIANGLES_PER_HAIR` long): a tube
/// around a helix that winds about a random radial direction, from near the ball's centre
/// out to its surface.
fn one_hair(rng: &mut Rng, center: Vec3, v0: &mut [Vec3], v1: &mut [Vec3], v2: &mut [Vec3]) {
    let dir = rng.direction();
    let (u, v) = dir.any_orthonormal_pair();
    let root = rng.range(0.15, 0.45) * BALL_RADIUS;
    let tip = rng.range(0.85, 1.0) * BALL_RADIUS;
    let curl = rng.range(0.04, 0.10) * BALL_RADIUS;
    let turns = rng.range(3.0, 7.0);
    let phase = rng.range(0.0, std::f32::consts::TAU);
    let bend = vec3(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    ) * 0.15
        * BALL_RADIUS;
    let bend = bend - dir * bend.dot(dir);
    let centreline = |t: f32| {
        let a = phase + std::f32::consts::TAU * turns * t;
        center
            + dir * (root + (tip - root) * t)
            + (u * a.cos() + v * a.sin()) * curl
            + bend * (t * t)
    };
    // Rings of HAIR_SIDES points around the centreline, framed by parallel transport so the
    // tube does not twist.
    let points: Vec<Vec3> = (0..=HAIR_SEGMENTS)
        .map(|k| centreline(k as f32 / HAIR_SEGMENTS as f32))
        .collect();
    let mut normal = u;
    let mut rings = Vec::with_capacity(points.len());
    for k in 0..points.len() {
        let tangent =
            (points[(k + 1).min(HAIR_SEGMENTS)] - points[k.saturating_sub(1)]).normalize_or(dir);
        normal =
            (normal - tangent * normal.dot(tangent)).normalize_or(tangent.any_orthonormal_vector());
        let binormal = tangent.cross(normal);
        let ring: [Vec3; HAIR_SIDES] = std::array::from_fn(|j| {
            let a = std::f32::consts::TAU * j as f32 / HAIR_SIDES as f32;
            points[k] + (normal * a.cos() + binormal * a.sin()) * HAIR_RADIUS
        });
        rings.push(ring);
    }
    let mut t = 0;
    for k in 0..HAIR_SEGMENTS {
        for j in 0..HAIR_SIDES {
            let jn = (j + 1) % HAIR_SIDES;
            let (a, b, c, d) = (rings[k][j], rings[k][jn], rings[k + 1][jn], rings[k + 1][j]);
            (v0[t], v1[t], v2[t]) = (a, b, c);
            (v0[t + 1], v1[t + 1], v2[t + 1]) = (a, c, d);
            t += 2;
        }
    }
}

// ---------------------------------------------------------------------------------------
// fence, fence-far

/// The wrought-iron fence (19,368 triangles, centimetres, Y up, 180 cm wide, 1 m tall).
const FENCE_OBJ: &str = include_str!("../../assets/fence/fence.obj");
/// The fence's materials.
const FENCE_MTL: &str = include_str!("../../assets/fence/fence.mtl");
/// The largest camera distance factor of the fence scenes.
const MAX_FENCE_DISTANCE: f32 = 100.0;
/// The camera distance factor of `fence-far`: far enough that the fence's scrollwork is
/// well below a pixel (the minification the convolution shadow map paper filters).
const FENCE_FAR_DISTANCE: f32 = 5.0;
/// Half extents (x, z) of `fence-far`'s ground, in centimetres: the yard in front of the
/// wall, from its back (z = −100) to 2 m in front of the fence, wide and deep enough to fill
/// the frame below the wall at distance factor 1.
const FENCE_YARD_HALF: (f32, f32) = (350.0, 150.0);
/// Centre (z) of `fence-far`'s ground.
const FENCE_YARD_CENTER_Z: f32 = 50.0;
/// The camera distances (factors) of the fence scenes' pull-away camera path.
const FENCE_PATH_DISTANCES: [f32; 5] = [1.0, 2.0, 4.0, 8.0, 16.0];

fn fence(p: &Params, far: bool) -> Result<Scene> {
    let default = if far { FENCE_FAR_DISTANCE } else { 1.0 };
    let distance = p.real("distance", default, 0.05, MAX_FENCE_DISTANCE)?;
    let mesh = asset("fence.obj", FENCE_OBJ, Some(FENCE_MTL))?;
    let mut s = Scene::new("fence");
    // Feet on the ground, centred on x = 0, in the plane z = 0.
    let c = mesh.bounds.center();
    add_scene(
        &mut s,
        &mesh,
        Mat4::from_translation(vec3(-c.x, -mesh.bounds.min.y, -c.z)),
    );
    let ground = s.add_material(Material::opaque("ground", vec3(0.55, 0.62, 0.45)));
    let wall = s.add_material(Material::opaque("wall", vec3(0.80, 0.74, 0.66)));
    let crate_ = s.add_material(Material::opaque("boxes", vec3(0.70, 0.52, 0.32)));
    let stone = s.add_material(Material::opaque("stone", vec3(0.62, 0.64, 0.68)));
    if far {
        // A bounded yard instead of the 100 m ground: the light's map is fitted to the visible
        // receivers, so with the ground to the horizon in view its texels would be 5 cm and
        // the fence's scrollwork would be magnified in light space however far the camera
        // is. Round the wall, fence and boxes only, the map's texels are a few millimetres and
        // the scrollwork is minified in light space as on screen (many texels per pixel). The
        // yard ends at the wall, so the wall's long shadow under the low sun falls off it and
        // the shadows in view span the fence's depths, not the wall's.
        add_plane(
            &mut s,
            vec3(0.0, 0.0, FENCE_YARD_CENTER_Z),
            FENCE_YARD_HALF.0,
            FENCE_YARD_HALF.1,
            ground,
        );
    } else {
        add_plane(&mut s, vec3(0.0, 0.0, -2000.0), 10_000.0, 10_000.0, ground);
    }
    // A wall behind, boxes and a low column between it and the fence.
    add_box(
        &mut s,
        vec3(-300.0, 0.0, -100.0),
        vec3(300.0, 260.0, -80.0),
        wall,
    );
    add_box(
        &mut s,
        vec3(-85.0, 0.0, -65.0),
        vec3(-35.0, 45.0, -30.0),
        crate_,
    );
    add_box(
        &mut s,
        vec3(-15.0, 0.0, -60.0),
        vec3(35.0, 25.0, -35.0),
        crate_,
    );
    add_box(
        &mut s,
        vec3(45.0, 0.0, -55.0),
        vec3(90.0, 55.0, -30.0),
        crate_,
    );
    add_cylinder(
        &mut s,
        vec3(-130.0, 0.0, -60.0),
        vec3(-130.0, 90.0, -60.0),
        18.0,
        24,
        true,
        stone,
    );
    add_sphere(&mut s, vec3(135.0, 25.0, -55.0), 25.0, 16, 24, stone);
    s.light = Some(Light::Directional {
        to_light: sky_direction(24.0, -30.0),
    });
    let mut cam = camera(vec3(70.0, 110.0, 270.0), vec3(0.0, 45.0, -40.0), 45.0);
    let base = cam;
    cam.scale_distance(distance);
    s.camera = Some(cam);
    let keys = FENCE_PATH_DISTANCES
        .iter()
        .map(|&f| {
            let mut c = base;
            c.scale_distance(f);
            CameraKey {
                eye: c.eye,
                target: c.target,
            }
        })
        .collect();
    s.camera_path = Some(CameraPath { keys });
    Ok(s)
}

// ---------------------------------------------------------------------------------------
// cage

/// The most bars `cage` makes.
pub const MAX_CAGE_BARS: u64 = 2_000;
/// Radius of a cage bar: a few pixels wide on screen in the default view, so its shadow is a
/// thin line that a coarse shadow map breaks up.
const CAGE_BAR_RADIUS: f32 = 0.012;

fn cage(p: &Params) -> Result<Scene> {
    let bars = p.int("bars", 32, 3, MAX_CAGE_BARS)? as u32;
    let mut s = Scene::new("cage");
    let ground = s.add_material(Material::opaque("ground", vec3(0.75, 0.74, 0.70)));
    let metal = s.add_material(Material::opaque("bars", vec3(0.35, 0.33, 0.30)));
    let bird = s.add_material(Material::opaque("ball", vec3(0.85, 0.75, 0.25)));
    add_plane(&mut s, Vec3::ZERO, 12.0, 12.0, ground);
    let (radius, height) = (1.0f32, 2.0f32);
    let top = vec3(0.0, height + 0.5, 0.0);
    let at = |k: u32, y: f32| {
        let a = std::f32::consts::TAU * k as f32 / bars as f32;
        vec3(radius * a.cos(), y, radius * a.sin())
    };
    let r = CAGE_BAR_RADIUS;
    for k in 0..bars {
        add_cylinder(&mut s, at(k, 0.0), at(k, height), r, 6, false, metal);
        // The dome: one bar from each upright to the top.
        add_cylinder(&mut s, at(k, height), top, r, 6, false, metal);
        // Rings at the foot, the middle and the top.
        for y in [0.02, height * 0.5, height] {
            add_cylinder(&mut s, at(k, y), at(k + 1, y), r, 6, false, metal);
        }
    }
    add_cylinder(
        &mut s,
        vec3(0.0, 0.0, 0.0),
        vec3(0.0, 0.6, 0.0),
        0.08,
        16,
        true,
        metal,
    );
    add_sphere(&mut s, vec3(0.0, 0.9, 0.0), 0.3, 24, 32, bird);
    s.light = Some(Light::Directional {
        to_light: sky_direction(35.0, -120.0),
    });
    s.camera = Some(camera(vec3(2.6, 3.4, 4.6), vec3(0.4, 0.7, 0.0), 45.0));
    Ok(s)
}

// ---------------------------------------------------------------------------------------
// bumpy

/// The finest height-field grid `bumpy` makes (cells per side; 2048² cells are 8.4 M
/// triangles).
pub const MAX_BUMPY_RESOLUTION: u64 = 2048;
/// Half the side of the bumpy receiver.
const BUMPY_HALF: f32 = 7.0;

/// The bumpy receiver's height at `(x, z)`: a few sines of different scales, so that it
/// both shadows itself and receives the casters' shadows on slopes.
fn bump_height(x: f32, z: f32) -> f32 {
    0.30 * (0.9 * x).sin() * (0.7 * z).cos()
        + 0.12 * (2.3 * x + 0.8 * z + 1.0).sin()
        + 0.05 * (6.1 * z - 2.7 * x).sin()
        + 0.02 * (13.0 * x + 1.7).sin() * (11.0 * z).cos()
}

fn bumpy(p: &Params) -> Result<Scene> {
    let res = p.int("resolution", 512, 1, MAX_BUMPY_RESOLUTION)? as usize;
    let mut s = Scene::new("bumpy");
    let terrain = s.add_material(Material::opaque("terrain", vec3(0.62, 0.66, 0.52)));
    let red = s.add_material(Material::opaque("sphere", vec3(0.80, 0.30, 0.25)));
    let blue = s.add_material(Material::opaque("box", vec3(0.30, 0.45, 0.80)));
    let step = 2.0 * BUMPY_HALF / res as f32;
    let point = |i: usize, j: usize| {
        let (x, z) = (-BUMPY_HALF + i as f32 * step, -BUMPY_HALF + j as f32 * step);
        vec3(x, bump_height(x, z), z)
    };
    s.reserve(2 * res * res + 2000);
    for j in 0..res {
        for i in 0..res {
            let (a, b, c, d) = (
                point(i, j),
                point(i + 1, j),
                point(i + 1, j + 1),
                point(i, j + 1),
            );
            s.push([a, b, c], terrain);
            s.push([a, c, d], terrain);
        }
    }
    add_sphere(&mut s, vec3(-1.2, 1.6, 0.6), 0.6, 24, 32, red);
    add_box(&mut s, vec3(0.8, 1.2, -1.4), vec3(1.8, 1.5, -0.4), blue);
    add_cylinder(
        &mut s,
        vec3(-0.5, 1.0, -2.0),
        vec3(1.5, 1.9, -2.2),
        0.12,
        12,
        true,
        blue,
    );
    s.light = Some(Light::Directional {
        to_light: sky_direction(30.0, -70.0),
    });
    s.camera = Some(camera(vec3(2.5, 4.5, 7.5), vec3(0.0, 0.2, -0.5), 50.0));
    Ok(s)
}

// ---------------------------------------------------------------------------------------
// room

/// The teapot (992 triangles, 32 units wide).
const TEAPOT_OBJ: &str = include_str!("../../assets/teapot.obj");
/// The room light's field of view: the adaptive shadow map paper's "point light with a 122°
/// field of view ... placed on the room ceiling".
pub const ROOM_LIGHT_FOV_DEG: f32 = 122.0;
/// The room's half width and depth, and its height (metres).
const ROOM: (f32, f32) = (4.0, 3.0);

fn room(p: &Params) -> Result<Scene> {
    let light_kind = p.map.get("light").map(|v| v.trim().to_ascii_lowercase());
    let point_light = match light_kind.as_deref() {
        None | Some("spot") => false,
        Some("point") => true,
        Some(other) => {
            return Err(Error::param(format!(
                "scene room: parameter light={other:?} is neither spot nor point"
            )))
        }
    };
    let (half, height) = ROOM;
    let mut s = Scene::new("room");
    let floor = s.add_material(Material::opaque("floor", vec3(0.70, 0.62, 0.50)));
    let walls = s.add_material(Material::opaque("walls", vec3(0.82, 0.80, 0.74)));
    let white = s.add_material(Material::opaque("white", vec3(0.85, 0.85, 0.85)));
    let wood = s.add_material(Material::opaque("wood", vec3(0.55, 0.36, 0.20)));
    let red = s.add_material(Material::opaque("red", vec3(0.78, 0.25, 0.20)));
    let metal = s.add_material(Material::opaque("metal", vec3(0.45, 0.47, 0.52)));
    // Floor, ceiling and four walls.
    add_plane(&mut s, Vec3::ZERO, half, half, floor);
    add_plane(&mut s, vec3(0.0, height, 0.0), half, half, walls);
    let (x, y, z) = (
        vec3(2.0 * half, 0.0, 0.0),
        vec3(0.0, height, 0.0),
        vec3(0.0, 0.0, 2.0 * half),
    );
    add_quad(&mut s, vec3(-half, 0.0, -half), x, y, walls);
    add_quad(&mut s, vec3(-half, 0.0, half), x, y, walls);
    add_quad(&mut s, vec3(-half, 0.0, -half), z, y, walls);
    add_quad(&mut s, vec3(half, 0.0, -half), z, y, walls);
    // The bunny, about 0.8 m tall, standing on the floor.
    let bunny = asset("bunny.obj", BUNNY_OBJ, None)?;
    let k = 0.8 / (bunny.bounds.max.y - bunny.bounds.min.y);
    let to_floor = Mat4::from_translation(vec3(-1.4, -bunny.bounds.min.y * k, -1.0))
        * Mat4::from_rotation_y(0.6)
        * Mat4::from_scale(Vec3::splat(k));
    let mut b = Scene::new("bunny");
    b.add_material(Material::opaque("bunny", vec3(0.80, 0.74, 0.64)));
    b.v0.clone_from(&bunny.v0);
    b.v1.clone_from(&bunny.v1);
    b.v2.clone_from(&bunny.v2);
    b.material = vec![0; bunny.len()];
    add_scene(&mut s, &b, to_floor);
    // A table with the teapot on it.
    let (tx, tz, th) = (1.5f32, -1.2f32, 0.75f32);
    add_box(
        &mut s,
        vec3(tx - 0.6, th - 0.05, tz - 0.4),
        vec3(tx + 0.6, th, tz + 0.4),
        wood,
    );
    for (dx, dz) in [(-0.55, -0.35), (0.55, -0.35), (-0.55, 0.35), (0.55, 0.35)] {
        add_box(
            &mut s,
            vec3(tx + dx - 0.03, 0.0, tz + dz - 0.03),
            vec3(tx + dx + 0.03, th - 0.05, tz + dz + 0.03),
            wood,
        );
    }
    let teapot = asset("teapot.obj", TEAPOT_OBJ, None)?;
    let k = 0.4 / (teapot.bounds.max.x - teapot.bounds.min.x);
    let on_table = Mat4::from_translation(vec3(tx, th - teapot.bounds.min.y * k, tz))
        * Mat4::from_rotation_y(-0.8)
        * Mat4::from_scale(Vec3::splat(k));
    let mut t = teapot.clone();
    t.materials = vec![Material::opaque("teapot", vec3(0.85, 0.85, 0.80))];
    t.material = vec![0; t.len()];
    add_scene(&mut s, &t, on_table);
    // Boxes, a sphere, and a lattice sculpture of thin rods (fine shadow detail).
    add_box(&mut s, vec3(-2.9, 0.0, 1.2), vec3(-2.1, 0.8, 2.0), red);
    add_box(
        &mut s,
        vec3(-2.75, 0.8, 1.35),
        vec3(-2.25, 1.2, 1.85),
        white,
    );
    add_sphere(&mut s, vec3(0.3, 0.45, 1.6), 0.45, 24, 32, white);
    let base = vec3(2.2, 0.0, 1.6);
    for i in 0..6 {
        let a = std::f32::consts::TAU * i as f32 / 6.0;
        let foot = base + vec3(0.35 * a.cos(), 0.0, 0.35 * a.sin());
        let head = base + vec3(0.35 * (a + 2.0).cos(), 1.6, 0.35 * (a + 2.0).sin());
        add_cylinder(&mut s, foot, head, 0.015, 6, false, metal);
    }
    for level in 1..6 {
        let y = 1.6 * level as f32 / 6.0;
        add_cylinder(
            &mut s,
            base + vec3(-0.35, y, 0.0),
            base + vec3(0.35, y, 0.0),
            0.012,
            6,
            false,
            metal,
        );
        add_cylinder(
            &mut s,
            base + vec3(0.0, y, -0.35),
            base + vec3(0.0, y, 0.35),
            0.012,
            6,
            false,
            metal,
        );
    }
    let lamp = vec3(0.3, height - 0.05, 0.2);
    s.light = Some(if point_light {
        Light::Point { position: lamp }
    } else {
        Light::Spot {
            position: lamp,
            target: vec3(0.3, 0.0, 0.2),
            fov_deg: ROOM_LIGHT_FOV_DEG,
        }
    });
    s.camera = Some(camera(vec3(3.4, 1.7, 3.5), vec3(-0.3, 0.5, -0.6), 60.0));
    // A walkthrough: along the room, up to the bunny, round to the table and the sculpture.
    let key = |eye: Vec3, target: Vec3| CameraKey { eye, target };
    s.camera_path = Some(CameraPath {
        keys: vec![
            key(vec3(3.4, 1.7, 3.5), vec3(-0.3, 0.5, -0.6)),
            key(vec3(0.5, 1.4, 2.5), vec3(-1.4, 0.4, -1.0)),
            key(vec3(-0.6, 1.0, 0.0), vec3(-1.4, 0.3, -1.0)),
            key(vec3(0.2, 1.3, -0.2), vec3(1.5, 0.8, -1.2)),
            key(vec3(1.0, 1.2, 0.3), vec3(2.2, 0.6, 1.6)),
            key(vec3(-1.0, 1.8, 3.2), vec3(0.5, 0.3, -0.5)),
        ],
    });
    Ok(s)
}

// ---------------------------------------------------------------------------------------
// street

/// The longest street `street` makes (metres).
pub const MAX_STREET_LENGTH: f32 = 20_000.0;
/// Distance between lamp posts along each side of the street (metres).
const LAMP_SPACING: f32 = 25.0;

fn street(p: &Params) -> Result<Scene> {
    let length = p.real("length", 1500.0, 50.0, MAX_STREET_LENGTH)?;
    let seed = p.int("seed", 1, 0, u64::MAX)?;
    let mut rng = Rng::new(seed, 0);
    let mut s = Scene::new("street");
    let asphalt = s.add_material(Material::opaque("road", vec3(0.35, 0.35, 0.37)));
    let pavement = s.add_material(Material::opaque("pavement", vec3(0.70, 0.68, 0.64)));
    let facade = [
        s.add_material(Material::opaque("brick", vec3(0.66, 0.40, 0.32))),
        s.add_material(Material::opaque("stucco", vec3(0.85, 0.80, 0.68))),
        s.add_material(Material::opaque("concrete", vec3(0.62, 0.63, 0.64))),
    ];
    let metal = s.add_material(Material::opaque("lamp posts", vec3(0.20, 0.22, 0.24)));
    let car_colours = [
        s.add_material(Material::opaque("red car", vec3(0.70, 0.12, 0.10))),
        s.add_material(Material::opaque("blue car", vec3(0.15, 0.25, 0.65))),
        s.add_material(Material::opaque("white car", vec3(0.85, 0.85, 0.85))),
    ];
    let (road_half, walk) = (6.0f32, 4.0f32);
    let (z0, z1) = (20.0f32, -length);
    let mid = (z0 + z1) * 0.5;
    let half_len = (z0 - z1) * 0.5;
    // Road, two raised pavements, and the ground beyond the buildings.
    add_plane(&mut s, vec3(0.0, 0.0, mid), road_half, half_len, asphalt);
    for side in [-1.0f32, 1.0] {
        let x = side * (road_half + walk * 0.5);
        add_box(
            &mut s,
            vec3(x - walk * 0.5, 0.0, z1),
            vec3(x + walk * 0.5, 0.15, z0),
            pavement,
        );
        let gx = side * (road_half + walk + 200.0);
        add_plane(&mut s, vec3(gx, 0.0, mid), 200.0, half_len, pavement);
    }
    // Buildings of random widths and heights along both sides.
    for side in [-1.0f32, 1.0] {
        let mut z = z0;
        while z > z1 {
            let w = rng.range(10.0, 28.0).min(z - z1);
            // The sunny side's buildings are lower, so their shadows end on the road in a
            // ragged edge (and the gaps between them let the sun through) rather than
            // covering the whole street.
            let h = if side > 0.0 {
                rng.range(5.0, 18.0)
            } else {
                rng.range(8.0, 40.0)
            };
            let depth = rng.range(12.0, 20.0);
            let gap = if rng.unit() < 0.4 {
                rng.range(5.0, 15.0)
            } else {
                0.0
            };
            let x_in = side * (road_half + walk);
            let x_out = side * (road_half + walk + depth);
            let m = facade[(rng.next_u64() % 3) as usize];
            add_box(
                &mut s,
                vec3(x_in.min(x_out), 0.0, z - w),
                vec3(x_in.max(x_out), h, z),
                m,
            );
            z -= w + gap;
        }
    }
    // Lamp posts on both pavements, their arms over the road.
    let mut z = z0 - 5.0;
    while z > z1 {
        for side in [-1.0f32, 1.0] {
            let x = side * (road_half + 0.6);
            add_cylinder(
                &mut s,
                vec3(x, 0.15, z),
                vec3(x, 6.0, z),
                0.09,
                8,
                false,
                metal,
            );
            add_cylinder(
                &mut s,
                vec3(x, 6.0, z),
                vec3(x - side * 1.5, 6.2, z),
                0.05,
                6,
                false,
                metal,
            );
            let lx = x - side * 1.5;
            add_box(
                &mut s,
                vec3(lx - 0.3, 5.95, z - 0.15),
                vec3(lx + 0.3, 6.2, z + 0.15),
                metal,
            );
        }
        z -= LAMP_SPACING;
    }
    // Parked and driving cars: a body and a cabin each.
    let mut z = z0 - 40.0;
    while z > z1 {
        let lane = if rng.unit() < 0.5 { -3.0 } else { 3.0 };
        let m = car_colours[(rng.next_u64() % 3) as usize];
        add_box(
            &mut s,
            vec3(lane - 0.9, 0.25, z - 2.2),
            vec3(lane + 0.9, 1.0, z + 2.2),
            m,
        );
        add_box(
            &mut s,
            vec3(lane - 0.8, 1.0, z - 1.1),
            vec3(lane + 0.8, 1.5, z + 1.0),
            m,
        );
        z -= rng.range(15.0, 60.0);
    }
    // Light from the right, perpendicular to the view down the street (−Z).
    s.light = Some(Light::Directional {
        to_light: sky_direction(50.0, 90.0),
    });
    s.camera = Some(camera(vec3(-2.0, 1.7, 15.0), vec3(-1.5, 1.2, -100.0), 60.0));
    Ok(s)
}
