"""The SDIRK4 stress stepper with and without the repeat cap (``continuum.stepper`` REPEAT_BAND: a Newton
failure at the step size of the previous one caps the steps), in one run: Newton iterations, steps,
rejections, CPU, and the change of u~_w and delta (max over the times, relative).  Prints the table for
bench/RESULTS.md ("The paper's figure set").  "before" is Numerics(repeat_cap=False).

    .venv/bin/python bench/stress_repeat_cap.py

Cases: (a) the breakdown, mu~_w = 0.1 on 64 cells at rtol 1e-4; (b) mu~_w = 0.1 and 0.5 on 96 cells at
rtol 1e-6; (c) the SDIRK4 rows of bench/work_precision.py (mu~_w = 0.5, t~ = 1, 16-128 cells, rtol
1e-4 ... 1e-8, summed); (d) mu~_w = 0.1 on 32, 64, 96 cells, rtol 1e-5 ... 1e-8, summed; (e) the figure
set's ten stress solves (default numerics).  Times t~ = 1e-4 ... 10 unless said.
"""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from granstokes.continuum.paper.figures import DECADES, FIG4_CASES, FIG4_T, STRESS_CASES
from granstokes.continuum.paper.figures import FRICTION as FR
from granstokes.continuum.solver import Numerics, solve_stress

TIMES = list(DECADES)
CASES = {
    "(a) mu~_w 0.1, 64 cells, rtol 1e-4": [(0.1, TIMES, Numerics(n_cells=64, rtol=1e-4))],
    "(b) mu~_w 0.1, 96 cells, rtol 1e-6": [(0.1, TIMES, Numerics(n_cells=96, rtol=1e-6))],
    "(b) mu~_w 0.5, 96 cells, rtol 1e-6": [(0.5, TIMES, Numerics(n_cells=96, rtol=1e-6))],
    "(c) work-precision SDIRK4 rows (30 solves)": [
        (0.5, [1.0], Numerics(n_cells=n, rtol=r, atol=r * 1e-2))
        for r in (1e-4, 1e-5, 1e-6, 1e-7, 1e-8) for n in (16, 32, 48, 64, 96, 128)],
    "(d) mu~_w 0.1, 32-96 cells, rtol 1e-5-1e-8 (12 solves)": [
        (0.1, TIMES, Numerics(n_cells=n, rtol=r)) for r in (1e-5, 1e-6, 1e-7, 1e-8) for n in (32, 64, 96)],
    "(e) figure set (10 solves)": [(mt, TIMES, Numerics()) for mt in STRESS_CASES]
                                  + [(mt, [FIG4_T], Numerics()) for mt in FIG4_CASES],
}


def run(solves, cap: bool):
    it = steps = rejected = 0
    cpu, values = 0.0, []
    for mt, times, num in solves:
        start = time.process_time()
        sol = solve_stress(FR, FR.mu_w_from_tilde(mt), times, replace(num, repeat_cap=cap))
        cpu += time.process_time() - start
        s = sol.stats
        it, steps, rejected = it + s.newton_iterations, steps + s.steps, rejected + s.rejected
        values.append((np.asarray(sol.u_w), np.asarray(sol.delta)))
    return it, steps, rejected, cpu, values


def main():
    print("| case | Newton iterations before -> after | steps | rejected | CPU [s] | change of u~_w, delta |")
    print("|---|---|---|---|---|---|")
    for name, solves in CASES.items():
        b, a = run(solves, False), run(solves, True)
        du = max(np.max(np.abs(x[0] / y[0] - 1)) for x, y in zip(a[4], b[4]))
        dd = max(np.max(np.abs(x[1] / y[1] - 1)) for x, y in zip(a[4], b[4]))
        print(f"| {name} | {b[0]} -> {a[0]} ({a[0] / b[0] - 1:+.1%}) | {b[1]} -> {a[1]} | {b[2]} -> {a[2]} "
              f"| {b[3]:.2f} -> {a[3]:.2f} | {du:.1e}, {dd:.1e} |", flush=True)


if __name__ == "__main__":
    main()
