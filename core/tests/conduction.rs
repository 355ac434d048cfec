//! Conduction and the heat that crosses the surface, against closed forms: a steady
//! one-dimensional profile through a block between two dies at different temperatures, and
//! a long bar set on a die at another temperature through a finite transfer coefficient
//! against the semi-infinite solution with surface resistance (Carslaw and Jaeger 1959,
//! section 2.7, eq. 2.7(1)). The bodies do not move (fixed dies touching them, the mass
//! scaled so that the mechanical step is not what the run waits on).

use rkforge_core::{Scene, Simulation, THERMAL_MEASURES};

/// Copper-like constants: k 400 W/(m K), rho 8960 kg/m^3, c 385 J/(kg K).
const K: f64 = 400.0;
const RHO_C: f64 = 8960.0 * 385.0;

/// A plane-strain block `width` x `height` (m) with `particles`, at `temps.0` (degrees C),
/// on a bottom die at `temps.1` and, when given, under a top die at `temps.2` (degrees C),
/// both with transfer coefficient `h` (W/(m^2 K)); the sides insulated; run to `end` (s).
fn block(
    size: [f64; 2],
    particles: [usize; 2],
    temps: (f64, f64, Option<f64>),
    h: f64,
    rule: &str,
    end: f64,
) -> Scene {
    let [w, ht] = size;
    let (t0, bottom, top) = temps;
    let top_tool = match top {
        Some(t) => format!(
            r#"
[[tools]]
name = "top"
points_m = [[{w2}, {ht}], [{mw}, {ht}]]
axis = [0.0, -1.0]
motion = {{ kind = "fixed" }}
temperature_c = {t}
heat_transfer_w_per_m2_k = {h}
"#,
            w2 = 2.0 * w,
            mw = -w
        ),
        None => String::new(),
    };
    let text = format!(
        r#"
name = "conduction"
[model]
kinematics = "plane_strain"
[workpiece]
origin_m = [0.0, 0.0]
size_m = [{w}, {ht}]
particles = [{}, {}]
[material]
density_kg_per_m3 = 8960.0
youngs_modulus_pa = 124.0e9
poisson_ratio = 0.34
hardening = {{ law = "linear", yield_stress_pa = 100.0e6, modulus_pa = 0.0 }}
[discretization]
integration = "{rule}"
[thermal]
initial_temperature_c = {t0}
specific_heat_j_per_kg_k = 385.0
conductivity_w_per_m_k = {K}
[time]
end_s = {end}
mass_scaling = {{ factor = 1.0e10 }}
[[tools]]
name = "bottom"
points_m = [[{mw}, 0.0], [{w2}, 0.0]]
axis = [0.0, 1.0]
motion = {{ kind = "fixed" }}
temperature_c = {bottom}
heat_transfer_w_per_m2_k = {h}
{top_tool}
"#,
        particles[0],
        particles[1],
        w2 = 2.0 * w,
        mw = -w
    );
    Scene::from_str_named(&text, "conduction.toml").unwrap()
}

/// Steady conduction through a 10 mm block (9 x 21 particles, 0.5 mm) between a die at 100 C
/// and one at 0 C, through
/// 2e5 W/(m^2 K) each: the flux `q = dT / (2 / h + L / k)` and the profile `T(y) = 100 - q
/// / h - q y / k`, the points' temperatures within 0.5 % of the 100 K across, with q2, q4
/// and SCNI; the heat into the cold die equals the heat out of the hot one at steady state.
#[test]
fn steady_profile_between_two_dies() {
    let (l, h) = (0.01, 2e5);
    let q = 100.0 / (2.0 / h + l / K);
    let tau = l * l * RHO_C / K;
    for rule in ["q2", "q4", "scni"] {
        let scene = block(
            [0.004, l],
            [9, 21],
            (50.0, 100.0, Some(0.0)),
            h,
            rule,
            6.0 * tau,
        );
        let mut sim = Simulation::new(&scene).unwrap();
        sim.run_to(scene.time.end_s, |_| {}).unwrap();
        let temps = sim.point_temperature().unwrap();
        let mut worst: f64 = 0.0;
        for (p, x) in sim.point_positions().iter().enumerate() {
            let exact = 100.0 - q / h - q * x[1] / K;
            worst = worst.max((temps[p] - exact).abs() / 100.0);
        }
        assert!(
            worst < 0.005,
            "{rule}: a point {:.3} % of the 100 K off the profile",
            100.0 * worst
        );
        // The heat account closes: content = made - lost (here nothing is made).
        let k = THERMAL_MEASURES
            .iter()
            .position(|m| m.0 == "heat_balance_rel");
        let balance = sim.thermal_values().unwrap()[k.unwrap()];
        assert!(balance.abs() < 1e-9, "{rule}: heat balance {balance:e}");
        let flows = sim.tool_heat_flows().unwrap();
        let depth_flux = q * 0.004;
        assert!(
            (flows[1] / depth_flux - 1.0).abs() < 0.01
                && (flows[0] / -depth_flux - 1.0).abs() < 0.01,
            "{rule}: heat flows {flows:?} W against {depth_flux:.3} W"
        );
    }
}

