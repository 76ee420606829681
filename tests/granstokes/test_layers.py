"""The house's layers, read from the source's imports (function-level ones included): no import circle, the
command layer on top (nothing imports it), granstokes.lib at the bottom (it imports nothing of the project),
and the packages in order: continuum below dem below compare."""
import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: folder -> installed package (pyproject.toml's package-dir)
PACKAGES = {"granstokes": "granstokes", "lib": "granstokes.lib", "continuum": "granstokes.continuum",
            "dem": "granstokes.dem", "compare": "granstokes.compare"}
COMMANDS = {"granstokes.cli", "granstokes.demo"}
#: the ground floor: granstokes.lib and the root package's __init__ (its version, nothing else)
GROUND = ("granstokes.lib",)


def _ground(module: str) -> bool:
    return module == "granstokes" or module.startswith(GROUND)
#: each package and what it may import of the project besides itself and granstokes.lib
ALLOWED = {"granstokes.continuum": set(), "granstokes.dem": {"granstokes.continuum"},
           "granstokes.compare": {"granstokes.continuum", "granstokes.dem"}}


def _modules() -> dict[str, Path]:
    out = {}
    for folder, package in PACKAGES.items():
        for path in (ROOT / folder).rglob("*.py"):
            parts = path.relative_to(ROOT / folder).with_suffix("").parts
            name = ".".join((package, *parts))
            out[name.removesuffix(".__init__")] = path
    return out


def _imports(name: str, path: Path, known: set[str]) -> set[str]:
    """The project's modules that ``name`` imports (a package import counts as its __init__)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        else:
            continue
        found |= {t for t in targets if t in known and t != name}
    return found


@pytest.fixture(scope="module")
def graph():
    modules = _modules()
    return {name: _imports(name, path, set(modules)) for name, path in modules.items()}


def test_the_walk_sees_the_house(graph):
    assert len(graph) > 60 and "granstokes.continuum.solver" in graph["granstokes.continuum.cli"]
    assert not graph["granstokes"]
    assert "granstokes.lib.validate" in graph["granstokes.lib.staging"]


def test_no_import_circle(graph):
    state, path = {}, []

    def visit(node):
        state[node] = "open"
        path.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == "open":
                pytest.fail("import circle: " + " -> ".join(path[path.index(nxt):] + [nxt]))
            if nxt not in state:
                visit(nxt)
        path.pop()
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node)


def _subcommand(module: str) -> bool:
    """A package's command-line module (its subcommand), part of the command layer."""
    return module.endswith((".cli", "_cli"))


def test_layers_point_down(graph):
    for name, imported in graph.items():
        if name not in COMMANDS:
            assert not imported & COMMANDS, f"{name} imports the command layer"
        if name not in COMMANDS and not _subcommand(name):
            assert not [m for m in imported if _subcommand(m)], f"{name} imports a subcommand's module"
        if name.startswith("granstokes.lib"):
            assert all(_ground(m) for m in imported), f"{name} imports {imported}"
        package = next((p for p in ALLOWED if name == p or name.startswith(p + ".")), None)
        if package is not None:
            for m in imported:
                other = next((p for p in ALLOWED if m == p or m.startswith(p + ".")), None)
                assert other in (None, package) or other in ALLOWED[package], f"{name} imports {m}"
                assert other is not None or _ground(m), f"{name} imports {m}"
