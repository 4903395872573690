//! Scene loaders: every test mesh loads with the triangle count its source gives and
//! renders; ASCII and binary PLY agree bit for bit; glTF hierarchies, instancing, cameras
//! and lights land where the transforms put them; the TOML format's documented example
//! loads as documented; and every malformed input is an error naming the file and the
//! problem — never a panic.

mod support;

use shadowlab::camera::{Camera, Projection};
use shadowlab::compare::compare;
use shadowlab::light::Light;
use shadowlab::math::{vec2, vec3, Mat4, Vec3};
use shadowlab::reference::Reference;
use shadowlab::scene::{self, gltf, obj, ply, Scene};
use shadowlab::techniques::{self, Frame};
use shadowlab::view::ViewSamples;
use std::path::Path;
use support::{data, load, scratch};

/// Image size of the render checks: small, the loaders are under test, not the techniques.
const TEST_WIDTH: u32 = 160;
/// Image height of the render checks.
const TEST_HEIGHT: u32 = 120;
/// Largest share of covered pixels on which the standard shadow map may disagree with the
/// ray-traced reference in the smoke renders: loose, since thin geometry (spokes, fence
/// scrollwork) aliases at the default map size, yet far below what a misplaced light or
/// broken geometry gives.
const SMOKE_MISMATCH_LIMIT: f64 = 0.2;
/// Tolerance on positions that pass through f32 transforms.
const POSITION_TOLERANCE: f32 = 1e-5;

/// Renders `scene` with its own camera (shrunk) and light through `sm` and the reference.
/// Returns (covered pixels, mismatch rate of `sm` against the reference).
fn smoke_render(scene: &Scene) -> (usize, f64) {
    let mut camera: Camera = scene.camera.expect("every loaded scene has a camera");
    let aspect = camera.aspect();
    camera.width = TEST_WIDTH;
    camera.height = ((TEST_WIDTH as f32 / aspect).round() as u32).max(1);
    camera.fit_depth_range(&scene.bounds);
    let light = scene.light.expect("every loaded scene has a light");
    let view = ViewSamples::render(scene, &camera);
    let frame = Frame::new(scene, &camera, &light, &view);
    let shadows = techniques::create("sm").unwrap().render(&frame).unwrap();
    assert_eq!(
        shadows.visibility.value.len(),
        (camera.width * camera.height) as usize
    );
    assert!(shadows
        .visibility
        .value
        .iter()
        .all(|v| v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0));
    let reference = Reference::build(scene).visibility(&frame, &[vec2(0.5, 0.5)]);
    let m = compare(&view, &shadows.visibility, &reference);
    (view.covered_count(), m.mismatch_rate)
}

/// Every mesh in the shared data folder, with the triangle count its source states.
const DATA_MESHES: &[(&str, usize)] = &[
    ("bunny.obj", 3_674),
    ("teapot.obj", 992),
    ("dragon-11k.ply", 11_102),
    ("fence/fence.obj", 19_368),
    ("chessboard/chessboard.obj", 125_810),
    ("bike/bike.obj", 15_120),
    ("gltf/2CylinderEngine.glb", 121_496),
    ("gltf/Cameras.gltf", 2),
    ("gltf/orthographic.gltf", 4),
    ("gltf/BoxTextured.glb", 12),
    ("lenient/edges.obj", 8),
    ("lenient/lines.gltf", 3),
    ("masked/leaf.gltf", 4),
    ("masked/cards.obj", 6),
    ("masked/cards-zup.obj", 6),
    ("masked/cards.gltf", 6),
];

#[test]
fn every_data_mesh_loads_with_its_triangle_count_and_renders() {
    // The list above must name every mesh in the folder (outside `bad/`).
    let mut found = Vec::new();
    let mut stack = vec![data("")];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                if p.file_name().unwrap() != "bad" {
                    stack.push(p);
                }
            } else if matches!(
                p.extension().and_then(|e| e.to_str()),
                Some("obj" | "ply" | "gltf" | "glb")
            ) {
                found.push(
                    p.strip_prefix(data(""))
                        .unwrap()
                        .to_string_lossy()
                        .replace('\\', "/"),
                );
            }
        }
    }
    found.sort();
    let mut listed: Vec<String> = DATA_MESHES.iter().map(|(n, _)| n.to_string()).collect();
    listed.sort();
    assert_eq!(found, listed, "the data folder and DATA_MESHES differ");

    for &(name, triangles) in DATA_MESHES {
        let path = data(name);
        let raw = match path.extension().unwrap().to_str().unwrap() {
            "obj" => obj::load(&path),
            "ply" => ply::load(&path),
            _ => gltf::load(&path),
        }
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(raw.len(), triangles, "{name}: triangle count");
        let s = load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        // A bare mesh gains a two-triangle ground plane; a glTF with a camera does not.
        let bare = raw.camera.is_none() && raw.light.is_none();
        // Loading drops faces that repeat an earlier opaque face exactly; counted here
        // by brute force over the raw file.
        let mut opaque_faces = std::collections::HashSet::new();
        let mut repeats = 0;
        for i in 0..raw.len() {
            let t = raw.triangle(i);
            let key = [t[0], t[1], t[2]].map(|v| v.to_array().map(f32::to_bits));
            if opaque_faces.contains(&key) {
                repeats += 1;
            } else if raw.material_of(i).is_opaque() {
                opaque_faces.insert(key);
            }
        }
        assert_eq!(
            s.len(),
            triangles - repeats + if bare { 2 } else { 0 },
            "{name}: triangles after framing"
        );
        let (covered, mismatch) = smoke_render(&s);
        let pixels = (TEST_WIDTH * TEST_HEIGHT) as usize;
        assert!(
            covered > pixels / 50,
            "{name}: only {covered} pixels covered"
        );
        assert!(
            mismatch < SMOKE_MISMATCH_LIMIT,
            "{name}: sm mismatch {mismatch} against the reference"
        );
        println!(
            "{name}: {} triangles, {covered} px covered, sm mismatch {mismatch:.4}",
            s.len()
        );
    }
}

