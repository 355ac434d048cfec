"""The FMI 3.0 Co-Simulation FMU (`rkforge fmu SCENE --fmi 3`) through fmpy: validation of
every shipped scene, the same bits as the FMI 2.0 FMU of the scene for the same inputs and
steps, rollback and serialization, and bad calls refused with a message."""
import json
import subprocess
import sys

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

import rkforge
from conftest import ROOT

SCENES = ["taylor_bar", "block_forging", "wheel_forging", "closed_die_hub", "ring_compression",
          "press_upsetting", "block_forging_press", "wheel_forging_press", "hot_upsetting"]
COARSE = {"workpiece.particles[0]": 9, "workpiece.particles[1]": 9}


def pack(rkforge_bin, scene, out, fmi):
    subprocess.run([rkforge_bin, "fmu", str(scene), "--out", str(out), "--fmi", fmi],
                   check=True, capture_output=True, text=True)
    return str(out)


@pytest.fixture(scope="module")
def fmus(rkforge_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("fmu3")
    return {s: pack(rkforge_bin, ROOT / "scenes" / f"{s}.toml", out / f"{s}.fmu", "3") for s in SCENES}


def test_every_shipped_scene_validates_as_fmi3(fmus):
    for s, p in fmus.items():
        assert validate_fmu(p) == [], s
        md = read_model_description(p)
        assert md.fmiVersion == "3.0" and md.coSimulation is not None, s
        assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
        time = [v for v in md.modelVariables if v.causality == "independent"]
        assert [v.name for v in time] == ["time"], s
        types = {v.name: v.type for v in md.modelVariables}
        assert types["discretization.integration"] == "String"
        assert types["workpiece.particles[0]"] == "Int32"
        assert types["time.end_s"] == "Float64"


def test_every_shipped_scene_packs_and_validates_in_fmi2_and_fmi3(rkforge_bin, tmp_path):
    """Every scene in scenes/, 2D and 3D, packed both ways: fmpy validates each FMU, and the
    2.0 and 3.0 FMUs list the same outputs, named by the register with their units."""
    scenes = sorted((ROOT / "scenes").glob("*.toml"))
    assert len(scenes) >= 13
    # The 3D scenes pack as the 2D ones do (tests/test_fmu_3d.py runs one).
    assert sum('kinematics = "3d"' in s.read_text() for s in scenes) >= 2
    for scene in scenes:
        outputs = []
        for fmi in ("2", "3"):
            path = pack(rkforge_bin, scene, tmp_path / f"{scene.stem}-{fmi}.fmu", fmi)
            assert validate_fmu(path) == [], f"{scene.name} FMI {fmi}"
            md = read_model_description(path)
            outputs.append([(v.name, v.unit) for v in md.modelVariables if v.causality == "output"])
        assert outputs[0] == outputs[1], scene.name
        units = dict(outputs[0])
        assert all(units[n] == "N" for n in units if n.endswith("_N")), scene.name
        assert all(units[n] == "J" for n in units if n.endswith("_J")), scene.name


def test_fmi2_and_fmi3_give_the_same_bits(rkforge_bin, tmp_path):
    """The block forging, coarse and with its fixed step, driven by the same velocity table
    at the same communication points through both FMUs: every output the same bits."""
    scene = ROOT / "scenes" / "block_forging.toml"
    two = pack(rkforge_bin, scene, tmp_path / "b2.fmu", "2")
    three = pack(rkforge_bin, scene, tmp_path / "b3.fmu", "3")
    outputs = [v.name for v in read_model_description(two).modelVariables if v.causality == "output"]
    assert outputs == [v.name for v in read_model_description(three).modelVariables
                       if v.causality == "output"]
    inp = np.array([(0.0, 10.0, 10.0), (2e-3, 6.0, 12.0), (4e-3, 6.0, 12.0)],
                   dtype=[("time", float), ("top.velocity_m_per_s", float), ("bottom.velocity_m_per_s", float)])
    runs = [simulate_fmu(p, stop_time=4e-3, output_interval=1e-4, input=inp,
                         start_values={**COARSE, "discretization.integration": "q4"},
                         output=outputs) for p in (two, three)]
    assert len(runs[0]) == len(runs[1]) == 41
    for name in outputs:
        assert runs[0][name].tobytes() == runs[1][name].tobytes(), name
    assert runs[1]["top.force_N"][-1] < 0.0
    assert runs[1]["top.pressure_mean_Pa"][-1] > 0.0


class Slave3:
    """One FMI 3.0 instance, initialised, with its log messages kept."""

    def __init__(self, path, params=None, early_return=False, intermediate_update=None,
                 stop_time=None, logging_on=True):
        self.md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages = []

        def log(env, status, category, message):
            self.messages.append(message.decode())

        self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=extract(path),
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName="rkforge3")
        self.fmu.instantiate(loggingOn=logging_on, logMessage=log, earlyReturnAllowed=early_return,
                             intermediateUpdate=intermediate_update)
        for k, v in (params or {}).items():
            if isinstance(v, bool):
                self.fmu.setBoolean([self.vr[k]], [v])
            elif isinstance(v, int):
                self.fmu.setInt32([self.vr[k]], [v])
            else:
                self.fmu.setFloat64([self.vr[k]], [v])
        self.fmu.enterInitializationMode(startTime=0.0, stopTime=stop_time)
        self.fmu.exitInitializationMode()
        self.t = 0.0

    def step(self, h):
        """One communication step; returns (earlyReturn, lastSuccessfulTime)."""
        _, _, early, last = self.fmu.doStep(currentCommunicationPoint=self.t, communicationStepSize=h)
        self.t = last if early else self.t + h
        return early, last

    def get(self, *names):
        return self.fmu.getFloat64([self.vr[n] for n in names])


