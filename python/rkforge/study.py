"""Parameter studies: a grid or a list of dotted-key overrides, run locally or on Dask."""
from __future__ import annotations

import itertools
import json
import asyncio
import math
import os
import time
import uuid
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Union

import pandas as pd

Cases = Union[Mapping[str, Sequence[Any]], Sequence[Mapping[str, Any]]]

#: Summary keys that are not figures of the case (timing and the machine it ran on).
_NOT_FIGURES = ("stage_seconds", "threads", "wall_s", "us_per_particle_step", "error", "status",
                "resumed_at_s")


def expand(cases: Cases) -> List[Dict[str, Any]]:
    """The explicit cases of a study: a dict of dotted key -> list of values gives every
    combination (the first key varying slowest, as ``rkforge sweep --set``); a list of dicts
    is taken as it is."""
    if isinstance(cases, Mapping):
        keys = list(cases)
        for k in keys:
            if isinstance(cases[k], (str, bytes)) or not isinstance(cases[k], Sequence):
                raise TypeError(f"cases[{k!r}] must be a list of values, got {type(cases[k]).__name__}")
        return [dict(zip(keys, combo)) for combo in itertools.product(*(cases[k] for k in keys))]
    out = []
    for i, case in enumerate(cases):
        if not isinstance(case, Mapping):
            raise TypeError(f"cases[{i}] must be a dict of dotted key -> value, got {type(case).__name__}")
        out.append(dict(case))
    return out


#: The file in a case's checkpoint folder that keeps its finished result.
RESULT = "result.json"


def _kept(folder: str, scene_toml: str, integration: Optional[str]):
    """The summary and history of the case finished before in ``folder`` (its
    :data:`RESULT`), or None; raises ValueError if that case ran another scene."""
    import pandas as pd

    path = os.path.join(folder, RESULT)
    if not os.path.exists(path):
        return None
    with open(path) as f:
        kept = json.load(f)
    if kept["scene"] != scene_toml or kept["integration"] != integration:
        raise ValueError(f"{folder} holds the result of another scene or rule: give the study "
                         "the cases it ran, or another checkpoints folder")
    return kept["summary"], pd.DataFrame(kept["rows"], columns=kept["columns"], dtype=float)


def _keep(folder: str, scene_toml: str, integration: Optional[str], summary: dict, history) -> None:
    """Write a finished case's result into ``folder`` (beside, then renamed over: a kill
    while it writes leaves no partial file)."""
    path = os.path.join(folder, RESULT)
    with open(path + ".partial", "w") as f:
        json.dump({"scene": scene_toml, "integration": integration, "summary": summary,
                   "columns": list(history.columns), "rows": history.to_numpy().tolist()}, f)
    os.replace(path + ".partial", path)


def run_case(scene, overrides: Dict[str, Any], integration: Optional[str], threads: Optional[int],
             checkpoint: Optional[str] = None, checkpoint_every_s: float = 600.0) -> dict:
    """One case: the scene with ``overrides`` run to its end. With a folder ``checkpoint``,
    a case finished there before is read back, not run; else the run writes checkpoints
    there (going on from the one a killed attempt left) and keeps its result there when it
    ends. Never raises: a bad override or a failed run gives ``status`` "error" and the
    error text."""
    from . import run  # the package is imported on Dask workers too

    start = time.perf_counter()
    summary, history, error = None, None, None
    try:
        case_scene = scene.copy()
        for key, value in overrides.items():
            case_scene.set(key, value)
        scene_toml = case_scene.to_toml()
        kept = None if checkpoint is None else _kept(checkpoint, scene_toml, integration)
        if kept is not None:
            summary, history = kept
        else:
            summary, history = run(case_scene, integration=integration, threads=threads,
                                   check=False, checkpoint=checkpoint,
                                   checkpoint_every_s=checkpoint_every_s)
            if checkpoint is not None and summary.get("error") is None:
                _keep(checkpoint, scene_toml, integration, summary, history)
        error = summary.get("error")
    except Exception as e:  # noqa: BLE001 - a case's error becomes its row
        error = f"{type(e).__name__}: {e}"
    return {
        "summary": summary,
        "history": history,
        "status": "ok" if error is None else "error",
        "error": error,
        "case_wall_s": time.perf_counter() - start,
    }


def figures(summary: Optional[dict]) -> Dict[str, Any]:
    """The summary's figures as flat columns: nested keys dotted (``workpiece.height_m``),
    tools by name (``tools.top.peak_force_N``), pairs split (``tools.top.force_N[0]``)."""
    flat: Dict[str, Any] = {}

    def walk(prefix: str, value: Any) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                walk(f"{prefix}.{k}" if prefix else k, v)
        elif isinstance(value, list) and all(isinstance(t, dict) and "name" in t for t in value) and value:
            for t in value:
                walk(f"{prefix}.{t['name']}", {k: v for k, v in t.items() if k != "name"})
        elif isinstance(value, list):
            for i, v in enumerate(value):
                walk(f"{prefix}[{i}]", v)
        else:
            flat[prefix] = value

    if summary is not None:
        walk("", {k: v for k, v in summary.items() if k not in _NOT_FIGURES})
    return flat


