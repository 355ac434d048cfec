//! `rkforge.Simulation` (stepping, tool commands, fields, the register's outputs, saved
//! states, the summary) and
//! `run_scene`, the whole run of `rkforge run --no-frames` (the history and summary of
//! [`rkforge_runner`], so the same bits as the command line), for a 2D scene or a 3D one
//! (`model.kinematics = "3d"`, the 3D register's outputs).

use crate::errors::{guarded, interruptible, to_py, StateError};
use crate::scene::{Scene, Source};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use rkforge_core::outputs::Since;
use rkforge_core::scene::SolidScene;
use rkforge_core::solver::{SolidSimulation, SolidState};
use rkforge_core::{outputs, IntegrationRule, State};
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// A running simulation of either kind.
enum Sim {
    /// Plane strain or axisymmetric.
    Plane(Box<rkforge_core::Simulation>),
    /// Three dimensions.
    Solid(Box<SolidSimulation>),
}

impl Sim {
    fn time(&self) -> f64 {
        match self {
            Sim::Plane(s) => s.time(),
            Sim::Solid(s) => s.time(),
        }
    }

    fn steps(&self) -> u64 {
        match self {
            Sim::Plane(s) => s.steps(),
            Sim::Solid(s) => s.steps(),
        }
    }

    /// One step, at most `limit` long (s).
    fn step(&mut self, limit: Option<f64>) -> rkforge_core::Result<()> {
        match self {
            Sim::Plane(s) => s.step(limit),
            Sim::Solid(s) => s.step(limit),
        }
    }

    /// Step to time `t` (s), the last step landing on it, or until `cancel` is set (read
    /// before each step).
    fn run_to(&mut self, t: f64, cancel: &AtomicBool) -> rkforge_core::Result<()> {
        let go_on = || !cancel.load(Ordering::Relaxed);
        match self {
            Sim::Plane(s) => s.run_toward(t, u64::MAX, |_, _| go_on()).map(|_| ()),
            Sim::Solid(s) => s.run_toward(t, u64::MAX, |_, _| go_on()).map(|_| ()),
        }
    }

    fn tool_names(&self) -> Vec<String> {
        match self {
            Sim::Plane(s) => s.tools().iter().map(|t| t.name.clone()).collect(),
            Sim::Solid(s) => s.tools().iter().map(|t| t.name.clone()).collect(),
        }
    }

    fn tool_index(&self, name: &str) -> Option<usize> {
        match self {
            Sim::Plane(s) => s.tool_index(name),
            Sim::Solid(s) => s.tool_index(name),
        }
    }

    fn set_tool_velocity(&mut self, k: usize, v: f64) -> rkforge_core::Result<()> {
        match self {
            Sim::Plane(s) => s.set_tool_velocity(k, v),
            Sim::Solid(s) => s.set_tool_velocity(k, v),
        }
    }

    /// Tool `k`'s force along its axis (N).
    fn tool_force(&self, k: usize) -> f64 {
        match self {
            Sim::Plane(s) => s.tools()[k].axial_force(),
            Sim::Solid(s) => s.tools()[k].axial_force(),
        }
    }

    /// Tool `k`'s stroke along its axis (m).
    fn tool_stroke(&self, k: usize) -> f64 {
        match self {
            Sim::Plane(s) => s.tools()[k].state.stroke,
            Sim::Solid(s) => s.tools()[k].state.stroke,
        }
    }

    /// The scene's name.
    fn scene_name(&self) -> &str {
        match self {
            Sim::Plane(s) => &s.scene().name,
            Sim::Solid(s) => &s.scene().name,
        }
    }

