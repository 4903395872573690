//! The geometry generators the built-in scenes and the TOML format's generators share:
//! quads, horizontal planes, boxes, UV spheres, cylinders, and whole meshes placed by a
//! transform. Each appends triangles of one material to a [`Scene`] (bounds kept current).

use crate::math::{vec3, Mat4, Vec3};
use crate::scene::{Material, Scene};

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

/// A face of an axis-aligned box, named by its outward normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxFace {
    /// The face at `min.z`.
    NegZ,
    /// The face at `max.z`.
    PosZ,
    /// The face at `min.x`.
    NegX,
    /// The face at `max.x`.
    PosX,
    /// The face at `min.y`.
    NegY,
    /// The face at `max.y`.
    PosY,
}

impl BoxFace {
    /// The order [`add_box`] appends the faces in.
    pub const BUILTIN_ORDER: [BoxFace; 6] = [
        BoxFace::NegZ,
        BoxFace::PosZ,
        BoxFace::NegX,
        BoxFace::PosX,
        BoxFace::NegY,
        BoxFace::PosY,
    ];
    /// The order of the TOML format's `box` generator: +X, −X, +Y, −Y, +Z, −Z (the
    /// triangles its files have always had).
    pub const AXIS_ORDER: [BoxFace; 6] = [
        BoxFace::PosX,
        BoxFace::NegX,
        BoxFace::PosY,
        BoxFace::NegY,
        BoxFace::PosZ,
        BoxFace::NegZ,
    ];
}

/// Appends an axis-aligned box from `min` to `max` (12 triangles, closed, outward-facing).
pub fn add_box(scene: &mut Scene, min: Vec3, max: Vec3, material: u32) {
    add_box_faces(scene, min, max, BoxFace::BUILTIN_ORDER, material);
}

/// Appends the box from `min` to `max` face by face in the order `faces` gives, each face
/// a quad ([`add_quad`]) wound counter-clockwise seen from outside.
pub fn add_box_faces(scene: &mut Scene, min: Vec3, max: Vec3, faces: [BoxFace; 6], material: u32) {
    let d = max - min;
    let (x, y, z) = (
        vec3(d.x, 0.0, 0.0),
        vec3(0.0, d.y, 0.0),
        vec3(0.0, 0.0, d.z),
    );
    for face in faces {
        let (corner, a, b) = match face {
            BoxFace::NegZ => (min, y, x),
            BoxFace::PosZ => (min + z, x, y),
            BoxFace::NegX => (min, z, y),
            BoxFace::PosX => (min + x, y, z),
            BoxFace::NegY => (min, x, z),
            BoxFace::PosY => (min + y, z, x),
        };
        add_quad(scene, corner, a, b, material);
    }
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

/// Appends the TOML format's `sphere` generator: diameter 1 at the origin, `segments`
/// around and `segments / 2` (at least 2) from pole to pole. Unlike [`add_sphere`] it runs
/// round the other way (towards −Z) and splits each cell along its other diagonal, so its
/// triangles are its own: TOML scenes keep the triangles they have always had.
pub fn add_unit_sphere(scene: &mut Scene, segments: u32, material: u32) {
    let rings = (segments / 2).max(2);
    let r = 0.5f32;
    let point = |i: u32, j: u32| {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = std::f32::consts::TAU * (j % segments) as f32 / segments as f32;
        vec3(
            theta.sin() * phi.cos(),
            theta.cos(),
            -theta.sin() * phi.sin(),
        ) * r
    };
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (
                point(i, j),
                point(i + 1, j),
                point(i + 1, j + 1),
                point(i, j + 1),
            );
            if i != 0 {
                scene.push([a, b, d], material);
            }
            if i != rings - 1 {
                scene.push([d, b, c], material);
            }
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

/// Appends every triangle of `src`, moved by `world_from_src`, all of one new material
/// `material` (a mesh recoloured as one object).
pub fn add_mesh_as(dst: &mut Scene, src: &Scene, world_from_src: Mat4, material: Material) {
    let m = dst.add_material(material);
    dst.reserve(src.len());
    for i in 0..src.len() {
        let t = src.triangle(i).map(|p| world_from_src.transform_point3(p));
        dst.push(t, m);
    }
}
