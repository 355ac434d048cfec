//! The FMI 2.0 C API's view of a co-simulation slave ([`Slave`]): the forging
//! [`Instance`] or a press plant ([`crate::press::Press`]), with its FMU states kept as the
//! slave's own type until the host asks for bytes.

use crate::instance::{Instance, Phase, Snapshot};
use rkforge_core::Error;
use rkforge_core::Result;

/// A saved FMU state of a [`Slave`], kept as it is (serialized only when the host asks).
pub type Saved = Box<dyn std::any::Any>;

/// An FMI 2.0 Co-Simulation slave behind the C API ([`ffi`]): a forging scene
/// ([`Instance`]) or a press plant ([`press::Press`]).
pub trait Slave {
    /// The GUID of its model description.
    fn guid(&self) -> &str;
    /// Where it is in the state machine.
    fn phase(&self) -> Phase;
    /// Current time (s).
    fn time(&self) -> f64;
    /// `fmi2SetupExperiment` (`fmi3EnterInitializationMode`'s times): the start time (s)
    /// and the stop time (s) when the host defines one ([`within_stop`]).
    fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Result<()>;
    /// `fmi2EnterInitializationMode`.
    fn enter_initialization(&mut self) -> Result<()>;
    /// `fmi2ExitInitializationMode`.
    fn exit_initialization(&mut self) -> Result<()>;
    /// `fmi2Terminate`.
    fn terminate(&mut self) -> Result<()>;
    /// `fmi2Reset`.
    fn reset(&mut self);
    /// `fmi2GetReal`.
    fn get_real(&mut self, vr: u32) -> Result<f64>;
    /// `fmi2SetReal`.
    fn set_real(&mut self, vr: u32, value: f64) -> Result<()>;
    /// `fmi2GetInteger`.
    fn get_integer(&mut self, vr: u32) -> Result<i32>;
    /// `fmi2SetInteger`.
    fn set_integer(&mut self, vr: u32, value: i32) -> Result<()>;
    /// `fmi2GetString`.
    fn get_string(&mut self, vr: u32) -> Result<String>;
    /// `fmi2SetString`.
    fn set_string(&mut self, vr: u32, value: &str) -> Result<()>;
    /// `fmi2DoStep` from `t` by `h` (s).
    fn do_step(&mut self, t: f64, h: f64) -> Result<()>;
    /// `fmi2GetFMUstate`: everything to continue bit for bit.
    fn save(&self) -> Saved;
    /// `fmi2SetFMUstate` from [`Slave::save`] or [`Slave::deserialize`].
    fn load(&mut self, state: &Saved) -> Result<()>;
    /// `fmi2SerializeFMUstate`.
    fn serialize(&self, state: &Saved) -> Result<Vec<u8>>;
    /// `fmi2DeSerializeFMUstate`.
    fn deserialize(&self, bytes: &[u8]) -> Result<Saved>;
}

/// The state of type `T` behind a [`Saved`] of a slave of that kind.
fn saved<T: 'static>(state: &Saved) -> Result<&T> {
    state
        .downcast_ref::<T>()
        .ok_or_else(|| Error::State("the FMU state belongs to another kind of FMU".into()))
}

impl Slave for Instance {
    fn guid(&self) -> &str {
        Instance::guid(self)
    }
    fn phase(&self) -> Phase {
        Instance::phase(self)
    }
    fn time(&self) -> f64 {
        Instance::time(self)
    }
    fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Result<()> {
        Instance::setup_experiment(self, start, stop)
    }
    fn enter_initialization(&mut self) -> Result<()> {
        Instance::enter_initialization(self)
    }
    fn exit_initialization(&mut self) -> Result<()> {
        Instance::exit_initialization(self)
    }
    fn terminate(&mut self) -> Result<()> {
        Instance::terminate(self)
    }
    fn reset(&mut self) {
        Instance::reset(self)
    }
    fn get_real(&mut self, vr: u32) -> Result<f64> {
        Instance::get_real(self, vr)
    }
    fn set_real(&mut self, vr: u32, value: f64) -> Result<()> {
        Instance::set_real(self, vr, value)
    }
    fn get_integer(&mut self, vr: u32) -> Result<i32> {
        Instance::get_integer(self, vr)
    }
    fn set_integer(&mut self, vr: u32, value: i32) -> Result<()> {
        Instance::set_integer(self, vr, value)
    }
    fn get_string(&mut self, vr: u32) -> Result<String> {
        Instance::get_string(self, vr)
    }
    fn set_string(&mut self, vr: u32, value: &str) -> Result<()> {
        Instance::set_string(self, vr, value)
    }
    fn do_step(&mut self, t: f64, h: f64) -> Result<()> {
        Instance::do_step(self, t, h)
    }
    fn save(&self) -> Saved {
        Box::new(self.snapshot())
    }
    fn load(&mut self, state: &Saved) -> Result<()> {
        self.restore(saved::<Snapshot>(state)?)
    }
    fn serialize(&self, state: &Saved) -> Result<Vec<u8>> {
        Ok(saved::<Snapshot>(state)?.to_bytes())
    }
    fn deserialize(&self, bytes: &[u8]) -> Result<Saved> {
        Ok(Box::new(Snapshot::from_bytes(bytes)?))
    }
}

/// The stop time the host defined (s), checked when it is set: finite, and not before the
/// start time `start` (s).
pub(crate) fn stop_time(start: f64, stop: Option<f64>) -> Result<Option<f64>> {
    match stop {
        Some(s) if !s.is_finite() || s < start => Err(Error::Request(format!(
            "stop time {s} s: must be finite and not before the start time {start} s"
        ))),
        _ => Ok(stop),
    }
}

/// FMI 2.0 (section 4.2.2) and 3.0: when the host defined a stop time `stop` (s), a step that
/// would compute past it is an error. A communication step from `t` by `h` (s) may end past
/// `stop` by a relative `1e-9` of the larger of the two, the tolerance importers compare
/// times with (fmpy's `math.isclose`): a grid ending at `0.0038000000000000004` for a stop
/// time of 3.8e-3 s passes.
pub(crate) fn within_stop(stop: Option<f64>, t: f64, h: f64) -> Result<()> {
    match stop {
        Some(stop) if t + h > stop + 1e-9 * stop.abs().max(h) => Err(Error::Request(format!(
            "a step from {t:e} s by {h:e} s would pass the stop time {stop:e} s the host set up"
        ))),
        _ => Ok(()),
    }
}
