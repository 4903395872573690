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
//!   gives the transmittance `1 − a` in every channel (the texture's alpha is not used,
//!   as before: a uniform filter); `OPAQUE` is opaque. `MASK` is an alpha mask
//!   ([`crate::scene::alpha_mask`]): the base colour texture's alpha times the factor's,
//!   read by the nearest texel at the interpolated texture coordinates of the set the
//!   texture names (`TEXCOORD_0` by default), with the sampler's wrap modes, against
//!   `alphaCutoff` (default 0.5); a cut-out point neither casts a shadow nor is seen, in
//!   every technique and the reference. Only the images of `MASK` materials are read
//!   (`textures`): PNG and GIF are decoded, a JPEG has no alpha and is opaque; one that
//!   cannot be read leaves its material opaque and is named in the warnings.
//!   `KHR_texture_transform` is not read (the extension warnings say so). A
//!   primitive without a material gets [`Material::default`](crate::scene::Material). Material extensions
//!   (`KHR_materials_transmission`, `…_volume`, …) are ignored.
//! - The camera nodes met in that walk, in order; the one at the asked index
//!   ([`load_with_camera`], the first by default): eye at the node's origin, looking down
//!   its −Z with its +Y up. A perspective camera keeps `yfov`, `znear` and `zfar` (a
//!   missing `zfar` — an infinite projection — is replaced by the far distance that fits
//!   the scene); the image is 768 pixels high and as wide as `aspectRatio` says (1024
//!   without one). An orthographic camera stays orthographic: it views the rectangle
//!   `2·xmag × 2·ymag` between `znear` and `zfar` (a `znear` of 0 is lifted to a tiny
//!   share of `zfar`), the image aspect is `xmag / ymag`; an `xmag` or `ymag` that is not
//!   positive, or a `zfar` not beyond `znear`, is refused. The camera's target is placed on its axis at the depth
//!   of the scene's centre, so moving it closer or farther keeps the scene in view.
//! - The first node carrying a `KHR_lights_punctual` light: directional (shining down the
//!   node's −Z), point (at its origin), or spot (at its origin, down its −Z, with
//!   `fov_deg = 2 · outerConeAngle`, at most [`MAX_SPOT_FOV_DEG`]). Colour, intensity and
//!   range do not matter for shadows and are ignored. The inner cone is ignored too: the
//!   falloff between the cones dims the light inside its cone, it does not move a shadow.
//!
//! Lenient where nothing that casts a shadow is lost, and saying so: every kind of thing
//! skipped or approximated above (primitives by mode, morph targets, skins, the alpha
//! modes, the spot's inner cone) and every extension the file
//! uses that shadowlab does not read is one sentence in [`Scene::warnings`]. A file that
//! *requires* an extension shadowlab lacks is refused naming it; those it reads are
//! [`READ_EXTENSIONS`], and [`SHADING_ONLY_EXTENSIONS`] change no shadow. A glTF 1.0
//! file (by its GLB header or `asset.version`) is refused as such.
//!
//! Every failure is an [`Error`] naming the file and the element at fault: a buffer file
//! that cannot be read (by its URI and resolved path), a buffer shorter than declared, an
//! accessor reaching past its buffer view, an index out of range (mesh, primitive, index),
//! a non-finite position (mesh, primitive, vertex), a hierarchy with a cycle.
//!
//! The reader, by what it reads: `document` (the GLB container, the version, the counts
//! of the top-level arrays, the crate's validation and the extensions), `buffers` (the
//! buffers and their URIs), `accessors` (accessors, sparse ones included, decoded to
//! numbers), `nodes` (the hierarchy walk and its transforms), `meshes` (primitives into
//! triangles), `materials` (colour, alpha and masks), `textures` (the masks' images),
//! `cameras` and `lights`
//! (`KHR_lights_punctual`); this module holds what they share and puts them together.

mod accessors;
mod buffers;
mod cameras;
mod document;
mod lights;
mod materials;
mod meshes;
mod nodes;
mod textures;

