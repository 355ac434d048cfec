//! The node's run-time settings as ROS 2 parameters, served with the standard
//! `rcl_interfaces` services (`list_parameters`, `get_parameters`, `set_parameters`,
//! `describe_parameters` under the node's name) in the request/reply mapping of
//! `rmw_cyclonedds_cpp` (`ros2-client`'s [`ServiceMapping::Cyclone`]):
//!
//! - `real_time_factor` (double, >= 0): simulated seconds per wall second; 0 runs as fast as
//!   possible;
//! - `lockstep` (bool): wait at every sample for a command per movable tool;
//! - `publish_rate` (double, read only): samples per second of simulation time, fixed at
//!   start because the sample schedule is.
//!
//! A refused value is answered with `successful = false` and the reason.

use crate::service::{server, ReplyReaders, Service};
use ros2_client::dds::Node;
use ros2_client::parameters::raw::{
    FloatingPointRange, Parameter, ParameterDescriptor, ParameterType, ParameterValue,
    SetParametersResult,
};
use ros2_client::rcl_interfaces::{
    DescribeParametersRequest, DescribeParametersResponse, GetParametersRequest,
    GetParametersResponse, ListParametersRequest, ListParametersResponse, ListParametersResult,
    SetParametersRequest, SetParametersResponse,
};
use ros2_client::QosProfile;
use std::sync::Arc;

/// The settings that parameters change while the node runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Simulated seconds per wall second; `None` runs as fast as possible.
    pub real_time_factor: Option<f64>,
    /// Wait at every sample for a command per movable tool.
    pub lockstep: bool,
    /// Samples per second of simulation time (read only).
    pub publish_rate: f64,
}

/// Parameter names, in the order `list_parameters` gives them.
const NAMES: [&str; 3] = ["lockstep", "publish_rate", "real_time_factor"];

/// The four parameter services of the node.
pub struct Parameters {
    list: Service<ListParametersRequest, ListParametersResponse>,
    get: Service<GetParametersRequest, GetParametersResponse>,
    set: Service<SetParametersRequest, SetParametersResponse>,
    describe: Service<DescribeParametersRequest, DescribeParametersResponse>,
}

impl Parameters {
    /// Serve the parameter services of node `node_name` in namespace `ns` (topics
    /// `rq/<ns>/<node_name>/<service>Request` and `rr/...Reply`) with QoS `qos` for requests
    /// and replies; replies wait for the clients' reply readers in `readers`.
    ///
    /// # Errors
    ///
    /// DDS could not create a service.
    pub fn new(
        node: &mut Node,
        readers: &Arc<ReplyReaders>,
        ns: &str,
        node_name: &str,
        qos: &QosProfile,
    ) -> Result<Parameters, String> {
        let base = format!("{}/{node_name}", ns.trim_end_matches('/'));
        Ok(Parameters {
            list: server(
                node,
                readers,
                &base,
                "list_parameters",
                "rcl_interfaces",
                "ListParameters",
                qos,
            )?,
            get: server(
                node,
                readers,
                &base,
                "get_parameters",
                "rcl_interfaces",
                "GetParameters",
                qos,
            )?,
            set: server(
                node,
                readers,
                &base,
                "set_parameters",
                "rcl_interfaces",
                "SetParameters",
                qos,
            )?,
            describe: server(
                node,
                readers,
                &base,
                "describe_parameters",
                "rcl_interfaces",
                "DescribeParameters",
                qos,
            )?,
        })
    }

    /// Write the replies held whose clients can now receive them (see
    /// [`crate::service`]); true if replies still wait.
    pub fn flush(&mut self) -> bool {
        let waiting = [
            self.list.flush(),
            self.get.flush(),
            self.describe.flush(),
            self.set.flush(),
        ];
        waiting.contains(&true)
    }

    /// Answer every pending request; set requests change `settings`. True if a setting
    /// changed.
    pub fn serve(&mut self, settings: &mut Settings) -> bool {
        self.flush();
        let mut changed = false;
        while let Some((id, _)) = self.list.take() {
            let result = ListParametersResult {
                names: NAMES.iter().map(|n| (*n).to_owned()).collect(),
                prefixes: Vec::new(),
            };
            self.list.reply(id, ListParametersResponse { result });
        }
        while let Some((id, req)) = self.get.take() {
            let values = req.names.iter().map(|n| value(settings, n)).collect();
            self.get.reply(id, GetParametersResponse { values });
        }
        while let Some((id, req)) = self.describe.take() {
            let values = req.names.iter().map(|n| describe(n)).collect();
            self.describe
                .reply(id, DescribeParametersResponse { values });
        }
        while let Some((id, req)) = self.set.take() {
            let results = req
                .parameter
                .iter()
                .map(|p| {
                    let r = set(settings, p);
                    changed |= r.is_ok();
                    SetParametersResult {
                        successful: r.is_ok(),
                        reason: r.err().unwrap_or_default(),
                    }
                })
                .collect();
            self.set.reply(id, SetParametersResponse { results });
        }
        changed
    }
}

/// A parameter value of type `ptype`, every other field empty.
fn raw(ptype: u8) -> ParameterValue {
    ParameterValue {
        ptype,
        boolean_value: false,
        int_value: 0,
        double_value: 0.0,
        string_value: String::new(),
        byte_array: Vec::new(),
        bool_array: Vec::new(),
        int_array: Vec::new(),
        double_array: Vec::new(),
        string_array: Vec::new(),
    }
}

