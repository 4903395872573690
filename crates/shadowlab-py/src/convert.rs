//! NumPy arrays in and out, and shadowlab's errors as Python exceptions.

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
    let arr: PyArrayLike2<'_, i64, AllowTypeChange> = a.extract().map_err(|_| {
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
            if x < 0 || x as u64 >= vertices as u64 {
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
