//! Scene validation: every value a run cannot use, named by its dotted key, checked in
//! named steps (identity, workpiece, material, discretisation, time, constraints, tools,
//! output and limits, mass scaling).

use crate::material::Hardening;
use crate::math::Real;
use crate::scene::*;
use crate::validation::{above_absolute_zero, increasing_table, is_name, pos, Checks};

impl Scene {
    /// Every non-physical or inconsistent value, as (key path, message), in the order of
    /// the steps below.
    pub fn validate(&self) -> Vec<(String, String)> {
        let mut out = Checks::default();
        self.check_identity(&mut out);
        self.check_workpiece(&mut out);
        self.check_material(&mut out);
        self.check_thermal(&mut out);
        self.check_discretization(&mut out);
        self.check_time(&mut out);
        self.check_constraints(&mut out);
        self.check_self_contact(&mut out);
        self.check_tools(&mut out);
        self.check_output_and_limits(&mut out);
        self.check_mass_scaling(&mut out);
        out.0
    }

    /// The scene's name and the model's depth.
    fn check_identity(&self, out: &mut Checks) {
        out.check(
            !self.name.is_empty()
                && self
                    .name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-'),
            "name",
            format!(
                "`{}` must be non-empty and use only letters, digits, `_` and `-`",
                self.name
            ),
        );
        out.check(
            pos(self.model.depth_m),
            "model.depth_m",
            format!("must be positive, got {}", self.model.depth_m),
        );
    }

    /// The workpiece's placement, size, particles and initial velocity.
    fn check_workpiece(&self, out: &mut Checks) {
        let w = &self.workpiece;
        for k in 0..2 {
            out.check(
                w.origin_m[k].is_finite(),
                "workpiece.origin_m",
                format!("must be finite, got {:?}", w.origin_m),
            );
            out.check(
                pos(w.size_m[k]),
                "workpiece.size_m",
                format!("both sizes must be positive, got {:?}", w.size_m),
            );
            out.check(
                w.particles[k] >= 2,
                "workpiece.particles",
                format!(
                    "need at least 2 particles in each direction, got {:?}",
                    w.particles
                ),
            );
            out.check(
                w.initial_velocity_m_per_s[k].is_finite(),
                "workpiece.initial_velocity_m_per_s",
                format!("must be finite, got {:?}", w.initial_velocity_m_per_s),
            );
        }
        out.check(
            w.particles[0].saturating_mul(w.particles[1]) <= 4_000_000,
            "workpiece.particles",
            format!("{:?} is more than 4 million particles", w.particles),
        );
        if self.model.kinematics == Kinematics::Axisymmetric {
            out.check(
                w.origin_m[0] >= 0.0,
                "workpiece.origin_m",
                format!(
                    "an axisymmetric workpiece must lie at r >= 0, got r = {}",
                    w.origin_m[0]
                ),
            );
            out.check(
                w.initial_velocity_m_per_s[0] == 0.0 || w.origin_m[0] > 0.0,
                "workpiece.initial_velocity_m_per_s",
                "a workpiece on the axis cannot have a radial initial velocity".into(),
            );
        }
    }

    /// Density, elastic constants and the hardening law.
    fn check_material(&self, out: &mut Checks) {
        let m = &self.material;
        out.check(
            pos(m.density_kg_per_m3),
            "material.density_kg_per_m3",
            format!("must be positive, got {}", m.density_kg_per_m3),
        );
        out.check(
            pos(m.youngs_modulus_pa),
            "material.youngs_modulus_pa",
            format!("must be positive, got {}", m.youngs_modulus_pa),
        );
        out.check(
            m.poisson_ratio.is_finite() && m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5,
            "material.poisson_ratio",
            format!("must lie in (-1, 0.5), got {}", m.poisson_ratio),
        );
        match m.hardening {
            Hardening::Linear {
                yield_stress_pa,
                modulus_pa,
            } => {
                out.check(
                    pos(yield_stress_pa),
                    "material.hardening.yield_stress_pa",
                    format!("must be positive, got {yield_stress_pa}"),
                );
                out.check(
                    modulus_pa.is_finite() && modulus_pa >= 0.0,
                    "material.hardening.modulus_pa",
                    format!("must be zero or positive, got {modulus_pa}"),
                );
            }
            Hardening::JohnsonCook { .. }
            | Hardening::HenselSpittel { .. }
            | Hardening::SellarsTegart { .. }
            | Hardening::Table { .. } => check_rate_temperature_law(&m.hardening, out),
            Hardening::Power { k_pa, eps0, n } => {
                out.check(
                    pos(k_pa),
                    "material.hardening.k_pa",
                    format!("must be positive, got {k_pa}"),
                );
                out.check(
                    pos(eps0),
                    "material.hardening.eps0",
                    format!("must be positive, got {eps0}"),
                );
                out.check(
                    n.is_finite() && (0.0..1.0).contains(&n),
                    "material.hardening.n",
                    format!("must lie in [0, 1), got {n}"),
                );
            }
        }
    }

