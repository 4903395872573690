//! glTF 2.0 files, `.gltf` (JSON with external or `data:` buffers) and `.glb` (binary),
//! parsed and validated with the `gltf` crate; buffers are loaded and accessors decoded
//! here, so that only geometry is ever read.
//!
//! What is read:
//! - The default scene (or the first one; with no scene at all, every node that is no
//!   other node's child), walked depth-first from its root nodes with each node's
//!   transform (`matrix` or TRS) composed onto its parent's. A mesh used by several nodes
//!   is decoded once and instanced with each node's world transform.
//! - Primitives in `TRIANGLES`, `TRIANGLE_STRIP` and `TRIANGLE_FAN` mode, indexed or not,
//!   with any component type the specification allows for positions (float, or
//!   normalized/unnormalized integers as with `KHR_mesh_quantization`) and sparse
//!   accessors. `POINTS` and `LINE*` primitives cast no shadow and are skipped, as are
//!   primitives without `POSITION` (the specification says to skip them). Skins and morph
//!   targets are ignored: the mesh is used in its bind pose.
//! - Materials: the base colour factor gives the colour; alpha mode `BLEND` with alpha `a`
//!   gives the transmittance `1 − a` in every channel; `MASK` and `OPAQUE` are opaque.
//!   Textures are never loaded, so missing or undecodable images are not errors. A
//!   primitive without a material gets [`Material::default`]. Material extensions
//!   (`KHR_materials_transmission`, `…_volume`, …) are ignored.
//! - The camera nodes met in that walk, in order; the one at the asked index
//!   ([`load_with_camera`], the first by default): eye at the node's origin, looking down
//!   its −Z with its +Y up. A perspective camera keeps `yfov`, `znear` and `zfar` (a
//!   missing `zfar` — an infinite projection — is replaced by the far distance that fits
//!   the scene); the image is 768 pixels high and as wide as `aspectRatio` says (1024
//!   without one). An orthographic camera becomes a narrow perspective camera
//!   ([`ORTHOGRAPHIC_FOV_DEG`]) pulled back along its axis so that, at the depth of the
//!   scene's centre, it frames exactly the orthographic rectangle `2·xmag × 2·ymag`; the
//!   image aspect is `xmag / ymag`. The camera's target is placed on its axis at the depth
//!   of the scene's centre, so moving it closer or farther keeps the scene in view.
//! - The first node carrying a `KHR_lights_punctual` light: directional (shining down the
//!   node's −Z), point (at its origin), or spot (at its origin, down its −Z, with
//!   `fov_deg = 2 · outerConeAngle`, at most [`MAX_SPOT_FOV_DEG`]). Colour, intensity and
//!   range do not matter for shadows and are ignored. The inner cone is ignored too: the
//!   falloff between the cones dims the light inside its cone, it does not move a shadow.
//!
//! Lenient where nothing that casts a shadow is lost, and saying so: every kind of thing
//! skipped or approximated above (primitives by mode, morph targets, skins, the alpha
//! modes, the orthographic stand-in, the spot's inner cone) and every extension the file
//! uses that shadowlab does not read is one sentence in [`Scene::warnings`]. A file that
//! *requires* an extension shadowlab lacks is refused naming it; those it reads are
//! [`READ_EXTENSIONS`], and [`SHADING_ONLY_EXTENSIONS`] change no shadow. A glTF 1.0
//! file (by its GLB header or `asset.version`) is refused as such.
//!
//! Every failure is an [`Error`] naming the file and the element at fault: a buffer file
//! that cannot be read (by its URI and resolved path), a buffer shorter than declared, an
//! accessor reaching past its buffer view, an index out of range (mesh, primitive, index),
//! a non-finite position (mesh, primitive, vertex), a hierarchy with a cycle.

