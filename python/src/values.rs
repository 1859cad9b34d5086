//! Python values ⇄ the scene schema's tree of values (`serde_json::Value`, JSON's data model):
//! dicts, lists, tuples, numbers, strings, None, and numpy scalars and arrays (as their Python
//! values). A value that has no place in a scene is refused with its path.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};

use crate::SceneError as PySceneError;

/// Deepest nesting accepted (a scene's regions nest; a cycle would never end).
const MAX_DEPTH: usize = 128;

/// `obj` as a tree of values; `path` names it in errors (`thermal.bcs[0]`).
pub(crate) fn to_value(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<Value> {
    to_value_at(obj, path, 0)
}

fn to_value_at(obj: &Bound<'_, PyAny>, path: &str, depth: usize) -> PyResult<Value> {
    if depth > MAX_DEPTH {
        return Err(PySceneError::new_err(format!(
            "scene field `{path}`: nested more than {MAX_DEPTH} levels deep (a dict that holds itself?)"
        )));
    }
    let child = |key: &str| {
        if path.is_empty() {
            key.to_string()
        } else {
            format!("{path}.{key}")
        }
    };
    if obj.is_none() {
        Ok(Value::Null)
    } else if obj.is_instance_of::<PyBool>() {
        Ok(Value::Bool(obj.extract()?))
    } else if obj.is_instance_of::<PyInt>() {
        if let Ok(i) = obj.extract::<i64>() {
            Ok(Value::from(i))
        } else {
            Ok(Value::from(obj.extract::<u64>().map_err(|_| {
                PySceneError::new_err(format!(
                    "scene field `{path}` = {}: an integer beyond 64 bits",
                    repr(obj)
                ))
            })?))
        }
    } else if obj.is_instance_of::<PyFloat>() {
        let x: f64 = obj.extract()?;
        Number::from_f64(x).map(Value::Number).ok_or_else(|| {
            PySceneError::new_err(format!(
                "scene field `{path}` = {x}: a scene's numbers must be finite"
            ))
        })
    } else if obj.is_instance_of::<PyString>() {
        Ok(Value::String(obj.extract()?))
    } else if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = Map::new();
        for (k, v) in d.iter() {
            let key: String = k.extract().map_err(|_| {
                PySceneError::new_err(format!(
                    "scene field `{path}`: key {} is not a string (a scene's keys are field and variant names)",
                    repr(&k)
                ))
            })?;
            let value = to_value_at(&v, &child(&key), depth + 1)?;
            map.insert(key, value);
        }
        Ok(Value::Object(map))
    } else if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let items = obj
            .try_iter()?
            .enumerate()
            .map(|(i, v)| to_value_at(&v?, &format!("{path}[{i}]"), depth + 1))
            .collect::<PyResult<Vec<_>>>()?;
        Ok(Value::Array(items))
    } else if obj.hasattr("tolist")? && obj.hasattr("dtype")? {
        // numpy scalars and arrays: their Python values (float64 → float, int64 → int, …)
        to_value_at(&obj.call_method0("tolist")?, path, depth + 1)
    } else {
        Err(PyTypeError::new_err(format!(
            "scene field `{path}` = {}: a value of type {} has no place in a scene (allowed: dict, list, \
             tuple, str, int, float, bool, None, numpy numbers and arrays)",
            repr(obj),
            obj.get_type().name().map(|n| n.to_string()).unwrap_or_default()
        )))
    }
}

/// A tree of values as Python objects (dicts, lists, floats, ints, str, None).
pub(crate) fn to_py(py: Python<'_>, v: &Value) -> PyResult<Py<PyAny>> {
    Ok(match v {
        Value::Null => py.None(),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any().unbind(),
        Value::Number(n) => match (n.as_i64(), n.as_u64(), n.as_f64()) {
            (Some(i), _, _) => i.into_pyobject(py)?.into_any().unbind(),
            (_, Some(u), _) => u.into_pyobject(py)?.into_any().unbind(),
            (_, _, Some(x)) => x.into_pyobject(py)?.into_any().unbind(),
            _ => py.None(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any().unbind(),
        Value::Array(a) => {
            let items = a.iter().map(|x| to_py(py, x)).collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any().unbind()
        }
        Value::Object(m) => {
            let d = PyDict::new(py);
            for (k, x) in m {
                d.set_item(k, to_py(py, x)?)?;
            }
            d.into_any().unbind()
        }
    })
}

/// A value's `repr`, cut to 60 characters, for messages.
pub(crate) fn repr(obj: &Bound<'_, PyAny>) -> String {
    let r = obj.repr().map(|r| r.to_string()).unwrap_or_else(|_| "?".into());
    match r.char_indices().nth(60) {
        Some((i, _)) => format!("{}…", &r[..i]),
        None => r,
    }
}
