//! `rkforge.Scene`: a scene file or text (2D or 3D) with dotted-key overrides, validated
//! like a file.

use crate::errors::{guarded, to_py};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use rkforge_core::outputs::{self, Kind, Output, Shown};
use rkforge_core::scene::solid::is_solid;
use rkforge_core::scene::SolidScene;
use rkforge_core::{Kinematics, SceneSource};
use std::path::PathBuf;
use toml::Value;

/// The source of a scene of either kind: 2D (plane strain, axisymmetric) or 3D.
#[derive(Clone, PartialEq)]
pub(crate) enum Source {
    /// Plane strain or axisymmetric.
    Plane(SceneSource),
    /// Three dimensions.
    Solid(SceneSource<SolidScene>),
}

impl Source {
    /// Scene text with overrides, of the kind its `model.kinematics` says.
    fn of_text(
        text: &str,
        file: &str,
        overrides: Vec<(String, Value)>,
    ) -> rkforge_core::Result<Source> {
        Ok(if is_solid(text) {
            Source::Solid(SceneSource::of_text(text, file, overrides)?)
        } else {
            Source::Plane(SceneSource::with_overrides(text, file, overrides)?)
        })
    }

    fn set(&mut self, key: &str, value: Value) -> rkforge_core::Result<()> {
        match self {
            Source::Plane(s) => s.set(key, value),
            Source::Solid(s) => s.set(key, value),
        }
    }

    fn text(&self) -> &str {
        match self {
            Source::Plane(s) => s.text(),
            Source::Solid(s) => s.text(),
        }
    }

    fn file(&self) -> &str {
        match self {
            Source::Plane(s) => s.file(),
            Source::Solid(s) => s.file(),
        }
    }

    fn overrides(&self) -> &[(String, Value)] {
        match self {
            Source::Plane(s) => s.overrides(),
            Source::Solid(s) => s.overrides(),
        }
    }

    fn name(&self) -> &str {
        match self {
            Source::Plane(s) => &s.scene().name,
            Source::Solid(s) => &s.scene().name,
        }
    }

    fn tools(&self) -> Vec<String> {
        match self {
            Source::Plane(s) => s.scene().tools.iter().map(|t| t.name.clone()).collect(),
            Source::Solid(s) => s.scene().tools.iter().map(|t| t.name.clone()).collect(),
        }
    }
}

/// A validated scene: its text, and overrides set by dotted key.
#[pyclass(module = "rkforge._rkforge", name = "Scene", from_py_object)]
#[derive(Clone)]
pub struct Scene {
    pub(crate) source: Source,
}

#[pymethods]
impl Scene {
    /// Read and validate a scene file (TOML), 2D or 3D (`model.kinematics = "3d"`).
    #[staticmethod]
    fn from_file(path: PathBuf) -> PyResult<Scene> {
        guarded(|| {
            let text = rkforge_core::scene::read_text(&path).map_err(to_py)?;
            Ok(Scene {
                source: Source::of_text(&text, &path.display().to_string(), Vec::new())
                    .map_err(to_py)?,
            })
        })
    }

