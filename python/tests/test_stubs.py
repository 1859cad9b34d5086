"""The type stubs (demcon/_demcon.pyi) name exactly what the compiled module offers."""

import ast
import inspect
from pathlib import Path

import demcon
from demcon import _demcon

STUBS = Path(demcon.__file__).with_name("_demcon.pyi")


def _stubbed():
    tree = ast.parse(STUBS.read_text())
    classes, functions = {}, set()
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            classes[node.name] = {
                n.name for n in node.body if isinstance(n, ast.FunctionDef) and not n.name.startswith("_")
            }
        elif isinstance(node, ast.FunctionDef):
            functions.add(node.name)
    return classes, functions


def test_stubs_match_the_module():
    classes, functions = _stubbed()
    public = {n for n in dir(_demcon) if not n.startswith("_")}
    runtime_classes = {n for n in public if inspect.isclass(getattr(_demcon, n))}
    assert runtime_classes == set(classes)
    assert public - runtime_classes == functions
    for name, members in classes.items():
        cls = getattr(_demcon, name)
        if issubclass(cls, BaseException):
            continue
        runtime = {n for n in dir(cls) if not n.startswith("_")}
        assert runtime == members, (name, runtime ^ members)


def test_the_progress_default_is_on(homogeneous, capsys):
    demcon.Scene.from_file(homogeneous).run()
    assert "demcon: packing" in capsys.readouterr().err
    demcon.Scene.from_file(homogeneous).run(progress=None)
    assert capsys.readouterr().err == ""
