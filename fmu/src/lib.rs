//! The rkforge FMU: FMI 2.0 and 3.0 Co-Simulation of any scene.
//!
//! Two layers: [`Instance`] is safe Rust over an explicit FMI state machine over a 2D or a
//! 3D scene, reading and writing variables through the scene's variable table and stepping
//! its simulation on the run layer (`rkforge-runner`, as the command line does); [`ffi`]
//! (FMI 2.0) and [`ffi3`]
//! (FMI 3.0) hold the exported C functions, thin wrappers over the bodies both share
//! (`component`, `values`, `fmu_state`, `logging`, `resources`), every one run in the panic
//! barrier of [`host`], with all `unsafe` pointer handling there.

mod component;
pub mod ffi;
pub mod ffi3;
mod fmu_state;
pub mod host;
mod instance;
mod logging;
pub mod press;
mod resources;
pub mod slave;
mod stepping;
mod values;

pub use slave::{Saved, Slave};
pub use stepping::Observer;

pub use instance::{Instance, Phase, Snapshot};
