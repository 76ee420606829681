"""An experiment: DEM drives of one kind confronted with the continuum models, in stages (in the spirit of
MDAnalysis's ``AnalysisBase``), and the registry that picks one by the drives' load.

    kind = experiment_for_runs(runs)                  # or experiment_for_tables(folder)
    exp = kind(calibration, jobs=2)                   # options checked before any work
    dem = exp.analyse(runs)                           # or exp.read_tables(folder): the DEM side, no calibration
    result = exp.run(dem)                             # _prepare, _predict per drive (forked processes), _conclude
    metrics = exp.write(result, out)                  # the shared shell: metrics.json, CSVs, tables/, index.html

A subclass names the loads it takes (``accepts``), reads its DEM side (``analyse``, ``read_tables``; ``write_tables``
for a report's tables/), prepares what every prediction shares from the calibration (``_prepare``), predicts and
scores one drive (``_predict``, run by ``map_drives``) and gathers the result (``_conclude``, with the scorecard rows
and law rows of compare.rows and the calibration band of compare.band).  It renders its own figures, sections and
metrics; ``write`` puts them in the one shell every report shares.  Adding an experiment is a subclass in its own
module listed in ``MODULES`` (docs/experiments.md: the oscillating plate as the worked example).
"""
from __future__ import annotations

import html
import importlib
import inspect
import json
import multiprocessing as mp
from collections.abc import Callable, Sequence
from concurrent.futures import as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
from granstokes.continuum.scales import UNITS
from tqdm import tqdm

from granstokes.lib.executor import forked_pool
from granstokes.lib.page import page
from granstokes.lib.provenance import provenance
from granstokes.lib.validate import require

from .findings import as_dict, evidence_text, findings, rows_text, scene_text
from .rows import UNSCORED, tally
from .words import VERDICT_COLOUR

#: the modules whose Experiment subclasses make the registry, in the order they are asked
MODULES = ("granstokes.compare.stokes_experiment", "granstokes.compare.oscillation_experiment")
#: the report folder's subfolder holding the DEM side as small tables (``--tables``: a comparison again without dumps)
TABLES = "tables"
#: a report's numbers (its scorecard, laws, drives)
METRICS_JSON = "metrics.json"
#: the CSV files' number format
CSV_FLOAT = "%.6g"
#: the reasons a finding without a scored row gives (the rest are in its rows' notes)
NAMED_REASONS = 2


#: the report's pages: index.html opens with the title, the verdict and the findings, then a contents list
INDEX, SCORECARD, DRIVES = "index.html", "scorecard.html", "drives.html"
#: the pages beside index.html, each headed by the study's title and this
PAGES = {SCORECARD: "the scorecard, row by row", DRIVES: "the drives, one by one"}


@dataclass(frozen=True)
class FigureFile:
    """A figure of a report: its kind (the experiment's TITLES and HOW_TO_READ key), file, drive name (or "") and
    the page it is on."""

    kind: str
    path: Path
    name: str = ""
    page: str = INDEX


@dataclass(frozen=True)
class Section:
    """A titled part of a report: its heading, its HTML, its anchor (the id the contents link to) and its page."""

    heading: str
    body: str
    anchor: str
    page: str = INDEX


