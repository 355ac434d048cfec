//! The explicit RKPM solver (total Lagrangian, Lagrangian kernel unless the scene
//! re-references it, `rereference.rs`): a [`Simulation`] of one scene, set up once in the
//! reference configuration and advanced step by step.
//!
//! Setup ([`Simulation::new`], `setup.rs`): particle lattice and planar volumes;
//! integration points of the chosen rule and their RK shape functions ([`crate::integration`],
//! [`crate::rk_shape`]); the point groups, shared shape-function blocks and chunk buffers
//! (`layout.rs`); row-sum lumped masses `m_I = sum_p rho N_I(X_p) w_p` (kg); essential
//! conditions ([`crate::constraints`]); the critical step (`critical_step.rs`).
//!
//! One step `n -> n+1` of the central-difference scheme (Belytschko, Liu, Moran 2000,
//! Box 6.1) with the paper's predictor-corrector contact (section II-3), as
//! [`Simulation::step`] calls the stages:
//! 0. when the scene sets `discretization.rereference_stretch` and the last stress stage
//!    reached it, the kernel re-reference (`rereference.rs`); then a tool commanded too far
//!    for the step stops the run (`stable_step.rs`);
//! 1. stress (`stress.rs`): `F = I + sum_I d_I (x) grad N_I` at each point (plus
//!    `F_33 = 1 + u_r / R` in axisymmetry), Hencky J2 update, first Piola-Kirchhoff stress
//!    `P`, fused with the scatter of `w_p (P grad N_I + e_r P_33 N_I / R)` into chunk
//!    buffers; with scni and `discretization.scni_stabilization`, the stabilization's
//!    force on the quadrants of the nodal domains (`nodal_stabilization.rs`);
//! 2. time step (`stable_step.rs`): fixed, or `dt_safety * dt_crit`, with
//!    `dt_crit = dt_crit0 h_min / h_min0` from the smallest altitude of the deformed cells;
//! 3. force gather and predictor (`update.rs`): `f_I` summed in a fixed order,
//!    `v* = v_{n-1/2} - dt_avg f_int / m`;
//! 4. contact (`contact_stage.rs` over [`crate::contact`]): the tools advance;
//!    penetration of the predicted boundary particles at `t_{n+1}`, paper eqs. 4-7 (on a
//!    step shortened to land on a requested time, positions and tools a natural step
//!    ahead); the laps grow;
//! 5. corrector (`update.rs`): `v_{n+1/2} = v* + dt_avg f_c / m`, then the projection onto the
//!    essential conditions, and the friction the corrector did not realise carried to the
//!    next step ([`crate::contact::Contact::carry`]);
//! 6. update (`update.rs`): `d_{n+1} = d_n + dt v_{n+1/2}` with the step's energy sums;
//! 7. energy account (`energy.rs`) and clock (`state.rs`);
//! 8. checks: penetration (`penetration.rs`), die fill (`fill.rs`), energy balance, the
//!    quasi-static watch (`quasi_static.rs`);
//! 9. the heat stage when due (`conduction.rs`).
//!
//! A [`Simulation`] (`simulation.rs`) holds its parts apart: the `Discretization` setup
//! fixes (`discretization.rs`: particles, points, shape functions, masses, boundary,
//! planes, critical step, heat settings), the tools, the [`State`] a snapshot saves
//! (`state.rs`) and the stages' `Workspace` (`workspace.rs`). Each stage is a free function
//! over the parts it reads and writes, in the file named above; `step` is the list of their
//! calls. The parallel phases (1; on large models also 3, the contact interpolation and 6)
//! run on a [`crate::team::Team`] over fixed chunks, so the bits do not depend on the
//! number of threads. What the outputs read is in `fields.rs`, `tool_readings.rs` and
//! `heat_readings.rs`.

mod conduction;
mod contact_stage;
mod critical_step;
pub mod detachment;
mod discretization;
mod energy;
#[cfg(test)]
mod feedback_tests;
mod fields;
mod fill;
mod heat;
mod heat_readings;
mod layout;
mod mass_scaling;
mod nodal_stabilization;
mod outline;
mod penetration;
mod point_outputs;
mod quasi_static;
mod rereference;
mod setup;
mod simulation;
pub mod solid;
mod stable_step;
mod state;
mod stress;
#[cfg(test)]
mod tests;
mod tool_readings;
mod update;
mod workspace;

pub(crate) use critical_step::largest_eigenvalue;
pub use discretization::MassScalingReport;
pub use energy::Energy;
pub use fields::Fields;
pub use heat::{Heat, Temperatures};
pub use penetration::{Depths, Penetrated, Within};
pub use quasi_static::QUASI_STATIC_WARNING;
pub use simulation::{Ran, Simulation, StageTimes};
pub use solid::{BodyReadings, DiePressure, Pressed, SolidSimulation, SolidState};
pub use state::{Filled, Reference, State};
pub use tool_readings::FillPoint;
