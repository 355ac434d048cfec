//! The penalty's collective feedback in 3D ([`crate::contact::penalty_feedback`]) on the
//! solver: the measurement against the dense matrix, and the bound 4/3 on a run.

use super::tests::quarter_bar;
use super::SolidSimulation;
use crate::contact::penalty_feedback::{dense_feedback, feedback, FEEDBACK_LIMIT};
use crate::error::Error;
use crate::math::Real;
use crate::solver::energy::{kinetic_energy, Energy};

/// The coarse quarter bar on its FE wall, with the masses of the particles next to
/// the symmetry planes (not on them) multiplied by `factor` (the energy account
/// started again), and the penalty's bound on or off.
fn bar_with_light_layer(factor: Real, bounded: bool) -> SolidSimulation {
    let scene = quarter_bar([4, 2, 16], "q2", 3e-6);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    let (np, nt) = (sim.disc.mass.len(), sim.st.tools.len());
    let on_plane = |j: usize| (1..nt).any(|t| sim.st.held[j * nt + t]);
    let off = |j: usize| sim.disc.ref_pos[j][0].min(sim.disc.ref_pos[j][1]);
    let first = (0..np)
        .filter(|&j| !on_plane(j))
        .map(off)
        .fold(Real::INFINITY, Real::min);
    let layer: Vec<usize> = (0..np)
        .filter(|&j| !on_plane(j) && off(j) < 1.5 * first)
        .collect();
    for j in layer {
        sim.disc.mass[j] *= factor;
        sim.disc.inv_mass[j] /= factor;
    }
    sim.st.energy = Energy::starting(kinetic_energy(&sim.disc.mass, &sim.st.v));
    sim.ws.contact.feedback.bounded = bounded;
    sim
}

/// The feedback is the largest eigenvalue of `G`: the Lanczos answer against power
/// iteration on the dense matrix built entry by entry from its definition; on the
/// undeformed lattice it lies between 1 and the limit, so no shipped scene is scaled
/// at the start.
#[test]
fn the_feedback_is_the_largest_eigenvalue_of_the_dense_matrix() {
    let sim = SolidSimulation::new(&quarter_bar([4, 2, 16], "q2", 1e-6)).unwrap();
    let (np, nt) = (sim.disc.mass.len(), sim.st.tools.len());
    let d = &sim.disc;
    for t in 1..nt {
        let set: Vec<usize> = (0..np).filter(|&j| sim.st.held[j * nt + t]).collect();
        let rho = feedback(&d.nodal, &d.mass, &set);
        let dense = dense_feedback(&d.nodal, &d.mass, &set);
        assert!(
            (rho - dense).abs() < 1e-6 * dense,
            "plane {t}: Lanczos {rho}, dense {dense}"
        );
        assert!(rho > 1.0 && rho < FEEDBACK_LIMIT, "plane {t}: {rho}");
    }
}

/// The FE wall's feedback over the bar's impact face, the particles it holds from the
/// first step of the impact on.
fn wall_feedback(sim: &SolidSimulation) -> Real {
    let face: Vec<usize> = (0..sim.disc.ref_pos.len())
        .filter(|&j| sim.disc.ref_pos[j][2].abs() < 1e-9)
        .collect();
    feedback(&sim.disc.nodal, &sim.disc.mass, &face)
}

/// The bound 4/3 on the solver itself: particles next to the symmetry planes made
/// lighter raise the FE wall's feedback over the impact face. At 1.26 (the layer at 0.15 of
/// its mass) the unscaled penalty runs the impact through; at 1.35 (0.12) it rings
/// and the energy balance stops the run; with the scale the same bar runs through with
/// the energy account closed and no particle inside the wall or beyond a plane.
#[test]
fn a_feedback_past_four_thirds_rings_unless_scaled() {
    let mut below = bar_with_light_layer(0.15, false);
    let rho = wall_feedback(&below);
    assert!(rho > FEEDBACK_LIMIT && rho < 4.0 / 3.0, "{rho}");
    below.run_toward(3e-6, u64::MAX, |_, _| true).unwrap();
    let mut above = bar_with_light_layer(0.12, false);
    let rho = wall_feedback(&above);
    assert!(rho > 4.0 / 3.0, "{rho}");
    let ran = above.run_toward(3e-6, u64::MAX, |_, _| true);
    assert!(
        matches!(ran, Err(Error::EnergyBalance { .. })),
        "the unscaled run: {ran:?}"
    );
    let mut bounded = bar_with_light_layer(0.12, true);
    bounded.run_toward(3e-6, u64::MAX, |_, _| true).unwrap();
    let e = bounded.energy();
    let (inside, beyond) = bounded.measure_penetration().unwrap();
    let h = bounded.disc.h_min;
    assert!(
        (bounded.plane_penalty_scale_min() - 1.0 / rho).abs() < 1e-12,
        "{} {rho}",
        bounded.plane_penalty_scale_min()
    );
    assert!(e.balance_error_rel() < 1e-3, "{}", e.balance_error_rel());
    assert!(inside < 0.05 * h && beyond < 0.05 * h, "{inside} {beyond}");
}
