//! rkforge-core: a 2D Reproducing Kernel Particle Method solver for metal forming and
//! impact, after Sidibe, Li, Ouane, Bokar (2009), "Numerical simulation of mechanical
//! contact problems using the RKPM with lower integration scheme".
//!
//! Stages, each in its own module and named after its method: RK shape functions
//! ([`rk_shape`], [`kernel`]), background-cell integration ([`integration`]), Hencky J2
//! plasticity ([`material`]), rigid tools and the penalty contact laws ([`tools`]) applied
//! by the contact stage ([`contact`]), essential conditions ([`constraints`]), and the
//! explicit solver that calls them in order ([`solver`], one file per stage). Scenes
//! ([`scene`]) decide what is modelled; [`geometry`] and [`sampling`] serve the solver and
//! every front end. Nothing below the solver imports it. Above it, [`outputs`] is the
//! register of every figure a run reports, which every front end reads.

pub mod constraints;
pub mod contact;
pub mod cylinder_grid;
pub mod error;
pub mod friction;
pub mod geometry;
pub mod integration;
pub mod kernel;
pub mod lanes;
pub mod laps;
pub mod material;
pub mod math;
pub mod memory;
pub mod outputs;
pub mod rk_shape;
pub mod sampling;
pub mod scene;
pub mod scene_keys;
pub mod scene_overrides;
pub mod scene_parameters;
pub mod segment_bins;
pub mod solid_tool;
pub mod solver;
pub mod stl;
pub mod team;
pub mod thermal;
pub mod tools;
pub mod triangle_surface;
mod validation;

pub use error::{Error, Result};
pub use geometry::Extents;
pub use outputs::THERMAL_MEASURES;
pub use sampling::{sample_times, MAX_SAMPLES};
pub use scene::{IntegrationRule, Kinematics, Scene};
pub use scene_overrides::SceneSource;
pub use solver::{Energy, Fields, MassScalingReport, Ran, Simulation, StageTimes, State};

/// Size rayon's global pool, which runs the parallel stages, to `threads` worker threads
/// (a `--threads` option); `None` keeps rayon's default of one per core. Results are the
/// same bits for any count.
///
/// # Errors
///
/// `Some(0)` or more than [`MAX_THREADS`], or the pool cannot be built (for example because
/// it already was).
pub fn set_threads(threads: Option<usize>) -> Result<()> {
    let Some(n) = threads else {
        return Ok(());
    };
    check_threads(n).map_err(|why| Error::Request(format!("--threads {why}")))?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .map_err(|e| Error::Request(format!("cannot start {n} threads: {e}")))
}

/// Most worker threads a run may ask for: a thousand threads took 40 s to start on a
/// two-core machine, and a million never finished starting.
pub const MAX_THREADS: usize = 256;

/// A thread count a run can use: 1 to [`MAX_THREADS`]; the error says why not (after the
/// option's or argument's name).
pub fn check_threads(n: usize) -> std::result::Result<(), String> {
    match n {
        0 => Err("must be at least 1".into()),
        n if n > MAX_THREADS => Err(format!(
            "= {n}: at most {MAX_THREADS} (this machine has {} cores; results are the same bits for any count)",
            std::thread::available_parallelism().map_or(1, |c| c.get())
        )),
        _ => Ok(()),
    }
}
