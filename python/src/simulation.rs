//! `rkforge.Simulation` (stepping, tool commands, fields, the register's outputs, saved
//! states, the summary) and
//! `run_scene`, the whole run of `rkforge run --no-frames` (the history and summary of
//! [`rkforge_runner`], so the same bits as the command line).

use crate::errors::{guarded, to_py, StateError};
use crate::scene::Scene;
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use rkforge_core::{outputs, IntegrationRule, State};
use serde::{Deserialize, Serialize};
use std::sync::Mutex;
use std::time::Instant;

/// A running simulation and the threads it steps on.
struct Inner {
    sim: rkforge_core::Simulation,
    /// Its own rayon pool when a thread count was asked for, else rayon's global pool.
    pool: Option<rayon::ThreadPool>,
    /// When it was created: the summary's wall time counts from here.
    started: Instant,
}

impl Inner {
    /// Run `f` on the simulation's threads.
    fn install<R: Send>(&mut self, f: impl FnOnce(&mut rkforge_core::Simulation) -> R + Send) -> R {
        match &self.pool {
            Some(pool) => pool.install(|| f(&mut self.sim)),
            None => f(&mut self.sim),
        }
    }
}

/// A saved state with the scene it belongs to.
#[derive(Serialize, Deserialize)]
struct Saved {
    scene: serde_json::Value,
    state: State,
}

/// The scene with the `integration` argument applied.
fn configured(scene: &Scene, integration: Option<&str>) -> PyResult<rkforge_core::Scene> {
    let s = scene.source.scene().clone();
    match integration {
        None => Ok(s),
        Some(name) => IntegrationRule::parse(name)
            .map(|r| s.with_integration(r))
            .ok_or_else(|| {
                PyValueError::new_err(format!(
                    "integration `{name}`: expected \"q4\", \"q2\" or \"scni\""
                ))
            }),
    }
}

/// A rayon pool of `threads` workers, or None for the global pool.
fn pool(threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    match threads {
        None => Ok(None),
        Some(0) => Err(PyValueError::new_err("threads must be at least 1")),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map(Some)
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start {n} threads: {e}"))),
    }
}

/// Positions or velocities as an (n, 2) array.
fn pairs<'py>(py: Python<'py>, v: &[[f64; 2]]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_vec(py, v.iter().flatten().copied().collect()).reshape([v.len(), 2])
}

/// A summary (JSON) as a Python dict, through `json.loads` (numbers round-trip exactly).
fn to_dict<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A simulation of a scene, stepped from Python. Stepping releases the GIL, so several
/// simulations run at once on Python threads; results are the same bits for any thread
/// count.
#[pyclass(module = "rkforge._rkforge", name = "Simulation")]
pub struct Simulation {
    inner: Mutex<Inner>,
}

impl Simulation {
    /// Run `f` on the simulation with the GIL released and panics caught.
    fn with<R: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut Inner) -> PyResult<R> + Send,
    ) -> PyResult<R> {
        py.detach(|| {
            guarded(|| {
                let mut inner = self.inner.lock().map_err(|_| {
                    PyRuntimeError::new_err(
                        "this simulation is unusable after an internal error; create a new one",
                    )
                })?;
                f(&mut inner)
            })
        })
    }

    /// A dict of tool name -> `value(sim, tool index)`.
    fn per_tool<'py>(
        &self,
        py: Python<'py>,
        value: fn(&rkforge_core::Simulation, usize) -> f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let values = self.with(py, |s| {
            Ok((0..s.sim.tools().len())
                .map(|k| (s.sim.tools()[k].name.clone(), value(&s.sim, k)))
                .collect::<Vec<_>>())
        })?;
        let d = PyDict::new(py);
        for (name, v) in values {
            d.set_item(name, v)?;
        }
        Ok(d)
    }
}

#[pymethods]
impl Simulation {
    /// Set up the discretisation of `scene`; `integration` ("q4", "q2", "scni") overrides
    /// the scene's rule, `threads` gives the simulation its own pool of that many threads.
    #[new]
    #[pyo3(signature = (scene, integration = None, threads = None))]
    fn new(
        py: Python<'_>,
        scene: &Scene,
        integration: Option<&str>,
        threads: Option<usize>,
    ) -> PyResult<Simulation> {
        let scene = configured(scene, integration)?;
        let pool = pool(threads)?;
        py.detach(|| {
            guarded(|| {
                let started = Instant::now();
                let build = || rkforge_core::Simulation::new(&scene);
                let sim = match &pool {
                    Some(p) => p.install(build),
                    None => build(),
                }
                .map_err(to_py)?;
                Ok(Simulation {
                    inner: Mutex::new(Inner { sim, pool, started }),
                })
            })
        })
    }