use super::{Material, Scene};
use crate::camera::{Camera, MAX_IMAGE_SIDE};
use crate::error::{Error, Result};
use crate::files::{read_prefix, Access, MAX_FILE_BYTES};
use crate::light::Light;
use crate::limits;
use crate::math::{vec3, Aabb, Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::json::validation::Checked;
use gltf::mesh::Mode;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Vertical field of view of the perspective camera that stands in for an orthographic
/// one. Narrower is closer to orthographic but puts the eye farther away (a longer depth
/// range, so coarser depth precision); 10° keeps the perspective distortion across the
/// frame below 1% of the depth of the framed plane.
pub const ORTHOGRAPHIC_FOV_DEG: f32 = 10.0;

/// The widest spot cone accepted, in degrees. glTF allows an outer cone angle of up to 90°
/// (a 180° cone), which no single perspective light view can hold; wider cones are
/// narrowed to this.
pub const MAX_SPOT_FOV_DEG: f32 = 178.0;

/// Height in pixels of the image of a glTF camera; the width follows its aspect ratio.
pub const CAMERA_HEIGHT: u32 = 768;

/// Width of the image of a glTF camera that gives no aspect ratio.
pub const CAMERA_DEFAULT_WIDTH: u32 = 1024;

/// The most camera nodes remembered (`--camera-index` picks among them).
const MAX_CAMERAS: usize = 1 << 16;

/// The most node visits of one hierarchy walk. A valid file visits each node once; a
/// file that lists shared children many times over could otherwise multiply the walk.
const MAX_NODE_VISITS: usize = 1 << 20;

/// The most mesh instances one hierarchy walk may place: a few bytes of node graph can
/// instance a mesh millions of times, each copy adding its triangles to the scene and to
/// every technique's work.
pub const MAX_MESH_INSTANCES: usize = 1 << 18;

/// The most entries of each top-level array (`nodes`, `meshes`, `accessors`, …) a file
/// may declare; counted before the document is decoded, so that a file listing ten
/// million empty nodes is refused before they take gigabytes.
pub const MAX_ELEMENTS: usize = 1 << 20;

/// Extensions shadowlab reads: a file that requires one of them loads.
pub const READ_EXTENSIONS: &[&str] = &["KHR_lights_punctual", "KHR_mesh_quantization"];

/// Material extensions that change shading only, never what blocks light: a file that
/// requires one of them loads, and says they are ignored.
pub const SHADING_ONLY_EXTENSIONS: &[&str] = &[
    "KHR_materials_unlit",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_iridescence",
    "KHR_materials_anisotropy",
];

/// Loads a `.gltf` or `.glb` file with its first camera; its buffer files must lie in its
/// folder.
pub fn load(path: &Path) -> Result<Scene> {
    load_with_camera(path, 0)
}

/// [`load`] with camera `camera_index` (see [`load_with`]).
pub fn load_with_camera(path: &Path, camera_index: usize) -> Result<Scene> {
    load_with(path, &Access::for_scene(path, false), camera_index)
}

/// Loads a `.gltf` or `.glb` file whose buffer URIs resolve as `access` allows, with
/// camera `camera_index`: the index among the camera nodes in the order the hierarchy walk
/// meets them. An index past the last camera is an error naming how many there are (a
/// file without cameras accepts only 0, and gets an automatic camera).
pub fn load_with(path: &Path, access: &Access, camera_index: usize) -> Result<Scene> {
    let bytes = super::read_input(path, MAX_FILE_BYTES)?;
    let fmt = |what: String| Error::format(path, what);
    let glb = bytes.starts_with(b"glTF");
    if let (true, Some(v)) = (glb, bytes.get(4..8)) {
        let version = u32::from_le_bytes([v[0], v[1], v[2], v[3]]);
        if version != 2 {
            return Err(fmt(unsupported_version(&format!(
                "GLB container version {version}"
            ))));
        }
    }
    let json = if glb {
        glb_json(&bytes).map_err(fmt)?
    } else {
        &bytes[..]
    };
    check_counts(json).map_err(fmt)?;
    let gltf =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| {
            match json_version(&bytes).filter(|v| !v.starts_with('2')) {
                Some(v) => fmt(unsupported_version(&format!("asset version {v:?}"))),
                None => fmt(describe(e)),
            }
        })?;
    let version = &gltf.document.as_json().asset.version;
    if !version.starts_with("2.") {
        return Err(fmt(unsupported_version(&format!(
            "asset version {:?}",
            version.chars().take(16).collect::<String>()
        ))));
    }
    validate(gltf.document.as_json()).map_err(|e| fmt(describe(e)))?;
    let mut warnings = extension_warnings(path, gltf.document.as_json())?;
    let gltf::Gltf { document, blob } = gltf;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = load_buffers(path, base, access, &document, blob)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut loader = Loader {
        path,
        doc: &document,
        buffers,
        scene: Scene::new(name),
        meshes: vec![None; document.meshes().len()],
        materials: vec![None; document.materials().len()],
        default_material: None,
        cameras: Vec::new(),
        light: None,
        skipped: Default::default(),
    };
    let planned = loader.walk(true)?;
    super::check_triangle_count(path, planned)?;
    // The planning walk met every camera and skipped primitive once already.
    loader.cameras.clear();
    loader.skipped = Default::default();
    loader.walk(false)?;
    let Loader {
        mut scene,
        cameras,
        light,
        skipped,
        ..
    } = loader;
    let name = scene.name.clone();
    if camera_index > 0 && camera_index >= cameras.len() {
        return Err(Error::param(format!(
            "--camera-index {camera_index} is out of range: {name} has {} camera{}{}",
            cameras.len(),
            if cameras.len() == 1 { "" } else { "s" },
            match cameras.len() {
                0 => String::new(),
                n => format!(" (0..={})", n - 1),
            }
        )));
    }
    if let Some(&(index, world)) = cameras.get(camera_index) {
        let (camera, note) = convert_camera(path, &document, index, world, &scene.bounds)?;
        scene.camera = Some(camera);
        warnings.extend(note.map(|n| format!("{name}: {n}")));
    }
    if let Some((index, world)) = light {
        let (l, note) = convert_light(path, &document, index, world)?;
        scene.light = Some(l);
        warnings.extend(note.map(|n| format!("{name}: {n}")));
    }
    warnings.extend(
        skipped
            .into_iter()
            .map(|(what, n)| format!("{name}: {}", what.describe(n))),
    );
    scene.warnings = warnings;
    Ok(scene)
}

/// "glTF 1.0 is not supported (…); convert it to glTF 2.0", or the like for another
/// version.
fn unsupported_version(found: &str) -> String {
    if found.contains("\"1") || found.ends_with(" 1") {
        format!("glTF 1.0 is not supported ({found}); convert it to glTF 2.0")
    } else {
        format!("only glTF 2.0 is supported, not {found}")
    }
}

/// `asset.version` of a glTF JSON document (or of a GLB's JSON chunk), read on its own
/// so that a file of another version can be named as such when it does not parse as 2.0.
fn json_version(bytes: &[u8]) -> Option<String> {
    #[derive(serde::Deserialize)]
    struct Asset {
        version: serde_json::Value,
    }
    #[derive(serde::Deserialize)]
    struct Root {
        asset: Asset,
    }
    let json = if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
        bytes.get(20..20usize.checked_add(len)?)?
    } else {
        bytes
    };
    let root: Root = serde_json::from_slice(json).ok()?;
    Some(match root.asset.version {
        serde_json::Value::String(s) => s,
        other => other.to_string(),
    })
}

