"""Velocity form (continuum.velocity) on the quick preset's two drives, as compare predicts them:
CPU time and error of u_w(t), mu_w(t), delta_u(t) (continuum.scene_models) and the velocity profiles, at the
comparison's output times, against a converged reference.  Writes bench/velocity_form.csv and prints
the table for bench/RESULTS.md.

    .venv/bin/python bench/velocity_form.py

Scene: dem/presets/quick.toml sized by dem.sizing (bed depth, drive values, durations), the plate's
mass per area from dem.scene; material from results/quick-calibration/calibration.json; times: the
comparison's log grid (compare.comparison) over the drive's duration.  Reference: stretch-2 meshes of
REFINE cells at rtol 1e-8, the order measured from the three, Richardson-extrapolated.
"""
from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.compare import calibrate
from granstokes.compare.comparison import PREDICTION_SPAN, PREDICTION_TIMES
from granstokes.continuum.scene import BedScene, SceneNumerics
from granstokes.continuum.scene_models import LOCAL
from granstokes.continuum.velocity import VELOCITY_NUMERICS
from granstokes.dem.config import preset
from granstokes.dem.scene import plate_geometry
from granstokes.dem.sizing import plan

HERE = Path(__file__).parent
ROOT = HERE.parent
TARGET = 1e-4
REFINE = (400, 800, 1600)
REFERENCE_TOL = dict(stretch=2.0, rtol=1e-8, atol=1e-11, method="sdirk4")
#: the baseline (200 cells, stretch 2, SDIRK4; "old default" in the table): the CPU ratios are against it, in the
#: same run
OLD_DEFAULT = SceneNumerics(n_cells=200, stretch=2.0, rtol=1e-5, atol=1e-9, method="sdirk4")
CANDIDATES = {"old default (200 cells, stretch 2, sdirk4)": OLD_DEFAULT,
              "default (400 cells, stretch 4, tr-bdf2, atol 1e-8)": VELOCITY_NUMERICS,
              "former default (as above, atol 1e-9)": replace(VELOCITY_NUMERICS, atol=1e-9),
              "as default, atol 1e-7": replace(VELOCITY_NUMERICS, atol=1e-7),
              "400 cells, stretch 4, sdirk4": replace(VELOCITY_NUMERICS, method="sdirk4"),
              "300 cells, stretch 4, tr-bdf2": replace(VELOCITY_NUMERICS, n_cells=300),
              "200 cells, stretch 3, tr-bdf2": replace(VELOCITY_NUMERICS, n_cells=200, stretch=3.0),
              "400 cells, stretch 4, tr-bdf2, rtol 2e-5": replace(VELOCITY_NUMERICS, rtol=2e-5),
              "400 cells, stretch 6, tr-bdf2": replace(VELOCITY_NUMERICS, stretch=6.0)}
REPEATS = 3


def quick_drives():
    """(material, scene, [(name, load, times)]) of the quick preset."""
    cfg, _ = preset("quick")
    p = plan(cfg)
    mass = plate_geometry(p)["mass_per_area"]
    material = calibrate.load(ROOT / "results/quick-calibration/calibration.json").material()
    drives = [(d.drive.name, d.load, np.geomspace(d.duration / PREDICTION_SPAN, d.duration, PREDICTION_TIMES))
              for d in p.drives]
    return material, BedScene(p.depth, plate_mass=mass), drives


def predict(material, scene, load, times, numerics):
    """The scene model LOCAL's transient (continuum.scene_models, as compare predicts): the series (u_w, mu_w,
    delta_u) and u(y)."""
    tr = LOCAL.transient(material, scene, load, times, numerics)
    return {"u_w": tr.u_w, "mu_w": tr.mu_w, "delta_u": tr.delta_u, "y": tr.y, "u": tr.u}


def reference(material, scene, load, times):
    """Richardson extrapolation over REFINE (order p measured per quantity, median over times) and
    the finest profile; returns (reference, orders, estimated error of the finest solve)."""
    runs = [predict(material, scene, load, times, SceneNumerics(n_cells=n, **REFERENCE_TOL)) for n in REFINE]
    ref, orders, err = {"y": runs[-1]["y"], "u": runs[-1]["u"]}, {}, {}
    for q in ("u_w", "mu_w", "delta_u"):
        a, b, c = (r[q] for r in runs)
        d1, d2 = np.abs(b - a), np.abs(c - b)
        ok = (d2 > 1e-14 * np.abs(c)) & (d1 > d2)
        p = float(np.median(np.log2(d1[ok] / d2[ok]))) if ok.any() else np.inf
        corr = (c - b) / (2**p - 1) if np.isfinite(p) else 0.0
        ref[q], orders[q] = c + corr, p
        err[q] = float(np.max(np.abs(corr) / np.abs(c)))
    return ref, orders, err


def errors(run, ref) -> dict:
    out = {q: float(np.nanmax(np.abs(run[q] / ref[q] - 1))) for q in ("u_w", "mu_w", "delta_u")}
    u_ref = np.array([np.interp(run["y"], ref["y"], u) for u in ref["u"]])
    out["u_profile"] = float(np.max(np.abs(run["u"] - u_ref) / np.abs(ref["u_w"])[:, None]))
    return out


def timed(run):
    best = np.inf
    for _ in range(REPEATS):
        start = time.process_time()
        value = run()
        best = min(best, time.process_time() - start)
    return best, value


def main() -> None:
    material, scene, drives = quick_drives()
    rows = []
    for name, load, times in drives:
        ref, orders, ref_err = reference(material, scene, load, times)
        print(f"{name}: measured orders {orders}; reference error estimate {ref_err}")
        for label, num in CANDIDATES.items():
            cpu, run = timed(lambda: predict(material, scene, load, times, num))
            rows.append({"drive": name, "numerics": label, "n_cells": num.n_cells, "stretch": num.stretch,
                         "rtol": num.rtol, "cpu_ms": 1e3 * cpu, **errors(run, ref)})
    table = pd.DataFrame(rows)
    table.to_csv(HERE / "velocity_form.csv", index=False)
    base = table[table.numerics == next(iter(CANDIDATES))].set_index("drive").cpu_ms
    print("| drive | numerics | CPU [ms] | / old default | u_w | mu_w | delta_u | u(y)/u_w |\n"
          "|---|---|---|---|---|---|---|---|")
    for r in table.itertuples():
        print(f"| {r.drive} | {r.numerics} | {r.cpu_ms:.0f} | {r.cpu_ms / base[r.drive]:.2f} | {r.u_w:.1e} | "
              f"{r.mu_w:.1e} | {r.delta_u:.1e} | {r.u_profile:.1e} |")
    print(f"target: every error <= {TARGET:g} in <= 50 ms per drive")


if __name__ == "__main__":
    main()
