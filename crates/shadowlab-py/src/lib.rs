//! The `shadowlab` Python package's native module: scenes from files or NumPy arrays,
//! cameras, lights, and the techniques' shadow terms as NumPy arrays. Every long
//! computation runs with the GIL released, on a copy of the inputs the call owns.
//!
//! Frames are set up as `shadowlab render` and `shadowlab compare` set them up — the
//! scene's camera (or the auto-framed one) with its depth range fitted to the scene, the
//! scene's light (or the default one) normalized — so the same scene and parameters give
//! the command line's values bit for bit.

mod compare;
mod convert;
mod scene;
mod sweep;

use convert::{bad, py_err, vec3_of, Int, ShadowlabError};
use pyo3::prelude::*;
use shadowlab::area_light::{check_light_samples, AreaLight, DEFAULT_LIGHT_SAMPLES};
use shadowlab::camera::{Camera, Projection};
use shadowlab::light::Light;

/// A camera (pixel `(x, y)` covers `[x, x+1) × [y, y+1)`, row 0 at the top): a
/// perspective pinhole (`fov_y_deg` is the vertical field of view) or, made by
/// `Camera.orthographic`, parallel rays viewing the rectangle `2·xmag × 2·ymag`.
#[pyclass(name = "Camera", module = "shadowlab", from_py_object)]
#[derive(Clone, Copy)]
pub struct PyCamera {
    pub inner: Camera,
}

/// `width` and `height` of an image, each in `1..=MAX_IMAGE_SIDE`.
fn image_size(width: &Int, height: &Int) -> PyResult<(u32, u32)> {
    let side = i128::from(shadowlab::camera::MAX_IMAGE_SIDE);
    Ok((width.get("width", 1, side)?, height.get("height", 1, side)?))
}

#[pymethods]
impl PyCamera {
    #[new]
    #[pyo3(signature = (eye, target, fov_y_deg = 45.0, width = Int::of(1024), height = Int::of(768)))]
    fn new(
        eye: &Bound<'_, PyAny>,
        target: &Bound<'_, PyAny>,
        fov_y_deg: f32,
        width: Int,
        height: Int,
    ) -> PyResult<Self> {
        let (width, height) = image_size(&width, &height)?;
        let c = Camera::look_at(
            vec3_of(eye, "camera eye")?,
            vec3_of(target, "camera target")?,
            fov_y_deg,
            width,
            height,
        );
        c.validate().map_err(py_err)?;
        Ok(PyCamera { inner: c })
    }

    /// An orthographic camera at `eye` looking at `target`, viewing the rectangle
    /// `2·xmag × 2·ymag` (world units) across its view axis; `xmag` defaults to `ymag`
    /// times the image's aspect.
    #[staticmethod]
    #[pyo3(signature = (eye, target, ymag, xmag = None, width = Int::of(1024), height = Int::of(768)))]
    fn orthographic(
        eye: &Bound<'_, PyAny>,
        target: &Bound<'_, PyAny>,
        ymag: f32,
        xmag: Option<f32>,
        width: Int,
        height: Int,
    ) -> PyResult<Self> {
        let (width, height) = image_size(&width, &height)?;
        let xmag = xmag.unwrap_or(ymag * width as f32 / height.max(1) as f32);
        let c = Camera::orthographic(
            vec3_of(eye, "camera eye")?,
            vec3_of(target, "camera target")?,
            (xmag, ymag),
            width,
            height,
        );
        c.validate().map_err(py_err)?;
        Ok(PyCamera { inner: c })
    }

