//! `rkforge.Scene`: a scene file or text with dotted-key overrides, validated like a file.

use crate::errors::{guarded, to_py};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use rkforge_core::outputs::{self, Kind};
use rkforge_core::SceneSource;
use std::path::PathBuf;
use toml::Value;

/// A validated scene: its text, and overrides set by dotted key.
#[pyclass(module = "rkforge._rkforge", name = "Scene", from_py_object)]
#[derive(Clone)]
pub struct Scene {
    pub(crate) source: SceneSource,
}

#[pymethods]
impl Scene {
    /// Read and validate a scene file (TOML).
    #[staticmethod]
    fn from_file(path: PathBuf) -> PyResult<Scene> {
        guarded(|| {
            Ok(Scene {
                source: SceneSource::from_file(&path).map_err(to_py)?,
            })
        })
    }

    /// Parse and validate scene text; `name` stands for the file in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, name = "<scene text>"))]
    fn from_toml(text: &str, name: &str) -> PyResult<Scene> {
        guarded(|| {
            Ok(Scene {
                source: SceneSource::from_str_named(text, name).map_err(to_py)?,
            })
        })
    }

    /// Override the key at a dotted path, e.g. `set("tools.top.friction", 0.1)`.
    fn set(&mut self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let value = to_toml(value).map_err(|e| PyTypeError::new_err(format!("`{key}`: {e}")))?;
        guarded(|| self.source.set(key, value).map_err(to_py))
    }

    /// A copy with its own overrides.
    fn copy(&self) -> Scene {
        self.clone()
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.source.scene().name.clone()
    }

    /// The names of the tools, in scene order.
    #[getter]
    fn tools(&self) -> Vec<String> {
        self.source
            .scene()
            .tools
            .iter()
            .map(|t| t.name.clone())
            .collect()
    }

    /// The overrides set so far, as (dotted key, value) pairs in order.
    #[getter]
    fn overrides<'py>(&self, py: Python<'py>) -> PyResult<Vec<(String, Bound<'py, PyAny>)>> {
        self.source
            .overrides()
            .iter()
            .map(|(k, v)| Ok((k.clone(), to_python(py, v)?)))
            .collect()
    }

    /// The scene text as read (without the overrides).
    #[getter]
    fn text(&self) -> String {
        self.source.text().to_string()
    }

    /// The validated scene with its overrides, as TOML.
    fn to_toml(&self) -> PyResult<String> {
        toml::to_string(self.source.scene())
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))
    }

    /// The times (s) at which `rkforge run --no-frames` records history rows after t = 0:
    /// stepping a `Simulation` to each of them with `run_to` lands on the same steps.
    fn sample_times(&self) -> PyResult<Vec<f64>> {
        rkforge_runner::schedule(self.source.scene(), 0)
            .map(|marks| marks.iter().map(|m| m.time).collect())
            .map_err(pyo3::exceptions::PyValueError::new_err)
    }

    /// The register of outputs (`rkforge_core::outputs`) as this scene has it: per column
    /// and per field a dict of `name`, `unit` (as FMI writes it; `1` for a pure number),
    /// `kind` (`scalar`, `per tool`, `per fill point`, `per face`, `per particle`,
    /// `per point`), `description`, and whether `history.csv`, `summary.json` and the FMU
    /// show it (`history`, `summary`, `fmu`).
    fn outputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let scene = self.source.scene();
        let list = PyList::empty(py);
        let columns = outputs::columns(scene)
            .into_iter()
            .map(|c| (c.name.clone(), c.description(scene), c.output));
        let fields = outputs::fields(scene).map(|o| (o.full_name(), o.description.into(), o));
        for (name, description, o) in columns.chain(fields) {
            let d = PyDict::new(py);
            d.set_item("name", name)?;
            d.set_item("unit", o.unit)?;
            d.set_item("kind", kind_name(o.read.kind()))?;
            d.set_item("description", description)?;
            d.set_item("history", o.shown.history)?;
            d.set_item("summary", o.shown.summary)?;
            d.set_item("fmu", o.shown.fmu)?;
            list.append(d)?;
        }
        Ok(list)
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?} from {:?}, {} override(s))",
            self.source.scene().name,
            self.source.file(),
            self.source.overrides().len()
        )
    }

    fn __eq__(&self, other: &Scene) -> bool {
        self.source.scene() == other.source.scene()
    }

    /// Pickling (for Dask workers): the text, the file name and the overrides.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let this = slf.borrow();
        let restore = py.get_type::<Scene>().getattr("_restore")?;
        let args = (this.source.text(), this.source.file(), this.overrides(py)?);
        (restore, args).into_pyobject(py)
    }

    /// Rebuild a pickled scene.
    #[staticmethod]
    fn _restore(
        text: &str,
        file: &str,
        overrides: Vec<(String, Bound<'_, PyAny>)>,
    ) -> PyResult<Scene> {
        let overrides = overrides
            .iter()
            .map(|(k, v)| Ok((k.clone(), to_toml(v).map_err(PyTypeError::new_err)?)))
            .collect::<PyResult<Vec<_>>>()?;
        guarded(|| {
            Ok(Scene {
                source: SceneSource::with_overrides(text, file, overrides).map_err(to_py)?,
            })
        })
    }
}

/// What an output is given for, in words.
fn kind_name(kind: Kind) -> &'static str {
    match kind {
        Kind::Scalar => "scalar",
        Kind::PerTool => "per tool",
        Kind::PerFillPoint => "per fill point",
        Kind::PerFace => "per face",
        Kind::PerParticle => "per particle",
        Kind::PerPoint => "per point",
    }
}

/// A Python value as a TOML value: bool, int, float, str, list or tuple, dict.
fn to_toml(v: &Bound<'_, PyAny>) -> Result<Value, String> {
    if v.is_instance_of::<PyBool>() {
        return Ok(Value::Boolean(
            v.extract().map_err(|e: PyErr| e.to_string())?,
        ));
    }
    if v.is_instance_of::<PyInt>() {
        return v
            .extract::<i64>()
            .map(Value::Integer)
            .map_err(|_| format!("integer {v} does not fit in 64 bits"));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(Value::Float(v.extract().map_err(|e: PyErr| e.to_string())?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Value::String(
            v.extract().map_err(|e: PyErr| e.to_string())?,
        ));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        return v
            .try_iter()
            .map_err(|e| e.to_string())?
            .map(|item| to_toml(&item.map_err(|e| e.to_string())?))
            .collect::<Result<Vec<_>, _>>()
            .map(Value::Array);
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, item) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| format!("dict key {k} is not a string"))?;
            t.insert(k, to_toml(&item)?);
        }
        return Ok(Value::Table(t));
    }
    // numpy scalars and other numbers: by their float value.
    if let Ok(x) = v.extract::<f64>() {
        return Ok(Value::Float(x));
    }
    let kind = v
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into());
    Err(format!(
        "cannot use a value of type `{kind}` in a scene (expected a number, string, bool, list or dict)"
    ))
}

/// A TOML value as a Python value.
fn to_python<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        Value::Float(x) => x.into_pyobject(py)?.into_any(),
        Value::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        Value::Array(a) => PyList::new(
            py,
            a.iter()
                .map(|x| to_python(py, x))
                .collect::<PyResult<Vec<_>>>()?,
        )?
        .into_any(),
        Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, to_python(py, x)?)?;
            }
            d.into_any()
        }
    })
}