/// `erfc(x)` to 1.2e-7 relative (Numerical Recipes, 2nd ed., section 6.2, `erfcc`).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// A 40 mm bar at 20 C set on a die at 520 C through h = 5e4 W/(m^2 K), with q2, q4 and SCNI
/// on 0.5 mm spacing: the temperature at depth x after time t (0.05 to 0.4 s) against the
/// semi-infinite solution with surface resistance,
/// `(T - T_i) / (T_d - T_i) = erfc(x / (2 sqrt(a t))) - exp(h x / k + h^2 a t / k^2)
/// erfc(x / (2 sqrt(a t)) + h sqrt(a t) / k)` (Carslaw and Jaeger 1959, 2.7(1)), within 2 % of
/// the 500 K step at the surface (the points within 1 mm) and inside, while the heat has not
/// reached the far end.
#[test]
fn a_bar_on_a_hot_die_against_the_semi_infinite_solution() {
    let (l, h) = (0.04, 5e4);
    let a = K / RHO_C;
    for rule in ["q2", "q4", "scni"] {
        let scene = block([0.004, l], [9, 81], (20.0, 520.0, None), h, rule, 0.4);
        let mut sim = Simulation::new(&scene).unwrap();
        for t in [0.05, 0.1, 0.2, 0.4] {
            sim.run_to(t, |_| {}).unwrap();
            let time = sim.heat_time();
            let exact = |x: f64| {
                let s = (a * time).sqrt();
                let e = x / (2.0 * s);
                let resistance =
                    (h * x / K + h * h * a * time / (K * K)).exp() * erfc(e + h * s / K);
                20.0 + 500.0 * (erfc(e) - resistance)
            };
            let temps = sim.point_temperature().unwrap();
            let (mut surface, mut inside): (f64, f64) = (0.0, 0.0);
            for (p, x) in sim.point_positions().iter().enumerate() {
                let off = (temps[p] - exact(x[1])).abs() / 500.0;
                if x[1] < 0.001 {
                    surface = surface.max(off);
                } else {
                    inside = inside.max(off);
                }
            }
            assert!(
                surface < 0.02 && inside < 0.02,
                "{rule}, t = {time}: {:.2} % of the 500 K step off at the surface, {:.2} % inside",
                100.0 * surface,
                100.0 * inside
            );
            // The far end is still cold: the semi-infinite solution holds.
            assert!(exact(l) - 20.0 < 0.5);
        }
    }
}

/// Steady conduction with a conductivity rising with temperature, `k = 200 (1 + 0.02 T)`
/// W/(m K) as the table `[[0, 200], [100, 600]]`, between dies at 100 C and 0 C through
/// 2e5 W/(m^2 K): with `Phi(T) = int_0^T k = 200 T + 2 T^2` the flux `q` is constant,
/// `Phi(T_s0) - Phi(T_sL) = q L` with the surface temperatures `100 - q / h` and `q / h`, and
/// the profile `Phi(T(y)) = Phi(T_s0) - q y` (the Kirchhoff transform); every point within
/// 0.5 % of the 100 K (q4).
#[test]
fn steady_profile_with_a_conductivity_of_temperature() {
    let (l, h) = (0.01, 2e5);
    let phi = |t: f64| 200.0 * t + 2.0 * t * t;
    let inverse = |p: f64| (-200.0 + (200.0f64 * 200.0 + 8.0 * p).sqrt()) / 4.0;
    // q by bisection on Phi(100 - q/h) - Phi(q/h) - q L = 0.
    let (mut lo, mut hi) = (0.0, 1e8);
    for _ in 0..200 {
        let q = 0.5 * (lo + hi);
        if phi(100.0 - q / h) - phi(q / h) - q * l > 0.0 {
            lo = q;
        } else {
            hi = q;
        }
    }
    let q = 0.5 * (lo + hi);
    let top = phi(100.0 - q / h);
    let tau = l * l * RHO_C / 200.0;
    let mut scene = block(
        [0.004, l],
        [9, 21],
        (50.0, 100.0, Some(0.0)),
        h,
        "q4",
        6.0 * tau,
    );
    let thermal = scene.thermal.as_mut().unwrap();
    thermal.conductivity_w_per_m_k = 0.0;
    thermal.conductivity_by_temperature = vec![[0.0, 200.0], [100.0, 600.0]];
    let mut sim = Simulation::new(&scene).unwrap();
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    let temps = sim.point_temperature().unwrap();
    let mut worst: f64 = 0.0;
    for (p, x) in sim.point_positions().iter().enumerate() {
        let exact = inverse(top - q * x[1]);
        worst = worst.max((temps[p] - exact).abs() / 100.0);
    }
    assert!(
        worst < 0.005,
        "a point {:.3} % of the 100 K off the profile",
        100.0 * worst
    );
    // Not the constant-conductivity line: the profile bows (T at mid-height above 50 C).
    let mid = inverse(top - q * 0.005);
    assert!(mid > 55.0, "{mid}");
}

