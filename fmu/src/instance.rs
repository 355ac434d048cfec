//! The FMU's instance in safe Rust: an explicit FMI state machine ([`Phase`]) over one
//! scene, 2D or 3D, reading and writing variables through the scene's variable table
//! (outputs from the register, [`rkforge_model_description::fmu_columns`]) and stepping its
//! simulation (`stepping.rs`), with the saved state of a rollback ([`Snapshot`]). What
//! depends on the kind of scene is a [`Model`] of its simulation ([`Forging`]), behind
//! [`Plant`].

use crate::stepping::{EarlyReturn, Forging, Observer, Stepper};
use rkforge_core::outputs::{Column, Sample, Since};
use rkforge_core::scene::solid::is_solid;
use rkforge_core::scene_parameters::Parameter;
use rkforge_core::solver::{SolidSimulation, SolidState};
use rkforge_core::{Error, Result, SceneSource, Simulation, State};
use rkforge_model_description::{
    fmu_columns, time_value_reference, variable_table3, xml, Binding, Causality, FmuScene, Kind,
    Variable,
};
use serde::{Deserialize, Serialize};
use std::any::Any;

/// Where an instance is in the FMI 2.0 Co-Simulation state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Phase {
    /// After `fmi2Instantiate`: parameters and inputs may be set.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    Initialization,
    /// Stepping (`slaveInitialized`).
    Stepping,
    /// After `fmi2Terminate`.
    Terminated,
    /// After a failed step: only reading, `fmi2Reset` and freeing are allowed.
    Failed,
}

/// The values set on the scene's parameters, by parameter index
/// ([`rkforge_core::scene_parameters::parameters`]); `None` keeps the scene's own.
pub type Params = Vec<Option<toml::Value>>;

/// The value of a Real variable that the simulation answers (an input's current value, an
/// output of the register, `columns` the FMU's [`fmu_columns`]), `None` for the other
/// bindings.
fn output_value<S: Forging>(
    binding: Binding,
    sample: &Sample<'_, S>,
    columns: &[Column<S>],
    commands: &[Option<f64>],
) -> Option<f64> {
    Some(match binding {
        Binding::ToolVelocity(k) => {
            commands[k].unwrap_or_else(|| sample.velocity_at(k, sample.time_now()))
        }
        Binding::Output(k) => columns[k].value(sample),
        Binding::Parameter(_)
        | Binding::ContactPressure(_)
        | Binding::Press(_)
        | Binding::ReturnForceLevel(_)
        | Binding::ReturnOnContact(_)
        | Binding::ReturnOnForce(_) => return None,
    })
}

/// The Float64 outputs of `table` now, by value reference (FMI 3.0 intermediate updates).
fn outputs_of<S: Forging>(
    table: &[Variable],
    sim: &S,
    since: Option<&Since>,
    columns: &[Column<S>],
    commands: &[Option<f64>],
) -> Vec<(u32, f64)> {
    let sample = Sample::new(sim).since(since);
    table
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .filter_map(|v| {
            let value = output_value(v.binding, &sample, columns, commands)?;
            Some((v.value_reference, value))
        })
        .collect()
}

/// The scene text an instance was made of, with the values set on its parameters: what
/// builds its simulation.
struct Configured<'a> {
    text: &'a str,
    label: &'a str,
    overrides: Vec<(String, toml::Value)>,
    commands: &'a [Option<f64>],
}

/// The dotted keys of `parameters` with the values set on them (`params`, by index).
fn overrides(parameters: &[Parameter], params: &Params) -> Vec<(String, toml::Value)> {
    parameters
        .iter()
        .zip(params)
        .filter_map(|(p, v)| Some((p.key.clone(), v.clone()?)))
        .collect()
}

/// The host's intermediate updates during a step: `observe` gets the time (shifted by
/// `start`, s) and the outputs of `table` after each solver step.
struct Watch<'a> {
    observe: Observer<'a>,
    table: &'a [Variable],
    commands: &'a [Option<f64>],
    start: f64,
}

