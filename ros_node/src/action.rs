//! The `simulation_interfaces` action `SimulateSteps` of the node, `NS/simulate_steps`: the
//! services `_action/send_goal`, `_action/get_result` and `_action/cancel_goal` in the
//! request/reply mapping of `rmw_cyclonedds_cpp`, and the topics `_action/feedback` and
//! `_action/status`, with rosidl's DDS type names
//! (`simulation_interfaces::action::dds_::SimulateSteps_SendGoal_Request_`,
//! `action_msgs::srv::dds_::CancelGoal_Request_`, ...). The goal, result and feedback are
//! generated from the standard `.action` file ([`crate::msgs`]); the envelopes around them
//! (goal id, status, cancel) are ros2-client's `action_msgs`.
//!
//! This module keeps the goals' states and answers the clients as `rcl_action` does; the
//! node's main loop decides and steps. Every goal is accepted, then carried out or aborted
//! with a `simulation_interfaces/msg/Result` that says why (as `StepSimulation` answers), one
//! goal at a time in the order received; a goal that arrives while another executes is
//! aborted. A canceled goal stops after the step under way.

use crate::msgs::{ResultMsg, SimulateStepsFeedback, SimulateStepsGoal, SimulateStepsResult};
use crate::service::{reply_topic, Outbox, ReplyReaders};
use ros2_client::action::{ActionServerQosPolicies, GetResultResponse, SendGoalResponse};
use ros2_client::action_msgs::{
    CancelGoalRequest, CancelGoalResponse, CancelGoalResponseEnum, GoalInfo, GoalStatus,
    GoalStatusArray,
};
pub use ros2_client::action_msgs::{GoalId, GoalStatusEnum};
use ros2_client::builtin_interfaces::Time;
use ros2_client::dds::{ActionServer, Node, ServiceMapping};
use ros2_client::service::RmwRequestId;
use ros2_client::{ActionTypeName, Name, QosProfile};
use serde::Deserialize;
use std::sync::Arc;
use std::time::Instant;

/// Finished goals kept for result and cancel requests that come later (the oldest are
/// forgotten first; a result request for a forgotten goal is answered `STATUS_UNKNOWN`).
const FINISHED_KEPT: usize = 32;

/// A goal accepted.
struct Goal {
    /// Its id and when it was accepted (wall time, as rclcpp stamps it by default).
    info: GoalInfo,
    status: GoalStatusEnum,
    /// The result, once the goal has ended.
    result: Option<SimulateStepsResult>,
}

/// The `SimulateSteps` action server and its goals.
pub struct StepsAction {
    server: ActionServer<SimulateStepsGoal, SimulateStepsResult, SimulateStepsFeedback>,
    /// In the order accepted.
    goals: Vec<Goal>,
    /// Result requests waiting for their goal to end.
    waiting: Vec<(RmwRequestId, GoalId)>,
    /// Replies waiting for their client's reply reader (see [`crate::service`]).
    goal_replies: Outbox<SendGoalResponse>,
    result_replies: Outbox<GetResultResponse<SimulateStepsResult>>,
    cancel_replies: Outbox<CancelGoalResponse>,
    readers: Arc<ReplyReaders>,
}

impl StepsAction {
    /// Serve the action `ns/simulate_steps` with QoS `services` for its three services,
    /// `feedback` for the feedback topic and `status` for the status topic; replies wait for
    /// the clients' reply readers in `readers`.
    ///
    /// # Errors
    ///
    /// A bad namespace, or DDS could not create the services or topics.
    pub fn new(
        node: &mut Node,
        readers: &Arc<ReplyReaders>,
        ns: &str,
        services: &QosProfile,
        feedback: &QosProfile,
        status: &QosProfile,
    ) -> Result<StepsAction, String> {
        let name = Name::new(ns, "simulate_steps")
            .map_err(|e| format!("action {ns}/simulate_steps: {e:?}"))?;
        let qos = ActionServerQosPolicies {
            goal_service: services.clone(),
            result_service: services.clone(),
            cancel_service: services.clone(),
            feedback_publisher: feedback.clone(),
            status_publisher: status.clone(),
        };
        let server = node
            .create_action_server(
                ServiceMapping::Cyclone,
                &name,
                &ActionTypeName::new("simulation_interfaces", "SimulateSteps"),
                qos,
            )
            .map_err(|e| format!("cannot serve the action {ns}/simulate_steps: {e:?}"))?;
        let topic = |service: &str| reply_topic(node, &name, &format!("/_action/{service}"));
        Ok(StepsAction {
            goal_replies: Outbox::new(&topic("send_goal")?),
            result_replies: Outbox::new(&topic("get_result")?),
            cancel_replies: Outbox::new(&topic("cancel_goal")?),
            server,
            goals: Vec::new(),
            waiting: Vec::new(),
            readers: Arc::clone(readers),
        })
    }

