"""``granstokes compare (RUN_DIR... | --tables REPORT_DIR/tables) --out REPORT_DIR [--calibration
DIR/calibration.json] [--ngf-from METRICS.json] [--jobs N] [--json]``: Stokes drives (compare.comparison) or, when the
runs' drives oscillate, the oscillating plate (compare.oscillation)."""
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
    require(bool(args.runs) != (args.tables is not None), "RUN_DIR / --tables",
            "either run folders or one tables folder of an earlier report", "both" if args.runs else "neither")
    for run in args.runs:
        require((run / RUN_JSON).is_file(), "RUN_DIR", "a folder written by granstokes dem run (with run.json)",
                str(run))
    if args.tables is not None:
        from .oscillation_tables import DRIVES_JSON
        from .tables import DEM_JSON
        require((args.tables / DEM_JSON).is_file() or (args.tables / DRIVES_JSON).is_file(), "--tables",
                f"the tables folder of a report (with {DEM_JSON} or {DRIVES_JSON})",
                str(args.tables))
    oscillating = _oscillating(args.runs, args.tables)
    require(args.ngf_from is None or oscillating, "--ngf-from", "only for oscillating drives (a Stokes comparison "
            "fits NGF's A on its own drives)", str(args.ngf_from))
    if args.ngf_from is not None:
        require(args.ngf_from.is_file(), "--ngf-from", "a Stokes report's metrics.json", str(args.ngf_from))
    sources = args.runs or [args.tables]
    inputs = [*sources, *([args.calibration] if args.calibration is not None else [])]
    claim(args.out, "--out", COMMAND, inputs)
    if oscillating:
        return _compare_oscillations(args, inputs)
    from .calibrate import load
    from .comparison import analyse, check_grains, compare, run_grains
    from .tables import read

    tabled = read(args.tables) if args.tables is not None else None
    if args.calibration is None and not args.fit_on_drives:
        raise ValueError("--calibration is required: a calibration.json of granstokes dem calibrate (an independent "
                         "plane-shear calibration of the same grains); or pass --fit-on-drives for a fit on the "
                         "drives that is never scored as support")
    if args.calibration is not None:  # bad calibrations fail before any coarse-graining
        require(not args.fit_on_drives, "--fit-on-drives", "left out when --calibration is given", True)
        check_grains(load(args.calibration), tabled.grains if tabled else run_grains(args.runs))
    from .report import write_report
    from .scorecard import tally

    dem = tabled or analyse(args.runs)
    comparison = compare(dem, calibration=args.calibration, fit_on_drives=args.fit_on_drives, jobs=args.jobs)
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


def _oscillating(runs, tables) -> bool:
    """Whether the runs' (or the tables') drives are oscillating plates: all of them or none (ValueError)."""
    from granstokes.dem.layout import RUN_JSON
    from granstokes.dem.sizing import sized_drives

    from .oscillation_tables import DRIVES_JSON
    if tables is not None:
        return (tables / DRIVES_JSON).is_file()
    kinds = set()
    for run in runs:
        # a run not yet sized has no drives: its own error follows
        kinds |= {d.load.oscillating for d in sized_drives(json.loads((run / RUN_JSON).read_text()))}
    require(len(kinds) <= 1, "RUN_DIR", "runs whose drives all oscillate or all are held (Stokes' first problem)",
            "both kinds")
    return kinds == {True}


def _compare_oscillations(args, inputs) -> int:
    from .oscillation import compare_oscillations, dem_side
    from .oscillation_report import write_report
    from .oscillation_tables import read

    require(args.calibration is not None and not args.fit_on_drives, "--calibration",
            "a calibration.json (the oscillating drives are predicted blind; no fit on them)", args.calibration)
    if args.runs:  # a calibration of other grains is refused before any work
        from .calibrate import load
        from .comparison import check_grains, run_grains
        check_grains(load(args.calibration), run_grains(args.runs))
    dem = read(args.tables) if args.tables is not None else dem_side(args.runs)
    comparison = compare_oscillations(dem, args.calibration, args.ngf_from, jobs=args.jobs)
    with staged(args.out, COMMAND, inputs) as work:
        m = write_report(comparison, work)
    if args.json:
        print(json.dumps(m, default=float))
        return 0
    print(m["verdict"])
    print(f"report: {(args.out / 'index.html').resolve()}")
    return 0


def register(sub) -> None:
    p = sub.add_parser("compare", help="coarse-grain DEM runs, predict them from mu(I) (independent or fitted), "
                                       "write the report")
    p.add_argument("runs", type=Path, nargs="*", metavar="RUN_DIR", help="run folders of granstokes dem run")
    p.add_argument("--tables", type=Path, help="instead of run folders: the tables folder of an earlier report "
                                               "(REPORT_DIR/tables: its DEM side, no dumps needed)")
    p.add_argument("--out", type=Path, required=True, help="report folder (index.html, CSV, metrics.json)")
    p.add_argument("--calibration", type=Path, help="calibration.json of granstokes dem calibrate (same grains): "
                                                    "mu(I) and phi from it, the drives a blind test (required "
                                                    "unless --fit-on-drives)")
    p.add_argument("--fit-on-drives", action="store_true",
                   help="fit mu(I) on the drives' own steady windows instead: a restatement, every row labelled not "
                        "blind and never counted as support for a model")
    p.add_argument("--ngf-from", type=Path, help="oscillating drives: a Stokes report's metrics.json whose NGF "
                                                 "amplitude A (fitted on a Stokes drive of the same grains) predicts "
                                                 "them (else no NGF rows)")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                   help="processes predicting and scoring the drives (default: the machine's cores)")
    p.add_argument("--json", action="store_true", help="also print metrics.json to stdout")
    p.set_defaults(func=run_compare)
