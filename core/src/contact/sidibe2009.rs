//! The paper's penalty contact law (Sidibe, Li, Ouane, Bokar 2009, section II-3, eqs. 4-7),
//! the force on one slave particle behind a master segment.
//!
//! For a slave `J` whose predicted physical position lies behind a segment by the gap
//! `g_J > 0`:
//! - normal force (eq. 4): `f_n = m_s g / dt^2` along the segment normal `n` (N);
//! - stick force (eq. 6): `f_st = -m_s v_TR / dt`, `v_TR` the tangential relative velocity,
//!   plus what the last step's friction left unrealised (see [`penalty_force`]);
//! - friction (eq. 5): `f_f = min(b, |f_st|) f_st / |f_st|` with the bound `b` of the
//!   law ([`Friction`]): `mu f_n` (Coulomb, the paper's), `m k A` (shear friction factor)
//!   or `min(mu f_n, m k A)`;
//! - the particle force is spread to the RK coefficients (eq. 7): `f_I += f_J N_I(X_J)`
//!   ([`crate::contact::Contact::stage`]).
//!
//! The masters are the tools' segments ([`crate::tools`]), the symmetry planes
//! ([`crate::contact::symmetry`]) and the workpiece's own surface
//! ([`crate::contact::self_contact`]); the force on a master is the reaction.

use crate::friction::Friction;
use crate::math::{dot, Real};
use crate::tools::Penetration;

/// What the shear friction factor needs of a slave particle: its flow stress and contact
/// area.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Interface {
    /// Current flow stress `sigma_y` of the particle's material (Pa).
    pub flow_stress: Real,
    /// Contact area `A` of the particle (m^2): its tributary length along the tool times
    /// the depth in plane strain, times `2 pi r` in axisymmetry.
    pub area: Real,
}

/// The force on one slave particle, with its friction part, in `D` dimensions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlaveForce<const D: usize = 2> {
    /// Contact force on the slave (N): normal penalty plus friction.
    pub force: [Real; D],
    /// Its tangential part, the friction force (N): the stick force while sticking, the
    /// law's bound while sliding.
    pub friction: [Real; D],
}

/// A slave particle as the contact force sees it, in `D` dimensions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slave<const D: usize = 2> {
    /// Mass `m` (kg).
    pub m: Real,
    /// Velocity relative to the tool (m/s).
    pub v_rel: [Real; D],
    /// The friction force the last step left unrealised (N; zero on a new contact).
    pub carried: [Real; D],
}

