//! Lenient loading of real files: what cannot cast a shadow (faces of one or two vertices,
//! polylines, points, unknown statements, `LINES`/`POINTS` primitives, optional
//! extensions) is skipped and said once per kind, and the rest loads exactly as the same
//! file without those parts; what cannot be trusted (a required extension shadowlab
//! lacks, a glTF 1.0 file, a file cut short) is still refused, naming the culprit.

mod support;

use shadowlab::scene::{self, gltf, obj, LoadOptions, Scene};
use std::path::{Path, PathBuf};
use support::{data, load, scratch};

/// The triangles of a scene, in order.
fn triangles(s: &Scene) -> Vec<[shadowlab::math::Vec3; 3]> {
    (0..s.len()).map(|i| s.triangle(i)).collect()
}

/// The one warning that mentions `needle`.
fn warning<'a>(s: &'a Scene, needle: &str) -> &'a str {
    let found: Vec<&String> = s.warnings.iter().filter(|w| w.contains(needle)).collect();
    assert_eq!(found.len(), 1, "{needle:?} in {:?}", s.warnings);
    found[0]
}

#[test]
fn obj_with_edges_points_and_polylines_loads_its_triangles_and_says_what_it_skipped() {
    let path = data("lenient/edges.obj");
    let text = std::fs::read_to_string(&path).unwrap();
    let s = obj::load(&path).unwrap();
    // The same file with every line shadowlab skips removed by hand: the same triangles,
    // and nothing to say.
    let kept: String = text
        .lines()
        .filter(|l| {
            let mut t = l.split_whitespace();
            match t.next() {
                Some("f") => t.count() >= 3,
                Some("l" | "p" | "vp" | "curv" | "cstype") => false,
                _ => true,
            }
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let clean = obj::load_from_str("edges.obj", &kept, None).unwrap();
    assert!(clean.warnings.is_empty(), "{:?}", clean.warnings);
    assert_eq!(triangles(&s), triangles(&clean));
    // Two quads (two triangles each) and four triangles; the 3-vertex `l` made none.
    assert_eq!(s.len(), 8);
    assert_eq!(s.warnings.len(), 4, "{:?}", s.warnings);
    assert!(warning(&s, "faces with fewer than 3 vertices").contains("skipped 3 "));
    assert!(warning(&s, "line element").contains("skipped 1 "));
    assert!(warning(&s, "point element").contains("skipped 1 "));
    let w = warning(&s, "does not read");
    assert!(w.starts_with("edges.obj: skipped 3 statements"), "{w}");
    for k in ["\"vp\" ×1", "\"curv\" ×1", "\"cstype\" ×1"] {
        assert!(w.contains(k), "{w}");
    }
    // Through scene::load the bare mesh gets its ground and camera, and keeps the warnings.
    let framed = load(&path).unwrap();
    assert_eq!(framed.warnings, s.warnings);
    assert_eq!(framed.len(), s.len() + 2);
}

#[test]
fn obj_cut_short_in_a_face_is_still_refused() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4";
    let e = obj::load_from_str("cut.obj", text, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cut.obj") && e.contains("line 6") && e.contains("truncated"),
        "{e}"
    );
    // The same short face followed by a newline is an edge among the faces.
    let s = obj::load_from_str("edge.obj", &format!("{text}\n"), None).unwrap();
    assert_eq!(s.len(), 1);
    assert_eq!(s.warnings.len(), 1);
    // Non-finite coordinates and missing vertices are refused as before.
    let nan = "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n";
    let e = obj::load_from_str("nan.obj", nan, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("non-finite"), "{e}");
    let missing = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n";
    assert!(obj::load_from_str("missing.obj", missing, None).is_err());
}

#[test]
fn gltf_lines_and_points_primitives_are_skipped_and_said() {
    let s = gltf::load(&data("lenient/lines.gltf")).unwrap();
    // The floor's two triangles and the caster's one; the LINES and POINTS primitives add
    // none.
    assert_eq!(s.len(), 3);
    assert!(warning(&s, "LINES").contains("skipped 1 primitive in LINES mode"));
    assert!(warning(&s, "POINTS").contains("skipped 1 primitive in POINTS mode"));
    // The optional extension is ignored, and said.
    assert!(warning(&s, "KHR_materials_volume").contains("lines.gltf: ignored"));
    assert_eq!(s.warnings.len(), 3, "{:?}", s.warnings);
}

/// `lines.gltf` with `edit` applied to its JSON, written to `dir/name`.
fn edited(dir: &Path, name: &str, edit: impl Fn(&mut serde_json::Value)) -> PathBuf {
    let text = std::fs::read_to_string(data("lenient/lines.gltf")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut json);
    let p = dir.join(name);
    std::fs::write(&p, serde_json::to_string(&json).unwrap()).unwrap();
    p
}

#[test]
fn gltf_required_extensions_are_refused_by_name_unless_shadowlab_reads_them() {
    let dir = scratch("required");
    let draco = edited(&dir, "draco.gltf", |j| {
        j["extensionsUsed"] = serde_json::json!(["KHR_draco_mesh_compression"]);
        j["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"]);
    });
    let e = gltf::load(&draco).unwrap_err().to_string();
    assert!(
        e.contains("draco.gltf") && e.contains("requires the extension KHR_draco_mesh_compression"),
        "{e}"
    );
    // Quantized positions are read, so a file requiring them loads without a word on it.
    let quantized = edited(&dir, "quantized.gltf", |j| {
        j["extensionsUsed"] = serde_json::json!(["KHR_mesh_quantization"]);
        j["extensionsRequired"] = serde_json::json!(["KHR_mesh_quantization"]);
    });
    let s = gltf::load(&quantized).unwrap();
    assert_eq!(s.len(), 3);
    assert!(
        s.warnings.iter().all(|w| !w.contains("quantization")),
        "{:?}",
        s.warnings
    );
    // A required extension that changes shading only loads, and is said to be ignored.
    let unlit = edited(&dir, "unlit.gltf", |j| {
        j["extensionsUsed"] = serde_json::json!(["KHR_materials_unlit"]);
        j["extensionsRequired"] = serde_json::json!(["KHR_materials_unlit"]);
    });
    let s = gltf::load(&unlit).unwrap();
    assert!(warning(&s, "KHR_materials_unlit").contains("ignored"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gltf_1_0_files_are_named_as_such() {
    let dir = scratch("v1");
    // A glTF 1.0 document: objects keyed by name where 2.0 has arrays.
    let v1 = dir.join("old.gltf");
    std::fs::write(
        &v1,
        r#"{"asset": {"version": "1.0"}, "scene": "defaultScene",
            "scenes": {"defaultScene": {"nodes": ["node_1"]}},
            "nodes": {"node_1": {"meshes": ["mesh_1"]}}, "meshes": {"mesh_1": {"primitives": []}}}"#,
    )
    .unwrap();
    let e = gltf::load(&v1).unwrap_err().to_string();
    assert!(
        e.contains("old.gltf")
            && e.contains("glTF 1.0 is not supported")
            && e.contains("convert it to glTF 2.0"),
        "{e}"
    );
    // A 2.0-shaped document that says it is 1.1 is named by its version too.
    let v11 = edited(&dir, "v11.gltf", |j| j["asset"]["version"] = "1.1".into());
    let e = gltf::load(&v11).unwrap_err().to_string();
    assert!(
        e.contains("glTF 1.0 is not supported (asset version \"1.1\")"),
        "{e}"
    );
    // A binary glTF 1.0 container (version 1 in its header).
    let glb = dir.join("old.glb");
    let json = br#"{"asset":{"version":"1.0"}}  "#;
    let mut b = b"glTF".to_vec();
    b.extend(1u32.to_le_bytes());
    b.extend((20 + json.len() as u32).to_le_bytes());
    b.extend((json.len() as u32).to_le_bytes());
    b.extend(0u32.to_le_bytes());
    b.extend(json);
    std::fs::write(&glb, b).unwrap();
    let e = gltf::load(&glb).unwrap_err().to_string();
    assert!(
        e.contains("glTF 1.0 is not supported (GLB container version 1)"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn camera_index_picks_among_the_files_cameras_and_names_the_count_when_out_of_range() {
    let path = data("gltf/Cameras.gltf");
    let spec = path.to_str().unwrap();
    let at = |i: usize| {
        scene::load_with(
            spec,
            &Default::default(),
            &LoadOptions {
                camera_index: i,
                ..Default::default()
            },
        )
    };
    let first = at(0).unwrap().camera.unwrap();
    let second = at(1).unwrap().camera.unwrap();
    assert_eq!(first, load(&path).unwrap().camera.unwrap());
    // Camera 0 is the perspective one (yfov 0.7 rad), camera 1 the orthographic one.
    assert!((first.fov_y_deg - 0.7f32.to_degrees()).abs() < 1e-4);
    assert!(!first.is_orthographic() && second.is_orthographic());
    assert_ne!(first, second);
    let e = at(2).unwrap_err();
    assert!(e.is_bad_input());
    let e = e.to_string();
    assert!(
        e.contains("--camera-index 2") && e.contains("has 2 cameras"),
        "{e}"
    );
    // A scene with one camera takes index 0 only; a bare mesh's automatic camera too.
    let e = scene::load_with(
        "bunny",
        &Default::default(),
        &LoadOptions {
            camera_index: 1,
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("--camera-index 1") && e.contains("has 1 camera"),
        "{e}"
    );
    let lines = data("lenient/lines.gltf");
    let e = scene::load_with(
        lines.to_str().unwrap(),
        &Default::default(),
        &LoadOptions {
            camera_index: 1,
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("has 0 cameras"), "{e}");
}
