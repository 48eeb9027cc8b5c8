//! Conversions between Python values and the store's types, each naming the argument
//! it refuses.

use numpy::{PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyString, PyTuple};
use ygg_store::query::Direction;
use ygg_store::{FeatureRef, FeatureValue, Point, SceneView, Scope};

use crate::errors::{QueryError, unknown_layer};

/// A point from any sequence of three numbers (list, tuple, numpy array), as `f32`.
pub fn point(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Point> {
    // The common case, a list or tuple of three floats, read item by item (about half the
    // cost of the generic sequence extraction on a call that takes well under a microsecond).
    let items = if let Ok(list) = obj.cast::<PyList>() {
        (list.len() == 3).then(|| [list.get_item(0), list.get_item(1), list.get_item(2)])
    } else if let Ok(tuple) = obj.cast::<PyTuple>() {
        (tuple.len() == 3).then(|| [tuple.get_item(0), tuple.get_item(1), tuple.get_item(2)])
    } else {
        None
    };
    if let Some([Ok(x), Ok(y), Ok(z)]) = items
        && let (Ok(x), Ok(y), Ok(z)) = (x.extract::<f64>(), y.extract::<f64>(), z.extract::<f64>())
    {
        return Ok([x as f32, y as f32, z as f32]);
    }
    let xyz: [f64; 3] = obj.extract().map_err(|_| {
        QueryError::new_err(format!(
            "{what}: expected a sequence of 3 numbers, got {}",
            describe(obj)
        ))
    })?;
    Ok([xyz[0] as f32, xyz[1] as f32, xyz[2] as f32])
}

/// Points from an `(n, 3)` array-like (converted to contiguous `float32` by numpy), copied
/// so that a query can run without the GIL.
pub fn points(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Point>> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let converted = np
        .call_method1("ascontiguousarray", (obj, "float32"))
        .map_err(|e| QueryError::new_err(format!("{what}: not an array of numbers: {e}")))?;
    let array = converted.cast::<PyArray2<f32>>().map_err(|_| {
        QueryError::new_err(format!(
            "{what}: expected an (n, 3) array, got {} dimension(s)",
            converted
                .getattr("ndim")
                .and_then(|d| d.extract::<usize>())
                .unwrap_or(0)
        ))
    })?;
    let shape = array.shape();
    if shape[1] != 3 {
        return Err(QueryError::new_err(format!(
            "{what}: expected an (n, 3) array, got shape ({}, {})",
            shape[0], shape[1]
        )));
    }
    let readonly = array.readonly();
    let flat = readonly
        .as_slice()
        .map_err(|e| QueryError::new_err(format!("{what}: {e}")))?;
    Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

/// The scope named by an optional layer name: the whole graph, or that layer.
pub fn scope<V: SceneView>(view: &V, layer: Option<&str>) -> PyResult<Scope> {
    match layer {
        None => Ok(Scope::Graph),
        Some(name) => view
            .layer_by_name(name)
            .map(Scope::Layer)
            .ok_or_else(|| unknown_layer(name)),
    }
}

/// A traversal direction: `"out"` (along edges) or `"both"` (undirected).
pub fn direction(name: &str) -> PyResult<Direction> {
    match name {
        "out" => Ok(Direction::Outgoing),
        "both" => Ok(Direction::Undirected),
        other => Err(QueryError::new_err(format!(
            "direction: expected \"out\" or \"both\", got {other:?}"
        ))),
    }
}

/// A feature value as a Python object.
pub fn feature_to_py<'py>(py: Python<'py>, value: FeatureRef<'_>) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        FeatureRef::Str(s) => PyString::new(py, s).into_any(),
        FeatureRef::Int(v) => v.into_pyobject(py)?.into_any(),
        FeatureRef::Float(v) => PyFloat::new(py, v).into_any(),
        FeatureRef::Bool(v) => PyBool::new(py, v).to_owned().into_any(),
    })
}

/// A Python `str`, `bool`, `int` or `float` as a feature value.
pub fn feature_from_py(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<FeatureValue> {
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(FeatureValue::Str(s.to_cow()?.into_owned()));
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(FeatureValue::Bool(b.is_true()));
    }
    if obj.is_instance_of::<PyInt>() {
        return obj.extract::<i64>().map(FeatureValue::Int).map_err(|_| {
            QueryError::new_err(format!("{what}: integer {obj} does not fit in 64 bits"))
        });
    }
    if let Ok(f) = obj.cast::<PyFloat>() {
        return Ok(FeatureValue::Float(f.value()));
    }
    Err(QueryError::new_err(format!(
        "{what}: expected str, bool, int or float, got {}",
        describe(obj)
    )))
}

/// A short description of a Python value for a message: its type and repr.
pub fn describe(obj: &Bound<'_, PyAny>) -> String {
    let kind = obj
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into());
    let repr = obj
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "?".into());
    let repr: String = repr.chars().take(60).collect();
    format!("{kind} {repr}")
}
