"""The comparison report on a real smoke run: the scorecard's contract, the pages a reader opens
(every link and image there, alt text, no raw dict or nan in a cell), and runs named alike."""
import html
import json
import math
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from granstokes.compare.report import display_label, nearest_frame, suptitle
from granstokes.compare.stokes_experiment import StokesDrives
from granstokes.compare.words import fmt, fmt_band
from granstokes.continuum.paper.report import write_continuum_report
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text
from scipy import stats

from granstokes.cli import main
from granstokes.demo import STUDY_DIR, write_index

pytestmark = pytest.mark.slow
SCORECARD_KEYS = {"drive", "observable", "unit", "dem", "dem_err", "model", "predicted", "band", "sigma", "verdict"}
#: a decimal number as a page prints it (not part of a version string such as 2025.7.22 or a word)
DECIMAL = re.compile(r"(?<![\w.])[-+]?(\d*\.\d+)(?:e[-+]?\d+)?(?![\w.]*\d)", re.IGNORECASE)
#: table columns and provenance items that are counts
COUNTS = {"seeds", "frames", "dropped frames", "cpus", "points"}
#: a count written as a float in prose ("2.0 seeds", "seeds 2.0")
COUNT_AS_FLOAT = re.compile(r"\b\d+\.0\s+(seeds?|frames?|points?|replicates|drives?|rows?)\b"
                            r"|\b(seeds?|frames?|points?|cpus)\s*[:=]?\s*\d+\.\d+", re.IGNORECASE)


def significant_digits(number: str) -> int:
    """Significant digits of a printed decimal (leading zeros are not)."""
    return len(number.replace(".", "").lstrip("0"))


class Page(HTMLParser):
    """Links, images (with their alt text), table cells (and each table's header and rows) and the text of
    paragraphs and list items."""

    def __init__(self):
        super().__init__()
        self.links, self.images, self.cells, self.tables, self.texts = [], [], [], [], []
        self.ids = set()
        self._row = self._cell = self._text = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a:
            self.ids.add(a["id"])
        if tag == "img":
            self.images.append(a)
        if "href" in a:
            self.links.append(a["href"])
        if tag == "table":
            self.tables.append({"header": [], "rows": []})
        if tag == "tr":
            self._row = []
        if tag in ("td", "th"):
            self._cell = []
        if tag in ("p", "li"):
            self._text = []

    def handle_data(self, data):
        for part in (self._cell, self._text):
            if part is not None:
                part.append(data)

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            cell = "".join(self._cell).strip()
            self.cells.append(cell)
            if self._row is not None:
                self._row.append((tag, cell))
            self._cell = None
        if tag == "tr" and self._row is not None and self.tables:
            cells = [c for _, c in self._row]
            if all(t == "th" for t, _ in self._row):
                self.tables[-1]["header"] = cells
            else:
                self.tables[-1]["rows"].append(cells)
            self._row = None
        if tag in ("p", "li") and self._text is not None:
            self.texts.append(" ".join("".join(self._text).split()))
            self._text = None


def check_numbers(path: Path, page: Page):
    """No number printed to more than 6 significant digits in a cell or paragraph; counts as integers."""
    for text in page.cells + page.texts:
        for number in DECIMAL.findall(text):
            assert significant_digits(number) <= 6, f"{path}: {number} printed to too many digits in {text!r}"
        assert not COUNT_AS_FLOAT.search(text), f"{path}: a count printed as a float in {text!r}"
    for table in page.tables:
        for row in table["rows"]:
            counts = {h: v for h, v in zip(table["header"], row, strict=False) if h in COUNTS}
            if table["header"] == ["item", "value"] and row[0] in COUNTS:
                counts[row[0]] = row[1]
            for name, value in counts.items():
                assert re.fullmatch(r"\d+", value), f"{path}: the count {name} printed as {value!r}"


def check_page(path: Path) -> Page:
    page = Page()
    page.feed(path.read_text())
    for target in page.links + [img.get("src", "") for img in page.images]:
        if target.startswith("#"):  # a place in the page itself
            assert target[1:] in page.ids, f"{path}: no element with id {target[1:]!r}"
            continue
        assert (path.parent / target).exists(), f"{path}: {target} missing"
    assert all(img.get("alt") for img in page.images), f"{path}: an image without alt text"
    for cell in page.cells:
        assert not cell.startswith("{") and "nan" not in cell.lower().split(), f"{path}: raw cell {cell!r}"
    check_numbers(path, page)
    return page


