//! The heat stage of a scene whose heat moves ([`crate::scene::Scene::transfers_heat`]):
//! conduction in the workpiece with the mechanics' own shape functions and integration
//! points, and the heat that crosses its surface to the tools and the surroundings;
//! explicit (forward Euler) and sub-cycled: it runs once the time since its last run would
//! pass its stable step, which is orders of magnitude above the mechanical one (a thermal
//! diffusion step `~ rho c h^2 / (2 d k)`, 0.1 s for steel at 1 mm, against microseconds),
//! so it costs a small share of the steps however fine the mechanical step.
//!
//! The particles carry the temperature field `T_I` (degrees C) the stage conducts; the
//! points carry `T_p = sum_I N_I(X_p) T_I` as of the last stage plus what plastic work added
//! since, point by point at every mechanical step ([`super::heat`]), which their flow
//! stress reads. A heat stage:
//! 1. lumped thermal masses `M_I = sum_p N_I(X_p) rho_0 w_p` (kg, physical density: mass
//!    scaling never enters), a particle's capacity `M_I c(T_I)`; the points' gains since
//!    the last stage into the particles, the heat `Q_I = sum_p N_I(X_p) rho_0 w_p (h(T_p) -
//!    h(sum_J N_J(X_p) T_J))` with `h(T) = int c dT` the specific enthalpy (`c dT` for a
//!    constant capacity), and `T_I = h^-1(h(T_I) + Q_I / M_I)` (the heat kept exactly:
//!    `sum_I M_I dh_I = sum_p rho_0 w_p dh_p`), with the friction work the contact stage
//!    booked at each particle, its share `thermal.friction_heat_to_workpiece` (the tool
//!    takes the rest);
//! 2. conduction in the reference configuration (total Lagrangian, as the stress stage),
//!    `R_I = - sum_p w_p J_ref grad_X N_I(X_p) . (k J C^-1 grad_X T)(X_p)` (W; `J_ref` the
//!    Jacobian at the last kernel re-reference, whose configuration `X` then is, 1 without
//!    one) with `grad_X T =
//!    sum_I T_I grad_X N_I`, `C^-1 = F^-1 F^-T` and `J = det F` (`F_33` the hoop stretch in
//!    axisymmetry, where `w_p` holds `2 pi R`): `sum_I R_I = 0`, conduction moves heat
//!    without making or losing any;
//! 3. surface flows at the surface particles, over each particle's share of the surface
//!    `A_I` in the current configuration (2D: the boundary ring, half of each segment to its
//!    neighbours, times the depth or `2 pi r`; 3D: the quarter of each boundary face of the
//!    hexahedral cells at the particle, [`Patch`]): to a tool
//!    that the particle touches (within [`TOUCH_SPACINGS`]) `h_t (T_tool - T_I) A_I`, with
//!    `h_t` the tool's constant or read at the particle's contact pressure `p_I = F_I /
//!    A_I`, `F_I` its normal contact force averaged since the last heat stage (the contact
//!    stage books its impulse), else
//!    to the surroundings `h_c (T_amb - T_I) A_I + eps sigma (T_amb^4 - T_I^4) A_I` (kelvin
//!    in the radiation); segments on a constrained edge and faces on a symmetry plane are
//!    adiabatic, and on the axis of an axisymmetric body a segment's area vanishes; `A_I`
//!    in contact is the share projected on the tool's surface (2D: each half segment on
//!    its tangent; 3D: each quarter face's area vector on its normal);
//! 4. `T_I = h^-1(h(T_I) + dt R_I / M_I)` (`T_I += dt R_I / (M_I c)` for a constant
//!    capacity), and the points take `T_p = h^-1(sum_I N_I(X_p) h(T_I))` (`sum_I N_I T_I`),
//!    which holds the particles' heat exactly (`sum_p rho_0 w_p h(T_p) = sum_I M_I h(T_I)`,
//!    as `sum_p N_I(X_p) rho_0 w_p = M_I`); steps 2-4 repeat when the elapsed time holds
//!    more than one stable heat step.
//!
//! The stable step: conduction's `2 / lambda_max(C^-1 K)`, the largest eigenvalue from power
//! iteration on the undeformed body at setup (the largest conductivity and least capacity
//! the scene's tables hold), scaled by `(h_min0 / h_min)^2` as the
//! smallest deformed cell altitude shrinks (the mechanical critical step scales with
//! `h_min`); a surface particle's `M_I c(T_I) / (h A_I)` (the radiation linearised,
//! `4 eps sigma T^3`); times `thermal.dt_safety`. Within it, the step is the accuracy's:
//! the first heat stage runs after the first mechanical step, and each next step is the
//! last one scaled by `thermal.max_change_per_step_k` over the largest change of a particle's
//! temperature in it, at most doubled or halved, so a die touching the hot billet is met
//! with short steps that lengthen as the chill spreads.
//!
//! One source for both dimensions: the stage is generic over the dimension `D` of the body
//! it conducts in ([`Body`]; `F` and `J C^-1` in [`Conduct`]), the 2D [`stage_if_due`] over
//! a [`Discretization`] and the 3D solver's over its own (`solid/heat.rs`), each with its
//! surface's [`Patch`]es.

