"""A comparison's DEM side as tables: everything the comparison takes from the dumps, written beside its report
(``tables/``, a few hundred kB per drive) and read back instead of them, so that a committed study is compared
again, under any calibration or model, without its dumps (compare.comparison.DemSide).

Layout: ``dem.json`` (the runs, their grains, the mass error, the checks' drive, one folder per drive),
``checks_width.csv`` and ``checks_crosscheck.csv`` (compare.checks on the first drive), and per drive
``drive.json`` (its scene, record, window, snapshot times, frames, the bulk-stress check), ``plates.csv.gz``
(every seed's plate record), ``samples.csv.gz`` (the independent steady-window profiles: depth, u_x),
``steady_profile.csv.gz``, ``mean_profile.csv.gz``, ``instant.csv.gz`` (the snapshots), ``delta.csv`` and
``layers.csv.gz`` (every seed's layer over time: compare.analysis.layer_series).
Reading recomputes what the plate records give (the ensemble series, the steady values and their errors,
the slip: compare.analysis.plate_estimates); the coarse-grained profiles are read as written.  DEM units.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from granstokes.lib.validate import require

from .analysis import DriveAnalysis, plate_estimates
from .comparison import Checks, DemSide
from .drive import DriveSpec
from .plate import PlateRecord

#: floats in every table: six significant digits (far below the DEM's errors)
CSV_FLOAT = "%.6g"
#: gzip without a timestamp: a table written again from the same data is the same bytes
GZIP = {"method": "gzip", "mtime": 0}
DEM_JSON = "dem.json"
PLATE_COLUMNS = ("t", "u_w", "tau_w", "p", "y", "u_c", "n_c")
#: what the steady-window samples keep: the estimators of compare.scorecard and compare.nonlocal_fit read u_x(depth)
SAMPLE_COLUMNS = ("depth", "y", "u_x")
UNITS = "DEM units: d = rho_p = g = 1; p, tau in rho_p g d, u in sqrt(g d), t in sqrt(d/g)"


def write_csv(table: pd.DataFrame, path: Path, float_format: str = CSV_FLOAT) -> None:
    """``table`` at ``path`` (gzip-compressed, without a timestamp, when it ends in .gz)."""
    table.to_csv(path, index=False, float_format=float_format, compression=GZIP if path.suffix == ".gz" else None)


def _number(v) -> float:
    return np.nan if v is None else float(v)


def _json(v):
    """JSON-ready: numpy scalars and arrays to Python, non-finite numbers to None."""
    if isinstance(v, dict):
        return {k: _json(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_json(x) for x in v]
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (float, np.floating)):
        return float(v) if np.isfinite(v) else None
    if isinstance(v, np.integer):
        return int(v)
    return v


def write_drive(a: DriveAnalysis, folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    record = {"units": UNITS, "spec": a.spec.as_record(), "t_window": a.t_window, "t_end": a.t_end,
              "snapshots": a.snapshots, "samples_how": a.samples_how, "frames": a.frames,
              "dropped_frames": a.dropped_frames, "bulk_tau": a.bulk_tau}
    (folder / "drive.json").write_text(json.dumps(_json(record), indent=1))
    write_csv(pd.concat([pd.DataFrame({k: getattr(p, k) for k in PLATE_COLUMNS}).assign(seed=i)
                         for i, p in enumerate(a.plates)], ignore_index=True), folder / "plates.csv.gz")
    write_csv(pd.concat([s[list(SAMPLE_COLUMNS)].assign(sample=i) for i, s in enumerate(a.samples)],
                        ignore_index=True), folder / "samples.csv.gz")
    for name in ("steady_profile", "mean_profile", "instant"):
        write_csv(getattr(a, name), folder / f"{name}.csv.gz")
    write_csv(a.delta, folder / "delta.csv")
    write_csv(a.layers, folder / "layers.csv.gz")


def read_drive(folder: Path) -> DriveAnalysis:
    record = json.loads((folder / "drive.json").read_text())
    spec = DriveSpec.from_record(record["spec"])
    table = pd.read_csv(folder / "plates.csv.gz")
    plates = tuple(PlateRecord(*(g[k].to_numpy() for k in PLATE_COLUMNS)) for _, g in table.groupby("seed"))
    series, steady, slips = plate_estimates(plates, spec.kind)
    samples = tuple(g.drop(columns="sample").reset_index(drop=True)
                    for _, g in pd.read_csv(folder / "samples.csv.gz").groupby("sample"))
    profiles = {name: pd.read_csv(folder / f"{name}.csv.gz") for name in ("steady_profile", "mean_profile",
                                                                          "instant")}
    bulk = record["bulk_tau"]
    bulk["difference_stderr"] = _number(bulk["difference_stderr"])
    return DriveAnalysis(spec, plates, (), series, steady, record["t_window"], record["t_end"], slips, bulk,
                         profiles["steady_profile"], profiles["mean_profile"], profiles["instant"],
                         pd.read_csv(folder / "delta.csv"), np.asarray(record["snapshots"], dtype=float), samples,
                         record["samples_how"], record["frames"], record["dropped_frames"],
                         pd.read_csv(folder / "layers.csv.gz"))


def _folder(i: int, a: DriveAnalysis) -> str:
    return f"drive{i:02d}-{Path(a.spec.run).name}-{a.spec.name}"


def write(dem: DemSide, folder: Path) -> None:
    """The DEM side's tables into ``folder`` (created)."""
    folder.mkdir(parents=True, exist_ok=True)
    drives = [_folder(i, a) for i, a in enumerate(dem.drives)]
    for name, a in zip(drives, dem.drives):
        write_drive(a, folder / name)
    write_csv(dem.checks.width, folder / "checks_width.csv")
    write_csv(dem.checks.crosscheck, folder / "checks_crosscheck.csv")
    meta = {"units": UNITS, "runs": [str(r) for r in dem.runs],
            "grains": {run: {"grains": g, "p_w": p} for run, (g, p) in dem.grains.items()},
            "mass_error": dem.mass_error, "checks_drive": dem.checks.drive, "drives": drives}
    (folder / DEM_JSON).write_text(json.dumps(_json(meta), indent=1))


