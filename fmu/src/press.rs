//! The four press plants of `examples/presses` as FMI 2.0 Co-Simulation slaves: a hydraulic
//! press (force-limited), a mechanical crank press (stroke-limited), a forging hammer and a
//! screw press (energy-limited), with the equations, parameters and defaults of the Python
//! examples (their variable tables in `modelDescription/src/press.rs`).
//!
//! Each press has the inputs `ram.force_N` (N: the force of the workpiece on the ram along the
//! ram's axis, the forging FMU's `<tool>.force`, negative while pressing), `ram.stroke_m` (m),
//! `ram.tool_work_J` (J) and `workpiece.height_m` (m), and the output `ram.velocity_m_per_s` (m/s along the
//! axis, the forging FMU's `<tool>.velocity` input), so the two connect name to name in an
//! SSP. The parameter `model_copies` (default 1) is how many copies of the forging FMU's
//! model make the whole workpiece (4 for a 3D quarter model): the press feels that many times
//! `ram.force_N`. Stepped as the Python examples' `co_simulate` steps its plant (the forging FMU
//! first, then the press with the forging outputs at the end of the step), a press FMU gives
//! the examples' histories: the same bits for the hydraulic press, the hammer and the screw
//! press. The crank press gives, after each step, the velocity that moves the ram along the
//! crank curve over a next step as long as that one (the example's `velocity(h)`); before
//! the first step it cannot know the step and gives `s'(theta0) omega0`, which moves the
//! force history by 3.5e-5 of its peak (tests/test_press_fmus.py).

use crate::instance::Phase;
use crate::slave::Saved;
use rkforge_core::Error;
use rkforge_core::Result;
pub use rkforge_model_description::press::{
    header, parse, variable_table, PressKind, MODEL_COPIES,
};
use rkforge_model_description::{Causality, Kind, Variable};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The state of a press that changes in time.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
struct State {
    /// Time (s).
    time: f64,
    /// Ram velocity along the axis (m/s).
    v: f64,
    /// Hydraulic: cylinder pressure (Pa).
    p: f64,
    /// Crank: angle (rad) and speed (rad/s); screw: flywheel speed (rad/s).
    theta: f64,
    omega: f64,
    /// Crank overload or stall, hammer's target reached, screw stopped.
    finished: bool,
    overload: bool,
    /// Hammer: blow under way, the stroke the ram is lifted to (between blows).
    blow: f64,
    lifting_to: Option<f64>,
}

/// A saved press state.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct PressState {
    kind: PressKind,
    values: Vec<f64>,
    state: State,
    phase: Phase,
}

/// One press instance.
pub struct Press {
    kind: PressKind,
    table: Vec<Variable>,
    guid: String,
    values: Vec<f64>,
    state: State,
    phase: Phase,
    /// The stop time the host set up (s), past which a step is an error.
    stop_time: Option<f64>,
}

/// Most sub-steps of the hydraulic press's semi-implicit Euler in one communication step: a
/// million take some 20 ms (1e12, accepted before, held a step for hours).
const MAX_SUBSTEPS: f64 = 1e6;

/// Most blows of the hammer.
const MAX_BLOWS: f64 = 1e6;

fn request(msg: String) -> Error {
    Error::Request(msg)
}

impl Press {
    /// A press of `kind` with the defaults, `model_copies` at `copies`.
    pub fn new(kind: PressKind, copies: f64) -> Press {
        let table = variable_table(kind, copies);
        let values = table
            .iter()
            .map(|v| match v.kind {
                Kind::Real(Some(x)) => x,
                _ => 0.0,
            })
            .collect();
        let guid = header(kind, "").guid;
        let mut p = Press {
            kind,
            table,
            guid,
            values,
            state: State::default(),
            phase: Phase::Instantiated,
            stop_time: None,
        };
        p.start();
        p
    }

    /// The GUID of the press's model description.
    pub fn guid(&self) -> &str {
        &self.guid
    }

    fn value(&self, name: &str) -> f64 {
        self.table
            .iter()
            .position(|v| v.name == name)
            .map_or(f64::NAN, |k| self.values[k])
    }

    /// The state at the start from the parameters.
    fn start(&mut self) {
        self.state = State {
            time: self.state.time,
            ..State::default()
        };
        match self.kind {
            PressKind::Hydraulic => {}
            PressKind::Crank => {
                self.state.theta = self.crank_start();
                self.state.omega = 2.0 * PI * self.value("strokes_per_minute") / 60.0;
                self.state.v = self.crank_rate(self.state.theta) * self.state.omega;
            }
            PressKind::Hammer => {
                self.state.v = self.value("impact_speed");
                self.state.blow = 1.0;
            }
            PressKind::Screw => {
                self.state.omega = self.value("omega");
                self.state.v = self.state.omega * self.value("lead") / (2.0 * PI);
            }
        }
    }