    /// Parse and validate scene text; `name` stands for the file in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, name = "<scene text>"))]
    fn from_toml(text: &str, name: &str) -> PyResult<Scene> {
        guarded(|| {
            Ok(Scene {
                source: Source::of_text(text, name, Vec::new()).map_err(to_py)?,
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
        self.source.name().to_string()
    }

    /// `"plane_strain"`, `"axisymmetric"` or `"3d"`.
    #[getter]
    fn kinematics(&self) -> String {
        match &self.source {
            Source::Plane(s) => match s.scene().model.kinematics {
                Kinematics::PlaneStrain => "plane_strain".into(),
                Kinematics::Axisymmetric => "axisymmetric".into(),
            },
            Source::Solid(_) => "3d".into(),
        }
    }

    /// The names of the tools, in scene order.
    #[getter]
    fn tools(&self) -> Vec<String> {
        self.source.tools()
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
        match &self.source {
            Source::Plane(s) => toml::to_string(s.scene()),
            Source::Solid(s) => toml::to_string(s.scene()),
        }
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))
    }

    /// The times (s) at which `rkforge run --no-frames` records history rows after t = 0:
    /// stepping a `Simulation` to each of them with `run_to` lands on the same steps.
    fn sample_times(&self) -> PyResult<Vec<f64>> {
        let (end, interval) = match &self.source {
            Source::Plane(s) => (s.scene().time.end_s, s.scene().history_interval()),
            Source::Solid(s) => (s.scene().time.end_s, s.scene().history_interval()),
        };
        rkforge_runner::schedule_every(end, interval, 0)
            .map(|marks| marks.iter().map(|m| m.time).collect())
            .ok_or_else(|| {
                pyo3::exceptions::PyValueError::new_err(format!(
                    "output.history_interval_s {interval:e} s: too many samples"
                ))
            })
    }

    /// The register of outputs (`rkforge_core::outputs`) as this scene has it: per column
    /// and per field a dict of `name`, `unit` (as FMI writes it; `1` for a pure number),
    /// `kind` (`scalar`, `per tool`, `per fill point`, `per face`, `per particle`,
    /// `per point`), `description`, and whether `history.csv`, `summary.json` and the FMU
    /// show it (`history`, `summary`, `fmu`). A 3D scene has the 3D register's.
    fn outputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let entries: Vec<Entry> = match &self.source {
            Source::Plane(s) => {
                let scene = s.scene();
                let columns = outputs::columns(scene)
                    .into_iter()
                    .map(|c| entry(c.name.clone(), c.description(scene), c.output));
                let fields =
                    outputs::fields(scene).map(|o| entry(o.full_name(), o.description.into(), o));
                columns.chain(fields).collect()
            }
            Source::Solid(s) => {
                let scene = s.scene();
                let columns = outputs::solid_columns(scene)
                    .into_iter()
                    .map(|c| entry(c.name.clone(), c.description(scene), c.output));
                let fields = outputs::solid_fields(scene)
                    .map(|o| entry(o.full_name(), o.description.into(), o));
                columns.chain(fields).collect()
            }
        };
        let list = PyList::empty(py);
        for (name, description, unit, kind, shown) in entries {
            let d = PyDict::new(py);
            d.set_item("name", name)?;
            d.set_item("unit", unit)?;
            d.set_item("kind", kind_name(kind))?;
            d.set_item("description", description)?;
            d.set_item("history", shown.history)?;
            d.set_item("summary", shown.summary)?;
            d.set_item("fmu", shown.fmu)?;
            list.append(d)?;
        }
        Ok(list)
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?} from {:?}, {} override(s))",
            self.source.name(),
            self.source.file(),
            self.source.overrides().len()
        )
    }

    fn __eq__(&self, other: &Scene) -> bool {
        match (&self.source, &other.source) {
            (Source::Plane(a), Source::Plane(b)) => a.scene() == b.scene(),
            (Source::Solid(a), Source::Solid(b)) => a.scene() == b.scene(),
            _ => false,
        }
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
                source: Source::of_text(text, file, overrides).map_err(to_py)?,
            })
        })
    }
}

/// One output as `Scene.outputs` lists it: name, description, unit, kind, where shown.
type Entry = (String, String, &'static str, Kind, Shown);

/// The entry of output `o` under `name` with `description`.
fn entry<S: outputs::Body>(name: String, description: String, o: &Output<S>) -> Entry {
    (name, description, o.unit, o.read.kind(), o.shown)
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
    // numpy scalars: a numpy bool as a bool, an integer (any `numbers.Integral`, numpy's
    // among them) by its `__index__`, and other numbers by their float value.
    let py = v.py();
    let module = v
        .get_type()
        .module()
        .map(|m| m.to_string())
        .unwrap_or_default();
    let name = v
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_default();
    if module == "numpy" && (name == "bool" || name == "bool_") {
        return v.is_truthy().map(Value::Boolean).map_err(|e| e.to_string());
    }
    let integral = py
        .import("numbers")
        .and_then(|m| m.getattr("Integral"))
        .and_then(|t| v.is_instance(&t))
        .unwrap_or(false);
    if integral {
        return v
            .call_method0("__index__")
            .and_then(|i| i.extract::<i64>())
            .map(Value::Integer)
            .map_err(|_| format!("integer {v} does not fit in 64 bits"));
    }
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
