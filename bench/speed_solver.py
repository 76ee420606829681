"""Imposed-speed solves: CPU and error of the speed's default map, the wall cluster
(``continuum.solver.map_for``: the layer's stretch plus WALL_FOLDS e-folds packed at the wall), against
one exponential map of stretch WALL_STRETCH (the wall-graded map without the cluster), in one run; then
the cost of an accuracy request.  Prints the tables for bench/RESULTS.md.

    .venv/bin/python bench/speed_solver.py

Cases: the paper's three imposed speeds, t~ = 1e-4 ... 10, default tolerances (bdf).  Errors of mu_w
and delta (max over the times, relative) against the Richardson extrapolation (order 4) of 256 and
REFERENCE_CELLS wall-clustered cells (the early times on the deeper cluster from 128 cells on,
continuum.solver.EARLY_SPAN, bench/early_times.py); CPU: best of REPEATS.
"""
from __future__ import annotations

import time

import numpy as np
from granstokes.continuum.rheology import Friction
from granstokes.continuum.solver import WALL_STRETCH, Numerics, solve_speed

FR = Friction(np.tan(np.radians(21.0)), np.tan(np.radians(33.0)))
SPEEDS = (0.198, 1.334, 4.629)
TIMES = [1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0]
CELLS, REFERENCE_CELLS, REPEATS = (64, 128, 256), 512, 2
ACCURACIES = (1e-4, 1e-5, 1e-6)
QUANTITIES = ("mu_w", "delta")


def timed(solve):
    best = np.inf
    for _ in range(REPEATS):
        start = time.process_time()
        sol = solve()
        best = min(best, time.process_time() - start)
    return sol, best


def reference(u_w) -> dict:
    """Richardson (order 4) from REFERENCE_CELLS/2 and REFERENCE_CELLS wall-clustered cells, default rtol
    (tighter, 1e-11, stalls BDF near the steady state of 0.198 on 512 cells)."""
    coarse, fine = (solve_speed(FR, u_w, TIMES, Numerics(n_cells=n))
                    for n in (REFERENCE_CELLS // 2, REFERENCE_CELLS))
    return {q: getattr(fine, q) + (getattr(fine, q) - getattr(coarse, q)) / 15 for q in QUANTITIES}


def error(sol, ref) -> dict:
    return {q: np.max(np.abs(getattr(sol, q) / ref[q] - 1)) for q in QUANTITIES}


def main():
    refs = {u_w: reference(u_w) for u_w in SPEEDS}
    print("| u~_w | map | cells | steps | CPU [ms] | / cluster 64 | mu_w error | delta error |")
    print("|---|---|---|---|---|---|---|---|")
    for u_w in SPEEDS:
        base = None
        for name, stretch in (("wall cluster (default)", None),
                              (f"exponential, stretch {WALL_STRETCH:g}", WALL_STRETCH)):
            for n in CELLS:
                sol, cpu = timed(lambda: solve_speed(FR, u_w, TIMES, Numerics(n_cells=n, stretch=stretch)))
                base = base or cpu
                err = error(sol, refs[u_w])
                print(f"| {u_w} | {name} | {n} | {sol.stats.steps} | {1e3 * cpu:.0f} | {cpu / base:.2f} | "
                      f"{err['mu_w']:.1e} | {err['delta']:.1e} |", flush=True)
    print("\n| u~_w | accuracy asked | cells reached | CPU [s] | worst estimate | worst error |")
    print("|---|---|---|---|---|---|")
    for u_w in SPEEDS:
        for accuracy in ACCURACIES:
            sol, cpu = timed(lambda: solve_speed(FR, u_w, TIMES, accuracy=accuracy))
            est = max(np.max(sol.errors[q] / np.abs(getattr(sol, q))) for q in QUANTITIES)
            print(f"| {u_w} | {accuracy:g} | {sol.numerics.n_cells} | {cpu:.1f} | {est:.1e} | "
                  f"{max(error(sol, refs[u_w]).values()):.1e} |", flush=True)


if __name__ == "__main__":
    main()