    /// `"perspective"` or `"orthographic"`.
    #[getter]
    fn projection(&self) -> &'static str {
        self.inner.projection.name()
    }
    /// An orthographic camera's half width (`None` for a perspective one).
    #[getter]
    fn xmag(&self) -> Option<f32> {
        match self.inner.projection {
            Projection::Orthographic { xmag, .. } => Some(xmag),
            Projection::Perspective => None,
        }
    }
    /// An orthographic camera's half height (`None` for a perspective one).
    #[getter]
    fn ymag(&self) -> Option<f32> {
        match self.inner.projection {
            Projection::Orthographic { ymag, .. } => Some(ymag),
            Projection::Perspective => None,
        }
    }
    /// Eye position.
    #[getter]
    fn eye(&self) -> [f32; 3] {
        self.inner.eye.to_array()
    }
    /// The point looked at.
    #[getter]
    fn target(&self) -> [f32; 3] {
        self.inner.target.to_array()
    }
    /// Vertical field of view in degrees.
    #[getter]
    fn fov_y_deg(&self) -> f32 {
        self.inner.fov_y_deg
    }
    /// Image width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.inner.width
    }
    /// Image height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.inner.height
    }

    /// The same camera with another image size (an orthographic one keeps its `ymag`
    /// and widens or narrows its `xmag` with the image).
    fn with_size(&self, width: Int, height: Int) -> PyResult<Self> {
        let (width, height) = image_size(&width, &height)?;
        let mut c = self.inner;
        (c.width, c.height) = (width, height);
        // An orthographic camera keeps its height and its pixels square.
        if let Projection::Orthographic { ymag, .. } = c.projection {
            let xmag = ymag * width as f32 / height.max(1) as f32;
            c.projection = Projection::Orthographic { xmag, ymag };
        }
        c.validate().map_err(py_err)?;
        Ok(PyCamera { inner: c })
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        if let Projection::Orthographic { xmag, ymag } = c.projection {
            return format!(
                "Camera.orthographic(eye={:?}, target={:?}, ymag={ymag}, xmag={xmag}, width={}, height={})",
                c.eye.to_array(),
                c.target.to_array(),
                c.width,
                c.height
            );
        }
        format!(
            "Camera(eye={:?}, target={:?}, fov_y_deg={}, width={}, height={})",
            c.eye.to_array(),
            c.target.to_array(),
            c.fov_y_deg,
            c.width,
            c.height
        )
    }
}

/// A light: `Light.directional(to_light)`, `Light.point(position)` or
/// `Light.spot(position, target, fov_deg)`; an area light `Light.rect(centre, edge_u,
/// edge_v)`, `Light.disk(centre, normal, radius)`, `Light.sphere(centre, radius)`, or any
/// punctual light given a size (`light.sized(size)`). An area light carries the number of
/// light samples per point (`samples`, default 256, as `--light-samples`) that the
/// soft-shadow reference (`raytrace`) and the soft techniques take; map-based techniques
/// see its centre as a punctual light.
#[pyclass(name = "Light", module = "shadowlab", from_py_object)]
#[derive(Clone)]
pub struct PyLight {
    /// The punctual light, or an area light's punctual stand-in.
    pub inner: Light,
    /// The area light, when the light has an area.
    pub area: Option<AreaLight>,
    /// Light samples per point under the area light.
    pub samples: u32,
}

impl PyLight {
    fn checked(l: Light) -> PyResult<Self> {
        l.validate().map_err(py_err)?;
        Ok(PyLight {
            inner: l.normalized(),
            area: None,
            samples: DEFAULT_LIGHT_SAMPLES,
        })
    }

    fn area(a: AreaLight, samples: u32) -> PyResult<Self> {
        a.validate().map_err(py_err)?;
        check_light_samples(samples).map_err(py_err)?;
        let a = a.normalized();
        Ok(PyLight {
            inner: a.punctual(),
            area: Some(a),
            samples,
        })
    }
}

