//! Conversions at the boundary: numpy arrays into the library's vectors (one
//! copy, checked for shape and dtype, naming the field) and its vectors out
//! as numpy arrays that own the Rust buffer (no copy); JSON values to and from
//! Python objects (settings in, reports out).

use numpy::{
    dtype, IntoPyArray, PyArray1, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::errors;

/// `obj` as a numpy array (a list or tuple is converted by `numpy.asarray`).
fn as_array<'py>(obj: &Bound<'py, PyAny>, field: &str) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    let py = obj.py();
    let converted = py
        .import("numpy")?
        .call_method1("asarray", (obj,))
        .map_err(|e| errors::network_input(field, format!("`{field}`: not an array: {e}")))?;
    converted
        .cast_into::<PyUntypedArray>()
        .map_err(|_| errors::network_input(field, format!("`{field}`: not an array")))
}

/// What a shape check reports: `(n, 3) float64, got shape (4,) int64`.
fn describe(a: &Bound<'_, PyUntypedArray>) -> String {
    let dims: Vec<String> = a.shape().iter().map(usize::to_string).collect();
    let shape = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let dt = a
        .dtype()
        .str()
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".into());
    format!("shape {shape} dtype {dt}")
}

/// A float64 array of `width` columns (`width` 0: one dimension) as rows,
/// copied once.
pub fn f64_rows<const W: usize>(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Vec<[f64; W]>> {
    let a = as_array(obj, field)?;
    let py = obj.py();
    if !a.dtype().is_equiv_to(&dtype::<f64>(py)) || a.ndim() != 2 || a.shape()[1] != W {
        return Err(errors::network_input(
            field,
            format!(
                "`{field}` must be an (n, {W}) float64 array, got {}",
                describe(&a)
            ),
        ));
    }
    let a = a.cast::<numpy::PyArray2<f64>>()?.readonly();
    Ok(match a.as_slice() {
        Ok(s) => s
            .chunks_exact(W)
            .map(|c| std::array::from_fn(|i| c[i]))
            .collect(),
        Err(_) => a
            .as_array()
            .rows()
            .into_iter()
            .map(|r| std::array::from_fn(|i| r[i]))
            .collect(),
    })
}

/// A one-dimensional float64 array, copied once.
pub fn f64_vector(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Vec<f64>> {
    let a = as_array(obj, field)?;
    let py = obj.py();
    if !a.dtype().is_equiv_to(&dtype::<f64>(py)) || a.ndim() != 1 {
        return Err(errors::network_input(
            field,
            format!(
                "`{field}` must be an (n,) float64 array, got {}",
                describe(&a)
            ),
        ));
    }
    Ok(a.cast::<PyArray1<f64>>()?.readonly().as_array().to_vec())
}

/// Node indices: an integer array of `W` columns (`W` = 1: one dimension),
/// each ≥ 0.
pub fn index_rows<const W: usize>(
    obj: &Bound<'_, PyAny>,
    field: &str,
) -> PyResult<Vec<[usize; W]>> {
    let a = as_array(obj, field)?;
    let py = obj.py();
    let kind = a.dtype().kind();
    let shape_ok = if W == 1 {
        a.ndim() == 1 || (a.ndim() == 2 && a.shape()[1] == 1)
    } else {
        a.ndim() == 2 && a.shape()[1] == W
    };
    let shape = if W == 1 {
        "(k,)".to_string()
    } else {
        format!("(m, {W})")
    };
    if !matches!(kind, b'i' | b'u') || !shape_ok {
        return Err(errors::network_input(
            field,
            format!(
                "`{field}` must be a {shape} integer array, got {}",
                describe(&a)
            ),
        ));
    }
    let a = if a.dtype().is_equiv_to(&dtype::<i64>(py)) {
        a
    } else {
        a.call_method1("astype", ("int64",))?
            .cast_into::<PyUntypedArray>()
            .map_err(PyErr::from)?
    };
    let flat = a.call_method0("ravel")?;
    let flat = flat.cast::<PyArray1<i64>>()?.readonly();
    let values = flat.as_array();
    let mut rows = Vec::with_capacity(values.len() / W);
    for (k, chunk) in values
        .as_slice()
        .into_iter()
        .flat_map(|s| s.chunks_exact(W))
        .enumerate()
    {
        let mut row = [0; W];
        for (slot, &v) in row.iter_mut().zip(chunk) {
            *slot = usize::try_from(v).map_err(|_| {
                errors::network_input(field, format!("`{field}[{k}]` holds {v}, a negative index"))
            })?;
        }
        rows.push(row);
    }
    Ok(rows)
}

/// Rows of floats as an (n, W) float64 array owning the vector (no copy).
pub fn rows_array<'py, const W: usize>(
    py: Python<'py>,
    rows: Vec<[f64; W]>,
) -> PyResult<Bound<'py, PyAny>> {
    let n = rows.len();
    let flat: Vec<f64> = rows.into_flattened();
    Ok(flat.into_pyarray(py).reshape([n, W])?.into_any())
}