// ---------------------------------------------------------------------------------- PLY

/// The dragon's vertices and its first `n` faces, read from its ASCII text.
fn dragon_part(n: usize) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let text = std::fs::read_to_string(data("dragon-11k.ply")).unwrap();
    let (header, body) = text.split_once("end_header\n").unwrap();
    let count = |el: &str| -> usize {
        let line = header
            .lines()
            .find(|l| l.starts_with(&format!("element {el} ")))
            .unwrap();
        line.rsplit(' ').next().unwrap().parse().unwrap()
    };
    let (nv, nf) = (count("vertex"), count("face"));
    assert!(n <= nf);
    let mut lines = body.lines();
    let verts: Vec<[f32; 3]> = (0..nv)
        .map(|_| {
            let v: Vec<f32> = lines
                .next()
                .unwrap()
                .split_whitespace()
                .map(|t| t.parse().unwrap())
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let faces = (0..n)
        .map(|_| {
            let v: Vec<u32> = lines
                .next()
                .unwrap()
                .split_whitespace()
                .map(|t| t.parse().unwrap())
                .collect();
            assert_eq!(v[0], 3);
            [v[1], v[2], v[3]]
        })
        .collect();
    (verts, faces)
}

fn ascii_ply(verts: &[[f32; 3]], faces: &[Vec<i64>]) -> Vec<u8> {
    let mut s = format!(
        "ply\nformat ascii 1.0\ncomment test\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        verts.len(),
        faces.len()
    );
    for v in verts {
        // `{:?}` prints the shortest text that reads back as the same f32.
        s += &format!("{:?} {:?} {:?}\n", v[0], v[1], v[2]);
    }
    for f in faces {
        s += &f.len().to_string();
        for i in f {
            s += &format!(" {i}");
        }
        s += "\n";
    }
    s.into_bytes()
}

/// A binary PLY: little-endian float positions with `uchar`/`int` lists, or big-endian
/// double positions with an extra colour property and `ushort`/`uint` lists named
/// `vertex_index`.
fn binary_ply(verts: &[[f32; 3]], faces: &[Vec<i64>], big_endian_doubles: bool) -> Vec<u8> {
    let mut out = Vec::new();
    let header = if big_endian_doubles {
        format!(
            "ply\nformat binary_big_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\n\
             property double z\nproperty uchar red\nelement face {}\nproperty list ushort uint vertex_index\nend_header\n",
            verts.len(),
            faces.len()
        )
    } else {
        format!(
            "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
             property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
            verts.len(),
            faces.len()
        )
    };
    out.extend_from_slice(header.as_bytes());
    for v in verts {
        for c in v {
            if big_endian_doubles {
                out.extend_from_slice(&(*c as f64).to_be_bytes());
            } else {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        if big_endian_doubles {
            out.push(200);
        }
    }
    for f in faces {
        if big_endian_doubles {
            out.extend_from_slice(&(f.len() as u16).to_be_bytes());
            for &i in f {
                out.extend_from_slice(&(i as u32).to_be_bytes());
            }
        } else {
            out.push(f.len() as u8);
            for &i in f {
                out.extend_from_slice(&(i as i32).to_le_bytes());
            }
        }
    }
    out
}

fn same_triangles(a: &Scene, b: &Scene) {
    assert_eq!(a.len(), b.len());
    for i in 0..a.len() {
        let (ta, tb) = (a.triangle(i), b.triangle(i));
        for k in 0..3 {
            assert_eq!(
                ta[k].to_array().map(f32::to_bits),
                tb[k].to_array().map(f32::to_bits),
                "triangle {i}"
            );
        }
    }
}

#[test]
fn ascii_and_binary_ply_give_identical_triangles() {
    let dir = scratch("ply-formats");
    let (verts, faces) = dragon_part(3000);
    let faces: Vec<Vec<i64>> = faces
        .iter()
        .map(|f| f.iter().map(|&i| i as i64).collect())
        .collect();
    let paths = [
        ("ascii.ply", ascii_ply(&verts, &faces)),
        ("le.ply", binary_ply(&verts, &faces, false)),
        ("be.ply", binary_ply(&verts, &faces, true)),
    ];
    let mut scenes = Vec::new();
    for (name, bytes) in &paths {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        scenes.push(ply::load(&p).unwrap_or_else(|e| panic!("{name}: {e}")));
    }
    assert_eq!(scenes[0].len(), 3000);
    same_triangles(&scenes[0], &scenes[1]);
    same_triangles(&scenes[0], &scenes[2]);
    // And the ASCII subset matches the original file's first faces.
    let full = ply::load(&data("dragon-11k.ply")).unwrap();
    for i in 0..3000 {
        assert_eq!(full.triangle(i), scenes[0].triangle(i));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ply_polygons_are_fan_triangulated() {
    let dir = scratch("ply-fan");
    let verts = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 1.5, 0.0],
    ];
    // A quad, a pentagon, and a two-vertex face that holds no area.
    let faces = vec![vec![0, 1, 2, 3], vec![0, 1, 2, 4, 3], vec![0, 1]];
    for binary in [false, true] {
        let p = dir.join(format!("fan{binary}.ply"));
        std::fs::write(
            &p,
            if binary {
                binary_ply(&verts, &faces, false)
            } else {
                ascii_ply(&verts, &faces)
            },
        )
        .unwrap();
        let s = ply::load(&p).unwrap();
        assert_eq!(s.len(), 2 + 3);
        let v = |i: usize| Vec3::from(verts[i]);
        assert_eq!(s.triangle(0), [v(0), v(1), v(2)]);
        assert_eq!(s.triangle(1), [v(0), v(2), v(3)]);
        assert_eq!(s.triangle(4), [v(0), v(4), v(3)]);
        // The fans cover the polygons' areas exactly.
        let area: f32 = (0..s.len())
            .map(|i| {
                let t = s.triangle(i);
                (t[1] - t[0]).cross(t[2] - t[0]).length() * 0.5
            })
            .sum();
        assert!((area - (1.0 + 1.25)).abs() < 1e-6, "area {area}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

// --------------------------------------------------------------------------------- glTF

fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The unit square [0,1]² at z = 0 as two indexed triangles: 6 `u16` indices (12 bytes),
/// then 4 `f32` positions (48 bytes).
fn square_buffer() -> Vec<u8> {
    let mut b = Vec::new();
    for i in [0u16, 1, 2, 0, 2, 3] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    for p in [
        [0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ] {
        for c in p {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    b
}

/// A glTF document around the square mesh; `extra` adds top-level members and `nodes`
/// gives the hierarchy (root nodes are listed in `roots`).
fn gltf_json(uri: &str, nodes: &str, roots: &str, extra: &str) -> String {
    format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "scene": 0,
  "scenes": [ {{ "nodes": {roots} }} ],
  "nodes": {nodes},
  "meshes": [ {{ "name": "square", "primitives": [ {{ "attributes": {{ "POSITION": 1 }}, "indices": 0, "material": 0 }} ] }} ],
  "materials": [ {{ "name": "glass", "alphaMode": "BLEND", "pbrMetallicRoughness": {{ "baseColorFactor": [0.2, 0.4, 0.6, 0.25] }} }} ],
  "buffers": [ {{ "uri": "{uri}", "byteLength": 60 }} ],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 12, "target": 34963 }},
    {{ "buffer": 0, "byteOffset": 12, "byteLength": 48, "target": 34962 }}
  ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5123, "count": 6, "type": "SCALAR" }},
    {{ "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0,0,0], "max": [1,1,0] }}
  ]{extra}
}}"#
    )
}

#[test]
fn gltf_hierarchy_composes_transforms_and_instances_meshes() {
    let dir = scratch("gltf-hierarchy");
    std::fs::write(dir.join("square.bin"), square_buffer()).unwrap();
    // Parent: translate by (10, 0, 0). Child A: scale 2 (TRS). Child B: a matrix that
    // translates by (0, 5, 0). Both children instance the same mesh.
    let nodes = r#"[
        { "translation": [10, 0, 0], "children": [1, 2] },
        { "scale": [2, 2, 2], "mesh": 0 },
        { "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,5,0,1], "mesh": 0 }
    ]"#;
    let data_uri = format!(
        "data:application/octet-stream;base64,{}",
        base64(&square_buffer())
    );
    for (file, uri) in [
        ("external.gltf", "square.bin"),
        ("embedded.gltf", data_uri.as_str()),
    ] {
        let p = dir.join(file);
        std::fs::write(&p, gltf_json(uri, nodes, "[0]", "")).unwrap();
        let s = gltf::load(&p).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(s.len(), 4, "{file}");
        assert!(
            (s.bounds.min - vec3(10.0, 0.0, 0.0)).length() < POSITION_TOLERANCE,
            "{file}: {:?}",
            s.bounds
        );
        assert!(
            (s.bounds.max - vec3(12.0, 6.0, 0.0)).length() < POSITION_TOLERANCE,
            "{file}: {:?}",
            s.bounds
        );
        // Instance A spans [10,12]×[0,2]; instance B spans [10,11]×[5,6].
        assert_eq!(
            s.triangle(0),
            [
                vec3(10.0, 0.0, 0.0),
                vec3(12.0, 0.0, 0.0),
                vec3(12.0, 2.0, 0.0)
            ]
        );
        assert_eq!(
            s.triangle(2),
            [
                vec3(10.0, 5.0, 0.0),
                vec3(11.0, 5.0, 0.0),
                vec3(11.0, 6.0, 0.0)
            ]
        );
        // One material, shared by both instances: BLEND alpha 0.25 lets 75% through.
        assert_eq!(s.materials.len(), 1);
        assert!(s.material.iter().all(|&m| m == 0));
        assert_eq!(s.materials[0].color, vec3(0.2, 0.4, 0.6));
        assert_eq!(s.materials[0].transmittance, Vec3::splat(0.75));
        assert!(s.camera.is_none() && s.light.is_none());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gltf_cameras_file_uses_its_perspective_camera() {
    let s = load(&data("gltf/Cameras.gltf")).unwrap();
    let c = s.camera.unwrap();
    // Node 1: translation (0.5, 0.5, 3), no rotation: looking down −Z with +Y up.
    assert!((c.eye - vec3(0.5, 0.5, 3.0)).length() < POSITION_TOLERANCE);
    assert!((c.forward() - Vec3::NEG_Z).length() < POSITION_TOLERANCE);
    assert!((c.up - Vec3::Y).length() < POSITION_TOLERANCE);
    assert!((c.fov_y_deg - 0.7f32.to_degrees()).abs() < 1e-4);
    // aspectRatio 1 keeps the height of 768.
    assert_eq!((c.width, c.height), (768, 768));
    assert_eq!((c.near, c.far), (0.01, 100.0));
    // A file with its own camera gets no ground plane; the missing light is supplied.
    assert_eq!(s.len(), 2);
    assert!(s.light.is_some());
    // The square (rotated about X by −45°) is in view.
    let (covered, _) = smoke_render(&s);
    assert!(covered > 1000, "{covered}");
}

#[test]
fn gltf_orthographic_camera_loads_as_orthographic() {
    let dir = scratch("gltf-ortho");
    std::fs::copy(data("gltf/simpleSquare.bin"), dir.join("simpleSquare.bin")).unwrap();
    // Cameras.gltf with the perspective camera node dropped, leaving the orthographic one.
    let text = std::fs::read_to_string(data("gltf/Cameras.gltf")).unwrap();
    let text = text.replace(r#""nodes" : [ 0, 1, 2 ]"#, r#""nodes" : [ 0, 2 ]"#);
    assert!(text.contains(r#"[ 0, 2 ]"#));
    let p = dir.join("ortho.gltf");
    std::fs::write(&p, text).unwrap();
    let s = gltf::load(&p).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let c = s.camera.unwrap();
    assert_eq!(
        c.projection,
        Projection::Orthographic {
            xmag: 1.0,
            ymag: 1.0
        }
    );
    // xmag = ymag = 1: a square image; the file's znear and zfar.
    assert_eq!((c.width, c.height), (768, 768));
    assert_eq!((c.near, c.far), (0.01, 100.0));
    assert!((c.forward() - Vec3::NEG_Z).length() < POSITION_TOLERANCE);
    // At every depth the orthographic rectangle (±xmag, ±ymag around the axis through
    // (0.5, 0.5)) fills the image exactly, and every primary ray runs along the axis.
    let m = c.clip_from_world();
    for z in [2.5, 0.0, -40.0] {
        for (dx, dy, u, v) in [
            (-1.0, -1.0, 0.0, 1.0),
            (1.0, 1.0, 1.0, 0.0),
            (1.0, -1.0, 1.0, 1.0),
        ] {
            let q = m * vec3(0.5 + dx, 0.5 + dy, z).extend(1.0);
            assert_eq!(q.w, 1.0);
            let (pu, pv) = (q.x * 0.5 + 0.5, 0.5 - q.y * 0.5);
            assert!(
                (pu - u).abs() < 1e-4 && (pv - v).abs() < 1e-4,
                "corner ({dx},{dy}) at depth {z}: ({pu},{pv})"
            );
            let (o, d) = c.ray(u * 768.0, v * 768.0);
            assert_eq!(d, c.forward());
            assert!((o - vec3(0.5 + dx, 0.5 + dy, 3.0)).length() < 1e-4, "{o}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gltf_punctual_lights_follow_their_nodes() {
    let dir = scratch("gltf-lights");
    std::fs::write(dir.join("square.bin"), square_buffer()).unwrap();
    // Rotation of −90° about X (quaternion x = −sin 45°, w = cos 45°): the node's −Z turns
    // to −Y, so a light on it shines straight down.
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let lights = r#",
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": { "KHR_lights_punctual": { "lights": [
      { "type": "directional" },
      { "type": "spot", "spot": { "outerConeAngle": 0.5 } },
      { "type": "point" }
  ] } }"#;
    for (index, expect) in [
        (0, Light::Directional { to_light: Vec3::Y }),
        (
            1,
            Light::Spot {
                position: vec3(1.0, 4.0, 2.0),
                target: vec3(1.0, 3.0, 2.0),
                fov_deg: 1.0f32.to_degrees(),
            },
        ),
        (
            2,
            Light::Point {
                position: vec3(1.0, 4.0, 2.0),
            },
        ),
    ] {
        let nodes = format!(
            r#"[
            {{ "mesh": 0 }},
            {{ "translation": [1, 4, 2], "rotation": [{}, 0, 0, {h}], "extensions": {{ "KHR_lights_punctual": {{ "light": {index} }} }} }},
            {{ "translation": [0, 9, 9], "extensions": {{ "KHR_lights_punctual": {{ "light": 2 }} }} }}
        ]"#,
            -h
        );
        let p = dir.join(format!("light{index}.gltf"));
        std::fs::write(&p, gltf_json("square.bin", &nodes, "[0, 1, 2]", lights)).unwrap();
        let s = gltf::load(&p).unwrap_or_else(|e| panic!("light {index}: {e}"));
        let got = s.light.unwrap();
        // The first light node in the walk wins (node 1, not node 2).
        match (got, expect) {
            (Light::Directional { to_light: a }, Light::Directional { to_light: b }) => {
                assert!((a - b).length() < POSITION_TOLERANCE, "{a}")
            }
            (
                Light::Spot {
                    position: p1,
                    target: t1,
                    fov_deg: f1,
                },
                Light::Spot {
                    position: p2,
                    target: t2,
                    fov_deg: f2,
                },
            ) => {
                assert!(
                    (p1 - p2).length() < POSITION_TOLERANCE
                        && (t1 - t2).length() < POSITION_TOLERANCE
                );
                assert!((f1 - f2).abs() < 1e-4);
            }
            (Light::Point { position: a }, Light::Point { position: b }) => {
                assert!((a - b).length() < POSITION_TOLERANCE)
            }
            (g, e) => panic!("light {index}: got {g:?}, expected {e:?}"),
        }
        // Its own light and no camera: framed, but no ground plane is added.
        let framed = load(&p).unwrap();
        assert_eq!(framed.len(), 2);
        assert_eq!(framed.light, s.light);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gltf_textures_are_never_needed() {
    // BoxTextured.glb embeds its image; the .gltf copy below names one that is missing.
    let dir = scratch("gltf-textures");
    std::fs::write(dir.join("square.bin"), square_buffer()).unwrap();
    let extra = r#",
  "images": [ { "uri": "missing-texture.png" } ],
  "textures": [ { "source": 0 } ]"#;
    let json = gltf_json("square.bin", r#"[ { "mesh": 0 } ]"#, "[0]", extra).replace(
        r#""baseColorFactor""#,
        r#""baseColorTexture": { "index": 0 }, "baseColorFactor""#,
    );
    let p = dir.join("textured.gltf");
    std::fs::write(&p, json).unwrap();
    assert_eq!(gltf::load(&p).unwrap().len(), 2);
    assert_eq!(gltf::load(&data("gltf/BoxTextured.glb")).unwrap().len(), 12);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `err.to_string()` must name the file and contain every one of `words`.
fn assert_names(err: &shadowlab::Error, file: &str, words: &[&str]) {
    let msg = err.to_string();
    assert!(msg.contains(file), "{msg:?} does not name {file}");
    for w in words {
        assert!(msg.contains(w), "{msg:?} does not mention {w:?}");
    }
    assert!(err.is_bad_input(), "{msg}");
}

#[test]
fn bad_gltf_files_give_clear_errors() {
    for (file, words) in [
        (
            "bad/index-out-of-range/IndexOutOfRange.gltf",
            // The index's value is not echoed: it is the file's bytes.
            &["mesh 0", "primitive 0", "index", "out of range"][..],
        ),
        (
            "bad/index-out-of-range/AllIndicesOutOfRange.gltf",
            &["mesh 0", "primitive 0", "index", "out of range"],
        ),
        (
            "bad/missing-bin/BoxTextured.gltf",
            &["BoxTextured0.bin", "does not exist"],
        ),
        (
            "bad/BoxWithInfinites.glb",
            &["mesh 0", "vertex 0", "non-finite"],
        ),
    ] {
        let e = load(&data(file)).expect_err(file);
        let name = Path::new(file).file_name().unwrap().to_str().unwrap();
        assert_names(&e, name, words);
        println!("{file}: {e}");
    }
}

// ---------------------------------------------------------------------------- malformed

#[test]
fn malformed_inputs_give_errors_naming_the_file() {
    let dir = scratch("malformed");
    let (verts, faces) = dragon_part(40);
    let faces: Vec<Vec<i64>> = faces
        .iter()
        .map(|f| f.iter().map(|&i| i as i64).collect())
        .collect();
    let ascii = ascii_ply(&verts, &faces);
    let binary = binary_ply(&verts, &faces, false);
    let header_len = ascii
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap();
    let bin_header_len = binary
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let mut nan_ascii = ascii_ply(
        &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[vec![0, 1, 2]],
    );
    let text = String::from_utf8(nan_ascii.clone())
        .unwrap()
        .replace("\n1.0 0.0 0.0\n", "\nnan 0.0 0.0\n");
    nan_ascii = text.into_bytes();
    let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let nan_binary = binary_ply(
        &[tri[0], [f32::NAN, 0.0, 0.0], tri[2]],
        &[vec![0, 1, 2]],
        false,
    );
    let huge_ascii = String::from_utf8(ascii_ply(&tri, &[vec![0, 1, 2]]))
        .unwrap()
        .replace("\n1.0 0.0 0.0\n", "\n1e39 0.0 0.0\n")
        .into_bytes();
    // The ASCII body cut cleanly after face 9's line.
    let body_start = header_len + 11;
    let mut cut = body_start;
    for _ in 0..verts.len() + 10 {
        cut += ascii[cut..].iter().position(|&b| b == b'\n').unwrap() + 1;
    }
    let cases: Vec<(&str, Vec<u8>, Vec<&str>)> = vec![
        ("header-cut.ply", ascii[..header_len / 2].to_vec(), vec!["header"]),
        ("body-cut.ply", ascii[..cut].to_vec(), vec!["face 10", "truncated"]),
        ("line-cut.ply", ascii[..cut + 4].to_vec(), vec!["face 10"]),
        ("binary-cut.ply", binary[..bin_header_len + verts.len() * 12 + 13 * 10 + 5].to_vec(), vec!["face 10", "truncated"]),
        ("index-range.ply", ascii_ply(&tri, &[vec![0, 1, 2], vec![0, 1, 9]]), vec!["face 1", "vertex 9"]),
        ("negative-index.ply", ascii_ply(&tri, &[vec![0, -1, 2]]), vec!["face 0", "vertex -1"]),
        ("nan-ascii.ply", nan_ascii, vec!["vertex 1"]),
        ("nan-binary.ply", nan_binary, vec!["vertex 1", "non-finite"]),
        ("overflow.ply", huge_ascii, vec!["vertex 1", "non-finite"]),
        ("no-faces.ply", ascii_ply(&tri, &[]), vec!["no triangles"]),
        ("point-cloud.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n".to_vec(), vec!["face"]),
        ("truncated.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4".to_vec(), vec!["line 6", "fewer than 3"]),
        ("cut-number.obj", b"v 0 0 0\nv 1 0 0\nv 0 1".to_vec(), vec!["OBJ"]),
        ("nan.obj", b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(), vec!["vertex 2", "non-finite"]),
        ("index-range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n".to_vec(), vec!["index"]),
        ("empty.obj", Vec::new(), vec!["no triangles"]),
        ("empty.gltf", br#"{"asset":{"version":"2.0"}}"#.to_vec(), vec!["no triangles"]),
        ("not-json.gltf", b"{ \"asset\": ".to_vec(), vec!["JSON"]),
        ("cut.glb", std::fs::read(data("gltf/BoxTextured.glb")).unwrap()[..1000].to_vec(), vec!["GLB"]),
        ("unknown-key.toml", b"[[mesh]]\ngenerator = \"box\"\ncolour = [1, 0, 0]\n".to_vec(), vec!["line 3", "colour"]),
        ("missing-mesh.toml", b"[[mesh]]\nfile = \"nowhere/gone.obj\"\n".to_vec(), vec!["[[mesh]] 1", "gone.obj", "does not exist"]),
        ("no-mesh.toml", b"[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n".to_vec(), vec!["[[mesh]]"]),
        ("bad-value.toml", b"[[mesh]]\ngenerator = \"box\"\nopacity = 1.5\n".to_vec(), vec!["[[mesh]] 1", "opacity"]),
        ("bad-light.toml", b"[[mesh]]\ngenerator = \"box\"\n[light]\nkind = \"point\"\nposition = [0, 3, 0]\nfov_deg = 30\n".to_vec(), vec!["[light]", "fov_deg"]),
        ("pace-alone.toml", b"[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\npace = 10\n[[mesh]]\ngenerator = \"box\"\n".to_vec(), vec!["[camera]", "pace", "path"]),
        ("pace-one.toml", b"[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\npath = [{ eye = [0, 0, 5], target = [0, 0, 0] }]\npace = 1\n[[mesh]]\ngenerator = \"box\"\n".to_vec(), vec!["[camera]", "pace", "1"]),
        ("bad-kind.toml", b"[[mesh]]\ngenerator = \"box\"\n[light]\nkind = \"area\"\n".to_vec(), vec!["line 4", "area"]),
        ("unknown-generator.toml", b"[[mesh]]\ngenerator = \"teapotz\"\n".to_vec(), vec!["[[mesh]] 1", "teapotz"]),
        ("bad-param.toml", b"[[mesh]]\ngenerator = \"sphere\"\nparams = { rings = 3 }\n".to_vec(), vec!["[[mesh]] 1", "rings", "segments"]),
        ("nested.toml", b"[[mesh]]\nfile = \"unknown-key.toml\"\n".to_vec(), vec!["another scene file"]),
        ("bad-inner.toml", b"[[mesh]]\nfile = \"nan.obj\"\n".to_vec(), vec!["[[mesh]] 1", "nan.obj", "non-finite"]),
    ];
    for (name, bytes, _) in &cases {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    for (name, _, words) in &cases {
        let e = load(&dir.join(name)).expect_err(name);
        assert_names(&e, name, words);
        println!("{name}: {e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Corrupted versions tried per source file (half truncated, half with flipped bytes).
const CORRUPTION_TRIALS: usize = 300;

/// A deterministic SplitMix64 stream for the corruption test.
struct SplitMix(u64);
impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

#[test]
fn truncated_and_corrupted_files_never_panic() {
    let dir = scratch("corrupt");
    let (verts, faces) = dragon_part(200);
    let faces: Vec<Vec<i64>> = faces
        .iter()
        .map(|f| f.iter().map(|&i| i as i64).collect())
        .collect();
    let glb = std::fs::read(data("gltf/BoxTextured.glb")).unwrap();
    let gltf_text = gltf_json("square.bin", r#"[ { "mesh": 0 } ]"#, "[0]", "").into_bytes();
    std::fs::write(dir.join("square.bin"), square_buffer()).unwrap();
    let obj = std::fs::read(data("teapot.obj")).unwrap();
    let sources: Vec<(&str, Vec<u8>)> = vec![
        ("a.ply", ascii_ply(&verts, &faces)),
        ("b.ply", binary_ply(&verts, &faces, false)),
        ("c.ply", binary_ply(&verts, &faces, true)),
        ("d.glb", glb),
        ("e.gltf", gltf_text),
        ("f.obj", obj[..obj.len().min(6000)].to_vec()),
    ];
    let mut rng = SplitMix(7);
    let (mut ok, mut err) = (0, 0);
    for (name, bytes) in &sources {
        let p = dir.join(name);
        for trial in 0..CORRUPTION_TRIALS {
            let mut b = bytes.clone();
            if trial % 2 == 0 {
                b.truncate((rng.next() % b.len() as u64) as usize);
            } else {
                for _ in 0..1 + rng.next() % 4 {
                    let k = (rng.next() % b.len() as u64) as usize;
                    b[k] = rng.next() as u8;
                }
            }
            std::fs::write(&p, &b).unwrap();
            match load(&p) {
                Ok(s) => {
                    s.validate().unwrap();
                    ok += 1;
                }
                Err(e) => {
                    assert!(e.to_string().contains(name), "{e}");
                    err += 1;
                }
            }
        }
    }
    println!("corrupted inputs: {ok} still loaded, {err} refused");
    assert!(err > 0);
    let _ = std::fs::remove_dir_all(&dir);
}

// --------------------------------------------------------------------------------- TOML

/// The example in the TOML module's documentation, taken from its source.
fn documented_example() -> String {
    let src = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/src/scene/toml/mod.rs"
    ))
    .unwrap();
    let mut out = String::new();
    let mut inside = false;
    for line in src.lines() {
        let Some(doc) = line.strip_prefix("//!") else {
            continue;
        };
        let doc = doc.strip_prefix(' ').unwrap_or(doc);
        if doc.starts_with("```") {
            if inside {
                break;
            }
            inside = doc == "```toml";
            continue;
        }
        if inside {
            out += doc;
            out += "\n";
        }
    }
    assert!(out.contains("[[mesh]]"));
    out
}

#[test]
fn toml_documented_example_loads_as_documented() {
    let dir = scratch("toml-example");
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::copy(data("bunny.obj"), dir.join("meshes/bunny.obj")).unwrap();
    let p = dir.join("scene.toml");
    std::fs::write(&p, documented_example()).unwrap();
    let s = load(&p).unwrap();
    assert_eq!(s.name, "bunny on a slab");
    // box 12 + bunny 3674 + sphere (48 around, 24 rings: 2·48·23) + plane 2; no ground added.
    assert_eq!(s.len(), 12 + 3674 + 2 * 48 * 23 + 2);
    let c = s.camera.unwrap();
    assert_eq!(
        (c.eye, c.target, c.fov_y_deg, c.width, c.height),
        (vec3(0.0, 1.2, 3.0), vec3(0.0, 0.3, 0.0), 45.0, 1024, 768)
    );
    assert_eq!((c.near, c.far), (0.05, 20.0));
    assert_eq!(s.camera_path.as_ref().unwrap().keys.len(), 2);
    assert_eq!(s.camera_path.as_ref().unwrap().pace, Some(48));
    assert_eq!(
        s.light,
        Some(Light::Spot {
            position: vec3(1.5, 3.0, 1.0),
            target: Vec3::ZERO,
            fov_deg: 60.0
        })
    );
    // The slab: the unit cube scaled to 2 × 0.1 × 1.2 and lowered by 0.05.
    let mut top = shadowlab::math::Aabb::EMPTY;
    for i in 0..12 {
        for p in s.triangle(i) {
            top.grow(p);
        }
    }
    assert!(
        (top.min - vec3(-1.0, -0.1, -0.6)).length() < POSITION_TOLERANCE,
        "{top:?}"
    );
    assert!(
        (top.max - vec3(1.0, 0.0, 0.6)).length() < POSITION_TOLERANCE,
        "{top:?}"
    );
    let m = s.material_of(0);
    assert_eq!((m.name.as_str(), m.color), ("slab", vec3(0.6, 0.45, 0.3)));
    // The sphere: opacity 0.4 lets 60% through.
    let sphere = s.material_of(12 + 3674);
    assert!((sphere.transmittance - Vec3::splat(0.6)).length() < 1e-6);
    // The plane spans 8 × 8 at y = −0.6.
    let n = s.len();
    let plane = [s.triangle(n - 2), s.triangle(n - 1)];
    assert!(plane
        .iter()
        .flatten()
        .all(|p| p.y == -0.6 && p.x.abs() == 4.0 && p.z.abs() == 4.0));
    let (covered, _) = smoke_render(&s);
    assert!(covered > 1000);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn toml_transforms_match_their_definition() {
    let dir = scratch("toml-transform");
    std::fs::copy(data("teapot.obj"), dir.join("teapot.obj")).unwrap();
    let teapot = obj::load(&dir.join("teapot.obj")).unwrap();
    let text = r#"
        [[mesh]]
        file = "teapot.obj"
        scale = [2.0, 3.0, 0.5]
        rotate_deg = [30.0, 45.0, 60.0]
        translate = [1.0, -2.0, 3.0]
        [[mesh]]
        file = "teapot.obj"
        rotate_axis = [0.0, 1.0, 0.0]
        rotate_angle_deg = 90.0
        [light]
        kind = "directional"
        direction = [0.0, -2.0, 0.0]
    "#;
    let p = dir.join("t.toml");
    std::fs::write(&p, text).unwrap();
    let s = load(&p).unwrap();
    assert_eq!(s.len(), 2 * teapot.len());
    assert_eq!(s.light, Some(Light::Directional { to_light: Vec3::Y }));
    // Scale, then X, Y, Z rotations about the world axes, then the translation.
    let r = Mat4::from_rotation_z(60f32.to_radians())
        * Mat4::from_rotation_y(45f32.to_radians())
        * Mat4::from_rotation_x(30f32.to_radians());
    let m =
        Mat4::from_translation(vec3(1.0, -2.0, 3.0)) * r * Mat4::from_scale(vec3(2.0, 3.0, 0.5));
    let y90 = Mat4::from_rotation_y(90f32.to_radians());
    for i in 0..teapot.len() {
        for k in 0..3 {
            let want = m.transform_point3(teapot.triangle(i)[k]);
            assert!((s.triangle(i)[k] - want).length() < 1e-4, "triangle {i}");
            let want = y90.transform_point3(teapot.triangle(i)[k]);
            assert!(
                (s.triangle(teapot.len() + i)[k] - want).length() < 1e-4,
                "triangle {i}"
            );
        }
    }
    // No camera given: one is framed automatically.
    assert!(s.camera.is_some());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn toml_generator_falls_back_to_builtin_scenes() {
    let dir = scratch("toml-builtin");
    let p = dir.join("b.toml");
    std::fs::write(
        &p,
        "[[mesh]]\ngenerator = \"bunny\"\ntranslate = [0.0, 10.0, 0.0]\n",
    )
    .unwrap();
    let s = load(&p).unwrap();
    let builtin = scene::builtin::generate("bunny", &Default::default()).unwrap();
    // The built-in scene's triangles and materials, moved; its camera and light are not
    // taken over (the framed camera differs from the built-in one).
    assert_eq!(s.len(), builtin.len());
    assert_eq!(s.materials.len(), builtin.materials.len());
    for i in [0, builtin.len() / 2, builtin.len() - 1] {
        for k in 0..3 {
            assert_eq!(
                s.triangle(i)[k],
                builtin.triangle(i)[k] + vec3(0.0, 10.0, 0.0)
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gltf_quantized_sparse_positions_and_strips_decode_exactly() {
    let dir = scratch("gltf-sparse");
    // Four normalized u16 positions with a stride of 8 bytes, then a sparse entry that
    // replaces vertex 3 by (1, 1, 1): a u8 index and three u16 values.
    let mut b = Vec::new();
    for p in [
        [0u16, 0, 0],
        [65535, 0, 0],
        [0, 65535, 0],
        [65535, 65535, 0],
    ] {
        for c in p {
            b.extend_from_slice(&c.to_le_bytes());
        }
        b.extend_from_slice(&[0, 0]);
    }
    b.extend_from_slice(&[3, 0, 0, 0]);
    for c in [65535u16; 3] {
        b.extend_from_slice(&c.to_le_bytes());
    }
    b.extend_from_slice(&[0, 0]);
    assert_eq!(b.len(), 44);
    std::fs::write(dir.join("q.bin"), &b).unwrap();
    let json = r#"{
  "asset": { "version": "2.0" },
  "scenes": [ { "nodes": [0] } ],
  "nodes": [ { "mesh": 0 } ],
  "meshes": [ { "primitives": [
      { "attributes": { "POSITION": 0 }, "mode": 5 },
      { "attributes": { "POSITION": 0 }, "mode": 6 },
      { "attributes": { "POSITION": 0 }, "mode": 1 }
  ] } ],
  "buffers": [ { "uri": "q.bin", "byteLength": 44 } ],
  "bufferViews": [
    { "buffer": 0, "byteOffset": 0, "byteLength": 32, "byteStride": 8 },
    { "buffer": 0, "byteOffset": 32, "byteLength": 1 },
    { "buffer": 0, "byteOffset": 36, "byteLength": 6 }
  ],
  "accessors": [ {
    "bufferView": 0, "componentType": 5123, "normalized": true, "count": 4, "type": "VEC3",
    "min": [0, 0, 0], "max": [1, 1, 1],
    "sparse": { "count": 1, "indices": { "bufferView": 1, "componentType": 5121 }, "values": { "bufferView": 2 } }
  } ]
}"#;
    let p = dir.join("q.gltf");
    std::fs::write(&p, json).unwrap();
    let s = gltf::load(&p).unwrap();
    let (v0, v1, v2, v3) = (Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE);
    // Strip: (0,1,2), then (2,1,3) to keep the winding; fan: (0,1,2), (0,2,3); the LINES
    // primitive adds nothing.
    assert_eq!(s.len(), 4);
    assert_eq!(s.triangle(0), [v0, v1, v2]);
    assert_eq!(s.triangle(1), [v2, v1, v3]);
    assert_eq!(s.triangle(2), [v0, v1, v2]);
    assert_eq!(s.triangle(3), [v0, v2, v3]);
    // Both primitives have no material: they share the default one.
    assert_eq!(s.materials.len(), 1);
    let _ = std::fs::remove_dir_all(&dir);
}
