"""The type stub and docstrings cover what the native module exports, so
editors complete it and type checkers see every class, method and property."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import tactile
from tactile import _tactile

STUB = Path(tactile.__file__).with_name("_tactile.pyi")


def _stub_names() -> dict[str, set[str]]:
    tree = ast.parse(STUB.read_text())
    names: dict[str, set[str]] = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names[node.name] = {
                n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.AnnAssign))
            }
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = set()
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names[node.target.id] = set()
    return names


def test_stub_lists_every_export_and_member():
    stub = _stub_names()
    public = [n for n in dir(_tactile) if not n.startswith("_") or n == "__version__"]
    missing = [n for n in public if n not in stub]
    assert not missing, f"not in _tactile.pyi: {missing}"
    for name in public:
        obj = getattr(_tactile, name)
        if inspect.isclass(obj):
            members = {m for m in vars(obj) if not m.startswith("_")}
            assert members <= stub[name], f"{name}: not in the stub: {members - stub[name]}"


def test_everything_public_has_a_docstring():
    for mod in (tactile, tactile.synth, tactile.train, tactile.eval, tactile.calibrate, tactile.study):
        assert mod.__doc__
        for name in getattr(mod, "__all__", []):
            obj = getattr(mod, name)
            if callable(obj):
                assert obj.__doc__, f"{mod.__name__}.{name} has no docstring"
    for cls in (
        tactile.Pipeline,
        tactile.FrameResult,
        tactile.TactipEncoder,
        tactile.PoseEstimator,
        tactile.Reconstructor,
        tactile.Dataset,
    ):
        for m, v in vars(cls).items():
            if not m.startswith("_"):
                assert getattr(v, "__doc__", None), f"{cls.__name__}.{m} has no docstring"
