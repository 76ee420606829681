"""Work-precision of the continuum solvers: error of u~_w(t~ = 1) for mu~_w = 0.5 against a
converged value, versus CPU time, in one process: the project's SDIRK4 on the fourth-order
discretisation (the default), the baseline scipy solve_ivp (BDF, Radau) on the standard
second-order method of lines, and solve_ivp BDF on the project's fourth-order discretisation.  Writes
bench/work_precision.{csv,png} and prints the table for bench/RESULTS.md, then times the cheapest
SDIRK4 and baseline BDF runs head to head (alternating rounds: the ratio least hit by the load).

    .venv/bin/python bench/work_precision.py
"""
from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.continuum.rheology import Friction
from granstokes.continuum.solver import Numerics, solve_stress
from matplotlib.figure import Figure

HERE = Path(__file__).parent
FR = Friction(np.tan(np.radians(21.0)), np.tan(np.radians(33.0)))
MU_W = FR.mu_w_from_tilde(0.5)
TARGET = 1e-6
#: CPU time of a run: the best of REPEATS
REPEATS = 5
#: the head-to-head check: rounds, and runs per round of the cheaper and of the costlier solve
ROUNDS, RUNS_FAST, RUNS_SLOW = 5, 20, 3


def reference() -> tuple[float, float]:
    """Fourth order on 1024 cells, rtol 1e-12; its error estimate from the 512-cell companion."""
    fine = solve_stress(FR, MU_W, [1.0], Numerics(n_cells=1024, rtol=1e-12, atol=1e-14))
    coarse = solve_stress(FR, MU_W, [1.0], Numerics(n_cells=512, rtol=1e-12, atol=1e-14))
    return fine.u_w[0], abs(fine.u_w[0] - coarse.u_w[0]) / 15


def timed(run, repeats=REPEATS):
    best, value = np.inf, None
    for _ in range(repeats):
        start = time.process_time()
        value = run()
        best = min(best, time.process_time() - start)
    return best, value


def head_to_head(fast, slow):
    """CPU times of two solves alternated in rounds (the load on shared cores hits both alike): their
    minima and medians."""
    times = {fast: [], slow: []}
    for _ in range(ROUNDS):
        for run, k in ((fast, RUNS_FAST), (slow, RUNS_SLOW)):
            for _ in range(k):
                start = time.process_time()
                run()
                times[run].append(time.process_time() - start)
    return [(min(times[r]), float(np.median(times[r]))) for r in (fast, slow)]


def baseline(numerics: Numerics, method: str) -> float:
    """u~_w(1) of solve_stress by scipy's solve_ivp(``method``) (the registry's baseline) on these numerics."""
    return solve_stress(FR, MU_W, [1.0], replace(numerics, method=f"solve_ivp-{method}")).u_w[0]