/// A vector of floats as a float64 array owning it (no copy).
pub fn vector_array(py: Python<'_>, v: Vec<f64>) -> Bound<'_, PyAny> {
    v.into_pyarray(py).into_any()
}

/// Index rows as an (n, W) int64 array (one pass from `usize`).
pub fn index_array<'py, const W: usize>(
    py: Python<'py>,
    rows: &[[usize; W]],
) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<i64> = rows.iter().flatten().map(|&i| i as i64).collect();
    let a = flat.into_pyarray(py);
    Ok(if W == 1 {
        a.into_any()
    } else {
        a.reshape([rows.len(), W])?.into_any()
    })
}

/// A JSON value as a Python object (objects as dicts, arrays as lists).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => PyFloat::new(py, n.as_f64().unwrap_or(f64::NAN)).into_any(),
        },
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(json_to_py(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, item) in map {
                dict.set_item(k, json_to_py(py, item)?)?;
            }
            dict.into_any()
        }
    })
}

/// A Python object (dict, list, tuple, str, int, float, bool, None, a numpy
/// scalar or array) as a JSON value; an error (a NaN, an object of another
/// type) is a `class` exception of `ringmesh.errors` naming `field`.
pub fn py_to_json(obj: &Bound<'_, PyAny>, field: &str, class: &str) -> PyResult<serde_json::Value> {
    let fail = |message: String| {
        errors::raise(
            obj.py(),
            class,
            message,
            errors::Detail {
                field: Some(field.to_string()),
                ..errors::Detail::default()
            },
        )
    };
    use serde_json::Value;
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if let Ok(i) = obj.cast::<PyInt>() {
        if let Ok(v) = i.extract::<i64>() {
            return Ok(Value::from(v));
        }
        return Ok(Value::from(i.extract::<u64>()?));
    }
    if let Ok(f) = obj.cast::<PyFloat>() {
        let v = f.value();
        return serde_json::Number::from_f64(v)
            .map(Value::Number)
            .ok_or_else(|| fail(format!("`{field}` = {v}: not a finite number")));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(s.extract::<String>()?));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = serde_json::Map::new();
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| fail(format!("`{field}`: a key that is not a string: {k}")))?;
            let inner = format!("{field}.{key}");
            let inner = inner.trim_start_matches('.').to_string();
            map.insert(key, py_to_json(&v, &inner, class)?);
        }
        return Ok(Value::Object(map));
    }
    if obj.cast::<PyList>().is_ok() || obj.cast::<PyTuple>().is_ok() {
        let items: PyResult<Vec<Value>> = obj
            .try_iter()?
            .enumerate()
            .map(|(k, item)| py_to_json(&item?, &format!("{field}[{k}]"), class))
            .collect();
        return Ok(Value::Array(items?));
    }
    // numpy scalars and arrays: their Python value (`tolist`).
    if obj.hasattr("tolist")? {
        let plain = obj.call_method0("tolist")?;
        if !plain.is(obj) {
            return py_to_json(&plain, field, class);
        }
    }
    let ty = obj.get_type().name()?.to_string();
    Err(fail(format!(
        "`{field}`: a value of type {ty}, not a number, string, bool, list or dict"
    )))
}
