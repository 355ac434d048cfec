//! The FMU's instance in safe Rust: an explicit FMI state machine ([`Phase`]) over one
//! scene, reading and writing variables through the scene's variable table (outputs from
//! the register, [`rkforge_model_description::fmu_columns`]) and stepping its simulation on
//! the run layer (`stepping.rs`), with the saved state of a rollback ([`Snapshot`]).

use crate::stepping::{EarlyReturn, Observer, Stepper};
use rkforge_core::outputs::{Column, Sample};
use rkforge_core::scene_parameters::{parameters, Parameter};
use rkforge_core::{Error, Result, Scene, SceneSource, Simulation, State};
use rkforge_model_description::{
    fmu_columns, variable_table3, xml, Binding, Causality, Kind, Variable,
};
use serde::{Deserialize, Serialize};

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
fn output_value(
    binding: Binding,
    sample: &Sample<'_>,
    columns: &[Column],
    commands: &[Option<f64>],
) -> Option<f64> {
    Some(match binding {
        Binding::ToolVelocity(k) => {
            commands[k].unwrap_or_else(|| sample.tools()[k].velocity_at(sample.time()))
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
fn outputs_of(
    table: &[Variable],
    sim: &Simulation,
    columns: &[Column],
    commands: &[Option<f64>],
) -> Vec<(u32, f64)> {
    let sample = Sample::new(sim);
    table
        .iter()
        .filter(|v| v.causality == Causality::Output)
        .filter_map(|v| {
            let value = output_value(v.binding, &sample, columns, commands)?;
            Some((v.value_reference, value))
        })
        .collect()
}

/// A saved FMU state: everything needed to continue bit for bit, also in a fresh instance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    guid: String,
    phase: Phase,
    params: Params,
    start_time: f64,
    commands: Vec<Option<f64>>,
    state: Option<State>,
}

/// One co-simulation instance.
pub struct Instance {
    /// The scene as packed, and its name in errors.
    text: String,
    label: String,
    scene: Scene,
    parameters: Vec<Parameter>,
    guid: String,
    /// The FMI 3.0 table (the 2.0 table and, after `time`, the early-return switches).
    table: Vec<Variable>,
    /// The register's columns the outputs read ([`Binding::Output`]).
    columns: Vec<Column>,
    early: Vec<EarlyReturn>,
    params: Params,
    commands: Vec<Option<f64>>,
    /// The simulation on the run layer, once built.
    sim: Option<Stepper>,
    phase: Phase,
    start_time: f64,
}

fn request(msg: String) -> Error {
    Error::Request(msg)
}

impl Instance {
    /// An instance of the scene given as TOML text; `label` names it in errors.
    pub fn new(scene_text: &str, label: &str) -> Result<Instance> {
        let scene = Scene::from_str_named(scene_text, label)?;
        let parameters = parameters(&scene);
        Ok(Instance {
            text: scene_text.to_string(),
            label: label.to_string(),
            table: variable_table3(&scene),
            columns: fmu_columns(&scene),
            early: vec![EarlyReturn::default(); scene.tools.len()],
            guid: xml::guid(scene_text),
            commands: vec![None; scene.tools.len()],
            params: vec![None; parameters.len()],
            parameters,
            scene,
            sim: None,
            phase: Phase::Instantiated,
            start_time: 0.0,
        })
    }

    /// The scene's GUID (digest of its text).
    pub fn guid(&self) -> &str {
        &self.guid
    }
    /// Value reference of FMI 3.0's independent variable `time`.
    pub fn time_value_reference(&self) -> u32 {
        rkforge_model_description::time_value_reference(&self.scene)
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
        self.start_time + self.simulation().map_or(0.0, Simulation::time)
    }
    /// The simulation, once initialised.
    pub fn simulation(&self) -> Option<&Simulation> {
        self.sim.as_ref().map(Stepper::sim)
    }

    fn variable(&self, vr: u32) -> Result<&Variable> {
        self.table
            .iter()
            .find(|v| v.value_reference == vr)
            .ok_or_else(|| request(format!("unknown value reference {vr}")))
    }

    /// The scene with `params` applied, as `--set` applies dotted keys, and validated by
    /// the scene's own rules: an error names the key.
    fn scene_with(&self, params: &Params) -> Result<Scene> {
        let overrides = self
            .parameters
            .iter()
            .zip(params)
            .filter_map(|(p, v)| Some((p.key.clone(), v.clone()?)))
            .collect();
        Ok(
            SceneSource::with_overrides(&self.text, &self.label, overrides)?
                .scene()
                .clone(),
        )
    }

    /// The scene with the current parameters applied.
    fn configured_scene(&self) -> Result<Scene> {
        self.scene_with(&self.params)
    }

    /// Set parameter `k` (the variable `v`) to `value` if the scene it gives is valid.
    fn set_parameter(&mut self, v: &Variable, k: usize, value: toml::Value) -> Result<()> {
        let mut params = self.params.clone();
        params[k] = Some(value.clone());
        self.scene_with(&params)
            .map_err(|e| request(format!("`{}` = {value}: {e}", v.name)))?;
        self.params = params;
        self.sim = None;
        Ok(())
    }

    /// The current value of parameter `k`.
    fn parameter(&self, k: usize) -> &toml::Value {
        self.params[k].as_ref().unwrap_or(&self.parameters[k].start)
    }

    fn build(&mut self) -> Result<()> {
        let mut sim = Simulation::new(&self.configured_scene()?)?;
        for (k, c) in self.commands.iter().enumerate() {
            if let Some(v) = c {
                sim.set_tool_velocity(k, *v)?;
            }
        }
        self.sim = Some(Stepper::new(sim));
        Ok(())
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

    /// `fmi2SetupExperiment`: the start time (s); stop time and tolerance are not used.
    pub fn setup_experiment(&mut self, start_time: f64) -> Result<()> {
        self.expect(&[Phase::Instantiated], "fmi2SetupExperiment")?;
        if !start_time.is_finite() {
            return Err(request(format!("start time {start_time} is not finite")));
        }
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
        if self.sim.is_none() {
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
        self.commands = vec![None; self.scene.tools.len()];
        self.early = vec![EarlyReturn::default(); self.scene.tools.len()];
        self.sim = None;
        self.phase = Phase::Instantiated;
        self.start_time = 0.0;
    }

    /// Outputs are read from a simulation; during initialisation one is built on demand.
    fn readable_sim(&mut self) -> Result<&Simulation> {
        self.expect(
            &[
                Phase::Initialization,
                Phase::Stepping,
                Phase::Terminated,
                Phase::Failed,
            ],
            "reading a variable",
        )?;
        if self.sim.is_none() {
            self.build()?;
        }
        self.simulation()
            .ok_or_else(|| request("no simulation".into()))
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
        self.readable_sim()?;
        let sim = self
            .simulation()
            .ok_or_else(|| request("no simulation".into()))?;
        output_value(binding, &Sample::new(sim), &self.columns, &self.commands)
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
                if let Some(sim) = self.sim.as_mut() {
                    sim.sim_mut().set_tool_velocity(k, value)?;
                }
                Ok(())
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
    /// after the solver step at which an armed event first happens (a tool's first touch of
    /// the workpiece, a tool's force magnitude first reaching its level); returns that time
    /// (s), or `None` when the step ran to its end.
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
        let target = now - self.start_time + h;
        let armed: Vec<EarlyReturn> = self.early.iter().map(|e| e.armed(early)).collect();
        let (table, columns, commands) = (&self.table, &self.columns, &self.commands);
        let start = self.start_time;
        let stepper = self
            .sim
            .as_mut()
            .ok_or_else(|| request("not initialised".into()))?;
        let mut report = observe.map(|o| {
            move |sim: &Simulation| {
                o(
                    start + sim.time(),
                    &outputs_of(table, sim, columns, commands),
                )
            }
        });
        let report = report
            .as_mut()
            .map(|r| r as &mut (dyn FnMut(&Simulation) -> bool + Send));
        match stepper.step_to(target, &armed, early, report) {
            Ok(true) => Ok(Some(start + stepper.sim().time())),
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
            Binding::ContactPressure(k) => Ok(self.readable_sim()?.contact_pressure(k)),
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
        Snapshot {
            guid: self.guid.clone(),
            phase: self.phase,
            params: self.params.clone(),
            start_time: self.start_time,
            commands: self.commands.clone(),
            state: self.simulation().map(|s| s.state().clone()),
        }
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
        match &s.state {
            Some(state) => {
                if self
                    .simulation()
                    .is_none_or(|sim| sim.state().d.len() != state.d.len())
                {
                    self.sim = None;
                    self.build()?;
                }
                if let Some(sim) = self.sim.as_mut() {
                    sim.sim_mut().restore(state.clone())?;
                }
            }
            None => self.sim = None,
        }
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

    fn scene_text() -> String {
        include_str!("../../scenes/taylor_bar.toml")
            .replace("particles = [21, 51]", "particles = [7, 15]")
            .replace(
                "motion = { kind = \"fixed\" }",
                "motion = { kind = \"external\" }",
            )
    }

    fn ready() -> Instance {
        let mut i = Instance::new(&scene_text(), "t").unwrap();
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        i
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
        let mut a = ready();
        let h = 1e-6;
        a.do_step(0.0, h).unwrap();
        let bytes = a.snapshot().to_bytes();
        a.do_step(h, h).unwrap();
        let mut b = Instance::new(&scene_text(), "t").unwrap();
        b.restore(&Snapshot::from_bytes(&bytes).unwrap()).unwrap();
        b.do_step(h, h).unwrap();
        assert_eq!(a.snapshot(), b.snapshot());
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
}
