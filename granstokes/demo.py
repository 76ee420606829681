"""``granstokes demo`` (``make demo``): the continuum report, the quick DEM preset (imposed stress and
imposed speed) and the smoke preset (a second, smaller scene for the cost-vs-noise chart), the quick
preset's independent mu(I) calibration by plane shear (``granstokes dem calibrate``, same grains), the
blind comparison report over both scenes (``compare --calibration``), and one index page linking them.
Metrics at the top level come from the quick preset's imposed-stress drive."""
from __future__ import annotations

import html
import json
import time
from pathlib import Path

from compare.comparison import build
from compare.report import slug, write_report
from continuum.paper.report import write_continuum_report
from dem import config as dem_config
from dem import layout
from dem.calibrate import calibrate as dem_calibrate
from dem.runner import run as dem_run

from .page import page


def _dem(preset: str, run_dir: Path) -> Path:
    """Run a DEM preset into run_dir, resuming an unfinished run and skipping a complete one."""
    meta = run_dir / "run.json"
    status = json.loads(meta.read_text()).get("status") if meta.exists() else None
    if status != "complete":
        cfg, text = dem_config.preset(preset)
        result = dem_run(cfg, text, run_dir, np=2, resume=status is not None)
        if result.status != "complete":
            raise RuntimeError(f"DEM preset {preset} did not complete: {result.status} {result.message} "
                               f"(see {meta}); rerun make demo to resume it")
    return run_dir


def _calibration(preset: str, folder: Path) -> Path:
    """Calibrate a preset's grains into folder (resuming or skipping as ``_dem``); its calibration.json."""
    state = folder / layout.CALIBRATION_STATE
    status = json.loads(state.read_text()).get("status") if state.exists() else None
    if status != "complete":
        cfg, text = dem_config.preset(preset)
        result = dem_calibrate(cfg, text, folder, resume=status is not None)
        if result.status != "complete":
            raise RuntimeError(f"calibration of {preset} did not complete: {result.status} {result.message} "
                               f"(see {state}); rerun make demo to resume it")
    return folder / layout.CALIBRATION_JSON


def run_demo(out_dir, presets: tuple[str, ...] = ("quick", "smoke"), calibrated: str = "quick") -> Path:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    clock = {}
    start = time.perf_counter()
    write_continuum_report(out / "continuum")
    clock["continuum"] = time.perf_counter() - start
    start = time.perf_counter()
    run_dirs = [_dem(preset, out / f"dem-{preset}") for preset in presets]
    clock["dem"] = time.perf_counter() - start
    start = time.perf_counter()
    calibration = _calibration(calibrated, out / f"calibration-{calibrated}")
    clock["calibration"] = time.perf_counter() - start
    start = time.perf_counter()
    m = write_report(build(run_dirs, calibration=calibration), out / "compare")
    clock["compare"] = time.perf_counter() - start
    keys = ("phi_bulk", "pressure_slope", "mu_s", "mu_d", "I0", "alpha_u", "alpha_delta")
    rows = "".join(f"<tr><th>{k}</th><td>{m[k]:.4g}</td></tr>" for k in keys if m.get(k) is not None)
    timing = ", ".join(f"{k} {v:.0f} s" for k, v in clock.items())
    body = (f"<h1>granstokes demo</h1><ul><li><a href='compare/index.html'>continuum vs DEM ({html.escape(', '.join(presets))} presets), "
            f"blind: mu(I) from the plane-shear calibration of the {html.escape(calibrated)} grains</a></li>"
            f"<li><a href='continuum/index.html'>continuum: the paper's figures regenerated</a></li></ul>"
            f"<table>{rows}</table><p>Wall time: {html.escape(timing)}.</p>"
            f"<p><img src='compare/drive_{slug(str(run_dirs[0]) + '/stress')}.png' alt='quick preset, imposed stress'></p>")
    index = out / "index.html"
    index.write_text(page("granstokes demo", body))
    return index