/// The part of an instance that depends on the kind of its scene ([`Model`]).
trait Plant: Send {
    /// Whether the scene with these overrides is valid.
    fn check(&self, c: &Configured<'_>) -> Result<()>;
    /// Build the simulation of the configured scene, its tools commanded.
    fn build(&mut self, c: &Configured<'_>) -> Result<()>;
    /// Drop the simulation (it is built again when needed).
    fn clear(&mut self);
    /// The simulation's time (s), once built.
    fn time(&self) -> Option<f64>;
    /// The simulation, once built.
    fn simulation(&self) -> Option<&dyn Any>;
    /// The value of a Real variable bound to `binding`, once built.
    fn output(&self, binding: Binding, commands: &[Option<f64>]) -> Option<f64>;
    /// Command tool `k`'s velocity (m/s), once built.
    fn command(&mut self, k: usize, v: f64) -> Result<()>;
    /// Step to `target` (s, the simulation's own time): [`Stepper::step_to`], reporting
    /// to the host's `report`.
    fn step_to(
        &mut self,
        target: f64,
        armed: &[EarlyReturn],
        early: bool,
        report: Option<Watch<'_>>,
    ) -> Result<bool>;
    /// The contact pressure at tool `k`'s stations (Pa), once built.
    fn contact_pressure(&self, k: usize) -> Option<Vec<f64>>;
    /// Keep the simulation's state in `snapshot`.
    fn save(&self, snapshot: &mut Snapshot);
    /// Go on from the state `snapshot` keeps (none: drop the simulation), built anew from
    /// `c` when the simulation has another discretisation.
    fn restore(&mut self, snapshot: &Snapshot, c: &Configured<'_>) -> Result<()>;
}

/// The simulation of a scene of kind `S` and the register's columns its outputs read.
struct Model<S: Forging> {
    /// The register's columns the outputs read ([`Binding::Output`]).
    columns: Vec<Column<S>>,
    /// The simulation, once built.
    sim: Option<Stepper<S>>,
    /// The start of the last communication step, where the interval means start.
    since: Option<Since>,
}

impl<S: Forging> Model<S> {
    fn scene(c: &Configured<'_>) -> Result<S::Scene> {
        Ok(
            SceneSource::<S::Scene>::of_text(c.text, c.label, c.overrides.clone())?
                .scene()
                .clone(),
        )
    }
}

impl<S: Forging> Plant for Model<S>
where
    Column<S>: Send,
{
    fn check(&self, c: &Configured<'_>) -> Result<()> {
        Self::scene(c).map(|_| ())
    }

    fn build(&mut self, c: &Configured<'_>) -> Result<()> {
        let mut sim = S::build(&Self::scene(c)?)?;
        for (k, v) in c.commands.iter().enumerate() {
            if let Some(v) = v {
                sim.command(k, *v)?;
            }
        }
        self.sim = Some(Stepper::new(sim));
        self.since = None;
        Ok(())
    }

    fn clear(&mut self) {
        self.sim = None;
        self.since = None;
    }

    fn time(&self) -> Option<f64> {
        self.sim.as_ref().map(|s| s.sim().time_now())
    }

    fn simulation(&self) -> Option<&dyn Any> {
        self.sim.as_ref().map(|s| s.sim() as &dyn Any)
    }

    fn output(&self, binding: Binding, commands: &[Option<f64>]) -> Option<f64> {
        let sim = self.sim.as_ref()?.sim();
        let sample = Sample::new(sim).since(self.since.as_ref());
        output_value(binding, &sample, &self.columns, commands)
    }

    fn command(&mut self, k: usize, v: f64) -> Result<()> {
        match self.sim.as_mut() {
            Some(s) => s.sim_mut().command(k, v),
            None => Ok(()),
        }
    }

    fn step_to(
        &mut self,
        target: f64,
        armed: &[EarlyReturn],
        early: bool,
        report: Option<Watch<'_>>,
    ) -> Result<bool> {
        let columns = &self.columns;
        let stepper = self
            .sim
            .as_mut()
            .ok_or_else(|| request("not initialised".into()))?;
        let since = &*self.since.insert(Since::of(stepper.sim()));
        let mut report = report.map(|w| {
            move |sim: &S| {
                (w.observe)(
                    w.start + sim.time_now(),
                    &outputs_of(w.table, sim, Some(since), columns, w.commands),
                )
            }
        });
        let report = report
            .as_mut()
            .map(|r| r as &mut (dyn FnMut(&S) -> bool + Send));
        stepper.step_to(target, armed, early, report)
    }

    fn contact_pressure(&self, k: usize) -> Option<Vec<f64>> {
        Some(self.sim.as_ref()?.sim().pressure(k))
    }

    fn save(&self, snapshot: &mut Snapshot) {
        if let Some(s) = &self.sim {
            S::put(s.sim().saved(), snapshot);
        }
        snapshot.since.clone_from(&self.since);
    }

    fn restore(&mut self, snapshot: &Snapshot, c: &Configured<'_>) -> Result<()> {
        match S::take(snapshot) {
            Some(state) => {
                if self.sim.as_ref().is_none_or(|s| !s.sim().fits(state)) {
                    self.build(c)?;
                }
                if let Some(s) = self.sim.as_mut() {
                    s.sim_mut().restore_state(state.clone())?;
                }
                self.since.clone_from(&snapshot.since);
            }
            None => self.sim = None,
        }
        Ok(())
    }
}

/// What an instance needs of its scene, of kind `S`: its plant, its FMI 3.0 variable
/// table, its parameters, the value reference of `time` and its number of tools.
type Made = (Box<dyn Plant>, Vec<Variable>, Vec<Parameter>, u32, usize);

fn made<S: Forging>(text: &str, label: &str) -> Result<Made>
where
    Column<S>: Send,
{
    let scene = SceneSource::<S::Scene>::of_text(text, label, Vec::new())?
        .scene()
        .clone();
    let model = Model::<S> {
        columns: fmu_columns(&scene),
        sim: None,
        since: None,
    };
    Ok((
        Box::new(model),
        variable_table3(&scene),
        scene.tunable(),
        time_value_reference(&scene),
        scene.tool_motions().len(),
    ))
}

/// A saved FMU state: everything needed to continue bit for bit, also in a fresh instance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    guid: String,
    phase: Phase,
    params: Params,
    start_time: f64,
    commands: Vec<Option<f64>>,
    /// The state of a 2D simulation.
    pub(crate) state: Option<State>,
    /// The state of a 3D simulation (absent from a 2D FMU's serialized states).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) solid: Option<Box<SolidState>>,
    /// Where the outputs' interval means start (the start of the last communication step).
    #[serde(default)]
    pub(crate) since: Option<Since>,
}

/// One co-simulation instance.
pub struct Instance {
    /// The scene as packed, and its name in errors.
    text: String,
    label: String,
    /// The scene's number of tools.
    tools: usize,
    parameters: Vec<Parameter>,
    guid: String,
    /// The FMI 3.0 table (the 2.0 table and, after `time`, the early-return switches).
    table: Vec<Variable>,
    /// Value reference of FMI 3.0's `time`.
    time_vr: u32,
    early: Vec<EarlyReturn>,
    params: Params,
    commands: Vec<Option<f64>>,
    /// The scene's simulation (2D or 3D) and the columns its outputs read.
    model: Box<dyn Plant>,
    phase: Phase,
    start_time: f64,
    /// The stop time the host set up (s), past which a step is an error.
    stop_time: Option<f64>,
}

fn request(msg: String) -> Error {
    Error::Request(msg)
}

/// Whether the parameter `name` is a component of a tool's direction, a unit vector
/// (`tools.top.axis[1]`, `tools.wall.normal[2]`, `tools.pin.axis_direction[0]`).
fn is_direction_component(name: &str) -> bool {
    name.rsplit_once('[').is_some_and(|(key, _)| {
        ["axis", "normal", "axis_direction"]
            .iter()
            .any(|d| key.strip_suffix(d).is_some_and(|k| k.ends_with('.')))
    })
}

impl Instance {
    /// An instance of the scene given as TOML text, 2D or 3D (`model.kinematics = "3d"`);
    /// `label` names it in errors.
    pub fn new(scene_text: &str, label: &str) -> Result<Instance> {
        let (model, table, parameters, time_vr, tools) = if is_solid(scene_text) {
            made::<SolidSimulation>(scene_text, label)?
        } else {
            made::<Simulation>(scene_text, label)?
        };
        Ok(Instance {
            text: scene_text.to_string(),
            label: label.to_string(),
            tools,
            table,
            time_vr,
            early: vec![EarlyReturn::default(); tools],
            guid: xml::guid(scene_text),
            commands: vec![None; tools],
            params: vec![None; parameters.len()],
            parameters,
            model,
            phase: Phase::Instantiated,
            start_time: 0.0,
            stop_time: None,
        })
    }

    /// The scene's GUID (digest of its text).
    pub fn guid(&self) -> &str {
        &self.guid
    }
    /// Value reference of FMI 3.0's independent variable `time`.
    pub fn time_value_reference(&self) -> u32 {
        self.time_vr
    }
    /// The variable table (FMI 3.0's: the 2.0 table, then the early-return switches).
    pub fn variables(&self) -> &[Variable] {
        &self.table
    }
    /// Where the instance is in the state machine.
    pub fn phase(&self) -> Phase {
        self.phase
    }
    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.start_time + self.model.time().unwrap_or(0.0)
    }
    /// The simulation of a 2D scene, once initialised.
    pub fn simulation(&self) -> Option<&Simulation> {
        self.model.simulation()?.downcast_ref()
    }
    /// The simulation of a 3D scene, once initialised.
    pub fn solid_simulation(&self) -> Option<&SolidSimulation> {
        self.model.simulation()?.downcast_ref()
    }

    fn variable(&self, vr: u32) -> Result<&Variable> {
        self.table
            .iter()
            .find(|v| v.value_reference == vr)
            .ok_or_else(|| request(format!("unknown value reference {vr}")))
    }

    /// The scene text with `params` applied, as `--set` applies dotted keys (validated by
    /// the scene's own rules when built: an error names the key).
    fn configured_with<'a>(&'a self, params: &Params) -> Configured<'a> {
        Configured {
            text: &self.text,
            label: &self.label,
            overrides: overrides(&self.parameters, params),
            commands: &self.commands,
        }
    }

    /// Run `f` on the model with the scene as configured now.
    fn on_model<R>(&mut self, f: impl FnOnce(&mut dyn Plant, &Configured<'_>) -> R) -> R {
        let c = Configured {
            text: &self.text,
            label: &self.label,
            overrides: overrides(&self.parameters, &self.params),
            commands: &self.commands,
        };
        f(self.model.as_mut(), &c)
    }

    /// The 2D scene with the current parameters applied.
    #[cfg(test)]
    fn configured_scene(&self) -> Result<rkforge_core::Scene> {
        let overrides = overrides(&self.parameters, &self.params);
        Ok(
            SceneSource::with_overrides(&self.text, &self.label, overrides)?
                .scene()
                .clone(),
        )
    }

    /// Set parameter `k` (the variable `v`) to `value` if the scene it gives is valid. A
    /// component of a direction (`axis`, `normal`, `axis_direction`: unit vectors) is taken
    /// whatever the scene then gives, as no single component can turn a unit vector into
    /// another: the direction is checked whole when the simulation is built
    /// (`ExitInitializationMode`, or an output read before it), the error naming its key.
    fn set_parameter(&mut self, v: &Variable, k: usize, value: toml::Value) -> Result<()> {
        let mut params = self.params.clone();
        params[k] = Some(value.clone());
        if !is_direction_component(&v.name) {
            self.model
                .check(&self.configured_with(&params))
                .map_err(|e| request(format!("`{}` = {value}: {e}", v.name)))?;
        }
        self.params = params;
        self.model.clear();
        Ok(())
    }

    /// The current value of parameter `k`.
    fn parameter(&self, k: usize) -> &toml::Value {
        self.params[k].as_ref().unwrap_or(&self.parameters[k].start)
    }

    fn build(&mut self) -> Result<()> {
        self.on_model(|m, c| m.build(c))
    }

    fn expect(&self, allowed: &[Phase], what: &str) -> Result<()> {
        if allowed.contains(&self.phase) {
            Ok(())
        } else {
            Err(request(format!(
                "{what} is not allowed in phase {:?}",
                self.phase
            )))
        }
    }

    /// `fmi2SetupExperiment`: the start time (s) and the stop time (s) if the host defines
    /// one, past which a step is an error ([`crate::slave::within_stop`]); the tolerance is
    /// not used.
    pub fn setup_experiment(&mut self, start_time: f64, stop_time: Option<f64>) -> Result<()> {
        self.expect(&[Phase::Instantiated], "fmi2SetupExperiment")?;
        if !start_time.is_finite() {
            return Err(request(format!("start time {start_time} is not finite")));
        }
        self.stop_time = crate::slave::stop_time(start_time, stop_time)?;
        self.start_time = start_time;
        Ok(())
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization(&mut self) -> Result<()> {
        self.expect(&[Phase::Instantiated], "fmi2EnterInitializationMode")?;
        self.phase = Phase::Initialization;
        Ok(())
    }

    /// `fmi2ExitInitializationMode`: builds the discretisation with the parameters set.
    pub fn exit_initialization(&mut self) -> Result<()> {
        self.expect(&[Phase::Initialization], "fmi2ExitInitializationMode")?;
        if self.model.time().is_none() {
            self.build()?;
        }
        self.phase = Phase::Stepping;
        Ok(())
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Result<()> {
        self.expect(&[Phase::Stepping, Phase::Failed], "fmi2Terminate")?;
        self.phase = Phase::Terminated;
        Ok(())
    }

    /// `fmi2Reset`: back to the freshly instantiated state with the scene's own values.
    pub fn reset(&mut self) {
        self.params = vec![None; self.parameters.len()];
        self.commands = vec![None; self.tools];
        self.early = vec![EarlyReturn::default(); self.tools];
        self.model.clear();
        self.phase = Phase::Instantiated;
        self.start_time = 0.0;
        self.stop_time = None;
    }

    /// Outputs are read from a simulation; during initialisation one is built on demand.
    fn readable(&mut self) -> Result<()> {
        self.expect(
            &[
                Phase::Initialization,
                Phase::Stepping,
                Phase::Terminated,
                Phase::Failed,
            ],
            "reading a variable",
        )?;
        if self.model.time().is_none() {
            self.build()?;
        }
        Ok(())
    }

    /// `fmi2GetReal`.
    pub fn get_real(&mut self, vr: u32) -> Result<f64> {
        let binding = self.variable(vr)?.binding;
        if let Binding::ReturnForceLevel(k) = binding {
            return Ok(self.early[k].level);
        }
        if let Binding::Parameter(k) = binding {
            return match self.parameter(k) {
                toml::Value::Float(x) => Ok(*x),
                _ => Err(request(format!(
                    "value reference {vr} is not a Real variable"
                ))),
            };
        }
        self.readable()?;
        self.model
            .output(binding, &self.commands)
            .ok_or_else(|| request(format!("value reference {vr} is not a Real variable")))
    }

    /// `fmi2GetInteger`.
    pub fn get_integer(&mut self, vr: u32) -> Result<i32> {
        match self.variable(vr)?.binding {
            Binding::Parameter(k) => match self.parameter(k) {
                toml::Value::Integer(i) => i32::try_from(*i)
                    .map_err(|_| request(format!("value reference {vr}: {i} overflows"))),
                _ => Err(request(format!(
                    "value reference {vr} is not an Integer variable"
                ))),
            },
            _ => Err(request(format!(
                "value reference {vr} is not an Integer variable"
            ))),
        }
    }

    /// `fmi2GetString`.
    pub fn get_string(&mut self, vr: u32) -> Result<String> {
        match self.variable(vr)?.binding {
            Binding::Parameter(k) => match self.parameter(k) {
                toml::Value::String(s) => Ok(s.clone()),
                _ => Err(request(format!(
                    "value reference {vr} is not a String variable"
                ))),
            },
            _ => Err(request(format!(
                "value reference {vr} is not a String variable"
            ))),
        }
    }

    fn settable(&self, v: &Variable) -> Result<()> {
        let allowed: &[Phase] = match v.causality {
            Causality::Parameter => &[Phase::Instantiated, Phase::Initialization],
            Causality::Input => &[Phase::Instantiated, Phase::Initialization, Phase::Stepping],
            Causality::Output => {
                return Err(request(format!(
                    "`{}` is an output and cannot be set",
                    v.name
                )))
            }
        };
        if allowed.contains(&self.phase) {
            Ok(())
        } else {
            Err(request(format!(
                "`{}` cannot be set in phase {:?}",
                v.name, self.phase
            )))
        }
    }

    /// `fmi2SetReal`: a tool velocity (m/s) or a Real parameter.
    pub fn set_real(&mut self, vr: u32, value: f64) -> Result<()> {
        let v = self.variable(vr)?.clone();
        self.settable(&v)?;
        if !value.is_finite() {
            return Err(request(format!(
                "`{}` = {value} is not finite; ignored",
                v.name
            )));
        }
        match (v.binding, &v.kind) {
            (Binding::ToolVelocity(k), _) => {
                self.commands[k] = Some(value);
                self.model.command(k, value)
            }
            (Binding::Parameter(k), Kind::Real(_)) => {
                self.set_parameter(&v, k, toml::Value::Float(value))
            }
            (Binding::ReturnForceLevel(k), _) if value >= 0.0 => {
                self.early[k].level = value;
                Ok(())
            }
            (Binding::ReturnForceLevel(_), _) => Err(request(format!(
                "`{}` = {value}: a force level is a magnitude, zero or positive",
                v.name
            ))),
            _ => Err(request(format!("`{}` is not a Real variable", v.name))),
        }
    }

    /// `fmi2SetInteger`: an Integer parameter (`workpiece.particles[0]`).
    pub fn set_integer(&mut self, vr: u32, value: i32) -> Result<()> {
        let v = self.variable(vr)?.clone();
        self.settable(&v)?;
        match (v.binding, &v.kind) {
            (Binding::Parameter(k), Kind::Integer(_)) => {
                self.set_parameter(&v, k, toml::Value::Integer(value.into()))
            }
            _ => Err(request(format!("`{}` is not an Integer variable", v.name))),
        }
    }

    /// `fmi2SetString`: an enumerated parameter (`discretization.integration`).
    pub fn set_string(&mut self, vr: u32, value: &str) -> Result<()> {
        let v = self.variable(vr)?.clone();
        self.settable(&v)?;
        match (v.binding, &v.kind) {
            (Binding::Parameter(k), Kind::String(_)) => {
                self.set_parameter(&v, k, toml::Value::String(value.into()))
            }
            _ => Err(request(format!("`{}` is not a String variable", v.name))),
        }
    }

    /// `fmi2DoStep` from the communication point `t` (s) by `h` (s), sub-cycled at the
    /// solver's step. A failed step leaves the instance in [`Phase::Failed`].
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<()> {
        self.step(t, h, false, None).map(|_| ())
    }

    /// `fmi3DoStep` with early return allowed: as [`Instance::do_step`], but the step ends
    /// after the first solver step at which an armed event happens (a tool coming to touch
    /// the workpiece, a tool's force magnitude rising to its level: each rise, so a later
    /// touch or rise ends a later step again); returns that time (s), or `None` when the
    /// step ran to its end.
    pub fn do_step_early(&mut self, t: f64, h: f64) -> Result<Option<f64>> {
        self.step(t, h, true, None)
    }

    /// `fmi3DoStep` with an intermediate update: as [`Instance::do_step_early`] (events
    /// armed only when `early`), and `observe` called after every solver step with the time
    /// and the outputs; when `early` and it returns true, the step returns there.
    pub fn do_step_observed(
        &mut self,
        t: f64,
        h: f64,
        early: bool,
        observe: Observer<'_>,
    ) -> Result<Option<f64>> {
        self.step(t, h, early, Some(observe))
    }

    fn step(
        &mut self,
        t: f64,
        h: f64,
        early: bool,
        observe: Option<Observer<'_>>,
    ) -> Result<Option<f64>> {
        self.expect(&[Phase::Stepping], "doStep")?;
        if !(h > 0.0 && h.is_finite()) {
            return Err(request(format!(
                "communication step size {h} s must be positive and finite"
            )));
        }
        let now = self.time();
        if !t.is_finite() || (t - now).abs() > 1e-9 * h.max(now.abs()).max(1e-300) {
            return Err(request(format!(
                "communication point {t} s does not match the FMU time {now} s"
            )));
        }
        crate::slave::within_stop(self.stop_time, t, h)?;
        let target = now - self.start_time + h;
        let armed: Vec<EarlyReturn> = self.early.iter().map(|e| e.armed(early)).collect();
        let start = self.start_time;
        let report = observe.map(|observe| Watch {
            observe,
            table: &self.table,
            commands: &self.commands,
            start,
        });
        match self.model.step_to(target, &armed, early, report) {
            Ok(true) => Ok(Some(self.time())),
            Ok(false) => Ok(None),
            Err(e) => {
                self.phase = Phase::Failed;
                Err(e)
            }
        }
    }

    /// How many values variable `vr` has when it is an array (FMI 3.0).
    pub fn array_len(&self, vr: u32) -> Option<usize> {
        match self.variable(vr).ok()?.kind {
            Kind::RealArray(n) => Some(n),
            _ => None,
        }
    }

    /// `fmi3GetFloat64` of an array variable: the contact pressure at a tool's stations (Pa).
    pub fn get_real_array(&mut self, vr: u32) -> Result<Vec<f64>> {
        match self.variable(vr)?.binding {
            Binding::ContactPressure(k) => {
                self.readable()?;
                self.model
                    .contact_pressure(k)
                    .ok_or_else(|| request("no simulation".into()))
            }
            _ => Err(request(format!("value reference {vr} is not an array"))),
        }
    }

    /// `fmi3GetBoolean`: an early-return switch.
    pub fn get_boolean(&self, vr: u32) -> Result<bool> {
        match self.variable(vr)?.binding {
            Binding::ReturnOnContact(k) => Ok(self.early[k].contact),
            Binding::ReturnOnForce(k) => Ok(self.early[k].force),
            _ => Err(request(format!(
                "value reference {vr} is not a Boolean variable"
            ))),
        }
    }

    /// `fmi3SetBoolean`: an early-return switch, before initialisation.
    pub fn set_boolean(&mut self, vr: u32, value: bool) -> Result<()> {
        let v = self.variable(vr)?.clone();
        self.settable(&v)?;
        match v.binding {
            Binding::ReturnOnContact(k) => self.early[k].contact = value,
            Binding::ReturnOnForce(k) => self.early[k].force = value,
            _ => return Err(request(format!("`{}` is not a Boolean variable", v.name))),
        }
        Ok(())
    }

    /// `fmi2GetFMUstate`.
    pub fn snapshot(&self) -> Snapshot {
        let mut s = Snapshot {
            guid: self.guid.clone(),
            phase: self.phase,
            params: self.params.clone(),
            start_time: self.start_time,
            commands: self.commands.clone(),
            state: None,
            solid: None,
            since: None,
        };
        self.model.save(&mut s);
        s
    }

    /// `fmi2SetFMUstate`: restores a snapshot of an instance of the same scene.
    pub fn restore(&mut self, s: &Snapshot) -> Result<()> {
        if s.guid != self.guid {
            return Err(request(
                "the FMU state belongs to another scene (GUID differs)".into(),
            ));
        }
        self.params = s.params.clone();
        self.commands = s.commands.clone();
        self.start_time = s.start_time;
        self.on_model(|m, c| m.restore(s, c))?;
        self.phase = s.phase;
        Ok(())
    }
}

impl Snapshot {
    /// Serialized bytes (JSON; floats round-trip exactly).
    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).unwrap_or_default()
    }
    /// From serialized bytes.
    pub fn from_bytes(b: &[u8]) -> Result<Snapshot> {
        serde_json::from_slice(b)
            .map_err(|e| Error::State(format!("cannot read the serialized FMU state: {e}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rkforge_core::Scene;

    /// A scene's text with its fixed tools commanded from outside.
    fn external(text: String) -> String {
        text.replace(
            "motion = { kind = \"fixed\" }",
            "motion = { kind = \"external\" }",
        )
    }

    fn scene_text() -> String {
        external(
            include_str!("../../scenes/taylor_bar.toml")
                .replace("particles = [21, 51]", "particles = [7, 15]"),
        )
    }

    /// An instance of `text`, initialised.
    fn initialised(text: &str) -> Instance {
        let mut i = Instance::new(text, "t").unwrap();
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        i
    }

    fn ready() -> Instance {
        initialised(&scene_text())
    }

    fn vr(i: &Instance, n: &str) -> u32 {
        i.variables()
            .iter()
            .find(|v| v.name == n)
            .unwrap()
            .value_reference
    }

    #[test]
    fn stroke_follows_the_velocity_input_and_force_appears() {
        let mut inst = ready();
        let (vel, stroke, force) = (
            vr(&inst, "wall.velocity_m_per_s"),
            vr(&inst, "wall.stroke_m"),
            vr(&inst, "wall.force_N"),
        );
        inst.set_real(vel, 2.0).unwrap();
        let h = 1e-6;
        for k in 0..5 {
            inst.do_step(k as f64 * h, h).unwrap();
        }
        assert!((inst.get_real(stroke).unwrap() - 2.0 * 5e-6).abs() < 1e-15);
        let f = inst.get_real(force).unwrap();
        assert!(f > 1e4, "the bar pushes the wall");
        // The wall backs away from the bar that pushes it: it takes work from the bar, at
        // most the largest force over the stroke (the force rises as the bar arrives).
        let work = inst.get_real(vr(&inst, "energy.tool_work_J")).unwrap();
        assert!(work < 0.0 && -work <= f * 2.0 * 5e-6, "{work} J");
    }

    /// A step that returns early leaves its communication point unreached; the next step
    /// runs from where it returned to its own point, not to the one left behind.
    #[test]
    fn a_step_after_an_early_return_lands_on_its_own_point() {
        let mut i = Instance::new(&scene_text(), "t").unwrap();
        i.set_boolean(vr(&i, "wall.early_return.force"), true)
            .unwrap();
        i.set_real(vr(&i, "wall.early_return.force_level"), 1e4)
            .unwrap();
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        let h = 1e-4;
        let back = i.do_step_early(0.0, h).unwrap().expect("an early return");
        assert!(back > 0.0 && back < h, "{back}");
        assert_eq!(i.time(), back);
        i.do_step(back, 1e-6).unwrap();
        assert!((i.time() - (back + 1e-6)).abs() < 1e-15, "{}", i.time());
        assert_eq!(i.do_step_early(i.time(), 1e-6).unwrap(), None);
    }

    #[test]
    fn bad_requests_are_errors_and_leave_the_instance_usable() {
        let mut inst = ready();
        assert!(inst.do_step(0.0, 0.0).is_err());
        assert!(inst.do_step(1.0, 1e-6).is_err());
        assert!(inst.get_real(9999).is_err());
        let vel = vr(&inst, "wall.velocity_m_per_s");
        assert!(inst.set_real(vel, f64::NAN).is_err());
        assert!(inst.set_real(vr(&inst, "wall.force_N"), 1.0).is_err());
        assert!(
            inst.set_integer(vr(&inst, "workpiece.particles[0]"), 9)
                .is_err(),
            "parameter after initialisation"
        );
        inst.do_step(0.0, 1e-6).unwrap();
    }

    #[test]
    fn snapshot_round_trip_continues_bit_for_bit() {
        continues_bit_for_bit(ready(), &scene_text());
    }

    /// `a`, an initialised instance of the scene `text`, steps, saves its serialized state
    /// and steps on; a fresh instance restoring the state and taking the same step ends in
    /// the same bits. Returns the serialized state.
    fn continues_bit_for_bit(mut a: Instance, text: &str) -> Vec<u8> {
        let h = 1e-6;
        a.do_step(0.0, h).unwrap();
        let bytes = a.snapshot().to_bytes();
        a.do_step(h, h).unwrap();
        let mut b = Instance::new(text, "t").unwrap();
        b.restore(&Snapshot::from_bytes(&bytes).unwrap()).unwrap();
        b.do_step(h, h).unwrap();
        assert_eq!(a.snapshot(), b.snapshot());
        assert_eq!(a.snapshot().to_bytes(), b.snapshot().to_bytes());
        bytes
    }

    #[test]
    fn parameters_change_the_discretisation() {
        let mut i = Instance::new(&scene_text(), "t").unwrap();
        i.set_integer(vr(&i, "workpiece.particles[0]"), 5).unwrap();
        i.set_string(vr(&i, "discretization.integration"), "q4")
            .unwrap();
        let err = i
            .set_string(vr(&i, "discretization.integration"), "q3")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("`discretization.integration`") && err.contains("q4"),
            "{err}"
        );
        assert_eq!(
            i.get_string(vr(&i, "discretization.integration")).unwrap(),
            "q4"
        );
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        let sim = i.simulation().unwrap();
        assert_eq!(sim.grid(), (5, 15));
        assert_eq!(sim.point_count(), 4 * 4 * 14);
    }

    /// A parameter is the scene key: the same value set through the FMU and written in the
    /// scene give the same scene; a bad value is refused at once with the key's name and
    /// the scene's own message, and the instance keeps its previous value.
    #[test]
    fn parameters_are_scene_keys_validated_by_the_scene() {
        let shear = scene_text().replace(
            "friction = 0.0",
            "friction = { model = \"shear\", m = 0.5 }",
        );
        let mut i = Instance::new(&shear, "t").unwrap();
        let m = vr(&i, "tools.wall.friction.m");
        let err = i.set_real(m, 1.5).unwrap_err().to_string();
        assert!(
            err.contains("`tools.wall.friction.m`") && err.contains("between 0 and 1"),
            "{err}"
        );
        assert_eq!(i.get_real(m).unwrap(), 0.5);
        i.set_real(m, 0.25).unwrap();
        let written = shear.replace("m = 0.5", "m = 0.25");
        assert_eq!(
            i.configured_scene().unwrap(),
            Scene::from_str_named(&written, "t").unwrap()
        );
    }

    /// `time.mass_scaling.factor`, a key of a scene with mass scaling, multiplies the
    /// masses (the critical step by its square root); a factor below 1 is refused, naming
    /// the key.
    #[test]
    fn mass_scaling_parameters_scale_the_masses() {
        let plain = ready();
        let scaled = scene_text().replace("[time]\n", "[time]\nmass_scaling = { factor = 2.0 }\n");
        let mut i = Instance::new(&scaled, "t").unwrap();
        let factor = vr(&i, "time.mass_scaling.factor");
        let err = i.set_real(factor, 0.5).unwrap_err().to_string();
        assert!(err.contains("`time.mass_scaling.factor`"), "{err}");
        i.set_real(factor, 100.0).unwrap();
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        let (a, b) = (plain.simulation().unwrap(), i.simulation().unwrap());
        assert!((b.total_mass() / a.total_mass() - 100.0).abs() < 1e-9);
        assert!((b.critical_dt0() / a.critical_dt0() - 10.0).abs() < 1e-4);
        assert!(!plain
            .variables()
            .iter()
            .any(|v| v.name.starts_with("time.mass_scaling")));
    }

    /// The Taylor bar in 3D, coarse and short, its wall commanded from outside.
    fn solid_text() -> String {
        external(
            include_str!("../../scenes/taylor_bar_3d.toml")
                .replace("cells = [8, 4, 60]", "cells = [2, 1, 8]")
                .replace("end_s = 80.0e-6", "end_s = 10.0e-6"),
        )
    }

    fn solid_ready() -> Instance {
        initialised(&solid_text())
    }

    /// A 3D scene gives the 2D interface: the wall's velocity input, the 3D register's
    /// outputs under their history names, the scene's own keys as parameters, no
    /// contact-pressure arrays; stepping moves the wall and the bar pushes it.
    #[test]
    fn a_3d_scene_steps_with_the_same_interface() {
        let mut i = solid_ready();
        assert!(i.simulation().is_none() && i.solid_simulation().is_some());
        let names: Vec<&str> = i.variables().iter().map(|v| v.name.as_str()).collect();
        for n in [
            "wall.velocity_m_per_s",
            "wall.force_N",
            "wall.stroke_m",
            "workpiece.height_m",
            "energy.kinetic_J",
            "workpiece.cells[2]",
            "discretization.integration",
            "wall.early_return.contact",
        ] {
            assert!(names.contains(&n), "{n} in {names:?}");
        }
        assert!(!names.iter().any(|n| n.contains("contact_pressure")));
        let (vel, stroke, force, height) = (
            vr(&i, "wall.velocity_m_per_s"),
            vr(&i, "wall.stroke_m"),
            vr(&i, "wall.force_N"),
            vr(&i, "workpiece.height_m"),
        );
        let h0 = i.get_real(height).unwrap();
        assert!((h0 - 0.0324).abs() < 1e-12, "{h0}");
        i.set_real(vel, 2.0).unwrap();
        let h = 1e-6;
        for k in 0..3 {
            i.do_step(k as f64 * h, h).unwrap();
        }
        assert!((i.time() - 3e-6).abs() < 1e-15);
        assert!((i.get_real(stroke).unwrap() - 2.0 * 3e-6).abs() < 1e-15);
        assert_eq!(i.get_real(vel).unwrap(), 2.0);
        // The bar hits the wall: it pushes it along -axis (the axis points down, -z).
        assert!(i.get_real(force).unwrap().abs() > 1e3);
        assert!(i.get_real(height).unwrap() < h0);
        let f = i.get_real(force).unwrap();
        let sim = i.solid_simulation().unwrap();
        assert_eq!(f.to_bits(), sim.tools()[0].axial_force().to_bits());
    }

    /// Early return on contact in 3D: the bar lies on the wall, so the first solver step
    /// that presses on it ends the step.
    #[test]
    fn a_3d_step_returns_early_at_the_first_touch() {
        let mut i = Instance::new(&solid_text(), "t3").unwrap();
        i.set_boolean(vr(&i, "wall.early_return.contact"), true)
            .unwrap();
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        let h = 1e-6;
        let back = i.do_step_early(0.0, h).unwrap().expect("an early return");
        assert!(back > 0.0 && back < h, "{back}");
        assert!(i.solid_simulation().unwrap().tools()[0].state.normal_force != 0.0);
        assert_eq!(i.do_step_early(back, h).unwrap(), None);
    }

    #[test]
    fn a_3d_snapshot_round_trip_continues_bit_for_bit() {
        let mut a = solid_ready();
        a.set_real(vr(&a, "wall.velocity_m_per_s"), -1.0).unwrap();
        let bytes = continues_bit_for_bit(a, &solid_text());
        // A 2D instance takes no 3D state.
        let mut plane = Instance::new(&scene_text(), "t").unwrap();
        assert!(plane
            .restore(&Snapshot::from_bytes(&bytes).unwrap())
            .is_err());
    }

    /// A 3D scene's keys are parameters, validated by the 3D scene's rules.
    #[test]
    fn a_3d_scenes_parameters_change_its_discretisation() {
        let mut i = Instance::new(&solid_text(), "t3").unwrap();
        let cells = vr(&i, "workpiece.cells[2]");
        assert_eq!(i.get_integer(cells).unwrap(), 8);
        i.set_integer(cells, 6).unwrap();
        let err = i
            .set_real(vr(&i, "material.poisson_ratio"), 0.7)
            .unwrap_err()
            .to_string();
        assert!(err.contains("`material.poisson_ratio`"), "{err}");
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        let coarse = solid_ready();
        let (a, b) = (
            coarse.solid_simulation().unwrap(),
            i.solid_simulation().unwrap(),
        );
        assert!(b.particle_count() < a.particle_count());
        i.reset();
        assert_eq!(i.get_integer(cells).unwrap(), 8);
    }
}
