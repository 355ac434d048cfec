//! The ROS 2 node of an rkforge scene over DDS (`ros2-client`, pure Rust); the messages,
//! frames, topics and the MCAP recorder are the `rkforge-messages` crate's, re-exported here.
//!
//! - `dds` (feature `dds`, on by default): the ROS 2 node over DDS;
//! - `params` (feature `dds`): the node's run-time settings as ROS 2 parameters;
//! - `control` (feature `dds`): the `simulation_interfaces` services (reset, step, pause);
//! - `action` (feature `dds`): the `simulation_interfaces` action `SimulateSteps`;
//! - `service` (feature `dds`): service servers in the `rmw_cyclonedds_cpp` mapping.

#[cfg(feature = "dds")]
pub mod action;
#[cfg(feature = "dds")]
pub mod control;
#[cfg(feature = "dds")]
pub mod dds;
#[cfg(feature = "dds")]
pub mod params;
#[cfg(feature = "dds")]
pub mod service;

pub use rkforge_messages::{
    frame, msgs, record, signals, topics, validate_namespace, PublishedScene, Topic,
};
