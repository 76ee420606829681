"""Which scenes reach the growth laws' window, and at what cost: the design table of docs/study.md.

    .venv/bin/python bench/growth_windows.py [--out bench/growth_windows.csv]

For the committed grains (the disks' calibration at p = 20, the spheres' at p = 10: their mu(I), phi and measured
shear-wave speed c_s), one imposed-stress drive per (p_w, mu~_w) planned as a study plans it (dem.sizing: depth
delta_s + the larger of BASE_CLEARANCE delta_s and 5 creep lengths, the box's preset width), its growth window as the
comparison will take it (compare.laws.growth_bounds from 3 transits at the measured c_s to min(t_s/2, half the
record)) and the DEM cost of one bed at this machine's probed speed (dem.throughput, one rank): with the record the
study runs (10 t_s, every law) and with a record of GROWTH_RECORD t_s, enough for the window (the growth laws alone;
the steady laws need the long one). A power law is fitted over at least compare.laws.MIN_DECADES. Prints the markdown
table and writes a CSV.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import pandas as pd
from granstokes.compare.laws import MIN_DECADES
from granstokes.compare.stokes_experiment import planned_window
from granstokes.dem.calibrate import material_table
from granstokes.dem.throughput import measured

from granstokes.study import config
from granstokes.study.plan import plan_study

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent
#: the grains and the calibration whose material and c_s size them
GRAINS = {"disks": ("quick", ROOT / "results/calibration-disks/p20/calibration.json"),
          "spheres": ("spheres", ROOT / "results/calibration-spheres/p10/calibration.json")}
PRESSURES = (5.0, 10.0, 20.0, 40.0, 80.0)
MU_TILDES = (0.1, 0.3, 0.6)
#: the study's record (every law) and one long enough for the growth window alone, in t_s
FULL_RECORD, GROWTH_RECORD = 10.0, 1.0


def rows(name: str) -> list[dict]:
    dem, calibration = GRAINS[name]
    material = material_table(calibration)[0]
    c_s = float(json.loads(calibration.read_text())["elasticity"]["c_s"])
    speed, out = measured(), []
    for p_w in PRESSURES:
        for mt in MU_TILDES:
            study = config.from_dict({"name": "design", "dem": dem, "seeds": [1], "pressures": [p_w],
                                      "calibration": {"file": str(calibration)}, "width_check": False,
                                      "drive": [{"kind": "stress", "mu_w_tilde": mt}]})
            p = next(iter(plan_study(study, material, str(calibration)).runs.values())).plan
            d = p.drives[0]
            start, end, decades = planned_window(p, d, c_s)
            drive_s = p.stage_seconds(f"seed-1/{d.drive.name}", speed)
            prepare_s = p.stage_seconds("seed-1", speed)
            out.append({"grains": name, "p_w": p_w, "mu_w_tilde": mt, "delta_s": d.scales.delta_s,
                        "t_s": d.scales.t_s, "depth": p.depth, "n_grains": p.n_grains, "transit": p.depth / c_s,
                        "t_s_transits": d.scales.t_s * c_s / p.depth, "window_start": start, "window_end": end,
                        "decades": decades, "bed_s_full": prepare_s + drive_s,
                        "bed_s_growth": prepare_s + drive_s * GROWTH_RECORD / FULL_RECORD, "c_s": c_s})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(HERE / "growth_windows.csv"))
    args = ap.parse_args()
    table = pd.DataFrame([r for name in GRAINS for r in rows(name)])
    table.to_csv(args.out, index=False, float_format="%.4g")
    print(f"| grains | p_w | μ̃_w | δ_s [d] | t_s | depth [d] | grains | t_s in transits | window (3 transits to "
          f"t_s/2) | decades (≥ {MIN_DECADES:g}) | one bed, 10 t_s | one bed, {GROWTH_RECORD:g} t_s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in table.itertuples():
        window = f"[{r.window_start:.3g}, {r.window_end:.3g}]" if r.decades > -1e9 else "none"
        decades = f"{r.decades:.2f}" if r.decades > -1e9 else "—"
        print(f"| {r.grains} | {r.p_w:g} | {r.mu_w_tilde:g} | {r.delta_s:.1f} | {r.t_s:.3g} | {r.depth:g} | "
              f"{r.n_grains} | {r.t_s_transits:.3g} | {window} | {decades} | {r.bed_s_full / 60:.3g} min | "
              f"{r.bed_s_growth / 60:.3g} min |")


if __name__ == "__main__":
    main()