/// Paper eqs. 4-6: contact force on a `slave` of mass `m` (kg) with gap `g` (m) along the
/// normal `n`, velocity relative to the tool `v_rel` (m/s), the friction force `carried`
/// (N) that the last step's friction left unrealised, the tool's `law` with the
/// particle's flow stress and area `at`, the natural step `dt_step` and the corrector's
/// step `dt_avg` (s):
/// - normal (eq. 4): `f_n = m g / (dt_step dt_avg)` (`m g / dt^2` at constant step);
/// - stick (eq. 6): `f_st = c_T - m v_TR / dt_avg`, the paper's force that stops the
///   tangential relative velocity `v_TR` in one step plus the tangential part `c_T` of the
///   carried force. For interpolating shape functions `c` is zero and this is the paper's
///   law. RK shape functions do not interpolate: eq. 7 spreads the force over coefficients
///   that move other particles too, so it changes the particle's velocity by less than
///   `f dt_avg / m`, and what it did not realise is carried to the next step
///   ([`crate::contact::Contact::carry`]). A sticking particle's force thus builds up until
///   its slip stops, instead of leaving it slipping at a speed set by the step and the mass
///   (which made the friction depend on the step, the mass scaling and the tool speed);
/// - friction (eq. 5): `f_f = min(b, |f_st|) f_st / |f_st|` with the law's bound `b`: the
///   particle sticks below the bound and slides at it (the return mapping of elasto-plastic
///   friction, Wriggers 2006, *Computational Contact Mechanics*, section 5.2), so the
///   tangential force never exceeds `b`.
///
/// The same law in 2 and 3 dimensions (`D`): dot products are summed from their first
/// component on ([`dot`]).
pub fn penalty_force<const D: usize>(
    slave: Slave<D>,
    pen: Penetration<D>,
    law: &Friction,
    at: Interface,
    dt_step: Real,
    dt_avg: Real,
) -> SlaveForce<D> {
    let Slave { m, v_rel, carried } = slave;
    let n = pen.normal;
    let fn_ = m * pen.gap / (dt_step * dt_avg);
    let mut force = n.map(|nk| fn_ * nk);
    let mut friction = [0.0; D];
    if !law.is_frictionless() {
        let tangential = |a: [Real; D]| {
            let an = dot(&a, &n);
            std::array::from_fn::<Real, D, _>(|k| a[k] - an * n[k])
        };
        let (vt, ct) = (tangential(v_rel), tangential(carried));
        let st: [Real; D] = std::array::from_fn(|k| ct[k] - m * vt[k] / dt_avg);
        let stick = dot(&st, &st).sqrt();
        if stick > 0.0 {
            let ff = law.bound(fn_, at.flow_stress, at.area).min(stick);
            friction = st.map(|sk| ff * sk / stick);
            for (f, r) in force.iter_mut().zip(friction) {
                *f += r;
            }
        }
    }
    SlaveForce { force, friction }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slave of mass `m` moving at `v` relative to the tool with `carried` force.
    fn slave(m: Real, v: [Real; 2], carried: [Real; 2]) -> Slave {
        Slave {
            m,
            v_rel: v,
            carried,
        }
    }

    #[test]
    fn friction_is_bounded_by_coulomb_and_by_the_stick_force() {
        let pen = Penetration {
            gap: 1e-3,
            normal: [0.0, 1.0],
        };
        let (m, dt) = (2.0, 1e-3);
        let fn_ = m * 1e-3 / (dt * dt);
        // Fast sliding: Coulomb bound.
        let c = Friction::Coulomb { mu: 0.3 };
        let at = Interface::default();
        let f = penalty_force(slave(m, [5.0, 0.0], [0.0; 2]), pen, &c, at, dt, dt).force;
        assert!(
            (f[1] - fn_).abs() < 1e-9 && (f[0] + 0.3 * fn_).abs() < 1e-9,
            "{f:?}"
        );
        // Slow sliding: the stick force m v / dt is smaller and wins.
        let slow = penalty_force(slave(m, [1e-4, 0.0], [0.0; 2]), pen, &c, at, dt, dt);
        assert!((slow.force[0] + m * 1e-4 / dt).abs() < 1e-12, "{slow:?}");
        assert_eq!(slow.friction, [slow.force[0], 0.0]);
        // A carried force adds to the stick force (its normal part is dropped); the sum is
        // still capped at the bound.
        let carried = [-50.0, 1e9];
        let held = penalty_force(slave(m, [1e-4, 0.0], carried), pen, &c, at, dt, dt);
        assert!(
            (held.friction[0] + 50.0 + m * 1e-4 / dt).abs() < 1e-9,
            "{held:?}"
        );
        assert_eq!(held.friction[1], 0.0);
        let capped = penalty_force(slave(m, [1e-4, 0.0], [-1e9, 0.0]), pen, &c, at, dt, dt);
        assert!((capped.friction[0] + 0.3 * fn_).abs() < 1e-9, "{capped:?}");
        // Frictionless: no tangential force, whatever is carried.
        let none = Friction::Coulomb { mu: 0.0 };
        let free = penalty_force(slave(m, [5.0, 0.0], carried), pen, &none, at, dt, dt);
        assert_eq!((free.force[0], free.friction), (0.0, [0.0; 2]));
    }

    #[test]
    fn shear_and_capped_friction_slide_at_their_bound_and_stick_below_it() {
        // A 1 mm^2 contact area on a material flowing at 300 MPa: k A = 173.2 N.
        let pen = Penetration {
            gap: 1e-6,
            normal: [0.0, 1.0],
        };
        let (m, dt): (Real, Real) = (1e-3, 1e-6);
        let fn_ = m * 1e-6 / (dt * dt);
        let at = Interface {
            flow_stress: 300e6,
            area: 1e-6,
        };
        let ka: Real = 300e6 / 3.0_f64.sqrt() * 1e-6;
        let laws = [
            (Friction::Shear { m: 0.4 }, 0.4 * ka),
            (
                Friction::Capped { mu: 0.1, m: 0.4 },
                (0.1 * fn_).min(0.4 * ka),
            ),
            (
                Friction::Capped { mu: 0.5, m: 0.4 },
                (0.5 * fn_).min(0.4 * ka),
            ),
        ];
        for (law, bound) in laws {
            for v in [
                [5.0, 0.0],
                [-3.0, 2.0],
                [0.0, -1e3],
                [1e-6, 0.0],
                [-2e-7, 7.0],
            ] {
                let SlaveForce { force: f, friction } =
                    penalty_force(slave(m, v, [0.0; 2]), pen, &law, at, dt, dt);
                assert_eq!(friction, [f[0], 0.0], "{law:?}: the tangential part");
                let vt = v[0];
                // Never above the bound nor the stick force; never along the sliding (no
                // energy created: f_t v_t <= 0).
                let stick = m * vt.abs() / dt;
                assert!(
                    f[0].abs() <= bound.min(stick) * (1.0 + 1e-15),
                    "{law:?} {v:?} {f:?}"
                );
                assert!(f[0] * vt <= 0.0, "{law:?} {v:?} {f:?}");
                // The normal force is untouched by friction.
                assert_eq!(f[1], fn_);
                if stick > bound {
                    assert!(
                        (f[0].abs() - bound).abs() <= 1e-12 * bound,
                        "{law:?} slides at its bound"
                    );
                } else {
                    // Sticking: the force stops the sliding in this step, m v + f dt = 0.
                    assert!(
                        (m * vt + f[0] * dt).abs() <= 1e-15 * m * vt.abs().max(1.0),
                        "{law:?} sticks"
                    );
                }
            }
        }
        // m = 0 and a bonded particle under tension (negative gap) carry no Coulomb friction.
        let fast = slave(m, [5.0, 0.0], [0.0; 2]);
        let none = penalty_force(fast, pen, &Friction::Shear { m: 0.0 }, at, dt, dt);
        assert_eq!(none.force[0], 0.0);
        let pull = Penetration {
            gap: -1e-7,
            normal: [0.0, 1.0],
        };
        let f = penalty_force(fast, pull, &Friction::Coulomb { mu: 0.3 }, at, dt, dt).force;
        assert!(f[1] < 0.0 && f[0] == 0.0, "{f:?}");
        let f = penalty_force(fast, pull, &Friction::Shear { m: 0.3 }, at, dt, dt).force;
        assert!(
            (f[0] + 0.3 * ka).abs() < 1e-12 * ka,
            "shear friction needs no pressure: {f:?}"
        );
    }
}
