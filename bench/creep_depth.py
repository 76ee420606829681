"""Does the creep below the flowing layer have a length of its own?  One drive at several bed depths.

    .venv/bin/python bench/creep_depth.py --out DIR [--depths 26 39 52 78] [--seeds 1 2] [--resume]

The disks study's grains (the quick preset, k_n = 2e5) at p_w = 10 under the imposed stress mu~_w = 0.45, sized from
the committed calibration at p = 20, 10 t_s, in beds of each depth (``box.depth``); each run compared with that
calibration (``granstokes compare``), and from its report the DEM's creep length (the e-folding length of u below
delta_s, over compare.scorecard's fixed zone, and fitted from delta_s down to the base), the steady layer delta_u (u =
5 % of u_w), the steady plate speed, t90 and the slip, each with its error over the beds. A creep length the flow sets
does not change with the depth; one the base sets grows with it. ``--resume`` keeps each depth's run and report
already in DIR. Writes bench/creep_depth.csv and prints the table for bench/RESULTS.md (the scene rule it supports:
dem.sizing.BASE_CLEARANCE).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.compare.calibrate import WALL_EXCLUSION
from granstokes.compare.tables import read_drive
from scipy import stats

HERE = Path(__file__).resolve().parent
CALIBRATION = HERE.parent / "results" / "calibration-disks" / "p20" / "calibration.json"
#: the drive: the 2D study's p_w = 10 stress drive at mu~_w = 0.45, its grains (k_n = 2e5: kappa 2e4 at p = 10)
SETTINGS = ["load.p_w=10.0", "grains.kappa=20000.0",
            'drive=[{name = "stress-mutilde0.45", kind = "stress", mu_w_tilde = 0.45, duration_ts = 10.0}]']


def granstokes(*args: str) -> None:
    subprocess.run([sys.executable, "-m", "granstokes.cli", *args], check=True, capture_output=True, text=True)


def to_base_lengths(tables: Path, delta_s: float) -> np.ndarray:
    """Each bed's e-folding length of u fitted from delta_s down to WALL_EXCLUSION above the base (least squares of
    ln u): the estimator before the fixed zones of compare.scorecard.CREEP_ZONES, whose growth with the depth they
    remove."""
    a = read_drive(tables)
    lengths = []
    for s in a.samples:
        zone = (s.depth >= delta_s) & (s.depth <= a.spec.depth - WALL_EXCLUSION) & (s.u_x > 0)
        lengths.append(-1 / stats.linregress(s.depth[zone], np.log(s.u_x[zone])).slope)
    return np.array(lengths)


def measure(out: Path, depth: float, seeds: list[int], resume: bool) -> dict:
    run, report = out / f"d{depth:g}", out / f"report-d{depth:g}"
    sets = [*SETTINGS, f"seeds={seeds}", f"box.depth={depth}"]
    if not (resume and (report / "metrics.json").is_file()):
        granstokes("dem", "run", "--preset", "quick", "--calibration", str(CALIBRATION), "--out", str(run), "--quiet",
                   *(x for s in sets for x in ("--set", s)), *(["--resume"] if resume and run.is_dir() else []))
        granstokes("compare", str(run), "--calibration", str(CALIBRATION), "--out", str(report), "--jobs", "1")
    m = json.loads((report / "metrics.json").read_text())
    rows = pd.DataFrame(m["scorecard"]).query("model == 'local'").set_index("observable")
    drive = next(iter(m["drives"].values()))
    to_base = to_base_lengths(next((report / "tables").glob("drive*")), drive["delta_s"])
    return {"depth": depth, "beds": len(seeds), "delta_s": drive["delta_s"],
            "creep_length": rows.loc["creep_length", "dem"], "creep_length_err": rows.loc["creep_length", "dem_err"],
            "creep_to_base": to_base.mean(), "creep_to_base_err": to_base.std(ddof=1) / np.sqrt(len(to_base)),
            "delta_u": rows.loc["delta_u", "dem"], "delta_u_err": rows.loc["delta_u", "dem_err"],
            "t90": rows.loc["t90", "dem"], "t90_err": rows.loc["t90", "dem_err"],
            "u_w_inf": drive["u_w_inf"]["dem"], "u_w_inf_err": drive["u_w_inf"]["dem_err"], "slip": drive["slip"]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="scratch folder for the runs and their reports")
    ap.add_argument("--depths", type=float, nargs="+", default=[26.0, 39.0, 52.0, 78.0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--resume", action="store_true", help="keep the runs and reports already in --out")
    args = ap.parse_args()
    table = pd.DataFrame([measure(args.out, d, args.seeds, args.resume) for d in args.depths])
    table.to_csv(HERE / "creep_depth.csv", index=False, float_format="%.4g")
    print("| bed depth [d] | beds | clearance below δ_s [δ_s] | creep length, δ_s to the base [d] | creep length, "
          "first 3 d [d] | δ_u (5 %) [d] | u_w∞ [√(g d)] | t90 [√(d/g)] | slip |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in table.itertuples():
        print(f"| {r.depth:g} | {r.beds} | {(r.depth - r.delta_s) / r.delta_s:.2f} | {r.creep_to_base:.2f} ± "
              f"{r.creep_to_base_err:.2f} | {r.creep_length:.2f} ± "
              f"{r.creep_length_err:.2f} | {r.delta_u:.2f} ± {r.delta_u_err:.2f} | {r.u_w_inf:.2f} ± "
              f"{r.u_w_inf_err:.2f} | {r.t90:.1f} ± {r.t90_err:.1f} | {100 * r.slip:.1f} % |")
    dof = len(table) - 2
    for key in ("creep_to_base", "creep_length", "delta_u", "u_w_inf", "t90"):
        slope, err, chi2_dof = depth_slope(table, key)
        p = stats.chi2.sf(chi2_dof * dof, dof)
        print(f"{key}: slope against the depth {slope:.3g} ± {err:.2g} per d (t = {slope / err:.2f}; 95 % at {dof} "
              f"dof: {stats.t.ppf(0.975, dof):.2f}; chi2/dof {chi2_dof:.2g}, p = {p:.2g})")


def depth_slope(table: pd.DataFrame, key: str) -> tuple[float, float, float]:
    """The weighted line of ``key`` against the bed's depth (weights 1/err): its slope, the slope's error scaled by
    sqrt(chi2/dof) where the depths scatter beyond their errors (as compare.laws' lines), and chi2/dof."""
    coef, cov = np.polyfit(table.depth, table[key], 1, w=1 / table[f"{key}_err"], cov="unscaled")
    residual = (table[key] - np.polyval(coef, table.depth)) / table[f"{key}_err"]
    chi2_dof = float(np.sum(residual**2)) / (len(table) - 2)
    return float(coef[0]), float(np.sqrt(cov[0, 0] * max(1.0, chi2_dof))), chi2_dof


if __name__ == "__main__":
    main()
