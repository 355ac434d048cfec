"""`rkforge.study`: parameter studies run locally and on a Dask cluster whose scheduler and
two workers are separate processes started with the `dask` command-line tools on the
loopback interface; the same rows bit for bit, and a worker killed mid-study loses nothing."""
import csv
import json
import os
import pathlib
import signal
import subprocess
import sys
import threading
import time

import pandas as pd
import pytest

import rkforge
from conftest import scene_variant

distributed = pytest.importorskip("distributed")

#: Columns that hold timings (not results) and the histories (compared one by one).
TIMES = ["wall_s", "case_wall_s", "resumed_at_s", "history"]

#: Friction x press speed: 8 cases of a coarse block forging, about a second each.
CASES = {
    "tools.top.friction": [0.1, 0.3],
    "tools.top.motion.velocity_m_per_s": [5.0, 7.5, 10.0, 12.5],
}

#: Generous: both cores may be busy with other work.
TIMEOUT = 900


def block_scene():
    text = scene_variant("block_forging.toml", {"particles = [21, 21]": "particles = [17, 17]",
                                                 "end_s = 0.015": "end_s = 0.008"})
    return rkforge.Scene.from_toml(text, "block.toml")


def results(table):
    return table.drop(columns=TIMES)


def assert_same_histories(a, b):
    assert len(a) == len(b)
    for ha, hb in zip(a["history"], b["history"]):
        pd.testing.assert_frame_equal(ha, hb, check_exact=True)


@pytest.fixture(scope="module")
def local():
    """The study run here, one case after the other."""
    return rkforge.study(block_scene(), CASES, progress=False)


class Cluster:
    """A scheduler and two single-threaded workers, each its own `dask` process."""

    def __init__(self, tmp):
        dask = str(pathlib.Path(sys.executable).parent / "dask")
        self.file = tmp / "scheduler.json"
        self.logs = []
        self.scheduler = self.start([dask, "scheduler", "--host", "127.0.0.1", "--port", "0",
                                     "--no-dashboard", "--scheduler-file", str(self.file)], tmp / "scheduler.log")
        self.workers = [
            self.start([dask, "worker", "--scheduler-file", str(self.file), "--host", "127.0.0.1",
                        "--nthreads", "1", "--no-nanny", "--no-dashboard", "--local-directory", str(tmp / f"w{k}")],
                       tmp / f"worker{k}.log")
            for k in range(2)
        ]
        # Client waits for the scheduler file and connects; then we wait for both workers.
        self.client = distributed.Client(scheduler_file=str(self.file), timeout=TIMEOUT)
        self.client.wait_for_workers(2, timeout=TIMEOUT)

    def start(self, args, log):
        f = open(log, "w")
        self.logs.append(f)
        return subprocess.Popen(args, stdout=f, stderr=subprocess.STDOUT, start_new_session=True)

    def worker_pids(self):
        """Scheduler address -> pid of each connected worker."""
        return self.client.run(os.getpid)

    def close(self):
        """Stop the workers, then the scheduler. A worker told by the closing scheduler to
        stop while it handles its own SIGTERM can hang in its close until killed (seen under
        load: 60 s lost per test), so the scheduler is signalled only after the workers
        have ended."""
        self.client.close()
        for group in (self.workers, [self.scheduler]):
            for p in group:
                if p.poll() is None:
                    p.send_signal(signal.SIGTERM)
            for p in group:
                try:
                    p.wait(timeout=60)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
        for f in self.logs:
            f.close()


@pytest.fixture
def cluster(tmp_path):
    c = Cluster(tmp_path)
    yield c
    c.close()


