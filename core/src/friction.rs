//! Friction laws of a tool interface, as forging codes state them (DEFORM, QForm, FORGE):
//! Coulomb `tau = mu p`, the shear friction factor `tau = m k` (Wanheim and Bay 1978;
//! Avitzur 1968) with `k = sigma_y / sqrt(3)` the shear flow stress of the von Mises
//! material, and Coulomb capped by it, `tau = min(mu p, m k)`.
//!
//! In the penalty contact of [`crate::tools`] a slave particle carries a normal force
//! `f_n` (N) over its contact area `A` (m^2), so the tangential bound is `mu f_n`, `m k A`
//! or `min(mu f_n, m k A)`; the stick force still caps it, so a sticking particle stays stuck
//! and a sliding one carries the bound ([`crate::contact::sidibe2009::penalty_force`]).
//!
//! Scene syntax: a plain number is a Coulomb coefficient (`friction = 0.2`); a table names
//! the model, `friction = { model = "shear", m = 0.3 }` or
//! `friction = { model = "capped", mu = 0.2, m = 0.5 }`.

use crate::math::Real;
use schemars::JsonSchema;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use std::fmt;

/// The friction law of one tool interface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Friction {
    /// Coulomb: `tau = mu p` (`mu` = 0: frictionless).
    Coulomb {
        /// Coefficient `mu` (-).
        mu: Real,
    },
    /// Shear friction factor: `tau = m k`, `k = sigma_y / sqrt(3)` (0 <= m <= 1).
    Shear {
        /// Factor `m` (-): 0 frictionless, 1 sticking (the material shears).
        m: Real,
    },
    /// Coulomb capped by the shear friction factor: `tau = min(mu p, m k)`.
    Capped {
        /// Coulomb coefficient `mu` (-).
        mu: Real,
        /// Shear friction factor `m` (-).
        m: Real,
    },
}

impl Default for Friction {
    fn default() -> Self {
        Friction::Coulomb { mu: 0.0 }
    }
}

/// `1 / sqrt(3)`: the shear flow stress of a von Mises material per unit flow stress.
const INV_SQRT3: Real = 0.577_350_269_189_625_8;

impl Friction {
    /// Whether the law needs the shear flow stress of the particle (`m k A`).
    pub fn needs_flow_stress(&self) -> bool {
        matches!(self, Friction::Shear { .. } | Friction::Capped { .. })
    }

    /// Whether the interface carries no tangential force at all.
    pub fn is_frictionless(&self) -> bool {
        match *self {
            Friction::Coulomb { mu } => mu == 0.0,
            Friction::Shear { m } => m == 0.0,
            Friction::Capped { mu, m } => mu == 0.0 || m == 0.0,
        }
    }

    /// Largest tangential force (N) on a particle with normal force `f_n` (N; only a
    /// compressive, positive one carries Coulomb friction), flow stress `sigma_y` (Pa) and
    /// contact area `area` (m^2).
    pub fn bound(&self, f_n: Real, sigma_y: Real, area: Real) -> Real {
        let shear = |m: Real| m * sigma_y * INV_SQRT3 * area;
        match *self {
            Friction::Coulomb { mu } => mu * f_n.max(0.0),
            Friction::Shear { m } => shear(m),
            Friction::Capped { mu, m } => (mu * f_n.max(0.0)).min(shear(m)),
        }
    }

    /// The law's main coefficient: `mu` for Coulomb and capped, `m` for shear (the FMU's
    /// friction parameter).
    pub fn coefficient(&self) -> Real {
        match *self {
            Friction::Coulomb { mu } | Friction::Capped { mu, .. } => mu,
            Friction::Shear { m } => m,
        }
    }

    /// The same law with its main coefficient ([`Friction::coefficient`]) set to `c`.
    pub fn with_coefficient(self, c: Real) -> Friction {
        match self {
            Friction::Coulomb { .. } => Friction::Coulomb { mu: c },
            Friction::Shear { .. } => Friction::Shear { m: c },
            Friction::Capped { m, .. } => Friction::Capped { mu: c, m },
        }
    }

    /// Every non-physical coefficient, as (key suffix, message).
    pub fn validate(&self) -> Vec<(&'static str, String)> {
        let mut v = Vec::new();
        let mu_ok = |mu: Real| mu.is_finite() && mu >= 0.0;
        let m_ok = |m: Real| (0.0..=1.0).contains(&m);
        match *self {
            Friction::Coulomb { mu } => {
                if !mu_ok(mu) {
                    v.push(("", format!("must be zero or positive, got {mu}")));
                }
            }
            Friction::Shear { m } => {
                if !m_ok(m) {
                    v.push((".m", format!("must be between 0 and 1, got {m}")));
                }
            }
            Friction::Capped { mu, m } => {
                if !mu_ok(mu) {
                    v.push((".mu", format!("must be zero or positive, got {mu}")));
                }
                if !m_ok(m) {
                    v.push((".m", format!("must be between 0 and 1, got {m}")));
                }
            }
        }
        v
    }
}

