//! Rigid tools from STL files in 3D against the plane tools they replace, and the analytic
//! cylinder tools against the STL cylinders they replace.

mod common;

use common::solid_scenes::{box_scene, ALUMINIUM};
use rkforge_core::outputs::{solid_columns, Sample};
use rkforge_core::scene::{SceneFile, SolidScene};
use rkforge_core::solver::{DiePressure, SolidSimulation};
use std::path::Path;

/// The closed box `lo..hi` (in the file's unit) as 12 triangles with outward normals,
/// reversed when `inverted`, less its last triangle when `open`.
fn cuboid(lo: [f32; 3], hi: [f32; 3], inverted: bool, open: bool) -> Vec<[[f32; 3]; 3]> {
    let corner = |i: usize| -> [f32; 3] {
        std::array::from_fn(|k| if i >> k & 1 == 1 { hi[k] } else { lo[k] })
    };
    // Corner i has bit k set where coordinate k is at `hi`; each quad wound outward.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut t: Vec<[[f32; 3]; 3]> = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .map(|tri: [usize; 3]| tri.map(corner))
        .collect();
    if inverted {
        for tri in &mut t {
            tri.swap(1, 2);
        }
    }
    if open {
        t.pop();
    }
    t
}

/// Writes `triangles` as an ASCII STL file.
fn write_ascii(path: &Path, triangles: &[[[f32; 3]; 3]]) {
    let mut s = String::from("solid die\n");
    for t in triangles {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for v in t {
            s += &format!("      vertex {} {} {}\n", v[0], v[1], v[2]);
        }
        s += "    endloop\n  endfacet\n";
    }
    s += "endsolid die\n";
    std::fs::write(path, s).unwrap();
}

/// Writes `triangles` as a binary STL file.
fn write_binary(path: &Path, triangles: &[[[f32; 3]; 3]]) {
    let t: Vec<stl_io::Triangle> = triangles
        .iter()
        .map(|t| stl_io::Triangle {
            normal: stl_io::Normal::new([0.0; 3]),
            vertices: t.map(stl_io::Vertex::new),
        })
        .collect();
    stl_io::write_stl(&mut std::fs::File::create(path).unwrap(), t.iter()).unwrap();
}

/// A folder of this test's own with a folder `dies` in it, removed when it drops.
fn folder(name: &str) -> tempfile::TempDir {
    let d = tempfile::Builder::new()
        .prefix(&format!("rkforge_stl_{name}_"))
        .tempdir()
        .unwrap();
    std::fs::create_dir(d.path().join("dies")).unwrap();
    d
}

/// A quarter cylinder (radius 5 mm, height 7.5 mm) of steel upset by 0.6 mm at 10 m/s
/// between a fixed anvil and a ram with Coulomb friction 0.1, the dies given by `dies`
/// (the `[[tools]]` keys of each after its name).
fn upset_text(anvil: &str, ram: &str) -> String {
    format!(
        r#"
name = "upset_stl"
[model]
kinematics = "3d"
[workpiece]
shape = "cylinder"
radius_m = 0.005
length_m = 0.0075
part = "quarter"
cells = [4, 2, 6]
[material]
density_kg_per_m3 = 7800.0
youngs_modulus_pa = 200e9
poisson_ratio = 0.3
hardening = {{ law = "linear", yield_stress_pa = 300e6, modulus_pa = 1e9 }}
[time]
end_s = 60e-6
[[tools]]
name = "anvil"
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "fixed" }}
friction = 0.1
{anvil}
[[tools]]
name = "ram"
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "constant", velocity_m_per_s = 10.0 }}
friction = 0.1
{ram}
"#
    )
}

const ANVIL_PLANE: &str = "point_m = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]";
const RAM_PLANE: &str = "point_m = [0.0, 0.0, 0.0075]\nnormal = [0.0, 0.0, -1.0]";

fn scene(text: &str, file: &Path) -> Result<SolidScene, String> {
    match SceneFile::from_str_named(text, &file.display().to_string()) {
        Ok(SceneFile::Solid(s)) => Ok(*s),
        Ok(SceneFile::Plane(_)) => panic!("read as 2D"),
        Err(e) => Err(e.to_string()),
    }
}

/// The ram's stroke and axial force (m, N) at every step, and the simulation at the end.
fn run(scene: &SolidScene) -> (Vec<[f64; 2]>, SolidSimulation) {
    let mut sim = SolidSimulation::new(scene).unwrap();
    let mut curve = Vec::new();
    sim.run_toward(scene.time.end_s, u64::MAX, |s, _| {
        let ram = &s.tools()[1];
        curve.push([ram.state.stroke, ram.axial_force()]);
        true
    })
    .unwrap();
    (curve, sim)
}

