//! The whole changing state of a simulation, saved and restored as one value.

use super::detachment::Isolation;
use super::energy::Energy;
use super::heat::Heat;
use crate::contact::Stick;
use crate::laps::Lap;
use crate::material::PointState;
use crate::math::Real;
use crate::tools::{Tool, ToolState};
use serde::{Deserialize, Serialize};

/// Everything that changes during a run: saving and restoring it continues bit for bit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Steps taken.
    pub step: u64,
    /// Time (s).
    pub time: Real,
    /// Length of the last step (s), 0 before the first.
    pub dt_prev: Real,
    /// RK coefficients of the displacement `d_I` (m).
    pub d: Vec<[Real; 2]>,
    /// Coefficient velocities at the last half step (m/s).
    pub v: Vec<[Real; 2]>,
    /// Integration point histories.
    pub points: Vec<PointState>,
    /// Tool states.
    pub tools: Vec<ToolState>,
    /// Energy account.
    pub energy: Energy,
    /// Deepest a particle's physical position lay inside a tool (m), over the steps'
    /// checks and the samples.
    pub max_penetration: Real,
    /// Stable step estimate on the deformation at `time` (s).
    pub stable_dt: Real,
    /// Time (s) and step count at the last step that was not a full fixed step: with a
    /// fixed step, `time = anchor_time + (step - anchor_step) dt` has no rounding drift, so
    /// requested instants that are whole multiples of the step are reached exactly.
    pub anchor_time: Real,
    /// Step count at `anchor_time`.
    pub anchor_step: u64,
    /// Largest kinetic-to-internal energy ratio since the quasi-static watch began (-).
    #[serde(default)]
    pub kinetic_to_internal_max: Real,
    /// Time of the first step with a contact force (s), where the watch's start-up begins.
    #[serde(default)]
    pub first_contact_s: Option<Real>,
    /// Which particles are held on which tool without separation
    /// (`[candidate * tools + tool]`; empty when every tool separates).
    #[serde(default)]
    pub held: Vec<bool>,
    /// Which particles are held on which symmetry plane (`[candidate * planes + plane]`;
    /// empty without planes).
    #[serde(default)]
    pub plane_held: Vec<bool>,
    /// Which boundary ring particles are in contact with the workpiece's own surface (by
    /// ring index; empty without self-contact): a self-contact begins shallow and goes on
    /// deeper ([`crate::contact::self_contact`]).
    #[serde(default)]
    pub self_touching: Vec<bool>,
    /// Deepest a particle's physical position lay beyond a symmetry plane or the axis (m),
    /// over the steps' checks and the samples.
    #[serde(default)]
    pub max_beyond_plane: Real,
    /// The particles' isolation at the samples, and the first that left the body
    /// (`detachment.rs`).
    #[serde(default)]
    pub isolation: Isolation,
    /// Largest collective feedback of the penalty of a tool without separation or a
    /// symmetry plane over the particles it held (-; [`crate::contact::penalty_feedback`]).
    #[serde(default)]
    pub plane_feedback_max: Real,
    /// Deepest a surface particle lay inside another part of the workpiece (m).
    #[serde(default)]
    pub max_inside_itself: Real,
    /// Most crossings of the boundary ring's segments at a sample (0: it never crossed
    /// itself).
    #[serde(default)]
    pub max_crossings: u32,
    /// The laps (folds of the surface onto itself) found so far, in the order they formed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub laps: Vec<Lap>,
    /// The friction state of each particle in contact with each tool that has friction
    /// (`[candidate * tools + tool]`, `None` out of contact).
    #[serde(default)]
    pub stick: Vec<Option<Stick>>,
    /// When the material first reached each tool's fill points, in scene order (tool by
    /// tool); `None` while a point is empty.
    #[serde(default)]
    pub fill: Vec<Option<Filled>>,
    /// The configuration the kernel was last re-referenced on (`None`: the lattice).
    #[serde(default)]
    pub reference: Option<Reference>,
    /// Largest principal in-plane stretch of `F` at the last stress stage (-), measured
    /// when the scene re-references the kernel (0 otherwise).
    #[serde(default)]
    pub max_stretch: Real,
    /// Normal contact force (N) on each pressure station of each tool in the last contact
    /// stage, tool by tool (`output.pressure_stations` per tool); empty without stations.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pressure: Vec<Real>,
    /// Temperatures and plastic work of the points in a scene with `[thermal]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heat: Option<Heat>,
}

impl State {
    /// Whether `other` has the lengths of this state's arrays: saved from a simulation of
    /// the same discretisation, tools and outputs.
    pub(super) fn same_shape(&self, other: &State) -> bool {
        self.d.len() == other.d.len()
            && self.v.len() == other.v.len()
            && self.points.len() == other.points.len()
            && self.tools.len() == other.tools.len()
            && self.held.len() == other.held.len()
            && self.plane_held.len() == other.plane_held.len()
            && self.self_touching.len() == other.self_touching.len()
            && self.stick.len() == other.stick.len()
            && self.fill.len() == other.fill.len()
    }

    /// The clock after a step of `dt` (s), with the `tools` saved as they ended it. A run of
    /// the scene's fixed step `fixed` keeps the time as `t_anchor + k dt_s` (no round-off
    /// piling up over millions of steps); any other step (a landing or a limited one)
    /// adds up and anchors the time anew.
    pub(super) fn advance_clock(&mut self, fixed: Option<Real>, dt: Real, tools: &[Tool]) {
        self.step += 1;
        match fixed {
            Some(fixed) if dt == fixed => {
                self.time = self.anchor_time + (self.step - self.anchor_step) as Real * fixed;
            }
            _ => {
                self.time += dt;
                self.anchor_time = self.time;
                self.anchor_step = self.step;
            }
        }
        self.dt_prev = dt;
        for (t, s) in tools.iter().zip(self.tools.iter_mut()) {
            *s = t.state;
        }
    }
}

/// The moment the material first reached a tool's fill point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Filled {
    /// Time (s).
    pub time_s: Real,
    /// The tool's stroke then (m).
    pub stroke_m: Real,
}

/// The configuration the kernel was last rebuilt on, saved with the state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// Re-references so far.
    pub count: u32,
    /// Time of the last one (s).
    pub time_s: Real,
    /// Particle positions `X'` (m).
    pub particles: Vec<[Real; 2]>,
    /// Planar kernel volumes `V'` (m^2).
    pub volumes: Vec<Real>,
    /// Each particle's deformed cell `G = [G_11, G_12, G_21, G_22]` (m).
    pub cells: Vec<[Real; 4]>,
    /// Integration point positions (m).
    pub points: Vec<[Real; 2]>,
    /// `J = det F` of each point from the original configuration (-).
    pub point_jacobian: Vec<Real>,
    /// Relative residual of the velocity transfer (-).
    pub fit_residual: Real,
    /// Particles and points, summed over the re-references so far, where the supports
    /// sized from the deformed cells covered too few particles and were grown
    /// ([`crate::rk_shape::cover_sites`]).
    #[serde(default)]
    pub short_sites: u64,
    /// Particles and points, summed over the re-references so far, where the covering
    /// particles left the moment matrix's condition above
    /// [`crate::rk_shape::MAX_CONDITION`] (a sheet that the axis-aligned supports do not
    /// span) and more supports were grown to reach them
    /// ([`crate::rk_shape::condition_sites`]).
    #[serde(default)]
    pub flat_sites: u64,
    /// The lumped masses (kg) with which selective mass scaling holds its target on these
    /// shape functions (`mass_scaling::hold`); `None` without it.
    #[serde(default)]
    pub masses: Option<Vec<Real>>,
}