def _bar(total: int, progress: bool):
    if not progress:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, unit="case", desc="rkforge study")


def _error_row(error: str) -> dict:
    """The result of a case that gave no run: its error only."""
    return {"summary": None, "history": None, "status": "error", "error": error,
            "case_wall_s": math.nan}


def study(
    scene,
    cases: Cases,
    client=None,
    *,
    integration: Optional[str] = None,
    threads: Optional[int] = None,
    retries: int = 2,
    progress: bool = True,
    on_case: Optional[Callable[[int, dict], None]] = None,
    timeout: Optional[float] = None,
    checkpoints: Optional[Union[str, os.PathLike]] = None,
    checkpoint_every_s: float = 600.0,
) -> pd.DataFrame:
    """Run ``scene`` once per case and return one row per case.

    ``cases`` is a dict of dotted key -> list of values (the full grid, first key slowest)
    or a list of dicts (explicit cases). Without ``client`` the cases run here, one after
    the other; with a ``distributed.Client`` each case is a Dask task (``pure=False``, a
    unique key, ``retries`` for cases that raise; cases on a worker that dies are
    rescheduled by the scheduler). ``progress`` shows a tqdm bar; ``on_case(index, result)``
    is called as each case finishes. ``timeout`` (s) bounds the wait for the cluster's
    results: past it the cases not finished are cancelled on the cluster and each is a row
    with its error (``TimeoutError: ...``), the finished ones rows as usual.

    ``checkpoints`` (a folder every worker can reach, e.g. on a shared file system) gives
    each case a folder ``case-<index>`` in it where its run writes a checkpoint every
    ``checkpoint_every_s`` seconds of wall time (:func:`rkforge.run`'s ``checkpoint``) and,
    when it finishes, its result (``result.json``: the scene as run, the summary and the
    history). A case whose worker died, retried by Dask, goes on from its last checkpoint
    to the same bits instead of from the start; the same study called again (after the
    client was lost, say) reads its finished cases back and goes on with the rest. A case's
    folder that holds a checkpoint or result of another scene makes that case an error row
    saying so (the checkpoint's names the first key that differs).

    Columns: ``case`` (its index), the inputs (named by their dotted keys), ``status``
    ("ok" or "error"), ``error`` (the error text), ``wall_s`` (the run's wall time as
    summary.json has it, over every attempt of a case that went on from its checkpoint),
    ``case_wall_s`` (the case's wall time on its worker, Python included), ``resumed_at_s``
    (the simulated times a case went on from its checkpoints, None for a case run in one
    go), then the summary's figures (:func:`figures`). A failed case is a row with
    its error. The last column, ``history``, holds each case's history DataFrame (None for
    a case whose scene was refused).
    """
    explicit = expand(cases)
    keys: List[str] = []
    for case in explicit:
        keys.extend(k for k in case if k not in keys)
    results: Dict[int, dict] = {}
    bar = _bar(len(explicit), progress)

    def done(i: int, result: dict) -> None:
        results[i] = result
        if bar is not None:
            bar.update(1)
        if on_case is not None:
            on_case(i, result)

    try:
        if checkpoint_every_s is None or not checkpoint_every_s >= 0:
            raise ValueError(f"checkpoint_every_s = {checkpoint_every_s}: give a number of seconds, 0 or more")
        folders = [None if checkpoints is None else os.path.join(os.fspath(checkpoints), f"case-{i}")
                   for i in range(len(explicit))]
        if client is None:
            for i, case in enumerate(explicit):
                done(i, run_case(scene, case, integration, threads, folders[i], checkpoint_every_s))
        else:
            from distributed import as_completed

            token = uuid.uuid4().hex
            futures = {}
            for i, case in enumerate(explicit):
                f = client.submit(run_case, scene, case, integration, threads, folders[i],
                                  checkpoint_every_s, key=f"rkforge-case-{i}-{token}",
                                  pure=False, retries=retries)
                futures[f] = i
            try:
                for future in as_completed(futures, timeout=timeout):
                    i = futures[future]
                    try:
                        result = future.result()
                    except Exception as e:  # noqa: BLE001 - a lost case becomes its row
                        result = _error_row(f"{type(e).__name__}: {e}")
                    done(i, result)
            except (TimeoutError, asyncio.TimeoutError):
                late = [f for f, i in futures.items() if i not in results]
                client.cancel(late)
                for f in late:
                    done(futures[f], _error_row(
                        f"TimeoutError: not finished within the study's timeout of {timeout} s "
                        f"({len(futures) - len(late)} of {len(futures)} cases were); cancelled"))
    finally:
        if bar is not None:
            bar.close()
    rows = []
    for i, case in enumerate(explicit):
        r = results[i]
        summary = r["summary"] or {}
        row: Dict[str, Any] = {"case": i}
        row.update({k: case.get(k) for k in keys})
        row.update(status=r["status"], error=r["error"], wall_s=summary.get("wall_s", math.nan),
                   case_wall_s=r["case_wall_s"], resumed_at_s=summary.get("resumed_at_s"))
        row.update(figures(r["summary"]))
        rows.append(row)
    table = pd.DataFrame(rows)
    table["history"] = pd.Series([results[i]["history"] for i in range(len(explicit))],
                                 index=table.index, dtype=object)
    return table
