"""Offline analysis of MCAP recordings (``rkforge run --mcap``, ``rkforge-ros --record``)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List

import numpy as np
import pandas as pd

#: history.csv's energy columns by the fields of rkforge_msgs/msg/Energy.
_ENERGY = {"kinetic": "kinetic_J", "elastic": "elastic_J", "plastic": "plastic_J",
           "internal": "internal_J", "contact_work": "contact_J", "tool_work": "tool_work_J",
           "initial": "initial_J"}

#: numpy types of the PointCloud2 field datatypes (sensor_msgs/PointField).
_POINT_TYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


@dataclass
class Recording:
    """What a recording holds.

    ``history``: one row per sample, ``time_s`` and per tool the history's columns
    ``<tool>.stroke_m``, ``<tool>.velocity_m_per_s``, ``<tool>.force_N`` (along its axis),
    ``<tool>.force_x_N``, ``<tool>.force_y_N``, ``<tool>.force_z_N`` (a 3D scene's only),
    ``<tool>.contact_fraction``, then per fill point
    ``<tool>.<point>.filled`` (0 or 1) where the recording has the die-fill topic,
    ``workpiece.laps`` (the laps formed so far) where it has the laps topic, then the energy
    account as history.csv names it
    (``energy.kinetic_J``, ``energy.elastic_J``, ``energy.plastic_J``, ``energy.internal_J``,
    ``energy.contact_J``, ``energy.tool_work_J``; J) where the recording has the energy
    topic, and ``energy.initial_J``. ``clouds``: per sample, the particles as a
    dict of numpy arrays (``x``, ``y``, ``z``, ``plastic_strain``, ``von_mises``; float32 as
    recorded), at the times ``cloud_times_s``.

    ``outputs``: where the recording has the ``outputs`` topic, one row per sample with
    every output of the register under its own name (history.csv's columns from ``time_s``,
    the same bits, and those only the summary and the FMU show, e.g.
    ``<tool>.pressure_mean_Pa``, ``<tool>.peak_force_N``); ``units``: each output's unit
    (``1`` for a pure number).
    """

    history: pd.DataFrame
    clouds: List[Dict[str, np.ndarray]] = field(default_factory=list)
    cloud_times_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    outputs: pd.DataFrame = field(default_factory=pd.DataFrame)
    units: Dict[str, str] = field(default_factory=dict)


def _cloud(msg) -> Dict[str, np.ndarray]:
    dtype = np.dtype({
        "names": [f.name for f in msg.fields],
        "formats": [("<" if not msg.is_bigendian else ">") + _POINT_TYPES[f.datatype] for f in msg.fields],
        "offsets": [f.offset for f in msg.fields],
        "itemsize": msg.point_step,
    })
    points = np.frombuffer(bytes(msg.data), dtype=dtype, count=msg.width * msg.height)
    return {name: points[name].copy() for name in dtype.names or ()}


def _kinematics(path) -> str:
    """The recorded scene's ``model.kinematics`` from the file's ``rkforge`` metadata
    record, read from the file's start (the record comes before the messages, so a file
    cut short, a killed recording, is never read to its cut end)."""
    from mcap.reader import NonSeekingReader

    with open(path, "rb") as f:
        for record in NonSeekingReader(f).iter_metadata():
            if record.name == "rkforge":
                return dict(record.metadata).get("kinematics", "")
    return ""


def read_mcap(path, namespace: str = "/rkforge") -> Recording:
    """Read a recording of the rkforge topics under ``namespace``: the tools' joint states
    and wrenches and the energy account as history columns, the register's outputs by name,
    the workpiece point clouds as numpy arrays.

    Compressed chunks (lz4, zstd) are read by the ``mcap`` reader; times are the messages'
    log times (simulation time, ns) in seconds.
    """
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    ns = namespace.rstrip("/")
    solid = _kinematics(path) == "3d"
    rows: Dict[int, Dict[str, float]] = {}
    outputs: Dict[int, Dict[str, float]] = {}
    units: Dict[str, str] = {}
    clouds, cloud_times = [], []
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, message, msg in reader.iter_decoded_messages(log_time_order=True):
            topic = channel.topic
            if topic == f"{ns}/tools":
                row = rows.setdefault(message.log_time, {})
                for k, name in enumerate(msg.name):
                    row[f"{name}.stroke_m"] = msg.position[k]
                    row[f"{name}.velocity_m_per_s"] = msg.velocity[k]
                    row[f"{name}.force_N"] = msg.effort[k]
            elif topic.startswith(f"{ns}/") and topic.endswith("/wrench"):
                name = topic[len(ns) + 1:-len("/wrench")]
                row = rows.setdefault(message.log_time, {})
                row[f"{name}.force_x_N"] = msg.wrench.force.x
                row[f"{name}.force_y_N"] = msg.wrench.force.y
                if solid:
                    row[f"{name}.force_z_N"] = msg.wrench.force.z
            elif topic == f"{ns}/die_fill":
                row = rows.setdefault(message.log_time, {})
                for name, fraction in zip(msg.tools, msg.contact_fraction):
                    row[f"{name}.contact_fraction"] = fraction
                for name, filled in zip(msg.points, msg.filled_time):
                    row[f"{name}.filled"] = 0.0 if math.isnan(filled) else 1.0
            elif topic == f"{ns}/laps":
                rows.setdefault(message.log_time, {})["workpiece.laps"] = float(len(msg.formed_time))
            elif topic == f"{ns}/energy":
                row = rows.setdefault(message.log_time, {})
                for name, column in _ENERGY.items():
                    row[f"energy.{column}"] = getattr(msg, name)
            elif topic == f"{ns}/outputs":
                outputs[message.log_time] = dict(zip(msg.names, msg.values))
                units.update(zip(msg.names, msg.units))
            elif topic == f"{ns}/workpiece":
                clouds.append(_cloud(msg))
                cloud_times.append(message.log_time * 1e-9)
    times = sorted(rows)
    history = pd.DataFrame([{"time_s": t * 1e-9, **rows[t]} for t in times])
    if len(history.columns) > 1:
        tools = []
        filled = [c for c in history.columns if c.endswith(".filled")]
        for c in history.columns[1:]:
            name = c.rsplit(".", 1)[0]
            if name not in tools and name not in ("energy", "workpiece") and c not in filled:
                tools.append(name)
        suffixes = ["stroke_m", "velocity_m_per_s", "force_N", "force_x_N", "force_y_N", "force_z_N",
                    "contact_fraction"]
        order = ["time_s"] + [f"{t}.{s}" for t in tools for s in suffixes if f"{t}.{s}" in history.columns]
        order += filled
        order += [c for c in ["workpiece.laps"] if c in history.columns]
        order += [f"energy.{c}" for c in _ENERGY.values() if f"energy.{c}" in history.columns]
        history = history[order]
    register = pd.DataFrame([outputs[t] for t in sorted(outputs)])
    return Recording(history=history, clouds=clouds, cloud_times_s=np.array(cloud_times),
                     outputs=register, units=units)