/// The 40 mm bar at 20 C on the die at 520 C through h = 5e4 W/(m^2 K) with a specific heat
/// that doubles over the range, `c` from 300 J/(kg K) at 0 C to 600 at 300 C (the table
/// `[[0, 300], [300, 600]]`, held beyond): against a one-dimensional finite-volume solution
/// of `rho dh/dt = k T''` in the enthalpy `h(T) = int c dT` (400 cells of 0.1 mm, explicit,
/// the surface cell meeting the die through `1 / (1 / h + dx / (2 k))`), every point within
/// 2 % of the 500 K step at 0.05, 0.1, 0.2 and 0.4 s (q2, q4 and SCNI); the heat account
/// closes (content = heat from the die) to 1e-9.
#[test]
fn a_bar_on_a_hot_die_with_a_capacity_of_temperature() {
    let (l, h, rho) = (0.04, 5e4, 8960.0);
    // h(T) from 0 C: trapezoids of the linear pieces, exact.
    let enthalpy = |t: f64| {
        let a = t.clamp(0.0, 300.0);
        300.0 * t.min(0.0) + 300.0 * a + 0.5 * a * a + 600.0 * (t - 300.0).max(0.0)
    };
    // Its inverse: `300 a + a^2 / 2 = e` on [0, 300] C.
    let top = enthalpy(300.0);
    let temperature = |e: f64| {
        if e <= 0.0 {
            e / 300.0
        } else if e >= top {
            300.0 + (e - top) / 600.0
        } else {
            -300.0 + (90000.0 + 2.0 * e).sqrt()
        }
    };
    // The reference: finite volumes over the bar's length.
    let cells = 400;
    let dx = l / cells as f64;
    let dt = 0.2 * rho * 300.0 * dx * dx / K;
    let mut e = vec![enthalpy(20.0); cells];
    let mut t_ref = vec![20.0; cells];
    let mut now = 0.0;
    let mut advance = |to: f64, e: &mut Vec<f64>, t_ref: &mut Vec<f64>| {
        while now < to - 1e-12 {
            let step = dt.min(to - now);
            let mut flux = vec![0.0; cells + 1];
            flux[0] = (520.0 - t_ref[0]) / (1.0 / h + dx / (2.0 * K));
            for i in 1..cells {
                flux[i] = K * (t_ref[i - 1] - t_ref[i]) / dx;
            }
            for i in 0..cells {
                e[i] += step * (flux[i] - flux[i + 1]) / (rho * dx);
                t_ref[i] = temperature(e[i]);
            }
            now += step;
        }
    };
    let mut refs = Vec::new();
    for t in [0.05, 0.1, 0.2, 0.4] {
        advance(t, &mut e, &mut t_ref);
        refs.push(t_ref.clone());
    }
    let at = |profile: &[f64], y: f64| {
        let s = (y / dx - 0.5).clamp(0.0, (cells - 1) as f64);
        let i = (s.floor() as usize).min(cells - 2);
        profile[i] + (s - i as f64) * (profile[i + 1] - profile[i])
    };
    for rule in ["q2", "q4", "scni"] {
        let mut scene = block([0.004, l], [9, 81], (20.0, 520.0, None), h, rule, 0.4);
        let thermal = scene.thermal.as_mut().unwrap();
        thermal.specific_heat_j_per_kg_k = 0.0;
        thermal.specific_heat_by_temperature = vec![[0.0, 300.0], [300.0, 600.0]];
        let mut sim = Simulation::new(&scene).unwrap();
        let mut worst: f64 = 0.0;
        for (k, t) in [0.05, 0.1, 0.2, 0.4].into_iter().enumerate() {
            sim.run_to(t, |_| {}).unwrap();
            // The heat stage's time lags the run's by less than a heat step: compare at the
            // reference's nearest time only when they agree to 1 %.
            assert!(
                (sim.heat_time() / t - 1.0).abs() < 0.01,
                "{}",
                sim.heat_time()
            );
            let temps = sim.point_temperature().unwrap();
            for (p, x) in sim.point_positions().iter().enumerate() {
                let off = (temps[p] - at(&refs[k], x[1])).abs() / 500.0;
                worst = worst.max(off);
            }
            let balance = sim.thermal_values().unwrap()[THERMAL_MEASURES
                .iter()
                .position(|m| m.0 == "heat_balance_rel")
                .unwrap()];
            assert!(balance.abs() < 1e-9, "{rule}: heat balance {balance:e}");
        }
        eprintln!("{rule}: worst point {:.3} % of the 500 K", 100.0 * worst);
        assert!(
            worst < 0.02,
            "{rule}: a point {:.2} % of the 500 K step off the reference",
            100.0 * worst
        );
    }
}

