//! rkforge-core: a 2D Reproducing Kernel Particle Method solver for metal forming and
//! impact, after Sidibe, Li, Ouane, Bokar (2009), "Numerical simulation of mechanical
//! contact problems using the RKPM with lower integration scheme".
//!
//! Stages, each in its own module and named after its method: RK shape functions
//! ([`rk_shape`], [`kernel`]), background-cell integration ([`integration`]), Hencky J2
//! plasticity ([`material`]), penalty contact ([`tools`]), essential conditions
//! ([`constraints`]), and the explicit solver that calls them in order ([`solver`]).
//! Scenes ([`scene`]) decide what is modelled.

pub mod constraints;
pub mod error;
pub mod integration;
pub mod kernel;
pub mod material;
pub mod math;
pub mod rk_shape;
pub mod scene;
pub mod solver;
pub mod tools;

pub use error::{Error, Result};
pub use scene::{IntegrationRule, Kinematics, Scene};
pub use solver::{Energy, Extents, Fields, Simulation, StageTimes, State};
