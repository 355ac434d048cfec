//! The one error type of the solver crate.

use thiserror::Error;

/// Everything that can go wrong while reading a scene, setting up or running a simulation.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// The scene text is not valid TOML, has a missing, unknown or mistyped key.
    #[error("{file}: {message}")]
    SceneSyntax { file: String, message: String },
    /// A key is present and well typed but its value is not physical or not consistent.
    #[error("{file}:{line}: `{key}`: {message}")]
    SceneValue {
        file: String,
        line: usize,
        key: String,
        message: String,
    },
    /// A dotted-key override (`tools.top.friction`) that cannot be applied, or that gives
    /// an invalid scene.
    #[error("override `{key}`: {message}")]
    Override { key: String, message: String },
    /// The particle layout does not support a well-posed RK approximation.
    #[error("shape functions: {0}")]
    ShapeFunctions(String),
    /// The state became non-finite or left the physically admissible range.
    #[error("step {step} (t = {time:.6e} s): {what}")]
    Diverged { step: u64, time: f64, what: String },
    /// The energy balance error exceeded the scene's bound.
    #[error("step {step} (t = {time:.6e} s): energy balance error {error_rel:.3e} of the reference energy exceeds the bound {bound:.3e} ({detail})")]
    EnergyBalance {
        step: u64,
        time: f64,
        error_rel: f64,
        bound: f64,
        detail: String,
    },
    /// Inertia stopped being negligible in a run that assumes it (mass scaling).
    #[error("step {step} (t = {time:.6e} s): kinetic energy {ratio:.3e} of the internal energy exceeds checks.kinetic_to_internal_max = {bound:.3e} ({detail})")]
    QuasiStatic {
        step: u64,
        time: f64,
        ratio: f64,
        bound: f64,
        detail: String,
    },
    /// A particle went deeper into a tool, beyond a symmetry plane or into the workpiece's
    /// own other part than the scene's bound: the contact lets material through. `into`
    /// names where ("inside tool `die`", "beyond the symmetry plane `y_min` (y = 0 m)").
    #[error("step {step} (t = {time:.6e} s): particle {particle} (reference position {reference:?} m) lies {depth:.3e} m ({depth_rel:.3e} spacings) {into}, deeper than checks.max_penetration_rel = {bound}")]
    Penetration {
        step: u64,
        time: f64,
        particle: usize,
        reference: [f64; 2],
        into: String,
        depth: f64,
        depth_rel: f64,
        bound: f64,
    },
    /// The time step is above the stable step.
    #[error("step {step} (t = {time:.6e} s): time step {dt:.3e} s exceeds the stable step {dt_crit:.3e} s ({detail})")]
    Unstable {
        step: u64,
        time: f64,
        dt: f64,
        dt_crit: f64,
        detail: String,
    },
    /// A request from a wrapper (FMU, ROS node) that the simulation cannot honour.
    #[error("{0}")]
    Request(String),
    /// A run that needs more memory than the process can have ([`crate::memory`]), refused
    /// before its tables are allocated.
    #[error("{0}")]
    Memory(String),
    /// A saved state that cannot be restored.
    #[error("state: {0}")]
    State(String),
}

/// Result alias of the solver crate.
pub type Result<T> = std::result::Result<T, Error>;
