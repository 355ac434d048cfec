//! Materials: isotropic elasticity and J2 plasticity at finite strain.

pub mod hardening;
pub mod rate_temperature;
pub mod simo1992_hencky_j2;
pub mod simo1992_hencky_j2_3d;

pub use crate::thermal::HeatCapacity;
pub use hardening::Hardening;
pub use rate_temperature::Flow;
pub use simo1992_hencky_j2::{HenckyJ2, PointLanes, PointState, StressLanes, StressUpdate};
pub use simo1992_hencky_j2_3d::{PointLanes3, PointState3, StressLanes3, StressUpdate3};
