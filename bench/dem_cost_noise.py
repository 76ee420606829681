"""DEM cost against noise: statistical error of u_w_inf and delta_s against grains x steps, for
scene sizes, 2D/3D and ensemble sizes (the smoke scene and its variants), all run in one process.

    .venv/bin/python bench/dem_cost_noise.py [--out /tmp/granstokes-cost]
    .venv/bin/python bench/dem_cost_noise.py --plot-only     # redraw the PNG from the committed CSV

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
from granstokes.compare.analysis import analyse_drive, drive_specs
from granstokes.compare.plate import STEADY_WINDOW_LATEST
from granstokes.compare.profiles import CGSettings
from granstokes.dem import config
from granstokes.dem.runner import run
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import LogFormatter

HERE = Path(__file__).parent
SMOKE = config.preset_text("smoke")
VARIANTS = {
    "2D, 40 d wide, 1 seed": SMOKE,
    "2D, 40 d wide, 3 seeds": SMOKE.replace("seeds = [1]", "seeds = [1, 2, 3]"),
    "2D, 80 d wide, 1 seed": SMOKE.replace("width = 40.0", "width = 80.0"),
    "3D, 12 x 6 d, 1 seed": re.sub(r"dimension = 2", "dimension = 3", SMOKE).replace(
        "width = 40.0", "width = 12.0\nwidth_z = 6.0"),
}


def plot(df: pd.DataFrame, path: Path) -> Path:
    """Relative standard error against grains x steps x seeds: colour per variant, marker per observable;
    the 1/sqrt(work) line through the first variant's u_w_inf; the legend below the axes."""
    fig = Figure(figsize=(7.5, 5.2), layout="constrained")
    ax = fig.subplots()
    markers = {"rel_stderr_u_w_inf": ("o", "full", "u_w_inf (steady plate speed)"),
               "rel_stderr_delta_s": ("s", "none", "delta_s (late delta_u)")}
    for k, r in enumerate(df.itertuples()):
        for col, (marker, fill, _) in markers.items():
            ax.plot(r.grains_x_steps, 100 * getattr(r, col), marker, ms=8, color=f"C{k}", fillstyle=fill, mew=1.5)
    x = np.geomspace(df.grains_x_steps.min(), df.grains_x_steps.max(), 20)
    ax.plot(x, 100 * df.rel_stderr_u_w_inf.iloc[0] * np.sqrt(x[0] / x), "k:", lw=1)
    ax.set(xscale="log", yscale="log", xlabel="DEM work: grains x steps x seeds",
           ylabel="relative standard error [%]")
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_minor_formatter(LogFormatter(labelOnlyBase=False))
        axis.set_major_formatter(LogFormatter())
    handles = [Line2D([], [], color=f"C{k}", marker="o", ls="none", ms=7,
                      label=f"{r.variant} ({r.stderr_over.replace('blocks of the final quarter', 'blocks')})")
               for k, r in enumerate(df.itertuples())]
    handles += [Line2D([], [], color="k", marker=m, fillstyle=f, ls="none", ms=7, label=label)
                for m, f, label in markers.values()]
    handles += [Line2D([], [], color="k", ls=":", label="~ (work)^-1/2 through the first u_w_inf")]
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=8, frameon=False)
    fig.suptitle("DEM cost vs noise: smoke-scene variants (2D disks, 3D spheres; DEM units)", fontsize=11)
    fig.savefig(path, dpi=120)
    return path


def measure(out: Path) -> pd.DataFrame:
    """Run (or resume) every variant under ``out`` and analyse it."""
    rows = []
    for name, text in VARIANTS.items():
        folder = out / re.sub(r"\W+", "_", name)
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
                     "grains_x_steps": spec.cost, "wall_s": wall, "stderr_over": g.steady["u_w"]["method"],
                     "u_w_inf": g.steady["u_w"]["value"],
                     "rel_stderr_u_w_inf": g.steady["u_w"]["stderr"] / g.steady["u_w"]["value"],
                     "delta_s": late.mean(), "rel_stderr_delta_s": late.std(ddof=1) / np.sqrt(len(late)) / late.mean()})
    return pd.DataFrame(rows)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", type=Path, default=Path("/tmp/granstokes-cost"))
    parser.add_argument("--plot-only", action="store_true", help="redraw the PNG from bench/dem_cost_noise.csv")
    args = parser.parse_args()
    if args.plot_only:
        df = pd.read_csv(HERE / "dem_cost_noise.csv")
    else:
        df = measure(args.out)
        df.to_csv(HERE / "dem_cost_noise.csv", index=False)
    plot(df, HERE / "dem_cost_noise.png")
    print("| variant | grains | seeds | grains x steps | wall [s] | u_w_inf | rel. stderr (over) | delta_s [d] "
          "| rel. stderr |")
    print("|---|---|---|---|---|---|---|---|---|")
    for _, r in df.iterrows():
        print(f"| {r.variant} | {r.grains} | {r.seeds} | {r.grains_x_steps:.3g} | {r.wall_s:.0f} | {r.u_w_inf:.3g} | "
              f"{r.rel_stderr_u_w_inf:.2%} ({r.stderr_over}) | {r.delta_s:.3g} | {r.rel_stderr_delta_s:.2%} |")


if __name__ == "__main__":
    main()
