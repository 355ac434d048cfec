//! Stage 4 of the step: the tools advance over the step at their mid-step velocity, the
//! contact stage ([`crate::contact`], the paper's eqs. 4-7) finds the penalty forces on the
//! predicted positions, each tool books its impulse and work ([`crate::tools::Account`]),
//! and the surface's self-contacts grow the laps ([`crate::laps`]).
//! Also the contact stage's construction for a scene, at setup and at a re-reference.

use super::discretization::Discretization;
use super::stable_step::StepLength;
use super::state::State;
use super::workspace::Workspace;
use crate::contact::self_contact::{neighbours, SelfContact};
use crate::contact::{Body, Contact, Pairs, Touch};
use crate::laps;
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::scene::Scene;
use crate::tools::Tool;

/// The contact stage over the step `step`. The predicted positions are a natural step
/// ahead; on a step shortened to land on a requested time the tools meet them there too, a
/// further `full - dt` ahead, and go back to the end of the step after the stage.
pub(super) fn run(
    scene: &Scene,
    disc: &Discretization,
    tools: &mut [Tool],
    st: &mut State,
    ws: &mut Workspace,
    step: StepLength,
) -> Touch {
    let (dt, full) = (step.dt, step.full);
    let t_mid = st.time + 0.5 * dt;
    for t in tools.iter_mut() {
        t.state.velocity = t.velocity_at(t_mid);
        t.state.stroke += dt * t.state.velocity;
    }
    let strokes = (dt < full).then(|| {
        let at_end: Vec<Real> = tools.iter().map(|t| t.state.stroke).collect();
        for t in tools.iter_mut() {
            t.state.stroke += (full - dt) * t.state.velocity;
        }
        at_end
    });
    let (temperature, impulse) = match &mut st.heat {
        Some(h) => (Some(&h.temperature_c[..]), &mut h.normal_impulse[..]),
        None => (None, &mut [][..]),
    };
    let body = Body {
        boundary: &disc.boundary,
        nodal: &disc.nodal,
        reference: &disc.ref_pos,
        mass: &disc.mass,
        d: &st.d,
        v: &st.v,
        spacing: disc.spacing,
        points: &st.points,
        hardening: &disc.material.hardening,
        temperature,
        kinematics: scene.model.kinematics,
        depth_m: scene.model.depth_m,
    };
    let touch = ws.contact.stage(
        &ws.team,
        tools,
        &disc.planes,
        &body,
        Pairs {
            held: &mut st.held,
            plane_held: &mut st.plane_held,
            self_touching: &mut st.self_touching,
            stick: &mut st.stick,
            pressure: &mut st.pressure,
            stations: scene.output.pressure_stations.unwrap_or(0),
            impulse,
        },
        full,
        step.avg,
    );
    st.plane_feedback_max = st.plane_feedback_max.max(touch.feedback);
    for t in tools.iter_mut() {
        let f = t.axial_force();
        t.state.account.book(f, t.state.velocity, step.avg);
    }
    if let Some(strokes) = strokes {
        for (t, stroke) in tools.iter_mut().zip(strokes) {
            t.state.stroke = stroke;
        }
    }
    let predicted_for = st.time + dt;
    grow_laps(scene, tools, st, ws, predicted_for);
    touch
}

/// Grows the laps by the contact stage's self-contacts, predicted for `time` (s)
/// ([`crate::laps`]).
fn grow_laps(scene: &Scene, tools: &[Tool], st: &mut State, ws: &Workspace, time: Real) {
    let (pairs, x) = ws.contact.self_pairs();
    if pairs.is_empty() {
        return;
    }
    let stage = laps::Stage {
        neighbours: neighbours(scene.discretization.support),
        x,
        time,
        strokes: tools.iter().map(|t| t.state.stroke).collect(),
    };
    laps::grow(&mut st.laps, pairs, &stage);
}

/// The contact stage of `scene` ([`Contact::new`]) for particles with the rows of `nodal`,
/// the counter-clockwise `boundary` ring, reference positions `reference` and integration
/// points at `points` (m), with `tools`: the flow stress where a friction law needs it, the
/// self-contact unless the scene turns it off.
pub(super) fn build(
    scene: &Scene,
    boundary: &[u32],
    nodal: &ShapeTable,
    reference: &[[Real; 2]],
    points: &[[Real; 2]],
    tools: &[Tool],
) -> Contact {
    let [nx, ny] = scene.workpiece.particles;
    let size = scene.workpiece.size_m;
    let h = [size[0] / (nx - 1) as Real, size[1] / (ny - 1) as Real];
    let self_contact = SelfContact::new(&scene.self_contact, h, scene.discretization.support);
    let flow_stress = tools.iter().any(|t| t.friction.needs_flow_stress())
        || self_contact
            .as_ref()
            .is_some_and(|s| s.friction.needs_flow_stress());
    Contact::new(
        boundary,
        nodal,
        reference,
        points,
        flow_stress,
        self_contact,
    )
}