/// The anvil and the ram as STL boxes (the anvil ASCII, the ram binary, both in
/// millimetres, wider than the bulging workpiece and reaching past the symmetry planes)
/// give the plane dies' force-stroke curve to the bit: on a face the triangle surface's gap
/// is the plane's formula, the contact normal its normal. The particles' physical positions
/// measured against the triangles lie no deeper than against the planes.
#[test]
fn stl_box_dies_give_the_plane_dies_force_stroke() {
    let dir = folder("upset");
    write_ascii(
        &dir.path().join("dies/anvil.stl"),
        &cuboid([-5.0, -5.0, -5.0], [15.0, 15.0, 0.0], false, false),
    );
    write_binary(
        &dir.path().join("dies/ram.stl"),
        &cuboid([-5.0, -5.0, 7.5], [15.0, 15.0, 12.5], false, false),
    );
    let scene_file = dir.path().join("upset.toml");
    let planes = scene(&upset_text(ANVIL_PLANE, RAM_PLANE), &scene_file).unwrap();
    let stl = |f: &str| format!("shape = \"stl\"\nfile = \"dies/{f}.stl\"\nunit = \"mm\"");
    let dies = scene(&upset_text(&stl("anvil"), &stl("ram")), &scene_file).unwrap();
    let (by_planes, mut sim_planes) = run(&planes);
    let (by_stl, mut sim_stl) = run(&dies);
    let last = by_planes[by_planes.len() - 1];
    assert!(last[0] > 5.9e-4 && last[1] < -1e3, "{last:?}");
    assert_eq!(by_planes.len(), by_stl.len());
    for (a, b) in by_planes.iter().zip(&by_stl) {
        assert_eq!(a[0].to_bits(), b[0].to_bits());
        assert_eq!(a[1].to_bits(), b[1].to_bits(), "{a:?} {b:?}");
    }
    assert_eq!(sim_planes.state().d, sim_stl.state().d);
    let (pen_planes, _) = sim_planes.measure_penetration().unwrap();
    let (pen_stl, _) = sim_stl.measure_penetration().unwrap();
    eprintln!(
        "steps {} stroke {:.4e} m force {:.4e} N; penetration {:.3e} of a spacing (planes {:.3e})",
        by_stl.len(),
        last[0],
        last[1],
        pen_stl / sim_stl.h_min(),
        pen_planes / sim_planes.h_min()
    );
    assert_eq!(pen_stl.to_bits(), pen_planes.to_bits());
    assert!(pen_stl < 0.05 * sim_stl.h_min());
}

/// A square punch (6 x 6 mm, a quarter modelled) indents the cylinder's top face: its
/// edges and corner touch the workpiece. The run keeps every particle's physical position
/// within the run's penetration bound against the triangles, the punch takes a load, and
/// the energy account closes.
#[test]
fn a_punch_with_edges_indents_with_bounded_penetration() {
    let dir = folder("punch");
    write_ascii(
        &dir.path().join("dies/anvil.stl"),
        &cuboid([-5.0, -5.0, -5.0], [15.0, 15.0, 0.0], false, false),
    );
    write_binary(
        &dir.path().join("dies/punch.stl"),
        &cuboid([-5.0, -5.0, 7.5], [3.0, 3.0, 12.5], false, false),
    );
    let scene_file = dir.path().join("punch.toml");
    let punch = "shape = \"stl\"\nfile = \"dies/punch.stl\"\nunit = \"mm\"";
    let anvil = "shape = \"stl\"\nfile = \"dies/anvil.stl\"\nunit = \"mm\"";
    let s = scene(&upset_text(anvil, punch), &scene_file).unwrap();
    let mut sim = SolidSimulation::new(&s).unwrap();
    let mut deepest: f64 = 0.0;
    sim.run_toward(s.time.end_s, u64::MAX, |s, step| {
        if step % 20 == 0 {
            deepest = deepest.max(s.measure_penetration().unwrap().0);
        }
        true
    })
    .unwrap();
    let force = sim.tools()[1].axial_force();
    let e = sim.energy();
    eprintln!(
        "punch force {force:.4e} N, deepest particle {:.3e} of a spacing, balance {:.2e}",
        deepest / sim.h_min(),
        e.balance_error_rel()
    );
    assert!(force < -1e3, "{force}");
    assert!(deepest < 0.05 * sim.h_min(), "{deepest}");
    assert!(e.balance_error_rel() < 0.01, "{e:?}");
}

/// A bad STL is refused naming the key, the file and the reason: an open surface, normals
/// pointing into the die, a die in millimetres read as metres.
#[test]
fn bad_stl_files_are_refused_with_the_file_and_reason() {
    let dir = folder("bad");
    let box_mm = |inverted, open| cuboid([-5.0, -5.0, 7.5], [15.0, 15.0, 12.5], inverted, open);
    write_binary(&dir.path().join("dies/open.stl"), &box_mm(false, true));
    write_binary(&dir.path().join("dies/flipped.stl"), &box_mm(true, false));
    write_ascii(&dir.path().join("dies/in_mm.stl"), &box_mm(false, false));
    let scene_file = dir.path().join("bad.toml");
    for (file, unit, reason) in [
        ("open", "mm", "open surface"),
        ("flipped", "mm", "inverted"),
        ("in_mm", "m", "millimetres given as metres"),
        ("missing", "mm", "cannot be read"),
    ] {
        let ram = format!("shape = \"stl\"\nfile = \"dies/{file}.stl\"\nunit = \"{unit}\"");
        let e = scene(&upset_text(ANVIL_PLANE, &ram), &scene_file).unwrap_err();
        assert!(
            e.contains("tools[1].file") && e.contains(&format!("{file}.stl")) && e.contains(reason),
            "{e}"
        );
    }
    let e = scene(
        &upset_text(ANVIL_PLANE, "shape = \"stl\"\npoint_m = [0.0, 0.0, 0.0]"),
        &scene_file,
    )
    .unwrap_err();
    assert!(e.contains("tools[1].file") && e.contains("needs"), "{e}");
}

