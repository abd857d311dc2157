"""The package's layers (docs/architecture.md): every module imports only from its own layer
or the layers above it, and no two modules import each other, directly or around a circle."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import ddpy

ROOT = Path(ddpy.__file__).resolve().parent
#: docs/architecture.md's table: a subpackage's layer (cad and studies share one).
LAYERS = {"core": 1, "geometry": 2, "model": 3, "io": 4, "cad": 5, "studies": 5, "app": 6}


def _modules() -> dict[str, set[str]]:
    """Every module of the package and the ddpy modules it imports (at any depth: a
    function-level import counts, it runs as well)."""
    found: dict[str, set[str]] = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = path.relative_to(ROOT.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        deps: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0 \
                    and node.module.split(".")[0] == "ddpy":
                deps.add(node.module)
                deps.update(f"{node.module}.{a.name}" for a in node.names)
            elif isinstance(node, ast.Import):
                deps.update(a.name for a in node.names if a.name.split(".")[0] == "ddpy")
        found[name] = deps
    return {m: {d for d in deps if d in found and d != m} for m, deps in found.items()}


def _layer(module: str) -> tuple[int, str]:
    parts = module.split(".")
    if len(parts) < 2 or parts[1] not in LAYERS:
        return 0, ""  # the root: ddpy, ddpy._validate, ddpy.__main__
    return LAYERS[parts[1]], parts[1]


def test_every_subpackage_is_in_a_layer() -> None:
    packages = {p.parent.name for p in ROOT.glob("*/__init__.py")}
    assert packages == set(LAYERS), "docs/architecture.md's layers and the subpackages differ"


def test_modules_import_only_from_their_layer_or_above() -> None:
    upward = []
    for module, deps in _modules().items():
        level, package = _layer(module)
        for dep in deps:
            dep_level, dep_package = _layer(dep)
            if module == "ddpy.__main__":
                continue  # `python -m ddpy` is the application's entry point
            if dep_level > level or (dep_level == level and dep_package != package):
                upward.append(f"{module} -> {dep}")
    assert not upward, "imports against the layers: " + ", ".join(sorted(upward))


def test_no_import_circles() -> None:
    graph = _modules()
    state: dict[str, int] = {}
    circles: list[list[str]] = []

    def visit(module: str, path: list[str]) -> None:
        state[module] = 1
        path.append(module)
        for dep in sorted(graph[module]):
            if state.get(dep) == 1:
                circles.append(path[path.index(dep):] + [dep])
            elif dep not in state:
                visit(dep, path)
        path.pop()
        state[module] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [])
    assert not circles, "import circles: " + "; ".join(" -> ".join(c) for c in circles)


@pytest.mark.parametrize("module", ["ddpy.model.forming", "ddpy.io.decks", "ddpy.app.cli"])
def test_the_check_sees_imports(module: str) -> None:
    # The checks above pass vacuously if the scan finds no imports: it must see these.
    assert _modules()[module], f"no ddpy imports found in {module}"


def _private_reaches(sources: dict[str, str]) -> list[str]:
    """Where a module (name -> source) reaches into another's private names: an attribute
    ``x._name`` (x not ``self`` or ``cls``; dunders aside) whose name this module does not
    define (as a function, class, variable or an attribute of self or cls) but another
    does, and an import of a private name from a module of another subpackage (a
    subpackage's modules may share their helpers; ddpy._core and ddpy._validate are
    modules, shared by every layer)."""
    defined: dict[str, set[str]] = {}
    trees = {name: ast.parse(source) for name, source in sources.items()}
    for name, tree in trees.items():
        names: set[str] = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                names.add(node.name)
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store) \
                    and isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
                names.add(node.attr)
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                names.add(node.id)
        defined[name] = {n for n in names if n.startswith("_") and not n.startswith("__")}

    def private(name: str) -> bool:
        return name.startswith("_") and not name.startswith("__")

    found = []
    for module, tree in trees.items():
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and private(node.attr) and not (
                    isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")):
                owners = sorted(m for m, names in defined.items()
                                if m != module and node.attr in names)
                if node.attr not in defined[module] and owners:
                    found.append(f"{module}:{node.lineno} .{node.attr} ({owners[0]})")
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0 \
                    and node.module.startswith("ddpy."):
                other = node.module.split(".")[:2] != module.split(".")[:2]
                for alias in node.names:
                    if private(alias.name) and other \
                            and f"{node.module}.{alias.name}" not in sources:
                        found.append(f"{module}:{node.lineno} import {alias.name} from "
                                     f"{node.module}")
    return found


def _sources() -> dict[str, str]:
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = path.relative_to(ROOT.parent).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path.read_text()
    return out


def test_no_module_reaches_into_another_modules_private_names() -> None:
    found = _private_reaches(_sources())
    assert not found, "private names used from another module: " + ", ".join(found)


def test_the_private_name_check_sees_reaches() -> None:
    # The check above passes vacuously if it sees nothing: a problem's private state read
    # by a runner, and a private helper imported across subpackages, are found; the
    # module's own and self's are not.
    sources = {
        "ddpy.model.thing": "class Thing:\n    def __init__(self):\n        self._state = 1\n"
                            "def _helper():\n    return 2\n",
        "ddpy.app.use": "from ddpy.model.thing import _helper\n"
                        "def run(thing):\n    thing._state = 3\n    return thing._mine\n"
                        "class Mine:\n    def __init__(self):\n        self._mine = 4\n",
    }
    assert _private_reaches(sources) == ["ddpy.app.use:1 import _helper from ddpy.model.thing",
                                         "ddpy.app.use:3 ._state (ddpy.model.thing)"]
