"""``granstokes compare (RUN_DIR... | --tables REPORT_DIR/tables [--tables ...]) --out REPORT_DIR [--calibration
DIR/calibration.json] [--fit-on-drives] [--ngf-from METRICS.json] [--jobs N] [--json]``: the experiment of the runs'
drives (compare.experiment's registry: Stokes' first problem or the oscillating plate) from the runs or from
earlier reports' tables (several: a study run in parts, their drives together), written as a report."""
from __future__ import annotations

import json
import os
from pathlib import Path

from granstokes.lib.staging import claim, staged
from granstokes.lib.validate import require

COMMAND = "compare"


def run_compare(args) -> int:
    from granstokes.dem.layout import RUN_JSON

    from .experiment import experiment_for_runs, experiment_for_tables

    require(args.jobs >= 1, "--jobs", "an integer >= 1 (processes predicting the drives)", args.jobs)
    require(bool(args.runs) != bool(args.tables), "--tables or RUN_DIR",
            "either run folders or tables folders of earlier reports", "both" if args.runs else "neither")
    for run in args.runs:
        require((run / RUN_JSON).is_file(), "RUN_DIR", "a folder written by granstokes dem run (with run.json)",
                str(run))
    kinds = {experiment_for_tables(t) for t in args.tables} if args.tables else {experiment_for_runs(args.runs)}
    require(len(kinds) == 1, "--tables", "tables folders of one experiment", sorted(k.name for k in kinds))
    kind = kinds.pop()
    sources = args.runs or args.tables
    inputs = [*sources, *([args.calibration] if args.calibration is not None else [])]
    claim(args.out, "--out", COMMAND, inputs)
    options = {k: v for k, v in (("fit_on_drives", args.fit_on_drives), ("ngf_from", args.ngf_from),
                                 ("any_pair_style", args.any_pair_style)) if v}
    experiment = kind.create(args.calibration, jobs=args.jobs, **options)  # every option checked before any work
    dem = experiment.read_parts(args.tables) if args.tables else experiment.analyse(args.runs)
    result = experiment.run(dem)
    with staged(args.out, COMMAND, inputs) as work:
        m = experiment.write(result, work)
    if args.json:
        print(json.dumps(m, default=float))
        return 0
    print(m["verdict"])
    shared = m["tally"]
    if shared:
        print("\n".join(f"{t['model']}: consistent on {t['consistent']} of {t['n']} shared rows (median |sigma| "
                        f"{t['median_abs_sigma']:.2f})" for t in shared))
    print(f"report: {(args.out / 'index.html').resolve()}")
    return 0


def register(sub) -> None:
    p = sub.add_parser("compare", help="coarse-grain DEM runs, predict them from mu(I) (independent or fitted), "
                                       "write the report")
    p.add_argument("runs", type=Path, nargs="*", metavar="RUN_DIR", help="run folders of granstokes dem run")
    p.add_argument("--tables", type=Path, action="append", default=[],
                   help="instead of run folders: the tables folder of an earlier report (REPORT_DIR/tables: its DEM "
                        "side, no dumps needed); repeat it for a study run in parts (their drives together)")
    p.add_argument("--out", type=Path, required=True, help="report folder (index.html, CSV, metrics.json)")
    p.add_argument("--calibration", type=Path, help="calibration.json of granstokes dem calibrate (same grains): "
                                                    "mu(I) and phi from it, the drives a blind test (required "
                                                    "unless --fit-on-drives)")
    p.add_argument("--fit-on-drives", action="store_true",
                   help="fit mu(I) on the drives' own steady windows instead: a restatement, every row labelled not "
                        "blind and never counted as support for a model")
    p.add_argument("--any-pair-style", action="store_true",
                   help="accept a --calibration run in the other LAMMPS pair style of the same contact law "
                        "(gran/hooke/history or pair granular; the grains otherwise the runs'): the two styles' "
                        "drives compared like for like; the report says so")
    p.add_argument("--ngf-from", type=Path, help="oscillating drives: a Stokes report's metrics.json whose NGF "
                                                 "amplitude A (fitted on a Stokes drive of the same grains) predicts "
                                                 "them (else no NGF rows)")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                   help="processes predicting and scoring the drives (default: the machine's cores)")
    p.add_argument("--json", action="store_true", help="also print metrics.json to stdout")
    p.set_defaults(func=run_compare)
