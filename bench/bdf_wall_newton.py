"""scipy's BDF on an imposed speed (tests/continuum/bdf_oracle.py) with and without the wall's Newton: the
order-1 trap through the lift-off is chaotic in the step sequence (a first step 1 ulp away could enter or leave
it), so each case runs over a spread of first steps.  Prints the table for bench/RESULTS.md "The order-1 trap".

    PYTHONPATH=. .venv/bin/python bench/bdf_wall_newton.py

Cases: the paper's beads at u~_w = 1.334 and 2.0 and the disks' 1.0 (tests/continuum/reference.py), 256 and 512
cells, t~ = 1e-4 ... 10 (bench/speed_solver.py TIMES), the solver's default tolerances and the looser rtol
that an accuracy of 1e-6 would allow on 512 cells (TIME_ERROR_PER_RTOL x rtol = 1e-7); first steps
Numerics.initial_step x t~_min x (1 + k 1e-3), k = 0 ... FIRST_STEPS - 1.  Per case: the steps (min,
median, max over the first steps), the CPU (median), and mu_w at t~ = 1 against the other setting's median.
"""
from __future__ import annotations

import time

import numpy as np
from granstokes.continuum.problems import ImposedSpeed
from granstokes.continuum.solver import INITIAL_STEP, Numerics, map_for
from granstokes.continuum.steady import mu_w_for_speed

from bench.speed_solver import TIMES
from tests.continuum import bdf_oracle
from tests.continuum.reference import DISKS, PAPER

CASES = [("paper", PAPER, 1.334, 256, None), ("paper", PAPER, 2.0, 256, None), ("paper", PAPER, 1.334, 512, None),
         ("paper", PAPER, 1.334, 512, 3.3e-9), ("disks", DISKS, 1.0, 256, None), ("paper", PAPER, 0.198, 256, None)]
FIRST_STEPS = 5


def run(fr, u_w, n, rtol, wall_newton):
    steps, cpu, mu_w = [], [], []
    numerics = Numerics(n_cells=n, rtol=rtol).for_drive("speed")
    pb = ImposedSpeed(fr, u_w, numerics.mesh(*map_for(fr, mu_w_for_speed(fr, u_w), "speed", TIMES[0])))
    for k in range(FIRST_STEPS):
        start = time.process_time()
        states, stats = bdf_oracle.integrate(pb, TIMES, rtol=numerics.rtol, atol=numerics.atol,
                                             h0=INITIAL_STEP * (1 + 1e-3 * k) * TIMES[0], wall_newton=wall_newton)
        cpu.append(time.process_time() - start)
        steps.append(stats.steps)
        mu_w.append(pb.mu(states[TIMES.index(1.0)])[0])
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