    /// Accept every new goal, answer result and cancel requests: the goals accepted since the
    /// last call, oldest first, with the steps each asks for. A goal id already known is
    /// refused (`accepted: false`).
    pub fn poll(&mut self) -> Vec<(GoalId, u64)> {
        self.flush();
        let mut accepted = Vec::new();
        while let Some((request, r)) = self.goal_replies.received(self.server.receive_goal()) {
            let stamp = Time::now();
            let new = self.find(r.goal_id).is_none();
            if new {
                self.goals.push(Goal {
                    info: GoalInfo {
                        goal_id: r.goal_id,
                        stamp,
                    },
                    status: GoalStatusEnum::Accepted,
                    result: None,
                });
                accepted.push((r.goal_id, r.goal.steps));
            }
            self.goal_replies.push(
                request,
                SendGoalResponse {
                    accepted: new,
                    stamp,
                },
                Instant::now(),
            );
        }
        if !accepted.is_empty() {
            self.publish_status();
        }
        while let Some((request, r)) = self
            .result_replies
            .received(self.server.receive_result_request())
        {
            match self.find(r.goal_id).map(|g| (g.status, g.result.clone())) {
                Some((status, Some(result))) => self.result_replies.push(
                    request,
                    GetResultResponse { status, result },
                    Instant::now(),
                ),
                Some((_, None)) => self.waiting.push((request, r.goal_id)),
                None => self.result_replies.push(
                    request,
                    GetResultResponse {
                        status: GoalStatusEnum::Unknown,
                        result: SimulateStepsResult::default(),
                    },
                    Instant::now(),
                ),
            }
        }
        while let Some((request, r)) = self
            .cancel_replies
            .received(self.server.receive_cancel_request())
        {
            let response = self.cancel(&r);
            self.cancel_replies.push(request, response, Instant::now());
        }
        self.flush();
        accepted
    }

    /// Write the replies held whose clients can now receive them (see
    /// [`crate::service`]); true if replies still wait.
    pub fn flush(&mut self) -> bool {
        for (id, r) in self.goal_replies.ready(&self.readers) {
            self.goal_replies
                .written(self.server.send_goal_response(id, r));
        }
        for (id, r) in self.result_replies.ready(&self.readers) {
            self.result_replies.written(self.server.send_result(id, r));
        }
        for (id, r) in self.cancel_replies.ready(&self.readers) {
            self.cancel_replies
                .written(self.server.send_cancel_response(id, r));
        }
        !(self.goal_replies.is_empty()
            && self.result_replies.is_empty()
            && self.cancel_replies.is_empty())
    }

    /// Mark the goals that `request` names as canceling, with rcl_action's policy: a zero
    /// id and a zero stamp name every goal; an id names that goal; a stamp names the goals
    /// accepted at or before it. Only accepted and executing goals can be canceled.
    fn cancel(&mut self, request: &CancelGoalRequest) -> CancelGoalResponse {
        let reply = |code, goals_canceling| CancelGoalResponse {
            return_code: code,
            goals_canceling,
        };
        let Some(target) = cancel_target(request) else {
            return reply(CancelGoalResponseEnum::Rejected, Vec::new());
        };
        let zero_id = target.goal_id == GoalId::ZERO;
        let zero_stamp = target.stamp == Time::ZERO;
        let mut canceling = Vec::new();
        for g in &mut self.goals {
            let cancelable = matches!(
                g.status,
                GoalStatusEnum::Accepted | GoalStatusEnum::Executing
            );
            let named = g.info.goal_id == target.goal_id
                || (zero_id && zero_stamp)
                || (!zero_stamp && g.info.stamp <= target.stamp);
            if cancelable && named {
                g.status = GoalStatusEnum::Canceling;
                canceling.push(g.info.clone());
            }
        }
        if !canceling.is_empty() {
            self.publish_status();
            reply(CancelGoalResponseEnum::None, canceling)
        } else if zero_id {
            reply(CancelGoalResponseEnum::Rejected, canceling)
        } else if self.find(target.goal_id).is_some() {
            reply(CancelGoalResponseEnum::GoalTerminated, canceling)
        } else {
            reply(CancelGoalResponseEnum::UnknownGoal, canceling)
        }
    }