/// A transfer coefficient over contact pressure, `h = 5e3 W/(m^2 K)` at 0 rising to 9.5e4 at
/// 200 MPa (the table `[[0, 5e3], [2e8, 9.5e4]]`): the 40 mm bar at 20 C (perfectly plastic
/// at 100 MPa, plane strain) on the bottom die at 520 C, pressed by a cold top die (no heat
/// across it) at 2 mm/s, 2 % of its height over 0.4 s. The bar yields (frictionless dies)
/// at a pressure between 100 MPa and `2 / sqrt(3)` of it; at 0.2 and 0.4 s, with `p` the
/// bottom die's force over the bar's width, every point lies within 2 % of the 500 K step of the
/// semi-infinite solution with the coefficient at that pressure (q4), and more than 2 % off
/// the solution at the table's zero-pressure value.
#[test]
fn a_transfer_coefficient_of_the_contact_pressure() {
    let (l, w) = (0.04, 0.004);
    let mut scene = block([w, l], [9, 81], (20.0, 520.0, Some(20.0)), 1.0, "q4", 0.4);
    scene.time.mass_scaling = Some(rkforge_core::scene::MassScaling {
        factor: Some(1e4),
        target_dt_s: None,
        at_rereferences: None,
    });
    let bottom = &mut scene.tools[0];
    bottom.heat_transfer_w_per_m2_k = 0.0;
    bottom.heat_transfer_by_pressure = vec![[0.0, 5e3], [2e8, 9.5e4]];
    let top = &mut scene.tools[1];
    top.heat_transfer_w_per_m2_k = 0.0;
    top.motion = rkforge_core::scene::Motion::Constant {
        velocity_m_per_s: 0.02 * l / 0.4,
    };
    // The bar's left edge a symmetry plane: a half of a bar twice as wide, which cannot
    // buckle (the free bar, ten times as tall as wide between frictionless dies, does).
    scene.constraints = vec![rkforge_core::scene::ConstraintSpec {
        edge: rkforge_core::scene::Edge::XMin,
        fix: vec![rkforge_core::scene::Component::X],
    }];
    assert_eq!(scene.validate(), vec![]);
    let a = K / RHO_C;
    let exact = |x: f64, time: f64, h: f64| {
        let s = (a * time).sqrt();
        let e = x / (2.0 * s);
        let resistance = (h * x / K + h * h * a * time / (K * K)).exp() * erfc(e + h * s / K);
        20.0 + 500.0 * (erfc(e) - resistance)
    };
    let mut sim = Simulation::new(&scene).unwrap();
    for t in [0.2, 0.4] {
        sim.run_to(t, |_| {}).unwrap();
        // The die's force over the bar's width (which grows as the bar shortens, the area
        // kept): between the uniaxial yield stress and the plane-strain one, 2 / sqrt(3) of
        // it, which the flow approaches as the plastic strain outgrows the elastic.
        let width = w / (1.0 - 0.02 * t / 0.4);
        let force = sim.tools()[0].axial_force().abs();
        let pressure = force / (width * scene.model.depth_m);
        assert!(
            pressure > 100e6 && pressure < 2.0 / 3f64.sqrt() * 100e6,
            "die pressure {pressure:.4e} Pa"
        );
        let h = scene.tools[0].heat_transfer_at(pressure);
        let time = sim.heat_time();
        let temps = sim.point_temperature().unwrap();
        let (mut worst, mut at_zero): (f64, f64) = (0.0, 0.0);
        for (p, x) in sim.point_positions().iter().enumerate() {
            worst = worst.max((temps[p] - exact(x[1], time, h)).abs() / 500.0);
            at_zero = at_zero.max((temps[p] - exact(x[1], time, 5e3)).abs() / 500.0);
        }
        eprintln!(
            "t = {time:.3} s: p {pressure:.4e} Pa, h {h:.0}; worst point {:.3} % of the 500 K \
             ({:.2} % against h(0))",
            100.0 * worst,
            100.0 * at_zero
        );
        assert!(worst < 0.02, "t = {time}: {:.2} % off", 100.0 * worst);
        assert!(at_zero > 0.02, "t = {time}: h(0) fits as well");
    }
}

