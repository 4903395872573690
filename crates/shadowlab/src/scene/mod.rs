//! Scenes: world-space triangles in structure-of-arrays form, their materials, and the
//! camera, camera path and light that come with them.
//!
//! This module holds the [`Scene`] and [`Material`] types, the limits every loader checks
//! ([`MAX_TRIANGLES`], [`check_triangle_count`]) and [`load`], which picks a loader or a
//! generator from a scene spec, validates the result and frames a bare mesh
//! ([`Scene::place_camera`]: a ground plane and a camera). The submodules:
//!
//! - [`builtin`]: the built-in test scenes, one module per scene family (`bunny`,
//!   `random_triangles`, `chessboard`, `hairball`, `fence`, `fence_leak`, `cage`, `bumpy`,
//!   `room`, `street`), their parameters and seeded generator, and [`builtin::shapes`], the
//!   geometry generators they and the TOML format share.
//! - [`obj`], [`ply`]: the OBJ (with MTL) and PLY loaders.
//! - [`gltf`]: glTF 2.0, one module per part of the file it reads (document and limits,
//!   buffers, accessors, nodes, meshes, materials, cameras, lights).
//! - [`toml`]: the TOML scene format (the file's structure, its `[[mesh]]` entries, its
//!   `[camera]` and `[light]` sections).
//! - [`alpha_mask`]: alpha-masked casters (a texture's alpha cutting triangles out).
//! - [`mesh`]: meshes added and edited in place; [`export`]: a scene written back as OBJ;
//!   `repeats`: faces that repeat an earlier opaque face, dropped on loading.
//! - [`up`]: a mesh file's up axis, and the turn that stands a Z-up (or X-up…) file
//!   upright in shadowlab's Y-up world.
//!
//! A scene loaded without a light keeps none here: the automatic light is chosen by a
//! ray-traced estimate, which sits above this layer (the crate's `auto_light` module, whose
//! `load` is this [`load`] followed by that choice).

pub mod alpha_mask;
pub mod builtin;
pub mod export;
pub mod gltf;
mod input;
mod material;
pub mod mesh;
pub mod obj;
mod obj_masks;
pub mod ply;
mod repeats;
pub mod texture_cache;
pub mod toml;
pub mod up;

pub use input::{check_triangle_count, BYTES_PER_TRIANGLE, GROUND_TRIANGLES, MAX_TRIANGLES};
pub(crate) use input::{file_name, read_input};
pub use material::Material;
pub use up::UpAxis;

use crate::area_light::AreaLight;
use crate::camera::{Camera, CameraPath, AUTO_VIEW_DIRECTION};
use crate::error::{Error, Result};
use crate::files;
use crate::light::Light;
use crate::math::{vec3, Aabb, Mat4, Vec2, Vec3};
use std::collections::BTreeMap;
use std::path::Path;

/// A triangle soup in world space with per-triangle materials.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Name of the scene (built-in name or file name).
    pub name: String,
    /// First vertex of each triangle.
    pub v0: Vec<Vec3>,
    /// Second vertex of each triangle.
    pub v1: Vec<Vec3>,
    /// Third vertex of each triangle.
    pub v2: Vec<Vec3>,
    /// Index into `materials` of each triangle.
    pub material: Vec<u32>,
    /// The materials.
    pub materials: Vec<Material>,
    /// Texture coordinates of each triangle's three vertices, read where its material has
    /// an [`Material::alpha_mask`]: empty while no triangle needs them, else one entry per
    /// triangle (zero for triangles without a mask).
    pub uv: Vec<[Vec2; 3]>,
    /// Bounds of all vertices (kept current by the methods that add triangles).
    pub bounds: Aabb,
    /// The scene's own camera, if it has one.
    pub camera: Option<Camera>,
    /// A key-framed camera path for walkthroughs.
    pub camera_path: Option<CameraPath>,
    /// The scene's own light, if it has one; under an area light, its punctual stand-in.
    pub light: Option<Light>,
    /// The scene's area light, if its light has an area (`light` is then
    /// [`AreaLight::punctual`] of it, or the punctual light it was sized from).
    pub area_light: Option<AreaLight>,
    /// What the loader skipped or approximated, one sentence per kind (e.g. "bike.obj:
    /// skipped 201 faces with fewer than 3 vertices"), in the order met.
    pub warnings: Vec<String>,
    /// True when `light` was chosen automatically (by the crate's `auto_light` module, which
    /// sits above the ray tracer it needs) rather than given by the scene, so a caller that
    /// moves the camera may choose it again.
    pub auto_light: bool,
    /// Bumped whenever the geometry is edited in place (see [`mesh`]), so techniques that
    /// keep state for a scene across frames know to rebuild it.
    pub revision: u64,
    /// One past the last triangle of each mesh added by [`Scene::from_meshes`] or
    /// [`Scene::add_mesh`].
    pub mesh_ends: Vec<usize>,
}

