"""scipy's BDF on an imposed speed with and without the wall's Newton (Numerics.wall_newton): the
order-1 trap through the lift-off is chaotic in the step sequence (a first step 1 ulp away could enter or leave
it), so each case runs over a spread of first steps.  Prints the table for bench/RESULTS.md "The order-1 trap".

    PYTHONPATH=. .venv/bin/python bench/bdf_wall_newton.py

Cases: the paper's beads at u~_w = 1.334 and 2.0 and the disks' 1.0 (tests/continuum/reference.py), 256 and 512
cells, t~ = 1e-4 ... 10 (bench/speed_solver.py TIMES), the solver's default tolerances and the looser rtol
that an accuracy of 1e-6 would allow on 512 cells (TIME_ERROR_PER_RTOL x rtol = 1e-7); first steps
continuum.solver.INITIAL_STEP x t~_min x (1 + k 1e-3), k = 0 ... FIRST_STEPS - 1.  Per case: the steps (min,
median, max over the first steps), the CPU (median), and mu_w at t~ = 1 against the other setting's median.
"""
from __future__ import annotations

import time

import granstokes.continuum.solver as solver
import numpy as np
from granstokes.continuum.solver import Numerics, solve_speed

from bench.speed_solver import TIMES
from tests.continuum.reference import DISKS, PAPER

CASES = [("paper", PAPER, 1.334, 256, None), ("paper", PAPER, 2.0, 256, None), ("paper", PAPER, 1.334, 512, None),
         ("paper", PAPER, 1.334, 512, 3.3e-9), ("disks", DISKS, 1.0, 256, None), ("paper", PAPER, 0.198, 256, None)]
FIRST_STEPS = 5


def run(fr, u_w, n, rtol, wall_newton):
    steps, cpu, mu_w = [], [], []
    default_step = solver.INITIAL_STEP
    try:
        for k in range(FIRST_STEPS):
            solver.INITIAL_STEP = default_step * (1 + 1e-3 * k)
            start = time.process_time()
            sol = solve_speed(fr, u_w, TIMES, Numerics(n_cells=n, rtol=rtol, wall_newton=wall_newton))
            cpu.append(time.process_time() - start)
            steps.append(sol.stats.steps)
            mu_w.append(sol.mu_w[TIMES.index(1.0)])
    finally:
        solver.INITIAL_STEP = default_step
    return np.array(steps), np.median(cpu), np.array(mu_w)


def main():
    print("| friction | u~_w | cells | rtol | wall Newton | steps min / median / max | CPU median [s] | "
          "mu_w(1) spread | vs the other's median |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, fr, u_w, n, rtol in CASES:
        runs = {on: run(fr, u_w, n, rtol, on) for on in (False, True)}
        for on, (steps, cpu, mu_w) in runs.items():
            other = np.median(runs[not on][2])
            print(f"| {name} | {u_w:g} | {n} | {rtol or 'default'} | {'yes' if on else 'no'} | "
                  f"{steps.min()} / {int(np.median(steps))} / {steps.max()} | {cpu:.2f} | "
                  f"{np.ptp(mu_w) / np.median(mu_w):.1e} | {np.max(np.abs(mu_w / other - 1)):.1e} |", flush=True)


if __name__ == "__main__":
    main()
