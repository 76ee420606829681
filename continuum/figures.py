"""Regenerate the paper's nine figures: the numerics against the closed forms, as the captions describe.

``paper_figures(out_dir)`` solves the paper's six cases once (mu_s = tan 21 deg, mu_d = tan 33 deg;
imposed stress mu~_w = 0.9, 0.5, 0.1; imposed speed u~_w = 0.198, 1.334, 4.629) and writes
figN_*.png, one long-format figN_*.csv per figure (panel, case, curve, t, x_var, x, y_var, y) and
paper_figures.json (parameters, units, timings).  Everything is in the paper's tilde variables.
"""
from __future__ import annotations

import json
import math
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from scipy.integrate import cumulative_trapezoid
from scipy.special import erfc

from .closed_forms import (SELF_SIMILAR_DELTA, WKB, self_similar_mu, self_similar_wall_speed,
                           speed_short_time_mu, speed_time_scales, uwall_asymp, uwall_mus)
from .rheology import Friction
from .scales import UNITS
from .solver import Numerics, solve_speed, solve_stress
from .steady import steady_delta, steady_mu, steady_velocity, steady_wall_speed

FRICTION = Friction(math.tan(math.radians(21.0)), math.tan(math.radians(33.0)))
STRESS_CASES = (0.9, 0.5, 0.1)              # imposed mu~_w
SPEED_CASES = (0.198, 1.334, 4.629)         # imposed u~_w
DECADES = 10.0 ** np.arange(-4, 2)          # t~ = 1e-4 ... 10; figs 5, 6, 9 start at 1e-3
FIG4_CASES = (0.99, 0.9, 0.75, 0.5, 0.3, 0.1, 0.03)  # mu~_w of the long-time circles of fig. 4
FIG4_T = 50.0                               # "long time": u~_w within 1e-5 of steady for mu~_w >= 0.1
PAPER_SPEED_DELTA = 3.66                    # delta ~ 3.66 Dmu sqrt(t~), quoted with eq. TimeScaleMu
T_MIN = 1e-4                                # time-series plots start here
WKB_T_MIN = 1e-2                            # 40-mode WKB series is not converged before this

LABELS = {
    "y": r"$\tilde y$", "t": r"$\tilde t$", "tau": r"$\tilde\tau=\mu\tilde p/\mu_w$", "mu": r"$\mu$",
    "delta": r"$\delta/\delta_s$", "u_w": r"$\tilde u_w$", "mu_w_tilde": r"$\tilde\mu_w$",
    "u_w_inf": r"$\tilde u_w^\infty$", "u": r"$\tilde u$", "eta": r"$\eta=\tilde y/2\Delta\mu\sqrt{\tilde t}$",
    "u/u_w": r"$\tilde u/\tilde u_w(\tilde t)$", "u/(u_w_inf*sqrt(t))": r"$\tilde u/\tilde u_w^\infty\sqrt{\tilde t}$",
    "mu_tilde": r"$\tilde\mu=(\mu_d-\mu)/\Delta\mu$", "mu_w": r"$\mu_w(\tilde t)$",
    "t/u_w^2": r"$\tilde t/\tilde u_w^2$", "mu_w-mu_s": r"$\mu_w(\tilde t)-\mu_s$",
    "t*(mu_w_inf-mu_s)^2/u_w^2": r"$\tilde t\,(\mu_w^\infty-\mu_s)^2/\tilde u_w^2$",
    "(mu_w-mu_s)/(mu_w_inf-mu_s)": r"$(\mu_w(\tilde t)-\mu_s)/(\mu_w^\infty-\mu_s)$",
}
CASE_STYLE = {0: dict(color="C0", marker="s"), 1: dict(color="C1", marker="o"), 2: dict(color="C2", marker="D")}


def _time_color(t):
    """One colour per decade t~ = 1e-4 ... 10, the same in every figure."""
    return Figure().colorbar  and None or __import__("matplotlib").colormaps["viridis"](
        (np.log10(t) + 4.0) / 5.5)