impl Scene {
    /// An empty scene called `name`.
    pub fn new(name: impl Into<String>) -> Self {
        Scene {
            name: name.into(),
            ..Default::default()
        }
    }

    /// A scene from a list of triangles sharing one material; fails on non-finite vertices
    /// or an empty list.
    pub fn from_triangles(tris: Vec<[Vec3; 3]>, material: Material) -> Result<Self> {
        let mut s = Scene::new("triangles");
        let m = s.add_material(material);
        for t in tris {
            s.push(t, m);
        }
        s.validate()?;
        Ok(s)
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.v0.len()
    }

    /// True when the scene has no triangles.
    pub fn is_empty(&self) -> bool {
        self.v0.is_empty()
    }

    /// Adds a material, returning its index.
    pub fn add_material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        (self.materials.len() - 1) as u32
    }

    /// Appends one triangle.
    pub fn push(&mut self, t: [Vec3; 3], material: u32) {
        if !self.uv.is_empty() {
            self.uv.push([Vec2::ZERO; 3]);
        }
        self.push_position(t, material);
    }

    fn push_position(&mut self, t: [Vec3; 3], material: u32) {
        self.v0.push(t[0]);
        self.v1.push(t[1]);
        self.v2.push(t[2]);
        self.material.push(material);
        for p in t {
            self.bounds.grow(p);
        }
    }

    /// Appends indexed triangles transformed by `world_from_mesh`.
    pub fn push_indexed(
        &mut self,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        world_from_mesh: Mat4,
        material: u32,
    ) {
        self.reserve(indices.len());
        for tri in indices {
            let t = tri.map(|i| world_from_mesh.transform_point3(positions[i as usize]));
            self.push(t, material);
        }
    }

    /// Reserves room for `n` more triangles.
    pub fn reserve(&mut self, n: usize) {
        self.v0.reserve(n);
        self.v1.reserve(n);
        self.v2.reserve(n);
        self.material.reserve(n);
    }

    /// The vertices of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        [self.v0[i], self.v1[i], self.v2[i]]
    }

    /// The material of triangle `i`.
    #[inline]
    pub fn material_of(&self, i: usize) -> &Material {
        &self.materials[self.material[i] as usize]
    }

    /// True when some triangle lets light through.
    pub fn has_transparency(&self) -> bool {
        self.materials.iter().any(|m| !m.is_opaque())
    }

    /// Records a warning: something the loader skipped or approximated.
    pub fn warn(&mut self, what: impl Into<String>) {
        self.warnings.push(what.into());
    }

    /// Appends all triangles of `other` (materials and warnings are appended too).
    pub fn append(&mut self, other: &Scene) {
        self.warnings.extend(other.warnings.iter().cloned());
        let base = self.materials.len() as u32;
        self.materials.extend(other.materials.iter().cloned());
        self.reserve(other.len());
        for i in 0..other.len() {
            match other.uv.get(i) {
                Some(&uv) => self.push_textured(other.triangle(i), uv, base + other.material[i]),
                None => self.push(other.triangle(i), base + other.material[i]),
            }
        }
    }

    /// Recomputes `bounds` from the vertices.
    pub fn recompute_bounds(&mut self) {
        let mut b = Aabb::EMPTY;
        for i in 0..self.len() {
            for p in self.triangle(i) {
                b.grow(p);
            }
        }
        self.bounds = b;
    }

    /// Fails with a sentence naming the problem: no triangles, too many, a non-finite
    /// vertex, or a bad material.
    pub fn validate(&self) -> Result<()> {
        let err = |what: String| Error::Scene {
            scene: self.name.clone(),
            what,
        };
        if self.is_empty() {
            return Err(err("it has no triangles".into()));
        }
        if self.len() > MAX_TRIANGLES {
            return Err(Error::Limit(format!(
                "scene {} has {} triangles, more than the limit of {MAX_TRIANGLES}",
                self.name,
                self.len()
            )));
        }
        for i in 0..self.len() {
            if !self.triangle(i).iter().all(|p| p.is_finite()) {
                return Err(err(format!(
                    "triangle {i} has a non-finite (NaN or infinite) vertex"
                )));
            }
            if self.material[i] as usize >= self.materials.len() {
                return Err(err(format!(
                    "triangle {i} names material {} that does not exist",
                    self.material[i]
                )));
            }
        }
        self.validate_alpha_masks().map_err(err)?;
        for m in &self.materials {
            let ok = m.color.is_finite() && m.transmittance.is_finite();
            if !ok || m.transmittance.min_element() < 0.0 || m.transmittance.max_element() > 1.0 {
                return Err(err(format!(
                    "material {:?} has a colour or transmittance outside [0, 1]",
                    m.name
                )));
            }
        }
        Ok(())
    }

    /// Gives a bare mesh what it needs to be looked at, whatever its units, but its light: a
    /// ground plane under it (at its lowest point, 4× its footprint) when `add_ground`, and,
    /// when it has none, a camera that frames it. A missing light is chosen above this
    /// layer, where the ray tracer its choice needs is (the crate's `auto_light::auto_frame`
    /// does both).
    pub fn place_camera(&mut self, add_ground: bool) {
        let b = self.bounds;
        let size = (b.max - b.min).max_element().max(1e-6);
        if add_ground {
            let c = b.center();
            let h = size * 2.0;
            let y = b.min.y - size * 1e-3;
            let m = self.add_material(Material::opaque("ground", vec3(0.75, 0.75, 0.72)));
            let (x0, x1, z0, z1) = (c.x - h, c.x + h, c.z - h, c.z + h);
            self.push([vec3(x0, y, z0), vec3(x0, y, z1), vec3(x1, y, z1)], m);
            self.push([vec3(x0, y, z0), vec3(x1, y, z1), vec3(x1, y, z0)], m);
        }
        if self.camera.is_none() {
            let c = b.center();
            let r = (b.max - b.min).length() * 0.5;
            let fov = 45.0f32;
            let dist = r / (fov.to_radians() * 0.5).sin() * 1.05;
            self.camera = Some(Camera::look_at(
                c + AUTO_VIEW_DIRECTION.normalize() * dist,
                c,
                fov,
                1024,
                768,
            ));
        }
    }
}

