//! Conversions between Python values and the store's types, each naming the argument
//! it refuses.

use numpy::{PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::Value;
use ygg_dsg::objects::ObjectQuery;
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

/// A query of the object contract from a dict (read directly into a JSON value, no text
/// in between) or a JSON string, refused with the message `ygg query` gives for
/// the same line.
pub fn object_query(obj: &Bound<'_, PyAny>) -> PyResult<ObjectQuery> {
    let parsed = match obj.cast::<PyString>() {
        Ok(line) => ObjectQuery::from_json(&line.to_cow()?),
        Err(_) => ObjectQuery::from_value(&json_value(obj, "query")?),
    };
    parsed.map_err(QueryError::new_err)
}

/// A Python value (dict with str keys, list, tuple, str, int, float, bool, None, or any
/// number-like such as a numpy scalar) as a JSON value.
fn json_value(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Value> {
    let refuse = |why: &str| QueryError::new_err(format!("{what}: {why}, got {}", describe(obj)));
    if obj.is_none() {
        Ok(Value::Null)
    } else if let Ok(b) = obj.cast::<PyBool>() {
        Ok(Value::Bool(b.is_true()))
    } else if let Ok(s) = obj.cast::<PyString>() {
        Ok(Value::String(s.to_cow()?.into_owned()))
    } else if let Ok(i) = obj.cast::<PyInt>() {
        if let Ok(n) = i.extract::<i64>() {
            Ok(Value::from(n))
        } else if let Ok(n) = i.extract::<u64>() {
            Ok(Value::from(n))
        } else {
            Ok(Value::from(i.extract::<f64>()?))
        }
    } else if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = serde_json::Map::new();
        for (k, v) in d.iter() {
            let key = k
                .cast::<PyString>()
                .map_err(|_| refuse("dict keys must be str"))?
                .to_cow()?
                .into_owned();
            let value = json_value(&v, &format!("{what}[{key:?}]"))?;
            map.insert(key, value);
        }
        Ok(Value::Object(map))
    } else if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        obj.try_iter()?
            .map(|item| json_value(&item?, what))
            .collect::<PyResult<Vec<Value>>>()
            .map(Value::Array)
    } else if let Ok(x) = obj.extract::<f64>() {
        // A float, or a number-like (a numpy scalar); JSON has no NaN or infinity.
        serde_json::Number::from_f64(x)
            .map(Value::Number)
            .ok_or_else(|| refuse("expected a finite number"))
    } else {
        Err(refuse("expected a dict, list, str, number, bool or None"))
    }
}
