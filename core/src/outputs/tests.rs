use super::*;
use crate::Scene;

fn scene(file: &str) -> Scene {
    let path = format!("{}/../scenes/{file}", env!("CARGO_MANIFEST_DIR"));
    Scene::from_file(std::path::Path::new(&path)).unwrap()
}

#[test]
fn every_section_is_of_one_kind_and_every_entry_complete() {
    check_sections(&REGISTER);
    check_sections(&SOLID_REGISTER);
}

fn check_sections<S: Body>(register: &[&[Output<S>]]) {
    for section in register {
        let kind = section[0].read.kind();
        for o in *section {
            assert_eq!(o.read.kind(), kind, "{} in a section of {kind:?}", o.name);
            assert!(!o.name.is_empty() && !o.unit.is_empty() && !o.description.is_empty());
            let placeholder = |p: &str| o.description.contains(p);
            assert_eq!(
                placeholder("{tool}"),
                matches!(kind, Kind::PerTool | Kind::PerFillPoint),
                "{}",
                o.name
            );
            assert_eq!(placeholder("{point}"), kind == Kind::PerFillPoint);
            assert_eq!(placeholder("{face}"), kind == Kind::PerFace);
            let field = matches!(kind, Kind::PerParticle | Kind::PerPoint);
            assert_eq!(o.shown == Shown::FIELD, field, "{}", o.name);
        }
    }
}

#[test]
fn column_names_are_unique_in_every_shipped_scene() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes");
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let mut names: Vec<String> = match crate::scene::solid::SceneFile::from_file(&path).unwrap()
        {
            crate::scene::solid::SceneFile::Solid(scene) => {
                let mut names: Vec<String> =
                    solid_columns(&scene).into_iter().map(|c| c.name).collect();
                names.extend(solid_fields(&scene).map(Output::full_name));
                names
            }
            crate::scene::solid::SceneFile::Plane(scene) => {
                let mut names: Vec<String> = columns(&scene).into_iter().map(|c| c.name).collect();
                names.extend(fields(&scene).map(Output::full_name));
                names
            }
        };
        let count = names.len();
        assert!(count > 10, "{}", path.display());
        names.sort();
        names.dedup();
        assert_eq!(names.len(), count, "{}", path.display());
    }
}

#[test]
fn a_scene_expands_tool_by_tool_in_history_order() {
    let s = scene("closed_die_hub_hot.toml");
    let cols = columns(&s);
    let history: Vec<&str> = cols
        .iter()
        .filter(|c| c.output.shown.history)
        .map(|c| c.name.as_str())
        .collect();
    let tool = s.tools[0].name.as_str();
    // One tool's columns side by side, then the next tool's.
    let first: Vec<String> = [
        "stroke_m",
        "velocity_m_per_s",
        "force_N",
        "force_mean_N",
        "force_x_N",
        "force_y_N",
        "contact_fraction",
        "pressure_mean_Pa",
        "impulse_N_s",
        "work_J",
    ]
    .iter()
    .map(|c| format!("{tool}.{c}"))
    .collect();
    assert_eq!(&history[..2], ["time_s", "dt_s"]);
    assert_eq!(history[2..12], first);
    assert!(history[12].starts_with(&format!("{}.", s.tools[1].name)));
    // Axisymmetric: the radius, not the width; thermal: the measures and heated tools.
    assert!(history.contains(&"workpiece.radius_m"));
    assert!(!history.contains(&"workpiece.width_m"));
    assert!(history.contains(&"thermal.temperature_max_c"));
    let heated = s.tools.iter().filter(|t| t.heat_transfer_w_per_m2_k > 0.0);
    for t in heated {
        assert!(history.contains(&format!("thermal.{}.heat_flow_W", t.name).as_str()));
    }
    let filled = cols.iter().find(|c| c.name.ends_with(".filled")).unwrap();
    let At::FillPoint { tool, within, .. } = filled.at else {
        panic!("{:?}", filled.at);
    };
    let point = &s.tools[tool].fill_points[within].name;
    assert_eq!(
        filled.name,
        format!("{}.{point}.filled", s.tools[tool].name)
    );
    assert!(filled
        .description(&s)
        .contains(&format!("point {point} of tool")));
}