/// The heat balance and the heat to each tool (J) of a thermal run.
fn heat_readings(sim: &SolidSimulation) -> (f64, Vec<f64>) {
    let v = sim.thermal_values().unwrap();
    let at = |name: &str| {
        v[rkforge_core::THERMAL_MEASURES
            .iter()
            .position(|m| m.0 == name)
            .unwrap()]
    };
    let heat = sim.state().heat.as_ref().unwrap();
    (at("heat_balance_rel"), heat.to_tools_j.clone())
}

/// Heat to STL dies: the upset of [`upset_text`] with the workpiece at 600 C, conduction
/// (k 40 W/(m K)) and the dies at 20 C, the anvil through 5e4 W/(m^2 K) and the ram through
/// a pressure-dependent coefficient ([[0, 1e4], [1e9, 1e5]] W/(m^2 K) over Pa), run for 60
/// us, the dies as planes and as the STL boxes of
/// `stl_box_dies_give_the_plane_dies_force_stroke`. The heat stage's contact is the same for
/// either kind of surface (`SolidTool::touching`: a surface particle within 0.05 spacings
/// of the die, its quarters' area projected on the contact normal, on a box's face its
/// normal): the heat each die took, the temperatures and the positions are the same bits,
/// and the heat balance closes to round-off.
#[test]
fn stl_box_dies_take_the_plane_dies_heat() {
    let dir = folder("heat");
    write_ascii(
        &dir.path().join("dies/anvil.stl"),
        &cuboid([-5.0, -5.0, -5.0], [15.0, 15.0, 0.0], false, false),
    );
    write_binary(
        &dir.path().join("dies/ram.stl"),
        &cuboid([-5.0, -5.0, 7.5], [15.0, 15.0, 12.5], false, false),
    );
    let hot = |anvil: &str, ram: &str| {
        format!(
            "{}\n[thermal]\ninitial_temperature_c = 600.0\nspecific_heat_j_per_kg_k = 460.0\nconductivity_w_per_m_k = 40.0\n",
            upset_text(
                &format!("{anvil}\ntemperature_c = 20.0\nheat_transfer_w_per_m2_k = 5.0e4"),
                &format!("{ram}\ntemperature_c = 20.0\nheat_transfer_by_pressure = [[0.0, 1.0e4], [1.0e9, 1.0e5]]"),
            )
        )
    };
    let scene_file = dir.path().join("upset.toml");
    let stl = |f: &str| format!("shape = \"stl\"\nfile = \"dies/{f}.stl\"\nunit = \"mm\"");
    let planes = scene(&hot(ANVIL_PLANE, RAM_PLANE), &scene_file).unwrap();
    let dies = scene(&hot(&stl("anvil"), &stl("ram")), &scene_file).unwrap();
    assert_eq!(dies.validate(), vec![]);
    let (_, sim_planes) = run(&planes);
    let (_, sim_stl) = run(&dies);
    let (balance_planes, to_planes) = heat_readings(&sim_planes);
    let (balance_stl, to_stl) = heat_readings(&sim_stl);
    eprintln!(
        "heat to the dies: STL {to_stl:?} J, planes {to_planes:?} J; balance {balance_stl:.1e} (planes {balance_planes:.1e})"
    );
    assert!(to_stl.iter().all(|&q| q > 0.0), "{to_stl:?}");
    assert_eq!(to_stl, to_planes);
    assert_eq!(sim_stl.point_temperature(), sim_planes.point_temperature());
    assert_eq!(sim_stl.state().d, sim_planes.state().d);
    assert!(balance_stl.abs() < 1e-9, "{balance_stl:e}");
}

// Die-contact outputs in 3D: the contact area, its share and the mean pressure of each
// tool, the pressure on an STL die's triangles, and fill points.

/// A quarter of an aluminium block 10 x 10 x 10 mm (`origin 0`, the planes x = 0 and y = 0
/// its symmetry planes, 5 x 5 x 9 particles: 1.25 mm spacing), frictionless between an anvil
/// under z = 0 and a ram whose face starts `gap` (mm) above the block, the ram moving down at
/// 2 m/s for `end` (s); `anvil` and `ram` the dies' surface keys, `fill` the ram's fill
/// points (TOML) and `reach` the `output.fill_distance_rel`.
fn block_text(anvil: &str, ram: &str, end: f64, fill: &str, reach: f64) -> String {
    let block = pressed_box([5.0, 5.0, 10.0], [5, 5, 9], end, anvil, ram);
    format!("{block}{fill}\n[output]\nfill_distance_rel = {reach}\n")
}