    /// The scene as JSON (what a saved state is checked against).
    fn scene_json(&self) -> PyResult<serde_json::Value> {
        match self {
            Sim::Plane(s) => serde_json::to_value(s.scene()),
            Sim::Solid(s) => serde_json::to_value(s.scene()),
        }
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// The summary as summary.json has it, `wall` (s) since the simulation was created.
    fn summary(&self, wall: f64) -> serde_json::Value {
        let ending = rkforge_runner::Ending::Finished;
        match self {
            Sim::Plane(s) => rkforge_runner::summary(s, wall, 0.0, ending),
            Sim::Solid(s) => rkforge_runner::solid_summary(s, wall, 0.0, ending),
        }
    }
}

/// A running simulation and the threads it steps on.
struct Inner {
    sim: Sim,
    /// Its own rayon pool when a thread count was asked for, else rayon's global pool.
    pool: Option<rayon::ThreadPool>,
    /// When it was created: the summary's wall time counts from here.
    started: Instant,
    /// The last `sample`, where the outputs' interval means start (none: the start).
    since: Option<Since>,
}

impl Inner {
    /// Run `f` on the simulation's threads.
    fn install<R: Send>(&mut self, f: impl FnOnce(&mut Sim) -> R + Send) -> R {
        match &self.pool {
            Some(pool) => pool.install(|| f(&mut self.sim)),
            None => f(&mut self.sim),
        }
    }
}

/// A saved state of either kind.
#[derive(Serialize, Deserialize)]
enum Saved {
    /// A 2D state with its scene.
    Plane {
        scene: serde_json::Value,
        state: Box<State>,
    },
    /// A 3D state with its scene.
    Solid {
        scene: serde_json::Value,
        state: Box<SolidState>,
    },
}

/// A scene of either kind, configured for a run.
enum Configured {
    Plane(rkforge_core::Scene),
    Solid(SolidScene),
}

impl Configured {
    /// Set up its simulation.
    fn build(&self) -> rkforge_core::Result<Sim> {
        Ok(match self {
            Configured::Plane(s) => Sim::Plane(Box::new(rkforge_core::Simulation::new(s)?)),
            Configured::Solid(s) => Sim::Solid(Box::new(SolidSimulation::new(s)?)),
        })
    }
}

/// The scene with the `integration` argument applied.
fn configured(scene: &Scene, integration: Option<&str>) -> PyResult<Configured> {
    let rule = integration
        .map(|name| {
            IntegrationRule::parse(name).ok_or_else(|| {
                PyValueError::new_err(format!(
                    "integration `{name}`: expected \"q4\", \"q2\" or \"scni\""
                ))
            })
        })
        .transpose()?;
    Ok(match &scene.source {
        Source::Plane(s) => {
            let s = s.scene().clone();
            Configured::Plane(match rule {
                Some(r) => s.with_integration(r),
                None => s,
            })
        }
        Source::Solid(s) => {
            let mut s = s.scene().clone();
            if let Some(r) = rule {
                s.discretization.integration = r;
                if let Some((key, message)) = s.validate().into_iter().next() {
                    return Err(PyValueError::new_err(format!(
                        "integration `{}`: `{key}` {message}",
                        r.name()
                    )));
                }
            }
            Configured::Solid(s)
        }
    })
}

/// A rayon pool of `threads` workers ([`rkforge_core::check_threads`]: 1 to
/// [`rkforge_core::MAX_THREADS`]), or None for the global pool.
fn pool(threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    let Some(n) = threads else {
        return Ok(None);
    };
    rkforge_core::check_threads(n)
        .map_err(|why| PyValueError::new_err(format!("threads {why}")))?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map(Some)
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start {n} threads: {e}")))
}

/// Positions or velocities as an (n, D) array.
fn rows<'py, const D: usize>(
    py: Python<'py>,
    v: &[[f64; D]],
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_vec(py, v.iter().flatten().copied().collect()).reshape([v.len(), D])
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
        py.detach(|| guarded(|| f(&mut *self.lock()?)))
    }

    /// The simulation, locked for one call.
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, Inner>> {
        self.inner.lock().map_err(|_| {
            PyRuntimeError::new_err(
                "this simulation is unusable after an internal error; create a new one",
            )
        })
    }

    /// A dict of tool name -> `value(sim, tool index)`.
    fn per_tool<'py>(
        &self,
        py: Python<'py>,
        value: fn(&Sim, usize) -> f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let values = self.with(py, |s| {
            Ok(s.sim
                .tool_names()
                .into_iter()
                .enumerate()
                .map(|(k, name)| (name, value(&s.sim, k)))
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
    /// Set up the discretisation of `scene` (2D or 3D); `integration` ("q4", "q2", "scni")
    /// overrides the scene's rule, `threads` gives the simulation its own
    /// pool of that many threads.
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
                let build = || scene.build();
                let sim = match &pool {
                    Some(p) => p.install(build),
                    None => build(),
                }
                .map_err(to_py)?;
                Ok(Simulation {
                    inner: Mutex::new(Inner {
                        sim,
                        pool,
                        started,
                        since: None,
                    }),
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

    /// Step until the time reaches `t` (s), the last step shortened to land on it; a
    /// Ctrl-C stops it at the next step and raises `KeyboardInterrupt`.
    fn run_to(&self, py: Python<'_>, t: f64) -> PyResult<f64> {
        interruptible(py, |cancel| {
            let mut s = self.lock()?;
            let now = s.sim.time();
            if !t.is_finite() || t < now {
                return Err(PyValueError::new_err(format!(
                    "run_to({t}): the time must be finite and not before the current time {now:e} s"
                )));
            }
            s.install(|sim| sim.run_to(t, cancel).map(|()| sim.time()))
                .map_err(to_py)
        })
    }

    /// Command the velocity (m/s, along its axis) of the tool `name` from the next step on.
    fn set_tool_velocity(&self, py: Python<'_>, name: &str, velocity: f64) -> PyResult<()> {
        self.with(py, |s| {
            let k = s.sim.tool_index(name).ok_or_else(|| {
                PyValueError::new_err(format!(
                    "no tool named `{name}` (tools: {})",
                    s.sim.tool_names().join(", ")
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
        self.per_tool(py, Sim::tool_force)
    }

    /// Stroke of each tool along its axis (m), by tool name.
    fn tool_strokes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.per_tool(py, Sim::tool_stroke)
    }

    /// Record a history row now, as `rkforge run` does at its samples (this also updates
    /// the run's largest penetration): a dict of history.csv's columns, the interval means
    /// (`<tool>.force_mean_N`) since the last `sample` (the start for the first).
    /// SimulationError when a particle lies deeper inside a tool than
    /// `checks.max_penetration_rel`.
    fn sample<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (columns, row) = self.with(py, |s| {
            let since = s.since.take();
            let (recorded, columns, row, next) = match &mut s.sim {
                Sim::Plane(sim) => {
                    let mut history = rkforge_runner::History::new(sim).since(since);
                    let recorded = history.record(sim);
                    let (columns, row) = (history.columns().to_vec(), history.rows()[0].clone());
                    (recorded, columns, row, history.next_since().cloned())
                }
                Sim::Solid(sim) => {
                    let mut history = rkforge_runner::History::solid(sim).since(since);
                    let recorded = history.record_solid(sim);
                    let (columns, row) = (history.columns().to_vec(), history.rows()[0].clone());
                    (recorded, columns, row, history.next_since().cloned())
                }
            };
            s.since = next;
            recorded.map_err(to_py)?;
            Ok((columns, row))
        })?;
        let d = PyDict::new(py);
        for (c, v) in columns.into_iter().zip(row) {
            d.set_item(c, v)?;
        }
        Ok(d)
    }

    /// Every output of the register of outputs (`rkforge_core::outputs`) now, by its name:
    /// each column (history.csv's, and those only the summary and the FMU show) as a float,
    /// each field (`particles.*`, `points.*`) as a numpy array; the interval means since the
    /// last `sample` (the start before the first). Unlike `sample`, reading changes nothing
    /// (the run's largest penetration is not updated).
    fn outputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (values, fields) = self.with(py, |s| {
            let since = s.since.as_ref();
            Ok(match &s.sim {
                Sim::Plane(sim) => read(
                    &outputs::Sample::new(&**sim).since(since),
                    outputs::columns(sim.scene()),
                    outputs::fields(sim.scene()),
                ),
                Sim::Solid(sim) => read(
                    &outputs::Sample::new(&**sim).since(since),
                    outputs::solid_columns(sim.scene()),
                    outputs::solid_fields(sim.scene()),
                ),
            })
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

    /// Every tool as in summary.json: name, stroke, velocity, force [x, y] ([x, y, z] in
    /// 3D), axial and peak force.
    fn tools<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let tools = self.with(py, |s| {
            Ok(match &s.sim {
                Sim::Plane(sim) => serde_json::Value::Array(
                    (0..sim.tools().len())
                        .map(|k| rkforge_runner::tool_json(sim, k))
                        .collect(),
                ),
                Sim::Solid(sim) => {
                    rkforge_runner::solid_summary(sim, 0.0, 0.0, rkforge_runner::Ending::Finished)
                        ["tools"]
                        .clone()
                }
            })
        })?;
        to_dict(py, &tools)
    }

    /// The laps so far (folds of the surface onto itself between points apart along it), as
    /// in summary.json: each with `formed_s`, `formed_stroke_m` (by tool), `start_m`,
    /// `end_m`, `length_m` (2D) or `extent_m` (3D), `reference_m` and its surface
    /// `particles`.
    fn laps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let laps = self.with(py, |s| match &s.sim {
            Sim::Plane(sim) => Ok(serde_json::Value::Array(rkforge_runner::laps_json(sim))),
            Sim::Solid(sim) => Ok(serde_json::Value::Array(rkforge_runner::solid_laps_json(
                sim,
            ))),
        })?;
        to_dict(py, &laps)
    }

    /// Particle fields as numpy arrays: `positions`, `displacement`, `velocity` (n, 2) in m
    /// and m/s; `plastic_strain`, `von_mises` (Pa) and, in a scene with `[thermal]`,
    /// `temperature` (degrees C) (n,), smoothed from the points; `lap` (n,), the lap each
    /// particle took part in numbered from 1 (0: none). In 3D: `positions`, `displacement`,
    /// `velocity` (n, 3); `cells` (m, 8), the hexahedra of 8 particles (VTK order); and per
    /// cell, the mean over its integration points, `plastic_strain` and `von_mises` (Pa)
    /// (m,) and with `[thermal]` `temperature` (degrees C).
    fn fields<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let solid = self.with(py, |s| {
            Ok(match &s.sim {
                Sim::Plane(sim) => Err(sim.fields()),
                Sim::Solid(sim) => Ok(SolidFields::of(sim)),
            })
        })?;
        match solid {
            Err(f) => {
                d.set_item("positions", rows(py, &f.positions)?)?;
                d.set_item("displacement", rows(py, &f.displacement)?)?;
                d.set_item("velocity", rows(py, &f.velocity)?)?;
                d.set_item("plastic_strain", PyArray1::from_vec(py, f.plastic_strain))?;
                d.set_item("von_mises", PyArray1::from_vec(py, f.von_mises))?;
                if let Some(t) = f.temperature {
                    d.set_item("temperature", PyArray1::from_vec(py, t))?;
                }
                d.set_item("lap", PyArray1::from_vec(py, f.lap))?;
            }
            Ok(f) => {
                d.set_item("positions", rows(py, &f.positions)?)?;
                d.set_item("displacement", rows(py, &f.displacement)?)?;
                d.set_item("velocity", rows(py, &f.velocity)?)?;
                let cells: Vec<i64> = f.cells.iter().flatten().map(|&i| i64::from(i)).collect();
                d.set_item(
                    "cells",
                    PyArray1::from_vec(py, cells).reshape([f.cells.len(), 8])?,
                )?;
                d.set_item("plastic_strain", PyArray1::from_vec(py, f.plastic_strain))?;
                d.set_item("von_mises", PyArray1::from_vec(py, f.von_mises))?;
                if let Some(t) = f.temperature {
                    d.set_item("temperature", PyArray1::from_vec(py, t))?;
                }
            }
        }
        Ok(d)
    }

    /// The whole changing state, with its scene, as bytes (restoring it continues bit for bit).
    fn save_state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = self.with(py, |s| {
            let scene = s.sim.scene_json()?;
            let saved = match &s.sim {
                Sim::Plane(sim) => Saved::Plane {
                    scene,
                    state: Box::new(sim.state().clone()),
                },
                Sim::Solid(sim) => Saved::Solid {
                    scene,
                    state: Box::new(sim.state().clone()),
                },
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
            let scene = match &saved {
                Saved::Plane { scene, .. } | Saved::Solid { scene, .. } => scene,
            };
            let ours = s.sim.scene_json()?;
            if *scene != ours {
                let name = scene["name"].as_str().unwrap_or("?");
                return Err(StateError::new_err(if name == s.sim.scene_name() {
                    format!("the state was saved from scene `{name}` with other settings")
                } else {
                    format!(
                        "the state was saved from scene `{name}`, not `{}`",
                        s.sim.scene_name()
                    )
                }));
            }
            match (&mut s.sim, saved) {
                (Sim::Plane(sim), Saved::Plane { state, .. }) => sim.restore(*state),
                (Sim::Solid(sim), Saved::Solid { state, .. }) => sim.restore(*state),
                _ => {
                    return Err(StateError::new_err(
                        "the state was saved from a scene of the other kind (2D and 3D)",
                    ))
                }
            }
            .map_err(to_py)?;
            // The interval means start again at the state restored.
            s.since = Some(match &s.sim {
                Sim::Plane(sim) => Since::of(&**sim),
                Sim::Solid(sim) => Since::of(&**sim),
            });
            Ok(())
        })
    }

    /// The summary as summary.json has it (wall time since the simulation was created).
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let summary = self.with(py, |s| {
            let wall = s.started.elapsed().as_secs_f64();
            Ok(s.install(|sim| sim.summary(wall)))
        })?;
        to_dict(py, &summary)
    }
}

/// The 3D fields `Simulation.fields` gives.
struct SolidFields {
    positions: Vec<[f64; 3]>,
    displacement: Vec<[f64; 3]>,
    velocity: Vec<[f64; 3]>,
    cells: Vec<[u32; 8]>,
    plastic_strain: Vec<f64>,
    von_mises: Vec<f64>,
    temperature: Option<Vec<f64>>,
}

impl SolidFields {
    fn of(sim: &SolidSimulation) -> SolidFields {
        SolidFields {
            positions: sim.positions(),
            displacement: sim.displacements(),
            velocity: sim.velocities(),
            cells: sim.cells().to_vec(),
            plastic_strain: sim.cell_means(&sim.point_plastic_strain()),
            von_mises: sim.cell_means(&sim.point_von_mises()),
            temperature: sim.point_temperature().map(|t| sim.cell_means(t)),
        }
    }
}

/// Every column's value and every field of a sample, by name.
type Read = (Vec<(String, f64)>, Vec<(String, Vec<f64>)>);

/// The values of `columns` and `fields` in `now`.
fn read<S: outputs::Body>(
    now: &outputs::Sample<'_, S>,
    columns: Vec<outputs::Column<S>>,
    fields: impl Iterator<Item = &'static outputs::Output<S>>,
) -> Read {
    let values = columns
        .into_iter()
        .map(|c| {
            let v = c.value(now);
            (c.name, v)
        })
        .collect();
    let fields = fields
        .filter_map(|o| Some((o.full_name(), o.field(now)?)))
        .collect();
    (values, fields)
}

/// What `run_scene` returns: the summary (dict), the history's columns and rows, the failure.
type RunResult<'py> = (
    Bound<'py, PyAny>,
    Vec<String>,
    Bound<'py, PyArray2<f64>>,
    Option<String>,
);

/// A finished run's summary, history columns, rows (flat) and failure.
type Ran = (serde_json::Value, Vec<String>, Vec<f64>, Option<String>);

/// A finished run's summary, history columns, rows (flat) and failure.
fn ran<S: outputs::Body>(summary: serde_json::Value, outcome: rkforge_runner::Outcome<S>) -> Ran {
    let columns = outcome.history.columns().to_vec();
    let rows: Vec<f64> = outcome.history.rows().iter().flatten().copied().collect();
    (summary, columns, rows, outcome.failure)
}

/// Checkpoints of a run in Python: written into a folder every interval of wall time.
struct Saving<'a> {
    checkpoints: Option<rkforge_runner::Checkpoints>,
    /// Set by a Ctrl-C ([`interruptible`]): the run stops at the next instant.
    cancel: &'a AtomicBool,
}

impl<S: rkforge_runner::Runnable> rkforge_runner::Observer<S> for Saving<'_> {
    fn stop(&self, _sim: &S) -> Option<String> {
        self.cancel
            .load(Ordering::Relaxed)
            .then(|| "interrupted (KeyboardInterrupt)".to_string())
    }
    fn checkpoint(
        &mut self,
        sim: &S,
        run: &rkforge_runner::Run<S>,
        output: std::time::Duration,
    ) -> Result<(), String> {
        rkforge_runner::checkpoint::keep(self.checkpoints.as_mut(), sim, run, &(), output)
    }
}

/// Run `sim` to its end without frames, with checkpoints in `folder` every `every` of wall
/// time when a folder is given (going on from the one there, if there is one), and its
/// summary from `summary(sim, wall_s, output_s, ending)`.
fn drive_saving<S: rkforge_runner::Runnable>(
    sim: &mut S,
    folder: Option<&std::path::Path>,
    every: std::time::Duration,
    cancel: &AtomicBool,
    summary: impl Fn(&S, f64, f64, rkforge_runner::Ending<'_>) -> serde_json::Value,
) -> PyResult<Ran> {
    use rkforge_runner::checkpoint::{self, Restart};
    let wall = Instant::now();
    if let Some(dir) = folder {
        std::fs::create_dir_all(dir).map_err(|e| {
            PyValueError::new_err(format!("checkpoint: cannot create {}: {e}", dir.display()))
        })?;
    }
    let how = Restart {
        every: Some(every),
        resume: folder.is_some_and(|dir| dir.join(checkpoint::FILE).exists()),
    };
    let mut started =
        checkpoint::start::<S, ()>(sim, 0, folder, how).map_err(PyValueError::new_err)?;
    let mut saving = Saving {
        checkpoints: started.checkpoints.take(),
        cancel,
    };
    let outcome = started
        .go(sim, 0, &mut saving)
        .map_err(PyRuntimeError::new_err)?;
    let mut summary = summary(
        sim,
        started.wall_s + wall.elapsed().as_secs_f64(),
        started.output_s + outcome.output_time.as_secs_f64(),
        outcome.ending(),
    );
    started.mark(&mut summary);
    Ok(ran(summary, outcome))
}

/// The whole run of a scene, as `rkforge run --no-frames` does it: returns the summary
/// (dict), the history's column names and its rows (a 2D array), and the failure, if any.
/// With `checkpoint` (a folder), a checkpoint is written there every `checkpoint_every_s`
/// of wall time and a run finds the one left by a run of the same scene that was killed,
/// and goes on from it to the same bits.
#[pyfunction]
#[pyo3(signature = (scene, integration = None, threads = None, checkpoint = None, checkpoint_every_s = 600.0))]
pub fn run_scene<'py>(
    py: Python<'py>,
    scene: &Scene,
    integration: Option<&str>,
    threads: Option<usize>,
    checkpoint: Option<std::path::PathBuf>,
    checkpoint_every_s: f64,
) -> PyResult<RunResult<'py>> {
    if !(checkpoint_every_s.is_finite() && checkpoint_every_s >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "checkpoint_every_s = {checkpoint_every_s}: give a number of seconds, 0 or more"
        )));
    }
    let every = std::time::Duration::from_secs_f64(checkpoint_every_s);
    let scene = configured(scene, integration)?;
    let pool = pool(threads)?;
    let (summary, columns, rows, failure) = interruptible(py, |cancel| {
        let go = || -> PyResult<_> {
            let folder = checkpoint.as_deref();
            match scene.build().map_err(to_py)? {
                Sim::Plane(mut sim) => {
                    drive_saving(&mut *sim, folder, every, cancel, rkforge_runner::summary)
                }
                Sim::Solid(mut sim) => drive_saving(
                    &mut *sim,
                    folder,
                    every,
                    cancel,
                    rkforge_runner::solid_summary,
                ),
            }
        };
        match &pool {
            Some(p) => p.install(go),
            None => go(),
        }
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
