"""rkforge: RKPM simulation of metal forming and impact, from Python.

- :class:`Scene` -- a scene file or text, with dotted-key overrides
  (``scene.set("tools.top.friction", 0.1)``) validated like the file itself.
- :class:`Simulation` -- step a scene, command tool velocities, read forces, strokes,
  particle fields (numpy) and every output of the register by name (``outputs()``), save
  and restore states. Stepping releases the GIL.
- :func:`run` -- the whole run of ``rkforge run --no-frames``: its summary and history,
  the same bits.
- :func:`study` -- a parameter study over dotted keys, locally or on a Dask cluster.
- :func:`read_mcap` -- tool histories, the register's outputs and point clouds of an MCAP
  recording.
"""
from __future__ import annotations

import os
from typing import Optional, Tuple, Union

import pandas as pd

from ._rkforge import (
    Scene,
    SceneError,
    Simulation,
    SimulationError,
    StateError,
    __version__,
    run_scene,
)
from .recording import Recording, read_mcap
from .study import study

__all__ = [
    "Recording",
    "Scene",
    "SceneError",
    "Simulation",
    "SimulationError",
    "StateError",
    "__version__",
    "read_mcap",
    "run",
    "study",
]


def run(
    scene: Scene,
    integration: Optional[str] = None,
    threads: Optional[int] = None,
    check: bool = True,
    checkpoint: Optional[Union[str, os.PathLike]] = None,
    checkpoint_every_s: float = 600.0,
) -> Tuple[dict, pd.DataFrame]:
    """Run ``scene`` to its end time as ``rkforge run --no-frames`` does.

    Returns ``(summary, history)``: the summary as in summary.json (a dict) and the time
    history as a DataFrame with history.csv's columns (``time_s``, ``<tool>.force_N``, ...),
    the same bits as the command line's files.

    ``integration`` ("q4", "q2", "scni") overrides the scene's rule; ``threads`` runs on a
    pool of that many threads (results do not depend on it). A run that fails midway raises
    :class:`SimulationError` carrying ``summary`` (``"status": "error"``) and ``history`` up
    to the failure; with ``check=False`` they are returned instead. A scene its setup refuses
    before the first step (a fixed ``time.dt_s`` above the measured critical step) raises
    :class:`SimulationError` without them, ``check=False`` too: there is no run to return. A
grid beyond the memory or address space the process can have raises ``MemoryError``
naming the key, before the setup allocates its tables.

    With ``checkpoint`` (a folder), the run writes ``checkpoint.cbor`` there every
    ``checkpoint_every_s`` seconds of wall time; a run given a folder that holds the
    checkpoint of a killed run of the same scene goes on from it, to the same bits as a run
    that never stopped (the summary then has ``resumed_at_s``), and a run that ends removes
    it. A checkpoint of another scene raises ``ValueError`` naming the first key that differs.
    """
    summary, columns, rows, failure = run_scene(
        scene,
        integration,
        threads,
        None if checkpoint is None else os.fspath(checkpoint),
        checkpoint_every_s,
    )
    history = pd.DataFrame(rows, columns=columns)
    if failure is not None and check:
        error = SimulationError(failure)
        error.summary = summary
        error.history = history
        raise error
    return summary, history
