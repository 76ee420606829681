"""The calibration band's step (compare.band.STEP): each committed study's model side again from its tables with the
calibrated parameters shifted by 1e-3, 3e-3, 1e-2 and 3e-2 of their values, and how the propagated standard
deviations (the scorecard rows' calibration_sd, the law rows' predicted_err) change with the step.

A step is good where the sd no longer depends on it: the solver's error (~ eps/h) falls as h grows and the
truncation error (~ h) grows with it; estimators that cross a threshold on a grid (t90 on output times, a depth on
the profile's nodes) also need h large enough to move the crossing by more than one grid interval.

    .venv/bin/python bench/band_step.py [--oscillating-drives N]

Prints the table for bench/RESULTS.md ("Calibration band step") and writes bench/band_step.json.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from granstokes.compare import band
from granstokes.compare.oscillation_experiment import OscillatingPlate
from granstokes.compare.stokes_experiment import StokesDrives

ROOT = Path(__file__).resolve().parents[1]
STEPS = (1e-3, 3e-3, 1e-2, 3e-2)
STUDIES = {"study-spheres": (StokesDrives, "results/calibration-spheres/p10/calibration.json", "tables"),
           "study-oscillating-disks": (OscillatingPlate, "results/calibration-disks/p20/calibration.json", "tables")}


def sds(kind, calibration: Path, tables: Path, drives: int | None) -> dict:
    """(row identity -> sd) of the scorecard's and the laws' rows at the current STEP."""
    experiment = kind(calibration, progress=False, jobs=2)
    dem = experiment.read_tables(tables)
    if drives is not None:
        dem = dem[:drives]
    result = experiment.run(dem)
    rows = result.rows[result.rows.scored]
    out = {f"{r.drive}|{r.observable}|{r.model}": r.calibration_sd for r in rows.itertuples()}
    laws = result.laws[np.isfinite(result.laws.predicted_err) & (result.laws.predicted_err > 0)]
    out |= {f"law|{r.law}|{r.quantity}|{r.model}": r.predicted_err for r in laws.itertuples()}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--oscillating-drives", type=int, default=4, help="drives of the oscillating study to solve")
    args = ap.parse_args()
    found = {}
    for study, (kind, calibration, tables) in STUDIES.items():
        limit = args.oscillating_drives if kind is OscillatingPlate else None
        per_step = {}
        for step in STEPS:
            band.STEP = step
            per_step[step] = sds(kind, ROOT / calibration, ROOT / "results" / study / tables, limit)
        keys = [k for k in per_step[STEPS[0]] if all(np.isfinite(per_step[s].get(k, np.nan)) and per_step[s][k] > 0
                                                      for s in STEPS)]
        reference = {k: per_step[1e-2][k] for k in keys}
        found[study] = {f"{s:g}": {"median_ratio": float(np.median([per_step[s][k] / reference[k] for k in keys])),
                                   "largest_change": float(np.max([abs(per_step[s][k] / reference[k] - 1)
                                                                   for k in keys])),
                                   "rows": len(keys)} for s in STEPS}
    print("| study | step | rows | median sd / sd at 1e-2 | largest relative change from 1e-2 |")
    print("|---|---|---|---|---|")
    for study, by_step in found.items():
        for s, v in by_step.items():
            print(f"| {study} | {s} | {v['rows']} | {v['median_ratio']:.3f} | {v['largest_change']:.2f} |")
    (ROOT / "bench" / "band_step.json").write_text(json.dumps(found, indent=2))


if __name__ == "__main__":
    main()