    /// The `[thermal]` section ([`ThermalSpec::check`]), what the tools' heat transfer
    /// needs, and that a law of rate and temperature has one.
    fn check_thermal(&self, out: &mut Checks) {
        let Some(t) = &self.thermal else {
            out.check(
                !self.material.hardening.is_thermal(),
                "material.hardening.law",
                "a flow stress of rate and temperature needs the [thermal] section \
                 (initial_temperature_c, specific_heat_j_per_kg_k)"
                    .into(),
            );
            for tool in &self.tools {
                out.check(
                    tool.temperature_c.is_none() && tool.heat_transfer_w_per_m2_k == 0.0,
                    &format!("tools.{}.temperature_c", tool.name),
                    "a tool's temperature and heat transfer need the [thermal] section".into(),
                );
            }
            return;
        };
        t.check(out);
        for tool in &self.tools {
            let key = |k: &str| format!("tools.{}.{k}", tool.name);
            if let Some(temp) = tool.temperature_c {
                out.check(
                    above_absolute_zero(temp),
                    &key("temperature_c"),
                    format!("must be above absolute zero (-273.15), got {temp}"),
                );
            }
            let h = tool.heat_transfer_w_per_m2_k;
            out.check(
                h.is_finite() && h >= 0.0,
                &key("heat_transfer_w_per_m2_k"),
                format!("must be zero or positive, got {h}"),
            );
            let table = &tool.heat_transfer_by_pressure;
            out.check(
                table.is_empty() || h == 0.0,
                &key("heat_transfer_by_pressure"),
                "give the heat transfer coefficient as a constant or as a table over pressure, \
                 not both"
                    .into(),
            );
            out.check(
                increasing_table(table, |h| h >= 0.0),
                &key("heat_transfer_by_pressure"),
                format!(
                    "must be [[p (Pa), h (W/(m^2 K))], ...] with p increasing and h zero or \
                     positive, got {table:?}"
                ),
            );
            out.check(
                !tool.transfers_heat() || tool.temperature_c.is_some(),
                &key("heat_transfer_w_per_m2_k"),
                format!(
                    "heat transfer to tool {} needs its temperature_c",
                    tool.name
                ),
            );
        }
    }

    /// Kernel support and re-referencing.
    fn check_discretization(&self, out: &mut Checks) {
        for k in 0..2 {
            let s = self.discretization.support[k];
            out.check(
                s.is_finite() && (1.05..=4.0).contains(&s),
                "discretization.support",
                format!("support radii must lie in [1.05, 4] particle spacings (a linear basis needs more than 1), got {:?}", self.discretization.support),
            );
        }
        if let Some(s) = self.discretization.rereference_stretch {
            out.check(
                s.is_finite() && (1.1..=10.0).contains(&s),
                "discretization.rereference_stretch",
                format!("must lie in [1.1, 10] (a principal stretch), got {s}"),
            );
            out.check(
                self.discretization.integration != IntegrationRule::Scni,
                "discretization.rereference_stretch",
                "re-referencing works with the cell rules q2 and q4; scni's nodal domains are not rebuilt on the deformed particles".into(),
            );
        }
        if let Some(c) = self.discretization.scni_stabilization {
            out.check(
                c.is_finite() && (0.0..=1.0).contains(&c),
                "discretization.scni_stabilization",
                format!("must lie in [0, 1] (a fraction of the shear modulus), got {c}"),
            );
        }
    }