/// Refuses a required extension shadowlab lacks (naming it); says which optional ones,
/// and which required shading-only ones, are ignored.
fn extension_warnings(path: &Path, root: &gltf::json::Root) -> Result<Vec<String>> {
    let read = |e: &str| READ_EXTENSIONS.contains(&e);
    let shading = |e: &str| SHADING_ONLY_EXTENSIONS.contains(&e);
    if let Some(e) = root
        .extensions_required
        .iter()
        .find(|e| !read(e) && !shading(e))
    {
        return Err(Error::format(
            path,
            format!("the file requires the extension {e}, which shadowlab does not support"),
        ));
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ignored: Vec<&str> = root
        .extensions_used
        .iter()
        .chain(&root.extensions_required)
        .map(String::as_str)
        .filter(|e| !read(e))
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    let mut out = Vec::new();
    if !ignored.is_empty() {
        out.push(format!(
            "{name}: ignored the extension{} {} (optional, or changing shading only)",
            if ignored.len() == 1 { "" } else { "s" },
            ignored.join(", ")
        ));
    }
    Ok(out)
}

/// A kind of thing the loader skips or approximates, counted over the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Skip {
    /// A primitive in a mode that makes no triangles.
    Mode(ModeName),
    /// A primitive without `POSITION`.
    NoPositions,
    /// A primitive with morph targets (used in its base shape).
    MorphTargets,
    /// A node with a skin (its mesh used in the bind pose).
    Skin,
    /// A material with alpha mode `MASK`, cast as opaque.
    Mask,
    /// A material with alpha mode `BLEND`, cast with its uniform alpha.
    Blend,
}

/// The modes [`Skip::Mode`] names, in an order that sorts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum ModeName {
    Points,
    Lines,
    LineLoop,
    LineStrip,
}

impl Skip {
    /// The sentence for `n` of this kind.
    fn describe(self, n: usize) -> String {
        let s = if n == 1 { "" } else { "s" };
        match self {
            Skip::Mode(m) => {
                let mode = match m {
                    ModeName::Points => "POINTS",
                    ModeName::Lines => "LINES",
                    ModeName::LineLoop => "LINE_LOOP",
                    ModeName::LineStrip => "LINE_STRIP",
                };
                format!("skipped {n} primitive{s} in {mode} mode (they cast no shadow)")
            }
            Skip::NoPositions => format!("skipped {n} primitive{s} without POSITION"),
            Skip::MorphTargets => format!(
                "ignored the morph targets of {n} primitive{s} (each is used in its base shape)"
            ),
            Skip::Skin => format!("ignored the skin of {n} node{s} (each mesh is used in its bind pose)"),
            Skip::Mask => format!(
                "{n} material{s} with alpha mode MASK cast opaque shadows (the texture's alpha is not used)"
            ),
            Skip::Blend => format!(
                "{n} material{s} with alpha mode BLEND cast shadows of uniform transmittance 1 − alpha (the texture's alpha is not used)"
            ),
        }
    }
}

/// One decoded primitive, in mesh space.
struct Primitive {
    positions: Vec<Vec3>,
    tris: Vec<[u32; 3]>,
    material: u32,
}

struct Loader<'a> {
    path: &'a Path,
    doc: &'a gltf::Document,
    buffers: Vec<Vec<u8>>,
    scene: Scene,
    /// Decoded meshes by glTF index, shared by every node that instances them.
    meshes: Vec<Option<Rc<Vec<Primitive>>>>,
    /// Scene material index of each glTF material, once used.
    materials: Vec<Option<u32>>,
    default_material: Option<u32>,
    /// Every camera node in walk order: (camera index, world transform).
    cameras: Vec<(usize, Mat4)>,
    /// First light node: (light index, world transform).
    light: Option<(usize, Mat4)>,
    /// How many of each kind of thing were skipped or approximated.
    skipped: std::collections::BTreeMap<Skip, usize>,
}

