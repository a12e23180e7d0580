"""umbra: probabilistic 3D occupancy maps with unknown, free and occupied space explicit.

The compiled module ``umbra._umbra`` does the work; this package re-exports it
and makes ``umbra.pred`` and ``umbra.sim`` importable as modules. Type stubs:
``__init__.pyi``, ``pred.pyi``, ``sim.pyi`` beside this file.
"""

import sys as _sys
from pathlib import Path as _Path


def _import_error(what, error):
    """An ImportError that says which interpreter failed to import what, and what to do."""
    folder = _Path(__file__).resolve().parent
    python = f"{_sys.executable} (Python {_sys.version_info[0]}.{_sys.version_info[1]})"
    if what == "numpy":
        return ImportError(
            f"umbra needs numpy, which {python} cannot import ({error}); on Debian: apt-get install "
            "python3-numpy, or a virtual environment made with --system-site-packages"
        )
    import sysconfig

    wanted = "_umbra" + sysconfig.get_config_var("EXT_SUFFIX")
    built = sorted(path.name for path in folder.glob("_umbra*.so"))
    if built and wanted not in built:
        return ImportError(
            f"umbra in {folder} was built for another Python: it holds {', '.join(built)}, {python} needs "
            f"{wanted}. Run it with the python3 it was built for (in a build folder: build/python/python3), "
            "or build it for this one (pip install ./python)"
        )
    return ImportError(f"umbra's compiled part {wanted} could not be loaded from {folder}: {error}")


try:
    import numpy as _numpy  # noqa: F401  (the module returns numpy arrays; fail early with a clear ImportError)
except ImportError as _error:
    raise _import_error("numpy", _error) from _error

try:
    from . import _umbra
except ImportError as _error:
    raise _import_error("_umbra", _error) from _error
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
    DistanceField,
    FormatError,
    Frustum,
    GainResult,
    InsertStats,
    MapStatistics,
    MergeStats,
    NavigationGrid,
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
    WindowMove,
    __version__,
    back_project,
    load,
    load_spill,
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
    "DistanceField",
    "FormatError",
    "Frustum",
    "GainResult",
    "InsertStats",
    "MapStatistics",
    "MergeStats",
    "NavigationGrid",
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
    "WindowMove",
    "back_project",
    "load",
    "load_spill",
    "pred",
    "read_scans",
    "sim",
]