/// The table form in scene files.
#[derive(Serialize, Deserialize, JsonSchema)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
enum Table {
    /// Coulomb: `tau = mu p`.
    Coulomb {
        /// Coulomb coefficient `mu` (-).
        mu: Real,
    },
    /// Shear friction factor: `tau = m k`.
    Shear {
        /// Shear friction factor `m` (-), 0 to 1.
        m: Real,
    },
    /// Coulomb capped by the shear friction factor: `tau = min(mu p, m k)`.
    Capped {
        /// Coulomb coefficient `mu` (-).
        mu: Real,
        /// Shear friction factor `m` (-), 0 to 1.
        m: Real,
    },
}

/// The scene's two forms: a number (a Coulomb coefficient) or a [`Table`].
impl JsonSchema for Friction {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Friction".into()
    }
    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "anyOf": [
                { "type": "number", "description": "Coulomb coefficient `mu` (-)" },
                generator.subschema_for::<Table>(),
            ]
        })
    }
}

impl Serialize for Friction {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match *self {
            Friction::Coulomb { mu } => s.serialize_f64(mu),
            Friction::Shear { m } => Table::Shear { m }.serialize(s),
            Friction::Capped { mu, m } => Table::Capped { mu, m }.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for Friction {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Friction, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Friction;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "a Coulomb coefficient or a table such as { model = \"shear\", m = 0.3 }",
                )
            }
            fn visit_f64<E: de::Error>(self, mu: f64) -> Result<Friction, E> {
                Ok(Friction::Coulomb { mu })
            }
            fn visit_i64<E: de::Error>(self, mu: i64) -> Result<Friction, E> {
                Ok(Friction::Coulomb { mu: mu as Real })
            }
            fn visit_u64<E: de::Error>(self, mu: u64) -> Result<Friction, E> {
                Ok(Friction::Coulomb { mu: mu as Real })
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Friction, A::Error> {
                Ok(
                    match Table::deserialize(de::value::MapAccessDeserializer::new(map))? {
                        Table::Coulomb { mu } => Friction::Coulomb { mu },
                        Table::Shear { m } => Friction::Shear { m },
                        Table::Capped { mu, m } => Friction::Capped { mu, m },
                    },
                )
            }
        }
        d.deserialize_any(V)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize, Serialize, Debug, PartialEq)]
    struct T {
        friction: Friction,
    }

    #[test]
    fn a_number_is_coulomb_and_tables_name_the_model() {
        let t: T = toml::from_str("friction = 0.2").unwrap();
        assert_eq!(t.friction, Friction::Coulomb { mu: 0.2 });
        let t: T = toml::from_str("friction = 0").unwrap();
        assert_eq!(t.friction, Friction::Coulomb { mu: 0.0 });
        let t: T = toml::from_str("friction = { model = \"shear\", m = 0.3 }").unwrap();
        assert_eq!(t.friction, Friction::Shear { m: 0.3 });
        let t: T = toml::from_str("friction = { model = \"capped\", mu = 0.1, m = 0.5 }").unwrap();
        assert_eq!(t.friction, Friction::Capped { mu: 0.1, m: 0.5 });
        for f in [
            Friction::Coulomb { mu: 0.25 },
            Friction::Shear { m: 0.4 },
            Friction::Capped { mu: 0.1, m: 1.0 },
        ] {
            let text = toml::to_string(&T { friction: f }).unwrap();
            assert_eq!(toml::from_str::<T>(&text).unwrap().friction, f, "{text}");
        }
        let e = toml::from_str::<T>("friction = { model = \"stick\", m = 0.3 }").unwrap_err();
        assert!(e.to_string().contains("stick"), "{e}");
        let e = toml::from_str::<T>("friction = { model = \"shear\", mu = 0.3 }").unwrap_err();
        assert!(e.to_string().contains("mu"), "{e}");
    }

    #[test]
    fn bounds_of_the_three_laws() {
        let k = 300e6 / 3.0_f64.sqrt();
        let (fn_, area) = (1000.0, 1e-5);
        let close = |a: Real, b: Real| (a - b).abs() <= 1e-12 * b.abs();
        assert!(close(
            Friction::Coulomb { mu: 0.2 }.bound(fn_, 300e6, area),
            200.0
        ));
        assert_eq!(Friction::Coulomb { mu: 0.2 }.bound(-fn_, 300e6, area), 0.0);
        let s = Friction::Shear { m: 0.5 }.bound(fn_, 300e6, area);
        assert!((s - 0.5 * k * area).abs() < 1e-9 * s, "{s}");
        let c = Friction::Capped { mu: 0.2, m: 0.5 };
        assert!(close(c.bound(fn_, 300e6, area), 200.0));
        assert!((c.bound(1e4, 300e6, area) - 0.5 * k * area).abs() < 1e-9 * s);
        assert!(Friction::Shear { m: 1.5 }.validate()[0].0 == ".m");
        assert!(Friction::Coulomb { mu: -1.0 }.validate()[0].0.is_empty());
    }
}
