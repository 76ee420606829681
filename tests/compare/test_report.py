"""The comparison report on a real smoke run: the scorecard's contract, the pages a reader opens
(every link and image there, alt text, no raw dict or nan in a cell), and runs named alike."""
import json
import math
import shutil
from html.parser import HTMLParser
from pathlib import Path

import pytest

from compare.comparison import build
from compare.report import write_report
from continuum.paper.report import write_continuum_report
from granstokes.cli import main
from granstokes.demo import write_index

pytestmark = pytest.mark.slow
SCORECARD_KEYS = {"drive", "observable", "unit", "dem", "dem_err", "model", "predicted", "band", "sigma", "verdict"}


class Page(HTMLParser):
    """Links, images (with their alt text) and table cells of one HTML page."""

    def __init__(self):
        super().__init__()
        self.links, self.images, self.cells, self._cell = [], [], [], None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append(a)
        if "href" in a:
            self.links.append(a["href"])
        if tag in ("td", "th"):
            self._cell = []

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.cells.append("".join(self._cell).strip())
            self._cell = None


def check_page(path: Path) -> Page:
    page = Page()
    page.feed(path.read_text())
    for target in page.links + [img.get("src", "") for img in page.images]:
        assert (path.parent / target).exists(), f"{path}: {target} missing"
    assert all(img.get("alt") for img in page.images), f"{path}: an image without alt text"
    for cell in page.cells:
        assert not cell.startswith("{") and "nan" not in cell.lower().split(), f"{path}: raw cell {cell!r}"
    return page


@pytest.fixture(scope="module")
def report(smoke_run, smoke_calibration, tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    comparison = build([smoke_run], progress=False, calibration=smoke_calibration)
    m = write_report(comparison, out / "compare")
    return comparison, m, out


def test_scorecard_contract(report):
    _, m, _ = report
    assert m["scorecard"] and m["provenance"]["granstokes"] and m["provenance"]["git"] is not None
    for row in m["scorecard"]:
        assert SCORECARD_KEYS <= set(row)
        numbers = [row["dem"], row["dem_err"], row["predicted"], row["sigma"], *row["band"]]
        assert all(isinstance(v, float) and math.isfinite(v) for v in numbers), row
        lo, hi = row["band"]
        assert lo <= row["predicted"] <= hi and row["dem_err"] > 0
        assert row["verdict"] == ("not scored" if not row["scored"] else
                                  "consistent" if abs(row["sigma"]) <= 2 else "disagrees")
        assert row["scored"] == (not row["note"]) and row["blind"]
    observables = {(r["observable"], r["model"]) for r in m["scorecard"]}
    response = "u_w_inf" if next(iter(m["drives"].values()))["kind"] == "stress" else "mu_w_inf"
    assert {(response, "local"), ("delta_u", "local"), ("t90", "local"), (response, "paper")} <= observables
    assert {"slip", "slip_err", "tau_bulk", "elastic_start"} <= set(next(iter(m["drives"].values())))


def test_every_page_the_demo_writes_is_whole(report):
    comparison, _, out = report
    write_continuum_report(out / "continuum")
    index = write_index(comparison, out, ("smoke",), {"test": 0.0})
    front = check_page(index)
    assert {"compare/index.html", "continuum/index.html"} <= set(front.links)
    compare_page = check_page(out / "compare" / "index.html")
    text = (out / "compare" / "index.html").read_text()
    assert text.index("Scorecard") < text.index("Conclusions") < text.index("Figures")
    assert len(compare_page.images) >= 5
    check_page(out / "continuum" / "index.html")


def test_runs_named_alike_get_their_own_sections(smoke_run, smoke_calibration, tmp_path, capsys):
    for parent in ("x", "y"):
        shutil.copytree(smoke_run, tmp_path / parent / "r")
    assert main(["compare", str(tmp_path / "x" / "r"), str(tmp_path / "y" / "r"), "--out", str(tmp_path / "rep"),
                 "--json", "--calibration", str(smoke_calibration)]) == 0
    m = json.loads(capsys.readouterr().out)
    assert len(m["drives"]) == 2 and len({k for k in m["drives"]}) == 2
    figures = sorted(p.name for p in (tmp_path / "rep").glob("drive_*.png"))
    assert len(figures) == 2
    assert main(["compare", str(tmp_path / "x" / "r"), str(tmp_path / "x" / "r"), "--out", str(tmp_path / "r2"),
                 "--calibration", str(smoke_calibration)]) == 2
    assert "distinct run folders" in capsys.readouterr().err and not (tmp_path / "r2").exists()
