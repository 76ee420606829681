"""``granstokes demo`` (``make demo``): the continuum report (the paper's figures regenerated) and the smoke study
(``granstokes study --preset smoke``: its grains calibrated by plane shear at two pressures, the drives sized from
that calibration, predicted blind by every model and scored), with one front page linking both reports.  A demo
that stopped resumes where it stopped; one that completed is rendered again without rerunning anything."""
from __future__ import annotations

import html
import json
import sys
import time
from pathlib import Path

from granstokes.continuum.paper.report import write_continuum_report

from .lib.page import page
from .lib.staging import claim, staged, start
from .study import config as study_config
from .study.runner import COMMAND as STUDY_COMMAND
from .study.runner import STUDY_JSON, STUDY_TOML, StudyStopped, run_study

COMMAND = "demo"
STUDY = "smoke"
STUDY_DIR = "study"  # the study's folder inside the demo's


def _stage(name: str, clock: dict, action):
    print(f"demo: {name} ...", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    result = action()
    clock[name] = time.perf_counter() - t0
    print(f"demo: {name} done in {clock[name]:.0f} s", file=sys.stderr, flush=True)
    return result


def run_demo(out_dir, study: str = STUDY) -> Path:
    out = start(claim(out_dir, "--out", COMMAND), COMMAND)
    claim(out / "continuum", "--out", COMMAND)
    claim(out / STUDY_DIR, "--out", STUDY_COMMAND)  # the study's own folder: run, resumed, or complete
    clock = {}

    def continuum_report():
        with staged(out / "continuum", COMMAND) as work:
            write_continuum_report(work)

    _stage("continuum report (the paper's figures)", clock, continuum_report)
    folder = out / STUDY_DIR
    stored = folder / STUDY_JSON
    resume = stored.exists() and json.loads(stored.read_text()).get("status") != "complete"
    if not stored.exists() or resume:
        st, text = ((study_config.parse((folder / STUDY_TOML).read_text(), folder), (folder / STUDY_TOML).read_text())
                    if resume else study_config.load(None, study))
        record = _stage(f"the {study} study (calibration, DEM drives, blind comparison)", clock,
                        lambda: run_study(st, text, folder, resume=resume))
        if record["status"] != "complete":
            raise StudyStopped(record["status"], f"the {study} study did not complete: {record['message']} (see "
                               f"{stored}); rerun make demo to resume it", record.get("signal"))
    with staged(out, COMMAND, keep=True) as work:
        write_index(work, folder, clock)
    return out / "index.html"


def laws_html(rows: list[dict]) -> str:
    """The paper's laws the study could measure (DEM against each model), and how many it could not."""
    measured = [r for r in rows if r["verdict"] in ("consistent", "disagrees")]
    laws = {(r["law"], r["quantity"]) for r in rows}
    decided = {(r["law"], r["quantity"]) for r in measured}
    items = "".join(f"<li>{html.escape(r['law'])} ({html.escape(r['quantity'])}): DEM {r['dem']:.3g} ± "
                    f"{r['dem_err']:.2g}, {html.escape(r['model'])} {r['predicted']:.3g}, sigma {r['sigma']:+.1f}: "
                    f"{html.escape(r['verdict'])}</li>" for r in measured)
    return (f"<h2>The paper's laws</h2><p>{len(decided)} of {len(laws)} law quantities measurable at this study's "
            f"size; the others say why in the study report.</p>" + (f"<ul>{items}</ul>" if items else ""))


def write_index(out: Path, study: Path, clock: dict) -> Path:
    """The demo's front page in ``out``: the verdict and main figure of the study report in ``study`` (the demo's
    STUDY_DIR), links to both reports."""
    from granstokes.compare.experiment import METRICS_JSON

    metrics = json.loads((study / METRICS_JSON).read_text())
    timing = ", ".join(f"{k} {v:.0f} s" for k, v in clock.items()) or "resumed: nothing left to run"
    figure = next(iter(sorted(study.glob("drive_*.png"))), None)
    body = (f"<h1>granstokes demo</h1>{laws_html(metrics.get('laws', []))}<p>{html.escape(metrics['verdict'])}</p>"
            f"<ul><li><a href='{STUDY_DIR}/index.html'>the smoke study: every drive against every model, blind "
            "(the full report)</a></li>"
            "<li><a href='continuum/index.html'>continuum: the paper's figures regenerated</a></li></ul>"
            f"<p>Units: {html.escape(metrics['units'])}. Wall time: {html.escape(timing)}.</p>"
            + (f"<p><img src='{STUDY_DIR}/{figure.name}' alt='drive figure {html.escape(figure.stem)}'></p>" if figure
               else ""))
    index = out / "index.html"
    index.write_text(page("granstokes demo", body))
    return index
