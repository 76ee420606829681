"""DEM cost against noise: statistical error of u_w_inf and delta_s against grains x steps, for
scene sizes, 2D/3D and ensemble sizes (the smoke scene and its variants), all run in one process.

    .venv/bin/python bench/dem_cost_noise.py [--out /tmp/granstokes-cost]

Writes bench/dem_cost_noise.{csv,png} and prints the table for bench/RESULTS.md.  Each variant is
analysed on its own (compare.analysis.analyse_drive: plate record, steady window, delta_u); no
calibration is pooled across 2D and 3D.
"""
from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from compare.analysis import analyse_drive, drive_specs
from compare.plate import STEADY_WINDOW_LATEST
from compare.profiles import CGSettings
from dem import config
from dem.runner import run

HERE = Path(__file__).parent
SMOKE = config.preset_text("smoke")
VARIANTS = {
    "2D, 40 d wide, 1 seed": SMOKE,
    "2D, 40 d wide, 3 seeds": SMOKE.replace("seeds = [1]", "seeds = [1, 2, 3]"),
    "2D, 80 d wide, 1 seed": SMOKE.replace("width = 40.0", "width = 80.0"),
    "3D, 12 x 6 d, 1 seed": re.sub(r"dimension = 2", "dimension = 3", SMOKE).replace(
        "width = 40.0", "width = 12.0\nwidth_z = 6.0"),
}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", type=Path, default=Path("/tmp/granstokes-cost"))
    args = parser.parse_args()
    rows = []
    for name, text in VARIANTS.items():
        folder = args.out / re.sub(r"\W+", "_", name)
        if not (folder / "run.json").exists() or '"status": "complete"' not in (folder / "run.json").read_text():
            cfg = config.parse(text)
            result = run(cfg, text, folder, np=2, resume=(folder / "run.json").exists(), progress=False)
            if result.status != "complete":
                raise RuntimeError(f"{name}: {result.status} {result.message}")
        stages = json.loads((folder / "run.json").read_text())["stages"].values()
        wall = sum(st["wall_time"] for st in stages)  # LAMMPS wall time of every stage of the run
        (spec,) = drive_specs(folder)
        g = analyse_drive(spec, CGSettings())
        late = g.delta[g.delta.t >= STEADY_WINDOW_LATEST * g.delta.t.max()].delta_u
        rows.append({"variant": name, "grains": len(spec.folders[0].grains), "seeds": len(spec.folders),
                     "grains_x_steps": spec.cost, "wall_s": wall, "stderr_over": g.steady["u_w"]["method"], "u_w_inf": g.steady["u_w"]["value"],
                     "rel_stderr_u_w_inf": g.steady["u_w"]["stderr"] / g.steady["u_w"]["value"],
                     "delta_s": late.mean(), "rel_stderr_delta_s": late.std(ddof=1) / np.sqrt(len(late)) / late.mean()})
    df = pd.DataFrame(rows)
    df.to_csv(HERE / "dem_cost_noise.csv", index=False)
    fig = Figure(figsize=(7, 4.5), layout="constrained")
    ax = fig.subplots()
    for _, r in df.iterrows():
        ax.loglog(r.grains_x_steps, r.rel_stderr_u_w_inf, "o", label=f"u_w_inf, {r.variant}")
        ax.loglog(r.grains_x_steps, r.rel_stderr_delta_s, "s", mfc="none", label=f"delta_s, {r.variant}")
    x = np.array([df.grains_x_steps.min(), df.grains_x_steps.max()])
    ax.loglog(x, df.rel_stderr_u_w_inf.iloc[0] * np.sqrt(x[0] / x), "k:", label="~ (grains x steps)^-1/2")
    ax.set(xlabel="grains x steps (x seeds)", ylabel="relative standard error",
           title="DEM cost vs noise (smoke scene variants)")
    ax.legend(fontsize=6)
    fig.savefig(HERE / "dem_cost_noise.png", dpi=120)
    print("| variant | grains | seeds | grains x steps | wall [s] | u_w_inf | rel. stderr (over) | delta_s [d] | rel. stderr |")
    print("|---|---|---|---|---|---|---|---|---|")
    for _, r in df.iterrows():
        print(f"| {r.variant} | {r.grains} | {r.seeds} | {r.grains_x_steps:.3g} | {r.wall_s:.0f} | {r.u_w_inf:.3g} | "
              f"{r.rel_stderr_u_w_inf:.2%} ({r.stderr_over}) | {r.delta_s:.3g} | {r.rel_stderr_delta_s:.2%} |")


if __name__ == "__main__":
    main()
