//! `shadowlab.Scene`: a scene and the frames rendered from it.

use crate::compare::{compare_frame, in_technique, make, CompareSpec};
use crate::convert::{self, bad, py_err, vec3_of, vec3s, Int};
use crate::sweep::{plan_runs, sweeps_of, MAX_FRAMES};
use crate::{PyCamera, PyLight};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};
use shadowlab::area_light::{AreaLight, DEFAULT_LIGHT_SAMPLES};
use shadowlab::camera::Camera;
use shadowlab::light::Light;
use shadowlab::math::{vec3, Vec3};
use shadowlab::multi_light::PerLight;
use shadowlab::points::{visibility_of_points, Points};
use shadowlab::scene::mesh::IndexedMesh;
use shadowlab::scene::{LoadOptions, Material, Scene, UpAxis};
use shadowlab::techniques::{self, Frame, Shadows};
use shadowlab::view::ViewSamples;
use std::collections::BTreeMap;
use std::sync::Arc;

/// The light a scene without one is lit by, as the command line chooses it.
const DEFAULT_TO_LIGHT: Vec3 = vec3(-0.4, 1.0, 0.3);

/// A scene: world-space triangles with their materials, and the camera and light that
/// came with it (if any).
#[pyclass(name = "Scene", module = "shadowlab")]
pub struct PyScene {
    inner: Arc<Scene>,
    /// The faces of each mesh added from arrays, to move it later.
    faces: BTreeMap<usize, Vec<[u32; 3]>>,
}

/// Technique parameters from a Python mapping (values as `str()` gives them, `True` and
/// `False` as `true` and `false`), so that the `params` of a result set them again.
fn params_of(p: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, String)>> {
    let mut out = Vec::new();
    if let Some(d) = p {
        for (k, v) in d.iter() {
            let text = if v.is_instance_of::<PyBool>() {
                v.is_truthy()?.to_string()
            } else {
                v.str()?.to_string()
            };
            out.push((k.str()?.to_string(), text));
        }
    }
    Ok(out)
}

fn material(
    name: String,
    color: Option<&Bound<'_, PyAny>>,
    tr: Option<&Bound<'_, PyAny>>,
) -> PyResult<Material> {
    let mut m = Material {
        name,
        ..Material::default()
    };
    if let Some(c) = color {
        m.color = vec3_of(c, "color")?;
    }
    if let Some(t) = tr {
        m.transmittance = vec3_of(t, "transmittance")?;
    }
    Ok(m)
}

impl PyScene {
    /// The camera and light of a frame, resolved as the command line resolves them: the
    /// given light (or the scene's, or the default one) and its area, if it has one.
    fn resolve(
        &self,
        camera: Option<PyCamera>,
        light: Option<PyLight>,
    ) -> PyResult<(Camera, Light, Option<AreaLight>, u32)> {
        let s = &self.inner;
        let mut c = match camera.map(|c| c.inner).or(s.camera) {
            Some(c) => c,
            None => {
                let mut framing = Scene::new("");
                framing.bounds = s.bounds;
                framing.place_camera(false);
                framing.camera.expect("place_camera sets a camera")
            }
        };
        c.fit_depth_range(&s.bounds);
        c.validate().map_err(py_err)?;
        let (l, area, samples) = match light {
            Some(l) => (l.inner, l.area, l.samples),
            None => match s.light {
                Some(l) => (l, s.area_light, DEFAULT_LIGHT_SAMPLES),
                None => (
                    Light::Directional {
                        to_light: DEFAULT_TO_LIGHT.normalize(),
                    },
                    None,
                    DEFAULT_LIGHT_SAMPLES,
                ),
            },
        };
        l.validate().map_err(py_err)?;
        Ok((c, l.normalized(), area, samples))
    }

    /// The camera and a punctual light, for the calls that take no area light.
    fn resolve_punctual(
        &self,
        camera: Option<PyCamera>,
        light: Option<PyLight>,
        call: &str,
    ) -> PyResult<(Camera, Light)> {
        match self.resolve(camera, light)? {
            (c, l, None, _) => Ok((c, l)),
            (_, _, Some(a), _) => Err(bad(format!(
                "{call} takes punctual lights only, not a {} light; Scene.render and \
                 Scene.compare take area lights",
                a.kind()
            ))),
        }
    }
}

