//! The `[discretization]` section: the integration rule, the kernel's support, re-referencing
//! and the stabilization of nodal integration, with what they must be
//! ([`Discretization::check`]).

use crate::math::Real;
use crate::validation::Checks;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Background-cell integration rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum IntegrationRule {
    /// 2x2 Gauss rule per cell.
    Q4,
    /// The paper's two-point rule: points at +-(1/sqrt3, 1/sqrt3) on a cell diagonal, weight 2.
    #[default]
    Q2,
    /// Stabilized conforming nodal integration (Chen, Wu, Yoon, You 2001): one point per
    /// particle, gradients smoothed over the particle's domain.
    Scni,
}

impl IntegrationRule {
    /// Every rule, in the order a sweep runs them.
    pub const ALL: [IntegrationRule; 3] = [
        IntegrationRule::Q4,
        IntegrationRule::Q2,
        IntegrationRule::Scni,
    ];
    /// The scene/CLI name.
    pub fn name(self) -> &'static str {
        match self {
            IntegrationRule::Q4 => "q4",
            IntegrationRule::Q2 => "q2",
            IntegrationRule::Scni => "scni",
        }
    }
    /// Parse a scene/CLI name.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "q4" => Some(IntegrationRule::Q4),
            "q2" => Some(IntegrationRule::Q2),
            "scni" => Some(IntegrationRule::Scni),
            _ => None,
        }
    }
}

/// Discretisation knobs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Discretization {
    /// Integration rule: `q4` (2x2 Gauss per cell), `q2` (the paper's two-point rule) or
    /// `scni` (stabilized conforming nodal integration).
    #[serde(default)]
    pub integration: IntegrationRule,
    /// Kernel support radius per direction, in particle spacings (-).
    #[serde(default = "default_support")]
    pub support: [Real; 2],
    /// Re-reference the kernel when an integration point's largest principal in-plane
    /// stretch since the last reference reaches this value (-): the shape functions are
    /// rebuilt on the current configuration and the state carried over
    /// ([`crate::solver`]'s `rereference.rs`). Absent: the Lagrangian kernel throughout.
    #[serde(default)]
    pub rereference_stretch: Option<Real>,
    /// With `integration = "scni"`: the coefficient `c` (-) of the stabilization of nodal
    /// integration (Puso, Chen, Zywicz, Elmer 2008's MSCNI; [`crate::solver`]'s
    /// `nodal_stabilization.rs`), a stiffness `c mu` against the variation of the
    /// displacement gradient over the quadrants of each nodal domain (octants in 3D), which holds the
    /// saw-tooth SCNI leaves free on a surface. Absent or 0: plain SCNI.
    #[serde(default)]
    pub scni_stabilization: Option<Real>,
}

fn default_support() -> [Real; 2] {
    [2.0, 2.0]
}

impl Default for Discretization {
    fn default() -> Self {
        Discretization {
            integration: IntegrationRule::default(),
            support: default_support(),
            rereference_stretch: None,
            scni_stabilization: None,
        }
    }
}

impl Discretization {
    /// Every value of the section a run cannot use, under its dotted key
    /// `discretization.*`: kernel support, re-referencing (which the cell rules alone
    /// allow) and the stabilization of nodal integration.
    pub(crate) fn check(&self, out: &mut Checks) {
        for k in 0..2 {
            let s = self.support[k];
            out.check(
                s.is_finite() && (1.05..=4.0).contains(&s),
                "discretization.support",
                format!("support radii must lie in [1.05, 4] particle spacings (a linear basis needs more than 1), got {:?}", self.support),
            );
        }
        check_rereference(self.rereference_stretch, self.integration, out);
        check_scni_stabilization(self.scni_stabilization, out);
    }
}

/// `discretization.scni_stabilization` (2D and 3D): a fraction of the shear modulus in
/// [0, 1].
pub(crate) fn check_scni_stabilization(c: Option<Real>, out: &mut Checks) {
    if let Some(c) = c {
        out.check(
            c.is_finite() && (0.0..=1.0).contains(&c),
            "discretization.scni_stabilization",
            format!("must lie in [0, 1] (a fraction of the shear modulus), got {c}"),
        );
    }
}

/// `discretization.rereference_stretch` (2D and 3D): a principal stretch in [1.1, 10], with
/// a cell rule (q2, q4).
pub(crate) fn check_rereference(
    stretch: Option<Real>,
    integration: IntegrationRule,
    out: &mut Checks,
) {
    if let Some(s) = stretch {
        out.check(
            s.is_finite() && (1.1..=10.0).contains(&s),
            "discretization.rereference_stretch",
            format!("must lie in [1.1, 10] (a principal stretch), got {s}"),
        );
        out.check(
            integration != IntegrationRule::Scni,
            "discretization.rereference_stretch",
            "re-referencing works with the cell rules q2 and q4; scni's nodal domains are not rebuilt on the deformed particles".into(),
        );
    }
}