impl Loader<'_> {
    fn err(&self, what: String) -> Error {
        Error::format(self.path, what)
    }

    /// Walks the scene's hierarchy depth-first, in file order, adding each mesh instance;
    /// with `plan`, only counts the triangles the instances would add (from the
    /// accessors' counts, nothing decoded) and returns the total.
    fn walk(&mut self, plan: bool) -> Result<u64> {
        let doc = self.doc;
        let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(s) => s.nodes().collect(),
            None => {
                let mut is_child = vec![false; doc.nodes().len()];
                for n in doc.nodes() {
                    for c in n.children() {
                        is_child[c.index()] = true;
                    }
                }
                doc.nodes().filter(|n| !is_child[n.index()]).collect()
            }
        };
        let node_count = doc.nodes().len();
        let mut stack: Vec<(gltf::Node, Mat4, usize)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, Mat4::IDENTITY, 0))
            .collect();
        let mut visits = 0usize;
        let mut instances = 0usize;
        let mut planned = 0u64;
        while let Some((node, parent, depth)) = stack.pop() {
            visits += 1;
            if depth > node_count {
                return Err(self.err(format!(
                    "node {} is its own ancestor: the node hierarchy has a cycle",
                    node.index()
                )));
            }
            if visits > MAX_NODE_VISITS {
                return Err(Error::Limit(format!(
                    "{}: the node hierarchy needs more node visits than the limit of {MAX_NODE_VISITS}",
                    self.path.display()
                )));
            }
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            if !local.is_finite() {
                return Err(self.err(format!("node {} has a non-finite transform", node.index())));
            }
            let world = parent * local;
            if let Some(c) = node.camera() {
                if self.cameras.len() < MAX_CAMERAS {
                    self.cameras.push((c.index(), world));
                }
            }
            if node.skin().is_some() && node.mesh().is_some() {
                *self.skipped.entry(Skip::Skin).or_default() += 1;
            }
            if self.light.is_none() {
                if let Some(l) = node.light() {
                    self.light = Some((l.index(), world));
                }
            }
            if let Some(mesh) = node.mesh() {
                instances += 1;
                if instances > MAX_MESH_INSTANCES {
                    return Err(Error::Limit(format!(
                        "{}: the node hierarchy places more mesh instances than the limit of {MAX_MESH_INSTANCES}",
                        self.path.display()
                    )));
                }
                if plan {
                    planned = planned.saturating_add(mesh_triangles(&mesh));
                } else {
                    let prims = self.mesh(&mesh)?;
                    let added: usize = prims.iter().map(|p| p.tris.len()).sum();
                    super::check_triangle_count(self.path, (self.scene.len() + added) as u64)?;
                    for p in prims.iter() {
                        self.scene
                            .push_indexed(&p.positions, &p.tris, world, p.material);
                    }
                }
            }
            let children: Vec<gltf::Node> = node.children().collect();
            for c in children.into_iter().rev() {
                stack.push((c, world, depth + 1));
            }
        }
        Ok(planned)
    }

    /// The decoded primitives of `mesh`, decoding them on first use.
    fn mesh(&mut self, mesh: &gltf::Mesh) -> Result<Rc<Vec<Primitive>>> {
        if let Some(m) = &self.meshes[mesh.index()] {
            return Ok(m.clone());
        }
        let label = match mesh.name() {
            Some(n) => format!("mesh {} ({n:?})", mesh.index()),
            None => format!("mesh {}", mesh.index()),
        };
        let mut prims = Vec::new();
        for prim in mesh.primitives() {
            let at = format!("{label}, primitive {}", prim.index());
            let mode = prim.mode();
            let skip = match mode {
                Mode::Points => Some(ModeName::Points),
                Mode::Lines => Some(ModeName::Lines),
                Mode::LineLoop => Some(ModeName::LineLoop),
                Mode::LineStrip => Some(ModeName::LineStrip),
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => None,
            };
            if let Some(m) = skip {
                *self.skipped.entry(Skip::Mode(m)).or_default() += 1;
                continue;
            }
            let Some(pos) = prim.get(&gltf::Semantic::Positions) else {
                *self.skipped.entry(Skip::NoPositions).or_default() += 1;
                continue;
            };
            if prim.morph_targets().next().is_some() {
                *self.skipped.entry(Skip::MorphTargets).or_default() += 1;
            }
            if pos.dimensions() != Dimensions::Vec3 {
                return Err(self.err(format!(
                    "{at}: POSITION accessor {} is not VEC3",
                    pos.index()
                )));
            }
            let raw = self.read_accessor(&pos, &at)?;
            let mut positions = Vec::with_capacity(raw.len() / 3);
            for (v, c) in raw.chunks_exact(3).enumerate() {
                let p = vec3(c[0] as f32, c[1] as f32, c[2] as f32);
                if !p.is_finite() {
                    return Err(self.err(format!("{at}: vertex {v} has a non-finite position")));
                }
                positions.push(p);
            }
            let indices: Vec<u32> = match prim.indices() {
                Some(acc) => {
                    if acc.dimensions() != Dimensions::Scalar
                        || !matches!(
                            acc.data_type(),
                            DataType::U8 | DataType::U16 | DataType::U32
                        )
                    {
                        return Err(self.err(format!(
                            "{at}: index accessor {} is not a scalar of unsigned integers",
                            acc.index()
                        )));
                    }
                    let raw = self.read_accessor(&acc, &at)?;
                    let n = positions.len();
                    let mut out = Vec::with_capacity(raw.len());
                    for (k, &i) in raw.iter().enumerate() {
                        if i >= n as f64 {
                            return Err(self.err(format!(
                                "{at}: index {k} (accessor {}) is out of range for the {n} vertices of POSITION",
                                acc.index()
                            )));
                        }
                        out.push(i as u32);
                    }
                    out
                }
                None => {
                    if positions.len() > u32::MAX as usize {
                        return Err(self.err(format!("{at}: too many vertices")));
                    }
                    (0..positions.len() as u32).collect()
                }
            };
            let tris = match assemble(mode, &indices) {
                Some(t) => t,
                None => {
                    return Err(self.err(format!(
                        "{at}: {} indices do not make whole triangles (TRIANGLES needs a multiple of 3)",
                        indices.len()
                    )))
                }
            };
            let material = self.material(prim.material())?;
            prims.push(Primitive {
                positions,
                tris,
                material,
            });
        }
        let prims = Rc::new(prims);
        self.meshes[mesh.index()] = Some(prims.clone());
        Ok(prims)
    }

    /// The scene material for a glTF material, converting it on first use.
    fn material(&mut self, m: gltf::Material) -> Result<u32> {
        let Some(index) = m.index() else {
            if let Some(d) = self.default_material {
                return Ok(d);
            }
            let d = self.scene.add_material(Material::default());
            self.default_material = Some(d);
            return Ok(d);
        };
        if let Some(i) = self.materials[index] {
            return Ok(i);
        }
        let [r, g, b, a] = m.pbr_metallic_roughness().base_color_factor();
        let label = match m.name() {
            Some(n) => format!("material {index} ({n:?})"),
            None => format!("material {index}"),
        };
        if ![r, g, b, a].iter().all(|x| x.is_finite()) {
            return Err(self.err(format!("{label}: the base colour factor is not finite")));
        }
        let transmittance = match m.alpha_mode() {
            gltf::material::AlphaMode::Blend => {
                *self.skipped.entry(Skip::Blend).or_default() += 1;
                Vec3::splat(1.0 - a.clamp(0.0, 1.0))
            }
            gltf::material::AlphaMode::Mask => {
                *self.skipped.entry(Skip::Mask).or_default() += 1;
                Vec3::ZERO
            }
            gltf::material::AlphaMode::Opaque => Vec3::ZERO,
        };
        let i = self.scene.add_material(Material {
            name: m
                .name()
                .map(str::to_owned)
                .unwrap_or_else(|| format!("material{index}")),
            color: vec3(r, g, b).clamp(Vec3::ZERO, Vec3::ONE),
            transmittance,
        });
        self.materials[index] = Some(i);
        Ok(i)
    }

    /// Decodes every component of `acc` (sparse substitutions applied, integers normalized
    /// where the accessor says so) in element order.
    fn read_accessor(&self, acc: &gltf::Accessor, at: &str) -> Result<Vec<f64>> {
        let ty = acc.data_type();
        let n = acc.dimensions().multiplicity();
        let count = acc.count();
        let elem = ty.size() * n;
        let what = format!("{at}: accessor {}", acc.index());
        let total = count
            .checked_mul(n)
            .filter(|&t| t <= 3 * (super::MAX_TRIANGLES + 2))
            .ok_or_else(|| {
                Error::Limit(format!(
                    "{}: {what} has too many elements ({count})",
                    self.path.display()
                ))
            })?;
        // What the decoded accessor and the scene's copy of it take, checked first.
        limits::check_bytes(
            || format!("{}: {what}: its {count} elements", self.path.display()),
            (total as u64).saturating_mul(8 + 4 + super::BYTES_PER_TRIANGLE / 3),
        )?;
        // The data is checked to be there before anything is allocated.
        let dense = match acc.view() {
            Some(view) => {
                let stride = view.stride().unwrap_or(elem);
                if stride < elem {
                    return Err(self.err(format!(
                        "{what}: buffer view {} has a stride of {stride} bytes, less than the {elem}-byte element",
                        view.index()
                    )));
                }
                let data = self.view_bytes(&view, &what)?;
                let end = match count {
                    0 => Some(0),
                    _ => (count - 1)
                        .checked_mul(stride)
                        .and_then(|x| x.checked_add(acc.offset()))
                        .and_then(|x| x.checked_add(elem)),
                };
                if end.is_none_or(|e| e > data.len()) {
                    return Err(self.err(format!(
                        "{what}: {count} elements from byte {} reach past the end of buffer view {} ({} bytes)",
                        acc.offset(),
                        view.index(),
                        data.len()
                    )));
                }
                Some((data, stride))
            }
            // No buffer view: zeros, to be replaced by sparse entries.
            None => None,
        };
        let mut out = limits::try_filled(total, 0.0f64, &what)?;
        if let Some((data, stride)) = dense {
            for i in 0..count {
                let start = acc.offset() + i * stride;
                decode(
                    ty,
                    acc.normalized(),
                    &data[start..start + elem],
                    &mut out[i * n..(i + 1) * n],
                );
            }
        }
        if let Some(sparse) = acc.sparse() {
            let k = sparse.count();
            let idx_view = sparse.indices().view();
            let idx_data = self.view_bytes(&idx_view, &what)?;
            let idx_size = match sparse.indices().index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let val_view = sparse.values().view();
            let val_data = self.view_bytes(&val_view, &what)?;
            let idx_off = sparse.indices().offset();
            let val_off = sparse.values().offset();
            let fits = |off: usize, size: usize, len: usize| {
                k.checked_mul(size)
                    .and_then(|b| b.checked_add(off))
                    .is_some_and(|e| e <= len)
            };
            if !fits(idx_off, idx_size, idx_data.len()) || !fits(val_off, elem, val_data.len()) {
                return Err(self.err(format!(
                    "{what}: its {k} sparse entries reach past the end of their buffer views"
                )));
            }
            for j in 0..k {
                let b = &idx_data[idx_off + j * idx_size..idx_off + (j + 1) * idx_size];
                let target = match idx_size {
                    1 => b[0] as usize,
                    2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
                };
                if target >= count {
                    return Err(self.err(format!(
                        "{what}: sparse entry {j} replaces element {target}, but the accessor has {count}"
                    )));
                }
                let v = &val_data[val_off + j * elem..val_off + (j + 1) * elem];
                decode(
                    ty,
                    acc.normalized(),
                    v,
                    &mut out[target * n..(target + 1) * n],
                );
            }
        }
        Ok(out)
    }

    /// The bytes of a buffer view, checked against its buffer.
    fn view_bytes(&self, view: &gltf::buffer::View, what: &str) -> Result<&[u8]> {
        let buffer = &self.buffers[view.buffer().index()];
        let end = view.offset().checked_add(view.length());
        match end {
            Some(end) if end <= buffer.len() => Ok(&buffer[view.offset()..end]),
            _ => Err(self.err(format!(
                "{what}: buffer view {} (bytes {}..+{}) reaches past the end of buffer {} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                buffer.len()
            ))),
        }
    }
}

