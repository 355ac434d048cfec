//! What closed-die users read of the die: which named points of each tool (cavity corners,
//! `[[tools]] fill_points`) the material has reached and when, and how much of each tool's
//! length the workpiece touches.
//!
//! A fill point is reached at the first step after which a surface particle (of the
//! boundary ring, or any particle in contact with a tool) lies, at its physical position
//! `x_J = X_J + sum_I N_I(X_J) d_I`, within `output.fill_distance_rel` smallest spacings of
//! the point (which moves with the tool). A point still empty at the end of the stroke is
//! underfill.
//!
//! The contact length of a tool is the length of the workpiece's surface polygon (the
//! boundary ring's physical positions) over the segments whose two particles both lie on
//! the tool: inside it, or outside by at most [`ON_TOOL_SPACINGS`] smallest spacings (the
//! corrector leaves a particle in contact at about zero gap, on either side); its fraction
//! is that over the length of the tool's polyline. Both are read from the state alone, so a
//! restored state reports them as first computed.

use super::Simulation;
use crate::math::Real;

/// Farthest outside a tool a surface particle counts as on it, in smallest spacings: the
/// acceptance bound on penetration, taken on the other side.
pub const ON_TOOL_SPACINGS: Real = 0.05;

/// A tool's fill point with its state.
#[derive(Debug, Clone, PartialEq)]
pub struct FillPoint {
    /// The tool's index.
    pub tool: usize,
    /// The point's name.
    pub name: String,
    /// Its position now (m).
    pub at_m: [Real; 2],
    /// When the material first reached it, if it has.
    pub filled: Option<super::Filled>,
}

impl Simulation {
    /// After a step with contact: records the fill points that a surface particle now
    /// reaches. The predicted positions of the ring and of the particles in contact (a step
    /// ahead, from the contact stage) pick those within a spacing more than the reach; their
    /// physical positions decide.
    pub(super) fn check_fill(&mut self) {
        if self.st.fill.iter().all(Option::is_some) {
            return;
        }
        let h = self.spacing[0].min(self.spacing[1]);
        let reach = self.scene.output.fill_distance_rel * h;
        let open: Vec<(usize, [Real; 2], usize)> = self
            .points_now()
            .filter(|&(k, _, _)| self.st.fill[k].is_none())
            .collect();
        let near = |x: [Real; 2], at: [Real; 2], r: Real| (x[0] - at[0]).hypot(x[1] - at[1]) <= r;
        let touching = self.contact.near().map(|n| (n.0, n.2));
        let particles: Vec<usize> = self
            .contact
            .ring_predicted()
            .chain(touching)
            .filter(|&(_, x)| open.iter().any(|&(_, at, _)| near(x, at, reach + h)))
            .map(|(j, _)| j)
            .collect();
        for j in particles {
            let x = self.position(j);
            for &(k, at, t) in &open {
                if self.st.fill[k].is_none() && near(x, at, reach) {
                    self.st.fill[k] = Some(super::Filled {
                        time_s: self.st.time,
                        stroke_m: self.tools[t].state.stroke,
                    });
                }
            }
        }
    }

    /// Every fill point as (index in [`super::State::fill`], position now (m), tool), tool
    /// by tool in scene order.
    fn points_now(&self) -> impl Iterator<Item = (usize, [Real; 2], usize)> + '_ {
        self.scene
            .tools
            .iter()
            .enumerate()
            .flat_map(move |(t, spec)| {
                let tool = &self.tools[t];
                let s = tool.state.stroke;
                spec.fill_points.iter().map(move |p| {
                    let at = [p.at_m[0] + s * tool.axis[0], p.at_m[1] + s * tool.axis[1]];
                    (at, t)
                })
            })
            .enumerate()
            .map(|(k, (at, t))| (k, at, t))
    }

    /// Every tool's fill points, tool by tool, with where they are now and when they filled.
    pub fn fill_points(&self) -> Vec<FillPoint> {
        let names = self.scene.tools.iter().flat_map(|t| &t.fill_points);
        self.points_now()
            .zip(names)
            .map(|((k, at_m, tool), p)| FillPoint {
                tool,
                name: p.name.clone(),
                at_m,
                filled: self.st.fill[k],
            })
            .collect()
    }

    /// The workpiece's surface in contact with tool `t` now: the boundary ring's segments
    /// whose two particles both lie on it, each as its two ends at their physical positions
    /// (m), counter-clockwise.
    pub fn contact_segments(&self, t: usize) -> Vec<[[Real; 2]; 2]> {
        let below = -ON_TOOL_SPACINGS * self.spacing[0].min(self.spacing[1]);
        let x: Vec<[Real; 2]> = self
            .boundary
            .iter()
            .map(|&j| self.position(j as usize))
            .collect();
        let inside: Vec<bool> = x
            .iter()
            .map(|&p| self.tools[t].gap_above(p, below).is_some())
            .collect();
        let n = x.len();
        (0..n)
            .filter(|&k| inside[k] && inside[(k + 1) % n])
            .map(|k| [x[k], x[(k + 1) % n]])
            .collect()
    }

    /// Length of the workpiece's surface in contact with tool `t` now (m): the length of
    /// its [`Simulation::contact_segments`].
    pub fn contact_length(&self, t: usize) -> Real {
        self.contact_segments(t)
            .iter()
            .map(|[a, b]| (b[0] - a[0]).hypot(b[1] - a[1]))
            .sum()
    }

    /// Contact pressure (Pa) at each of tool `t`'s `output.pressure_stations`: the normal
    /// penalty forces of the last contact stage on the station over its area (length times
    /// depth, or times `2 pi r` in axisymmetry); empty without stations. Vertex forces of
    /// the corner pass are not included.
    pub fn contact_pressure(&self, t: usize) -> Vec<Real> {
        let Some(n) = self.scene.output.pressure_stations else {
            return Vec::new();
        };
        let axi = self.scene.model.kinematics == crate::scene::Kinematics::Axisymmetric;
        let tool = &self.tools[t];
        self.st.pressure[t * n..(t + 1) * n]
            .iter()
            .enumerate()
            .map(|(k, f)| f / tool.station_area(k, n, axi, self.scene.model.depth_m))
            .collect()
    }

    /// [`Simulation::contact_length`] over the length of the tool's polyline (-).
    pub fn contact_fraction(&self, t: usize) -> Real {
        self.contact_length(t) / self.tools[t].length()
    }
}
