"""The type stubs name what the module has: every public class, function and method, and
nothing it lacks (an editor completes from them)."""

import ast
import pathlib

import bi_am_rrt
from bi_am_rrt import _core

STUB = pathlib.Path(bi_am_rrt.__file__).with_name("_core.pyi")


def stub_names():
    tree = ast.parse(STUB.read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            top.add(node.name)
        if isinstance(node, ast.ClassDef):
            members[node.name] = {
                n.name if not isinstance(n, ast.AnnAssign) else n.target.id
                for n in node.body
                if isinstance(n, (ast.FunctionDef, ast.AnnAssign))
            }
        if isinstance(node, ast.AnnAssign):
            top.add(node.target.id)
    return top, members


def public(obj):
    return {n for n in dir(obj) if not n.startswith("_")}


def test_the_stub_is_shipped():
    assert STUB.is_file() and STUB.with_name("py.typed").is_file()


def test_top_level_names_match():
    top, _ = stub_names()
    assert public(_core) == {n for n in top if not n.startswith("_")} - {"Xy", "StrPath"}


def test_class_members_match():
    _, members = stub_names()
    for name, names in members.items():
        cls = getattr(_core, name)
        if issubclass(cls, Exception):
            continue
        have = public(cls)
        stubbed = {n for n in names if not n.startswith("_")}
        assert have == stubbed, name


def test_docstrings_reach_python():
    assert "numpy" in _core.Map.from_array.__doc__
    assert "InWallError" in _core.Planner.set_goal.__doc__
    assert _core.Planner.__doc__ and _core.run.__doc__ and _core.experiment.__doc__