/// The triangles `mesh` adds per instance, from its accessors' counts alone.
fn mesh_triangles(mesh: &gltf::Mesh) -> u64 {
    let mut n = 0u64;
    for prim in mesh.primitives() {
        let Some(pos) = prim.get(&gltf::Semantic::Positions) else {
            continue;
        };
        let k = prim.indices().map_or(pos.count(), |a| a.count()) as u64;
        n = n.saturating_add(match prim.mode() {
            Mode::Triangles => k / 3,
            Mode::TriangleStrip | Mode::TriangleFan => k.saturating_sub(2),
            _ => 0,
        });
    }
    n
}

/// Decodes one element's components from little-endian bytes; normalized integers map to
/// [0, 1] (unsigned) or [−1, 1] (signed) as the glTF specification defines.
fn decode(ty: DataType, normalized: bool, bytes: &[u8], out: &mut [f64]) {
    let size = ty.size();
    for (c, o) in out.iter_mut().enumerate() {
        let b = &bytes[c * size..(c + 1) * size];
        *o = match ty {
            DataType::I8 => {
                let v = f64::from(b[0] as i8);
                if normalized {
                    (v / 127.0).max(-1.0)
                } else {
                    v
                }
            }
            DataType::U8 => {
                let v = f64::from(b[0]);
                if normalized {
                    v / 255.0
                } else {
                    v
                }
            }
            DataType::I16 => {
                let v = f64::from(i16::from_le_bytes([b[0], b[1]]));
                if normalized {
                    (v / 32767.0).max(-1.0)
                } else {
                    v
                }
            }
            DataType::U16 => {
                let v = f64::from(u16::from_le_bytes([b[0], b[1]]));
                if normalized {
                    v / 65535.0
                } else {
                    v
                }
            }
            DataType::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            DataType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        };
    }
}

