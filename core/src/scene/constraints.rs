//! The `[[constraints]]` section: which displacement components of which workpiece edges
//! are held (symmetry planes), with what each must be ([`check`]). The solver applies them
//! in [`crate::constraints`].

use crate::validation::Checks;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A workpiece edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Edge {
    /// Particles with the smallest x.
    XMin,
    /// Particles with the largest x.
    XMax,
    /// Particles with the smallest y.
    YMin,
    /// Particles with the largest y.
    YMax,
}

impl Edge {
    /// The edge's name in scene files and outputs (`x_min`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Edge::XMin => "x_min",
            Edge::XMax => "x_max",
            Edge::YMin => "y_min",
            Edge::YMax => "y_max",
        }
    }

    /// The particles on this edge of an `nx` x `ny` grid numbered row by row.
    pub fn particles(self, nx: usize, ny: usize) -> Vec<u32> {
        let id = |i: usize, j: usize| (j * nx + i) as u32;
        match self {
            Edge::XMin => (0..ny).map(|j| id(0, j)).collect(),
            Edge::XMax => (0..ny).map(|j| id(nx - 1, j)).collect(),
            Edge::YMin => (0..nx).map(|i| id(i, 0)).collect(),
            Edge::YMax => (0..nx).map(|i| id(i, ny - 1)).collect(),
        }
    }
}

/// A displacement component.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Component {
    /// x (or r).
    X,
    /// y (or z).
    Y,
}

/// The physical displacement component `fix` of the particles on `edge` stays zero
/// (a symmetry plane). The axis r = 0 of an axisymmetric workpiece is added automatically.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSpec {
    /// Which edge.
    pub edge: Edge,
    /// Which components are held.
    pub fix: Vec<Component>,
}

/// What each condition of the section must be, under `constraints[i].*`: it names a
/// component.
pub(crate) fn check(constraints: &[ConstraintSpec], out: &mut Checks) {
    for (i, c) in constraints.iter().enumerate() {
        out.check(
            !c.fix.is_empty(),
            &format!("constraints[{i}].fix"),
            "names no component".into(),
        );
    }
}
