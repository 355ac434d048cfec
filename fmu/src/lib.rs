//! The safe co-simulation layer of the rkforge FMU: an instance that owns one simulation,
//! reads and writes variables through the scene's variable table, and advances between
//! communication points, sub-cycling at the solver's stable step.

use rkforge_core::{Error, Kinematics, Result, Scene, Simulation};
use rkforge_model_description::{variable_table, Binding, Causality, Variable};

/// One co-simulation instance.
pub struct Instance {
    table: Vec<Variable>,
    sim: Simulation,
}

impl Instance {
    /// Set up the simulation of a validated scene.
    pub fn new(scene: &Scene) -> Result<Instance> {
        Ok(Instance {
            table: variable_table(scene),
            sim: Simulation::new(scene)?,
        })
    }

    /// The variable table.
    pub fn variables(&self) -> &[Variable] {
        &self.table
    }

    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.sim.time()
    }

    /// The simulation.
    pub fn simulation(&self) -> &Simulation {
        &self.sim
    }

    fn variable(&self, vr: u32) -> Result<&Variable> {
        self.table
            .get(vr as usize)
            .ok_or_else(|| Error::Request(format!("unknown value reference {vr}")))
    }

    /// Read a real variable.
    pub fn get_real(&self, vr: u32) -> Result<f64> {
        let v = self.variable(vr)?;
        let tools = self.sim.tools();
        Ok(match v.binding {
            Binding::ToolVelocity(k) => tools[k].velocity_at(self.sim.time()),
            Binding::ToolForce(k) => tools[k].axial_force(),
            Binding::ToolStroke(k) => tools[k].state.stroke,
            Binding::WorkpieceLateral => {
                let e = self.sim.extents();
                match self.sim.scene().model.kinematics {
                    Kinematics::Axisymmetric => e.x[1],
                    Kinematics::PlaneStrain => e.x[1] - e.x[0],
                }
            }
            Binding::WorkpieceHeight => {
                let e = self.sim.extents();
                e.y[1] - e.y[0]
            }
            Binding::MaxPlasticStrain => self.sim.max_plastic_strain(),
            Binding::KineticEnergy => self.sim.energy().kinetic,
            Binding::PlasticEnergy => self.sim.energy().plastic,
            Binding::DtSafety => self.sim.scene().time.dt_safety,
            Binding::Friction(k) => tools[k].friction,
            Binding::Integration | Binding::ParticlesX | Binding::ParticlesY => {
                return Err(Error::Request(format!(
                    "`{}` is not a Real variable",
                    v.name
                )))
            }
        })
    }

    /// Write a real input: a tool velocity (m/s). Parameters are fixed once the instance exists.
    pub fn set_real(&mut self, vr: u32, value: f64) -> Result<()> {
        let v = self.variable(vr)?;
        match (v.causality, v.binding) {
            (Causality::Input, Binding::ToolVelocity(k)) => self.sim.set_tool_velocity(k, value),
            _ => Err(Error::Request(format!(
                "`{}` cannot be set during the simulation",
                v.name
            ))),
        }
    }

    /// Advance from the communication point `t` (s) by `h` (s).
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<()> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(Error::Request(format!(
                "communication step {h} s must be positive and finite"
            )));
        }
        let now = self.sim.time();
        if (t - now).abs() > 1e-9 * h.max(now.abs()) {
            return Err(Error::Request(format!(
                "communication point {t} s does not match the instance time {now} s"
            )));
        }
        self.sim.run_to(now + h, |_| {})
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rkforge_core::scene::Motion;

    fn scene() -> Scene {
        let mut s = Scene::from_str_named(
            include_str!("../../scenes/taylor_bar.toml"),
            "taylor_bar.toml",
        )
        .unwrap();
        s.workpiece.particles = [7, 15];
        s.time.dt_s = None;
        s.tools[0].motion = Motion::External {
            initial_velocity_m_per_s: 0.0,
        };
        s
    }

    #[test]
    fn stroke_follows_the_velocity_input_and_force_appears() {
        let mut inst = Instance::new(&scene()).unwrap();
        let vr = |n: &str| {
            inst.variables()
                .iter()
                .find(|v| v.name == n)
                .unwrap()
                .value_reference
        };
        let (vel, stroke, force) = (vr("wall.velocity"), vr("wall.stroke"), vr("wall.force"));
        inst.set_real(vel, 2.0).unwrap();
        let h = 1e-6;
        for k in 0..5 {
            inst.do_step(k as f64 * h, h).unwrap();
        }
        assert!((inst.get_real(stroke).unwrap() - 2.0 * 5e-6).abs() < 1e-15);
        assert!(
            inst.get_real(force).unwrap() > 1e4,
            "the bar pushes the wall"
        );
    }

    #[test]
    fn bad_requests_are_errors() {
        let mut inst = Instance::new(&scene()).unwrap();
        assert!(inst.do_step(0.0, 0.0).is_err());
        assert!(inst.do_step(1.0, 1e-6).is_err());
        assert!(inst.get_real(9999).is_err());
        let vel = inst
            .variables()
            .iter()
            .find(|v| v.name == "wall.velocity")
            .unwrap()
            .value_reference;
        assert!(inst.set_real(vel, f64::NAN).is_err());
        let f = inst
            .variables()
            .iter()
            .find(|v| v.name == "wall.force")
            .unwrap()
            .value_reference;
        assert!(inst.set_real(f, 1.0).is_err());
    }
}