/// Triangles from a primitive's vertex list: `None` when a `TRIANGLES` list is not a
/// whole number of triangles. Strips alternate their winding so every triangle keeps the
/// orientation of the first.
fn assemble(mode: Mode, idx: &[u32]) -> Option<Vec<[u32; 3]>> {
    let n = idx.len();
    match mode {
        Mode::Triangles => {
            let chunks = idx.chunks_exact(3);
            if !chunks.remainder().is_empty() {
                return None;
            }
            Some(chunks.map(|c| [c[0], c[1], c[2]]).collect())
        }
        Mode::TriangleStrip => Some(
            (0..n.saturating_sub(2))
                .map(|i| {
                    if i % 2 == 0 {
                        [idx[i], idx[i + 1], idx[i + 2]]
                    } else {
                        [idx[i + 1], idx[i], idx[i + 2]]
                    }
                })
                .collect(),
        ),
        Mode::TriangleFan => Some(
            (1..n.saturating_sub(1))
                .map(|i| [idx[0], idx[i], idx[i + 1]])
                .collect(),
        ),
        _ => Some(Vec::new()),
    }
}

/// Loads every buffer: the GLB binary chunk, `data:` URIs, or files beside the glTF file.
fn load_buffers(
    path: &Path,
    base: &Path,
    access: &Access,
    doc: &gltf::Document,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>> {
    let fmt = |what: String| Error::format(path, what);
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let (data, label) = match buffer.source() {
            gltf::buffer::Source::Bin => {
                let data = blob.take().ok_or_else(|| {
                    fmt(format!(
                        "buffer {i} refers to the GLB binary chunk, which the file lacks"
                    ))
                })?;
                (data, "the GLB binary chunk".to_string())
            }
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let data =
                    gltf::buffer::Data::from_source(buffer.source(), Some(base)).map_err(|e| {
                        fmt(format!("buffer {i}: its data: URI cannot be decoded ({e})"))
                    })?;
                (data.0, "its data: URI".to_string())
            }
            gltf::buffer::Source::Uri(uri) => {
                let shown: String = uri.chars().take(120).collect();
                let file = resolve_uri(base, access, uri)
                    .map_err(|why| fmt(format!("buffer {i} ({shown:?}) {why}")))?;
                // Never more than the declared length: the rest of the file is not the
                // buffer's.
                let data = read_prefix(&file, buffer.length() as u64).map_err(|why| {
                    fmt(format!(
                        "buffer {i} refers to the file {shown:?} ({}), which {why}",
                        file.display()
                    ))
                })?;
                (data, format!("the file {shown:?}"))
            }
        };
        if data.len() < buffer.length() {
            return Err(fmt(format!(
                "buffer {i} declares {} bytes but {label} holds only {}",
                buffer.length(),
                data.len()
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// The file a non-`data:` buffer URI names: a relative, percent-encoded reference
/// resolved against the glTF file's folder, or a `file:` URI, decoded first and then
/// kept where `access` allows. `Err` is a phrase following the URI.
fn resolve_uri(base: &Path, access: &Access, uri: &str) -> std::result::Result<PathBuf, String> {
    let decoded = if let Some(rest) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        percent_decode(rest)?
    } else if uri.contains(':') {
        return Err(
            "uses a URI scheme that is not supported (only relative paths, file: and data: are)"
                .into(),
        );
    } else {
        percent_decode(uri)?
    };
    access.resolve(base, &decoded)
}

/// The JSON chunk of a GLB file, after checking that the header's length is the file's
/// and that every chunk lies inside it.
fn glb_json(bytes: &[u8]) -> std::result::Result<&[u8], String> {
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64)
    };
    let (Some(version), Some(declared)) = (word(4), word(8)) else {
        return Err("the GLB header is truncated".into());
    };
    if version != 2 {
        return Err(format!(
            "the GLB header declares container version {version}, not 2"
        ));
    }
    if declared != bytes.len() as u64 {
        return Err(format!(
            "the GLB header declares {declared} bytes but the file holds {}",
            bytes.len()
        ));
    }
    let mut at = 12u64;
    let mut json = None;
    let mut chunk = 0;
    while at < declared {
        let (Some(len), Some(kind)) = (word(at as usize), word(at as usize + 4)) else {
            return Err(format!("GLB chunk {chunk}: its header is truncated"));
        };
        let end = at + 8 + len;
        if end > declared {
            return Err(format!(
                "GLB chunk {chunk} declares {len} bytes, past the end of the file"
            ));
        }
        if chunk == 0 {
            if kind != 0x4E4F_534A {
                return Err("the first GLB chunk is not JSON".into());
            }
            json = Some(&bytes[at as usize + 8..end as usize]);
        }
        at = end;
        chunk += 1;
    }
    json.ok_or_else(|| "the GLB file has no JSON chunk".into())
}

/// Fails when a top-level array of the document has more than [`MAX_ELEMENTS`] entries,
/// counted without decoding them.
fn check_counts(json: &[u8]) -> std::result::Result<(), String> {
    use serde::de::{IgnoredAny, SeqAccess, Visitor};
    /// The length of a JSON array whose elements are skipped.
    #[derive(Default)]
    struct Count(usize);
    impl<'de> serde::Deserialize<'de> for Count {
        fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
            struct V;
            impl<'de> Visitor<'de> for V {
                type Value = Count;
                fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                    f.write_str("an array")
                }
                fn visit_seq<A: SeqAccess<'de>>(
                    self,
                    mut seq: A,
                ) -> std::result::Result<Count, A::Error> {
                    let mut n = 0;
                    while seq.next_element::<IgnoredAny>()?.is_some() {
                        n += 1;
                    }
                    Ok(Count(n))
                }
            }
            d.deserialize_any(V)
        }
    }
    #[derive(serde::Deserialize)]
    struct Top {
        #[serde(default)]
        nodes: Count,
        #[serde(default)]
        meshes: Count,
        #[serde(default)]
        accessors: Count,
        #[serde(default, rename = "bufferViews")]
        buffer_views: Count,
        #[serde(default)]
        buffers: Count,
        #[serde(default)]
        materials: Count,
        #[serde(default)]
        scenes: Count,
        #[serde(default)]
        cameras: Count,
    }
    // A document that does not parse is left to the glTF crate, which says why.
    let Ok(top) = serde_json::from_slice::<Top>(json) else {
        return Ok(());
    };
    for (name, n) in [
        ("nodes", top.nodes.0),
        ("meshes", top.meshes.0),
        ("accessors", top.accessors.0),
        ("bufferViews", top.buffer_views.0),
        ("buffers", top.buffers.0),
        ("materials", top.materials.0),
        ("scenes", top.scenes.0),
        ("cameras", top.cameras.0),
    ] {
        if n > MAX_ELEMENTS {
            return Err(format!(
                "it declares {n} {name}, more than the limit of {MAX_ELEMENTS}"
            ));
        }
    }
    Ok(())
}