def test_rollback_and_serialization_continue_with_the_same_bits(fmus):
    s = Slave3(fmus["block_forging"], COARSE)
    names = ["top.force_N", "top.stroke_m", "workpiece.width_m", "energy.plastic_J", "time"]
    for _ in range(5):
        s.step(1e-4)
    state = s.fmu.getFMUState()
    saved = s.fmu.serializeFMUState(state)
    s.fmu.setFloat64([s.vr["top.velocity_m_per_s"]], [4.0])
    s.step(5e-4)
    first = s.get(*names)
    s.fmu.setFMUState(state)
    s.t = 5e-4
    assert s.get("time") == [pytest.approx(5e-4)]
    s.fmu.setFloat64([s.vr["top.velocity_m_per_s"]], [4.0])
    s.step(5e-4)
    assert s.get(*names) == first
    # A serialized state restored into a fresh instance continues the same way.
    t = Slave3(fmus["block_forging"], COARSE)
    restored = t.fmu.deserializeFMUState(saved)
    t.fmu.setFMUState(restored)
    t.t = 5e-4
    t.fmu.setFloat64([t.vr["top.velocity_m_per_s"]], [4.0])
    t.step(5e-4)
    assert t.get(*names) == first
    for x in (s, t):
        x.fmu.terminate()
        x.fmu.freeInstance()


def test_bad_calls_are_refused_with_a_message(fmus):
    s = Slave3(fmus["taylor_bar"])
    with pytest.raises(FMICallException):
        s.fmu.setFloat64([s.vr["time"]], [1.0])
    assert "`time` is the independent variable" in s.messages[-1]
    with pytest.raises(FMICallException):
        s.fmu.setFloat64([s.vr["time.end_s"]], [1.0])
    assert "`time.end_s`" in s.messages[-1] and "cannot be set" in s.messages[-1]
    with pytest.raises(FMICallException):
        s.fmu.getBoolean([s.vr["wall.force_N"]])
    assert "not a Boolean variable" in s.messages[-1]
    with pytest.raises(FMICallException):
        s.fmu.doStep(currentCommunicationPoint=1.0, communicationStepSize=1e-6)
    assert "does not match" in s.messages[-1]
    s.step(1e-6)
    assert s.get("time") == [pytest.approx(1e-6)]
    s.fmu.terminate()
    s.fmu.freeInstance()


def approach(rkforge_bin, tmp_path, gap):
    """The press upsetting billet with the ram `gap` (m) above it, coarse: its FMI 3.0 FMU,
    the FMU's parameters, and the same scene for the Python package."""
    from driver import upsetting_scene
    text = upsetting_scene(gap)
    (tmp_path / "approach.toml").write_text(text)
    fmu = pack(rkforge_bin, tmp_path / "approach.toml", tmp_path / "approach.fmu", "3")
    params = {"workpiece.particles[0]": 6, "workpiece.particles[1]": 16}
    scene = rkforge.Scene.from_toml(text, "approach")
    scene.set("workpiece.particles", [6, 16])
    return fmu, params, scene


def first_step_where(scene, toward, condition):
    """The time after the first solver step at which `condition(sample)` holds, stepping
    the scene through the Python package one solver step at a time toward `toward` (s), the
    steps a run to that time (a communication step of that length) takes."""
    sim = rkforge.Simulation(scene)
    while sim.time < toward:
        sim.step(toward=toward)
        if condition(sim.sample()):
            return sim.time
    return None