def read(folder: Path) -> DemSide:
    """The DEM side written by ``write`` (ValueError naming the folder when it is not one)."""
    folder = Path(folder)
    if not (folder / DEM_JSON).is_file():
        raise ValueError(f"{folder}: not a tables folder of granstokes compare (no {DEM_JSON})")
    meta = json.loads((folder / DEM_JSON).read_text())
    drives = tuple(read_drive(folder / name) for name in meta["drives"])
    first = next(a for a in drives if a.label == meta["checks_drive"])
    checks = Checks.of(meta["checks_drive"], pd.read_csv(folder / "checks_width.csv"),
                       pd.read_csv(folder / "checks_crosscheck.csv"), first.steady_profile.y)
    grains = {run: (g["grains"], _number(g["p_w"])) for run, g in meta["grains"].items()}
    return DemSide(tuple(Path(r) for r in meta["runs"]), grains, drives, checks, _number(meta["mass_error"]))


def merge(sides: list[DemSide]) -> DemSide:
    """Several DEM sides as one (a study run in parts, each part's tables read by ``read``): the runs, grains and
    drives of all, the coarse-graining checks and mass error of the first (ValueError naming --tables when a run
    appears in two parts)."""
    runs = [r for side in sides for r in side.runs]
    require(len({str(r) for r in runs}) == len(runs), "--tables", "tables of distinct runs (a study's parts)",
            [str(r) for r in runs])
    return DemSide(tuple(runs), {k: v for side in sides for k, v in side.grains.items()},
                   tuple(a for side in sides for a in side.drives), sides[0].checks, sides[0].mass_error)
