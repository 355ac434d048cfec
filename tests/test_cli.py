"""End-to-end tests of `rkforge run`: the files it writes, their keys and values, and its
answers to bad scene files."""
import csv
import json
import subprocess
import xml.etree.ElementTree as ET

import pytest

from conftest import ROOT, assert_stages_account_for_the_wall_time, scene_variant

COARSE = {
    "particles = [21, 51]": "particles = [11, 26]",
    "dt_s = 5.0e-9                    # paper Table 1 (about 0.14 of the stable step)": "dt_safety = 0.5",
}


@pytest.fixture(scope="module")
def coarse_run(rkforge_bin, tmp_path_factory):
    """A coarse Taylor bar run with q4 (overriding the scene's q2 from the command line)."""
    tmp = tmp_path_factory.mktemp("taylor")
    scene = tmp / "taylor_coarse.toml"
    scene.write_text(scene_variant("taylor_bar.toml", COARSE))
    out = tmp / "out"
    proc = subprocess.run(
        [rkforge_bin, "run", str(scene), "--integration", "q4", "--out", str(out), "--quiet"],
        capture_output=True, text=True, timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    return out, proc.stdout


def test_summary_has_the_documented_keys_and_physical_values(coarse_run):
    out, _ = coarse_run
    s = json.loads((out / "summary.json").read_text())
    for key in ["scene", "integration", "particles", "integration_points", "steps", "end_time_s", "wall_s"]:
        assert key in s, key
    assert s["scene"] == "taylor_bar" and s["integration"] == "q4"
    assert s["particles"] == 11 * 26 and s["integration_points"] == 4 * 10 * 25
    assert abs(s["end_time_s"] - 80e-6) < 1e-12
    w = s["workpiece"]
    assert 6.8e-3 < w["radius_m"] < 7.5e-3
    assert 21.2e-3 < w["height_m"] < 21.9e-3
    assert abs(w["volume_change_rel"]) < 0.01
    assert w["max_plastic_strain"] > 1.5
    e = s["energy"]
    assert abs(e["initial_J"] - 239.8) < 0.2
    assert e["balance_error_rel"] < 0.01
    for key in ["kinetic_J", "internal_J", "plastic_J", "contact_J"]:
        assert key in e
    assert e["plastic_J"] > 0.9 * e["initial_J"] - abs(e["contact_J"]) - e["kinetic_J"] - e["elastic_J"] - 1.0
    (wall,) = s["tools"]
    assert wall["name"] == "wall" and wall["stroke_m"] == 0.0
    assert len(wall["force_N"]) == 2 and wall["peak_force_N"] > 1e5
    assert 0.0 <= s["contact"]["max_penetration_rel"] < 0.1


def test_history_is_a_time_series_with_tool_and_workpiece_columns(coarse_run):
    out, _ = coarse_run
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) > 100
    for col in ["time_s", "wall.stroke_m", "wall.force_N", "workpiece.radius_m", "workpiece.height_m",
                "energy.kinetic_J", "energy.plastic_J"]:
        assert col in rows[0], col
    t = [float(r["time_s"]) for r in rows]
    assert t[0] == 0.0 and all(b > a for a, b in zip(t, t[1:]))
    h = [float(r["workpiece.height_m"]) for r in rows]
    assert h[0] == pytest.approx(32.4e-3) and h[-1] < 22e-3
    # The bar pushes the wall along its axis (0, -1): positive axial force while in contact.
    f = [float(r["wall.force_N"]) for r in rows[1:20]]
    assert max(f) > 1e5


def test_frames_are_valid_vtk_and_plots_are_png(coarse_run):
    out, _ = coarse_run
    frames = sorted((out / "frames").glob("*.vtu"))
    assert len(frames) == 6  # t = 0 and the scene's 5 frames
    grid = ET.parse(frames[-1]).getroot().find("UnstructuredGrid/Piece")
    assert int(grid.get("NumberOfPoints")) == 11 * 26
    assert int(grid.get("NumberOfCells")) == 10 * 25
    names = {a.get("Name") for a in grid.find("PointData")}
    assert {"plastic_strain", "von_mises_Pa", "displacement_m", "velocity_m_per_s"} <= names
    pvd = ET.parse(out / "frames.pvd").getroot()
    assert len(pvd.findall("Collection/DataSet")) == 6
    for png in ["shape.png", "stages.png", "radius_history.png", "height_history.png", "energy.png", "forces.png"]:
        data = (out / png).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n", png


