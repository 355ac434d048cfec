//! The `simulation_interfaces` services of the node (the ROS 2 standard for simulator
//! control), under its namespace: `get_simulator_features`, `get_simulation_state`,
//! `set_simulation_state`, `reset_simulation` and `step_simulation`, in the request/reply
//! mapping of `rmw_cyclonedds_cpp`. This module answers what needs no simulation and decides
//! the rest ([`transition`], [`check_reset`], [`check_step`]); the node's main loop carries
//! the decisions out.
//!
//! Supported: the state (playing, paused, stopped = reset and paused, quitting), a reset of
//! the whole scene (scopes `SCOPE_DEFAULT`, `SCOPE_ALL`, or time and state together, since
//! the time and the state of a forging are one), and stepping N solver steps while paused,
//! with this service or the `SimulateSteps` action ([`crate::action`]).

use crate::msgs::{
    GetSimulationStateRequest, GetSimulationStateResponse, GetSimulatorFeaturesRequest,
    GetSimulatorFeaturesResponse, ResetSimulationRequest, ResetSimulationResponse, ResultMsg,
    SetSimulationStateRequest, SetSimulationStateResponse, SimulationState, SimulatorFeatures,
    StepSimulationRequest, StepSimulationResponse,
};
use crate::service::{server, ReplyReaders, Service};
use ros2_client::dds::Node;
use ros2_client::service::RmwRequestId;
use ros2_client::QosProfile;
use std::sync::Arc;

/// The features the node supports, as `GetSimulatorFeatures` lists them.
pub const FEATURES: [u16; 7] = [
    SimulatorFeatures::SIMULATION_RESET as u16,
    SimulatorFeatures::SIMULATION_STATE_GETTING as u16,
    SimulatorFeatures::SIMULATION_STATE_SETTING as u16,
    SimulatorFeatures::SIMULATION_STATE_PAUSE as u16,
    SimulatorFeatures::STEP_SIMULATION_SINGLE as u16,
    SimulatorFeatures::STEP_SIMULATION_MULTIPLE as u16,
    SimulatorFeatures::STEP_SIMULATION_ACTION as u16,
];

/// A request that the main loop carries out, then answers with [`Services::answer`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Request {
    /// `SetSimulationState` to this state.
    SetState(RmwRequestId, u8),
    /// `ResetSimulation` with this scope.
    Reset(RmwRequestId, u8),
    /// `StepSimulation` this many steps.
    Step(RmwRequestId, u64),
}

/// What a `SetSimulationState` request asks of the main loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transition {
    /// Run on (playing).
    Play,
    /// Hold the current time (paused).
    Pause,
    /// Reset the scene and hold it (stopped).
    Stop,
    /// End the node.
    Quit,
}

/// The five servers.
pub struct Services {
    features: Service<GetSimulatorFeaturesRequest, GetSimulatorFeaturesResponse>,
    get_state: Service<GetSimulationStateRequest, GetSimulationStateResponse>,
    set_state: Service<SetSimulationStateRequest, SetSimulationStateResponse>,
    reset: Service<ResetSimulationRequest, ResetSimulationResponse>,
    step: Service<StepSimulationRequest, StepSimulationResponse>,
}

/// A `simulation_interfaces/msg/Result`.
#[must_use]
pub fn result(code: u8, message: &str) -> ResultMsg {
    ResultMsg {
        result: code,
        error_message: message.to_owned(),
    }
}

/// The result of a request carried out.
fn ok() -> ResultMsg {
    result(ResultMsg::RESULT_OK, "")
}