#[pymethods]
impl PyScene {
    /// A built-in scene by name, or a `.toml`, `.obj`, `.ply`, `.gltf` or `.glb` file
    /// (bare meshes get a ground plane, a camera and a light); `params` are a built-in
    /// scene's parameters. `up` is a mesh file's up axis (`"z"` stands a Z-up file
    /// upright); `obj_kd_alpha=False` keeps OBJ materials without `map_d` whole where their
    /// `map_Kd` image has alpha.
    #[staticmethod]
    #[pyo3(signature = (spec, params = None, *, up = "y", obj_kd_alpha = true))]
    fn load(
        py: Python<'_>,
        spec: String,
        params: Option<&Bound<'_, PyDict>>,
        up: &str,
        obj_kd_alpha: bool,
    ) -> PyResult<Self> {
        let params: BTreeMap<String, String> = params_of(params)?.into_iter().collect();
        let up: UpAxis = up.parse().map_err(|e| bad(format!("up {e}")))?;
        let options = LoadOptions {
            up,
            obj_kd_alpha,
            ..Default::default()
        };
        let s = py
            .detach(|| shadowlab::auto_light::load_with(&spec, &params, &options))
            .map_err(py_err)?;
        Ok(PyScene {
            inner: Arc::new(s),
            faces: BTreeMap::new(),
        })
    }

    /// A scene of one mesh: `vertices` `(n, 3)` float32, `faces` `(m, 3)` integer indices.
    /// `ground=True` adds a ground plane under it; the camera and light are chosen to
    /// frame it unless given to each call.
    #[staticmethod]
    #[pyo3(signature = (vertices, faces, *, name = "arrays".to_string(), color = None, transmittance = None, ground = false))]
    fn from_arrays(
        vertices: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        name: String,
        color: Option<&Bound<'_, PyAny>>,
        transmittance: Option<&Bound<'_, PyAny>>,
        ground: bool,
    ) -> PyResult<Self> {
        let v = vec3s(vertices, "vertices")?;
        let f = convert::faces(faces, "faces", v.len())?;
        let m = material("mesh0".into(), color, transmittance)?;
        let mut s = Scene::from_meshes(
            &name,
            &[IndexedMesh {
                positions: &v,
                indices: &f,
                material: &m,
            }],
        )
        .map_err(py_err)?;
        if ground {
            // As the command line frames a bare mesh: the ground, and a camera and light
            // chosen for the mesh alone.
            shadowlab::auto_light::auto_frame(&mut s, true);
        }
        Ok(PyScene {
            inner: Arc::new(s),
            faces: BTreeMap::from([(0, f)]),
        })
    }

    /// Adds a mesh from arrays; returns its mesh number (for `set_mesh_vertices`).
    #[pyo3(signature = (vertices, faces, *, color = None, transmittance = None))]
    fn add_mesh(
        &mut self,
        vertices: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        color: Option<&Bound<'_, PyAny>>,
        transmittance: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<usize> {
        let v = vec3s(vertices, "vertices")?;
        let f = convert::faces(faces, "faces", v.len())?;
        let s = Arc::make_mut(&mut self.inner);
        let m = material(format!("mesh{}", s.mesh_count()), color, transmittance)?;
        let i = s
            .add_mesh(&IndexedMesh {
                positions: &v,
                indices: &f,
                material: &m,
            })
            .map_err(py_err)?;
        self.faces.insert(i, f);
        Ok(i)
    }

    /// Moves mesh `mesh` (added from arrays) to new vertex positions, same faces: a moving
    /// or deforming object. Techniques see the scene's revision change and drop what they
    /// kept for the old geometry.
    fn set_mesh_vertices(&mut self, mesh: Int, vertices: &Bound<'_, PyAny>) -> PyResult<()> {
        let mesh: usize = mesh.get("mesh", 0, i128::from(u32::MAX))?;
        let f = self
            .faces
            .get(&mesh)
            .ok_or_else(|| bad(format!("scene has no mesh {mesh} added from arrays")))?;
        let v = vec3s(vertices, "vertices")?;
        Arc::make_mut(&mut self.inner)
            .replace_mesh(mesh, &v, f)
            .map_err(py_err)
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }
    /// Number of triangles.
    #[getter]
    fn triangles(&self) -> usize {
        self.inner.len()
    }
    /// Bumped on every geometry edit.
    #[getter]
    fn revision(&self) -> u64 {
        self.inner.revision
    }
    /// `(min, max)` corners of the bounding box.
    #[getter]
    fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        (
            self.inner.bounds.min.to_array(),
            self.inner.bounds.max.to_array(),
        )
    }
    /// The camera a frame uses when none is given (the scene's own, or one that frames it).
    #[getter]
    fn camera(&self) -> PyResult<PyCamera> {
        Ok(PyCamera {
            inner: self.resolve(None, None)?.0,
        })
    }
    /// The light a frame uses when none is given (the scene's own, or the default).
    #[getter]
    fn light(&self) -> PyResult<PyLight> {
        let (_, inner, area, samples) = self.resolve(None, None)?;
        Ok(PyLight {
            inner,
            area,
            samples,
        })
    }

