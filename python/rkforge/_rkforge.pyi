"""Type stubs of the Rust extension ``rkforge._rkforge``."""
from os import PathLike
from typing import Any, Dict, List, Optional, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__all__ = ["Scene", "Simulation", "run_scene", "SceneError", "StateError", "SimulationError", "__version__"]

__version__: str

class SceneError(ValueError):
    """A scene that cannot be read or is not valid: the key and its line, or the dotted key
    of an override, are named."""

class StateError(ValueError):
    """A saved state that cannot be restored (corrupt, or saved from another scene)."""

class SimulationError(RuntimeError):
    """A simulation that failed: divergence, energy balance or stability, with the step and
    time named. From :func:`rkforge.run` once the run has started, it carries ``summary`` and
    ``history`` (a scene the setup refuses, e.g. a fixed step above the critical one, has
    none)."""

    summary: Dict[str, Any]
    history: Any

_Value = Union[bool, int, float, str, List[Any], Tuple[Any, ...], Dict[str, Any]]

@final
class Scene:
    """A validated scene: its text, and overrides set by dotted key."""

    @staticmethod
    def from_file(path: Union[str, PathLike[str]]) -> Scene:
        """Read and validate a scene file (TOML). Raises SceneError naming key and line."""
    @staticmethod
    def from_toml(text: str, name: str = "<scene text>") -> Scene:
        """Parse and validate scene text; ``name`` stands for the file in error messages."""
    def set(self, key: str, value: _Value) -> None:
        """Override the key at a dotted path, e.g. ``set("tools.top.friction", 0.1)``; tools
        by name (or ``tools[1]``). Validated at once like a file: SceneError names the key,
        TypeError a value that cannot be a TOML value; on error the scene is unchanged."""
    def copy(self) -> Scene:
        """A copy with its own overrides."""
    @property
    def name(self) -> str:
        """The scene's name."""
    @property
    def kinematics(self) -> str:
        """``"plane_strain"``, ``"axisymmetric"`` or ``"3d"``."""
    @property
    def tools(self) -> List[str]:
        """The names of the tools, in scene order."""
    @property
    def overrides(self) -> List[Tuple[str, _Value]]:
        """The overrides set so far, as (dotted key, value) pairs in order."""
    @property
    def text(self) -> str:
        """The scene text as read (without the overrides)."""
    def to_toml(self) -> str:
        """The validated scene with its overrides, as TOML."""
    def sample_times(self) -> List[float]:
        """The times (s) at which ``rkforge run --no-frames`` records history rows after
        t = 0."""
    def outputs(self) -> List[Dict[str, Any]]:
        """The register of outputs as this scene has it: per column and per field ``name``,
        ``unit`` (``1`` for a pure number), ``kind``, ``description`` and whether
        ``history``, ``summary`` and ``fmu`` show it."""

@final
class Simulation:
    """A simulation of a scene, stepped from Python with the GIL released."""

    def __new__(cls, scene: Scene, integration: Optional[str] = None, threads: Optional[int] = None) -> Simulation:
        """Set up the discretisation; ``integration`` ("q4", "q2", "scni") overrides the
        scene's rule, ``threads`` gives the simulation its own pool of that many threads.
        MemoryError, naming the key, for a grid beyond what the process can have."""
    def step(self, toward: Optional[float] = None) -> float:
        """One time step; returns the new time (s). With ``toward`` (s), the step
        ``run_to(toward)`` would take next (shortened and evened out to land on it).
        SimulationError on divergence; ValueError when ``toward`` is not after now."""
    def run_to(self, t: float) -> float:
        """Step until the time reaches ``t`` (s), the last step shortened to land on it."""
    def set_tool_velocity(self, name: str, velocity: float) -> None:
        """Command the velocity (m/s, along its axis) of the tool ``name`` from the next step
        on. ValueError for an unknown or fixed tool or a non-finite velocity."""
    @property
    def time(self) -> float:
        """Time (s)."""
    @property
    def steps(self) -> int:
        """Steps taken."""
    def tool_forces(self) -> Dict[str, float]:
        """Force of the workpiece on each tool along the tool's axis (N), by tool name."""
    def tool_strokes(self) -> Dict[str, float]:
        """Stroke of each tool along its axis (m), by tool name."""
    def sample(self) -> Dict[str, float]:
        """Record a history row now, as ``rkforge run`` does at its samples; its
        ``<tool>.force_mean_N`` is the force averaged since the last ``sample()`` (the start
        for the first)."""
    def outputs(self) -> Dict[str, Union[float, npt.NDArray[np.float64]]]:
        """Every output of the register now, by name: each column (history.csv's and those
        only the summary and the FMU show, e.g. ``top.pressure_mean_Pa``) as a float, each
        field (``particles.*``, ``points.*``) as a numpy array; ``<tool>.force_mean_N``
        averaged since the last ``sample()``."""
    def tools(self) -> List[Dict[str, Any]]:
        """Every tool as in summary.json."""
    def laps(self) -> List[Dict[str, Any]]:
        """The laps so far, as in summary.json: ``formed_s``, ``formed_stroke_m`` (by tool),
        ``start_m``, ``end_m``, ``length_m`` (2D) or ``extent_m`` (3D), ``reference_m``,
        ``particles``."""
    def fields(self) -> Dict[str, npt.NDArray[Any]]:
        """Particle fields: ``positions``, ``displacement``, ``velocity`` (n, 2);
        ``plastic_strain``, ``von_mises``, ``lap`` (n,), and ``temperature`` with heat.
        In 3D: ``positions``, ``displacement``, ``velocity`` (n, 3), ``cells`` (m, 8) the
        hexahedra (VTK order, int64), and per cell the mean over its points
        ``plastic_strain``, ``von_mises`` and with heat ``temperature`` (m,)."""
    def save_state(self) -> bytes:
        """The whole changing state with its scene, as bytes."""
    def restore_state(self, state: bytes) -> None:
        """Restore a state of a simulation of the same scene (StateError otherwise)."""
    def summary(self) -> Dict[str, Any]:
        """The summary as summary.json has it."""

def run_scene(
    scene: Scene,
    integration: Optional[str] = None,
    threads: Optional[int] = None,
    checkpoint: Optional[str] = None,
    checkpoint_every_s: float = 600.0,
) -> Tuple[Dict[str, Any], List[str], npt.NDArray[np.float64], Optional[str]]:
    """The whole run as ``rkforge run --no-frames``: summary, history columns and rows,
    failure."""
