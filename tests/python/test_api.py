"""The package's public names: each documented, each compiled class's
members in the type stubs, and the stubs' members real."""

import ast
import inspect

import purkinje
import purkinje._purkinje as core
from conftest import SOURCE_DIR

STUB = SOURCE_DIR / "python/purkinje/_purkinje.pyi"


def stub_classes():
    tree = ast.parse(STUB.read_text())
    classes = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            classes[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
    functions = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
    return classes, functions


def test_every_public_name_has_a_docstring():
    for name in purkinje.__all__:
        if name == "__version__":
            continue
        obj = getattr(purkinje, name)
        assert inspect.getdoc(obj), f"purkinje.{name} has no docstring"
        if inspect.isclass(obj):
            for member, value in vars(obj).items():
                if not member.startswith("_") and (callable(value) or isinstance(value, property)):
                    assert inspect.getdoc(value), f"purkinje.{name}.{member} has no docstring"


def test_the_stubs_name_exactly_the_compiled_modules_public_members():
    classes, functions = stub_classes()
    public = {n for n in dir(core) if not n.startswith("_")}
    compiled_classes = {n for n in public if inspect.isclass(getattr(core, n))}
    assert set(classes) == compiled_classes
    assert functions == {n for n in public - compiled_classes if callable(getattr(core, n))}
    for name, members in classes.items():
        cls = getattr(core, name)
        if issubclass(cls, BaseException):
            continue
        real = {m for m in dir(cls) if not m.startswith("_")}
        assert members == real, f"{name}: stubs lack {real - members}, name {members - real} it lacks"


def test_every_public_name_is_exported_once():
    assert len(purkinje.__all__) == len(set(purkinje.__all__))
    for name in purkinje.__all__:
        assert hasattr(purkinje, name), name
