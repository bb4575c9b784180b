"""python/bsv/_bsv.pyi matches the extension: the same public names, and every function's (and
method's) parameters and defaults as pyo3 reports them (``__text_signature__``)."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path
from typing import Any

import bsv
from bsv import _bsv

STUB = Path(bsv.__file__).with_name("_bsv.pyi")
#: Names the stub declares for typing only (aliases), not present in the extension.
TYPING_ONLY = {"F64", "I64", "U8", "MeshTuple", "CloudTuple", "ArrayLike"}


def _stub() -> ast.Module:
    return ast.parse(STUB.read_text())


def _stub_names(tree: ast.Module) -> dict[str, ast.AST]:
    out: dict[str, ast.AST] = {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            out[node.name] = node
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            out[node.target.id] = node
        elif isinstance(node, ast.Assign):
            for t in node.targets:
                if isinstance(t, ast.Name):
                    out[t.id] = node
    return out


def _params(fn: ast.FunctionDef) -> list[tuple[str, Any]]:
    """(name, default) of a stub function, ``...`` for no default; ``**kwargs`` as ``**kwargs``."""
    a = fn.args
    positional = a.posonlyargs + a.args
    defaults: list[Any] = [...] * (len(positional) - len(a.defaults)) + [ast.literal_eval(d) for d in a.defaults]
    out = [(p.arg, d) for p, d in zip(positional, defaults, strict=True)]
    if a.kwarg is not None:
        out.append((f"**{a.kwarg.arg}", ...))
    return out


def _runtime_params(obj: Any) -> list[tuple[str, Any]]:
    out: list[tuple[str, Any]] = []
    for p in inspect.signature(obj).parameters.values():
        if p.kind is inspect.Parameter.VAR_KEYWORD:
            out.append((f"**{p.name}", ...))
        else:
            out.append((p.name, ... if p.default is inspect.Parameter.empty else p.default))
    return out


def test_stub_and_extension_have_the_same_names() -> None:
    stub = set(_stub_names(_stub())) - TYPING_ONLY
    runtime = {n for n in dir(_bsv) if not n.startswith("_")} | {"__version__"}
    assert stub == runtime, f"only in the stub: {stub - runtime}; only in the extension: {runtime - stub}"


def test_function_signatures_match_text_signature() -> None:
    for name, node in _stub_names(_stub()).items():
        if isinstance(node, ast.FunctionDef):
            fn = getattr(_bsv, name)
            assert fn.__text_signature__, name
            assert _params(node) == _runtime_params(fn), name


def test_class_members_match() -> None:
    for name, node in _stub_names(_stub()).items():
        if not isinstance(node, ast.ClassDef):
            continue
        cls = getattr(_bsv, name)
        assert isinstance(cls, type), name
        declared = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        public = {n for n in vars(cls) if not n.startswith("_")}
        assert public <= declared, f"{name}: not in the stub: {public - declared}"
        for member in sorted(declared):
            if member.startswith("__"):  # slots (__getattr__, __getitem__, __init__) are checked by use
                continue
            assert hasattr(cls, member), f"{name}.{member} is in the stub but not in the extension"
            stub_fn = next(n for n in node.body if isinstance(n, ast.FunctionDef) and n.name == member)
            if not any(isinstance(d, ast.Name) and d.id == "property" for d in stub_fn.decorator_list):
                assert _params(stub_fn) == _runtime_params(getattr(cls, member)), f"{name}.{member}"
        init = next((n for n in node.body if isinstance(n, ast.FunctionDef) and n.name == "__init__"), None)
        if init is not None:
            assert _params(init)[1:] == _runtime_params(cls), f"{name}.__init__"