class Experiment:
    """The stages of a comparison (see the module's docstring); class attributes name and describe it."""

    name: ClassVar[str]               # the registry's key, metrics.json's "experiment"
    title: ClassVar[str]              # the report's heading
    problem: ClassVar[str]            # the problem in words (metrics.json)
    tables_marker: ClassVar[str]      # the file that marks a tables folder of this experiment
    titles: ClassVar[dict]            # figure kind -> title
    how_to_read: ClassVar[dict]       # figure kind -> how to read it
    definitions: ClassVar[dict]       # name -> (unit, definition)
    report: ClassVar = None           # the module that renders it: verdict, metrics, files, sections, scene, names,
                                      # kinds (each optional)

    def __init__(self, calibration: str | Path | None = None, *, jobs: int = 1, progress: bool = True):
        """A subclass adds its own keyword options (checked there, before any work)."""
        require(jobs >= 1, "--jobs", "an integer >= 1 (processes predicting the drives)", jobs)
        self.calibration, self.jobs, self.progress = calibration, jobs, progress

    @classmethod
    def create(cls, calibration: str | Path | None = None, *, jobs: int = 1, progress: bool = True, **options):
        """The experiment with the options a user set (ValueError naming one this experiment does not take)."""
        takes = inspect.signature(cls.__init__).parameters
        for option in options:
            require(option in takes, "--" + option.replace("_", "-"), f"left out: the {cls.name} experiment does not "
                    "take it", options[option])
        return cls(calibration, jobs=jobs, progress=progress, **options)

    # --- what a subclass provides ------------------------------------------------------------------------------
    @classmethod
    def accepts(cls, load) -> bool:
        """Whether a drive with this continuum.load.Load belongs to this experiment."""
        raise NotImplementedError

    @classmethod
    def planned(cls, plan, drive, c_s: float | None = None) -> str:
        """What a planned drive (dem.sizing's Plan and DriveSizing) offers this experiment's laws, as a study's plan
        prints it ("" when nothing beyond its size); ``c_s`` the bed's measured shear-wave speed, if known."""
        return ""

    @classmethod
    def plan_header(cls, c_s: float | None = None) -> str:
        """The line that explains ``planned``'s, or ""."""
        return ""

    def analyse(self, runs: Sequence[Path], root: Path | None = None):
        """The DEM side of the run folders (``root``: name the runs by their paths relative to it)."""
        raise NotImplementedError

    def read_tables(self, folder: Path):
        """The DEM side a report's ``write_tables`` stored."""
        raise NotImplementedError

    @classmethod
    def merge(cls, sides: list):
        """Several DEM sides as one (a study run in parts: their runs and drives together)."""
        raise NotImplementedError

    def read_parts(self, folders: Sequence[Path]):
        """The DEM side of one or several reports' tables folders (a study run in parts, ``merge``d)."""
        sides = [self.read_tables(f) for f in folders]
        return sides[0] if len(sides) == 1 else self.merge(sides)

    @classmethod
    def write_tables(cls, result, folder: Path) -> None:
        raise NotImplementedError

    def _prepare(self, dem):
        """What every drive's prediction shares (the calibrated material, its replicates, the models)."""
        raise NotImplementedError

    def _units(self, dem, setup) -> list:
        """The independent units of prediction work (a drive, or a drive x model)."""
        raise NotImplementedError

    def _predict(self, unit, setup):
        """One unit's predictions and scores (runs in a forked process: nothing it returns may hold a pool)."""
        raise NotImplementedError

    def _conclude(self, dem, setup, predicted: list):
        """The result the report renders (``rows``, ``laws``, ``runs``, ``calibration_source``)."""
        raise NotImplementedError

    @classmethod
    def _rendered(cls, name: str, default, *args):
        """The report module's ``name`` of ``args``, or ``default``'s when the module has none."""
        return getattr(cls.report, name, default)(*args)

    @classmethod
    def verdict(cls, result) -> str:
        """The comparison's verdict in words (the report module's ``verdict``, else the result's own)."""
        return cls._rendered("verdict", lambda r: r.verdict, result)

    @classmethod
    def metrics(cls, result) -> dict:
        """metrics.json's entries of this experiment beyond the shared ones."""
        return cls._rendered("metrics", lambda r: {}, result)

    @classmethod
    def files(cls, result, out: Path) -> list[FigureFile]:
        """Write the experiment's CSV files and figures into ``out``; the figures, in the report's order."""
        return cls._rendered("files", lambda r, o: [], result, out)

    @classmethod
    def sections(cls, result, metrics: dict) -> list[Section]:
        """The report's titled sections, each on its page (index.html's after its findings and contents)."""
        return cls._rendered("sections", lambda r, m: [], result, metrics)

    @classmethod
    def scene(cls, result) -> list[dict]:
        """Each drive's scene checks in compare.findings' terms (check, drive, holds, detail)."""
        return cls._rendered("scene", lambda r: [], result)

    @classmethod
    def names(cls, result) -> dict:
        """The drives' labels as a reader sees them (label -> name)."""
        return cls._rendered("names", lambda r: {}, result)

    @classmethod
    def kinds(cls, result) -> dict:
        """Each drive's load kind (label -> "stress" or "speed"), for rows that do not carry it."""
        return cls._rendered("kinds", lambda r: {}, result)

    @classmethod
    def outputs(cls, drives, output) -> dict:
        """A run's output intervals (dem.config's [output] entries) that resolve its ``drives`` (dem.sizing's
        DriveSizing) for this experiment's estimators; ``output`` the DEM preset's intervals."""
        raise NotImplementedError

    @classmethod
    def comparison_seconds(cls, drives: int, grain_frames: float, jobs: int, speed) -> float:
        """The comparison's wall time for ``drives`` scored drives whose snapshots hold ``grain_frames``, over
        ``jobs`` processes at ``speed`` (dem.throughput.Throughput: its cost constants are in 2D drive grain-steps)."""
        raise NotImplementedError

    @classmethod
    def comparison_work(cls, drives: int, grain_frames: float) -> str:
        """That work in words (a dry run's line)."""
        raise NotImplementedError

    # --- the shared stages -------------------------------------------------------------------------------------
    def run(self, dem):
        """Prepare, predict every unit (``map_drives`` over ``jobs`` processes), conclude."""
        setup = self._prepare(dem)
        units = self._units(dem, setup)
        predicted = map_drives(lambda u: self._predict(u, setup), units, self.jobs, self.progress,
                               "continuum predictions")
        return self._conclude(dem, setup, predicted)

    @classmethod
    def write(cls, result, out_dir) -> dict:
        """The shell every report shares: metrics.json (the shared keys with the findings, then the experiment's),
        scorecard.csv, laws.csv, the experiment's files and tables/, and the pages: index.html (the study's title,
        the verdict and the findings on one screen, a contents list, the index's sections and figures, definitions,
        provenance) and each of PAGES that has a section or a figure, titled by the study and linking back; returns
        the metrics."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        rows, laws = result.rows, result.laws
        runs = [str(r) for r in result.runs]
        names = cls.names(result)
        found = findings(rows, laws, cls.scene(result), names, cls.kinds(result))
        m = json_ready({
            "experiment": cls.name, "problem": cls.problem, "verdict": cls.verdict(result),
            "findings": [as_dict(f, names) for f in found],
            "tally": tally(rows).to_dict("records"),
            "scorecard": [{k: r[k] for k in rows.columns} for r in rows.to_dict("records")],
            "laws": laws.to_dict("records"),
            **cls.metrics(result),
            "definitions": {k: {"unit": u, "definition": d} for k, (u, d) in cls.definitions.items()},
            "units": UNITS["dem_units"], "I_convention": UNITS["inertial_number"], "runs": runs,
            "provenance": provenance(runs=runs, calibration=result.calibration_source),
        })
        (out / METRICS_JSON).write_text(json.dumps(m, indent=2))
        rows.to_csv(out / "scorecard.csv", index=False, float_format=CSV_FLOAT)
        laws.to_csv(out / "laws.csv", index=False, float_format=CSV_FLOAT)
        figures = cls.files(result, out)
        cls.write_tables(result, out / TABLES)
        sections = cls.sections(result, m)
        pages = [p for p in PAGES if any(s.page == p for s in sections) or any(f.page == p for f in figures)]
        closing = [Section("Definitions", table(["name", "unit", "definition"], [
                       [html.escape(k), html.escape(u), html.escape(d)] for k, (u, d) in cls.definitions.items()]),
                           "definitions"),
                   Section("Provenance", table(["item", "value"], [[html.escape(k), html.escape(_cell(v))] for k, v
                                                                  in m["provenance"].items() if k != "inputs"]),
                           "provenance")]
        index = [s for s in sections if s.page == INDEX] + cls._figures_section(figures, INDEX) + closing
        contents = "".join(f"<li><a href='#{s.anchor}'>{html.escape(s.heading)}</a></li>" for s in index)
        contents += "".join(f"<li><a href='{p}'>{html.escape(PAGES[p][:1].upper() + PAGES[p][1:])}</a> (a page of "
                            "its own)</li>" for p in pages)
        title = cls.title[:1].upper() + cls.title[1:]
        body = [f"<h1>{html.escape(title)}</h1>",
                f"<p class='verdict'><b>Verdict.</b> {html.escape(m['verdict'])}</p>",
                "<h2 id='findings'>Findings</h2>", findings_html(found, names),
                f"<h2 id='contents'>Contents</h2><ul>{contents}</ul>", *(cls._section_html(s) for s in index)]
        (out / INDEX).write_text(page(f"granstokes: {title}", "".join(body)))
        for p in pages:
            here = [s for s in sections if s.page == p] + cls._figures_section(figures, p)
            links = "".join(f"<li><a href='#{s.anchor}'>{html.escape(s.heading)}</a></li>" for s in here)
            body = [f"<h1>{html.escape(title)}: {html.escape(PAGES[p])}</h1>",
                    f"<p><a href='{INDEX}'>Back to the report: the verdict and the findings</a></p>",
                    f"<ul>{links}</ul>", *(cls._section_html(s) for s in here)]
            (out / p).write_text(page(f"granstokes: {title}: {PAGES[p]}", "".join(body)))
        return m

    @staticmethod
    def _section_html(s: Section) -> str:
        return f"<h2 id='{s.anchor}'>{html.escape(s.heading)}</h2>{s.body}"

    @classmethod
    def _figures_section(cls, figures: list[FigureFile], on: str) -> list[Section]:
        """The figures of page ``on`` as one section (none when it has none); off the index, the first figure of each
        name (a drive's) links from the section's head."""
        shown = [f for f in figures if f.page == on]
        if not shown:
            return []
        drives = list(dict.fromkeys(f.name for f in shown if f.name))
        anchors = {name: f"figures-{k}" for k, name in enumerate(drives)}
        head = ("<p>Jump to: " + ", ".join(f"<a href='#{anchors[n]}'>{html.escape(n)}</a>" for n in drives)
                + ".</p>" if drives and on != INDEX else "")
        first = {f.name: f for f in reversed(shown) if f.name}
        body = "".join(cls._figure_html(f, anchors[f.name] if f.name and first[f.name] is f else "") for f in shown)
        return [Section("Figures", head + body, "figures")]

    @classmethod
    def _figure_html(cls, f: FigureFile, anchor: str = "") -> str:
        title = cls.titles[f.kind] + (f": {f.name}" if f.name else "")
        alt = f"{cls.titles[f.kind]} figure" + (f" of {f.name}" if f.name else "")
        ident = f" id='{anchor}'" if anchor else ""
        return (f"<h3{ident}>{html.escape(title)}</h3><p class='how'>{html.escape(cls.how_to_read[f.kind])}</p>"
                f"<p><img src='{Path(f.path).name}' alt='{html.escape(alt)}'></p>")


def findings_html(found: list, names: dict) -> str:
    """The findings as a short table: the effect and its status, its strongest robust evidence, the rows behind it,
    the scene checks that could fake it (compare.findings)."""
    if not found:
        return "<p>No finding: no row of this study measures an effect.</p>"
    rows = [[f"<b>{html.escape(f.effect)}</b><br><small style='color:{_status_colour(f.status)}'>"
             f"{html.escape(f.status)}</small>",
             html.escape(evidence_text(f, names) or "no scored row: " + "; ".join(f.why[:NAMED_REASONS])),
             html.escape(rows_text(f)), html.escape(scene_text(f))] for f in found]
    return table(["finding", "strongest robust evidence", "rows", "what could fake it: the scene"], rows)


def _status_colour(status: str) -> str:
    """A finding's status in its rows' verdict colour: no row disagrees (green), none is scored (grey), else red."""
    return VERDICT_COLOUR[{"not shown": "consistent", "not measurable": UNSCORED[-1]}.get(status, "disagrees")]


def table(header, rows) -> str:
    """An HTML table (cells already HTML)."""
    head = "".join(f"<th>{h}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _cell(v) -> str:
    return json.dumps(v) if isinstance(v, dict | list) else str(v)


def json_ready(v):
    """JSON-ready: numpy scalars and arrays to Python, non-finite numbers to None (valid JSON, pandas-readable)."""
    if isinstance(v, dict):
        return {k: json_ready(x) for k, x in v.items()}
    if isinstance(v, list | tuple | np.ndarray):
        return [json_ready(x) for x in v]
    if isinstance(v, bool | np.bool_):
        return bool(v)
    if isinstance(v, int | np.integer):
        return int(v)
    if isinstance(v, float | np.floating):
        return float(v) if np.isfinite(v) else None
    return v


#: the work a forked worker reads (set by map_drives before the pool starts: nothing large is pickled)
_SHARED: dict = {}


def _call(i: int):
    return _SHARED["fn"](_SHARED["items"][i])


def map_drives(fn: Callable, items: Sequence, jobs: int = 1, progress: bool = True, desc: str = "") -> list:
    """``fn`` of every item, in ``jobs`` forked processes (the items are independent), in order; the function and
    the items reach the workers by the fork, only the results are pickled."""
    jobs = max(1, min(jobs, len(items)))
    bar = dict(total=len(items), desc=desc, disable=not progress or None)
    if jobs == 1 or "fork" not in mp.get_all_start_methods():
        return [fn(item) for item in tqdm(items, **bar)]
    _SHARED.update(fn=fn, items=items)
    try:
        with forked_pool(jobs) as pool:
            futures = [pool.submit(_call, i) for i in range(len(items))]
            for _ in tqdm(as_completed(futures), **bar):
                pass
            return [f.result() for f in futures]
    finally:
        _SHARED.clear()


# --- the registry ----------------------------------------------------------------------------------------------

def experiments() -> list[type[Experiment]]:
    """Every registered experiment (MODULES imported: their subclasses register by being defined)."""
    for module in MODULES:
        importlib.import_module(module)
    return list(Experiment.__subclasses__())


def experiment_for(loads) -> type[Experiment]:
    """The experiment that takes every one of ``loads`` (ValueError when none does, or when they need two); with
    no loads at all (runs not yet sized), the first registered, whose own checks then say what is missing."""
    loads = list(loads)
    if not loads:
        return experiments()[0]
    kinds = {k for load in loads for k in experiments() if k.accepts(load)}
    require(len(kinds) == 1, "RUN_DIR", "runs whose drives all belong to one experiment (" +
            ", ".join(k.name for k in experiments()) + ")", sorted(k.name for k in kinds) or "none")
    return kinds.pop()


def experiment_for_runs(runs) -> type[Experiment]:
    """The experiment of the run folders' drives (their run.json's loads)."""
    from .drive import run_loads

    return experiment_for(load for run in runs for load in run_loads(run))


def experiment_for_tables(folder: Path) -> type[Experiment]:
    """The experiment whose tables a report's tables folder holds."""
    kinds = [k for k in experiments() if (Path(folder) / k.tables_marker).is_file()]
    require(len(kinds) == 1, "--tables", "the tables folder of a report (with " +
            " or ".join(k.tables_marker for k in experiments()) + ")", str(folder))
    return kinds[0]