impl Services {
    /// Serve the five services under namespace `ns` with QoS `qos` for requests and replies;
    /// replies wait for the clients' reply readers in `readers`.
    ///
    /// # Errors
    ///
    /// DDS could not create a service.
    pub fn new(
        node: &mut Node,
        readers: &Arc<ReplyReaders>,
        ns: &str,
        qos: &QosProfile,
    ) -> Result<Services, String> {
        let p = "simulation_interfaces";
        Ok(Services {
            features: server(
                node,
                readers,
                ns,
                "get_simulator_features",
                p,
                "GetSimulatorFeatures",
                qos,
            )?,
            get_state: server(
                node,
                readers,
                ns,
                "get_simulation_state",
                p,
                "GetSimulationState",
                qos,
            )?,
            set_state: server(
                node,
                readers,
                ns,
                "set_simulation_state",
                p,
                "SetSimulationState",
                qos,
            )?,
            reset: server(
                node,
                readers,
                ns,
                "reset_simulation",
                p,
                "ResetSimulation",
                qos,
            )?,
            step: server(
                node,
                readers,
                ns,
                "step_simulation",
                p,
                "StepSimulation",
                qos,
            )?,
        })
    }

    /// Answer the feature and state queries (the simulation is in `state`) and return the
    /// other requests received, for the main loop.
    pub fn poll(&mut self, state: u8) -> Vec<Request> {
        self.flush();
        while let Some((id, _)) = self.features.take() {
            let features = SimulatorFeatures {
                features: FEATURES.to_vec(),
                spawn_formats: Vec::new(),
                custom_info: format!(
                    "rkforge {}: reset restores the scene's initial state bit for bit; a step is one explicit solver step (the last step before a sample time is shortened to land on it); SimulateSteps runs one goal at a time and can be canceled",
                    env!("CARGO_PKG_VERSION")
                ),
            };
            self.features
                .reply(id, GetSimulatorFeaturesResponse { features });
        }
        while let Some((id, _)) = self.get_state.take() {
            let response = GetSimulationStateResponse {
                state: SimulationState { state },
                result: ok(),
            };
            self.get_state.reply(id, response);
        }
        let mut out = Vec::new();
        while let Some((id, r)) = self.set_state.take() {
            out.push(Request::SetState(id, r.state.state));
        }
        while let Some((id, r)) = self.reset.take() {
            out.push(Request::Reset(id, r.scope));
        }
        while let Some((id, r)) = self.step.take() {
            out.push(Request::Step(id, r.steps));
        }
        out
    }

    /// Write the replies held whose clients can now receive them (see
    /// [`crate::service`]); true if replies still wait.
    pub fn flush(&mut self) -> bool {
        let waiting = [
            self.features.flush(),
            self.get_state.flush(),
            self.set_state.flush(),
            self.reset.flush(),
            self.step.flush(),
        ];
        waiting.contains(&true)
    }

    /// Answer `request` with `result`.
    pub fn answer(&mut self, request: Request, result: ResultMsg) {
        match request {
            Request::SetState(id, _) => self
                .set_state
                .reply(id, SetSimulationStateResponse { result }),
            Request::Reset(id, _) => self.reset.reply(id, ResetSimulationResponse { result }),
            Request::Step(id, _) => self.step.reply(id, StepSimulationResponse { result }),
        }
    }
}

/// What `SetSimulationState` to `target` asks in state `current` (`at_end`: the run has
/// reached its end time), or the result that refuses it.
///
/// # Errors
///
/// `ALREADY_IN_TARGET_STATE`, `STATE_TRANSITION_ERROR` (playing at the end time),
/// `RESULT_FEATURE_UNSUPPORTED` (no world or loading one) or `RESULT_OPERATION_FAILED` (not
/// a state).
pub fn transition(current: u8, target: u8, at_end: bool) -> Result<Transition, ResultMsg> {
    if target == current {
        return Err(result(
            SetSimulationStateResponse::ALREADY_IN_TARGET_STATE,
            "the simulation is already in that state",
        ));
    }
    match target {
        SimulationState::STATE_PLAYING if at_end => Err(result(
            SetSimulationStateResponse::STATE_TRANSITION_ERROR,
            "the run is at its end time: reset it (or stop it) before playing",
        )),
        SimulationState::STATE_PLAYING => Ok(Transition::Play),
        SimulationState::STATE_PAUSED => Ok(Transition::Pause),
        SimulationState::STATE_STOPPED => Ok(Transition::Stop),
        SimulationState::STATE_QUITTING => Ok(Transition::Quit),
        SimulationState::STATE_NO_WORLD | SimulationState::STATE_LOADING_WORLD => Err(result(
            ResultMsg::RESULT_FEATURE_UNSUPPORTED,
            "the node runs one scene; worlds cannot be unloaded or loaded",
        )),
        other => Err(result(
            ResultMsg::RESULT_OPERATION_FAILED,
            &format!("unknown simulation state {other}"),
        )),
    }
}