use super::discretization::{Discretization, Thermal};
use super::heat::Heat;
use super::layout::Scatter;
use super::point_outputs::PointOut;
use super::state::State;
use super::stress::{Dim, PlasticStrain};
use crate::error::{Error, Result};
use crate::material::{Hardening, HeatCapacity};
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::scene::{HeatContact, Kinematics, Scene, ToolSpec};
use crate::tools::Tool;
use std::f64::consts::PI;

/// Stefan-Boltzmann constant (W/(m^2 K^4)).
const STEFAN_BOLTZMANN: Real = 5.670_374_419e-8;

/// A surface particle within this many smallest spacings of a tool's surface (or inside
/// it) exchanges heat with the tool.
pub const TOUCH_SPACINGS: Real = 0.05;

/// Kelvin of a temperature in degrees C.
fn kelvin(t_c: Real) -> Real {
    t_c + 273.15
}

/// Power iterations for conduction's largest eigenvalue at setup.
const POWER_ITERATIONS: usize = 60;

/// What the heat stage reads of a body of dimension `D`: a 2D [`Discretization`]
/// ([`Discretization::heat_body`]) or the 3D solver's.
pub(super) struct Body<'a, const D: usize> {
    /// Reference volume weights `w_p` of the points (m^3; `2 pi R` included in
    /// axisymmetry).
    pub weights: &'a [Real],
    /// `J = det F` of each point at the last kernel re-reference (-), 1 without one.
    pub reference_jacobian: &'a [Real],
    /// `1 / R_p` of each point (1/m) in axisymmetry, whose hoop stretch `F_33 = 1 + u_r /
    /// R_p` enters `J`; `None` otherwise.
    pub hoop: Option<&'a [Real]>,
    /// The point shape functions ([`Scatter::point_entries`]).
    pub scatter: &'a Scatter<D>,
    /// `N_I(X_J)` in row `J`.
    pub nodal: &'a ShapeTable<D>,
    /// The undeformed particle positions (m), naming a particle in an error.
    pub particles: &'a [[Real; D]],
    /// The points' reference positions (m), naming a point in an error.
    pub point_positions: &'a [[Real; D]],
    /// The critical step of the undeformed body (s): the heat step's bound shrinks with the
    /// mechanical stable step's ratio to it.
    pub critical_dt0: Real,
    /// The workpiece's hardening, whose flow stress over temperature the stage updates.
    pub hardening: &'a Hardening,
}

/// A surface particle's share of the surface in the current configuration (step 3 of the
/// module doc): particle `j`, its area `A_j` (m^2), the part of it on the tool it touches
/// (m^2, projected on the tool's surface) and that tool (an index into the scene's tools),
/// `None` when it touches none.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Patch {
    pub j: usize,
    pub area: Real,
    pub contact: Real,
    pub tool: Option<usize>,
}

