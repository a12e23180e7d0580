"""What Python users look at: inspect.signature and help() name every argument as the type stubs
(umbra/*.pyi, written by hand) do, constructors have docstrings, umbra.__version__ is the project's
version, and result objects print their values."""

import ast
import inspect
import pydoc
import re

import numpy as np
import pytest

import umbra
from conftest import SOURCE_DIR

PACKAGE = SOURCE_DIR / "python" / "umbra"
MODULES = {"__init__.pyi": umbra._umbra, "pred.pyi": umbra.pred, "sim.pyi": umbra.sim}


def decorator_names(node):
    return {d.id if isinstance(d, ast.Name) else getattr(d, "attr", "") for d in node.decorator_list}


def stub_functions(path):
    """(qualified name, ast.FunctionDef) of every function and method of a stub, overloads and
    properties excluded (they have no single signature)."""
    found = []

    def visit(body, prefix):
        for node in body:
            if isinstance(node, ast.ClassDef):
                visit(node.body, prefix + node.name + ".")
            elif isinstance(node, ast.FunctionDef):
                decorators = decorator_names(node)
                if decorators & {"overload", "property", "setter"}:
                    continue
                if node.name.startswith("__") and node.name != "__init__":
                    continue  # operators: pybind11's are overloaded (self, other) and the like
                found.append((prefix + node.name, node))

    visit(ast.parse(path.read_text()).body, "")
    return found


def stub_parameters(function):
    """[(name, kind, default)] of a stub function as inspect would describe it."""
    args = function.args
    result = []
    positional = args.posonlyargs + args.args
    defaults = [None] * (len(positional) - len(args.defaults)) + args.defaults
    for i, (arg, default) in enumerate(zip(positional, defaults)):
        kind = "POSITIONAL_ONLY" if i < len(args.posonlyargs) else "POSITIONAL_OR_KEYWORD"
        result.append((arg.arg, kind, ast.literal_eval(default) if default else inspect.Parameter.empty))
    if args.vararg:
        result.append((args.vararg.arg, "VAR_POSITIONAL", inspect.Parameter.empty))
    for arg, default in zip(args.kwonlyargs, args.kw_defaults):
        result.append((arg.arg, "KEYWORD_ONLY", ast.literal_eval(default) if default else inspect.Parameter.empty))
    if args.kwarg:
        result.append((args.kwarg.arg, "VAR_KEYWORD", inspect.Parameter.empty))
    return result


def runtime_object(module, qualified_name):
    value = module
    for part in qualified_name.split("."):
        value = inspect.getattr_static(value, part) if isinstance(value, type) else getattr(value, part)
    return value.__func__ if isinstance(value, staticmethod) else value


def runtime_parameters(signature, stub_parameters):
    """[(name, kind, default)] of a runtime signature; a default the stub leaves open (`= ...`) matches any."""
    open_defaults = {name for name, _, default in stub_parameters if default is Ellipsis}
    return [
        (p.name, p.kind.name, ... if p.name in open_defaults and p.default is not p.empty else p.default)
        for p in signature.parameters.values()
    ]


def all_stub_functions():
    return [
        pytest.param(stub, name, node, id=f"{stub}:{name}")
        for stub in MODULES
        for name, node in stub_functions(PACKAGE / stub)
    ]


@pytest.mark.parametrize("stub, name, node", all_stub_functions())
def test_inspect_signature_matches_the_stub(stub, name, node):
    function = runtime_object(MODULES[stub], name)
    signature = inspect.signature(function)  # ValueError: no __text_signature__ (text_signatures.cpp)
    expected = stub_parameters(node)
    assert runtime_parameters(signature, expected) == expected, f"{name}: runtime {signature}, stub says {expected}"


def test_classes_have_the_signature_of_their_constructor():
    assert str(inspect.signature(umbra.OccupancyMap)) == (
        "(resolution, depth_levels=16, color=False, sensor_model=None, thresholds=None)"
    )
    assert list(inspect.signature(umbra.sim.LidarModel).parameters)[:2] == ["rings", "fov_down_deg"]
    # A bound method drops self, as for Python functions.
    m = umbra.OccupancyMap(0.1)
    assert list(inspect.signature(m.insert).parameters)[:3] == ["points", "origin", "colors"]


def test_help_shows_argument_names_types_and_docstrings():
    text = pydoc.render_doc(umbra.OccupancyMap, renderer=pydoc.plaintext)
    assert "insert(self, points, origin, colors=None, *, integrator='discrete'" in text
    # pybind11's typed signature follows, then the docstring.
    assert re.search(r"insert\(self: umbra\._umbra\.OccupancyMap, points: \w+, origin: \w+, colors: \w+ = None, \*, integrator: str", text)
    assert "Integrates one scan" in text
    assert "An empty map, everything unknown" in text  # __init__'s docstring


def test_version_is_the_projects():
    cmake = (SOURCE_DIR / "CMakeLists.txt").read_text()
    version = re.search(r"project\(\s*umbra\s+VERSION\s+([0-9.]+)", cmake).group(1)
    assert umbra.__version__ == version
    assert umbra._umbra.__version__ == version


def small_map():
    m = umbra.OccupancyMap(0.1)
    stats = m.insert(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), [0.0, 0.0, 0.0])
    return m, stats


def test_result_objects_print_their_values(tmp_path):
    m, stats = small_map()
    statistics = m.statistics()
    hits = m.cast_rays([0.0, 0.0, 0.0], np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]), max_range=5.0)
    objects = {
        statistics: ["resolution", "depth_levels", "nodes", "memory_bytes", "occupied_voxels", "free_voxels",
                     "occupied_volume_m3", "free_volume_m3", "known_min", "known_max"],
        stats: ["points", "rays", "hits", "truncated", "non_finite", "out_of_bounds", "outside_box"],
        m.node_counts(): ["inner", "inner_leaf", "leaf"],
        umbra.DepthCamera(): ["fx", "fy", "cx", "cy", "depth_scale"],
        umbra.sim.LidarModel(rings=4): ["rings", "azimuth_steps", "max_range"],
        m.cast_ray([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]): ["hit", "distance"],
    }
    for value, attributes in objects.items():
        text = repr(value)
        assert text.startswith(type(value).__name__ + "("), text
        for attribute in attributes:
            assert f"{attribute}={getattr(value, attribute)!r}" in text, f"{attribute} not in {text}"
    assert repr(hits) == f"RayHits(rays=2, hits={int(hits.hit.sum())})"
    (tmp_path / "scan.xyz").write_text("1 2 3\n")
    reader = umbra.read_scans(tmp_path / "scan.xyz")
    assert repr(reader).startswith("ScanReader(name="), repr(reader)