    /// End time, fixed step and step safety factor.
    fn check_time(&self, out: &mut Checks) {
        let t = &self.time;
        out.check(
            pos(t.end_s),
            "time.end_s",
            format!("must be positive, got {}", t.end_s),
        );
        if let Some(dt) = t.dt_s {
            out.check(pos(dt), "time.dt_s", format!("must be positive, got {dt}"));
            out.check(
                !pos(dt) || !pos(t.end_s) || t.end_s / dt <= 1e9,
                "time.dt_s",
                format!("{dt} s gives more than 1e9 steps"),
            );
        }
        out.check(
            t.dt_safety.is_finite() && t.dt_safety > 0.0 && t.dt_safety <= 1.0,
            "time.dt_safety",
            format!("must lie in (0, 1], got {}", t.dt_safety),
        );
    }

    /// Each essential condition names a component.
    fn check_constraints(&self, out: &mut Checks) {
        for (i, c) in self.constraints.iter().enumerate() {
            out.check(
                !c.fix.is_empty(),
                &format!("constraints[{i}].fix"),
                "names no component".into(),
            );
        }
    }

    /// The self-contact's friction law.
    fn check_self_contact(&self, out: &mut Checks) {
        for (suffix, message) in self.self_contact.friction.validate() {
            out.check(false, &format!("self_contact.friction{suffix}"), message);
        }
    }

    /// Each tool: name, geometry, friction, motion, fill points.
    fn check_tools(&self, out: &mut Checks) {
        let mut names = std::collections::BTreeSet::new();
        for (i, tool) in self.tools.iter().enumerate() {
            let key = |k: &str| format!("tools[{i}].{k}");
            out.check(
                is_name(&tool.name),
                &key("name"),
                format!(
                    "`{}` must be non-empty and use only letters, digits and `_`",
                    tool.name
                ),
            );
            out.check(
                names.insert(tool.name.clone()),
                &key("name"),
                format!("`{}` is used by two tools", tool.name),
            );
            out.check(
                tool.points_m.len() >= 2,
                &key("points_m"),
                format!(
                    "a tool needs at least 2 points, got {}",
                    tool.points_m.len()
                ),
            );
            out.check(
                tool.points_m
                    .iter()
                    .all(|p| p[0].is_finite() && p[1].is_finite()),
                &key("points_m"),
                "all coordinates must be finite".into(),
            );
            out.check(
                tool.points_m.windows(2).all(|s| s[0] != s[1]),
                &key("points_m"),
                "two consecutive points coincide (a zero-length segment)".into(),
            );
            let an = (tool.axis[0] * tool.axis[0] + tool.axis[1] * tool.axis[1]).sqrt();
            out.check(
                (an - 1.0).abs() < 1e-6,
                &key("axis"),
                format!("must be a unit vector, got {:?} (length {an})", tool.axis),
            );
            for (suffix, message) in tool.friction.validate() {
                out.check(false, &key(&format!("friction{suffix}")), message);
            }
            let mut points = std::collections::BTreeSet::new();
            for (k, f) in tool.fill_points.iter().enumerate() {
                out.check(
                    is_name(&f.name) && points.insert(f.name.clone()),
                    &key(&format!("fill_points[{k}].name")),
                    format!("`{}` must be a new name of letters, digits and `_`", f.name),
                );
                out.check(
                    f.at_m.iter().all(|c| c.is_finite()),
                    &key(&format!("fill_points[{k}].at_m")),
                    "must be finite".into(),
                );
            }
            match &tool.motion {
                Motion::Fixed => {}
                Motion::Constant { velocity_m_per_s } => out.check(
                    velocity_m_per_s.is_finite(),
                    &key("motion.velocity_m_per_s"),
                    "must be finite".into(),
                ),
                Motion::Table { points } => {
                    out.check(
                        !points.is_empty(),
                        &key("motion.points"),
                        "needs at least one (t, v) point".into(),
                    );
                    out.check(
                        points.iter().all(|p| p[0].is_finite() && p[1].is_finite()),
                        &key("motion.points"),
                        "all values must be finite".into(),
                    );
                    out.check(
                        points.windows(2).all(|p| p[1][0] > p[0][0]),
                        &key("motion.points"),
                        "times must increase strictly".into(),
                    );
                }
                Motion::External {
                    initial_velocity_m_per_s,
                } => out.check(
                    initial_velocity_m_per_s.is_finite(),
                    &key("motion.initial_velocity_m_per_s"),
                    "must be finite".into(),
                ),
            }
        }
    }