/// What differs with the dimension in conduction: from the deformation gradient `F` and
/// the material temperature gradient `g = grad_X T`, `det F` and `C^-1 g = F^-1 F^-T g`
/// (`det F` in-plane in 2D, where the hoop stretch multiplies it).
pub(super) trait Conduct<const D: usize> {
    fn pull_back(f: [[Real; D]; D], g: [Real; D]) -> (Real, [Real; D]);
}

impl Conduct<2> for Dim<2> {
    #[inline]
    fn pull_back(f: [[Real; 2]; 2], g: [Real; 2]) -> (Real, [Real; 2]) {
        let f = [f[0][0], f[0][1], f[1][0], f[1][1]];
        let det2 = f[0] * f[3] - f[1] * f[2];
        // F^-1 = [[F22, -F12], [-F21, F11]] / det2; C^-1 = F^-1 F^-T.
        let inv = [f[3] / det2, -f[1] / det2, -f[2] / det2, f[0] / det2];
        let c11 = inv[0] * inv[0] + inv[1] * inv[1];
        let c12 = inv[0] * inv[2] + inv[1] * inv[3];
        let c22 = inv[2] * inv[2] + inv[3] * inv[3];
        (det2, [c11 * g[0] + c12 * g[1], c12 * g[0] + c22 * g[1]])
    }
}

impl Conduct<3> for Dim<3> {
    #[inline]
    fn pull_back(f: [[Real; 3]; 3], g: [Real; 3]) -> (Real, [Real; 3]) {
        // F^-1 = cof(F)^T / det F; C^-1 g = F^-1 (F^-T g).
        let cof = |a: usize, b: usize| {
            let (a1, a2, b1, b2) = ((a + 1) % 3, (a + 2) % 3, (b + 1) % 3, (b + 2) % 3);
            f[a1][b1] * f[a2][b2] - f[a1][b2] * f[a2][b1]
        };
        let det = f[0][0] * cof(0, 0) + f[0][1] * cof(0, 1) + f[0][2] * cof(0, 2);
        let inv: [[Real; 3]; 3] = std::array::from_fn(|a| std::array::from_fn(|b| cof(b, a) / det));
        let ftg: [Real; 3] =
            std::array::from_fn(|k| inv[0][k] * g[0] + inv[1][k] * g[1] + inv[2][k] * g[2]);
        (det, std::array::from_fn(|a| dot(inv[a], ftg)))
    }
}

/// `a . b`, summed in component order.
#[inline]
fn dot<const D: usize>(a: [Real; D], b: [Real; D]) -> Real {
    let mut s = a[0] * b[0];
    for k in 1..D {
        s += a[k] * b[k];
    }
    s
}

/// Stage 9 of the step, after a step of `dt` (s): runs the heat stage when the time since
/// its last run would pass the heat step at the next mechanical step, in as many equal
/// sub-steps as that step needs, updating the points' flow stresses in `out`. A scene whose
/// heat does not move never runs it.
pub(super) fn stage_if_due(
    scene: &Scene,
    disc: &Discretization,
    tools: &[Tool],
    st: &mut State,
    out: &mut [PointOut],
    dt: Real,
) -> Result<()> {
    let (Some(thermal), Some(heat)) = (&disc.thermal, &mut st.heat) else {
        return Ok(());
    };
    let Some(transfer) = &thermal.transfer else {
        return Ok(());
    };
    let Some(elapsed) = due(heat, dt) else {
        return Ok(());
    };
    let axi = scene.model.kinematics == Kinematics::Axisymmetric;
    let d = &st.d;
    let stage = Stage {
        body: disc.heat_body(axi),
        thermal,
        tools: scene.tools.iter().map(ToolSpec::heat_contact).collect(),
        surface: || ring_patches(scene, disc, tools, &transfer.adiabatic_edge, d),
        lambda0: transfer.lambda0,
        d,
        points: &st.points,
        step: st.step,
        time: st.time,
        stable_dt: st.stable_dt,
    };
    stage.run(heat, out, elapsed)
}

