"""An imposed speed at the CLI's default accuracy over the admissible range (any admissible u~_w):
for each friction and speed, the cells the refinement reached, the steps, the CPU, the worst estimated
relative error of mu_w and delta, and mu_w at t~ = 10 against the exact steady mu_w^inf.  A robustness
survey, not a timing: a failure is printed as such and the survey goes on.

    PYTHONPATH=. .venv/bin/python bench/speed_range.py

Times t~ = 1e-4 ... 10 (bench/speed_solver.py TIMES); frictions: the paper's beads and the disks of
tests/continuum/reference.py.  mu_w(10) is the steady value only where t~ = 10 is well past the lift-off
(t~_mud = u~_w^2): for the larger speeds the gap is the approach, not an error.
"""
from __future__ import annotations

import time

import numpy as np
from granstokes.continuum.cli import ACCURACY
from granstokes.continuum.scales import UNITS
from granstokes.continuum.solver import solve_speed

from bench.speed_solver import QUANTITIES, TIMES
from tests.continuum.reference import DISKS, PAPER

FRICTIONS = {"paper": PAPER, "disks": DISKS}
SPEEDS = (0.001, 0.005, 0.02, 0.05, 0.1, 0.5, 2.0, 10.0, 30.0)


def main():
    print(f"accuracy asked: {ACCURACY:g}; t~ = {TIMES}; the paper's dimensionless variables: "
          f"{UNITS['tilde_variables']}")
    print("| friction | u~_w | t~_mud | cells | steps | CPU [s] | worst estimate | mu_w(10)/mu_w^inf - 1 |")
    print("|---|---|---|---|---|---|---|---|")
    for name, fr in FRICTIONS.items():
        for u_w in SPEEDS:
            start = time.process_time()
            try:
                sol = solve_speed(fr, u_w, TIMES, accuracy=ACCURACY)
            except (ValueError, RuntimeError) as err:
                print(f"| {name} | {u_w:g} | {u_w**2:.2g} | failed: {err} | | | | |", flush=True)
                continue
            cpu = time.process_time() - start
            worst = max(np.max(sol.errors[q] / np.abs(getattr(sol, q))) for q in QUANTITIES)
            print(f"| {name} | {u_w:g} | {u_w**2:.2g} | {sol.numerics.n_cells} | {sol.stats.steps} | {cpu:.1f} | "
                  f"{worst:.1e} | {sol.mu_w[-1] / sol.steady['mu_w'] - 1:.1e} |", flush=True)


if __name__ == "__main__":
    main()