def test_early_return_stops_at_the_first_contact_step(rkforge_bin, tmp_path):
    """The ram 2 mm above the billet at 20 mm/s: one 0.5 s communication step returns early
    at the solver step where the ram first touches, the time of that step in a run without
    early return (the Python package stepping the same scene) to the bit; stepping on from
    there does not return again for the same contact."""
    fmu, params, scene = approach(rkforge_bin, tmp_path, 0.002)
    s = Slave3(fmu, {**params, "ram.early_return.contact": True}, early_return=True)
    early, last = s.step(0.5)
    assert early
    expected = first_step_where(scene, 0.5, lambda row: row["ram.contact_fraction"] > 0.0)
    assert last == expected and 0.09 < last < 0.11, (last, expected)
    assert s.get("time") == [last]
    assert s.get("ram.contact_fraction")[0] > 0.0
    assert s.get("ram.stroke_m")[0] == pytest.approx(0.020 * last, rel=1e-9)
    early, last = s.step(0.05)
    assert not early and last == pytest.approx(expected + 0.05)
    s.fmu.terminate()
    s.fmu.freeInstance()
    # Without the importer's leave, the same step runs to its end.
    plain = Slave3(fmu, {**params, "ram.early_return.contact": True}, early_return=False)
    assert plain.step(0.5) == (False, 0.5)
    plain.fmu.freeInstance()


def test_early_return_when_the_force_reaches_a_level(rkforge_bin, tmp_path):
    """The ram on the billet: the step returns at the solver step where the force magnitude
    first reaches 200 kN, as stepping the scene one solver step at a time finds it."""
    fmu, params, scene = approach(rkforge_bin, tmp_path, 0.0)
    s = Slave3(fmu, {**params, "ram.early_return.force": True,
                     "ram.early_return.force_level": 2.0e5}, early_return=True)
    early, last = s.step(1.0)
    assert early
    expected = first_step_where(scene, 1.0, lambda row: abs(row["ram.force_N"]) >= 2.0e5)
    assert last == expected, (last, expected)
    assert abs(s.get("ram.force_N")[0]) >= 2.0e5
    s.fmu.freeInstance()


def test_intermediate_updates_follow_every_solver_step(rkforge_bin, tmp_path):
    """One 1 ms communication step of the coarse block: the intermediate-update callback
    sees every solver step, its time and force the bits of the Python package stepping the
    same scene toward the same point; a setter called in it is refused (the instance is being
    stepped); asking for an early return in the fifth update ends the step there."""
    scene = ROOT / "scenes" / "block_forging.toml"
    fmu = pack(rkforge_bin, scene, tmp_path / "b3.fmu", "3")
    seen, refused, stop_at = [], [], [None]
    holder = {}

    def update(env, time, set_requested, get_allowed, finished, can_return, early, when):
        s = holder["s"]
        assert get_allowed and finished and not set_requested
        seen.append((time, *s.fmu.getFloat64([s.vr["time"], s.vr["top.force_N"]])))
        try:
            s.fmu.setFloat64([s.vr["top.velocity_m_per_s"]], [1.0])
        except FMICallException:
            refused.append(time)
        if stop_at[0] is not None and len(seen) == stop_at[0] and can_return:
            early[0] = True
            when[0] = time

    holder["s"] = s = Slave3(fmu, COARSE, intermediate_update=update)
    assert s.step(1e-3) == (False, 1e-3)
    py = rkforge.Scene.from_file(str(scene))
    py.set("workpiece.particles", [9, 9])
    sim = rkforge.Simulation(py)
    expected = []
    while sim.time < 1e-3:
        sim.step(toward=1e-3)
        expected.append((sim.time, sim.time, sim.tool_forces()["top"]))
    assert len(seen) == len(expected) > 10
    assert seen == expected
    assert seen[-1][2] == s.get("top.force_N")[0]
    assert refused == [t for t, _, _ in seen]
    # Each refusal is logged, naming the call and why.
    why = [m for m in s.messages if "inside this instance's intermediate update" in m]
    assert len(why) == len(refused) and why[0].startswith("fmi3SetFloat64: not allowed"), why[:1]
    s.fmu.freeInstance()

    seen.clear()
    stop_at[0] = 5
    holder["s"] = s = Slave3(fmu, COARSE, early_return=True, intermediate_update=update)
    early, last = s.step(1e-3)
    assert early and last == expected[4][0] and len(seen) == 5
    s.fmu.freeInstance()


def test_a_step_past_the_stop_time_is_an_error_logged_with_debug_logging_off(fmus):
    s = Slave3(fmus["block_forging"], COARSE, stop_time=2e-4, logging_on=False)
    s.step(1e-4)
    with pytest.raises(FMICallException):
        s.fmu.doStep(currentCommunicationPoint=1e-4, communicationStepSize=2e-4)
    assert s.messages == ["fmi3DoStep: a step from 1e-4 s by 2e-4 s would pass the stop time 2e-4 s the host set up"]
    assert s.step(1e-4) == (False, pytest.approx(2e-4, rel=1e-12))
    s.fmu.freeInstance()