/// Counts the step `dt` (s) into the time since the last heat stage and says whether the
/// stage is due: the time it is to cover (s), the time since the last (reset), when the
/// next mechanical step would pass the heat step.
pub(super) fn due(heat: &mut Heat, dt: Real) -> Option<Real> {
    heat.since_s += dt;
    if heat.since_s + dt < heat.step_s {
        return None;
    }
    Some(std::mem::take(&mut heat.since_s))
}

/// The boundary ring's share of the surface (2D): each ring particle's half of the
/// segments to its neighbours (m) times the depth (plane strain, m) or `2 pi r` at the
/// half segment's midpoint (axisymmetry), in the current configuration; a segment between
/// two particles on a constrained edge is adiabatic (left out); the part on a tool the
/// particle touches (within [`TOUCH_SPACINGS`] smallest spacings) is each half segment
/// projected on the tool's tangent.
fn ring_patches(
    scene: &Scene,
    disc: &Discretization,
    tools: &[Tool],
    adiabatic_edge: &[bool],
    d: &[[Real; 2]],
) -> Vec<Patch> {
    let axi = scene.model.kinematics == Kinematics::Axisymmetric;
    let depth = scene.model.depth_m;
    let ring = &disc.boundary;
    let n = ring.len();
    let x = disc.ring(d);
    let touch = TOUCH_SPACINGS * disc.h_min();
    (0..n)
        .map(|k| {
            let j = ring[k] as usize;
            let touched = tools
                .iter()
                .enumerate()
                .find_map(|(tt, tool)| tool.touches(x[k], touch).map(|tangent| (tt, tangent)));
            let (mut area, mut contact) = (0.0, 0.0);
            for other in [(k + n - 1) % n, (k + 1) % n] {
                if adiabatic_edge[j] && adiabatic_edge[ring[other] as usize] {
                    continue;
                }
                let mid = [0.5 * (x[k][0] + x[other][0]), 0.5 * (x[k][1] + x[other][1])];
                let half = [mid[0] - x[k][0], mid[1] - x[k][1]];
                let scale = if axi {
                    PI * (x[k][0] + mid[0]).max(0.0)
                } else {
                    depth
                };
                area += scale * half[0].hypot(half[1]);
                if let Some((_, tangent)) = touched {
                    contact += scale * (half[0] * tangent[0] + half[1] * tangent[1]).abs();
                }
            }
            Patch {
                j,
                area,
                contact,
                tool: touched.map(|(tt, _)| tt),
            }
        })
        .collect()
}

impl Discretization {
    /// What the heat stage reads of the 2D body; `axi` for an axisymmetric one.
    fn heat_body(&self, axi: bool) -> Body<'_, 2> {
        Body {
            weights: &self.weights,
            reference_jacobian: &self.reference_jacobian,
            hoop: axi.then_some(&self.inv_radius[..]),
            scatter: &self.scatter,
            nodal: &self.nodal,
            particles: &self.original,
            point_positions: &self.points.positions,
            critical_dt0: self.critical_dt0,
            hardening: &self.material.hardening,
        }
    }
}

/// Conduction's largest eigenvalue `lambda_max(C^-1 K)` (1/s) of `disc` on the undeformed
/// body, stored in its heat settings when the scene's heat moves; `step` and `time` (s)
/// name where in the run a particle's thermal mass is not positive.
pub(super) fn update_eigenvalue(disc: &mut Discretization, step: u64, time: Real) -> Result<()> {
    let nx = disc.nx;
    let lambda = match disc.thermal.as_ref() {
        Some(th) if th.transfer.is_some() => eigenvalue(
            &disc.heat_body(false),
            th,
            |j| (j % nx + j / nx) % 2 == 0,
            step,
            time,
        )?,
        _ => return Ok(()),
    };
    if let Some(transfer) = disc.thermal.as_mut().and_then(|th| th.transfer.as_mut()) {
        transfer.lambda0 = lambda;
    }
    Ok(())
}