/// Choices made while loading a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoadOptions {
    /// Which of the file's cameras to use: a glTF file's camera nodes in the order its
    /// hierarchy walk meets them; other scenes have at most one (index 0).
    pub camera_index: usize,
    /// Let glTF buffer URIs, OBJ `mtllib` lines and TOML mesh `file` paths name files
    /// outside the scene file's folder (by default they are refused).
    pub allow_outside_scene_dir: bool,
    /// The axis of a mesh file (`.obj`, `.ply`, `.gltf`, `.glb`) that points up; the file
    /// is turned so that it points up in shadowlab's Y-up world before it is framed (see
    /// [`up`]). Built-in and TOML scenes are Y-up already (a TOML mesh has its own `up`).
    pub up: UpAxis,
    /// Let an OBJ material without `map_d` cut its triangles out by the alpha channel of
    /// its `map_Kd` image, when that image has one (see [`obj`]). On by default.
    pub obj_kd_alpha: bool,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            camera_index: 0,
            allow_outside_scene_dir: false,
            up: UpAxis::Y,
            obj_kd_alpha: true,
        }
    }
}

/// Loads a scene from a spec: a built-in scene name, or a path to a `.toml` scene, an
/// `.obj`, `.ply`, `.gltf` or `.glb` mesh. `params` are a built-in scene's parameters
/// (an error for files). Bare meshes get a ground plane and a camera
/// ([`Scene::place_camera`]); the result is validated. A file without a light is returned
/// without one: the crate's `auto_light::load` loads through this and adds the automatic
/// light.
pub fn load(spec: &str, params: &BTreeMap<String, String>) -> Result<Scene> {
    load_with(spec, params, &LoadOptions::default())
}