    /// History interval, fill distance and the run's checks.
    fn check_output_and_limits(&self, out: &mut Checks) {
        if let Some(h) = self.output.history_interval_s {
            out.check(
                pos(h)
                    && (self.time.end_s.is_nan()
                        || self.time.end_s / h <= crate::sampling::MAX_SAMPLES as Real),
                "output.history_interval_s",
                format!(
                    "must be positive and give at most {} samples over time.end_s, got {h}",
                    crate::sampling::MAX_SAMPLES
                ),
            );
        }
        out.check(
            self.checks.energy_balance_tol.is_finite() && self.checks.energy_balance_tol > 0.0,
            "checks.energy_balance_tol",
            format!("must be positive, got {}", self.checks.energy_balance_tol),
        );
        if let Some(r) = self.checks.kinetic_to_internal_max {
            out.check(
                pos(r),
                "checks.kinetic_to_internal_max",
                format!("must be positive, got {r}"),
            );
        }
        let fill = self.output.fill_distance_rel;
        out.check(
            pos(fill),
            "output.fill_distance_rel",
            format!("must be positive, got {fill}"),
        );
        if let Some(n) = self.output.pressure_stations {
            out.check(
                (1..=10_000).contains(&n),
                "output.pressure_stations",
                format!("must lie in [1, 10000], got {n}"),
            );
        }
        let pen = self.checks.max_penetration_rel;
        out.check(
            pos(pen),
            "checks.max_penetration_rel",
            format!("must be positive, got {pen}"),
        );
        let from = self.checks.kinetic_to_internal_from;
        out.check(
            (0.0..1.0).contains(&from),
            "checks.kinetic_to_internal_from",
            format!("must lie in [0, 1), got {from}"),
        );
    }

    /// One of a uniform factor or a target step.
    fn check_mass_scaling(&self, out: &mut Checks) {
        if let Some(ms) = self.time.mass_scaling {
            match (ms.factor, ms.target_dt_s) {
                (Some(f), None) => out.check(
                    f.is_finite() && f >= 1.0,
                    "time.mass_scaling.factor",
                    format!("must be at least 1, got {f}"),
                ),
                (None, Some(dt)) => out.check(
                    pos(dt),
                    "time.mass_scaling.target_dt_s",
                    format!("must be positive, got {dt}"),
                ),
                _ => out.check(
                    false,
                    "time.mass_scaling",
                    "give one of `factor` (uniform) or `target_dt_s` (selective)".into(),
                ),
            }
        }
    }
}

