"""Does the creep below the flowing layer have a length of its own?  One drive at several bed depths.

    .venv/bin/python bench/creep_depth.py --out DIR [--depths 26 39 52 78] [--seeds 1 2]

The disks study's grains (the quick preset, k_n = 2e5) at p_w = 10 under the imposed stress mu~_w = 0.45, sized from
the committed calibration at p = 20, 10 t_s, in beds of each depth (``box.depth``); each run compared with that
calibration (``granstokes compare``), and from its report the DEM's creep length (the e-folding length of u below
delta_s, compare.scorecard), the steady layer delta_u (u = 5 % of u_w), the steady plate speed and the slip, each with
its error over the beds.  A creep length the flow sets does not change with the depth; one the base sets grows with
it.  Writes bench/creep_depth.csv and prints the table for bench/RESULTS.md.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import pandas as pd

HERE = Path(__file__).resolve().parent
CALIBRATION = HERE.parent / "results" / "calibration-disks" / "p20" / "calibration.json"
#: the drive: the 2D study's p_w = 10 stress drive at mu~_w = 0.45, its grains (k_n = 2e5: kappa 2e4 at p = 10)
SETTINGS = ["load.p_w=10.0", "grains.kappa=20000.0",
            'drive=[{name = "stress-mutilde0.45", kind = "stress", mu_w_tilde = 0.45, duration_ts = 10.0}]']


def granstokes(*args: str) -> None:
    subprocess.run([sys.executable, "-m", "granstokes.cli", *args], check=True, capture_output=True, text=True)


def measure(out: Path, depth: float, seeds: list[int]) -> dict:
    run, report = out / f"d{depth:g}", out / f"report-d{depth:g}"
    sets = [*SETTINGS, f"seeds={seeds}", f"box.depth={depth}"]
    granstokes("dem", "run", "--preset", "quick", "--calibration", str(CALIBRATION), "--out", str(run), "--quiet",
               *(x for s in sets for x in ("--set", s)))
    granstokes("compare", str(run), "--calibration", str(CALIBRATION), "--out", str(report), "--jobs", "1")
    m = json.loads((report / "metrics.json").read_text())
    rows = pd.DataFrame(m["scorecard"]).query("model == 'local'").set_index("observable")
    drive = next(iter(m["drives"].values()))
    return {"depth": depth, "beds": len(seeds), "delta_s": drive["delta_s"],
            "creep_length": rows.loc["creep_length", "dem"], "creep_length_err": rows.loc["creep_length", "dem_err"],
            "delta_u": rows.loc["delta_u", "dem"], "delta_u_err": rows.loc["delta_u", "dem_err"],
            "u_w_inf": drive["u_w_inf"]["dem"], "u_w_inf_err": drive["u_w_inf"]["dem_err"], "slip": drive["slip"]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="scratch folder for the runs and their reports")
    ap.add_argument("--depths", type=float, nargs="+", default=[26.0, 39.0, 52.0, 78.0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    table = pd.DataFrame([measure(args.out, d, args.seeds) for d in args.depths])
    table.to_csv(HERE / "creep_depth.csv", index=False, float_format="%.4g")
    print("| bed depth [d] | beds | creep length [d] | δ_u (5 %) [d] | u_w∞ [√(g d)] | slip |")
    print("|---|---|---|---|---|---|")
    for r in table.itertuples():
        print(f"| {r.depth:g} | {r.beds} | {r.creep_length:.2f} ± {r.creep_length_err:.2f} | {r.delta_u:.2f} ± "
              f"{r.delta_u_err:.2f} | {r.u_w_inf:.2f} ± {r.u_w_inf_err:.2f} | {100 * r.slip:.1f} % |")


if __name__ == "__main__":
    main()
