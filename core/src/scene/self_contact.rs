//! The `[self_contact]` section: whether the workpiece's surface holds against itself, and
//! its friction law, with what they must be ([`SelfContactSpec::check`]). The contact stage
//! applies it in [`crate::contact::self_contact`].

use crate::friction::Friction;
use crate::validation::Checks;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Contact of the workpiece's surface with itself: where the surface folds, its parts press
/// on each other instead of passing through, and a fold between surface points that were
/// apart along the surface is reported as a lap ([`crate::contact::self_contact`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SelfContactSpec {
    /// Whether the surface holds against itself (the default). `false` saves the search
    /// where a scene cannot fold, and lets a fold pass through itself unreported.
    #[serde(default = "default_true")]
    pub enabled: bool,
    /// Friction law between the surface's parts, as a tool's ([`Friction`]): a number is a
    /// Coulomb coefficient, a table names the model; default frictionless.
    #[serde(default)]
    pub friction: Friction,
}

fn default_true() -> bool {
    true
}

impl Default for SelfContactSpec {
    fn default() -> Self {
        SelfContactSpec {
            enabled: true,
            friction: Friction::default(),
        }
    }
}

impl SelfContactSpec {
    /// Every value of the section a run cannot use, under its dotted key `self_contact.*`:
    /// the friction law's.
    pub(crate) fn check(&self, out: &mut Checks) {
        for (suffix, message) in self.friction.validate() {
            out.check(false, &format!("self_contact.friction{suffix}"), message);
        }
    }
}
