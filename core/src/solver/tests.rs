//! Tests of the solver's internals: grouped and SIMD stress stages, shared blocks and
//! contact skipping against their plain counterparts, bit for bit.

use super::detachment;
use super::layout::Scatter;
use super::Simulation;
use crate::integration::point_shapes;
use crate::math::Real;
use crate::rk_shape::{Lattice, ShapeTable};
use crate::tools::Driven;
use crate::{IntegrationRule, Scene};

const RULES: [IntegrationRule; 3] = [
    IntegrationRule::Q4,
    IntegrationRule::Q2,
    IntegrationRule::Scni,
];

/// The shipped Taylor bar with `rule` on a grid of `particles`.
fn taylor(rule: IntegrationRule, particles: [usize; 2]) -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/taylor_bar.toml");
    let mut scene = Scene::from_file(std::path::Path::new(path))
        .unwrap()
        .with_integration(rule);
    scene.workpiece.particles = particles;
    scene
}

/// The point shape table of a simulation, built again as its setup builds it.
fn point_table(sim: &Simulation) -> ShapeTable {
    let (nx, ny) = sim.grid();
    let (h, s) = (sim.spacing(), sim.scene.discretization.support);
    let support = [s[0] * h[0], s[1] * h[1]];
    let lattice = Lattice::new(sim.scene.workpiece.origin_m, h, [nx, ny], support);
    point_shapes(&lattice, sim.scene.discretization.integration)
        .unwrap()
        .1
}

/// The stress stage processes points in groups: the 4 points of a q4 cell over their
/// shared list; two q2 cells (2 + 2 points) as a strip where their lists are the same
/// offsets one particle apart, else over the union of their lists, zero-padded, as four
/// SCNI points are. The bits must equal a point-by-point loop.
#[test]
fn grouped_points_give_the_bits_of_single_points() {
    for rule in RULES {
        let scene = taylor(rule, [11, 26]);
        let mut grouped = Simulation::new(&scene).unwrap();
        let sc = &grouped.disc.scatter;
        let in_quads = sc.group.iter().filter(|&&g| g == 4).count() * 4;
        assert!(
            in_quads * 10 >= sc.group.len() * 9,
            "{rule:?}: {in_quads} of {} points in groups of 4",
            sc.group.len()
        );
        // On 10 cells a row, three pairs of the five are strips (not the edge cells).
        let in_strips = sc.strip.iter().filter(|&&s| s).count() * 4;
        assert_eq!(
            in_strips * 5 >= sc.group.len() * 3,
            rule == IntegrationRule::Q2,
            "{rule:?}: {in_strips} of {} points in strips",
            sc.group.len()
        );
        // Merged SCNI groups run over a union longer than one point's own list (a q2
        // pair that is not a strip has an edge cell, whose list the other's holds).
        let longest_union = (0..sc.group.len())
            .filter(|&p| sc.group[p] == 4)
            .map(|p| (sc.list_range[p][1] - sc.list_range[p][0]) as usize)
            .max();
        let pt = point_table(&grouped);
        let longest_own = (0..pt.rows()).map(|p| pt.row(p).len()).max();
        assert_eq!(
            longest_union > longest_own,
            rule == IntegrationRule::Scni,
            "{rule:?}: unions {longest_union:?}, own lists {longest_own:?}"
        );
        let mut single = grouped.clone();
        single.disc.scatter = Scatter::new(
            &pt,
            single.disc.ref_pos.len(),
            grouped.disc.scatter.chunk,
            1,
        );
        for _ in 0..200 {
            grouped.step(None).unwrap();
            single.step(None).unwrap();
        }
        assert!(
            grouped.max_plastic_strain() > 0.05,
            "{rule:?}: plastic flow"
        );
        assert_eq!(grouped.st.d, single.st.d, "{rule:?}");
        assert_eq!(grouped.st.points, single.st.points, "{rule:?}");
        assert_eq!(grouped.st.energy, single.st.energy, "{rule:?}");
    }
}