/// Lumped thermal masses `M_I = sum_p N_I(X_p) rho_0 w_p` (kg, the physical density
/// `density`): a particle's heat capacity is `M_I c(T_I)`. An error names a particle whose
/// mass is not positive, at `step` and `time` (s).
pub(super) fn thermal_masses<const D: usize>(
    body: &Body<'_, D>,
    density: Real,
    step: u64,
    time: Real,
) -> Result<Vec<Real>> {
    let mut mass = vec![0.0; body.particles.len()];
    for (p, &w) in body.weights.iter().enumerate() {
        for (i, n, _) in body.scatter.point_entries(p) {
            mass[i] += n * w * density;
        }
    }
    match mass.iter().position(|&m| m.is_nan() || m <= 0.0) {
        Some(i) => Err(Error::Diverged {
            step,
            time,
            what: format!(
                "thermal mass of particle {i} at {:?} m is {:.3e} kg, not positive",
                body.particles[i], mass[i]
            ),
        }),
        None => Ok(mass),
    }
}

/// The particles' temperatures `t` interpolated at the points of `body`, `sum_I N_I(X_p)
/// t_I` (in enthalpy with a capacity over temperature, [`HeatCapacity::interpolate`]).
pub(super) fn at_points<const D: usize>(
    body: &Body<'_, D>,
    capacity: &HeatCapacity,
    t: &[Real],
) -> Vec<Real> {
    (0..body.weights.len())
        .map(|p| capacity.interpolate(body.scatter.point_entries(p).map(|(i, n, _)| (n, t[i]))))
        .collect()
}

/// Conduction heat rates `R_I` (W) of the particles' temperatures `t` (step 2 of the
/// module doc), each point conducting at `k(p)` (W/(m K)), with `F` of the displacement
/// `deformed` (m; with `F_33` in axisymmetry), or `F = I` without one.
fn conduction_rates<const D: usize>(
    body: &Body<'_, D>,
    t: &[Real],
    k: impl Fn(usize) -> Real,
    deformed: Option<&[[Real; D]]>,
) -> Vec<Real>
where
    Dim<D>: Conduct<D>,
{
    let mut rates = vec![0.0; t.len()];
    for p in 0..body.weights.len() {
        let (mut g, mut ur) = ([0.0; D], 0.0);
        let mut f: [[Real; D]; D] =
            std::array::from_fn(|a| std::array::from_fn(|b| if a == b { 1.0 } else { 0.0 }));
        for (i, n, grad) in body.scatter.point_entries(p) {
            for (g, nk) in g.iter_mut().zip(grad) {
                *g += t[i] * nk;
            }
            if let Some(d) = deformed {
                let d = d[i];
                for (row, da) in f.iter_mut().zip(d) {
                    for (fab, nb) in row.iter_mut().zip(grad) {
                        *fab += da * nb;
                    }
                }
                ur += n * d[0];
            }
        }
        let f33 = match (body.hoop, deformed) {
            (Some(inv_radius), Some(_)) => 1.0 + ur * inv_radius[p],
            _ => 1.0,
        };
        let (det, c_inv_g) = Dim::<D>::pull_back(f, g);
        // The volume the point stands for now, `w_p J_ref J` (the weight is per original
        // volume; `J_ref` the Jacobian at the last re-reference, 1 without one); q = k J
        // C^-1 g.
        let kj = k(p) * det * f33 * body.weights[p] * body.reference_jacobian[p];
        let q = c_inv_g.map(|c| kj * c);
        for (i, _, grad) in body.scatter.point_entries(p) {
            rates[i] -= dot(grad, q);
        }
    }
    rates
}

