//! The second pass of the 3D contact (`ridges.rs`): a knife edge and a pyramid's tip pressed
//! into a block between its surface particles, with and without the pass.

use super::*;
use crate::scene::SceneFile;
use crate::stl::TriangleMesh;
use std::path::{Path, PathBuf};

/// A folder of this test's own.
fn folder(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rkforge_ridges_{name}_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes `mesh` (m) as an ASCII STL file in metres, its triangles turned out of the die
/// when they were wound inward.
fn write_stl(path: &Path, mut mesh: TriangleMesh) {
    if mesh.volume() < 0.0 {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
    mesh.check().unwrap();
    let mut s = String::from("solid die\n");
    for t in &mesh.triangles {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for &v in t {
            let p = mesh.vertices[v as usize];
            s += &format!("      vertex {:e} {:e} {:e}\n", p[0], p[1], p[2]);
        }
        s += "    endloop\n  endfacet\n";
    }
    s += "endsolid die\n";
    std::fs::write(path, s).unwrap();
}

/// The prism of the polygon `section` in the x-z plane (m, in order around it) from
/// `y0` to `y1` (m).
fn prism(section: &[[Real; 2]], y0: Real, y1: Real) -> TriangleMesh {
    let n = section.len() as u32;
    let vertices = [y0, y1]
        .iter()
        .flat_map(|&y| section.iter().map(move |p| [p[0], y, p[1]]))
        .collect();
    let mut triangles = Vec::new();
    for k in 0..n {
        let l = (k + 1) % n;
        triangles.push([k, l, n + l]);
        triangles.push([k, n + l, n + k]);
    }
    for k in 1..n - 1 {
        triangles.push([0, k + 1, k]);
        triangles.push([n, n + k, n + k + 1]);
    }
    TriangleMesh {
        vertices,
        triangles,
    }
}

/// The square pyramid with its tip at `tip` (m), pointing down, of height `h` (m) and base
/// half-width `w` (m).
fn pyramid(tip: [Real; 3], h: Real, w: Real) -> TriangleMesh {
    let base = |sx: Real, sy: Real| [tip[0] + sx * w, tip[1] + sy * w, tip[2] + h];
    TriangleMesh {
        vertices: vec![
            tip,
            base(-1.0, -1.0),
            base(1.0, -1.0),
            base(1.0, 1.0),
            base(-1.0, 1.0),
        ],
        triangles: vec![
            [0, 2, 1],
            [0, 3, 2],
            [0, 4, 3],
            [0, 1, 4],
            [1, 2, 3],
            [1, 3, 4],
        ],
    }
}

/// A steel block 8 x 4 x 4 mm of 1 mm particles on a fixed flat anvil, the die of
/// `die.stl` (m) coming down at 10 m/s, frictionless unless `friction` says, for `end_s`.
fn block(dir: &Path, end_s: Real, friction: &str) -> SolidScene {
    let text = format!(
        r#"
name = "ridges"
[model]
kinematics = "3d"
[workpiece]
shape = "box"
origin_m = [0.0, 0.0, 0.0]
size_m = [0.008, 0.004, 0.004]
particles = [9, 5, 5]
[material]
density_kg_per_m3 = 7800.0
youngs_modulus_pa = 200e9
poisson_ratio = 0.3
hardening = {{ law = "linear", yield_stress_pa = 300e6, modulus_pa = 1e9 }}
[time]
end_s = {end_s:e}
[[tools]]
name = "anvil"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "fixed" }}
[[tools]]
name = "die"
shape = "stl"
file = "die.stl"
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "constant", velocity_m_per_s = 10.0 }}
{friction}
"#
    );
    match SceneFile::from_str_named(&text, &dir.join("ridges.toml").display().to_string()).unwrap()
    {
        SceneFile::Solid(s) => *s,
        SceneFile::Plane(_) => panic!("not 3D"),
    }
}

/// What a run measured: the die's axial force at each step (N), the deepest its ridges
/// and the particles lay (m), the largest energy balance error (-).
struct Ran {
    force: Vec<Real>,
    ridge_depth: Real,
    particle_depth: Real,
    balance: Real,
    sim: SolidSimulation,
}