/// A quarter aluminium box `size` mm (`particles` along x, y, z; the planes x = 0 and
/// y = 0 holding it by symmetry, q2) on the fixed `anvil`, pressed by the `ram` (their
/// surface keys, TOML) moving down at 2 m/s for `end` s.
fn pressed_box(size: [f64; 3], particles: [usize; 3], end: f64, anvil: &str, ram: &str) -> String {
    let quarter = ["x_min", "y_min"];
    let block = box_scene(
        "pressed_box",
        size.map(|v| v * 1e-3),
        particles,
        &quarter,
        ALUMINIUM,
        "q2",
    );
    format!(
        r#"{block}[time]
end_s = {end:e}
[[tools]]
name = "anvil"
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "fixed" }}
{anvil}
[[tools]]
name = "ram"
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "constant", velocity_m_per_s = 2.0 }}
{ram}
"#
    )
}

/// The anvil's and the ram's surface keys: planes (the ram's face `gap` mm above the block)
/// or the STL boxes of `dir` (written here, in millimetres, wider than the bulging block).
fn block_dies(dir: &Path, gap: f64, stl: bool) -> (String, String) {
    let top = 10.0 + gap;
    if !stl {
        return (
            ANVIL_PLANE.into(),
            format!(
                "point_m = [0.0, 0.0, {:e}]\nnormal = [0.0, 0.0, -1.0]",
                top * 1e-3
            ),
        );
    }
    write_ascii(
        &dir.join("dies/anvil.stl"),
        &cuboid([-5.0, -5.0, -5.0], [15.0, 15.0, 0.0], false, false),
    );
    write_binary(
        &dir.join("dies/ram.stl"),
        &cuboid(
            [-5.0, -5.0, top as f32],
            [15.0, 15.0, top as f32 + 5.0],
            false,
            false,
        ),
    );
    let stl = |f: &str| format!("shape = \"stl\"\nfile = \"dies/{f}.stl\"\nunit = \"mm\"");
    (stl("anvil"), stl("ram"))
}

/// Runs `scene` to its end.
fn run_to_end(scene: &SolidScene) -> SolidSimulation {
    let mut sim = SolidSimulation::new(scene).unwrap();
    sim.run_toward(scene.time.end_s, u64::MAX, |_, _| true)
        .unwrap();
    sim
}

/// The value of the register column `name` of a 3D simulation now.
fn column(sim: &SolidSimulation, name: &str) -> f64 {
    let columns = solid_columns(sim.scene());
    let c = columns.iter().find(|c| c.name == name).unwrap();
    c.value(&Sample::new(sim))
}

/// A quarter block pressed frictionless by 0.5 mm (5 %, plastic) between flat dies, as
/// planes and as STL boxes (the same bits). The block stays a block: its top face is the
/// rectangle `x_max y_max` of its bounds, and the ram's contact area is that within 0.1 %
/// (measured: 2.63058e-5 against 2.63153e-5 m^2, -0.036 %; the anvil's alike); the share of
/// the surface is `x y / (2 x y + h (x + y))` of the bounds within 0.2 %; the mean pressure,
/// the normal force over the contact area, is the axial force over the top face's area
/// within 0.1 % and the true stress of homogeneous compression `sigma_0 + H ln(h_0 / h)`
/// within 2 % (124.77 against 125.63 MPa, -0.7 %); the pressure field over the STL ram's
/// triangles, and over the plane's contact patch (the pressed particles' quarters projected
/// on it, whose area is the contact area), integrates to the tool's normal force to round-off
/// (2.2e-16 and 4.4e-16).
#[test]
fn flat_dies_report_the_contact_area_and_pressure_of_a_quarter_block() {
    let dir = folder("contact");
    let file = dir.path().join("block.toml");
    let mut areas = Vec::new();
    for stl in [false, true] {
        let (anvil, ram) = block_dies(dir.path(), 0.0, stl);
        let s = scene(&block_text(&anvil, &ram, 250e-6, "", 1.0), &file).unwrap();
        let sim = run_to_end(&s);
        let r = sim.readings();
        let (x, y, h) = (r.extents[0][1], r.extents[1][1], r.height());
        let top = x * y;
        for (t, name) in ["anvil", "ram"].into_iter().enumerate() {
            let tool = &sim.tools()[t];
            let area = column(&sim, &format!("{name}.contact_area_m2"));
            assert_eq!(area, sim.contact_area(t));
            let share = column(&sim, &format!("{name}.surface_fraction"));
            let mean = column(&sim, &format!("{name}.pressure_mean_Pa"));
            let force = tool.axial_force().abs();
            let stress = 100e6 + 500e6 * (0.01 / h).ln();
            eprintln!(
                "{name} (stl {stl}): area {area:.5e} m^2 against the top face {top:.5e} ({:+.3} %), share {share:.5} against {:.5}, mean pressure {mean:.5e} Pa against F / A {:.5e} and homogeneous {stress:.5e}",
                100.0 * (area / top - 1.0),
                top / (2.0 * top + h * (x + y)),
                force / top,
            );
            assert!((area / top - 1.0).abs() < 1e-3);
            assert!((share * (2.0 * top + h * (x + y)) / top - 1.0).abs() < 2e-3);
            assert_eq!(mean, tool.state.normal_force / area);
            assert!((mean * top / force - 1.0).abs() < 1e-3);
            assert!((mean / stress - 1.0).abs() < 0.02);
            areas.push(area.to_bits());
            let die = sim.die_pressure(t);
            let integral: f64 = die
                .pressure
                .iter()
                .zip(&die.areas)
                .map(|(p, a)| p * a)
                .sum();
            let rel = integral / tool.state.normal_force - 1.0;
            let (loaded, peak) = loaded_area_and_peak(&die);
            eprintln!(
                "  {} triangles, integral against the normal force {rel:.1e}, loaded area {loaded:.4e} m^2, highest {peak:.4e} Pa",
                die.triangles.len()
            );
            assert!(rel.abs() < 1e-9);
            if stl {
                assert_eq!(die.triangles.len(), 12);
            } else {
                // The plane's patch is the pressed particles' quarters, the 5 x 5 particles of
                // the top face with their quarters on it (64) and on the free sides (16, edge-on
                // to the die): 160 triangles, whose area is the contact area.
                assert_eq!(die.triangles.len(), 160);
                // (the side quarters' slivers add their areas' round-off: 7e-6)
                assert!((loaded / area - 1.0).abs() < 1e-4, "{loaded} {area}");
                // Each particle's pressure is its penalty force of the last step over its
                // area: it scatters about the mean (69 to 153 MPa against 125 MPa here).
                assert!(peak > mean && peak < 1.3 * mean, "{peak} {mean}");
            }
        }
    }
    assert_eq!(areas[..2], areas[2..]);
}

