"""The model side of a study's comparison, timed: every drive x model (the prediction, the calibration's
replicates through each steady state, the linearised bands), in one process and in forked processes
(compare.comparison.model_drive over compare.experiment.map_drives), on the committed disks study.

The DEM side is not recomputed (the study's dumps are not committed): each drive is rebuilt from the study's
committed tables (its series, its steady profile, its scene from the study's plan at the committed
calibration), which is all the model side reads.  Both job counts run the same drives in the same process,
alternating, so that the machine's load cancels in the ratio.

    .venv/bin/python bench/compare_cost.py [--study results/study-disks] [--calibrations results/calibration-disks]
"""
from __future__ import annotations

import argparse
import json
import math
import os
import time
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.compare.analysis import DriveAnalysis, snapshot_times
from granstokes.compare.calibrate import load as load_calibration
from granstokes.compare.comparison import REPLICATES, ModelSide, material_at, model_drive, replicates_of
from granstokes.compare.drive import DriveSpec
from granstokes.compare.experiment import map_drives
from granstokes.compare.nonlocal_fit import A_RANGE
from granstokes.compare.report import display_label, slug
from granstokes.continuum import ngf
from granstokes.continuum.scene_models import LOCAL, PAPER, ngf_model
from granstokes.dem.calibrate import material_table
from granstokes.dem.scene import plate_geometry

from granstokes.study.config import parse
from granstokes.study.plan import plan_study

ROOT = Path(__file__).resolve().parents[1]


def drives_of(folder: Path, calibrations: Path) -> tuple[list[DriveAnalysis], ModelSide]:
    """The committed study's drives as the model side sees them, and the side (calibration, models)."""
    meta = json.loads((folder / "metrics.json").read_text())
    study = parse((folder / "study.toml").read_text())
    calibration = calibrations / f"p{max(study.calibration_pressures):g}" / "calibration.json"
    material, _, _ = material_table(calibration)
    sp = plan_study(study, material, str(calibration))
    cal = load_calibration(calibration)
    labels = list(meta["drives"])
    drives = []
    for label in labels:
        run, name = label.rsplit("/", 1)
        plan = sp.runs[Path(run).name].plan
        dp = next(d for d in plan.drives if d.drive.name == name)
        plate = plate_geometry(plan)
        record = meta["drives"][label]
        spec = DriveSpec(Path(run), name, dp.load, plan.depth, plate["mass_per_area"], plate["surface_offset"],
                         dp.steps, record["elastic_start"]["transit_time"], record["seeds"], plan.n_grains,
                         plan.dimension)
        stem = slug(display_label(label, labels))
        series = pd.read_csv(folder / f"series_{stem}.csv")
        steady = pd.read_csv(folder / f"steady_profile_{stem}.csv")
        plate_values = {k[:-4]: {"value": record[k]["dem"], "stderr": record[k]["dem_err"],
                                 "method": record[k]["dem_how"]} for k in ("u_w_inf", "mu_w_inf") if k in record}
        drives.append(DriveAnalysis(spec, (), (), series, plate_values, record["t_window"], record["duration"], {},
                                    {}, steady, steady, steady, pd.DataFrame(), snapshot_times(series.t), (steady,),
                                    "the committed steady profile (timing only)", record["frames"], 0,
                                    pd.DataFrame()))
    ngf = meta["ngf"]
    replicates = replicates_of(cal, cal.replicates["phi_max"])
    rng = np.random.default_rng(1)
    replicates = replicates.assign(A=np.clip(rng.normal(ngf["A"], ngf["A_err"], len(replicates)), *A_RANGE))
    models = (LOCAL, PAPER, ngf_model(ngf["A"]))
    return drives, ModelSide(cal.material(), models, "", replicates, {"ngf": ngf["fitted_on"]}, True)


def chebyshev_cache(drives: list[DriveAnalysis], side: ModelSide, n: int = 50) -> dict:
    """CPU seconds of ``n`` replicates' NGF steady states of the first imposed-speed drive, with the Chebyshev
    matrices cached (continuum.ngf._cheb_reference) and rebuilt on every call, alternating."""
    a = next(d for d in drives if d.spec.kind == "speed")
    ngf_side = side.models[-1]
    reps = side.replicates.head(n)
    out = {"cached": [], "rebuilt": []}
    for _ in range(2):
        for mode in out:
            t0 = time.process_time()
            for _, r in reps.iterrows():
                if mode == "rebuilt":
                    ngf._cheb_reference.cache_clear()
                ngf_side.at(r).steady(material_at(side.material, r), a.spec.scene, a.spec.load)
            out[mode].append(time.process_time() - t0)
    return {"drive": a.label, "solves": n, **{k: min(v) for k, v in out.items()},
            "speedup": min(out["rebuilt"]) / min(out["cached"])}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", type=Path, default=ROOT / "results" / "study-disks")
    ap.add_argument("--calibrations", type=Path, default=ROOT / "results" / "calibration-disks",
                    help="the study's calibrations, one folder per pressure (pP/calibration.json)")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "compare_cost.json")
    args = ap.parse_args()
    drives, side = drives_of(args.study, args.calibrations)
    jobs = os.cpu_count() or 1
    times = {1: [], jobs: []}
    rows = {}
    for _ in range(args.repeats):
        for n in (1, jobs):
            t0 = time.perf_counter()
            out = map_drives(lambda a: model_drive(a, side), drives, jobs=n, progress=False)
            times[n].append(time.perf_counter() - t0)
            rows[n] = pd.concat([r[1] for r in out if len(r[1])], ignore_index=True)
            print(f"{n} process(es): {times[n][-1]:.1f} s", flush=True)
    cache = chebyshev_cache(drives, side)
    print(f"NGF steady states, Chebyshev matrices cached: {cache['speedup']:.2f}x", flush=True)
    same = bool(np.allclose(rows[1].predicted, rows[jobs].predicted, equal_nan=True))
    result = {"study": str(args.study.relative_to(ROOT)), "drives": len(drives),
              "models": [m.key for m in side.models], "replicates": len(side.replicates), "max_replicates": REPLICATES,
              "rows": len(rows[1]), "seconds": {str(k): min(v) for k, v in times.items()},
              "speedup": min(times[1]) / min(times[jobs]), "same_rows": same,
              "chebyshev_cache": cache, "load": os.getloadavg()[0]}
    args.out.write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))
    if not (same and math.isfinite(result["speedup"])):
        raise SystemExit("the forked processes gave other rows than one process")


if __name__ == "__main__":
    main()