#[pymethods]
impl PyLight {
    /// Parallel light from the direction `to_light` (from the scene towards the light).
    #[staticmethod]
    fn directional(to_light: &Bound<'_, PyAny>) -> PyResult<Self> {
        Self::checked(Light::Directional {
            to_light: vec3_of(to_light, "directional light direction")?,
        })
    }
    /// Light in every direction from `position`.
    #[staticmethod]
    fn point(position: &Bound<'_, PyAny>) -> PyResult<Self> {
        Self::checked(Light::Point {
            position: vec3_of(position, "point light position")?,
        })
    }
    /// A cone of light from `position` towards `target`, `fov_deg` wide.
    #[staticmethod]
    fn spot(
        position: &Bound<'_, PyAny>,
        target: &Bound<'_, PyAny>,
        fov_deg: f32,
    ) -> PyResult<Self> {
        Self::checked(Light::Spot {
            position: vec3_of(position, "spot light position")?,
            target: vec3_of(target, "spot light target")?,
            fov_deg,
        })
    }
    /// A parallelogram light `centre + s·edge_u + t·edge_v`, `s, t ∈ [-½, ½]` (full edges),
    /// emitting from both faces.
    #[staticmethod]
    #[pyo3(signature = (centre, edge_u, edge_v, samples = Int::of(DEFAULT_LIGHT_SAMPLES as i128)))]
    fn rect(
        centre: &Bound<'_, PyAny>,
        edge_u: &Bound<'_, PyAny>,
        edge_v: &Bound<'_, PyAny>,
        samples: Int,
    ) -> PyResult<Self> {
        let samples = samples.get("samples", 0, u32::MAX.into())?;
        let a = AreaLight::Rect {
            centre: vec3_of(centre, "rect light centre")?,
            edge_u: vec3_of(edge_u, "rect light edge_u")?,
            edge_v: vec3_of(edge_v, "rect light edge_v")?,
        };
        Self::area(a, samples)
    }
    /// A disk light of `radius` about `centre`, facing along `normal` (both faces emit).
    #[staticmethod]
    #[pyo3(signature = (centre, normal, radius, samples = Int::of(DEFAULT_LIGHT_SAMPLES as i128)))]
    fn disk(
        centre: &Bound<'_, PyAny>,
        normal: &Bound<'_, PyAny>,
        radius: f32,
        samples: Int,
    ) -> PyResult<Self> {
        let samples = samples.get("samples", 0, u32::MAX.into())?;
        let a = AreaLight::Disk {
            centre: vec3_of(centre, "disk light centre")?,
            normal: vec3_of(normal, "disk light normal")?,
            radius,
        };
        Self::area(a, samples)
    }
    /// A spherical light of `radius` about `centre`.
    #[staticmethod]
    #[pyo3(signature = (centre, radius, samples = Int::of(DEFAULT_LIGHT_SAMPLES as i128)))]
    fn sphere(centre: &Bound<'_, PyAny>, radius: f32, samples: Int) -> PyResult<Self> {
        let samples = samples.get("samples", 0, u32::MAX.into())?;
        let a = AreaLight::Sphere {
            centre: vec3_of(centre, "sphere light centre")?,
            radius,
        };
        Self::area(a, samples)
    }
    /// This punctual light given a size, as `--light-size`: a point light becomes a sphere
    /// of radius `size`, a spot light a disk of radius `size` facing its target, a
    /// directional light a sun of angular diameter `size` degrees.
    #[pyo3(signature = (size, samples = Int::of(DEFAULT_LIGHT_SAMPLES as i128)))]
    fn sized(&self, size: f32, samples: Int) -> PyResult<Self> {
        let samples = samples.get("samples", 0, u32::MAX.into())?;
        if self.area.is_some() {
            return Err(bad("sized: the light already has an area"));
        }
        let a = AreaLight::sized(&self.inner, size).map_err(py_err)?;
        let mut l = Self::area(a, samples)?;
        // A sized spot light keeps its cone: the stand-in stays the spot light itself.
        l.inner = self.inner;
        Ok(l)
    }
    /// Light samples per point under an area light (the reference's and the soft
    /// techniques'); 256 unless given.
    #[getter]
    fn samples(&self) -> u32 {
        self.samples
    }
    /// `"directional"`, `"point"` or `"spot"`; for an area light its shape (`"rect"`,
    /// `"disk"`, `"sphere"`, `"distant"`).
    #[getter]
    fn kind(&self) -> &'static str {
        match &self.area {
            Some(a) => a.kind(),
            None => self.inner.kind(),
        }
    }
    /// True for an area light.
    #[getter]
    fn is_area(&self) -> bool {
        self.area.is_some()
    }
    /// The light as `metrics.json` records it (an area light as `{"area": …, "stand_in":
    /// …}`).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        convert::json_to_py(py, &self.json())
    }
    fn __repr__(&self) -> String {
        format!("Light({})", self.json())
    }
}

impl PyLight {
    fn json(&self) -> serde_json::Value {
        let punctual = serde_json::to_value(self.inner).expect("lights serialize");
        match &self.area {
            None => punctual,
            Some(a) => serde_json::json!({
                "area": serde_json::to_value(a).expect("area lights serialize"),
                "samples": self.samples,
                "stand_in": punctual,
            }),
        }
    }
}

/// Every technique name, in the order reports list them.
#[pyfunction]
fn techniques() -> Vec<&'static str> {
    shadowlab::techniques::ALL.to_vec()
}

/// Reads a visibility EXR written by `shadowlab render --visibility`: an `(H, W, 4)`
/// float32 array, RGB = shadow term, A = coverage.
#[pyfunction]
fn read_exr<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let (vis, covered) = py
        .detach(|| shadowlab::shade::read_visibility_exr(&path))
        .map_err(py_err)?;
    let flat: Vec<f32> = vis
        .value
        .iter()
        .zip(&covered)
        .flat_map(|(v, &c)| [v.x, v.y, v.z, if c { 1.0 } else { 0.0 }])
        .collect();
    let arr =
        numpy::ndarray::Array3::from_shape_vec((vis.height as usize, vis.width as usize, 4), flat)
            .map_err(|e| bad(e.to_string()))?;
    Ok(numpy::IntoPyArray::into_pyarray(arr, py).into_any())
}

#[pymodule]
fn _shadowlab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The `gpu:` techniques, created by name like the library's own.
    shadowlab_gpu::register();
    m.add_class::<PyCamera>()?;
    m.add_class::<PyLight>()?;
    m.add_class::<scene::PyScene>()?;
    m.add_function(wrap_pyfunction!(techniques, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add("ShadowlabError", m.py().get_type::<ShadowlabError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