def test_a_study_is_a_grid_of_rows_with_inputs_figures_and_histories(local):
    assert len(local) == 8
    assert list(local["tools.top.friction"]) == [0.1] * 4 + [0.3] * 4
    assert list(local["tools.top.motion.velocity_m_per_s"]) == [5.0, 7.5, 10.0, 12.5] * 2
    assert (local["status"] == "ok").all() and local["error"].isna().all()
    # Faster presses stroke further in the same time; the history holds every sample.
    strokes = local["tools.top.stroke_m"]
    assert strokes.iloc[0] < strokes.iloc[1] < strokes.iloc[2] < strokes.iloc[3]
    for i, h in enumerate(local["history"]):
        assert h["top.stroke_m"].iloc[-1] == strokes.iloc[i]
        assert h["time_s"].iloc[-1] == local["end_time_s"].iloc[i]
    # Friction changes the result at the same speed.
    width = local["workpiece.width_m"]
    assert all(width.iloc[k] != width.iloc[k + 4] for k in range(4))


def test_failed_cases_are_rows_with_their_error():
    table = rkforge.study(block_scene(), [
        {"tools.top.friction": 0.2},
        {"tools.top.friction": -1.0},
        {"checks.energy_balance_tol": 1e-9},
        {"tools.middle.friction": 0.1},
    ], progress=False)
    assert list(table["status"]) == ["ok", "error", "error", "error"]
    assert "must be zero or positive" in table["error"][1]
    assert "energy balance error" in table["error"][2]
    assert "no entry of `tools` is named `middle`" in table["error"][3]
    # The diverged run keeps its history up to the failure; the refused scenes have none.
    assert len(table["history"][2]) == 2 and table["history"][1] is None


def test_the_study_on_a_dask_cluster_gives_the_local_rows_bit_for_bit(cluster, local):
    remote = rkforge.study(block_scene(), CASES, client=cluster.client, timeout=TIMEOUT)
    pd.testing.assert_frame_equal(results(remote), results(local), check_exact=True)
    assert_same_histories(remote, local)


def test_cases_past_the_timeout_are_cancelled_and_are_rows_with_their_error(cluster):
    """A study whose cases (a finer block, several seconds each) cannot finish in 0.3 s:
    each unfinished case is an error row naming the timeout, and the cluster holds none of
    its tasks afterwards (they were cancelled, not left running)."""
    text = scene_variant("block_forging.toml", {"particles = [21, 21]": "particles = [41, 41]"})
    slow = rkforge.Scene.from_toml(text, "block.toml")
    table = rkforge.study(slow, {"tools.top.friction": [0.1, 0.2, 0.3]}, client=cluster.client,
                          progress=False, timeout=0.3)
    late = table[table["status"] == "error"]
    assert len(late) >= 1
    assert all(e.startswith("TimeoutError: not finished within the study's timeout of 0.3 s")
               and e.endswith("cancelled") for e in late["error"])
    assert all(h is None for h in late["history"])
    deadline = time.time() + 60
    while any(cluster.client.processing().values()) and time.time() < deadline:
        time.sleep(0.2)
    assert not any(cluster.client.processing().values())


def test_a_worker_killed_mid_study_loses_no_case(cluster, local, tmp_path):
    """A worker killed while it runs a case: the case is rescheduled on the other worker
    and, with checkpoints in a folder both reach, goes on from its last one; the table is the
    local study's, bit for bit."""
    ours = {p.pid for p in cluster.workers}
    pids = cluster.worker_pids()
    assert set(pids.values()) == ours
    killed = {}
    lock = threading.Lock()

    def on_case(i, result):
        # At the first finished case, kill a worker while it runs a case that has written a
        # checkpoint (waiting for one, if none has yet).
        with lock:
            if killed:
                return
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline:
                for addr, keys in cluster.client.processing().items():
                    pid = pids.get(addr)
                    for key in keys:
                        case = int(str(key).split("-")[2])
                        if pid in ours and (tmp_path / f"case-{case}" / "checkpoint.cbor").exists():
                            os.kill(pid, signal.SIGKILL)
                            killed.update(pid=pid, case=case, running=list(keys))
                            return
                time.sleep(0.005)

    remote = rkforge.study(block_scene(), CASES, client=cluster.client, progress=False,
                           on_case=on_case, timeout=TIMEOUT, checkpoints=tmp_path,
                           checkpoint_every_s=0)
    assert killed, "no worker was running a case with a checkpoint after the first one finished"
    resumed = [i for i, r in enumerate(remote["resumed_at_s"]) if r is not None]
    print(f"killed {killed}: cases that went on from a checkpoint: {resumed}")
    # The killed case went on from its checkpoint on the other worker (unless it finished in
    # the microseconds between the look at its checkpoint and the kill: then it was not
    # running and none is resumed).
    assert resumed in ([killed["case"]], []), resumed
    assert len(cluster.client.scheduler_info()["workers"]) == 1
    pd.testing.assert_frame_equal(results(remote), results(local), check_exact=True)
    assert_same_histories(remote, local)