/// Conduction's largest eigenvalue `lambda_max(C^-1 K)` (1/s) on the undeformed body, by
/// power iteration from a checkerboard of the particles (`colour` one or the other: the
/// shortest wave the grid carries); 0 without conduction.
pub(super) fn eigenvalue<const D: usize>(
    body: &Body<'_, D>,
    thermal: &Thermal,
    colour: impl Fn(usize) -> bool,
    step: u64,
    time: Real,
) -> Result<Real>
where
    Dim<D>: Conduct<D>,
{
    // The largest conductivity the table holds: the stable step's bound for any
    // temperature.
    let k = thermal.spec.conductivity_max();
    if k == 0.0 {
        return Ok(0.0);
    }
    // The least capacity: the stable step's bound for any temperature.
    let least = thermal.capacity.least();
    let cap: Vec<Real> = thermal_masses(body, thermal.density, step, time)?
        .iter()
        .map(|m| m * least)
        .collect();
    let mut v: Vec<Real> = (0..cap.len())
        .map(|j| if colour(j) { 1.0 } else { -1.0 })
        .collect();
    let mut lambda = 0.0;
    for _ in 0..POWER_ITERATIONS {
        // A v = -C^-1 R(v); Rayleigh quotient in the C inner product.
        let r = conduction_rates(body, &v, |_| k, None);
        let av: Vec<Real> = r.iter().zip(&cap).map(|(r, c)| -r / c).collect();
        let num: Real = av
            .iter()
            .zip(&v)
            .zip(&cap)
            .map(|((a, v), c)| a * v * c)
            .sum();
        let den: Real = v.iter().zip(&cap).map(|(v, c)| v * v * c).sum();
        lambda = num / den;
        let norm = av.iter().map(|a| a * a).sum::<Real>().sqrt();
        if norm.is_nan() || norm <= 0.0 {
            break;
        }
        v = av.iter().map(|a| a / norm).collect();
    }
    Ok(lambda)
}

/// A heat stage that is due, on a body of dimension `D` whose points keep histories `P`:
/// what it reads besides the heat state.
pub(super) struct Stage<'a, const D: usize, P, S> {
    pub body: Body<'a, D>,
    pub thermal: &'a Thermal,
    /// The scene tools' heat contact, in the scene's order.
    pub tools: Vec<HeatContact<'a>>,
    /// The surface's [`Patch`]es in the current configuration, asked once per stage.
    pub surface: S,
    /// Conduction's largest eigenvalue on the undeformed body (1/s, [`eigenvalue`]).
    pub lambda0: Real,
    /// Displacement coefficients (m).
    pub d: &'a [[Real; D]],
    /// The points' histories (their plastic strains for the flow stresses).
    pub points: &'a [P],
    pub step: u64,
    /// Time (s).
    pub time: Real,
    /// The mechanical stable step estimate now (s).
    pub stable_dt: Real,
}