def main():
    ref, ref_err = reference()
    rows = []
    for rtol in (1e-4, 1e-5, 1e-6, 1e-7, 1e-8):
        for order, cells in ((4, (16, 32, 48, 64, 96, 128)), (2, (100, 200, 400, 800, 1600))):
            for n in cells:
                num = Numerics(n_cells=n, rtol=rtol, atol=rtol * 1e-2, order=order)
                runs = ({"sdirk4, fourth order (granstokes)": lambda: solve_stress(FR, MU_W, [1.0], num).u_w[0],
                         "solve_ivp BDF, fourth order": lambda: baseline(num, "BDF")}
                        if order == 4 else
                        {"solve_ivp BDF, second order (baseline)":
                             lambda: baseline(num, "BDF"),
                         "solve_ivp Radau, second order (baseline)":
                             lambda: baseline(num, "Radau")})
                for name, run in runs.items():
                    cpu, value = timed(run)
                    rows.append({"method": name, "n_cells": n, "rtol": rtol, "cpu_s": cpu,
                                 "rel_error": abs(value / ref - 1)})
    df = pd.DataFrame(rows)
    df.to_csv(HERE / "work_precision.csv", index=False)

    fig = Figure(figsize=(12, 5), layout="constrained")
    ax, ax_space = fig.subplots(1, 2)
    for k, (name, g) in enumerate(df.groupby("method")):
        color = f"C{k}"
        ax.scatter(g.cpu_s, g.rel_error, color=color, alpha=0.3, s=12)
        front = g.sort_values("cpu_s")
        front = front[front.rel_error <= front.rel_error.cummin()]
        ax.plot(front.cpu_s, front.rel_error, "o-", color=color, label=f"{name}: best of (n_cells, rtol)")
        tight = g[g.rtol == g.rtol.min()]
        ax_space.loglog(tight.n_cells, tight.rel_error, "o-", color=color, label=name)
    ax.axhline(TARGET, color="k", lw=0.8, ls="--")
    ax.set(xscale="log", yscale="log", xlabel="CPU time [s], one core",
           ylabel="relative error of u~_w(t~=1), mu~_w = 0.5",
           title="Work-precision (faint: every run; line: Pareto front)")
    fig.legend(*ax.get_legend_handles_labels(), fontsize=8, loc="outside lower left",
               ncol=2)  # the fronts fill the panel
    n = np.array([16, 1600])
    ax_space.loglog(n, 2.5e-5 * (n / 200.0) ** -2, "k:", label="slope -2")
    ax_space.loglog(n, 1e-5 * (n / 32.0) ** -4, "k--", label="slope -4")
    ax_space.set(xlabel="n_cells", ylabel="relative error at rtol = 1e-8",
                 title="Spatial floor: second and fourth order in the mesh")
    ax_space.legend(fontsize=8)
    fig.savefig(HERE / "work_precision.png", dpi=130)

    best = df[df.rel_error <= TARGET].sort_values("cpu_s").groupby("method").head(1).set_index("method")
    print(f"reference u~_w(1) = {ref:.10f} (error estimate {ref_err:.1e})\n")
    print("| method | cheapest run reaching 1e-6 | CPU [ms] | error |")
    print("|---|---|---|---|")
    for name, r in best.sort_values("cpu_s").iterrows():
        print(f"| {name} | n_cells={int(r.n_cells)}, rtol={r.rtol:g} | {1e3 * r.cpu_s:.1f} | {r.rel_error:.1e} |")
    ours = best.loc["sdirk4, fourth order (granstokes)", "cpu_s"]
    for other in ("solve_ivp BDF, second order (baseline)", "solve_ivp Radau, second order (baseline)",
                  "solve_ivp BDF, fourth order"):
        if other in best.index:
            print(f"speed-up of sdirk4 over {other} at 1e-6: {best.loc[other, 'cpu_s'] / ours:.2f}x")
        else:  # never reached the target: its best run bounds the ratio from below
            g = df[df.method == other].sort_values("rel_error").iloc[0]
            print(f"{other} never reached 1e-6 (best {g.rel_error:.1e} in {1e3 * g.cpu_s:.0f} ms): "
                  f"speed-up > {g.cpu_s / ours:.1f}x")
    mine, base = (best.loc[m] for m in ("sdirk4, fourth order (granstokes)", "solve_ivp BDF, second order (baseline)"))
    (o_min, o_med), (b_min, b_med) = head_to_head(
        lambda: solve_stress(FR, MU_W, [1.0], Numerics(n_cells=int(mine.n_cells), rtol=mine.rtol,
                                                       atol=mine.rtol * 1e-2)).u_w[0],
        lambda: baseline(Numerics(n_cells=int(base.n_cells), rtol=base.rtol, atol=base.rtol * 1e-2, order=2), "BDF"))
    print(f"head to head ({ROUNDS} alternating rounds): sdirk4 {1e3 * o_min:.1f} ms (median {1e3 * o_med:.1f}), "
          f"BDF second order {1e3 * b_min:.1f} ms (median {1e3 * b_med:.1f}): "
          f"{b_min / o_min:.2f}x on minima, {b_med / o_med:.2f}x on medians")

if __name__ == "__main__":
    main()
