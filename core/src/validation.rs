//! What a scene's validation shares between its sections: the findings, as (dotted key,
//! message), and the predicates on values that several sections use.

use crate::math::Real;

/// The findings of a validation, as (key path, message).
#[derive(Default)]
pub(crate) struct Checks(pub(crate) Vec<(String, String)>);

impl Checks {
    /// Records `msg` under `key` unless `ok`.
    pub(crate) fn check(&mut self, ok: bool, key: &str, msg: String) {
        if !ok {
            self.0.push((key.to_string(), msg));
        }
    }
}

/// A finite, positive number.
pub(crate) fn pos(x: Real) -> bool {
    x.is_finite() && x > 0.0
}

/// A finite temperature above absolute zero (degrees C).
pub(crate) fn above_absolute_zero(t: Real) -> bool {
    t.is_finite() && t > -273.15
}

/// A table `[[x, value], ...]` (over temperature, pressure): its `x` finite and increasing,
/// each value finite and accepted by `value_ok`.
pub(crate) fn increasing_table(table: &[[Real; 2]], value_ok: impl Fn(Real) -> bool) -> bool {
    table
        .iter()
        .all(|p| p[0].is_finite() && p[1].is_finite() && value_ok(p[1]))
        && table.windows(2).all(|w| w[0][0] < w[1][0])
}

/// A name usable in outputs and interfaces: non-empty, letters, digits and `_`.
pub(crate) fn is_name(name: &str) -> bool {
    !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// A scene's name, used for output folders and FMU identifiers: non-empty, letters,
/// digits, `_` and `-`, under the key `name`.
pub(crate) fn scene_name(name: &str, out: &mut Checks) {
    out.check(
        !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-'),
        "name",
        format!("`{name}` must be non-empty and use only letters, digits, `_` and `-`"),
    );
}
