"""Checkpoints of `rkforge run` and `rkforge sweep` (`--checkpoint-every-s`, `--resume`) and
of Python runs and studies: a run killed with SIGKILL goes on from its last checkpoint and
ends with the files of a run that never stopped, to the bit (history.csv, every VTK frame),
in 2D and in 3D; a killed sweep keeps the runs it finished and goes on from the one it was
in; a study's killed case goes on from its checkpoint; bad uses are refused with the option
and the reason."""
import json
import signal
import subprocess
import time

import pytest

from conftest import ROOT, scene_variant

BLOCK = {"particles = [21, 21]": "particles = [41, 41]"}
BAR_3D = {"cells = [8, 4, 60]": "cells = [4, 2, 30]"}


def killed_after_checkpoint(args, checkpoint, settle_s):
    """Run `args` in a process of its own and kill it (SIGKILL) `settle_s` after
    `checkpoint` appears (0: at once, before it may write another)."""
    run = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 600
    while not checkpoint.exists():
        assert run.poll() is None, f"the run ended before its first checkpoint: {run.stderr.read()}"
        assert time.monotonic() < deadline, "no checkpoint in 600 s"
        time.sleep(0.01)
    time.sleep(settle_s)
    assert run.poll() is None, "the run ended before it was killed: lengthen the scene"
    run.send_signal(signal.SIGKILL)
    run.wait(timeout=60)