#[test]
fn thermal_measures_read_the_register() {
    assert_eq!(THERMAL_MEASURES[0].0, "temperature_min_c");
    assert_eq!(THERMAL_MEASURES[0].1, "degC");
    // A pure number has no unit attribute.
    assert_eq!(
        THERMAL_MEASURES[8],
        (
            "heat_balance_rel",
            "",
            "heat content less the heat made plus the heat lost, over the heat made and lost"
        )
    );
    let isothermal = scene("block_forging.toml");
    assert!(columns(&isothermal)
        .iter()
        .all(|c| c.output.group != "thermal"));
    assert_eq!(fields(&isothermal).count(), 6);
}

#[test]
fn a_sample_reads_every_column_and_field() {
    let text = include_str!("../../../scenes/block_forging.toml")
        .replace("particles = [21, 21]", "particles = [6, 6]");
    let scene = Scene::from_str_named(&text, "block").unwrap();
    let mut sim = Simulation::new(&scene).unwrap();
    for _ in 0..50 {
        sim.step(None).unwrap();
    }
    let sample = Sample::new(&sim);
    let value = |name: &str| {
        let c = columns(&scene)
            .into_iter()
            .find(|c| c.name == name)
            .unwrap();
        c.value(&sample)
    };
    assert_eq!(value("time_s"), sim.time());
    assert_eq!(value("top.force_N"), sim.tools()[0].axial_force());
    assert_eq!(value("energy.kinetic_J"), sim.energy().kinetic);
    let x = sim.extents();
    assert_eq!(value("workpiece.width_m"), x.x[1] - x.x[0]);
    assert_eq!(value("workpiece.max_penetration_rel"), {
        let h = sim.spacing();
        sim.penetration().tools.depth / h[0].min(h[1])
    });
    for f in fields(&scene) {
        let n = match f.read.kind() {
            Kind::PerParticle => sim.particle_count(),
            _ => sim.point_count(),
        };
        assert_eq!(f.field(&sample).unwrap().len(), n, "{}", f.full_name());
    }
}

/// The tools' accounts: their work sums to the energy account's tool work, and the force
/// averaged over an interval is the change of impulse over it, over the whole run when no
/// sample came before, and the last step's force over an empty interval.
#[test]
fn the_tools_work_sums_to_the_tool_work_and_the_mean_force_to_the_impulse() {
    let text = include_str!("../../../scenes/block_forging.toml")
        .replace("particles = [21, 21]", "particles = [6, 6]");
    let scene = Scene::from_str_named(&text, "block").unwrap();
    let mut sim = Simulation::new(&scene).unwrap();
    let columns = columns(&scene);
    let column = |name: &str| columns.iter().find(|c| c.name == name).unwrap();
    for _ in 0..300 {
        sim.step(None).unwrap();
    }
    let before = Since::of(&sim);
    for _ in 0..200 {
        sim.step(None).unwrap();
    }
    let (t, t0) = (sim.time(), before.time);
    let accounts = sim.tool_accounts();
    let work: Real = accounts.iter().map(|a| a.work).sum();
    let tool_work = sim.energy().tool_work;
    assert!(tool_work > 0.0);
    assert!(
        (work - tool_work).abs() < 1e-12 * tool_work,
        "{work} {tool_work}"
    );
    let mean = column("top.force_mean_N");
    let since = Sample::new(&sim).since(Some(&before));
    let interval = (accounts[0].impulse - before.impulse[0]) / (t - t0);
    assert_eq!(mean.value(&since), interval);
    assert!(
        interval < 0.0,
        "the top die pressed against its axis: {interval} N"
    );
    let whole = Sample::new(&sim);
    assert_eq!(mean.value(&whole), accounts[0].impulse / t);
    let empty = Sample::new(&sim).since(Some(&Since::of(&sim)));
    assert_eq!(mean.value(&empty), sim.tools()[0].axial_force());
    assert_eq!(column("top.impulse_N_s").value(&whole), accounts[0].impulse);
    assert_eq!(column("bottom.work_J").value(&whole), accounts[1].work);
}