/// On a uniform grid the interior groups' shape-function blocks are bitwise equal (they
/// are formed from lattice offsets) and stored once: on 81 x 201 the stored table is
/// 0.13 % (q4), 0.15 % (q2) and 0.49 % (SCNI) of one block per group, the distinct
/// neighbourhoods near the edges.
#[test]
fn interior_groups_share_their_stored_tables() {
    for rule in RULES {
        let scene = taylor(rule, [81, 201]);
        let sim = Simulation::new(&scene).unwrap();
        let sc = &sim.disc.scatter;
        let unshared: usize = (0..sc.group.len())
            .filter(|&p| sc.group[p] > 0)
            .map(|p| {
                let [a, b] = sc.list_range[p];
                3 * sc.group[p] as usize * (b - a) as usize
            })
            .sum();
        let share = sc.table.len() as f64 / unshared as f64;
        assert!(share < 0.01, "{rule:?}: stored {share:.4} of the blocks");
    }
}

/// The point rows read back from the shared blocks are the shape table's rows, bit for
/// bit, with zeros only where a particle belongs to another point of the group.
#[test]
fn point_rows_from_the_shared_blocks_are_the_table_rows() {
    for rule in RULES {
        let scene = taylor(rule, [11, 26]);
        let sim = Simulation::new(&scene).unwrap();
        let pt = point_table(&sim);
        for p in 0..pt.rows() {
            let own: Vec<(usize, [u64; 3])> = pt
                .row(p)
                .map(|e| {
                    let v = [pt.n[e], pt.grad[0][e], pt.grad[1][e]];
                    (pt.index[e] as usize, v.map(f64::to_bits))
                })
                .collect();
            let mut read = Vec::new();
            for (i, v) in sim.point_shapes(p) {
                if own.iter().any(|&(j, _)| j == i) {
                    read.push((i, v.map(f64::to_bits)));
                } else {
                    assert_eq!(v, [0.0; 3], "{rule:?}: point {p}, particle {i}");
                }
            }
            assert_eq!(read, own, "{rule:?}: point {p}");
        }
    }
}

/// The isolation's pass over the scatter's groups (each group's points formed over its
/// list, then its pairs) gives the distances of the plain formulation, bit for bit: each
/// point formed alone over its own entries, then every (point, particle) pair with
/// `N != 0` ([`detachment::nearest_points`]), on a deformed bar with each rule (q2's strips,
/// q4's cells, SCNI's own points left out).
#[test]
fn isolation_by_groups_gives_the_bits_of_single_points() {
    for rule in RULES {
        let scene = taylor(rule, [11, 26]);
        let mut sim = Simulation::new(&scene).unwrap();
        for _ in 0..400 {
            sim.step(None).unwrap();
        }
        assert!(sim.max_plastic_strain() > 0.05, "{rule:?}: plastic flow");
        let (d, sc) = (&sim.st.d, &sim.disc.scatter);
        let reference = &sim.disc.points.positions;
        let particles = sim.positions();
        let nodal = rule == IntegrationRule::Scni;
        let points: Vec<[Real; 2]> = (0..reference.len())
            .map(|p| {
                let mut x = reference[p];
                for (i, n, _) in sc.point_entries(p) {
                    for k in 0..2 {
                        x[k] += n * d[i][k];
                    }
                }
                x
            })
            .collect();
        let pairs = (0..points.len()).flat_map(|p| {
            sc.point_entries(p)
                .filter(move |&(i, n, _)| n != 0.0 && !(nodal && i == p))
                .map(move |(i, _, _)| (p, i))
        });
        let plain = detachment::nearest_points(&particles, &points, pairs);
        let grouped = detachment::point_distances(&detachment::Body {
            scatter: sc,
            points: reference,
            d,
            particles: &particles,
            nodal,
        });
        assert_eq!(
            grouped.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            plain.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            "{rule:?}"
        );
    }
}

/// The AVX2 build of the stress stage gives the bits of the generic build (no fused
/// multiply-adds, lanes independent), so results do not depend on the CPU's features.
#[test]
fn simd_and_generic_stress_stages_give_the_same_bits() {
    #[cfg(target_arch = "x86_64")]
    if !std::arch::is_x86_feature_detected!("avx2") {
        eprintln!("no AVX2 on this CPU: both runs take the generic path");
    }
    for rule in RULES {
        let scene = taylor(rule, [11, 26]);
        let mut simd = Simulation::new(&scene).unwrap();
        let mut generic = simd.clone();
        generic.ws.simd = false;
        for _ in 0..300 {
            simd.step(None).unwrap();
            generic.step(None).unwrap();
        }
        assert!(simd.max_plastic_strain() > 0.05, "{rule:?}: plastic flow");
        assert_eq!(simd.st.d, generic.st.d, "{rule:?}");
        assert_eq!(simd.st.points, generic.st.points, "{rule:?}");
        assert_eq!(simd.st.energy, generic.st.energy, "{rule:?}");
    }
}

