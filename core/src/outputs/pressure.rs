//! The mean contact pressure on a tool, `p = N / A` (Pa): the normal contact force of the
//! workpiece on the tool over the area of the workpiece's surface in contact with it.
//!
//! `N` is the contact stage's own sum of the normal parts of its contact forces on the tool
//! over the last step (`ToolState::normal_force`), each along its own contact normal, so
//! that on a curved or closed die it is the integral of the pressure, `int p dA`, which the
//! resultant force is not (a closed die's side walls cancel in the resultant); it includes
//! the corner pass's forces. `A` is the area of the boundary ring's segments that lie on the
//! tool ([`Simulation::contact_segments`], as the contact length and fraction count them):
//! their length times `model.depth_m` in plane strain, and in axisymmetry the surfaces of
//! revolution of the segments, `sum pi (r_a + r_b) |b - a|` (a segment from radius `r_a`
//! to `r_b` sweeps a conical band; a flat face of radius `R` gives `pi R^2`).

use crate::math::Real;
use crate::scene::Kinematics;
use crate::solver::Simulation;

/// The area of the workpiece's surface in contact with tool `t` now (m^2; the whole ring in
/// axisymmetry, per `model.depth_m` of depth in plane strain).
pub fn contact_area(sim: &Simulation, t: usize) -> Real {
    let model = &sim.scene().model;
    match model.kinematics {
        Kinematics::PlaneStrain => sim.contact_length(t) * model.depth_m,
        Kinematics::Axisymmetric => sim
            .contact_segments(t)
            .iter()
            .map(|[a, b]| {
                let length = (b[0] - a[0]).hypot(b[1] - a[1]);
                std::f64::consts::PI * (a[0] + b[0]).abs() * length
            })
            .sum(),
    }
}

/// The mean contact pressure on tool `t` (Pa): its normal contact force over the
/// [`contact_area`]; 0 while no segment of the surface lies on the tool (a first touch at a
/// single particle has a force but no area yet). Negative where a tool without separation
/// holds the surface back more than it presses.
pub fn mean_contact_pressure(sim: &Simulation, t: usize) -> Real {
    let area = contact_area(sim, t);
    if area > 0.0 {
        sim.tools()[t].state.normal_force / area
    } else {
        0.0
    }
}