#: The 3D block of scenes/block_upsetting_3d.toml (the quarter model, 7 x 5 x 9 particles,
#: mass-scaled), 50 ms of its press stroke: 1 mm.
BLOCK_3D = {"end_s = 1.0 ": "end_s = 0.05 "}

#: Friction of both dies and a coarser grid, and two cases that cannot run.
CASES_3D = [
    {"tools.anvil.friction": 0.1, "tools.ram.friction": 0.1},
    {"tools.anvil.friction": 0.5, "tools.ram.friction": 0.5},
    {"workpiece.particles": [5, 3, 7]},
    {"tools.ram.friction": -0.1},
    {"workpiece.particles": [7, 5]},
]


def cli_case(rkforge_bin, scene, case, out):
    """`rkforge run` of the scene file with the case's keys as `--set` overrides: its
    summary and history."""
    sets = [f"--set={k}={json.dumps(v)}" for k, v in case.items()]
    subprocess.run([rkforge_bin, "run", str(scene), "--out", str(out), "--quiet", "--no-frames",
                    *sets], check=True, capture_output=True, text=True, timeout=TIMEOUT)
    summary = json.loads((out / "summary.json").read_text())
    with open(out / "history.csv") as f:
        rows = list(csv.reader(f))
    return summary, pd.DataFrame([[float(x) for x in r] for r in rows[1:]], columns=rows[0])


def test_a_3d_forging_study_on_the_cluster_gives_rkforge_runs_figures(cluster, rkforge_bin,
                                                                      tmp_path):
    """A study of the rectangular block in 3D on the cluster of separate processes: each
    case's row has the figures of `rkforge run` with the same overrides, bit for bit, and its
    history; the cases that cannot run are rows with their errors; more friction on the dies
    takes more force at the same stroke."""
    from rkforge.study import figures

    text = scene_variant("block_upsetting_3d.toml", BLOCK_3D)
    path = tmp_path / "block3d.toml"
    path.write_text(text)
    table = rkforge.study(rkforge.Scene.from_toml(text, str(path)), CASES_3D,
                          client=cluster.client, progress=False, timeout=TIMEOUT)
    assert list(table["status"]) == ["ok", "ok", "ok", "error", "error"]
    assert "must be zero or positive" in table["error"][3]
    assert "workpiece.particles" in table["error"][4]
    assert table["history"][3] is None and table["history"][4] is None
    for i, case in enumerate(CASES_3D[:3]):
        summary, history = cli_case(rkforge_bin, path, case, tmp_path / f"cli{i}")
        expected = {k: v for k, v in figures(summary).items()
                    if not k.startswith(("stage_seconds", "wall_s", "threads"))}
        assert "us_per_particle_step" not in table.columns  # timing, like wall_s
        row = table.iloc[i]
        got = {k: row[k] for k in expected}
        assert got == expected, i
        pd.testing.assert_frame_equal(table["history"][i], history, check_exact=True)
    # 1 mm of stroke at 20 mm/s, and the whole history to the end.
    assert table["tools.ram.stroke_m"][0] == pytest.approx(1e-3, rel=1e-9)
    force = table["history"][0]["ram.force_N"].iloc[-1], table["history"][1]["ram.force_N"].iloc[-1]
    print(f"3D block at 1 mm: ram force {force[0]:.4g} N (mu 0.1), {force[1]:.4g} N (mu 0.5)")
    assert force[1] < force[0] < 0.0, "pressing: more friction, more force"