/// Decodes `%XX` escapes; a `%` not followed by two hex digits stays as it is.
fn percent_decode(s: &str) -> std::result::Result<String, String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8(out).map_err(|_| "the URI decodes to a name that is not UTF-8".into())
}

/// The `gltf` crate's validation, less two rules: the `min`/`max` a `POSITION` accessor
/// must carry (many exporters omit them and the loader never reads them: it computes
/// bounds itself), and the crate's own list of required extensions (the loader checks
/// `extensionsRequired` against what shadowlab reads, which includes
/// `KHR_mesh_quantization`). Every other rule is kept: the crate's accessors rely on them.
fn validate(root: &gltf::json::Root) -> std::result::Result<(), gltf::Error> {
    use gltf::json::validation::{Error as Rule, Validate};
    // The crate's own primitive check indexes the POSITION accessor before any bounds
    // check, so out-of-range attribute accessors are caught here first.
    for (mi, mesh) in root.meshes.iter().enumerate() {
        for (pi, prim) in mesh.primitives.iter().enumerate() {
            for acc in prim.attributes.values() {
                if acc.value() >= root.accessors.len() {
                    let path =
                        gltf::json::Path(format!("meshes[{mi}].primitives[{pi}].attributes"));
                    return Err(gltf::Error::Validation(vec![(
                        path,
                        Rule::IndexOutOfBounds,
                    )]));
                }
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path();
        let p = path.as_str();
        let bounds =
            p.contains("attributes[\"POSITION\"]") && (p.ends_with(".min") || p.ends_with(".max"));
        // Required extensions are checked against shadowlab's own list instead.
        let required = p.starts_with("extensionsRequired") && matches!(error, Rule::Unsupported);
        let dropped = required || (bounds && matches!(error, Rule::Missing));
        if !dropped {
            errors.push((path, error));
        }
    });
    if errors.is_empty() {
        Ok(())
    } else {
        Err(gltf::Error::Validation(errors))
    }
}

/// One sentence for a parse or validation failure of the glTF crate.
fn describe(e: gltf::Error) -> String {
    match e {
        gltf::Error::Validation(list) => {
            let shown: Vec<String> = list
                .iter()
                .take(4)
                .map(|(p, e)| format!("{p}: {e}"))
                .collect();
            let more = if list.len() > 4 {
                format!(" (and {} more)", list.len() - 4)
            } else {
                String::new()
            };
            format!("not a valid glTF 2.0 file: {}{more}", shown.join("; "))
        }
        gltf::Error::Deserialize(e) => format!("not valid glTF JSON ({e})"),
        gltf::Error::Binary(e) => format!("not a valid GLB container ({e})"),
        other => format!("cannot be read as glTF ({other})"),
    }
}

/// The scene camera for glTF camera `index` on a node with world transform `world`.
fn convert_camera(
    path: &Path,
    doc: &gltf::Document,
    index: usize,
    world: Mat4,
    bounds: &Aabb,
) -> Result<(Camera, Option<String>)> {
    let fmt = |what: String| Error::format(path, what);
    let mut note = None;
    let json = &doc.as_json().cameras[index];
    let eye = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
    if !eye.is_finite()
        || forward == Vec3::ZERO
        || up == Vec3::ZERO
        || forward.cross(up).length_squared() < 1e-12
    {
        return Err(fmt(format!(
            "camera {index}: its node's transform is degenerate"
        )));
    }
    // The scene centre's depth along the view axis: where the target goes.
    let center_depth = (bounds.center() - eye).dot(forward);
    let image = |aspect: f32| -> Result<(u32, u32)> {
        if !(aspect.is_finite() && aspect > 0.0) {
            return Err(fmt(format!(
                "camera {index}: aspect ratio {aspect} is not a positive number"
            )));
        }
        let w = (CAMERA_HEIGHT as f32 * aspect).round();
        if !(1.0..=MAX_IMAGE_SIDE as f32).contains(&w) {
            return Err(fmt(format!(
                "camera {index}: aspect ratio {aspect} gives an image {w} pixels wide, outside 1..={MAX_IMAGE_SIDE}"
            )));
        }
        Ok((w as u32, CAMERA_HEIGHT))
    };
    let kind = match &json.type_ {
        Checked::Valid(k) => *k,
        Checked::Invalid => return Err(fmt(format!("camera {index}: unknown camera type"))),
    };
    let mut camera = match (kind, &json.perspective, &json.orthographic) {
        (gltf::json::camera::Type::Perspective, Some(p), _) => {
            let fov = p.yfov.to_degrees();
            if !(fov > 0.0 && fov < 179.0) {
                return Err(fmt(format!(
                    "camera {index}: yfov {} rad is outside (0°, 179°)",
                    p.yfov
                )));
            }
            let (width, height) = match p.aspect_ratio {
                Some(a) => image(a)?,
                None => (CAMERA_DEFAULT_WIDTH, CAMERA_HEIGHT),
            };
            let dist = if center_depth > 0.0 {
                center_depth
            } else {
                1.0
            };
            let mut c = Camera {
                eye,
                target: eye + forward * dist,
                up,
                fov_y_deg: fov,
                near: 0.01,
                far: 1000.0,
                width,
                height,
            };
            c.fit_depth_range(bounds);
            if p.znear.is_finite() && p.znear > 0.0 {
                c.near = p.znear;
            }
            if let Some(f) = p.zfar.filter(|f| f.is_finite() && *f > c.near) {
                c.far = f;
            }
            c
        }
        (gltf::json::camera::Type::Orthographic, _, Some(o)) => {
            let (xmag, ymag) = (o.xmag.abs(), o.ymag.abs());
            if !(xmag.is_finite() && ymag.is_finite() && xmag > 0.0 && ymag > 0.0) {
                return Err(fmt(format!(
                    "camera {index}: orthographic xmag {} and ymag {} must be finite and non-zero",
                    o.xmag, o.ymag
                )));
            }
            let (width, height) = image(xmag / ymag)?;
            note = Some(format!(
                "orthographic camera {index} is approximated by a {ORTHOGRAPHIC_FOV_DEG}° perspective camera framing the same rectangle at the scene's centre"
            ));
            let plane = center_depth.max(o.znear.max(0.0));
            let half = (ORTHOGRAPHIC_FOV_DEG.to_radians() * 0.5).tan();
            // Pull the eye back so the frustum's cross-section at `plane` is the
            // orthographic rectangle.
            let back = ymag / half;
            let target = eye + forward * plane;
            let mut c = Camera {
                eye: target - forward * back,
                target,
                up,
                fov_y_deg: ORTHOGRAPHIC_FOV_DEG,
                near: 0.01,
                far: 1000.0,
                width,
                height,
            };
            c.fit_depth_range(bounds);
            c
        }
        _ => {
            return Err(fmt(format!(
            "camera {index}: its type's parameters (`perspective` or `orthographic`) are missing"
        )))
        }
    };
    camera.near = camera.near.max(camera.far * 1e-7);
    camera
        .validate()
        .map_err(|e| fmt(format!("camera {index}: {e}")))?;
    Ok((camera, note))
}

/// The scene light for `KHR_lights_punctual` light `index` on a node with world transform
/// `world`, with a note of what of it is ignored.
fn convert_light(
    path: &Path,
    doc: &gltf::Document,
    index: usize,
    world: Mat4,
) -> Result<(Light, Option<String>)> {
    let fmt = |what: String| Error::format(path, what);
    let light = doc
        .lights()
        .and_then(|mut l| l.nth(index))
        .ok_or_else(|| fmt(format!("light {index} does not exist")))?;
    let position = world.transform_point3(Vec3::ZERO);
    let dir = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let mut note = None;
    let out = match light.kind() {
        gltf::khr_lights_punctual::Kind::Directional => Light::Directional { to_light: -dir },
        gltf::khr_lights_punctual::Kind::Point => Light::Point { position },
        gltf::khr_lights_punctual::Kind::Spot {
            outer_cone_angle,
            inner_cone_angle,
        } => {
            let half_pi = std::f32::consts::FRAC_PI_2;
            if !(outer_cone_angle > 0.0 && outer_cone_angle <= half_pi) {
                return Err(fmt(format!(
                    "light {index}: outerConeAngle {outer_cone_angle} rad is outside (0, π/2]"
                )));
            }
            if !(inner_cone_angle >= 0.0 && inner_cone_angle < outer_cone_angle) {
                return Err(fmt(format!(
                    "light {index}: innerConeAngle {inner_cone_angle} rad is outside [0, outerConeAngle)"
                )));
            }
            note = Some(format!(
                "spot light {index}: its inner cone ({:.1}°) is ignored, the light reaching the whole outer cone ({:.1}°): the falloff between them shades, it does not change a shadow",
                inner_cone_angle.to_degrees(),
                outer_cone_angle.to_degrees()
            ));
            Light::Spot {
                position,
                target: position + dir,
                fov_deg: (2.0 * outer_cone_angle).to_degrees().min(MAX_SPOT_FOV_DEG),
            }
        }
    };
    if matches!(out, Light::Directional { .. } | Light::Spot { .. }) && dir == Vec3::ZERO {
        return Err(fmt(format!(
            "light {index}: its node's transform is degenerate"
        )));
    }
    out.validate()
        .map_err(|e| fmt(format!("light {index}: {e}")))?;
    Ok((out, note))
}