fn run(scene: &SolidScene, pass: bool) -> Ran {
    let mut sim = SolidSimulation::new(scene).unwrap();
    sim.ws.contact.ridges.on = pass;
    let mut ran = (Vec::new(), 0.0 as Real, 0.0 as Real, 0.0 as Real);
    sim.run_toward(scene.time.end_s, u64::MAX, |s, _| {
        ran.0.push(-s.tools()[1].axial_force());
        ran.1 = ran.1.max(s.ridge_depth_now());
        ran.2 = ran.2.max(s.penetration_now()[0].0);
        ran.3 = ran.3.max(s.energy().balance_error_rel());
        true
    })
    .unwrap();
    Ran {
        force: ran.0,
        ridge_depth: ran.1,
        particle_depth: ran.2,
        balance: ran.3,
        sim,
    }
}

/// The box die's ridges: its twelve edges and eight corners; a pyramid's eight edges, its
/// tip and its base's four corners.
#[test]
fn a_box_and_a_pyramid_have_their_edges_and_corners_as_ridges() {
    let die = crate::triangle_surface::TriangleSurface::new(crate::stl::tests::box_mesh(
        [0.0; 3],
        [1.0, 2.0, 3.0],
    ));
    let corners = |s: &crate::triangle_surface::TriangleSurface| {
        s.ridges().iter().filter(|r| r.a == r.b).count()
    };
    assert_eq!((die.ridges().len(), corners(&die)), (20, 8));
    let tip = crate::triangle_surface::TriangleSurface::new(pyramid([0.0; 3], 1.0, 0.5));
    assert_eq!(
        (tip.ridges().len(), corners(&tip)),
        (13, 5),
        "4 slanted edges, the base's 4, the tip and the base's corners"
    );
}

/// The wedge of half-angle 30 degrees with its edge along y at `x` (m), 0.02 mm above the
/// block, from y = -1 to 5 mm, written to `dir/die.stl`.
fn knife(dir: &Path, x: Real) {
    let half = (30.0 as Real).to_radians().tan() * 4e-3;
    let edge_z = 4.02e-3;
    write_stl(
        &dir.join("die.stl"),
        prism(
            &[
                [x, edge_z],
                [x + half, edge_z + 4e-3],
                [x - half, edge_z + 4e-3],
            ],
            -1e-3,
            5e-3,
        ),
    );
}

/// The largest change of the force from one step to the next (N) once it has reached half
/// its final value (past the impact of the first touch), over the final force (-).
fn largest_jump(force: &[Real]) -> Real {
    let last = force[force.len() - 1];
    let from = force.iter().position(|&f| f > 0.5 * last).unwrap_or(0);
    force[from..]
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(0.0, Real::max)
        / last
}

/// One run with the pass and one without of the block under the die in `dir`.
fn with_and_without(dir: &Path) -> (Ran, Ran) {
    let scene = block(dir, 62e-6, "");
    let without = run(&scene, false);
    (run(&scene, true), without)
}

/// Prints and checks a die pressed 0.6 mm into the block between its surface particles:
/// without the pass its ridge sinks more than half a spacing below the surface facets
/// and the die takes no force; with it the ridge and the particles stay within 5 % of a
/// spacing, the force rises from the first touch without a jump past its impact and the
/// energy account closes.
fn check(name: &str, with: &Ran, without: &Ran) {
    let h = with.sim.h_min();
    let top = without.force.iter().copied().fold(0.0, Real::max);
    let end_force = with.force[with.force.len() - 1];
    eprintln!(
        "{name}: without the pass the ridge lay {:.3} spacings deep, the force at most {top:.3e} N; with it {:.4} spacings, particles {:.4}, force {end_force:.4e} N at the end, largest step change past half of it {:.3} of it, balance {:.2e}",
        without.ridge_depth / h,
        with.ridge_depth / h,
        with.particle_depth / h,
        largest_jump(&with.force),
        with.balance,
    );
    assert!(without.ridge_depth > 0.5 * h, "{}", without.ridge_depth);
    assert!(top < 1e-9, "{top}");
    assert!(with.ridge_depth < 0.05 * h, "{}", with.ridge_depth);
    assert!(with.particle_depth < 0.05 * h, "{}", with.particle_depth);
    assert!(end_force > 1e3, "{end_force}");
    assert!(
        largest_jump(&with.force) < 0.05,
        "{}",
        largest_jump(&with.force)
    );
    assert!(with.balance < 0.01, "{}", with.balance);
}

/// A wedge (half-angle 30 degrees, its edge along y at x = 4.5 mm, midway between the
/// surface particles' rows x = 4 and 5 mm): no particle reaches the wedge's faces before
/// the edge is 0.87 mm deep ([`check`]).
#[test]
fn a_knife_edge_cannot_cut_between_two_particle_rows() {
    let dir = folder("knife");
    knife(&dir, 4.5e-3);
    let (with, without) = with_and_without(&dir);
    check("knife", &with, &without);
}
