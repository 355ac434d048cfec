"""The built wheel in a clean virtual environment: installed with only the dependencies it
declares, it imports every module and runs a study (issue 26: `pip install ./python` then
`rkforge.study(...)` failed with "No module named 'tqdm'", which the test venv, with tqdm
from tests/requirements.txt, could not see).

One fresh venv (no system site packages): first the wheel alone (its required
dependencies), where every submodule imports and a local study runs with its progress bar;
then the wheel with the `[dask]` extra, where the same study runs on a local Dask cluster of
worker processes and gives the same rows. Every module the package's sources import (also
inside functions) must come from a distribution the wheel declares."""
import json
import os
import pathlib
import re
import subprocess
import sys
import zipfile

import pytest

from conftest import ROOT, scene_variant

WHEEL_DIR = ROOT / "target" / "python-wheel"

#: Modules imported by rkforge that the venv (required dependencies and `[dask]`) does not
#: install: those of the `mcap` extra, with the distribution that provides each.
NOT_INSTALLED = {"mcap": ("mcap", "mcap"), "mcap_ros2": ("mcap-ros2-support", "mcap")}

#: 4 cases of a 9 x 9 block forged for 2 ms: a fraction of a second each.
SCENE = ("block_forging.toml", {"particles = [21, 21]": "particles = [9, 9]",
                                 "end_s = 0.015": "end_s = 0.002"})
CASES = {"tools.top.friction": [0.1, 0.3], "tools.top.motion.velocity_m_per_s": [5.0, 10.0]}

#: Generous: pip downloads, and both cores may be busy with other work.
TIMEOUT = 900

#: Run by the venv's interpreter (isolated mode: no PYTHONPATH, no user site, not the
#: current directory). Prints one JSON object on its last stdout line.
SCRIPT = r'''
import ast, importlib, importlib.metadata, importlib.util, json, math, pathlib, pkgutil, sys, traceback

import rkforge


def rows(table):
    return [{k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()}
            for row in table.drop(columns=["history"]).to_dict("records")]


def run_study(scene_path, cases, client=None):
    scene = rkforge.Scene.from_file(scene_path)
    table = rkforge.study(scene, cases, client=client, progress=True, timeout=600)
    return table, {"rows": rows(table), "history_rows": [len(h) for h in table["history"]]}


def submodules():
    names = []
    for info in pkgutil.walk_packages(rkforge.__path__, "rkforge."):
        importlib.import_module(info.name)
        names.append(info.name)
    return names


def imports_of_the_package():
    # Every module named by an import statement in the package's sources and stubs,
    # inside functions too (relative imports are the package's own).
    imported = set()
    for path in pathlib.Path(rkforge.__file__).parent.rglob("*"):
        if path.suffix not in (".py", ".pyi"):
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                imported.update(a.name.split(".")[0] for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                imported.add(node.module.split(".")[0])
    return sorted(m for m in imported if m not in sys.stdlib_module_names and m != "rkforge")


def dask_study(scene_path, cases):
    import pandas as pd
    from distributed import Client, LocalCluster

    local, out = run_study(scene_path, cases)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        remote, out["dask"] = run_study(scene_path, cases, client)
        out["worker_prefixes"] = sorted(set(client.run(lambda: sys.prefix).values()))
    timing = ["wall_s", "case_wall_s", "history"]
    pd.testing.assert_frame_equal(remote.drop(columns=timing), local.drop(columns=timing),
                                  check_exact=True)
    for a, b in zip(remote["history"], local["history"]):
        pd.testing.assert_frame_equal(a, b, check_exact=True)
    out["dask_equals_local"] = True
    return out


def step(fn, *args):
    # Each check on its own: a failure is reported with its traceback, the others still run.
    try:
        return {"ok": fn(*args)}
    except BaseException:
        return {"error": traceback.format_exc()}


def main(mode, scene_path, cases, modules):
    out = {"file": rkforge.__file__, "prefix": sys.prefix, "base_prefix": sys.base_prefix}
    if mode == "local":
        out["submodules"] = step(submodules)
        out["third_party"] = step(imports_of_the_package)
        out["study"] = step(lambda: run_study(scene_path, cases)[1])
    else:
        # Which distributions provide the (installed) third-party modules.
        dists = importlib.metadata.packages_distributions()
        out["installed"] = {m: dists.get(m, []) for m in modules if importlib.util.find_spec(m) is not None}
        out["study"] = step(dask_study, scene_path, cases)
    return out


if __name__ == "__main__":  # the Dask workers are spawned processes that import this file
    print(json.dumps(main(sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), sys.argv[4:])))
'''


def newest_wheel():
    wheels = sorted(WHEEL_DIR.glob("rkforge-*.whl"), key=lambda p: p.stat().st_mtime)
    return wheels[-1] if wheels else None


def declared(wheel):
    """The wheel's Requires-Dist: normalized distribution name -> set of extras (None for
    a required dependency)."""
    with zipfile.ZipFile(wheel) as z:
        meta = next(n for n in z.namelist() if n.endswith(".dist-info/METADATA"))
        text = z.read(meta).decode()
    out = {}
    for line in text.splitlines():
        if not line.startswith("Requires-Dist:"):
            continue
        spec = line.split(":", 1)[1].strip()
        name = normalize(re.match(r"[A-Za-z0-9._-]+", spec).group(0))
        extra = re.search(r"""extra\s*==\s*['"]([^'"]+)['"]""", spec)
        out.setdefault(name, set()).add(extra.group(1) if extra else None)
    return out


def normalize(name):
    return re.sub(r"[-_.]+", "-", name).lower()