/// Whether `ResetSimulation` with `scope` is supported.
///
/// # Errors
///
/// `RESULT_FEATURE_UNSUPPORTED` for a scope that resets the time without the state or the
/// state without the time.
pub fn check_reset(scope: u8) -> Result<(), ResultMsg> {
    let both = ResetSimulationRequest::SCOPE_TIME | ResetSimulationRequest::SCOPE_STATE;
    if scope == ResetSimulationRequest::SCOPE_DEFAULT || scope & both == both {
        Ok(())
    } else {
        Err(result(
            ResultMsg::RESULT_FEATURE_UNSUPPORTED,
            &format!(
                "reset scope {scope}: only the whole scene resets (SCOPE_DEFAULT, SCOPE_ALL, or SCOPE_TIME | SCOPE_STATE)"
            ),
        ))
    }
}

/// Whether `interface` (`StepSimulation` or `SimulateSteps`) can take `steps` steps in
/// `state` (`at_end`: the run has reached its end time).
///
/// # Errors
///
/// `RESULT_OPERATION_FAILED`: not paused, no steps, or at the end time.
pub fn check_step(interface: &str, state: u8, steps: u64, at_end: bool) -> Result<(), ResultMsg> {
    let fail = |m: &str| Err(result(ResultMsg::RESULT_OPERATION_FAILED, m));
    if state != SimulationState::STATE_PAUSED {
        return fail(&format!("{interface} needs the simulation paused"));
    }
    if steps == 0 {
        return fail(&format!("{interface} needs at least one step"));
    }
    if at_end {
        return fail("the run is at its end time: reset it before stepping");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const PLAYING: u8 = SimulationState::STATE_PLAYING;
    const PAUSED: u8 = SimulationState::STATE_PAUSED;
    const STOPPED: u8 = SimulationState::STATE_STOPPED;

    #[test]
    fn transitions_follow_simulation_interfaces() {
        assert_eq!(transition(PLAYING, PAUSED, false), Ok(Transition::Pause));
        assert_eq!(transition(PAUSED, PLAYING, false), Ok(Transition::Play));
        assert_eq!(transition(STOPPED, PAUSED, false), Ok(Transition::Pause));
        assert_eq!(transition(PAUSED, STOPPED, true), Ok(Transition::Stop));
        assert_eq!(transition(PLAYING, 3, false), Ok(Transition::Quit));
        let code = |r: Result<Transition, ResultMsg>| r.unwrap_err().result;
        assert_eq!(code(transition(PAUSED, PAUSED, false)), 101);
        assert_eq!(code(transition(PAUSED, PLAYING, true)), 102);
        assert_eq!(code(transition(PAUSED, 4, false)), 0);
        assert_eq!(code(transition(PAUSED, 9, false)), 4);
    }

    #[test]
    fn only_whole_resets_and_paused_steps() {
        for scope in [0, 3, 7, 255] {
            assert_eq!(check_reset(scope), Ok(()), "{scope}");
        }
        for scope in [1, 2, 4] {
            assert_eq!(check_reset(scope).unwrap_err().result, 0, "{scope}");
        }
        assert_eq!(check_step("StepSimulation", PAUSED, 5, false), Ok(()));
        for (state, steps, at_end) in [(PLAYING, 5, false), (PAUSED, 0, false), (PAUSED, 1, true)] {
            let refused = check_step("SimulateSteps", state, steps, at_end).unwrap_err();
            assert_eq!(refused.result, 4);
        }
        let refused = check_step("SimulateSteps", PLAYING, 5, false).unwrap_err();
        assert_eq!(
            refused.error_message,
            "SimulateSteps needs the simulation paused"
        );
    }
}