/// [`load`] with [`LoadOptions`]; a camera index past the scene's cameras is an error
/// naming how many it has.
pub fn load_with(
    spec: &str,
    params: &BTreeMap<String, String>,
    options: &LoadOptions,
) -> Result<Scene> {
    let s = load_spec(spec, params, options)?;
    // The glTF loader checks the index against the file's own cameras.
    let gltf = Path::new(spec)
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"));
    let count = usize::from(s.camera.is_some());
    if !gltf && options.camera_index > 0 && options.camera_index >= count {
        return Err(Error::param(format!(
            "--camera-index {} is out of range: {} has {count} camera{}",
            options.camera_index,
            s.name,
            if count == 1 { " (index 0)" } else { "s" }
        )));
    }
    Ok(s)
}

fn load_spec(
    spec: &str,
    params: &BTreeMap<String, String>,
    options: &LoadOptions,
) -> Result<Scene> {
    let path = Path::new(spec);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let is_file = matches!(
        ext.as_deref(),
        Some("obj" | "ply" | "gltf" | "glb" | "toml")
    );
    if options.up != UpAxis::Y && ext.as_deref() == Some("toml") {
        return Err(Error::param(format!(
            "--up {} turns mesh files (.obj, .ply, .gltf, .glb), not the TOML scene {spec}: give its meshes an `up` key",
            options.up
        )));
    }
    if !is_file {
        if options.up != UpAxis::Y {
            return Err(Error::param(format!(
                "--up {} turns mesh files (.obj, .ply, .gltf, .glb), not the built-in scene {spec}",
                options.up
            )));
        }
        let s = builtin::generate(spec, params)?;
        s.validate()?;
        return Ok(s);
    }
    if let Some(k) = params.keys().next() {
        return Err(Error::param(format!(
            "--scene-param {k} applies to built-in scenes only, not to the file {spec}"
        )));
    }
    let access = files::Access::for_scene(path, options.allow_outside_scene_dir);
    let mut s = match ext.as_deref() {
        Some("obj") => obj::load_opts(path, &access, options.obj_kd_alpha)?,
        Some("ply") => ply::load(path)?,
        Some("gltf" | "glb") => gltf::load_with(path, &access, options.camera_index)?,
        Some("toml") => toml::load_opts(path, &access, options.obj_kd_alpha)?,
        _ => unreachable!("extension checked above"),
    };
    s.turn_up(options.up);
    if s.name.is_empty() {
        s.name = file_name(path);
    }
    if s.is_empty() {
        return Err(Error::format(path, "the file holds no triangles"));
    }
    let extent = s.bounds.max - s.bounds.min;
    if !(extent * 4.0).is_finite() {
        return Err(Error::format(
            path,
            format!(
                "its vertices span from {} to {}, too far apart to frame and light (scale the mesh down)",
                s.bounds.min, s.bounds.max
            ),
        ));
    }
    let bare = s.camera.is_none() && s.light.is_none() && ext.as_deref() != Some("toml");
    let framed = s.camera.is_none();
    // Before framing: the automatic light chosen later traces rays, which needs finite
    // geometry.
    s.validate()?;
    let repeated = s.drop_repeated_faces();
    if repeated > 0 {
        s.warn(format!(
            "{}: skipped {repeated} faces that repeat an earlier opaque face exactly",
            s.name
        ));
    }
    s.place_camera(bare);
    if let (true, Some(mut c)) = (framed, s.camera) {
        c.fit_depth_range(&s.bounds);
        c.validate().map_err(|e| {
            Error::format(
                path,
                format!("the camera framed around its extent {extent} is unusable ({e})"),
            )
        })?;
    }
    s.validate()?;
    Ok(s)
}
