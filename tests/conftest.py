"""Shared fixtures: the rkforge binary and scene files derived from the shipped scenes."""
import faulthandler
import json
import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
# The FMU driver and the press plants of examples/presses are imported by the FMU tests.
sys.path.insert(0, str(ROOT / "examples" / "presses"))

# The longest a test may take (s); each takes at most about a minute with both cores loaded.
WATCHDOG_S = 900


@pytest.fixture(autouse=True)
def watchdog(request):
    """A test that hangs (a DDS peer library stuck in native code holding the GIL, as
    cyclonedds once did inside `Topic(...)`; a process that never answers) prints every
    thread's stack and ends the session after `WATCHDOG_S`, instead of holding CI until its
    limit. faulthandler's watchdog is a native thread: it needs no GIL to fire. It writes to
    the copy of the terminal's stderr that pytest's faulthandler plugin keeps: the test's
    own stderr is captured, and a dump there would be lost with the process."""
    from _pytest.faulthandler import fault_handler_stderr_fd_key
    terminal = request.config.stash[fault_handler_stderr_fd_key]
    faulthandler.dump_traceback_later(WATCHDOG_S, exit=True, file=terminal)
    yield
    faulthandler.cancel_dump_traceback_later()


@pytest.fixture(scope="session")
def rkforge_bin():
    """Path to the release `rkforge` binary (built by tests/run.sh, or here if missing)."""
    path = os.environ.get("RKFORGE_BIN")
    if path and pathlib.Path(path).is_file():
        return path
    subprocess.run(["cargo", "build", "--release", "-p", "rkforge"], cwd=ROOT, check=True)
    return str(ROOT / "target" / "release" / "rkforge")


def scene_variant(src: str, replacements: dict) -> str:
    """The text of a shipped scene with exact line replacements (each must match once)."""
    text = (ROOT / "scenes" / src).read_text()
    for old, new in replacements.items():
        assert text.count(old) == 1, f"{old!r} not found exactly once in {src}"
        text = text.replace(old, new)
    return text


@pytest.fixture(scope="session")
def rkforge_ros_bin():
    """Path to the release `rkforge-ros` binary (built by tests/run.sh, or here if missing)."""
    path = os.environ.get("RKFORGE_ROS_BIN")
    if path and pathlib.Path(path).is_file():
        return path
    subprocess.run(["cargo", "build", "--release", "-p", "rkforge-ros", "--bins", "--examples"],
                   cwd=ROOT, check=True)
    return str(ROOT / "target" / "release" / "rkforge-ros")


@pytest.fixture(scope="session")
def force_controller_bin(rkforge_ros_bin):
    """Path to the release build of the example `force_controller`."""
    path = pathlib.Path(rkforge_ros_bin).parent / "examples" / "force_controller"
    if not path.is_file():
        subprocess.run(["cargo", "build", "--release", "-p", "rkforge-ros", "--examples"],
                       cwd=ROOT, check=True)
    return str(path)


def stl_box(path, lo, hi):
    """The closed box lo..hi (mm) as an ASCII STL, its 12 triangles wound outward."""
    corner = lambda i: [hi[k] if i >> k & 1 else lo[k] for k in range(3)]
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    lines = ["solid die"]
    for q in quads:
        for tri in ([q[0], q[1], q[2]], [q[0], q[2], q[3]]):
            lines += ["  facet normal 0 0 0", "    outer loop"]
            lines += ["      vertex %r %r %r" % tuple(corner(i)) for i in tri]
            lines += ["    endloop", "  endfacet"]
    path.write_text("\n".join(lines + ["endsolid die", ""]))


def assert_stages_account_for_the_wall_time(out, stdout):
    """A finished run's `stage_seconds` (2D or 3D): each stage timed, the stages disjoint parts
    of the run that never add up to more than its wall time and account for most of it (the
    rest is loop control and the progress bar), output timed (the run wrote frames and
    plots), and the stage line printed. How the time splits between stages is a measurement,
    not asserted: on a busy machine a preempted plot can outlast the stress stage of a small
    run."""
    s = json.loads((out / "summary.json").read_text())
    t = s["stage_seconds"]
    stages = ["stress", "internal_force", "contact", "integration", "output"]
    for key in ["setup", "shape_functions", *stages]:
        assert t[key] >= 0.0, key
    assert t["shape_functions"] <= t["setup"]
    total = t["setup"] + sum(t[k] for k in stages)
    assert 0.5 * s["wall_s"] < total <= s["wall_s"], s
    assert t["output"] > 0.0
    assert "stages: setup" in stdout and "strain and stress" in stdout and "output" in stdout