use super::Scene;
use crate::error::{Error, Result};
use crate::files::{Access, MAX_FILE_BYTES};
use crate::math::Mat4;
use meshes::Primitive;
use std::path::Path;
use std::rc::Rc;

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
    let bytes = super::read_input(path, MAX_FILE_BYTES, document::sniff)?;
    let fmt = |what: String| Error::format(path, what);
    let glb = bytes.starts_with(b"glTF");
    if let (true, Some(v)) = (glb, bytes.get(4..8)) {
        let version = u32::from_le_bytes([v[0], v[1], v[2], v[3]]);
        if version != 2 {
            return Err(fmt(document::unsupported_version(&format!(
                "GLB container version {version}"
            ))));
        }
    }
    let json = if glb {
        document::glb_json(&bytes).map_err(fmt)?
    } else {
        &bytes[..]
    };
    document::check_counts(json).map_err(fmt)?;
    let gltf =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(
            |e| match document::json_version(&bytes).filter(|v| !v.starts_with('2')) {
                Some(v) => fmt(document::unsupported_version(&format!(
                    "asset version {v:?}"
                ))),
                None => fmt(document::describe(e)),
            },
        )?;
    let version = &gltf.document.as_json().asset.version;
    if !version.starts_with("2.") {
        return Err(fmt(document::unsupported_version(&format!(
            "asset version {:?}",
            version.chars().take(16).collect::<String>()
        ))));
    }
    document::validate(gltf.document.as_json()).map_err(|e| fmt(document::describe(e)))?;
    let mut warnings = document::extension_warnings(path, gltf.document.as_json())?;
    let gltf::Gltf { document, blob } = gltf;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = buffers::load_buffers(path, base, access, &document, blob)?;
    let name = super::file_name(path);
    let mut loader = Loader {
        path,
        access,
        doc: &document,
        buffers,
        scene: Scene::new(name),
        meshes: vec![None; document.meshes().len()],
        materials: vec![None; document.materials().len()],
        default_material: None,
        cameras: Vec::new(),
        light: None,
        skipped: Default::default(),
        textures: Default::default(),
        texture_cache: Default::default(),
        notes: Vec::new(),
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
        notes,
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
        scene.camera = Some(cameras::convert_camera(
            path,
            &document,
            index,
            world,
            &scene.bounds,
        )?);
    }
    if let Some((index, world)) = light {
        let (l, note) = lights::convert_light(path, &document, index, world)?;
        scene.light = Some(l);
        warnings.extend(note.map(|n| format!("{name}: {n}")));
    }
    warnings.extend(
        skipped
            .into_iter()
            .map(|(what, n)| format!("{name}: {}", what.describe(n))),
    );
    warnings.extend(notes.into_iter().map(|n| format!("{name}: {n}")));
    scene.warnings = warnings;
    Ok(scene)
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
    /// A material with alpha mode `MASK` whose texture could not be read, cast as opaque.
    Mask,
    /// An alpha-masked primitive without the texture coordinates its texture names.
    NoTexCoords,
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
                "{n} material{s} with alpha mode MASK cast opaque shadows (their texture could not be read)"
            ),
            Skip::NoTexCoords => format!(
                "{n} alpha-masked primitive{s} lack the texture coordinates their texture names (the texture is read at (0, 0) everywhere)"
            ),
            Skip::Blend => format!(
                "{n} material{s} with alpha mode BLEND cast shadows of uniform transmittance 1 − alpha (the texture's alpha is not used)"
            ),
        }
    }
}

/// The state of one file's loading: the document, its buffers, the scene built so far and
/// what the hierarchy walk has met.
struct Loader<'a> {
    path: &'a Path,
    /// Where the file's image URIs may point.
    access: &'a Access,
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
    /// Alpha textures by glTF image index, once read (or why they could not be).
    textures: std::collections::BTreeMap<usize, textures::TextureResult>,
    /// The decoded images, shared by content and summed against the memory limit.
    texture_cache: crate::scene::texture_cache::TextureCache,
    /// Sentences for the warnings beyond the counted kinds (an unreadable texture).
    notes: Vec<String>,
}

impl Loader<'_> {
    fn err(&self, what: String) -> Error {
        Error::format(self.path, what)
    }
}