@pytest.fixture(scope="module")
def report(smoke_run, smoke_calibration, tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    experiment = StokesDrives(smoke_calibration, progress=False)
    comparison = experiment.run(experiment.analyse([smoke_run]))
    m = StokesDrives.write(comparison, out / "compare")
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
        dof = row["dof"] if row["dof"] is not None else np.inf  # JSON writes an infinite dof as null
        threshold = stats.t.ppf(0.975, dof) if np.isfinite(dof) else stats.norm.ppf(0.975)
        assert row["verdict"] == ("not scored" if not row["scored"] else
                                  "consistent" if abs(row["sigma"]) <= threshold else "disagrees")
        assert row["scored"] == (not row["note"]) and row["blind"]
    observables = {(r["observable"], r["model"]) for r in m["scorecard"]}
    response = "u_w_inf" if next(iter(m["drives"].values()))["kind"] == "stress" else "mu_w_inf"
    assert {(response, "local"), ("delta_u", "local"), ("t90", "local"), (response, "paper")} <= observables
    assert {"slip", "slip_err", "tau_bulk", "elastic_start"} <= set(next(iter(m["drives"].values())))
    from granstokes.compare.laws import LAWS
    from granstokes.compare.rows import LAW_KEYS

    assert {(law.name, law.quantity) for law in LAWS} == {(r["law"], r["quantity"]) for r in m["laws"]}
    for r in m["laws"]:
        assert set(LAW_KEYS) <= set(r)
        assert (r["verdict"] in ("consistent", "disagrees")) == (r["note"] == "")
        if r["note"] == "":
            assert all(isinstance(r[k], float) and math.isfinite(r[k]) for k in ("dem", "dem_err", "predicted"))


def test_every_page_the_demo_writes_is_whole(report):
    _, m, out = report
    write_continuum_report(out / "continuum")
    shutil.copytree(out / "compare", out / STUDY_DIR)  # the demo's study report is a comparison report
    index = write_index(out, out / STUDY_DIR, {"test": 0.0})
    front = check_page(index)
    assert {f"{STUDY_DIR}/index.html", "continuum/index.html"} <= set(front.links)
    assert html.escape(m["verdict"]) in index.read_text() and len(front.images) == 1
    decided = {(r["law"], r["quantity"]) for r in m["laws"] if r["verdict"] in ("consistent", "disagrees")}
    opening = f"{len(decided)} of {len({(r['law'], r['quantity']) for r in m['laws']})} law quantities measurable"
    assert index.read_text().index(opening) < index.read_text().index(html.escape(m["verdict"]))
    pages = {name: check_page(out / "compare" / name) for name in ("index.html", "scorecard.html", "drives.html")}
    text = (out / "compare" / "index.html").read_text()
    assert text.index("Findings") < text.index("Contents") < text.index("Conclusions") < text.index("<img")
    assert {"scorecard.html", "drives.html"} <= set(pages["index.html"].links)
    assert sum(len(p.images) for p in pages.values()) >= 5
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


def test_numbers_labels_and_frames_a_reader_trusts():
    assert fmt(1.809861200000000059, 3.4e-17) == "1.80986 ± 3e-17"  # an imposed value: 6 digits at most
    assert fmt(10.451, 0.098) == "10.451 ± 0.098" and fmt(-0.001, 0.24) == "0.00 ± 0.24"
    assert fmt_band((1.8098612, 1.8098613), 3e-17) == "[1.80986, 1.80986]"
    labels = ["/tmp/gs-smoke/speed", "/tmp/x/r/speed", "/tmp/y/r/speed"]
    assert [display_label(x, labels) for x in labels] == ["gs-smoke: speed", "x/r: speed", "y/r: speed"]
    # two output times a rounding apart are one profile, never two joined by a line
    t_end = 9.99
    frames = pd.DataFrame({"t": [1.0] * 3 + [t_end] * 3 + [t_end * (1 + 1e-15)] * 3, "depth": [0, 1, 2] * 3})
    assert len(nearest_frame(frames, t_end)) == 3 and len(nearest_frame(frames, 1.2)) == 3
    # a long drive label on the narrowest figure: the title wraps inside it
    fig = Figure(figsize=(6.5, 5))
    suptitle(fig, "/a/very/long/run/folder/spheres-3d-long-name: stress – transient profiles at snapshot times "
             "t [sqrt(d/g)] (DEM units, I in the DEM convention); shear-wave transit 0.0685, compared from 0.206")
    title = next(t for t in fig.findobj(Text) if t.get_text() == fig.get_suptitle())
    extent = title.get_window_extent(FigureCanvasAgg(fig).get_renderer())
    assert fig.get_suptitle().count("\n") >= 1 and 0 <= extent.x0 and extent.x1 <= fig.bbox.width


def test_drives_modelled_in_forked_processes_match_one_process(report):
    """The model side of every drive (predictions, replicates, bands, rows) is the same whether the drives run
    in one process or in two forked ones, in the drives' order."""
    from granstokes.compare.comparison import ModelSide, model_drive
    from granstokes.compare.experiment import map_drives
    from granstokes.continuum.scene_models import LOCAL, PAPER

    c, _, _ = report
    a = c.drives[0].dem
    side = ModelSide(c.material, (LOCAL, PAPER), "", c.replicates.head(12), {}, True, (np.nan, np.nan))
    one = map_drives(lambda d: model_drive(d, side), [a, a], jobs=1, progress=False)
    two = map_drives(lambda d: model_drive(d, side), [a, a], jobs=2, progress=False)
    for (head1, rows1, edge1, _), (head2, rows2, edge2, _) in zip(one, two):
        assert [p.model for p in head1[1]] == [p.model for p in head2[1]] == ["local", "paper"]
        assert len(rows1) >= 4
        pd.testing.assert_frame_equal(rows1, rows2)
        assert edge1 == edge2 or (np.isnan(edge1) and np.isnan(edge2))
    np.testing.assert_array_equal(one[0][0][1][0].series.u_w, two[1][0][1][0].series.u_w)


def test_a_comparison_from_the_reports_tables_matches_the_one_from_the_dumps(report, smoke_calibration):
    """The report's tables/ hold the DEM side: compared again from them (no dumps), every scorecard row has the
    same DEM value, error and prediction as from the dumps (to the tables' six significant digits), and the
    tables are small."""

    c, _, out = report
    folder = out / "compare" / "tables"
    size = sum(f.stat().st_size for f in folder.rglob("*") if f.is_file())
    assert 0 < size < 2_000_000
    experiment = StokesDrives(smoke_calibration, progress=False)
    again = experiment.run(experiment.read_tables(folder))
    a, b = c.scorecard.rows, again.scorecard.rows
    assert len(a) == len(b) >= 4
    assert list(a.observable) == list(b.observable) and list(a.model) == list(b.model)
    for col in ("dem", "dem_err", "predicted", "sigma"):
        np.testing.assert_allclose(b[col], a[col], rtol=1e-3, atol=1e-9, err_msg=col)
    assert again.dem.drives[0].spec.seeds == c.dem.drives[0].spec.seeds
    layers, read_back = c.dem.drives[0].layers, again.dem.drives[0].layers
    assert len(layers) >= 20 and set(layers.seed) == set(range(c.dem.drives[0].spec.seeds))
    np.testing.assert_allclose(read_back[["t", "delta_50", "delta_05", "moment"]],
                               layers[["t", "delta_50", "delta_05", "moment"]], rtol=1e-5)
    both = layers.dropna(subset=["delta_50", "delta_05"])
    assert len(both) >= 10 and (both.delta_05 >= both.delta_50).all() and (layers.moment.dropna() > 0).all()
    assert again.mass_error == pytest.approx(c.mass_error, rel=1e-4)
    assert again.checks.crosscheck_bulk == pytest.approx(c.checks.crosscheck_bulk, rel=1e-3)


def test_runs_named_relative_to_a_root(smoke_run, smoke_calibration):
    """A study names its runs relative to its folder: labels, runs, grains and the checks' drive carry no
    absolute path, and the analysis is the same."""
    from granstokes.compare.comparison import analyse

    dem = analyse([smoke_run], progress=False, root=smoke_run.parent)
    assert dem.runs == (Path(smoke_run.name),) and list(dem.grains) == [smoke_run.name]
    assert all(not Path(a.label).is_absolute() and a.label.startswith(f"{smoke_run.name}/") for a in dem.drives)
    assert dem.checks.drive == dem.drives[0].label
    plain = analyse([smoke_run], progress=False)
    assert dem.drives[0].steady["mu_w"]["value"] == plain.drives[0].steady["mu_w"]["value"]