def test_contact_pressure_is_an_array_output(rkforge_bin, tmp_path):
    """The block with `output.pressure_stations = 40`: `top.contact_pressure_Pa` is a Float64
    array of 40 values (2 m of tool in 5 cm stations); its pressures times the stations'
    areas add up to the force on the tool, the stations beyond the block carry none."""
    text = (ROOT / "scenes" / "block_forging.toml").read_text().replace(
        "[output]", "[output]\npressure_stations = 40")
    scene = tmp_path / "block.toml"
    scene.write_text(text)
    fmu = pack(rkforge_bin, scene, tmp_path / "block3.fmu", "3")
    assert validate_fmu(fmu) == []
    md = read_model_description(fmu)
    pressure = next(v for v in md.modelVariables if v.name == "top.contact_pressure_Pa")
    assert pressure.type == "Float64" and pressure.causality == "output"
    assert [int(d.start) for d in pressure.dimensions] == [40]
    s = Slave3(fmu, COARSE)
    s.step(2e-3)
    p = np.array(s.fmu.getFloat64([s.vr["top.contact_pressure_Pa"]], nValues=40))
    force = s.get("top.force_N")[0]
    assert p.max() > 1e8
    assert np.sum(p) * 0.05 == pytest.approx(abs(force), rel=1e-9)
    # The block is 0.5 m wide (a little wider now) in the middle of the 2 m tool.
    assert np.all(p[:12] == 0.0) and np.all(p[-12:] == 0.0)
    both = s.fmu.getFloat64([s.vr["top.force_N"], s.vr["top.contact_pressure_Pa"]], nValues=41)
    assert both[0] == force and list(both[1:]) == list(p)
    with pytest.raises(FMICallException):
        s.fmu.getFloat64([s.vr["top.contact_pressure_Pa"]], nValues=1)
    assert "holding 40 values" in s.messages[-1]
    s.fmu.freeInstance()


def test_an_fmi3_container_of_the_fmu_gives_the_same_bits(rkforge_bin, tmp_path):
    """The FMU Manipulation Toolbox wraps the 3.0 FMU of the coarse block in an FMI 3.0
    container (`fmucontainer -fmi 3`); fmpy validates the container and, driven by the
    same velocity table at the same steps, it gives the FMU's own force and stroke bit for
    bit."""
    text = (ROOT / "scenes" / "block_forging.toml").read_text().replace(
        "particles = [21, 21]", "particles = [9, 9]")
    (tmp_path / "block.toml").write_text(text)
    pack(rkforge_bin, tmp_path / "block.toml", tmp_path / "block3.fmu", "3")
    (tmp_path / "c.json").write_text(json.dumps({
        "name": "container3.fmu", "step_size": 1e-4, "auto_input": False,
        "auto_output": False, "auto_link": False, "fmu": ["block3.fmu"],
        "input": [["top_velocity", "block3.fmu", "top.velocity_m_per_s"]],
        "output": [["block3.fmu", "top.force_N", "top_force"],
                   ["block3.fmu", "top.stroke_m", "top_stroke"]]}))
    made = subprocess.run([sys.executable, "-m", "fmu_manipulation_toolbox.cli.fmucontainer",
                           "-container", "c.json", "-fmu-directory", str(tmp_path), "-fmi", "3"],
                          cwd=tmp_path, capture_output=True, text=True)
    container = tmp_path / "container3.fmu"
    assert made.returncode == 0 and container.is_file(), made.stdout + made.stderr
    assert validate_fmu(str(container)) == []
    assert read_model_description(str(container)).fmiVersion == "3.0"

    def table(name):
        return np.array([(0.0, 10.0), (2e-3, 5.0)], dtype=[("time", float), (name, float)])

    a = simulate_fmu(str(container), stop_time=3e-3, step_size=1e-4, output_interval=1e-4,
                     input=table("top_velocity"), output=["top_force", "top_stroke"])
    b = simulate_fmu(str(tmp_path / "block3.fmu"), stop_time=3e-3, step_size=1e-4,
                     output_interval=1e-4, input=table("top.velocity_m_per_s"),
                     output=["top.force_N", "top.stroke_m"])
    assert len(a) == len(b) == 31 and b["top.force_N"][-1] < 0.0
    assert a["top_force"].tobytes() == b["top.force_N"].tobytes()
    assert a["top_stroke"].tobytes() == b["top.stroke_m"].tobytes()
