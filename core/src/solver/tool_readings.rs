//! What closed-die users read of the die now: each tool's fill points with when they
//! filled (`fill.rs` records it), how much of each tool's length the workpiece touches, and
//! the contact pressure at its stations.
//!
//! The contact length of a tool is the length of the workpiece's surface polygon (the
//! boundary ring's physical positions) over the segments whose two particles both lie on
//! the tool: inside it, or outside by at most [`ON_TOOL_SPACINGS`] smallest spacings (the
//! corrector leaves a particle in contact at about zero gap, on either side), and over the
//! segments a convex corner of the tool touches within that reach (where the corner pass
//! holds the surface, its particles sit just off the tool's faces); its fraction is that
//! over the length of the tool's polyline. Both are read from the state alone, so a
//! restored state reports them as first computed.

use super::fill::{fill_points, scene_points, ON_TOOL_SPACINGS};
use super::simulation::Simulation;
use super::state::Filled;
use crate::contact::corners;
use crate::math::Real;
use crate::scene::Kinematics;

/// A tool's fill point with its state, in 2D or (`D = 3`) 3D.
#[derive(Debug, Clone, PartialEq)]
pub struct FillPoint<const D: usize = 2> {
    /// The tool's index.
    pub tool: usize,
    /// The point's name.
    pub name: String,
    /// Its position now (m).
    pub at_m: [Real; D],
    /// When the material first reached it, if it has.
    pub filled: Option<Filled>,
}

impl Simulation {
    /// Every tool's fill points, tool by tool, with where they are now and when they filled.
    pub fn fill_points(&self) -> Vec<FillPoint> {
        fill_points(scene_points(&self.scene, &self.tools), &self.st.fill)
    }

    /// The workpiece's surface in contact with tool `t` now: the boundary ring's segments
    /// whose two particles both lie on it, and those a convex corner of the tool touches
    /// ([`corners::touching`], within the same reach), each as its two ends at their physical
    /// positions (m), counter-clockwise.
    pub fn contact_segments(&self, t: usize) -> Vec<[[Real; 2]; 2]> {
        let reach = ON_TOOL_SPACINGS * self.disc.h_min();
        let x = self.disc.ring(&self.st.d);
        let inside: Vec<bool> = x
            .iter()
            .map(|&p| self.tools[t].gap_above(p, -reach).is_some())
            .collect();
        let n = x.len();
        let mut touched: Vec<bool> = (0..n).map(|k| inside[k] && inside[(k + 1) % n]).collect();
        for k in corners::touching(&self.tools[t], &x, reach) {
            touched[k] = true;
        }
        (0..n)
            .filter(|&k| touched[k])
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
        let axi = self.scene.model.kinematics == Kinematics::Axisymmetric;
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