/// The value of parameter `name` (type `NOT_SET` if there is no such parameter).
fn value(s: &Settings, name: &str) -> ParameterValue {
    match name {
        "lockstep" => ParameterValue {
            boolean_value: s.lockstep,
            ..raw(ParameterType::BOOL)
        },
        "real_time_factor" => ParameterValue {
            double_value: s.real_time_factor.unwrap_or(0.0),
            ..raw(ParameterType::DOUBLE)
        },
        "publish_rate" => ParameterValue {
            double_value: s.publish_rate,
            ..raw(ParameterType::DOUBLE)
        },
        _ => raw(ParameterType::NOT_SET),
    }
}

/// The descriptor of parameter `name` (type `NOT_SET` if there is no such parameter).
fn describe(name: &str) -> ParameterDescriptor {
    let (ptype, description, read_only, range) = match name {
        "lockstep" => (
            ParameterType::BOOL,
            "wait at every sample until each movable tool has received a command",
            false,
            vec![],
        ),
        "real_time_factor" => (
            ParameterType::DOUBLE,
            "simulated seconds per wall second; 0 runs as fast as possible",
            false,
            vec![FloatingPointRange {
                from_value: 0.0,
                to_value: f64::MAX,
                step: 0.0,
            }],
        ),
        "publish_rate" => (
            ParameterType::DOUBLE,
            "samples per second of simulation time, fixed at start",
            true,
            vec![],
        ),
        _ => (ParameterType::NOT_SET, "", false, vec![]),
    };
    ParameterDescriptor {
        name: name.to_owned(),
        r#type: ptype,
        description: description.to_owned(),
        additional_constraints: String::new(),
        read_only,
        dynamic_typing: false,
        floating_point_range: range,
        integer_range: vec![],
    }
}

/// Apply `p` to `s`, or the reason it is refused.
fn set(s: &mut Settings, p: &Parameter) -> Result<(), String> {
    let v = &p.value;
    match (p.name.as_str(), v.ptype) {
        ("lockstep", ParameterType::BOOL) => {
            s.lockstep = v.boolean_value;
            Ok(())
        }
        ("real_time_factor", ParameterType::DOUBLE) => {
            let r = v.double_value;
            if !(r.is_finite() && r >= 0.0) {
                return Err(format!(
                    "real_time_factor {r}: must be finite and >= 0 (0 = as fast as possible)"
                ));
            }
            s.real_time_factor = (r > 0.0).then_some(r);
            Ok(())
        }
        ("publish_rate", _) => Err(
            "publish_rate is read only: the sample schedule is fixed at start (--publish-rate)"
                .to_owned(),
        ),
        ("lockstep", t) => Err(format!("lockstep is a bool, not of parameter type {t}")),
        ("real_time_factor", t) => Err(format!(
            "real_time_factor is a double, not of parameter type {t}"
        )),
        (name, _) => Err(format!(
            "no parameter `{name}` (parameters: {})",
            NAMES.join(", ")
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> Settings {
        Settings {
            real_time_factor: None,
            lockstep: false,
            publish_rate: 100.0,
        }
    }

    fn param(name: &str, v: ParameterValue) -> Parameter {
        Parameter {
            name: name.to_owned(),
            value: v,
        }
    }

    #[test]
    fn valid_values_change_the_settings() {
        let mut s = settings();
        let rtf = ParameterValue {
            double_value: 0.5,
            ..raw(ParameterType::DOUBLE)
        };
        set(&mut s, &param("real_time_factor", rtf)).unwrap();
        assert_eq!(s.real_time_factor, Some(0.5));
        let zero = raw(ParameterType::DOUBLE);
        set(&mut s, &param("real_time_factor", zero)).unwrap();
        assert_eq!(s.real_time_factor, None);
        let on = ParameterValue {
            boolean_value: true,
            ..raw(ParameterType::BOOL)
        };
        set(&mut s, &param("lockstep", on)).unwrap();
        assert!(s.lockstep);
        assert!(value(&s, "lockstep").boolean_value);
        assert_eq!(value(&s, "publish_rate").double_value, 100.0);
        assert_eq!(value(&s, "nothing").ptype, ParameterType::NOT_SET);
    }

    #[test]
    fn invalid_values_are_refused_with_a_reason() {
        let mut s = settings();
        let negative = ParameterValue {
            double_value: -1.0,
            ..raw(ParameterType::DOUBLE)
        };
        let e = set(&mut s, &param("real_time_factor", negative)).unwrap_err();
        assert!(e.contains("must be finite and >= 0"), "{e}");
        let e = set(&mut s, &param("lockstep", raw(ParameterType::DOUBLE))).unwrap_err();
        assert!(e.contains("lockstep is a bool"), "{e}");
        let e = set(&mut s, &param("publish_rate", raw(ParameterType::DOUBLE))).unwrap_err();
        assert!(e.contains("read only"), "{e}");
        let e = set(&mut s, &param("speed", raw(ParameterType::DOUBLE))).unwrap_err();
        assert!(e.contains("no parameter `speed`"), "{e}");
        assert_eq!(s, settings());
        assert!(describe("publish_rate").read_only);
    }
}
