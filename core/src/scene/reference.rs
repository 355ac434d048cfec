//! The `[[reference]]` section: published results printed beside a run's own (not used by
//! the solver, nothing to check).

use super::discretization::IntegrationRule;
use crate::math::Real;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A published result to compare with: `values` maps summary keys to numbers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    /// Where the numbers come from.
    pub source: String,
    /// The integration rule this reference corresponds to, if any.
    #[serde(default)]
    pub integration: Option<IntegrationRule>,
    /// Summary key -> value, e.g. `"workpiece.radius_m" = 7.11e-3`.
    pub values: std::collections::BTreeMap<String, Real>,
}