def straight_and_resumed(rkforge_bin, tmp_path, scene, settle_s):
    """A run to the end, and the same run killed `settle_s` after its first checkpoint and
    resumed: their output folders."""
    args = [rkforge_bin, "run", str(scene), "--threads", "1", "--quiet"]
    whole = tmp_path / "whole"
    proc = subprocess.run(args + ["--out", str(whole)], capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    cut = tmp_path / "cut"
    checkpoint = cut / "checkpoint.cbor"
    killed_after_checkpoint(args + ["--out", str(cut), "--checkpoint-every-s", "0"], checkpoint,
                            settle_s)
    assert checkpoint.exists()
    assert not (cut / "summary.json").exists()
    proc = subprocess.run(args + ["--out", str(cut), "--resume", "--checkpoint-every-s", "0"],
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    assert "resumed from its checkpoint at t = " in proc.stdout, proc.stdout
    return whole, cut


def assert_same_files(whole, cut):
    assert (cut / "history.csv").read_bytes() == (whole / "history.csv").read_bytes()
    frames = sorted(p.name for p in (whole / "frames").iterdir())
    assert frames and frames == sorted(p.name for p in (cut / "frames").iterdir())
    for name in frames:
        assert (cut / "frames" / name).read_bytes() == (whole / "frames" / name).read_bytes(), name
    assert (cut / "frames.pvd").read_bytes() == (whole / "frames.pvd").read_bytes()
    a = json.loads((whole / "summary.json").read_text())
    b = json.loads((cut / "summary.json").read_text())
    assert b["status"] == "ok" and b["steps"] == a["steps"]
    (resumed_at,) = b["resumed_at_s"]
    assert 0.0 < resumed_at < b["end_time_s"]
    assert "resumed_at_s" not in a
    # A run that reached its end removes its checkpoint.
    assert not (cut / "checkpoint.cbor").exists()
    # The resumed run's stage times cover both processes as its wall time does: disjoint,
    # never more than the wall time, most of it (the killed process's work after its last
    # checkpoint is in neither).
    for s in (a, b):
        t = s["stage_seconds"]
        total = sum(v for k, v in t.items() if k != "shape_functions")
        assert 0.5 * s["wall_s"] < total <= s["wall_s"], s


def test_a_killed_2d_run_resumes_to_the_same_bits(rkforge_bin, tmp_path):
    scene = tmp_path / "block.toml"
    scene.write_text(scene_variant("block_forging.toml", BLOCK))
    whole, cut = straight_and_resumed(rkforge_bin, tmp_path, scene, 0.5)
    assert_same_files(whole, cut)


def test_a_killed_3d_run_resumes_to_the_same_bits(rkforge_bin, tmp_path):
    scene = tmp_path / "bar.toml"
    scene.write_text(scene_variant("taylor_bar_3d.toml", BAR_3D))
    whole, cut = straight_and_resumed(rkforge_bin, tmp_path, scene, 1.0)
    assert_same_files(whole, cut)
    assert (cut / "stages.png").read_bytes() == (whole / "stages.png").read_bytes()


@pytest.mark.parametrize("extra, message", [
    (["--resume"], "no checkpoint to resume"),
    (["--checkpoint-every-s", "-1"], "--checkpoint-every-s -1: give a number of seconds"),
    (["--checkpoint-every-s", "60", "--mcap", "{tmp}/x.mcap"], "--mcap: a recording cannot be resumed"),
])
def test_bad_checkpoint_options_are_refused(rkforge_bin, tmp_path, extra, message):
    extra = [a.format(tmp=tmp_path) for a in extra]
    proc = subprocess.run([rkforge_bin, "run", str(ROOT / "scenes" / "block_forging.toml"), "--quiet",
                           "--out", str(tmp_path / "o")] + extra,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0
    assert message in proc.stderr, proc.stderr


def test_a_checkpoint_of_another_scene_is_refused(rkforge_bin, tmp_path):
    scene = tmp_path / "block.toml"
    scene.write_text(scene_variant("block_forging.toml", BLOCK))
    out = tmp_path / "o"
    killed_after_checkpoint([rkforge_bin, "run", str(scene), "--threads", "1", "--quiet",
                             "--out", str(out), "--checkpoint-every-s", "0"],
                            out / "checkpoint.cbor", 0.0)
    proc = subprocess.run([rkforge_bin, "run", str(scene), "--quiet", "--out", str(out),
                           "--resume", "--set", "tools.top.friction=0.3"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0
    assert "taken of another scene" in proc.stderr and "differs" in proc.stderr, proc.stderr
    proc = subprocess.run([rkforge_bin, "run", str(scene), "--quiet", "--out", str(out),
                           "--resume", "--no-frames"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0
    assert "frames" in proc.stderr and "--no-frames" in proc.stderr, proc.stderr


KILLED_IN_PYTHON = """
import sys
import rkforge
scene = rkforge.Scene.from_file(sys.argv[1])
rkforge.run(scene, threads=1, checkpoint=sys.argv[2], checkpoint_every_s=0)
"""


def test_a_killed_python_run_resumes_to_the_same_bits(tmp_path):
    """`rkforge.run(..., checkpoint=folder)` killed in a process of its own, then run again
    with the same folder: the history of a run that never stopped, to the bit."""
    import sys

    import numpy as np
    import rkforge

    path = tmp_path / "bar.toml"
    path.write_text(scene_variant("taylor_bar_3d.toml", BAR_3D))
    scene = rkforge.Scene.from_file(path)
    whole, whole_history = rkforge.run(scene, threads=1)
    folder = tmp_path / "checkpoints"
    in_python = [sys.executable, "-c", KILLED_IN_PYTHON, str(path), str(folder)]
    killed_after_checkpoint(in_python, folder / "checkpoint.cbor", 1.0)
    summary, history = rkforge.run(scene, threads=1, checkpoint=folder)
    assert list(history.columns) == list(whole_history.columns)
    assert np.array_equal(history.to_numpy().view(np.uint64),
                          whole_history.to_numpy().view(np.uint64))
    assert summary["steps"] == whole["steps"] and len(summary["resumed_at_s"]) == 1
    assert not (folder / "checkpoint.cbor").exists()
    # A checkpoint of another scene is refused, naming the key.
    other = rkforge.Scene.from_file(path)
    other.set("time.end_s", 70e-6)
    killed_after_checkpoint(in_python, folder / "checkpoint.cbor", 0.0)
    with pytest.raises(ValueError, match="`time.end_s` differs"):
        rkforge.run(other, checkpoint=folder)
    with pytest.raises(ValueError, match="checkpoint_every_s"):
        rkforge.run(scene, checkpoint=folder, checkpoint_every_s=-1.0)


SWEEP = ["--resolution", "21x21,41x41,51x51", "--integration", "q2", "--threads", "1"]


def sweep(rkforge_bin, scene, out, *extra, check=True):
    proc = subprocess.run([rkforge_bin, "sweep", str(scene), "--out", str(out), *SWEEP, *extra],
                          capture_output=True, text=True, timeout=900)
    assert not check or proc.returncode == 0, proc.stderr
    return proc


def test_a_killed_sweep_keeps_its_finished_runs_and_resumes_the_one_it_was_in(rkforge_bin, tmp_path):
    """`rkforge sweep --checkpoint-every-s 0` killed in its second run, then `--resume`: the
    first run is kept as it was (not run again), the second goes on from its checkpoint, the
    third runs; every history is the bits of a sweep that never stopped, and so is the table
    but for the wall times."""
    scene = tmp_path / "block.toml"
    scene.write_text(scene_variant("block_forging.toml", {"end_s = 0.015": "end_s = 0.008"}))
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    sweep(rkforge_bin, scene, whole)
    second = cut / "q2_41x41_0.5"
    killed_after_checkpoint([rkforge_bin, "sweep", str(scene), "--out", str(cut), *SWEEP,
                             "--checkpoint-every-s", "0"], second / "checkpoint.cbor", 0.3)
    first = cut / "q2_21x21_0.5"
    kept = (first / "summary.json").read_bytes()
    assert (first / "scene.json").exists() and not (second / "summary.json").exists()
    sweep(rkforge_bin, scene, cut, "--checkpoint-every-s", "0", "--resume")
    assert (first / "summary.json").read_bytes() == kept
    for grid in ("21x21", "41x41", "51x51"):
        run_dir = f"q2_{grid}_0.5"
        assert (cut / run_dir / "history.csv").read_bytes() == (whole / run_dir / "history.csv").read_bytes()
        assert not (cut / run_dir / "checkpoint.cbor").exists()
    resumed = json.loads((second / "summary.json").read_text())
    assert len(resumed["resumed_at_s"]) == 1
    assert "resumed_at_s" not in json.loads((cut / "q2_51x51_0.5" / "summary.json").read_text())

    def table(folder):
        # Every column but the wall time and memory (columns 5 and 6): a resumed run's wall
        # time counts both processes, its memory the last.
        lines = (folder / "sweep.csv").read_text().splitlines()
        return [[f for i, f in enumerate(line.split(",")) if i not in (5, 6)] for line in lines]

    header = (whole / "sweep.csv").read_text().splitlines()[0].split(",")
    assert header[5:7] == ["wall_s", "memory_MB"], header
    assert table(cut) == table(whole)
    # Resumed once more, nothing is left to run: every run is kept.
    summaries = {p: p.read_bytes() for p in cut.glob("*/summary.json")}
    sweep(rkforge_bin, scene, cut, "--resume")
    assert len(summaries) == 3 and all(p.read_bytes() == b for p, b in summaries.items())


def test_a_sweep_resumed_over_another_scenes_runs_is_refused(rkforge_bin, tmp_path):
    scene = tmp_path / "block.toml"
    scene.write_text(scene_variant("block_forging.toml", {"end_s = 0.015": "end_s = 0.003"}))
    out = tmp_path / "o"
    sweep(rkforge_bin, scene, out, "--resolution", "11x11")
    other = tmp_path / "other.toml"
    other.write_text(scene_variant("block_forging.toml", {"end_s = 0.015": "end_s = 0.004"}))
    proc = sweep(rkforge_bin, other, out, "--resolution", "11x11", "--resume", check=False)
    assert proc.returncode != 0
    assert "holds a run of another scene: `time.end_s` differs" in proc.stderr, proc.stderr
    # Without --resume the runs are made again, over the old ones.
    sweep(rkforge_bin, other, out, "--resolution", "11x11")
    assert json.loads((out / "q2_11x11_0.5" / "scene.json").read_text())["time"]["end_s"] == 0.004


KILLED_CASE = """
import sys
import rkforge
from rkforge.study import run_case
scene = rkforge.Scene.from_file(sys.argv[1])
run_case(scene, {"tools.top.friction": 0.3}, None, 1, sys.argv[2], 0.0)
"""


def test_a_studys_killed_case_goes_on_from_its_checkpoint(tmp_path):
    """`rkforge.study(..., checkpoints=folder)`: a case killed in a process of its own (as a
    Dask worker dies) and the study called again go on from the case's checkpoint; the
    table is the bits of a study that never stopped, the case's `resumed_at_s` says where it
    went on; called once more, the study reads its finished cases back."""
    import sys

    import pandas as pd
    import rkforge

    path = tmp_path / "block.toml"
    path.write_text(scene_variant("block_forging.toml", BLOCK))
    scene = rkforge.Scene.from_file(path)
    cases = {"tools.top.friction": [0.1, 0.3]}
    folder = tmp_path / "checkpoints"
    killed_after_checkpoint([sys.executable, "-c", KILLED_CASE, str(path), str(folder / "case-1")],
                            folder / "case-1" / "checkpoint.cbor", 0.5)
    table = rkforge.study(scene, cases, progress=False, threads=1, checkpoints=folder,
                          checkpoint_every_s=0)
    straight = rkforge.study(scene, cases, progress=False, threads=1)
    assert table["resumed_at_s"][0] is None and straight["resumed_at_s"][1] is None
    (at,) = table["resumed_at_s"][1]
    assert 0.0 < at < table["end_time_s"][1]
    timing = ["wall_s", "case_wall_s", "resumed_at_s", "history"]
    pd.testing.assert_frame_equal(table.drop(columns=timing), straight.drop(columns=timing),
                                  check_exact=True)
    for a, b in zip(table["history"], straight["history"]):
        pd.testing.assert_frame_equal(a, b, check_exact=True)
    assert sorted(p.name for p in folder.glob("case-*/*")) == ["result.json", "result.json"]
    # Called again, the study reads every case back from its folder and runs none: the same
    # table (the summaries' own wall times included) and histories, the files untouched.
    stamps = [p.stat().st_mtime_ns for p in sorted(folder.glob("case-*/result.json"))]
    again = rkforge.study(scene, cases, progress=False, threads=1, checkpoints=folder)
    pd.testing.assert_frame_equal(again.drop(columns=["case_wall_s", "history"]),
                                  table.drop(columns=["case_wall_s", "history"]), check_exact=True)
    for a, b in zip(again["history"], table["history"]):
        pd.testing.assert_frame_equal(a, b, check_exact=True)
    assert stamps == [p.stat().st_mtime_ns for p in sorted(folder.glob("case-*/result.json"))]
    # A case whose folder holds another scene's result is an error row saying so; the
    # case that matches is read back.
    other = rkforge.study(scene, {"tools.top.friction": [0.2, 0.3]}, progress=False,
                          checkpoints=folder)
    assert list(other["status"]) == ["error", "ok"]
    assert "holds the result of another scene" in other["error"][0]
    with pytest.raises(ValueError, match="checkpoint_every_s"):
        rkforge.study(scene, cases, progress=False, checkpoints=folder, checkpoint_every_s=-1)
