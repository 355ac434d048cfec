"""Checkpoints of `rkforge run` (`--checkpoint-every-s`, `--resume`): a run killed with
SIGKILL goes on from its last checkpoint and ends with the files of a run that never
stopped, to the bit (history.csv, every VTK frame), in 2D and in 3D; bad uses are refused
with the option and the reason."""
import json
import signal
import subprocess
import time

import pytest

from conftest import ROOT, scene_variant

BLOCK = {"particles = [21, 21]": "particles = [41, 41]"}
BAR_3D = {"cells = [8, 4, 60]": "cells = [4, 2, 30]"}


def straight_and_resumed(rkforge_bin, tmp_path, scene, settle_s):
    """A run to the end, and the same run killed `settle_s` after its first checkpoint and
    resumed: their output folders."""
    args = [rkforge_bin, "run", str(scene), "--threads", "1", "--quiet"]
    whole = tmp_path / "whole"
    proc = subprocess.run(args + ["--out", str(whole)], capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    cut = tmp_path / "cut"
    checkpoint = cut / "checkpoint.cbor"
    run = subprocess.Popen(args + ["--out", str(cut), "--checkpoint-every-s", "0"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 600
    while not checkpoint.exists() and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    time.sleep(settle_s)
    assert run.poll() is None, "the run ended before it was killed: lengthen the scene"
    run.send_signal(signal.SIGKILL)
    run.wait(timeout=60)
    assert checkpoint.exists()
    assert not (cut / "summary.json").exists()
    proc = subprocess.run(args + ["--out", str(cut), "--resume", "--checkpoint-every-s", "0"],
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
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
    run = subprocess.Popen([rkforge_bin, "run", str(scene), "--threads", "1", "--quiet",
                            "--out", str(out), "--checkpoint-every-s", "0"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 600
    while not (out / "checkpoint.cbor").exists() and time.monotonic() < deadline:
        assert run.poll() is None, "the run ended before it was killed"
        time.sleep(0.01)
    run.kill()
    run.wait(timeout=60)
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
    run = subprocess.Popen([sys.executable, "-c", KILLED_IN_PYTHON, str(path), str(folder)],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 600
    while not (folder / "checkpoint.cbor").exists() and time.monotonic() < deadline:
        assert run.poll() is None, run.stderr.read()
        time.sleep(0.01)
    time.sleep(1.0)
    assert run.poll() is None, "the run ended before it was killed: lengthen the scene"
    run.kill()
    run.wait(timeout=60)
    summary, history = rkforge.run(scene, threads=1, checkpoint=folder)
    assert list(history.columns) == list(whole_history.columns)
    assert np.array_equal(history.to_numpy().view(np.uint64),
                          whole_history.to_numpy().view(np.uint64))
    assert summary["steps"] == whole["steps"] and len(summary["resumed_at_s"]) == 1
    assert not (folder / "checkpoint.cbor").exists()
    # A checkpoint of another scene is refused, naming the key.
    other = rkforge.Scene.from_file(path)
    other.set("time.end_s", 70e-6)
    run = subprocess.Popen([sys.executable, "-c", KILLED_IN_PYTHON, str(path), str(folder)],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    while not (folder / "checkpoint.cbor").exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    run.kill()
    run.wait(timeout=60)
    with pytest.raises(ValueError, match="`time.end_s` differs"):
        rkforge.run(other, checkpoint=folder)
    with pytest.raises(ValueError, match="checkpoint_every_s"):
        rkforge.run(scene, checkpoint=folder, checkpoint_every_s=-1.0)