/// Skipping the particles whose clearance to every tool's search box is positive gives
/// the bits of evaluating all of them, on the shipped scenes, with tool
/// velocities that jump and reverse, and across a restore; and it does skip where the
/// tools' search boxes leave room.
#[test]
fn contact_skipping_gives_the_bits_of_checking_every_particle() {
    // The least share of evaluations skipped: most of the bar is far from the wall;
    // the block's top and bottom rows are always inside the dies' boxes; the wheel's
    // die is a container whose box holds the whole workpiece.
    for (name, particles, steps, least_skipped) in [
        ("taylor_bar", [11, 26], 600, 0.5),
        ("block_forging", [21, 21], 3000, 0.2),
        ("wheel_forging", [20, 20], 3000, 0.0),
    ] {
        let path = format!("{}/../scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let mut scene = Scene::from_file(std::path::Path::new(&path)).unwrap();
        scene.workpiece.particles = particles;
        let mut skipping = Simulation::new(&scene).unwrap();
        let mut all = skipping.clone();
        all.ws.contact.skip = false;
        let (mut skipped, mut evaluated) = (0, 0);
        for step in 0..steps {
            if step == steps / 3 || step == 2 * steps / 3 {
                // A jump to 50 m/s, then a reversal: the tools leave.
                let v = if step == steps / 3 { 50.0 } else { -20.0 };
                for sim in [&mut skipping, &mut all] {
                    for t in 0..sim.tools().len() {
                        if sim.tools()[t].is_movable() {
                            sim.set_tool_velocity(t, v).unwrap();
                        }
                    }
                }
            }
            if step == steps / 2 {
                let saved = skipping.state().clone();
                skipping.restore(saved).unwrap();
            }
            skipping.step(None).unwrap();
            all.step(None).unwrap();
            // Every particle is a candidate (the ring first); a positive clearance skips it.
            let clearance = &skipping.ws.contact.clearance;
            let positive = clearance.iter().filter(|&&c| c > 0.0).count();
            skipped += positive;
            evaluated += clearance.len() - positive;
        }
        assert_eq!(skipping.state(), all.state(), "{name}");
        assert!(
            skipping.tools().iter().any(|t| t.state.peak_force > 0.0),
            "{name}: contact"
        );
        assert!(
            skipped as f64 >= least_skipped * (skipped + evaluated) as f64,
            "{name}: skipped {skipped}, evaluated {evaluated}"
        );
    }
}

/// Each tool's impulse is the momentum the workpiece gave up to it: on the Taylor bar
/// against its wall (the only outside force; the internal forces sum to zero by the shape
/// functions' partition of unity, and the axis holds only radial motion), the bar's axial
/// momentum `sum_I M_I v_I` changes by minus the wall's impulse along its axis, to
/// round-off, with every rule; and the wall, fixed, does no work.
#[test]
fn a_tools_impulse_is_the_momentum_the_workpiece_gave_up() {
    for rule in RULES {
        let mut sim = Simulation::new(&taylor(rule, [11, 26])).unwrap();
        let momentum = |sim: &Simulation| -> Real {
            sim.disc
                .mass
                .iter()
                .zip(&sim.st.v)
                .map(|(m, v)| m * v[1])
                .sum()
        };
        let p0 = momentum(&sim);
        sim.run_to(30e-6, |_| {}).unwrap();
        let wall = &sim.tools()[0];
        let (axis, account) = (wall.axis[1], wall.state.account);
        let lost = (p0 - momentum(&sim)) * axis;
        assert!(
            account.impulse > 0.3 * p0.abs(),
            "{rule:?}: the wall took {} N s of {p0} N s",
            account.impulse
        );
        assert!(
            (lost - account.impulse).abs() < 1e-9 * p0.abs(),
            "{rule:?}: momentum lost {lost} N s, impulse {} N s",
            account.impulse
        );
        assert_eq!(account.work, 0.0);
    }
}