    /// One time step (at the scene's step or the stable step); returns the new time (s).
    /// With `toward` (s), the step is the one `run_to(toward)` would take next: shortened
    /// and evened out to land on that time (as the FMU steps to its communication point).
    #[pyo3(signature = (toward = None))]
    fn step(&self, py: Python<'_>, toward: Option<f64>) -> PyResult<f64> {
        self.with(py, |s| {
            let now = s.sim.time();
            let limit = match toward {
                Some(t) if !(t.is_finite() && t > now) => {
                    return Err(PyValueError::new_err(format!(
                        "step(toward={t}): the time must be finite and after the current time {now:e} s"
                    )))
                }
                Some(t) => Some(t - now),
                None => None,
            };
            s.install(|sim| sim.step(limit).map(|()| sim.time()))
                .map_err(to_py)
        })
    }

    /// Step until the time reaches `t` (s), the last step shortened to land on it.
    fn run_to(&self, py: Python<'_>, t: f64) -> PyResult<f64> {
        self.with(py, |s| {
            let now = s.sim.time();
            if !t.is_finite() || t < now {
                return Err(PyValueError::new_err(format!(
                    "run_to({t}): the time must be finite and not before the current time {now:e} s"
                )));
            }
            s.install(|sim| sim.run_to(t, |_| {}).map(|()| sim.time()))
                .map_err(to_py)
        })
    }

    /// Command the velocity (m/s, along its axis) of the tool `name` from the next step on.
    fn set_tool_velocity(&self, py: Python<'_>, name: &str, velocity: f64) -> PyResult<()> {
        self.with(py, |s| {
            let k = s.sim.tool_index(name).ok_or_else(|| {
                let names: Vec<&str> = s.sim.tools().iter().map(|t| t.name.as_str()).collect();
                PyValueError::new_err(format!(
                    "no tool named `{name}` (tools: {})",
                    names.join(", ")
                ))
            })?;
            s.sim.set_tool_velocity(k, velocity).map_err(to_py)
        })
    }

    /// Time (s).
    #[getter]
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        self.with(py, |s| Ok(s.sim.time()))
    }

    /// Steps taken.
    #[getter]
    fn steps(&self, py: Python<'_>) -> PyResult<u64> {
        self.with(py, |s| Ok(s.sim.steps()))
    }

    /// Force of the workpiece on each tool along the tool's axis (N), by tool name.
    fn tool_forces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.per_tool(py, |sim, k| sim.tools()[k].axial_force())
    }

    /// Stroke of each tool along its axis (m), by tool name.
    fn tool_strokes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.per_tool(py, |sim, k| sim.tools()[k].state.stroke)
    }

    /// Record a history row now, as `rkforge run` does at its samples (this also updates
    /// the run's largest penetration): a dict of history.csv's columns. SimulationError
    /// when a particle lies deeper inside a tool than `checks.max_penetration_rel`.
    fn sample<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (columns, row) = self.with(py, |s| {
            let mut history = rkforge_runner::History::new(&s.sim);
            history.record(&mut s.sim).map_err(to_py)?;
            Ok((history.columns().to_vec(), history.rows()[0].clone()))
        })?;
        let d = PyDict::new(py);
        for (c, v) in columns.into_iter().zip(row) {
            d.set_item(c, v)?;
        }
        Ok(d)
    }

    /// Every output of the register of outputs (`rkforge_core::outputs`) now, by its name:
    /// each column (history.csv's, and those only the summary and the FMU show) as a float,
    /// each field (`particles.*`, `points.*`) as a numpy array. Unlike `sample`, reading
    /// changes nothing (the run's largest penetration is not updated).
    fn outputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (values, fields) = self.with(py, |s| {
            let now = outputs::Sample::new(&s.sim);
            let scene = s.sim.scene();
            let values: Vec<(String, f64)> = outputs::columns(scene)
                .into_iter()
                .map(|c| {
                    let v = c.value(&now);
                    (c.name, v)
                })
                .collect();
            let fields: Vec<(String, Vec<f64>)> = outputs::fields(scene)
                .filter_map(|o| Some((o.full_name(), o.field(&now)?)))
                .collect();
            Ok((values, fields))
        })?;
        let d = PyDict::new(py);
        for (name, v) in values {
            d.set_item(name, v)?;
        }
        for (name, v) in fields {
            d.set_item(name, PyArray1::from_vec(py, v))?;
        }
        Ok(d)
    }

    /// Every tool as in summary.json: name, stroke, velocity, force [x, y], axial and peak force.
    fn tools<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let tools = self.with(py, |s| {
            Ok(serde_json::Value::Array(
                (0..s.sim.tools().len())
                    .map(|k| rkforge_runner::tool_json(&s.sim, k))
                    .collect(),
            ))
        })?;
        to_dict(py, &tools)
    }

    /// The laps so far (folds of the surface onto itself between points apart along it), as
    /// in summary.json: each with `formed_s`, `formed_stroke_m` (by tool), `start_m`,
    /// `end_m`, `length_m`, `reference_m` and its surface `particles`.
    fn laps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let laps = self.with(py, |s| {
            Ok(serde_json::Value::Array(rkforge_runner::laps_json(&s.sim)))
        })?;
        to_dict(py, &laps)
    }

    /// Particle fields as numpy arrays: `positions`, `displacement`, `velocity` (n, 2) in m
    /// and m/s; `plastic_strain`, `von_mises` (Pa) and, in a scene with `[thermal]`,
    /// `temperature` (degrees C) (n,), smoothed from the points; `lap` (n,), the lap each
    /// particle took part in numbered from 1 (0: none).
    fn fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = self.with(py, |s| Ok(s.sim.fields()))?;
        let d = PyDict::new(py);
        d.set_item("positions", pairs(py, &f.positions)?)?;
        d.set_item("displacement", pairs(py, &f.displacement)?)?;
        d.set_item("velocity", pairs(py, &f.velocity)?)?;
        d.set_item("plastic_strain", PyArray1::from_vec(py, f.plastic_strain))?;
        d.set_item("von_mises", PyArray1::from_vec(py, f.von_mises))?;
        if let Some(t) = f.temperature {
            d.set_item("temperature", PyArray1::from_vec(py, t))?;
        }
        d.set_item("lap", PyArray1::from_vec(py, f.lap))?;
        Ok(d)
    }

    /// The whole changing state, with its scene, as bytes (restoring it continues bit for bit).
    fn save_state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = self.with(py, |s| {
            let saved = Saved {
                scene: serde_json::to_value(s.sim.scene())
                    .map_err(|e| PyRuntimeError::new_err(e.to_string()))?,
                state: s.sim.state().clone(),
            };
            serde_json::to_vec(&saved).map_err(|e| PyRuntimeError::new_err(e.to_string()))
        })?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// Restore a state from `save_state` of a simulation of the same scene.
    fn restore_state(&self, py: Python<'_>, state: &[u8]) -> PyResult<()> {
        let state = state.to_vec();
        self.with(py, move |s| {
            let saved: Saved = serde_json::from_slice(&state)
                .map_err(|e| StateError::new_err(format!("not a saved rkforge state: {e}")))?;
            let ours = serde_json::to_value(s.sim.scene())
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
            if saved.scene != ours {
                let name = saved.scene["name"].as_str().unwrap_or("?");
                return Err(StateError::new_err(if name == s.sim.scene().name {
                    format!("the state was saved from scene `{name}` with other settings")
                } else {
                    format!(
                        "the state was saved from scene `{name}`, not `{}`",
                        s.sim.scene().name
                    )
                }));
            }
            s.sim.restore(saved.state).map_err(to_py)
        })
    }

    /// The summary as summary.json has it (wall time since the simulation was created).
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let summary = self.with(py, |s| {
            let wall = s.started.elapsed().as_secs_f64();
            Ok(s.install(|sim| {
                rkforge_runner::summary(sim, wall, 0.0, rkforge_runner::Ending::Finished)
            }))
        })?;
        to_dict(py, &summary)
    }
}