def test_stage_timers_account_for_the_wall_time(coarse_run):
    assert_stages_account_for_the_wall_time(*coarse_run)


def test_a_history_interval_that_does_not_divide_the_run_still_reaches_the_end(rkforge_bin, tmp_path):
    scene = tmp_path / "block.toml"
    scene.write_text(scene_variant("block_forging.toml", {
        "particles = [21, 21]": "particles = [7, 7]",
        "history_interval_s = 0.15e-3": "history_interval_s = 6.2e-3",
    }))
    out = tmp_path / "out"
    proc = subprocess.run([rkforge_bin, "run", str(scene), "--no-frames", "--quiet", "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["end_time_s"] == pytest.approx(0.015, rel=1e-12)
    with open(out / "history.csv") as f:
        times = [float(row["time_s"]) for row in csv.DictReader(f)]
    assert times == pytest.approx([0.0, 6.2e-3, 12.4e-3, 15e-3], rel=1e-12)


def test_table_is_printed_beside_the_references(coarse_run):
    _, stdout = coarse_run
    assert "Sidibe et al. 2009, Table 3, RKPM Q2" in stdout
    assert "radius (mm)" in stdout and "height (mm)" in stdout
    # Every row named in full: Table 5's two rows differ only after the 39th character.
    for source in ("Sidibe et al. 2009, Table 5 CPU (Pentium 4), Q4",
                   "Sidibe et al. 2009, Table 5 CPU (Pentium 4), Q2"):
        assert sum(line.startswith(source) for line in stdout.splitlines()) == 1, stdout


@pytest.mark.parametrize(
    "old,new,expected",
    [
        ("density_kg_per_m3 = 8930.0\n", "", ["missing field `density_kg_per_m3`", "line "]),
        ("poisson_ratio = 0.35", "poisson_ratio = 0.5", ["material.poisson_ratio", "(-1, 0.5)", ":28:"]),
        ("density_kg_per_m3 = 8930.0", "density_kg_per_m3 = -8930.0", ["material.density_kg_per_m3", ":26:"]),
        ("particles = [21, 51]", "particles = [0, 51]", ["workpiece.particles", ":22:"]),
        ("poisson_ratio = 0.35", "poisson_ratio = \"0.35\"", ["line 28", "poisson_ratio"]),
        ("end_s = 80.0e-6", "end_s = 80.0e-6\nend_time = 1.0", ["unknown field `end_time`", "line 37"]),
    ],
)
def test_bad_scene_is_refused_with_key_and_line(rkforge_bin, tmp_path, old, new, expected):
    scene = tmp_path / "bad.toml"
    scene.write_text(scene_variant("taylor_bar.toml", {old: new}))
    proc = subprocess.run([rkforge_bin, "run", str(scene), "--out", str(tmp_path / "o"), "--quiet"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1, proc.stdout
    assert "panicked" not in proc.stderr
    for e in expected:
        assert e in proc.stderr, (e, proc.stderr)


def test_missing_scene_file_is_a_clear_error(rkforge_bin, tmp_path):
    proc = subprocess.run([rkforge_bin, "run", str(tmp_path / "nope.toml")], capture_output=True, text=True)
    assert proc.returncode == 1 and "cannot read" in proc.stderr


def test_compare_prints_table_5_beside_ours(rkforge_bin, tmp_path):
    scene = tmp_path / "taylor_coarse.toml"
    scene.write_text(scene_variant("taylor_bar.toml", {**COARSE, "end_s = 80.0e-6": "end_s = 20.0e-6"}))
    out = tmp_path / "cmp"
    proc = subprocess.run([rkforge_bin, "compare", str(scene), "--out", str(out)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    table = (out / "compare.md").read_text()
    row = next(line for line in table.splitlines() if line.startswith("| taylor_bar"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    q4, q2, ratio = float(cells[1]), float(cells[2]), float(cells[3])
    # Wall times are printed to 1 ms: the ratio agrees within that rounding.
    assert q4 > 0 and q2 > 0 and abs(ratio - q2 / q4) < 0.0011 / q4 + 0.001
    assert cells[4] == "1238" and cells[5] == "644" and cells[6] == "0.520"
    # Costs per point-step and particle-step, each from its run's stage times.
    costs = [float(c) for c in cells[7:11]]
    assert all(c > 0 for c in costs), costs
    s = json.loads((out / "taylor_bar" / "q2" / "summary.json").read_text())
    per_point = s["stage_seconds"]["stress"] * 1e9 / (s["integration_points"] * s["steps"])
    assert costs[1] == pytest.approx(per_point, abs=0.051)
    for rule in ("q4", "q2"):
        s = json.loads((out / "taylor_bar" / rule / "summary.json").read_text())
        assert s["integration"] == rule and s["status"] == "ok"


def test_sweep_writes_csv_markdown_and_the_pareto_plot(rkforge_bin, tmp_path):
    scene = tmp_path / "taylor_short.toml"
    scene.write_text(scene_variant("taylor_bar.toml", {**COARSE, "end_s = 80.0e-6": "end_s = 10.0e-6"}))
    out = tmp_path / "sweep"
    proc = subprocess.run([rkforge_bin, "sweep", str(scene), "--resolution", "4x9,6x16,11x26",
                           "--integration", "q2,scni", "--dt-safety", "0.5,0.9", "--out", str(out)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    with open(out / "sweep.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 * 3 * 2
    assert {r["integration"] for r in rows} == {"q2", "scni"}
    for r in rows:
        assert float(r["wall_s"]) > 0 and float(r["memory_MB"]) > 0 and float(r["error_rel"]) >= 0
    assert any(r["pareto"] == "true" for r in rows)
    # Memory grows with the grid.
    q2 = [r for r in rows if r["integration"] == "q2" and r["dt_safety"] == "0.5"]
    assert float(q2[0]["memory_MB"]) < float(q2[-1]["memory_MB"])
    assert "Reference (extrapolated" in (out / "sweep.md").read_text()
    assert (out / "sweep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = subprocess.run([rkforge_bin, "sweep", str(scene), "--resolution", "11by26"], capture_output=True, text=True)
    assert bad.returncode == 1 and "--resolution `11by26`" in bad.stderr


def test_a_failed_compare_run_is_a_row_and_the_other_scenes_are_tabled(rkforge_bin, tmp_path):
    # The block at 10 km/s stops in its first steps; the coarse Taylor bar runs.
    fast = tmp_path / "block_fast.toml"
    fast.write_text(scene_variant("block_forging.toml", {"particles = [21, 21]": "particles = [7, 7]"})
                    .replace("velocity_m_per_s = 10.0 }", "velocity_m_per_s = 10000.0 }"))
    bar = tmp_path / "taylor_small.toml"
    bar.write_text(scene_variant("taylor_bar.toml", {**COARSE, "end_s = 80.0e-6": "end_s = 5.0e-6"}))
    out = tmp_path / "cmp"
    proc = subprocess.run([rkforge_bin, "compare", str(bar), str(fast), "--out", str(out)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 1 and "the runs of 1 of 2 scenes failed" in proc.stderr, proc.stderr
    table = (out / "compare.md").read_text()
    assert "| taylor_bar | " in table and "| block_forging | failed: see below |" in table
    assert "- failed: block_forging (q4): step" in table


def test_a_closed_standard_output_does_not_stop_a_run(rkforge_bin, tmp_path):
    # `rkforge run ... | head -1`: printing to the closed pipe panicked before.
    out = tmp_path / "o"
    proc = subprocess.Popen([rkforge_bin, "run", str(ROOT / "scenes" / "taylor_bar.toml"), "--set", "time.end_s=2e-6",
                             "--no-frames", "--quiet", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    proc.stdout.close()
    stderr = proc.stderr.read()
    assert proc.wait(timeout=600) == 0 and "panicked" not in stderr, stderr
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"


def test_a_step_safety_a_fixed_step_leaves_unused_is_named_in_a_warning(rkforge_bin, tmp_path):
    """The Taylor bar fixes its step (`time.dt_s`); a `dt_safety` beside it does nothing, and
    the run says so (on stderr and in the summary) instead of taking it silently."""
    proc = subprocess.run([rkforge_bin, "run", str(ROOT / "scenes" / "taylor_bar.toml"), "--no-frames",
                           "--set", "time.dt_safety=0.9", "--set", "time.end_s=1e-6",
                           "--out", str(tmp_path / "o")], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    line = "time.dt_safety = 0.9 is not used: the fixed step time.dt_s = 5e-9 s sets every step"
    assert f"warning: {line}" in proc.stderr, proc.stderr
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert any(w.startswith(line) for w in summary["warnings"]), summary["warnings"]


def test_a_step_safety_that_would_never_end_is_refused_by_name(rkforge_bin, tmp_path):
    proc = subprocess.run([rkforge_bin, "run", str(ROOT / "scenes" / "taylor_ofhc.toml"), "--set", "time.dt_safety=1e-20",
                           "--out", str(tmp_path / "o")], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 1 and "time.dt_safety = 1e-20 of the critical step" in proc.stderr, proc.stderr
    assert "more than 1e9: raise time.dt_safety" in proc.stderr



def test_a_grid_beyond_the_machines_memory_is_refused_by_key(rkforge_bin, tmp_path):
    """Under a 3 GB address-space limit a 2000 x 2000 block is refused before its tables are
    allocated (before, the allocation failed and the process aborted with SIGABRT); the 3D
    bar's cells likewise."""
    import resource

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (3_000_000_000, resource.RLIM_INFINITY))

    for scene, key, value in [("block_forging", "workpiece.particles", "[2000, 2000]"),
                              ("taylor_bar_3d", "workpiece.cells", "[40, 20, 200]")]:
        proc = subprocess.run([rkforge_bin, "run", str(ROOT / "scenes" / f"{scene}.toml"), "--set",
                               f"{key}={value}", "--no-frames", "--quiet", "--out", str(tmp_path / scene)],
                              capture_output=True, text=True, timeout=600, preexec_fn=limit)
        assert proc.returncode == 1, (proc.returncode, proc.stderr[-2000:])
        assert f"`{key}`" in proc.stderr and "need at least" in proc.stderr, proc.stderr
        assert "GB of address space" in proc.stderr and "fewer particles" in proc.stderr

def test_a_failed_sweep_run_is_a_row_with_its_error_and_the_others_are_tabled(rkforge_bin, tmp_path):
    # At 10 km/s the block's tools pass a spacing per step and the runs stop; at 10 m/s they run.
    scene = ROOT / "scenes" / "block_forging.toml"
    out = tmp_path / "sweep"
    proc = subprocess.run([rkforge_bin, "sweep", str(scene), "--resolution", "5x5,7x7", "--integration", "q2",
                           "--set", "tools.top.motion.velocity_m_per_s=10000,10", "--set", "time.end_s=2e-3",
                           "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 1 and "2 of 4 runs failed" in proc.stderr, proc.stderr
    with open(out / "sweep.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4
    failed = [r for r in rows if r["failure"]]
    assert [r["tools.top.motion.velocity_m_per_s"] for r in failed] == ["10000", "10000"]
    assert all(r["width_m"] == "NaN" and r["pareto"] == "false" for r in failed)
    assert all(float(r["error_rel"]) >= 0 and r["width_m"] != "NaN" for r in rows if not r["failure"])
    md = (out / "sweep.md").read_text()
    assert "| failed |" in md and "q2 5x5 dt_safety 0.5 failed: step" in md
    assert "order 1.00 (assumed)" in md  # two grids: the order is not measured
    # One grid gives no reference: no run is given an error.
    one = subprocess.run([rkforge_bin, "sweep", str(scene), "--resolution", "5x5", "--integration", "q2",
                          "--set", "time.end_s=2e-3", "--out", str(tmp_path / "one")],
                         capture_output=True, text=True, timeout=600)
    assert one.returncode == 0, one.stderr
    assert "Reference (extrapolated, +- uncertainty): none" in one.stdout
    with open(tmp_path / "one" / "sweep.csv") as f:
        assert [r["error_rel"] for r in csv.DictReader(f)] == ["NaN"]


def test_sweep_holds_the_added_mass_of_a_selectively_scaled_scene(rkforge_bin, tmp_path):
    # The press upsetting scales its masses to a 20 us step: at one target a grid twice as
    # fine would add four times the mass (another, heavier problem); the sweep holds it.
    scene = tmp_path / "press.toml"
    scene.write_text(scene_variant("press_upsetting.toml", {
        "end_s = 1.5                      # 30 mm at 20 mm/s": "end_s = 0.05",
        "history_interval_s = 0.01": "history_interval_s = 0.005",
    }))
    out = tmp_path / "sweep"
    proc = subprocess.run([rkforge_bin, "sweep", str(scene), "--resolution", "11x31,21x61",
                           "--integration", "q2", "--dt-safety", "0.5,0.9", "--out", str(out)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    with open(out / "sweep.csv") as f:
        rows = {(r["nx"], r["dt_safety"]): r for r in csv.DictReader(f)}
    own = float(rows[("11", "0.5")]["added_mass_rel"])
    assert own > 1000, own
    for key, r in rows.items():
        assert 0.8 * own < float(r["added_mass_rel"]) <= own * (1 + 1e-9), (key, r["added_mass_rel"], own)
    # The same mass: the finer grid steps twice as often, the larger safety less often.
    steps = {k: int(r["steps"]) for k, r in rows.items()}
    assert 1.8 < steps[("21", "0.5")] / steps[("11", "0.5")] < 2.2, steps
    assert steps[("11", "0.9")] < steps[("11", "0.5")], steps
    assert "Mass scaling held" in (out / "sweep.md").read_text()


BLOCK_SHORT = {
    "particles = [21, 21]": "particles = [9, 9]",
    "end_s = 0.015": "end_s = 0.002",
}


def test_run_overrides_keys_by_their_dotted_path(rkforge_bin, tmp_path):
    scene = tmp_path / "block.toml"
    scene.write_text(scene_variant("block_forging.toml", BLOCK_SHORT))
    runs = {}
    for name, sets in [("base", []), ("slow", ["tools.top.motion.velocity_m_per_s=5.0",
                                               "--set", "tools.top.friction=0"])]:
        args = [rkforge_bin, "run", str(scene), "--out", str(tmp_path / name), "--quiet", "--no-frames"]
        if sets:
            args += ["--set", *sets]
        proc = subprocess.run(args, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr
        runs[name] = json.loads((tmp_path / name / "summary.json").read_text())
    top = {n: next(t for t in s["tools"] if t["name"] == "top") for n, s in runs.items()}
    # Half the speed over the same time: half the stroke.
    assert top["slow"]["stroke_m"] == pytest.approx(top["base"]["stroke_m"] / 2, rel=1e-9)


@pytest.mark.parametrize(
    "arg, expected",
    [
        ("tools.middle.friction=0.1", ["override `tools.middle.friction`", "no entry of `tools` is named `middle`"]),
        ("tools.top.frction=0.1", ["override `tools.top.frction`", "unknown field `frction`"]),
        ("tools.top.friction=high", ["override `tools.top.friction`", "invalid type"]),
        ("tools.top.friction=-1", ["override `tools.top.friction`", "must be zero or positive"]),
        ("time.end_s", ["--set `time.end_s`: expected KEY=VALUE"]),
    ],
)
def test_bad_overrides_name_the_dotted_key(rkforge_bin, tmp_path, arg, expected):
    proc = subprocess.run([rkforge_bin, "run", "scenes/block_forging.toml", "--set", arg,
                           "--out", str(tmp_path / "o"), "--quiet"],
                          capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert proc.returncode == 1 and "panicked" not in proc.stderr
    for e in expected:
        assert e in proc.stderr, (e, proc.stderr)


def test_sweep_varies_scene_keys_over_a_grid(rkforge_bin, tmp_path):
    scene = tmp_path / "block.toml"
    scene.write_text(scene_variant("block_forging.toml", BLOCK_SHORT))
    out = tmp_path / "sweep"
    proc = subprocess.run([rkforge_bin, "sweep", str(scene), "--integration", "q2",
                           "--set", "tools.top.friction=0.1,0.3",
                           "--set", "tools.top.motion.velocity_m_per_s=10.0,5.0",
                           "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    with open(out / "sweep.csv") as f:
        rows = list(csv.DictReader(f))
    assert [(r["tools.top.friction"], r["tools.top.motion.velocity_m_per_s"]) for r in rows] == [
        ("0.1", "10.0"), ("0.1", "5.0"), ("0.3", "10.0"), ("0.3", "5.0")]
    assert all((r["nx"], r["ny"]) == ("9", "9") for r in rows)
    # Each case's own run summary carries its overrides' effect.
    for r in rows:
        case = out / f"tools.top.friction={r['tools.top.friction']},tools.top.motion.velocity_m_per_s={r['tools.top.motion.velocity_m_per_s']}"
        s = json.loads((case / "q2_9x9_0.5" / "summary.json").read_text())
        top = next(t for t in s["tools"] if t["name"] == "top")
        assert top["velocity_m_per_s"] == float(r["tools.top.motion.velocity_m_per_s"])


RING_SHORT = {
    "particles = [31, 21]": "particles = [11, 7]",
    "end_s = 1.025e-3                 # 0.125 mm of ramp + 4.875 mm at 5 m/s = 5 mm stroke":
        "end_s = 0.225e-3",  # 1 mm stroke: 10 % height reduction
}


def test_ring_chart_sets_the_upper_bound_beside_the_runs(rkforge_bin, tmp_path):
    scene = tmp_path / "ring.toml"
    scene.write_text(scene_variant("ring_compression.toml", RING_SHORT))
    out = tmp_path / "chart"
    proc = subprocess.run([rkforge_bin, "ring-chart", str(scene), "--m", "0,1", "--mu", "0.1",
                           "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "| m | | 10 % | 20 % | 30 % | 40 % | 50 % |" in lines
    cells = {}
    for line in lines:
        if line.startswith("| ") and "%" not in line:
            row = [c.strip() for c in line.strip("|").split("|")]
            m = row[0] or m
            cells[(m, row[1])] = row[2:]
    # Homogeneous upsetting at m = 0: 1 - 1 / sqrt(0.9) = -5.4 % at 10 %; nothing past the stroke.
    assert cells[("0", "upper bound")] == ["-5.4", "-11.8", "-19.5", "-29.1", "-41.4"]
    assert cells[("0", "simulated")][1:] == ["-"] * 4 and cells[("0", "difference")][1:] == ["-"] * 4
    for m in ("0", "1"):
        sim, ub, diff = (float(cells[(m, k)][0]) for k in ("simulated", "upper bound", "difference"))
        assert abs(sim - ub - diff) <= 0.11
    # Sticking friction closes the hole in both, from the start.
    assert float(cells[("1", "simulated")][0]) > 0 and float(cells[("1", "upper bound")][0]) > 0
    with open(out / "ring_chart.csv") as f:
        rows = list(csv.DictReader(f))
    runs = {(r["source"], r["law"], r["mu"], r["m"]) for r in rows}
    assert runs == {("simulation", "shear", "NaN", "0"), ("simulation", "shear", "NaN", "1"),
                    ("simulation", "coulomb", "0.1", "NaN"),
                    ("upper_bound", "shear", "NaN", "0"), ("upper_bound", "shear", "NaN", "1")}
    bound = [r for r in rows if r["source"] == "upper_bound" and r["m"] == "0"]
    assert float(bound[0]["height_reduction_pct"]) == 0.0 and 9.9 < float(bound[-1]["height_reduction_pct"]) <= 10.0
    with open(out / "ring_chart_comparison.csv") as f:
        table = list(csv.DictReader(f))
    assert [(r["m"], r["height_reduction_pct"]) for r in table][:2] == [("0", "10"), ("0", "20")]
    assert len(table) == 10 and table[1]["simulated_pct"] == ""
    assert (out / "ring_chart.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
