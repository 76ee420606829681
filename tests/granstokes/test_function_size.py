"""The house's functions stay readable, read from the source (ast): none in any package folder is longer than
MAX_LINES lines (a nested function counts within its parent, as it is read), and none in continuum/ takes more than
MAX_POSITIONAL positional arguments (the time-stepping loops pass named tuples, continuum.stepper and
continuum.bdf)."""
import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: the package folders (pyproject.toml's package-dir)
FOLDERS = ("continuum", "dem", "compare", "granstokes")
MAX_LINES = 120
MAX_POSITIONAL = 8


def _functions(folder: str, root: Path = ROOT):
    """(where, lines, positional arguments) of every function and method under ``folder``."""
    for path in sorted((root / folder).rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                where = f"{path.relative_to(root)}:{node.lineno} {node.name}"
                yield where, node.end_lineno - node.lineno + 1, len(node.args.posonlyargs) + len(node.args.args)


@pytest.mark.parametrize("folder", FOLDERS)
def test_no_function_is_longer_than_max_lines(folder):
    functions = list(_functions(folder))
    assert functions, folder
    long = [f"{where}: {lines} lines" for where, lines, _ in functions if lines > MAX_LINES]
    assert not long, long


def test_no_continuum_function_takes_more_than_max_positional_arguments():
    many = [f"{where}: {n}" for where, _, n in _functions("continuum") if n > MAX_POSITIONAL]
    assert not many, many


def test_the_walk_measures_what_it_should(tmp_path):
    """A function of MAX_LINES + 1 lines and one of MAX_POSITIONAL + 1 positional arguments (keyword-only ones not
    counted) are measured as such: the rules are not vacuous."""
    body = "\n".join(f"    x{k} = {k}" for k in range(MAX_LINES))
    names = ", ".join(f"a{k}" for k in range(MAX_POSITIONAL + 1))
    (tmp_path / "probe").mkdir()
    (tmp_path / "probe" / "long.py").write_text(f"def long():\n{body}\n\n\ndef wide({names}, *, b=1):\n    pass\n")
    assert [(lines, n) for _, lines, n in _functions("probe", tmp_path)] == [(MAX_LINES + 1, 0),
                                                                            (2, MAX_POSITIONAL + 1)]