impl<const D: usize, P: PlasticStrain, S: Fn() -> Vec<Patch>> Stage<'_, D, P, S>
where
    Dim<D>: Conduct<D>,
{
    /// The heat stage over the `elapsed` time (s) since the last ([`due`]).
    pub(super) fn run(&self, heat: &mut Heat, out: &mut [PointOut], elapsed: Real) -> Result<()> {
        let mass = thermal_masses(&self.body, self.thermal.density, self.step, self.time)?;
        self.gather_point_heat(heat, &mass);
        // The mean normal contact force on each particle since the last stage (N).
        let normal_force: Vec<Real> = heat
            .normal_impulse
            .iter_mut()
            .map(|i| std::mem::take(i) / elapsed)
            .collect();
        let patches = (self.surface)();
        let before = (!heat.stage_change_k.is_empty()).then(|| heat.temperature_c.clone());
        let mut done = 0.0;
        while done < elapsed {
            done += self.heat_step(heat, out, elapsed - done, &mass, &normal_force, &patches)?;
        }
        // The stage's change at each point, for the elasticity over temperature to ramp in.
        if let Some(before) = before {
            for ((c, t), b) in heat
                .stage_change_k
                .iter_mut()
                .zip(&heat.temperature_c)
                .zip(before)
            {
                *c = t - b;
            }
        }
        Ok(())
    }

    /// What the points gained since the last heat stage (plastic work), the heat `dQ_p =
    /// rho_0 w_p (h(T_p) - h(sum_I N_I T_I))` (J; `rho_0 c w_p dT_p` for a constant
    /// capacity), into the particles: `Q_I = sum_p N_I dQ_p`, the heat kept exactly; with
    /// the workpiece's share of the friction work done at each particle since then, `Q_J +=
    /// phi W_J`; each particle heated by `Q_I / M_I` (J/kg).
    fn gather_point_heat(&self, heat: &mut Heat, mass: &[Real]) {
        let (body, capacity) = (&self.body, &self.thermal.capacity);
        let base = at_points(body, capacity, &heat.particle_c);
        let rho = self.thermal.density;
        let mut gain = vec![0.0; mass.len()];
        for (p, (&w, (&t, b))) in body
            .weights
            .iter()
            .zip(heat.temperature_c.iter().zip(base))
            .enumerate()
        {
            let dq = rho * w * capacity.heat_between(b, t);
            for (i, n, _) in body.scatter.point_entries(p) {
                gain[i] += n * dq;
            }
        }
        let share = self.thermal.spec.friction_heat_to_workpiece;
        // Friction work at the tools since the last stage, the workpiece's share at the
        // particles where it was done.
        for (g, w) in gain.iter_mut().zip(&mut heat.friction_work) {
            heat.friction_heat_j += *w;
            *g += share * std::mem::take(w);
        }
        for ((t, g), m) in heat.particle_c.iter_mut().zip(gain).zip(mass) {
            *t = capacity.heat(*t, g / m);
        }
    }

    /// The surface flows (W) into each surface particle of `patches` (step 3 of the module
    /// doc) at the particles' temperatures `t`, with the heat flow into each tool (W, the
    /// negative of what the workpiece gains from it) and into the surroundings (W), and the
    /// surface's stable step bound `min M_I c(T_I) / (h A_I)` (s). `normal_force` (N, by
    /// particle; empty unless a tool's transfer coefficient depends on pressure) is each
    /// particle's mean normal contact force since the last heat stage: over the particle's
    /// contact area it is the pressure the coefficient is read at.
    fn surface_flows(
        &self,
        patches: &[Patch],
        t: &[Real],
        mass: &[Real],
        normal_force: &[Real],
    ) -> SurfaceFlows {
        let (nodal, capacity, spec) = (self.body.nodal, &self.thermal.capacity, &self.thermal.spec);
        let mut out = SurfaceFlows {
            into: vec![0.0; patches.len()],
            tools: vec![0.0; self.tools.len()],
            surroundings: 0.0,
            step_bound: Real::INFINITY,
        };
        let (ambient, ambient_k) = (
            spec.ambient_temperature_c,
            kelvin(spec.ambient_temperature_c),
        );
        for (
            k,
            &Patch {
                j,
                area,
                contact,
                tool,
            },
        ) in patches.iter().enumerate()
        {
            if area == 0.0 {
                continue;
            }
            // The field's temperature at the particle, `sum_I N_I(X_J) T_I`.
            let tj = capacity.interpolate(
                nodal
                    .row(j)
                    .map(|e| (nodal.n[e], t[nodal.index[e] as usize])),
            );
            let free = (area - contact).max(0.0);
            let tk = kelvin(tj);
            let radiation = spec.emissivity * STEFAN_BOLTZMANN;
            let mut flow = spec.convection_w_per_m2_k * free * (ambient - tj)
                + radiation * free * (ambient_k.powi(4) - tk.powi(4));
            out.surroundings -= flow;
            let linear = 4.0 * radiation * tk.max(ambient_k).powi(3);
            let mut conductance = (spec.convection_w_per_m2_k + linear) * free;
            if let Some(tt) = tool {
                let tool = &self.tools[tt];
                let force = normal_force.get(j).copied().unwrap_or(0.0);
                let h = tool.heat_transfer_at(if contact > 0.0 { force / contact } else { 0.0 });
                let to_tool = h * contact * (tool.temperature_c.unwrap_or(tj) - tj);
                out.tools[tt] -= to_tool;
                flow += to_tool;
                conductance += h * contact;
            }
            out.into[k] = flow;
            if conductance > 0.0 {
                out.step_bound = out
                    .step_bound
                    .min(mass[j] * capacity.at(t[j]) / conductance);
            }
        }
        out
    }

    /// One heat step of at most `at_most` (s), the rest of the elapsed time (steps 1-4 of
    /// the module doc): returns the step taken, the stable step's share of it when that is
    /// shorter. Updates the heat step for the next trigger and the yield test's flow
    /// stresses of the laws of temperature in `out`.
    fn heat_step(
        &self,
        heat: &mut Heat,
        out: &mut [PointOut],
        at_most: Real,
        mass: &[Real],
        normal_force: &[Real],
        patches: &[Patch],
    ) -> Result<Real> {
        let (body, spec, capacity) = (&self.body, &self.thermal.spec, &self.thermal.capacity);
        let t = &heat.particle_c;
        let mut rates = if spec.conductivity_max() > 0.0 {
            let temps = &heat.temperature_c;
            conduction_rates(body, t, |p| spec.conductivity_at(temps[p]), Some(self.d))
        } else {
            vec![0.0; t.len()]
        };
        let surface = self.surface_flows(patches, t, mass, normal_force);
        for (patch, into) in patches.iter().zip(&surface.into) {
            rates[patch.j] += into;
        }
        // Conduction's bound at this deformation: 2 / lambda, lambda ~ 1 / h_min^2.
        let shrink = body.critical_dt0 / self.stable_dt.max(Real::MIN_POSITIVE);
        let lambda = self.lambda0 * shrink * shrink;
        let conduction = if lambda > 0.0 {
            2.0 / lambda
        } else {
            Real::INFINITY
        };
        let stable = spec.dt_safety * conduction.min(surface.step_bound);
        let dt = at_most.min(stable);
        if dt.is_nan() || dt <= 0.0 {
            return Err(Error::Diverged {
                step: self.step,
                time: self.time,
                what: format!("heat step {dt:.3e} s is not positive"),
            });
        }
        let mut particle = t.clone();
        let mut largest: Real = 0.0;
        for ((t, r), m) in particle.iter_mut().zip(&rates).zip(mass) {
            let heated = capacity.heat(*t, dt * r / m);
            largest = largest.max((heated - *t).abs());
            *t = heated;
        }
        // The next step: this one scaled by how far the largest change stayed below the
        // accuracy limit, at most doubled or halved, within the stable step.
        let growth = if largest > 0.0 {
            (spec.max_change_per_step_k / largest).clamp(0.5, 2.0)
        } else {
            2.0
        };
        let points = at_points(body, capacity, &particle);
        heat.particle_c = particle;
        heat.temperature_c = points;
        for (total, flow) in heat.to_tools_j.iter_mut().zip(&surface.tools) {
            *total += dt * flow;
        }
        heat.tool_flow_w = surface.tools;
        heat.to_surroundings_j += dt * surface.surroundings;
        heat.step_s = (growth * dt).min(stable);
        if let Some(bad) = heat.temperature_c.iter().position(|t| !t.is_finite()) {
            return Err(Error::Diverged {
                step: self.step,
                time: self.time,
                what: format!(
                    "temperature of integration point {bad} at {:?} m is not finite",
                    body.point_positions[bad]
                ),
            });
        }
        if body.hardening.is_thermal() {
            for (p, out) in out.iter_mut().enumerate() {
                out.flow_stress = body
                    .hardening
                    .flow(self.points[p].eps_p(), 0.0, heat.temperature_c[p])
                    .stress;
            }
        }
        Ok(dt)
    }
}

/// What [`Stage::surface_flows`] returns.
struct SurfaceFlows {
    /// Heat flow into each surface particle (W), in the order of the patches.
    into: Vec<Real>,
    /// Heat flow into each tool (W).
    tools: Vec<Real>,
    /// Heat flow into the surroundings (W).
    surroundings: Real,
    /// `min C_I / (h A_I)` over the surface (s).
    step_bound: Real,
}
