"""``granstokes demo`` (``make demo``): the continuum report, the quick DEM preset (imposed stress and
imposed speed) and the smoke preset (a second, smaller scene), an independent mu(I) calibration of the
quick grains by plane shear (``granstokes dem calibrate`` at the demo's reduced protocol DEMO_CALIBRATION),
the blind comparison over both scenes (``compare --calibration``), and one index page with the scorecard
and the conclusions, linking both reports."""
from __future__ import annotations

import html
import json
import re
import sys
import time
from pathlib import Path

from granstokes.compare.comparison import build
from granstokes.compare.report import conclusions, display_labels, scorecard_html, slug, verdict_html, write_report
from granstokes.continuum.paper.report import write_continuum_report
from granstokes.dem import config as dem_config
from granstokes.dem import layout
from granstokes.dem.calibrate import calibrate as dem_calibrate
from granstokes.dem.runner import run as dem_run

from .lib.page import page
from .lib.staging import claim, staged, start

COMMAND = "demo"


def _resumable(what: str, preset: str, folder: Path, state: Path, action) -> None:
    """Run ``action(cfg, text, folder, resume=...)`` on a preset unless ``state`` says complete, resuming an
    unfinished one; a run that does not complete stops the demo with where to look."""
    status = json.loads(state.read_text()).get("status") if state.exists() else None
    if status != "complete":
        cfg, text = dem_config.preset(preset)
        result = action(cfg, text, folder, resume=status is not None)
        if result.status != "complete":
            raise RuntimeError(f"{what} of preset {preset} did not complete: {result.status} {result.message} "
                               f"(see {state}); rerun make demo to resume it")


def _dem(preset: str, run_dir: Path) -> Path:
    _resumable("the DEM run", preset, run_dir, run_dir / layout.RUN_JSON, dem_run)
    return run_dir


#: the demo's plane-shear protocol for the preset's grains: 5 inertial numbers over two decades, one cell
#: each (about 3 min of wall time on 2 cores, the I = 0.005 cell being the longest); the preset's own
#: [calibration] table (13 listed I over 2.7 decades, 3 seeds: 13 min) is results/quick-calibration, rerun
#: with granstokes dem calibrate --preset quick
DEMO_CALIBRATION = {"I_min": "0.005", "I_max": "0.5", "points": "5", "seeds": "[1]"}


def demo_calibration_text(preset: str) -> str:
    """The preset's TOML with the demo's protocol in its [calibration] table (grains untouched): the
    table's inertial numbers (a list ``I`` or a range) and seeds replaced by DEMO_CALIBRATION."""
    head, table = dem_config.preset_text(preset).split("[calibration]\n", 1)
    table = re.sub(rf"(?m)^({'|'.join(['I', *DEMO_CALIBRATION])}) = .*\n", "", table)
    return head + "[calibration]\n" + "".join(f"{k} = {v}\n" for k, v in DEMO_CALIBRATION.items()) + table


def _calibration(preset: str, folder: Path) -> Path:
    def action(cfg, text, out, resume):
        text = demo_calibration_text(preset)
        return dem_calibrate(dem_config.parse(text), text, out, resume=resume)

    _resumable("the mu(I) calibration", preset, folder, folder / layout.CALIBRATION_STATE, action)
    return folder / layout.CALIBRATION_JSON


def _stage(name: str, clock: dict, action):
    print(f"demo: {name} ...", file=sys.stderr, flush=True)
    start = time.perf_counter()
    result = action()
    clock[name] = time.perf_counter() - start
    print(f"demo: {name} done in {clock[name]:.0f} s", file=sys.stderr, flush=True)
    return result


def run_demo(out_dir, presets: tuple[str, ...] = ("quick", "smoke"), calibrated: str = "quick") -> Path:
    out = start(claim(out_dir, "--out", COMMAND), COMMAND)
    for part in ("continuum", "compare"):
        claim(out / part, "--out", COMMAND)
    clock = {}

    def continuum_report():
        with staged(out / "continuum", COMMAND) as work:
            write_continuum_report(work)

    _stage("continuum report (the paper's figures)", clock, continuum_report)
    run_dirs = [_stage(f"DEM preset {p}", clock, lambda p=p: _dem(p, out / f"dem-{p}")) for p in presets]
    calibration = _stage(f"mu(I) calibration of the {calibrated} grains by plane shear", clock,
                         lambda: _calibration(calibrated, out / f"calibration-{calibrated}"))
    comparison = _stage("blind comparison (coarse-graining, predictions from the calibration, uncertainty)", clock,
                        lambda: build(run_dirs, calibration=calibration))
    with staged(out / "compare", COMMAND) as work:
        write_report(comparison, work)
    with staged(out, COMMAND, keep=True) as work:
        write_index(comparison, work, presets, clock)
    return out / "index.html"


def write_index(comparison, out: Path, presets, clock: dict) -> Path:
    """The demo's front page: links to both reports, the scorecard, the conclusions, the main figure."""
    timing = ", ".join(f"{k} {v:.0f} s" for k, v in clock.items())
    main = next((dc for dc in comparison.drives if dc.predictions), comparison.drives[0])
    name = display_labels(comparison)[main.label]
    body = (f"<h1>granstokes demo</h1>{verdict_html(comparison)}<ul><li><a href='compare/index.html'>continuum vs DEM "
            f"({html.escape(', '.join(presets))} presets): the full report</a></li>"
            f"<li><a href='continuum/index.html'>continuum: the paper's figures regenerated</a></li></ul>"
            f"<h2>Scorecard</h2>{scorecard_html(comparison)}<h2>Conclusions</h2><ul>"
            + "".join(f"<li>{c}</li>" for c in conclusions(comparison)) + "</ul>"
            f"<p>Wall time: {html.escape(timing)}.</p>"
            f"<p><img src='compare/drive_{slug(name)}.png' alt='drive figure of {html.escape(name)}'></p>")
    index = out / "index.html"
    index.write_text(page("granstokes demo", body))
    return index
