//! Temperature and heat: the `[thermal]` section of a scene with its validation
//! (`settings.rs`) and the properties over temperature it gives, heat capacity and
//! enthalpy, elasticity and thermal stretch (`properties.rs`). The solver's heat stages
//! read them (`solver/heat.rs`, `solver/conduction.rs`).

pub mod properties;
pub mod settings;

pub use properties::HeatCapacity;
pub use settings::ThermalSpec;