class CleanVenv:
    def __init__(self, tmp):
        self.dir = tmp / "venv"
        self.python = str(self.dir / "bin" / "python")
        self.env = {k: v for k, v in os.environ.items()
                    if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "PYTHONSTARTUP")}
        self.env.update(PYTHONNOUSERSITE="1", VIRTUAL_ENV=str(self.dir),
                        PATH=f"{self.dir / 'bin'}{os.pathsep}{os.environ.get('PATH', '')}")
        self.cwd = tmp
        self.script = tmp / "check.py"
        self.script.write_text(SCRIPT)
        # The base interpreter of the test venv, without its site packages.
        self.check([sys.executable, "-m", "venv", str(self.dir)])

    def check(self, args):
        proc = subprocess.run(args, cwd=self.cwd, env=self.env, capture_output=True, text=True,
                              timeout=TIMEOUT)
        assert proc.returncode == 0, f"{' '.join(args)} failed:\n{proc.stdout[-4000:]}\n{proc.stderr[-6000:]}"
        return proc

    def pip_install(self, requirement):
        # The index, certificates and cache of the environment (as tests/run.sh's pip).
        self.check([self.python, "-m", "pip", "install", "-q", "--disable-pip-version-check", requirement])

    def run(self, mode, scene, modules=()):
        proc = self.check([self.python, "-I", str(self.script), mode, str(scene), json.dumps(CASES), *modules])
        return json.loads(proc.stdout.strip().splitlines()[-1]), proc.stderr


def ok(result):
    """The value of a step of the script, or the failure with its traceback."""
    if "error" in result:
        pytest.fail(result["error"], pytrace=False)
    return result["ok"]


@pytest.fixture(scope="module")
def wheel():
    path = newest_wheel()
    if path is None:
        pytest.skip(f"no built wheel in {WHEEL_DIR} (tests/run.sh builds it with maturin)")
    return path


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("clean_venv")
    v = CleanVenv(tmp)
    v.scene = tmp / SCENE[0]
    v.scene.write_text(scene_variant(*SCENE))
    return v


@pytest.fixture(scope="module")
def required_only(wheel, venv):
    """The wheel installed with its required dependencies only: imports and a local study."""
    venv.pip_install(str(wheel))
    return venv.run("local", venv.scene)


@pytest.fixture(scope="module")
def with_dask(wheel, venv, required_only):
    """Then the `[dask]` extra: the study here and on a local cluster of worker processes."""
    third_party = required_only[0]["third_party"].get("ok", [])
    venv.pip_install(f"{wheel}[dask]")
    return venv.run("dask", venv.scene, third_party)


def assert_study_rows(result):
    rows = result["rows"]
    assert [r["case"] for r in rows] == [0, 1, 2, 3]
    assert [r["tools.top.friction"] for r in rows] == [0.1, 0.1, 0.3, 0.3]
    assert [r["tools.top.motion.velocity_m_per_s"] for r in rows] == [5.0, 10.0, 5.0, 10.0]
    assert [r["status"] for r in rows] == ["ok"] * 4, [r["error"] for r in rows]
    assert [r["error"] for r in rows] == [None] * 4
    # The faster press strokes further in the same time; each case has its whole history.
    assert rows[0]["tools.top.stroke_m"] < rows[1]["tools.top.stroke_m"]
    assert all(n > 2 for n in result["history_rows"])


def test_rkforge_is_the_wheel_installed_in_the_clean_venv(required_only, venv):
    out, _ = required_only
    assert pathlib.Path(out["prefix"]).resolve() == venv.dir.resolve()
    assert out["base_prefix"] != out["prefix"]
    # rkforge is the installed wheel, not the sources of this repository.
    assert pathlib.Path(out["file"]).resolve().is_relative_to(venv.dir.resolve())


def test_every_submodule_imports_with_the_required_dependencies_only(required_only):
    out, _ = required_only
    assert {"rkforge._rkforge", "rkforge.recording", "rkforge.study"} <= set(ok(out["submodules"]))


def test_a_local_study_with_its_progress_bar_runs_with_the_required_dependencies_only(required_only):
    """The issue's case: `pip install` the package, then `rkforge.study(...)` (with its
    progress bar, the default)."""
    out, stderr = required_only
    assert_study_rows(ok(out["study"]))
    assert "rkforge study" in stderr, "the tqdm progress bar was not shown"


def test_every_imported_module_comes_from_a_declared_distribution(wheel, required_only, with_dask):
    """Static: the modules named by import statements anywhere in the package (inside
    functions too) are each provided by a distribution in the wheel's Requires-Dist; those
    the venv lacks are the `mcap` extra's."""
    third_party = ok(required_only[0]["third_party"])
    installed = with_dask[0]["installed"]
    requires = declared(wheel)
    assert {"numpy", "pandas", "tqdm", "distributed"} <= set(third_party)
    for module in third_party:
        if module in installed:
            dists = {normalize(d) for d in installed[module]}
            assert dists & set(requires), f"`import {module}` (from {sorted(dists)}) is not declared: {requires}"
        else:
            assert module in NOT_INSTALLED, f"`import {module}`: not installed by the wheel's dependencies and [dask]"
            dist, extra = NOT_INSTALLED[module]
            assert extra in requires.get(dist, set()), f"{dist} is not declared in the [{extra}] extra: {requires}"


def test_a_study_on_a_local_dask_cluster_gives_the_local_rows(with_dask, venv):
    out, stderr = with_dask
    result = ok(out["study"])
    assert_study_rows(result)
    assert_study_rows(result["dask"])
    assert result["dask_equals_local"]
    # The cases ran in worker processes of the clean venv.
    assert [pathlib.Path(p).resolve() for p in result["worker_prefixes"]] == [venv.dir.resolve()]
    assert stderr.count("rkforge study") >= 2