/// The loaded area of a die's pressure field, its triangles' with a pressure on them (m^2;
/// a triangle of no area carries none), and the highest pressure on one (Pa).
fn loaded_area_and_peak(die: &DiePressure) -> (f64, f64) {
    let loaded = die
        .pressure
        .iter()
        .zip(&die.areas)
        .filter(|(p, _)| **p != 0.0)
        .map(|(_, a)| a)
        .sum();
    let peak = die.pressure.iter().copied().fold(0.0, f64::max);
    (loaded, peak)
}

/// Each triangle of `triangles` split into four at its edges' midpoints, `levels` times (a
/// shared edge splits alike on both sides, so the surface stays closed).
fn refined(mut triangles: Vec<[[f32; 3]; 3]>, levels: usize) -> Vec<[[f32; 3]; 3]> {
    let mid = |a: [f32; 3], b: [f32; 3]| std::array::from_fn(|k| (a[k] + b[k]) * 0.5);
    for _ in 0..levels {
        triangles = triangles
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    triangles
}

/// The pressure on an STL ram whose triangles are finer than the particles (its faces split
/// to 12 288 triangles, legs of 0.625 mm against the block's 1.25 mm spacing), the block of
/// the test above: each particle's force is spread over its own contact patch, so the field
/// still integrates to the ram's normal force to round-off, the loaded triangles cover about
/// the contact area, and no triangle carries more than the particles' pressures do on the
/// plane's patch (there at most 1.3 times the mean). Before the spreading each particle's
/// whole force went to one triangle an eighth of its area: eight times its pressure.
#[test]
fn a_die_finer_than_the_particles_carries_each_particles_pressure_over_its_patch() {
    let dir = folder("fine_ram");
    let file = dir.path().join("block.toml");
    let ram = refined(
        cuboid([-5.0, -5.0, 10.0], [15.0, 15.0, 15.0], false, false),
        5,
    );
    assert_eq!(ram.len(), 12 * 1024);
    write_binary(&dir.path().join("dies/ram.stl"), &ram);
    let ram = "shape = \"stl\"\nfile = \"dies/ram.stl\"\nunit = \"mm\"";
    let s = scene(&block_text(ANVIL_PLANE, ram, 250e-6, "", 1.0), &file).unwrap();
    let sim = run_to_end(&s);
    let tool = &sim.tools()[1];
    let area = sim.contact_area(1);
    let mean = tool.state.normal_force / area;
    let die = sim.die_pressure(1);
    let integral: f64 = die.forces.iter().sum();
    let (loaded, peak) = loaded_area_and_peak(&die);
    eprintln!(
        "integral against the normal force {:.1e}, loaded {loaded:.4e} against the contact area {area:.4e} m^2, peak {peak:.4e} against the mean {mean:.4e} Pa",
        integral / tool.state.normal_force - 1.0
    );
    assert!((integral / tool.state.normal_force - 1.0).abs() < 1e-9);
    assert!((loaded / area - 1.0).abs() < 0.25, "{loaded} {area}");
    assert!(peak < 1.5 * mean, "{peak} {mean}");

    // A pressed particle with no contact area of its own (edge-on quarters, or a particle off
    // the surface pressed in a flash; here the block's centre particle, booked with the mean
    // particle's force) is spread over the mean patch of the others, A_t / n: the triangles
    // it adds to carry its force f at about f / (A_t / n), not all of f on the one triangle
    // (1/32 of a particle's patch) nearest to it.
    let pressed = &sim.state().pressed;
    let n = pressed.iter().filter(|p| p.tool == 1).count() as f64;
    let f = tool.state.normal_force / n;
    let x = sim.positions();
    let middle: [f64; 3] =
        std::array::from_fn(|k| x.iter().map(|p| p[k]).sum::<f64>() / x.len() as f64);
    let d2 = |p: &[f64; 3]| (0..3).map(|k| (p[k] - middle[k]).powi(2)).sum::<f64>();
    let centre = (0..x.len())
        .min_by(|&a, &b| d2(&x[a]).total_cmp(&d2(&x[b])))
        .unwrap();
    assert!(pressed.iter().all(|p| p.particle as usize != centre));
    let mut st = sim.state().clone();
    st.pressed.push(rkforge_core::solver::Pressed {
        particle: centre as u32,
        tool: 1,
        force_n: f,
        normal: [0.0, 0.0, -1.0],
    });
    let mut with = sim.clone();
    with.restore(st).unwrap();
    let more = with.die_pressure(1);
    let added: Vec<(f64, f64)> = more
        .forces
        .iter()
        .zip(&die.forces)
        .zip(&die.areas)
        .filter(|((a, b), _)| **a != **b)
        .map(|((a, b), &area)| (a - b, area))
        .collect();
    let spread: f64 = added.iter().map(|(_, a)| a).sum();
    let carried: f64 = added.iter().map(|(df, _)| df).sum();
    let highest = added.iter().map(|(df, a)| df / a).fold(0.0, f64::max);
    let patch = area / n;
    eprintln!(
        "a particle of no area of its own: {} triangles, {spread:.4e} m^2 against the mean patch {patch:.4e} m^2, highest added pressure {highest:.4e} against f / patch {:.4e} Pa",
        added.len(),
        f / patch
    );
    assert!((carried / f - 1.0).abs() < 1e-9);
    assert!((spread / patch - 1.0).abs() < 0.5, "{spread} {patch}");
    assert!(highest < 2.0 * f / patch, "{highest} {}", f / patch);
}

/// Fill points on the ram's face, which starts 0.5 mm above the block, with a fill distance
/// of 0.1 spacings (0.125 mm): the block does not move before the ram touches it, so a point
/// above a particle of its top face (the corner on the axis, `centre`, and the outer corner,
/// `corner`) fills when the ram's face comes within 0.125 mm of it, at the stroke `0.5 -
/// 0.125 = 0.375` mm, within one step's travel; a point beyond the block (`beyond`, 12 mm out)
/// stays empty. The same with the ram as an STL box. A point off the die's surface is
/// refused at setup naming its key.
#[test]
fn fill_points_on_a_die_fill_at_the_stroke_the_gap_gives() {
    let dir = folder("fill");
    let file = dir.path().join("block.toml");
    let fill = |points: &[(&str, [f64; 3])]| -> String {
        points
            .iter()
            .map(|(n, p)| {
                format!(
                    "[[tools.fill_points]]\nname = \"{n}\"\nat_m = [{:e}, {:e}, {:e}]\n",
                    p[0], p[1], p[2]
                )
            })
            .collect()
    };
    let on_face = [
        ("centre", [0.0, 0.0, 0.0105]),
        ("corner", [0.005, 0.005, 0.0105]),
        ("beyond", [0.012, 0.0, 0.0105]),
    ];
    let mut strokes = Vec::new();
    for stl in [false, true] {
        let (anvil, ram) = block_dies(dir.path(), 0.5, stl);
        let s = scene(
            &block_text(&anvil, &ram, 500e-6, &fill(&on_face), 0.1),
            &file,
        )
        .unwrap();
        let sim = run_to_end(&s);
        let points = sim.fill_points();
        let expected = 0.5e-3 - 0.1 * sim.h_min();
        let travel = 2.0 * sim.critical_dt0();
        for p in &points[..2] {
            let f = p.filled.unwrap();
            eprintln!(
                "{} (stl {stl}) filled at {:.4e} s, stroke {:.6e} m against {expected:.6e} m (+{:.3e} m, a step's travel at most {travel:.3e} m)",
                p.name,
                f.time_s,
                f.stroke_m,
                f.stroke_m - expected
            );
            assert!(f.stroke_m >= expected && f.stroke_m - expected <= travel);
            assert_eq!(column(&sim, &format!("ram.{}.filled", p.name)), 1.0);
            strokes.push(f.stroke_m.to_bits());
        }
        assert!(points[2].filled.is_none());
        assert_eq!(column(&sim, "ram.beyond.filled"), 0.0);
        assert!(sim.tools()[1].state.stroke > 0.99e-3);
        for (at, side) in [(0.0125, "inside"), (0.0085, "in front of")] {
            let bad = fill(&[("centre", [0.0, 0.0, 0.0105]), ("off", [0.0, 0.0, at])]);
            let s = scene(&block_text(&anvil, &ram, 500e-6, &bad, 0.1), &file).unwrap();
            let e = SolidSimulation::new(&s).unwrap_err().to_string();
            eprintln!("{e}");
            assert!(
                e.contains("tools[1].fill_points[1].at_m") && e.contains(side),
                "{e}"
            );
        }
    }
    assert_eq!(strokes[..2], strokes[2..]);
    let twice = fill(&[
        ("centre", [0.0, 0.0, 0.0105]),
        ("centre", [0.0, 0.0, 0.0105]),
    ]);
    let (anvil, ram) = block_dies(dir.path(), 0.5, false);
    let e = scene(&block_text(&anvil, &ram, 500e-6, &twice, 0.1), &file).unwrap_err();
    assert!(e.contains("tools[1].fill_points[1].name"), "{e}");
}

/// A closed cylinder (in the file's unit) about the line through `centre` along the
/// coordinate axis `axis`, of radius `r` and half length `h`: `n` side quads (inscribed,
/// their vertices on the circle) as two triangles each and its two caps as fans, wound out.
fn cylinder_triangles(
    centre: [f32; 3],
    axis: usize,
    r: f32,
    h: f32,
    n: usize,
) -> Vec<[[f32; 3]; 3]> {
    // `u, v, d` right-handed: `d` the axis.
    let (ku, kv) = ((axis + 1) % 3, (axis + 2) % 3);
    let point = |i: usize, a: f32| -> [f32; 3] {
        let t = std::f64::consts::TAU * (i % n) as f64 / n as f64;
        let mut p = centre;
        p[ku] += r * t.cos() as f32;
        p[kv] += r * t.sin() as f32;
        p[axis] += a;
        p
    };
    let mut ends = [centre; 2];
    ends[0][axis] -= h;
    ends[1][axis] += h;
    let mut t = Vec::with_capacity(4 * n);
    for i in 0..n {
        let (b0, b1, t0, t1) = (point(i, -h), point(i + 1, -h), point(i, h), point(i + 1, h));
        t.push([b0, b1, t1]);
        t.push([b0, t1, t0]);
        t.push([ends[1], t0, t1]);
        t.push([ends[0], b1, b0]);
    }
    t
}

/// A quarter block of aluminium 5 mm wide (x), `y` mm deep and 5 mm high on a fixed plane
/// anvil, pressed by the cylinder `cylinder` (its `[[tools]]` keys) moving down at 2 m/s
/// for `end` s; particles 0.5 mm apart, Coulomb friction 0.1 on the cylinder.
fn pressed_block_text(y: f64, cylinder: &str, end: f64) -> String {
    let ny = (y / 0.5).round() as usize + 1;
    let ram = format!("friction = 0.1\n{cylinder}");
    pressed_box([5.0, y, 5.0], [11, ny, 11], end, ANVIL_PLANE, &ram)
}

/// What one cylinder run gives: the ram's stroke and force at every step, the deepest
/// particle (physical positions against the exact tools, every 20 steps, m), the energy
/// balance at the end, the contact stage's time (s) and the simulation.
struct CylinderRun {
    curve: Vec<[f64; 2]>,
    deepest: f64,
    balance: f64,
    contact_s: f64,
    sim: SolidSimulation,
}

fn run_cylinder(scene: &SolidScene) -> CylinderRun {
    let mut sim = SolidSimulation::new(scene).unwrap();
    let (mut curve, mut deepest) = (Vec::new(), 0.0_f64);
    sim.run_toward(scene.time.end_s, u64::MAX, |s, step| {
        let ram = &s.tools()[1];
        curve.push([ram.state.stroke, ram.axial_force()]);
        if step % 20 == 0 {
            deepest = deepest.max(s.penetration_now()[0].0);
        }
        true
    })
    .unwrap();
    deepest = deepest.max(sim.penetration_now()[0].0);
    CylinderRun {
        curve,
        deepest,
        balance: sim.energy().balance_error_rel(),
        contact_s: sim.times.contact.as_secs_f64(),
        sim,
    }
}

/// The force of a stroke-force `curve` (m, N; strokes increasing) at the stroke `s` (m),
/// linear between its points.
fn force_at(curve: &[[f64; 2]], s: f64) -> f64 {
    let k = curve
        .partition_point(|p| p[0] < s)
        .clamp(1, curve.len() - 1);
    let ([s0, f0], [s1, f1]) = (curve[k - 1], curve[k]);
    f0 + (f1 - f0) * (s - s0) / (s1 - s0)
}

/// The analytic cylinder against the same cylinder as a fine STL (`n` facets round):
/// the force-stroke curves at each tenth of the stroke within `tol` of the largest force
/// (the facets are inscribed, `R (1 - cos(pi / n))` inside the circle), the deepest
/// particle against the analytic surface under 5 % of a spacing, the energy balance within
/// the run's default check (1e-2), the analytic contact stage cheaper, and the pressure
/// over the contact patch on the cylinder adding up to its normal force. Returns the
/// analytic run.
fn cylinder_against_stl(
    name: &str,
    y: f64,
    analytic: &str,
    stl: Vec<[[f32; 3]; 3]>,
    end: f64,
    tol: f64,
) -> CylinderRun {
    let dir = folder(name);
    write_binary(&dir.path().join("dies/cylinder.stl"), &stl);
    let file = dir.path().join("cylinder.toml");
    let by_stl = "shape = \"stl\"\nfile = \"dies/cylinder.stl\"\nunit = \"mm\"";
    let exact = run_cylinder(&scene(&pressed_block_text(y, analytic, end), &file).unwrap());
    let faceted = run_cylinder(&scene(&pressed_block_text(y, by_stl, end), &file).unwrap());
    let h = exact.sim.h_min();
    let peak = exact.curve.iter().map(|p| -p[1]).fold(0.0, f64::max);
    let mut worst = 0.0_f64;
    let stroke = exact.curve.last().unwrap()[0].min(faceted.curve.last().unwrap()[0]);
    for tenth in 1..=10 {
        let s = stroke * tenth as f64 / 10.0;
        let (a, b) = (force_at(&exact.curve, s), force_at(&faceted.curve, s));
        worst = worst.max((a - b).abs() / peak);
        eprintln!(
            "{name}: stroke {:.3} mm force {:.1} N analytic, {:.1} N STL ({:+.2} %)",
            s * 1e3,
            -a,
            -b,
            100.0 * (a - b) / b
        );
    }
    eprintln!(
        "{name}: worst force difference {:.2} % of the peak {peak:.1} N; deepest {:.3} (STL {:.3}) of a spacing; balance {:.2e} (STL {:.2e}); contact stage {:.3} s analytic, {:.3} s STL ({} triangles), {} steps",
        100.0 * worst,
        exact.deepest / h,
        faceted.deepest / h,
        exact.balance,
        faceted.balance,
        exact.contact_s,
        faceted.contact_s,
        stl.len(),
        exact.sim.steps()
    );
    assert!(worst < tol, "{worst}");
    // The pressure over the contact patch on the cylinder: its corners on the surface, its
    // forces adding up to the tool's normal force.
    let die = exact.sim.die_pressure(1);
    let tool = &exact.sim.tools()[1];
    let total: f64 = die.forces.iter().sum();
    eprintln!(
        "{name}: patch of {} triangles, {total:.6e} N against the normal force {:.6e} N",
        die.triangles.len(),
        tool.state.normal_force
    );
    assert!(!die.triangles.is_empty());
    assert!((total - tool.state.normal_force).abs() < 1e-9 * tool.state.normal_force.abs());
    assert!(die.vertices.iter().all(|v| tool.depth_of(*v).abs() < 1e-12));
    assert!(exact.deepest < 0.05 * h, "{}", exact.deepest / h);
    assert!(exact.balance < 1e-2 && faceted.balance < 1e-2);
    assert!(exact.contact_s < faceted.contact_s);
    exact
}

/// A bar of radius 2 mm lying across the block (unbounded along y, its axis at x = 0, z = 7
/// mm: touching the top face at the start) pressed 1 mm (two spacings) into it: fullering,
/// the mantle against the material. The same bar as an STL of 512 facets, 2048 triangles.
#[test]
fn a_bar_pressed_across_a_block_gives_the_stl_bars_force() {
    let bar = "shape = \"cylinder\"\ncenter_m = [0.0, 0.0, 0.007]\naxis_direction = [0.0, 1.0, 0.0]\nradius_m = 0.002";
    let stl = cylinder_triangles([0.0, 1.5, 7.0], 1, 2.0, 3.5, 512);
    let run = cylinder_against_stl("bar", 2.5, bar, stl, 500e-6, 0.03);
    assert!(run.curve.last().unwrap()[1] < -1e3);
}

/// A pin of radius 1.5 mm and 4 mm long, its axis on the block's corner line x = y = 0
/// and its flat end on the top face at the start, pressed 1 mm into it: the cap, its rim
/// and the mantle against the material. The same pin as an STL of 512 facets.
#[test]
fn a_pin_pressed_into_a_block_gives_the_stl_pins_force() {
    let pin = "shape = \"cylinder\"\ncenter_m = [0.0, 0.0, 0.007]\naxis_direction = [0.0, 0.0, 1.0]\nradius_m = 0.0015\nlength_m = 0.004";
    let stl = cylinder_triangles([0.0, 0.0, 7.0], 2, 1.5, 2.0, 512);
    let run = cylinder_against_stl("pin", 5.0, pin, stl, 500e-6, 0.03);
    assert!(run.curve.last().unwrap()[1] < -1e3);
}