/// A law of rate and temperature: finite constants in their ranges, increasing table axes.
fn check_rate_temperature_law(law: &Hardening, out: &mut Checks) {
    let key = |k: &str| format!("material.hardening.{k}");
    let increasing =
        |v: &[Real]| v.windows(2).all(|w| w[0] < w[1]) && v.iter().all(|x| x.is_finite());
    // A fitted range of a positive quantity (strain, strain rate).
    let positive_range = |out: &mut Checks, name: &str, range: &[Real; 2]| {
        out.check(
            pos(range[0]) && increasing(range),
            &key(name),
            format!("must be [least, largest] with 0 < least < largest, got {range:?}"),
        );
    };
    match law {
        Hardening::JohnsonCook {
            a_pa,
            b_pa,
            n,
            c,
            reference_strain_rate_per_s,
            m,
            reference_temperature_c,
            melting_temperature_c,
        } => {
            for (name, v) in [("a_pa", a_pa), ("b_pa", b_pa), ("n", n), ("c", c)] {
                out.check(
                    v.is_finite() && *v >= 0.0,
                    &key(name),
                    format!("must be zero or positive, got {v}"),
                );
            }
            out.check(
                pos(*a_pa + *b_pa),
                &key("a_pa"),
                "A + B must be positive".into(),
            );
            out.check(
                pos(*reference_strain_rate_per_s),
                &key("reference_strain_rate_per_s"),
                format!("must be positive, got {reference_strain_rate_per_s}"),
            );
            out.check(pos(*m), &key("m"), format!("must be positive, got {m}"));
            out.check(
                reference_temperature_c.is_finite()
                    && melting_temperature_c.is_finite()
                    && melting_temperature_c > reference_temperature_c,
                &key("melting_temperature_c"),
                format!(
                    "must be above reference_temperature_c ({reference_temperature_c}), got {melting_temperature_c}"
                ),
            );
        }
        Hardening::HenselSpittel {
            a_pa,
            m1,
            m2,
            m3,
            m4,
            m5,
            m7,
            m8,
            m9,
            strain_range,
            strain_rate_range_per_s,
            temperature_range_c,
        } => {
            out.check(
                pos(*a_pa),
                &key("a_pa"),
                format!("must be positive, got {a_pa}"),
            );
            for (name, v) in [
                ("m1", m1),
                ("m2", m2),
                ("m3", m3),
                ("m4", m4),
                ("m5", m5),
                ("m7", m7),
                ("m8", m8),
                ("m9", m9),
            ] {
                out.check(
                    v.is_finite(),
                    &key(name),
                    format!("must be finite, got {v}"),
                );
            }
            positive_range(out, "strain_range", strain_range);
            positive_range(out, "strain_rate_range_per_s", strain_rate_range_per_s);
            out.check(
                increasing(temperature_range_c) && (*m9 == 0.0 || temperature_range_c[0] > 0.0),
                &key("temperature_range_c"),
                format!(
                    "must be [least, largest] with least < largest (and least > 0 with m9 set), got {temperature_range_c:?}"
                ),
            );
        }
        Hardening::SellarsTegart {
            alpha_per_pa,
            n,
            activation_energy_j_per_mol,
            a_per_s,
            strain_rate_range_per_s,
            temperature_range_c,
        } => {
            for (name, v) in [
                ("alpha_per_pa", alpha_per_pa),
                ("n", n),
                ("activation_energy_j_per_mol", activation_energy_j_per_mol),
                ("a_per_s", a_per_s),
            ] {
                out.check(pos(*v), &key(name), format!("must be positive, got {v}"));
            }
            positive_range(out, "strain_rate_range_per_s", strain_rate_range_per_s);
            out.check(
                increasing(temperature_range_c) && above_absolute_zero(temperature_range_c[0]),
                &key("temperature_range_c"),
                format!(
                    "must be [least, largest] above absolute zero with least < largest, got {temperature_range_c:?}"
                ),
            );
        }
        Hardening::Table {
            strains,
            strain_rates_per_s,
            temperatures_c,
            flow_stress_pa,
        } => {
            for (name, axis) in [
                ("strains", strains),
                ("strain_rates_per_s", strain_rates_per_s),
                ("temperatures_c", temperatures_c),
            ] {
                out.check(
                    !axis.is_empty() && increasing(axis),
                    &key(name),
                    format!("must be one or more increasing values, got {axis:?}"),
                );
            }
            out.check(
                strain_rates_per_s.iter().all(|&r| pos(r)),
                &key("strain_rates_per_s"),
                "every rate must be positive".into(),
            );
            let cells = strains.len() * strain_rates_per_s.len() * temperatures_c.len();
            out.check(
                flow_stress_pa.len() == cells,
                &key("flow_stress_pa"),
                format!(
                    "needs {} x {} x {} = {cells} values (strains x rates x temperatures), got {}",
                    strains.len(),
                    strain_rates_per_s.len(),
                    temperatures_c.len(),
                    flow_stress_pa.len()
                ),
            );
            if let Some(i) = flow_stress_pa.iter().position(|&s| !pos(s)) {
                out.check(
                    false,
                    &key("flow_stress_pa"),
                    format!("entry {i} must be positive, got {}", flow_stress_pa[i]),
                );
            }
        }
        Hardening::Linear { .. } | Hardening::Power { .. } => {}
    }
}