    /// The shadow term of one frame: an `(H, W, 3)` float32 array of RGB transmittance
    /// towards the light (1 = lit; uncovered pixels 1). Under an area light, `raytrace` is
    /// the soft-shadow reference and the soft techniques sample the light, both with
    /// the light's `samples` per point. The GIL is released meanwhile.
    #[pyo3(signature = (technique = "afsm".to_string(), camera = None, light = None, params = None))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        technique: String,
        camera: Option<PyCamera>,
        light: Option<PyLight>,
        params: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (c, l, area, light_samples) = self.resolve(camera, light)?;
        shadowlab::limits::check_frame(c.width, c.height, 1, "the camera").map_err(py_err)?;
        let params = params_of(params)?;
        let scene = Arc::clone(&self.inner);
        let vis = py
            .detach(move || -> shadowlab::Result<_> {
                let mut t = make(&technique, &params)?;
                let view = ViewSamples::render(&scene, &c);
                let frame =
                    Frame::new(&scene, &c, &l, &view).with_area(area.as_ref(), light_samples);
                let s = t.render(&frame).map_err(|e| in_technique(&technique, e))?;
                Ok(s.visibility)
            })
            .map_err(py_err)?;
        Ok(convert::image(py, vis.width, vis.height, &vis.value).into_any())
    }

    /// One shadow term per light of one frame (a list of `(H, W, 3)` arrays), each equal
    /// to a one-light frame's.
    #[pyo3(signature = (technique, lights, camera = None, params = None))]
    fn render_lights<'py>(
        &self,
        py: Python<'py>,
        technique: String,
        lights: Vec<PyLight>,
        camera: Option<PyCamera>,
        params: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Vec<Bound<'py, PyAny>>> {
        let (c, l0, _, _) = self.resolve(camera, None)?;
        shadowlab::limits::check_frame(c.width, c.height, lights.len(), "the camera")
            .map_err(py_err)?;
        let params = params_of(params)?;
        if let Some(a) = lights.iter().find_map(|l| l.area) {
            return Err(bad(format!(
                "render_lights takes punctual lights only, not a {} light; render each \
                 area light with Scene.render",
                a.kind()
            )));
        }
        let lights: Vec<Light> = lights.iter().map(|l| l.inner).collect();
        let scene = Arc::clone(&self.inner);
        let all = py
            .detach(move || -> shadowlab::Result<Vec<Shadows>> {
                let mut per = PerLight::new(&technique, &params)?;
                let view = ViewSamples::render(&scene, &c);
                per.render(&Frame::new(&scene, &c, &l0, &view), &lights)
                    .map_err(|e| in_technique(&technique, e))
            })
            .map_err(py_err)?;
        Ok(all
            .iter()
            .map(|s| {
                convert::image(
                    py,
                    s.visibility.width,
                    s.visibility.height,
                    &s.visibility.value,
                )
                .into_any()
            })
            .collect())
    }

    /// The shadow term of arbitrary points: `points` and `normals` `(n, 3)`; `triangles`
    /// optionally names the triangle each point lies on (skipped by its shadow ray).
    /// Returns `(n, 3)` float32. Techniques: raytrace and afsm (exact), sm, pcf, csm, vsm.
    #[pyo3(signature = (points, normals, light = None, technique = "raytrace".to_string(), params = None, triangles = None))]
    fn visibility<'py>(
        &self,
        points: &Bound<'py, PyAny>,
        normals: &Bound<'py, PyAny>,
        light: Option<PyLight>,
        technique: String,
        params: Option<&Bound<'py, PyDict>>,
        triangles: Option<Vec<Int>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let py = points.py();
        let triangles = triangles
            .map(|t| convert::indices(&t, "triangles", self.inner.len()))
            .transpose()?;
        let (_, l) = self.resolve_punctual(None, light, "Scene.visibility")?;
        let p = vec3s(points, "points")?;
        let n = vec3s(normals, "normals")?;
        let params = params_of(params)?;
        let scene = Arc::clone(&self.inner);
        let v = py
            .detach(move || -> shadowlab::Result<Vec<Vec3>> {
                let mut t = make(&technique, &params)?;
                let q = Points {
                    triangle: triangles.as_deref(),
                    ..Points::new(&p, &n)
                };
                visibility_of_points(t.as_mut(), &scene, &l, &q)
            })
            .map_err(py_err)?;
        Ok(convert::rows(py, &v).into_any())
    }

    /// Every technique of `techniques` (default: all) against the ray-traced reference on
    /// one frame: a dict shaped like `metrics.json` (`results[i]` with `mismatch_rate`,
    /// `mean_abs_error`, `time_ms`, `memory_bytes`, ...). `params` maps a technique name
    /// to its parameters. In `techniques`, `"all"` stands for every CPU technique and
    /// `"gpu:all"` for every GPU one, and a technique's `gpu:` twin follows it, as
    /// `compare --techniques` orders them.
    /// Under an area light the reference is the soft-shadow reference with
    /// the light's `samples` per pixel, and `reference.mean_std_error` states its own
    /// noise.
    ///
    /// `sweeps` maps `"technique.key"` to a list of values, as `--sweep`: one result per
    /// value (labelled `technique.key=value`, with `sweep`), all over one camera pass and
    /// one reference. `frames > 1` renders the scene's camera path (a still camera without
    /// one) and measures every frame against its own reference (`results[i].frames`).
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (techniques = None, camera = None, light = None, params = None, reference_spp = Int::of(1), reference_pattern = "grid".to_string(), sweeps = None, frames = Int::of(1)))]
    fn compare<'py>(
        slf: PyRef<'py, Self>,
        techniques: Option<Vec<String>>,
        camera: Option<PyCamera>,
        light: Option<PyLight>,
        params: Option<&Bound<'py, PyDict>>,
        reference_spp: Int,
        reference_pattern: String,
        sweeps: Option<&Bound<'py, PyDict>>,
        frames: Int,
    ) -> PyResult<Bound<'py, PyAny>> {
        let reference_spp: u32 = reference_spp.get("reference_spp", 1, u32::MAX.into())?;
        let py = slf.py();
        let (c, l, area, light_samples) = slf.resolve(camera, light)?;
        let names: Vec<String> = match techniques {
            Some(list) => techniques::expand_names(&list),
            None => techniques::ALL.iter().map(|s| s.to_string()).collect(),
        };
        if names.len() > shadowlab::limits::MAX_RUNS {
            return Err(bad(format!(
                "techniques lists {} runs, more than the limit of {}",
                names.len(),
                shadowlab::limits::MAX_RUNS
            )));
        }
        // Each run's result and the reference's are kept until the comparison is made.
        shadowlab::limits::check_frame(c.width, c.height, names.len() + 1, "the camera")
            .map_err(py_err)?;
        let mut per: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
        if let Some(d) = params {
            for (k, v) in d.iter() {
                let t = k.str()?.to_string();
                if !names.contains(&t) {
                    return Err(bad(format!(
                        "params names technique {t}, which is not among techniques {}",
                        names.join(",")
                    )));
                }
                let v = v
                    .cast_into::<PyDict>()
                    .map_err(|_| bad(format!("params[{t:?}] must be a dict of parameters")))?;
                per.insert(t, params_of(Some(&v))?);
            }
        }
        let frames: usize = frames.get("frames", 1, MAX_FRAMES as i128)?;
        let sweeps = sweeps_of(sweeps, &names)?;
        let spec = CompareSpec {
            kind: reference_pattern.parse().map_err(py_err)?,
            runs: plan_runs(&names, &per, &sweeps)?,
            spp: reference_spp,
            pattern_name: reference_pattern,
            area,
            light_samples,
            frames,
        };
        let scene = Arc::clone(&slf.inner);
        let metrics = py
            .detach(move || compare_frame(&scene, &c, &l, &spec))
            .map_err(py_err)?;
        convert::json_to_py(py, &metrics)
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene(name={:?}, triangles={})",
            self.inner.name,
            self.inner.len()
        )
    }
}