    /// Whether goal `id` has been asked to cancel.
    #[must_use]
    pub fn canceling(&self, id: GoalId) -> bool {
        self.find(id)
            .is_some_and(|g| g.status == GoalStatusEnum::Canceling)
    }

    /// Goal `id` starts executing.
    pub fn execute(&mut self, id: GoalId) {
        if let Some(g) = self.goals.iter_mut().find(|g| g.info.goal_id == id) {
            g.status = GoalStatusEnum::Executing;
        }
        self.publish_status();
    }

    /// Publish the feedback of goal `id`: steps completed and remaining.
    pub fn feedback(&self, id: GoalId, completed_steps: u64, remaining_steps: u64) {
        let _ = self.server.send_feedback(
            id,
            SimulateStepsFeedback {
                completed_steps,
                remaining_steps,
            },
        );
    }

    /// End goal `id` with `status` (succeeded, canceled or aborted) and `result`: answer the
    /// result requests waiting for it and publish the goals' statuses.
    pub fn finish(&mut self, id: GoalId, status: GoalStatusEnum, result: ResultMsg) {
        let result = SimulateStepsResult { result };
        if let Some(g) = self.goals.iter_mut().find(|g| g.info.goal_id == id) {
            g.status = status;
            g.result = Some(result.clone());
        }
        let (answer, wait) = std::mem::take(&mut self.waiting)
            .into_iter()
            .partition(|(_, goal)| *goal == id);
        self.waiting = wait;
        for (request, _) in answer {
            self.result_replies.push(
                request,
                GetResultResponse {
                    status,
                    result: result.clone(),
                },
                Instant::now(),
            );
        }
        self.flush();
        while self.goals.iter().filter(|g| g.result.is_some()).count() > FINISHED_KEPT {
            if let Some(k) = self.goals.iter().position(|g| g.result.is_some()) {
                self.goals.remove(k);
            }
        }
        self.publish_status();
    }

    fn find(&self, id: GoalId) -> Option<&Goal> {
        self.goals.iter().find(|g| g.info.goal_id == id)
    }

    /// The status of every goal kept, on the latched status topic.
    fn publish_status(&self) {
        let status_list = self
            .goals
            .iter()
            .map(|g| GoalStatus {
                goal_info: g.info.clone(),
                status: g.status,
            })
            .collect();
        let _ = self
            .server
            .send_goal_statuses(GoalStatusArray { status_list });
    }
}

/// The goal id and stamp a cancel request names. ros2-client keeps the request's
/// `goal_info` private; its serde form is public, so it is read back through that.
fn cancel_target(request: &CancelGoalRequest) -> Option<GoalInfo> {
    #[derive(Deserialize)]
    struct Request {
        goal_info: GoalInfo,
    }
    serde_json::to_value(request)
        .and_then(serde_json::from_value::<Request>)
        .ok()
        .map(|r| r.goal_info)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The serde form of a cancel request gives back its goal id and stamp.
    #[test]
    fn a_cancel_request_names_its_goal() {
        let info = GoalInfo {
            goal_id: GoalId::new_random(),
            stamp: Time::new(12, 345),
        };
        // Built the way it arrives: deserialized from its fields.
        let request: CancelGoalRequest = serde_json::from_value(
            serde_json::json!({ "goal_info": serde_json::to_value(&info).unwrap() }),
        )
        .unwrap();
        let target = cancel_target(&request).unwrap();
        assert_eq!(target.goal_id, info.goal_id);
        assert_eq!(target.stamp, info.stamp);
    }
}
