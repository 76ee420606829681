"""Imposed-speed solves (issue 11): CPU and error of the remeshed solver (``continuum.solver.phases``:
wall-graded map through the lift-off, then the layer's map) against one map that follows the layer
(the previous default), in one run; then the cost of an accuracy request with bdf's Newton systems by
scipy's own LU (stepper.BORDERED_BDF False) and by the bordered band.  Prints the tables for
bench/RESULTS.md.

    .venv/bin/python bench/speed_solver.py

Cases: the paper's three imposed speeds, t~ = 1e-4 ... 10, default tolerances (bdf); errors of mu_w
and delta (max over the times, relative) against 512 remeshed cells; CPU: best of REPEATS.
"""
from __future__ import annotations

import time

import numpy as np

from continuum import stepper
from continuum.rheology import Friction
from continuum.solver import Numerics, solve_speed

FR = Friction(np.tan(np.radians(21.0)), np.tan(np.radians(33.0)))
SPEEDS = (0.198, 1.334, 4.629)
TIMES = [1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0]
CELLS, REFERENCE_CELLS, REPEATS = (64, 128, 256), 512, 2
ACCURACIES = (1e-3, 1e-4, 1e-5)


def timed(solve):
    best = np.inf
    for _ in range(REPEATS):
        start = time.process_time()
        sol = solve()
        best = min(best, time.process_time() - start)
    return sol, best


def main():
    print("| u~_w | mesh | cells | steps | CPU [ms] | / remeshed 64 | mu_w error | delta error |")
    print("|---|---|---|---|---|---|---|---|")
    for u_w in SPEEDS:
        ref = solve_speed(FR, u_w, TIMES, Numerics(n_cells=REFERENCE_CELLS))
        base = None
        for name, remesh in (("remeshed", True), ("layer's map alone", False)):
            for n in CELLS:
                sol, cpu = timed(lambda: solve_speed(FR, u_w, TIMES, Numerics(n_cells=n, remesh=remesh)))
                base = base or cpu
                err = {q: np.max(np.abs(getattr(sol, q) / getattr(ref, q) - 1)) for q in ("mu_w", "delta")}
                print(f"| {u_w} | {name} | {n} | {sol.stats.steps} | {1e3 * cpu:.0f} | {cpu / base:.2f} | "
                      f"{err['mu_w']:.1e} | {err['delta']:.1e} |", flush=True)
    print("\n| u~_w | accuracy asked | cells reached | CPU [s], scipy's LU | CPU [s], bordered band | ratio "
          "| worst estimate | worst error against 512 |")
    print("|---|---|---|---|---|---|---|---|")
    for u_w in SPEEDS:
        ref = solve_speed(FR, u_w, TIMES, Numerics(n_cells=REFERENCE_CELLS))
        for accuracy in ACCURACIES:
            cpu = {}
            for bordered in (False, True):
                stepper.BORDERED_BDF = bordered
                start = time.process_time()
                try:
                    sol = solve_speed(FR, u_w, TIMES, accuracy=accuracy)
                except ValueError as refused:
                    sol = refused
                cpu[bordered] = time.process_time() - start
            if isinstance(sol, ValueError):
                print(f"| {u_w} | {accuracy:g} | refused: {sol} | {cpu[False]:.1f} | {cpu[True]:.1f} | | | |")
                continue
            est = max(np.max(sol.errors[q] / np.abs(getattr(sol, q))) for q in ("mu_w", "delta"))
            true = max(np.max(np.abs(getattr(sol, q) / getattr(ref, q) - 1)) for q in ("mu_w", "delta"))
            print(f"| {u_w} | {accuracy:g} | {sol.numerics.n_cells} | {cpu[False]:.1f} | {cpu[True]:.1f} | "
                  f"{cpu[False] / cpu[True]:.1f} | {est:.1e} | {true:.1e} |", flush=True)


if __name__ == "__main__":
    main()
