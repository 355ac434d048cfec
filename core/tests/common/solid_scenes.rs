//! 3D scenes written in code: the start of a box scene's text that the tests complete with
//! their `[time]` section and tools.

/// The `[material]` keys of an aluminium: 2700 kg/m^3, E 70 GPa, nu 0.33, linear hardening
/// from 100 MPa by 500 MPa.
pub const ALUMINIUM: &str = r#"density_kg_per_m3 = 2700.0
youngs_modulus_pa = 70e9
poisson_ratio = 0.33
hardening = { law = "linear", yield_stress_pa = 100e6, modulus_pa = 500e6 }"#;

/// The start of the text of the 3D scene `name` whose workpiece is a box at the origin,
/// `size_m` (m) with `particles` along x, y and z, its faces `symmetry` (`"x_min"`,
/// `"y_min"`, `"z_min"`; none, no key) on symmetry planes, of the `material` (the
/// `[material]` keys) integrated by the rule `integration`: its `[model]`, `[workpiece]`,
/// `[material]` and `[discretization]`. The `[time]` section, the tools and any other
/// sections follow.
pub fn box_scene(
    name: &str,
    size_m: [f64; 3],
    particles: [usize; 3],
    symmetry: &[&str],
    material: &str,
    integration: &str,
) -> String {
    let symmetry = match symmetry {
        [] => String::new(),
        faces => format!("symmetry = {faces:?}\n"),
    };
    format!(
        r#"
name = "{name}"
[model]
kinematics = "3d"
[workpiece]
shape = "box"
origin_m = [0.0, 0.0, 0.0]
size_m = {size_m:?}
particles = {particles:?}
{symmetry}[material]
{material}
[discretization]
integration = "{integration}"
"#
    )
}