/// What `run_scene` returns: the summary (dict), the history's columns and rows, the failure.
type RunResult<'py> = (
    Bound<'py, PyAny>,
    Vec<String>,
    Bound<'py, PyArray2<f64>>,
    Option<String>,
);

/// The whole run of a scene, as `rkforge run --no-frames` does it: returns the summary
/// (dict), the history's column names and its rows (a 2D array), and the failure, if any.
#[pyfunction]
#[pyo3(signature = (scene, integration = None, threads = None))]
pub fn run_scene<'py>(
    py: Python<'py>,
    scene: &Scene,
    integration: Option<&str>,
    threads: Option<usize>,
) -> PyResult<RunResult<'py>> {
    let scene = configured(scene, integration)?;
    let pool = pool(threads)?;
    let (summary, columns, rows, failure) = py.detach(|| {
        guarded(|| {
            let go = || -> PyResult<_> {
                let wall = Instant::now();
                let mut sim = rkforge_core::Simulation::new(&scene).map_err(to_py)?;
                let outcome = rkforge_runner::drive(&mut sim, 0, &mut rkforge_runner::Quiet)
                    .map_err(PyRuntimeError::new_err)?;
                let summary = rkforge_runner::summary(
                    &sim,
                    wall.elapsed().as_secs_f64(),
                    outcome.output_time.as_secs_f64(),
                    outcome.ending(),
                );
                let columns = outcome.history.columns().to_vec();
                let rows: Vec<f64> = outcome.history.rows().iter().flatten().copied().collect();
                Ok((summary, columns, rows, outcome.failure))
            };
            match &pool {
                Some(p) => p.install(go),
                None => go(),
            }
        })
    })?;
    let n = columns.len();
    let count = rows.len() / n.max(1);
    let table = PyArray1::from_vec(py, rows);
    Ok((
        to_dict(py, &summary)?,
        columns,
        table.reshape([count, n])?,
        failure,
    ))
}