/// Conduction after kernel re-referencing: the 4 x 10 mm block between the dies at 100 C and
/// 0 C (2e5 W/(m^2 K) each, both holding the particles that reach them) squeezed to 6 mm at
/// 40 mm/s (linear hardening, 100 MPa and 2 GPa: a perfectly plastic block does not deform
/// evenly), frictionless, re-referenced whenever a point's stretch reaches 1.1, then held
/// until steady: every point within 0.5 % of the 100 K of the steady profile through the
/// squeezed height `L'`, `T = 100 - q / h - q y / k`, `q = 100 / (2 / h + L' / k)` (q4, at
/// the points' current positions), and within 0.1 K of the same run with the Lagrangian
/// kernel; the heat account closes to 1e-9.
#[test]
fn steady_profile_through_a_rereferenced_block() {
    let (l, h) = (0.01, 2e5);
    let mut scene = block([0.004, l], [9, 21], (50.0, 100.0, Some(0.0)), h, "q4", 3.4);
    scene.time.mass_scaling = Some(rkforge_core::scene::MassScaling {
        factor: Some(1e6),
        target_dt_s: None,
        at_rereferences: None,
    });
    scene.material.hardening = rkforge_core::material::Hardening::Linear {
        yield_stress_pa: 100e6,
        modulus_pa: 2e9,
    };
    for tool in &mut scene.tools {
        tool.separation = false;
    }
    scene.tools[1].motion = rkforge_core::scene::Motion::Table {
        points: vec![[0.0, 0.04], [0.1, 0.04], [0.1001, 0.0]],
    };
    // The Lagrangian kernel throughout, for comparison.
    let mut lagrangian = Simulation::new(&scene).unwrap();
    lagrangian.run_to(scene.time.end_s, |_| {}).unwrap();
    scene.discretization.rereference_stretch = Some(1.1);
    assert_eq!(scene.validate(), vec![]);
    let mut sim = Simulation::new(&scene).unwrap();
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    let count = sim.reference().map_or(0, |r| r.count);
    assert!(count > 0, "no re-reference");
    // The points' current positions, x_p = X_p + sum_I N_I d_I.
    let d = &sim.state().d;
    let x: Vec<[f64; 2]> = (0..sim.point_count())
        .map(|p| {
            let mut x = sim.point_positions()[p];
            for (i, [n, _, _]) in sim.point_shapes(p) {
                x[0] += n * d[i][0];
                x[1] += n * d[i][1];
            }
            x
        })
        .collect();
    let gap = l - sim.tools()[1].state.stroke;
    let q = 100.0 / (2.0 / h + gap / K);
    let temps = sim.point_temperature().unwrap();
    let worst = x
        .iter()
        .zip(temps)
        .map(|(x, t)| (t - (100.0 - q / h - q * x[1] / K)).abs() / 100.0)
        .fold(0.0f64, f64::max);
    let balance = sim.thermal_values().unwrap()[THERMAL_MEASURES
        .iter()
        .position(|m| m.0 == "heat_balance_rel")
        .unwrap()];
    eprintln!(
        "{count} re-references, gap {:.4} mm: worst point {:.3} % of the 100 K, balance {balance:.1e}",
        1e3 * gap,
        100.0 * worst
    );
    assert!((gap - 0.006).abs() < 1e-4, "gap {gap}");
    assert!(worst < 0.005, "a point {:.3} % off", 100.0 * worst);
    assert!(balance.abs() < 1e-9, "heat balance {balance:e}");
    let apart = temps
        .iter()
        .zip(lagrangian.point_temperature().unwrap())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f64, f64::max);
    eprintln!("re-referenced against Lagrangian: {apart:.4} K at most");
    assert!(apart < 0.1, "{apart} K apart");
}
