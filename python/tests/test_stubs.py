"""The hand-written stubs (tessera/_tessera.pyi) declare exactly what the module has: every
public function, class and class member, so an IDE shows every signature and none that is gone."""
import ast
import inspect
import pathlib

import tessera
from tessera import _tessera

STUB = pathlib.Path(_tessera.__file__).with_name("_tessera.pyi")


def stub_declarations():
    tree = ast.parse(STUB.read_text())
    top, classes, helpers = set(), {}, set()
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            bases = {ast.unparse(b) for b in node.bases}
            if "TypedDict" in bases:
                helpers.add(node.name)
                continue
            top.add(node.name)
            classes[node.name] = {n.name for n in node.body
                                  if isinstance(n, (ast.FunctionDef, ast.AnnAssign))
                                  and not getattr(n, "name", "").startswith("__")} | {
                n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
        elif isinstance(node, ast.FunctionDef):
            top.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            top.add(node.target.id)
        elif isinstance(node, ast.Assign):
            name = node.targets[0].id
            # Type aliases (X = Union[...]) are helpers; `color = colour` is the module's.
            (top if name == "color" else helpers).add(name)
    return top, classes


def test_every_public_name_is_declared_and_nothing_else():
    top, classes = stub_declarations()
    public = {name for name in dir(_tessera) if not name.startswith("_")} | {"__version__"}
    assert top == public
    assert set(tessera.__all__) == public


def test_every_class_member_is_declared_and_nothing_else():
    _, classes = stub_declarations()
    for name, members in classes.items():
        cls = getattr(_tessera, name)
        if not inspect.isclass(cls) or issubclass(cls, BaseException):
            continue
        actual = {m for m in vars(cls) if not m.startswith("_")}
        assert members == actual, name


def test_docstrings_are_there():
    for name in ("colour", "scene", "families", "strategies", "validate", "constraint_graph"):
        assert getattr(tessera, name).__doc__, name
    for cls in (tessera.Model, tessera.Solver, tessera.Colouring, tessera.ConstraintGraph):
        assert cls.__doc__, cls
    assert "Releases the GIL" in tessera.Solver.step.__doc__
