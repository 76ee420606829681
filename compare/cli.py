"""``granstokes compare RUN_DIR... --out REPORT_DIR [--calibration DIR/calibration.json] [--json]``."""
from __future__ import annotations

import json
import os
from pathlib import Path

from granstokes.lib.staging import claim, staged
from granstokes.lib.validate import require

COMMAND = "compare"


def run_compare(args) -> int:
    from granstokes.dem.layout import RUN_JSON

    require(args.jobs >= 1, "--jobs", "an integer >= 1 (processes predicting the drives)", args.jobs)
    for run in args.runs:
        require((run / RUN_JSON).is_file(), "RUN_DIR", "a folder written by granstokes dem run (with run.json)",
                str(run))
    inputs = [*args.runs, *([args.calibration] if args.calibration is not None else [])]
    claim(args.out, "--out", COMMAND, inputs)
    from .calibrate import load
    from .comparison import build, check_grains

    if args.calibration is None and not args.fit_on_drives:
        raise ValueError("--calibration is required: a calibration.json of granstokes dem calibrate (an independent "
                         "plane-shear calibration of the same grains); or pass --fit-on-drives for a fit on the "
                         "drives that is never scored as support")
    if args.calibration is not None:  # bad calibrations fail before any coarse-graining
        require(not args.fit_on_drives, "--fit-on-drives", "left out when --calibration is given", True)
        check_grains(load(args.calibration), args.runs)
    from .report import write_report
    from .scorecard import tally

    comparison = build(args.runs, calibration=args.calibration, fit_on_drives=args.fit_on_drives, jobs=args.jobs)
    with staged(args.out, COMMAND, inputs) as work:
        m = write_report(comparison, work)
    if args.json:
        print(json.dumps(m, default=float))
        return 0
    print(comparison.verdict)
    shared = tally(comparison.scorecard.rows)
    if len(shared):
        print(shared[["model", "n", "consistent", "median_abs_sigma"]].to_string(index=False, float_format="%.2f"))
    print(f"report: {(args.out / 'index.html').resolve()}")
    return 0


def register(sub) -> None:
    p = sub.add_parser("compare", help="coarse-grain DEM runs, predict them from mu(I) (independent or fitted), "
                                       "write the report")
    p.add_argument("runs", type=Path, nargs="+", metavar="RUN_DIR", help="run folders of granstokes dem run")
    p.add_argument("--out", type=Path, required=True, help="report folder (index.html, CSV, metrics.json)")
    p.add_argument("--calibration", type=Path, help="calibration.json of granstokes dem calibrate (same grains): "
                                                    "mu(I) and phi from it, the drives a blind test (required "
                                                    "unless --fit-on-drives)")
    p.add_argument("--fit-on-drives", action="store_true",
                   help="fit mu(I) on the drives' own steady windows instead: a restatement, every row labelled not "
                        "blind and never counted as support for a model")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                   help="processes predicting and scoring the drives (default: the machine's cores)")
    p.add_argument("--json", action="store_true", help="also print metrics.json to stdout")
    p.set_defaults(func=run_compare)
