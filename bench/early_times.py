"""An imposed speed's early output times on the deeper wall cluster (Numerics.early_span):
error and CPU with the early times apart (the default) against the solve's one map (early_span = 0), in one
run.  Prints the table for bench/RESULTS.md "The early times on a deeper cluster".

    PYTHONPATH=. .venv/bin/python bench/early_times.py

Cases: the paper's three speeds at the early reference's times below solver.early_until (tests/continuum/reference.py
SPEED_CASES' early_times, t~ = 1e-4 up to before the lift-off) plus t~ = 10, default tolerances; errors (max over the
early times, relative) of mu_w and delta against that reference (converged to 2e-10); CPU: best of
bench/speed_solver.py's REPEATS of the whole solve through t~ = 10.
"""
from __future__ import annotations

import numpy as np
from granstokes.continuum.solver import EARLY_SPAN, Numerics, early_until, solve_speed

from bench.speed_solver import QUANTITIES, timed  # timed: best of its REPEATS
from tests.continuum.reference import PAPER, SPEED_CASES, cached

CELLS = (64, 128, 256, 512)


def main():
    print("| u~_w | early times below | cells | one map: mu_w | delta | CPU [ms] | apart: mu_w | delta | CPU [ms] "
          "| CPU ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for label, case in SPEED_CASES.items():
        if case.friction != PAPER:
            continue
        u_w = case.u_w
        early = tuple(t for t in case.early_times if t < early_until(u_w))
        ref = {q: v[:len(early)] for q, v in cached(f"speed-early-{label}", times=np.array(case.early_times)).items()}
        times = [*early, 10.0]
        for n in CELLS:
            row = []
            for span in (0.0, EARLY_SPAN):
                sol, cpu = timed(lambda: solve_speed(PAPER, u_w, times, Numerics(n_cells=n, early_span=span)))
                row += [f"{np.max(np.abs(getattr(sol, q)[:len(early)] / ref[q] - 1)):.1e}" for q in QUANTITIES]
                row.append(cpu)
            print(f"| {u_w} | {early_until(u_w):.3g} | {n} | {row[0]} | {row[1]} | {1e3 * row[2]:.0f} | {row[3]} | "
                  f"{row[4]} | {1e3 * row[5]:.0f} | {row[5] / row[2]:.2f} |", flush=True)


if __name__ == "__main__":
    main()
