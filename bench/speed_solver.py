"""Imposed-speed solves (issue 11): CPU and error of the default (scipy BDF on the constraint manifold)
against SDIRK4 on the same discretisation and tolerance, in one run.  Prints the table for
bench/RESULTS.md.

    .venv/bin/python bench/speed_solver.py

Cases: the paper's three imposed speeds, t~ = 1e-4 ... 10, 64 cells (the CLI default); errors of mu_w
and delta (max over the times, relative) against 512 cells at the default tolerance; CPU: best of REPEATS.
"""
from __future__ import annotations

import time

import numpy as np

from continuum.rheology import Friction
from continuum.solver import Numerics, solve_speed

FR = Friction(np.tan(np.radians(21.0)), np.tan(np.radians(33.0)))
SPEEDS = (0.198, 1.334, 4.629)
TIMES = [1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0]
CELLS, REFERENCE_CELLS, REPEATS = 64, 512, 3
RUNS = {"bdf, default rtol (1e-8)": {}, "bdf, rtol 1e-6": {"rtol": 1e-6}, "sdirk4, rtol 1e-6": {"rtol": 1e-6, "method": "sdirk4"},
        "bdf, rtol 1e-8": {"rtol": 1e-8}, "sdirk4, rtol 1e-8": {"rtol": 1e-8, "method": "sdirk4"}}


def timed(u_w, **kw):
    best = np.inf
    for _ in range(REPEATS):
        start = time.process_time()
        sol = solve_speed(FR, u_w, TIMES, Numerics(n_cells=CELLS, **kw))
        best = min(best, time.process_time() - start)
    return sol, best


def main():
    print("| u~_w | run | steps | CPU [ms] | / bdf default | mu_w error | delta error |")
    print("|---|---|---|---|---|---|---|")
    for u_w in SPEEDS:
        ref = solve_speed(FR, u_w, TIMES, Numerics(n_cells=REFERENCE_CELLS))
        base = None
        for name, kw in RUNS.items():
            sol, cpu = timed(u_w, **kw)
            base = base or cpu
            err = {q: np.max(np.abs(getattr(sol, q) / getattr(ref, q) - 1)) for q in ("mu_w", "delta")}
            print(f"| {u_w} | {name} | {sol.stats.steps} | {1e3 * cpu:.0f} | {cpu / base:.2f} | "
                  f"{err['mu_w']:.1e} | {err['delta']:.1e} |", flush=True)


if __name__ == "__main__":
    main()
