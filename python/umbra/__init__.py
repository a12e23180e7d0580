"""umbra: probabilistic 3D occupancy maps with unknown, free and occupied space explicit.

The compiled module ``umbra._umbra`` does the work; this package re-exports it
and makes ``umbra.pred`` and ``umbra.sim`` importable as modules. Type stubs:
``__init__.pyi``, ``pred.pyi``, ``sim.pyi`` beside this file.
"""

import sys as _sys

import numpy as _numpy  # noqa: F401  (the module returns numpy arrays; fail early with a clear ImportError)

from . import _umbra
from ._umbra import (
    FREE,
    GAIN_DTYPE,
    NODE_DTYPE,
    OCCUPIED,
    UNKNOWN,
    Aabb,
    Capsule,
    CollisionResult,
    DepthCamera,
    FormatError,
    Frustum,
    GainResult,
    InsertStats,
    MapStatistics,
    Node,
    NodeCounts,
    OccupancyMap,
    OrientedBox,
    PinholeCamera,
    Predicate,
    RayHit,
    RayHits,
    ScanReader,
    SensorModel,
    Segment,
    Sphere,
    Thresholds,
    back_project,
    load,
    pred,
    read_scans,
    sim,
)

# `import umbra.pred` and `from umbra.sim import demo_scene` work like modules.
_sys.modules[__name__ + ".pred"] = pred
_sys.modules[__name__ + ".sim"] = sim

# The error shows as umbra.FormatError, where users find it.
FormatError.__module__ = __name__
FormatError.__doc__ = (
    "A file that is not what it claims to be; the message names the file and the line or byte offset."
)

__all__ = [
    "FREE",
    "GAIN_DTYPE",
    "NODE_DTYPE",
    "OCCUPIED",
    "UNKNOWN",
    "Aabb",
    "Capsule",
    "CollisionResult",
    "DepthCamera",
    "FormatError",
    "Frustum",
    "GainResult",
    "InsertStats",
    "MapStatistics",
    "Node",
    "NodeCounts",
    "OccupancyMap",
    "OrientedBox",
    "PinholeCamera",
    "Predicate",
    "RayHit",
    "RayHits",
    "ScanReader",
    "SensorModel",
    "Segment",
    "Sphere",
    "Thresholds",
    "back_project",
    "load",
    "pred",
    "read_scans",
    "sim",
]
