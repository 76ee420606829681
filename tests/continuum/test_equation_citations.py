"""The paper's equations are cited by the published numbers, never by the manuscript's LaTeX labels: in the
figure titles, report tables and law names the package writes, in the committed reports, docs and in the
source's strings and comments (a label only as the key continuum.paper.equations.eq looks up)."""
import ast
import io
import re
import tokenize
from pathlib import Path

import pytest
from granstokes.compare.law_figures import HOW_TO_READ
from granstokes.compare.laws import LAWS
from granstokes.continuum.paper.equations import EQUATIONS, eq
from granstokes.continuum.paper.figures import FIGURES, Sheet
from granstokes.continuum.paper.report import steady_table

ROOT = Path(__file__).resolve().parents[2]
LABEL = re.compile(r"\b(" + "|".join(sorted(EQUATIONS, key=len, reverse=True)) + r")\b")
CITED = re.compile(r"\beqs?\. \((\d+\.\d+)\)")
NUMBERS = {n for numbers, _ in EQUATIONS.values() for n in numbers}
SOURCES = ("bench", "compare", "continuum", "dem", "granstokes", "tests")
EQUATIONS_PY = ROOT / "continuum" / "paper" / "equations.py"


def figure_titles() -> dict[str, str]:
    return {draw.__name__: Sheet(draw.__name__, draw.__doc__, *layout).fig.get_suptitle()
            for draw, *layout in FIGURES}


def written_texts() -> dict[str, str]:
    """What the package writes, rendered without solving: the paper's figure titles, the continuum report's
    steady-state table, the laws' names and the law figures' captions."""
    return {**figure_titles(), "steady table": " ".join(steady_table().columns),
            "laws": " ".join(law.quantity for law in LAWS), **HOW_TO_READ}


@pytest.mark.parametrize("label", sorted(EQUATIONS))
def test_a_label_in_a_figure_title_is_found(label):
    title = Sheet("fig0_probe", f"Fig. 0: u~_w against eq. {label} and {eq(label)}", 1, 1).fig.get_suptitle()
    assert LABEL.findall(title) == [label]


def test_written_texts_cite_numbers_of_the_paper():
    texts = written_texts()
    assert {k: LABEL.findall(v) for k, v in texts.items() if LABEL.search(v)} == {}
    cited = {n for v in texts.values() for n in CITED.findall(v)}
    assert cited and cited <= NUMBERS
    assert eq("Uwall_asymp") in texts["fig4_steady_wall_speed"]


def test_the_numbering_is_by_section_and_complete():
    """Every numbered row of the manuscript has its number once: section 2 rows 1-16, section 3 rows 1-20."""
    numbers = [n for numbers, _ in EQUATIONS.values() for n in numbers]
    assert numbers == [f"2.{k}" for k in range(1, 17)] + [f"3.{k}" for k in range(1, 21)]
    assert eq("BCStokesEqn") == "eqs. (2.8)-(2.9)"
    assert eq("Uwall_asymp", named=True) == "eq. (3.12), the steady wall speed's asymptote"


def test_committed_reports_and_docs_show_no_label():
    files = [ROOT / "README.md", *(ROOT / "docs").glob("*.md"), *(ROOT / "results").glob("*/index.html"),
             *(ROOT / "results").glob("*/metrics.json"), *(ROOT / "results").glob("*/README.md")]
    found = {str(f.relative_to(ROOT)): sorted(set(LABEL.findall(f.read_text()))) for f in files}
    assert {k: v for k, v in found.items() if v} == {}


def _lookup_keys(tree: ast.AST, path: Path) -> set[int]:
    """The string nodes that are labels looked up, not shown: eq()'s first argument, EQUATIONS' keys."""
    keys = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "eq" and node.args:
            keys.add(id(node.args[0]))
        if path == EQUATIONS_PY and isinstance(node, ast.Dict):
            keys.update(id(k) for k in node.keys)
    return keys


@pytest.mark.slow
def test_the_source_cites_no_label():
    found = {}
    for path in (p for top in SOURCES for p in (ROOT / top).rglob("*.py")):
        text = path.read_text()
        tree = ast.parse(text)
        keys = _lookup_keys(tree, path)
        strings = [n.value for n in ast.walk(tree)
                   if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in keys]
        comments = [t.string for t in tokenize.generate_tokens(io.StringIO(text).readline)
                    if t.type == tokenize.COMMENT]
        hits = sorted({m for s in strings + comments for m in LABEL.findall(s)})
        if hits:
            found[str(path.relative_to(ROOT))] = hits
    assert found == {}
