"""The type stubs (umbra/*.pyi) describe the module as it is: the same public
names, and each docstring word for word the runtime one."""

import ast
import importlib
import inspect
import re
import types
from pathlib import Path

import pytest

import umbra

PACKAGE = Path(umbra.__file__).parent


def stub_docs(path):
    """{qualified name: docstring or None} of every def and class in a stub file (setters excluded)."""
    tree = ast.parse(path.read_text())
    docs = {}

    def visit(body, prefix):
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                if any(isinstance(d, ast.Attribute) and d.attr == "setter" for d in getattr(node, "decorator_list", [])):
                    continue
                docs[prefix + node.name] = ast.get_docstring(node, clean=False)
                if isinstance(node, ast.ClassDef):
                    visit(node.body, prefix + node.name + ".")

    visit(tree.body, "")
    return docs


def without_signature(name, doc):
    """A function's docstring without the signature lines pybind11 puts in front of it ("name(a: T = 1) -> R"),
    and of an overloaded function the docstrings of its overloads, one a line."""
    name = name.split(".")[-1]
    if not doc or not doc.startswith(name + "("):
        return doc
    parts = doc.rstrip("\n").split("\n\n")
    if parts[0] == f"{name}(*args, **kwargs)\nOverloaded function.":
        overload = re.compile(rf"\d+\. {re.escape(name)}\(")
        return "\n".join(part for part in parts[1:] if not overload.match(part))
    assert len(parts) > 1, f"{name}: no text after the signature {parts[0]!r}"
    return "\n\n".join(parts[1:])


def runtime_docs(module):
    """{qualified name: docstring} of the public functions, classes, their members and constructors at run time."""
    docs = {}
    for name, value in vars(module).items():
        if name.startswith("_") or inspect.ismodule(value) or not callable(value):
            continue
        docs[name] = without_signature(name, value.__doc__)
        if inspect.isclass(value) and not issubclass(value, BaseException):
            for member, raw in vars(value).items():
                if member.startswith("_") and member != "__init__":
                    continue
                if isinstance(raw, types.WrapperDescriptorType):
                    continue  # a class without constructor: Python's slot, not umbra's
                # getattr, not vars(): a static method's own docstring, not staticmethod's.
                docs[f"{name}.{member}"] = without_signature(member, getattr(value, member).__doc__)
    return docs


@pytest.mark.parametrize(
    "stub, module",
    [("__init__.pyi", umbra._umbra), ("pred.pyi", umbra.pred), ("sim.pyi", umbra.sim)],
)
def test_stubs_match_the_module(stub, module):
    written = stub_docs(PACKAGE / stub)
    actual = runtime_docs(module)
    if module is umbra._umbra:
        actual["FormatError"] = umbra.FormatError.__doc__
    dunder = {name for name in written if name.split(".")[-1].startswith("__") and not name.endswith(".__init__")}
    missing = sorted(set(actual) - set(written))
    extra = sorted(set(written) - set(actual) - dunder)
    assert not missing, f"{stub} lacks {missing}"
    assert not extra, f"{stub} describes what the module does not have: {extra}"
    for name, doc in actual.items():
        assert written[name] == doc, f"{stub}: the docstring of {name} differs from the module's"


def test_every_public_name_is_exported():
    public = {name for name in vars(umbra._umbra) if not name.startswith("_")}
    assert public == set(umbra.__all__)
    # The submodules import as modules too.
    assert importlib.import_module("umbra.pred") is umbra.pred
    assert importlib.import_module("umbra.sim").demo_scene is umbra.sim.demo_scene


def test_every_constructor_is_documented():
    for module in (umbra._umbra, umbra.sim):
        for name, value in vars(module).items():
            own = vars(value).get("__init__") if inspect.isclass(value) else None
            if own is not None and not isinstance(own, types.WrapperDescriptorType):
                doc = without_signature("__init__", value.__init__.__doc__)
                assert doc and not doc.startswith("__init__("), f"{name}.__init__ has no docstring"