    /// Ram travel from top dead centre at crank angle `theta` (m):
    /// `s = r (1 - cos theta) + l (1 - sqrt(1 - (r/l)^2 sin^2 theta))`.
    fn crank_stroke(&self, theta: f64) -> f64 {
        let (r, l) = (self.value("crank_radius"), self.value("rod_length"));
        let lam = r / l;
        r * (1.0 - theta.cos()) + l * (1.0 - (1.0 - (lam * theta.sin()).powi(2)).sqrt())
    }

    /// The crank angle where the co-simulation starts: the ram `ram_gap` above the billet
    /// at the angle that puts it at `shut_height` at bottom dead centre,
    /// `s(theta0) = 2 r - ram_gap - (billet_height - shut_height)`, by bisection on [0, pi]
    /// as the Python example finds it.
    fn crank_start(&self) -> f64 {
        let r = self.value("crank_radius");
        let s0 = 2.0 * r
            - self.value("ram_gap")
            - (self.value("billet_height") - self.value("shut_height"));
        let (mut lo, mut hi) = (0.0, PI);
        for _ in 0..100 {
            let mid = (lo + hi) / 2.0;
            if self.crank_stroke(mid) - s0 < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (lo + hi) / 2.0
    }

    /// `d s / d theta` of the slider-crank (m/rad).
    fn crank_rate(&self, theta: f64) -> f64 {
        let (r, l) = (self.value("crank_radius"), self.value("rod_length"));
        let lam = r / l;
        let (s, c) = theta.sin_cos();
        r * s * (1.0 + lam * c / (1.0 - (lam * s).powi(2)).sqrt())
    }

    fn allowed_force(&self, theta: f64) -> f64 {
        let (rated, angle) = (self.value("rated_force"), self.value("rated_angle"));
        if PI - theta <= angle {
            rated
        } else {
            rated * self.crank_rate(PI - angle) / self.crank_rate(theta)
        }
    }

    /// Check the parameters as the Python examples do.
    fn check(&self) -> Result<()> {
        for (k, v) in self.table.iter().enumerate() {
            if v.causality != Causality::Parameter {
                continue;
            }
            let x = self.values[k];
            let ok = if v.name == "damping" {
                x >= 0.0 && x.is_finite()
            } else {
                x > 0.0 && x.is_finite()
            };
            if !ok {
                return Err(request(format!(
                    "`{}` = {x}: must be {} and finite",
                    v.name,
                    if v.name == "damping" {
                        "zero or positive"
                    } else {
                        "positive"
                    }
                )));
            }
            let most = match v.name.as_str() {
                "substeps" => MAX_SUBSTEPS,
                "max_blows" => MAX_BLOWS,
                _ => continue,
            };
            if x.fract() != 0.0 || x > most {
                return Err(request(format!(
                    "`{}` = {x}: must be a whole number from 1 to {most}",
                    v.name
                )));
            }
        }
        if self.kind == PressKind::Crank {
            let (r, l) = (self.value("crank_radius"), self.value("rod_length"));
            if r >= l {
                return Err(request(format!(
                    "`crank_radius` = {r} must be shorter than `rod_length` = {l}"
                )));
            }
            let s0 = 2.0 * r
                - self.value("ram_gap")
                - (self.value("billet_height") - self.value("shut_height"));
            if !(0.0..2.0 * r).contains(&s0) {
                return Err(request(format!(
                    "`ram_gap` and `shut_height` do not fit the stroke 2 r = {} m of the crank",
                    2.0 * r
                )));
            }
        }
        Ok(())
    }

    /// One communication step of `h` (s) with the inputs held: the equations of the Python
    /// examples (`advance`), the force resisting the stroke `F = -ram.force_N`.
    fn advance(&mut self, h: f64) {
        if self.state.finished {
            self.state.v = 0.0;
            return;
        }
        let force = -self.value("ram.force_N") * self.value("model_copies");
        match self.kind {
            PressKind::Hydraulic => {
                // Semi-implicit Euler in `substeps` steps, the pressure capped by the valve.
                let n = self.value("substeps").round().max(1.0) as usize;
                let (area, mass, c) = (
                    self.value("area"),
                    self.value("ram_mass"),
                    self.value("damping"),
                );
                let (flow, relief) = (self.value("flow"), self.value("relief_pressure"));
                let stiff = self.value("bulk_modulus") / self.value("oil_volume");
                let dt = h / n as f64;
                let st = &mut self.state;
                for _ in 0..n {
                    st.v += dt * (st.p * area - force - c * st.v) / mass;
                    st.p += dt * stiff * (flow - area * st.v);
                    st.p = st.p.clamp(0.0, relief);
                }
            }
            PressKind::Crank => {
                // I d omega/dt = -F s'(theta), s' at the step's mid angle.
                let rate_mid = self.crank_rate(self.state.theta + self.state.omega * h / 2.0);
                let inertia = self.value("inertia");
                let theta = self.state.theta + self.state.omega * h;
                let mut omega = self.state.omega - h * force * rate_mid / inertia;
                let overload = force > self.allowed_force(theta);
                let stalled = omega <= 0.0;
                if stalled {
                    omega = 0.0;
                }
                // The velocity that moves the ram along the crank curve over a next step as
                // long as this one, as the Python example's `velocity(h)`.
                let v = (self.crank_stroke(theta + omega * h) - self.crank_stroke(theta)) / h;
                let end = PI + self.value("end_angle");
                let st = &mut self.state;
                st.theta = theta;
                st.omega = omega;
                st.v = v;
                st.overload |= overload;
                st.finished = overload || stalled || theta >= end;
            }
            PressKind::Hammer => {
                // m dv/dt = -F until the ram rebounds; lifted by `gap`, then the next blow.
                let stroke = self.value("ram.stroke_m");
                let (mass, v0) = (self.value("ram_mass"), self.value("impact_speed"));
                let (gap, lift) = (self.value("gap"), self.value("lift_speed"));
                let (target, most) = (self.value("target_height"), self.value("max_blows"));
                let height = self.value("workpiece.height_m");
                let st = &mut self.state;
                if let Some(to) = st.lifting_to {
                    if stroke <= to {
                        st.lifting_to = None;
                        st.v = v0;
                        st.blow += 1.0;
                    }
                    return;
                }
                st.v -= h * force / mass;
                if st.v < 0.0 && force <= 0.0 {
                    if height <= target || st.blow >= most {
                        st.finished = true;
                        st.v = 0.0;
                    } else {
                        st.lifting_to = Some(stroke - gap);
                        st.v = -lift;
                    }
                }
            }
            PressKind::Screw => {
                // I d omega/dt = -F p / (2 pi), v = omega p / (2 pi).
                let (inertia, lead) = (self.value("inertia"), self.value("lead"));
                let st = &mut self.state;
                st.omega -= h * force * lead / (2.0 * PI * inertia);
                if st.omega <= 0.0 {
                    st.omega = 0.0;
                    st.finished = true;
                }
                st.v = st.omega * lead / (2.0 * PI);
            }
        }
    }

    fn output(&self, name: &str) -> Option<f64> {
        let st = &self.state;
        let energy = |i: f64, w: f64| i * w * w / 2.0;
        Some(match name {
            "ram.velocity_m_per_s" => st.v,
            "finished" => f64::from(u8::from(st.finished)),
            "pressure_Pa" => st.p,
            "crank_angle_rad" => st.theta,
            "crank_speed_rad_per_s" | "flywheel_speed_rad_per_s" => st.omega,
            "flywheel_energy_J" => energy(self.value("inertia"), st.omega),
            "allowed_force_N" => self.allowed_force(st.theta),
            "overload" => f64::from(u8::from(st.overload)),
            "blow" => st.blow,
            _ => return None,
        })
    }

    fn variable(&self, vr: u32) -> Result<(usize, &Variable)> {
        self.table
            .get(vr as usize)
            .map(|v| (vr as usize, v))
            .ok_or_else(|| request(format!("unknown value reference {vr}")))
    }
}

impl crate::slave::Slave for Press {
    fn guid(&self) -> &str {
        &self.guid
    }
    fn phase(&self) -> Phase {
        self.phase
    }
    fn time(&self) -> f64 {
        self.state.time
    }
    fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Result<()> {
        if self.phase != Phase::Instantiated || !start.is_finite() {
            return Err(request(format!("setup at {start} s is not allowed now")));
        }
        self.stop_time = crate::slave::stop_time(start, stop)?;
        self.state.time = start;
        Ok(())
    }
    fn enter_initialization(&mut self) -> Result<()> {
        if self.phase != Phase::Instantiated {
            return Err(request("enter initialization is not allowed now".into()));
        }
        self.phase = Phase::Initialization;
        Ok(())
    }
    fn exit_initialization(&mut self) -> Result<()> {
        if self.phase != Phase::Initialization {
            return Err(request("exit initialization is not allowed now".into()));
        }
        self.check()?;
        self.start();
        self.phase = Phase::Stepping;
        Ok(())
    }
    fn terminate(&mut self) -> Result<()> {
        self.phase = Phase::Terminated;
        Ok(())
    }
    fn reset(&mut self) {
        let copies = match self.table.iter().find(|v| v.name == MODEL_COPIES.0) {
            Some(Variable {
                kind: Kind::Real(Some(x)),
                ..
            }) => *x,
            _ => 1.0,
        };
        *self = Press::new(self.kind, copies);
    }
    fn get_real(&mut self, vr: u32) -> Result<f64> {
        let (k, v) = self.variable(vr)?;
        match v.causality {
            Causality::Output => self
                .output(&v.name)
                .ok_or_else(|| request(format!("`{}` has no value", v.name))),
            _ => Ok(self.values[k]),
        }
    }
    fn set_real(&mut self, vr: u32, value: f64) -> Result<()> {
        let (k, v) = self.variable(vr)?;
        let (causality, name) = (v.causality, v.name.clone());
        let allowed = match causality {
            Causality::Input => true,
            Causality::Parameter => {
                matches!(self.phase, Phase::Instantiated | Phase::Initialization)
            }
            Causality::Output => false,
        };
        if !allowed {
            return Err(request(format!("`{name}` cannot be set now")));
        }
        if !value.is_finite() {
            return Err(request(format!("`{name}` = {value} is not finite")));
        }
        self.values[k] = value;
        if causality == Causality::Parameter {
            self.start();
        }
        Ok(())
    }
    fn get_integer(&mut self, vr: u32) -> Result<i32> {
        Err(request(format!(
            "value reference {vr}: a press has no Integer variables"
        )))
    }
    fn set_integer(&mut self, vr: u32, _value: i32) -> Result<()> {
        Err(request(format!(
            "value reference {vr}: a press has no Integer variables"
        )))
    }
    fn get_string(&mut self, vr: u32) -> Result<String> {
        Err(request(format!(
            "value reference {vr}: a press has no String variables"
        )))
    }
    fn set_string(&mut self, vr: u32, _value: &str) -> Result<()> {
        Err(request(format!(
            "value reference {vr}: a press has no String variables"
        )))
    }
    fn do_step(&mut self, t: f64, h: f64) -> Result<()> {
        if self.phase != Phase::Stepping {
            return Err(request(format!(
                "doStep is not allowed in phase {:?}",
                self.phase
            )));
        }
        if !(h > 0.0 && h.is_finite()) {
            return Err(request(format!(
                "communication step size {h} s must be positive and finite"
            )));
        }
        if (t - self.state.time).abs() > 1e-9 * h.max(t.abs()) {
            return Err(request(format!(
                "communication point {t} s does not match the FMU time {} s",
                self.state.time
            )));
        }
        crate::slave::within_stop(self.stop_time, t, h)?;
        self.advance(h);
        self.state.time += h;
        Ok(())
    }
    fn save(&self) -> Saved {
        Box::new(PressState {
            kind: self.kind,
            values: self.values.clone(),
            state: self.state.clone(),
            phase: self.phase,
        })
    }
    fn load(&mut self, state: &Saved) -> Result<()> {
        let s = state
            .downcast_ref::<PressState>()
            .filter(|s| s.kind == self.kind)
            .ok_or_else(|| Error::State("the state belongs to another press".into()))?;
        self.values = s.values.clone();
        self.state = s.state.clone();
        self.phase = s.phase;
        Ok(())
    }
    fn serialize(&self, state: &Saved) -> Result<Vec<u8>> {
        let s = state
            .downcast_ref::<PressState>()
            .ok_or_else(|| Error::State("the state belongs to another kind of FMU".into()))?;
        serde_json::to_vec(s).map_err(|e| Error::State(e.to_string()))
    }
    fn deserialize(&self, bytes: &[u8]) -> Result<Saved> {
        let s: PressState = serde_json::from_slice(bytes)
            .map_err(|e| Error::State(format!("cannot read the press state: {e}")))?;
        Ok(Box::new(s))
    }
}
