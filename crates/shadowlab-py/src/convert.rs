//! NumPy arrays in and out, integer arguments checked, and shadowlab's errors as Python
//! exceptions.
//!
//! Every integer argument of the module is taken as an [`Int`] and converted by
//! [`Int::get`], which raises `ShadowlabError` naming the argument for a negative value,
//! one past the type's range or a value that is no integer (where a plain `u32` argument
//! would raise an `OverflowError` naming nothing); integer arrays go through [`faces`] or
//! [`indices`], which refuse fractions instead of truncating them.

use numpy::ndarray::{Array2, Array3};
use numpy::{AllowTypeChange, IntoPyArray, PyArray2, PyArray3, PyArrayLike2};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use shadowlab::math::{vec3, Vec3};

pyo3::create_exception!(
    _shadowlab,
    ShadowlabError,
    PyValueError,
    "Bad input (a scene, array, parameter, camera or light): the message is one sentence naming the culprit, as the command line prints it."
);

/// A library error as a Python exception: bad input as [`ShadowlabError`] (a
/// `ValueError`), other failures as `RuntimeError`, with the library's own sentence.
pub fn py_err(e: shadowlab::Error) -> PyErr {
    if e.is_bad_input() {
        ShadowlabError::new_err(e.to_string())
    } else {
        PyRuntimeError::new_err(e.to_string())
    }
}

/// A bad-input exception with `msg`.
pub fn bad(msg: impl Into<String>) -> PyErr {
    ShadowlabError::new_err(msg.into())
}

/// An integer argument as Python gave it: any `int` (and anything with `__index__`),
/// however large or negative, or what it is instead. Converted, and refused with its
/// name, by [`Int::get`].
#[derive(Clone, Debug)]
pub struct Int(Given);

#[derive(Clone, Debug)]
enum Given {
    /// An integer within 128 bits.
    Small(i128),
    /// An integer of more bits, shown by its number of decimal digits.
    Huge(usize),
    /// Not an integer: its `repr`, cut short.
    Other(String),
}

impl Int {
    /// The default value `v` of an argument.
    pub const fn of(v: i128) -> Self {
        Int(Given::Small(v))
    }

    /// The value as `T`, which must lie in `lo..=hi`; else a `ShadowlabError` naming
    /// `name`, the value and the range.
    pub fn get<T: TryFrom<i128>>(&self, name: &str, lo: i128, hi: i128) -> PyResult<T> {
        let outside =
            |v: &dyn std::fmt::Display| bad(format!("{name} = {v} is outside {lo}..={hi}"));
        match &self.0 {
            Given::Small(v) if (lo..=hi).contains(v) => T::try_from(*v).map_err(|_| outside(v)),
            Given::Small(v) => Err(outside(v)),
            Given::Huge(digits) => Err(outside(&format!("(an integer of {digits} digits)"))),
            Given::Other(what) => Err(bad(format!("{name} must be an integer, not {what}"))),
        }
    }
}

impl<'a, 'py> FromPyObject<'a, 'py> for Int {
    type Error = PyErr;

    fn extract(obj: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        Ok(Int(match obj.extract::<i128>() {
            Ok(v) => Given::Small(v),
            Err(_) if obj.is_instance_of::<pyo3::types::PyInt>() => {
                let digits = obj.str().map(|s| s.to_string().len()).unwrap_or(0);
                Given::Huge(digits)
            }
            Err(_) => {
                let shown = obj.repr().map(|r| r.to_string()).unwrap_or_default();
                Given::Other(shown.chars().take(40).collect())
            }
        }))
    }
}

/// A sequence of integers, each in `0..count`, named `what` in errors (triangle ids).
pub fn indices(v: &[Int], what: &str, count: usize) -> PyResult<Vec<u32>> {
    let hi = (count as i128 - 1).min(i128::from(u32::MAX));
    v.iter()
        .enumerate()
        .map(|(i, x)| x.get(&format!("{what}[{i}]"), 0, hi))
        .collect()
}

/// An `(n, 3)` array of any real dtype as points, named `what` in errors.
pub fn vec3s(a: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Vec3>> {
    let arr: PyArrayLike2<'_, f32, AllowTypeChange> = a.extract().map_err(|_| {
        bad(format!(
            "{what} must be a 2-D array of numbers of shape (n, 3)"
        ))
    })?;
    let v = arr.as_array();
    if v.ncols() != 3 {
        return Err(bad(format!(
            "{what} must have shape (n, 3), not ({}, {})",
            v.nrows(),
            v.ncols()
        )));
    }
    Ok(v.rows()
        .into_iter()
        .map(|r| vec3(r[0], r[1], r[2]))
        .collect())
}

/// An `(m, 3)` integer array as triangle indices into `vertices` vertices, named `what`.
pub fn faces(a: &Bound<'_, PyAny>, what: &str, vertices: usize) -> PyResult<Vec<[u32; 3]>> {
    // Read as f64 so a fraction is seen (an i64 cast would truncate 0.5 to 0); vertex
    // counts are below 2^53, where every integer is exact.
    let arr: PyArrayLike2<'_, f64, AllowTypeChange> = a.extract().map_err(|_| {
        bad(format!(
            "{what} must be a 2-D array of integers of shape (m, 3)"
        ))
    })?;
    let v = arr.as_array();
    if v.ncols() != 3 {
        return Err(bad(format!(
            "{what} must have shape (m, 3), not ({}, {})",
            v.nrows(),
            v.ncols()
        )));
    }
    let mut out = Vec::with_capacity(v.nrows());
    for (i, r) in v.rows().into_iter().enumerate() {
        let mut f = [0u32; 3];
        for (j, &x) in r.iter().enumerate() {
            if x.fract() != 0.0 {
                return Err(bad(format!(
                    "{what} row {i} names vertex {x}, which is not an integer"
                )));
            }
            if !(x >= 0.0 && x < vertices as f64) {
                return Err(bad(format!(
                    "{what} row {i} names vertex {x}, outside 0..{vertices}"
                )));
            }
            f[j] = x as u32;
        }
        out.push(f);
    }
    Ok(out)
}

/// Three numbers as a vector, named `what` in errors.
pub fn vec3_of(a: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec3> {
    let v: Vec<f32> = a
        .extract()
        .map_err(|_| bad(format!("{what} must be three numbers")))?;
    match v.as_slice() {
        [x, y, z] => Ok(vec3(*x, *y, *z)),
        _ => Err(bad(format!(
            "{what} must be three numbers, not {}",
            v.len()
        ))),
    }
}

/// Per-pixel RGB values as an `(height, width, 3)` float32 array.
pub fn image<'py>(py: Python<'py>, w: u32, h: u32, v: &[Vec3]) -> Bound<'py, PyArray3<f32>> {
    let flat: Vec<f32> = v.iter().flat_map(|c| c.to_array()).collect();
    Array3::from_shape_vec((h as usize, w as usize, 3), flat)
        .expect("one value per pixel")
        .into_pyarray(py)
}

/// Per-point RGB values as an `(n, 3)` float32 array.
pub fn rows<'py>(py: Python<'py>, v: &[Vec3]) -> Bound<'py, PyArray2<f32>> {
    let flat: Vec<f32> = v.iter().flat_map(|c| c.to_array()).collect();
    Array2::from_shape_vec((v.len(), 3), flat)
        .expect("three values per point")
        .into_pyarray(py)
}

/// A JSON value as the Python object `json.loads` makes of it.
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).expect("JSON values serialize");
    py.import("json")?.call_method1("loads", (text,))
}
