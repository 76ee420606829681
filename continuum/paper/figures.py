"""The paper's nine figures, numerics against the closed forms as the captions describe.

``paper_figures(out_dir)`` solves the six cases once and writes figN_*.png, one long-format figN_*.csv
each (panel, case, curve, t, x_var, x, y_var, y) and paper_figures.json; all in the tilde variables."""
from __future__ import annotations

import json
import math
import textwrap
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib import colormaps
from matplotlib.figure import Figure
from scipy.integrate import cumulative_trapezoid
from scipy.special import erfc

from ..closed_forms import (
    SELF_SIMILAR_DELTA,
    UWALL_MUS_PRINTED_B2,
    WKB,
    self_similar_mu,
    self_similar_wall_speed,
    speed_short_time_mu,
    speed_time_scales,
    uwall_asymp,
    uwall_mus,
)
from ..rheology import Friction
from ..scales import UNITS
from ..solver import Numerics, Solution, solve_speed, solve_stress, stretch_for
from ..steady import steady_mu, steady_velocity, steady_wall_speed
from .equations import eq

FRICTION = Friction(math.tan(math.radians(21.0)), math.tan(math.radians(33.0)))
STRESS_CASES = (0.9, 0.5, 0.1)              # imposed mu~_w
SPEED_CASES = (0.198, 1.334, 4.629)         # imposed u~_w
DECADES = 10.0 ** np.arange(-4, 2)          # t~ = 1e-4 ... 10; figs 5, 6, 9 start at 1e-3
FIG4_CASES = (0.99, 0.9, 0.75, 0.5, 0.3, 0.1, 0.03)  # mu~_w of the long-time circles of fig. 4
FIG4_T = 50.0                               # their "long time"
PAPER_SPEED_DELTA = 3.66                    # delta ~ 3.66 Dmu sqrt(t~), quoted with eq. (3.16)
T_MIN = 1e-4                                # time series are plotted from here on
WKB_T_MIN = 1e-2                            # the 40-mode WKB series has not converged before this
ETA_MAX = 2.5                               # similarity-variable plots stop here

LABELS = {  # CSV variable name -> axis label
    "y": r"$\tilde y$", "t": r"$\tilde t$", "tau": r"$\tilde\tau=\mu\tilde p/\mu_w$", "mu": r"$\mu$",
    "u": r"$\tilde u$", "delta": r"$\delta/\delta_s$", "u_w": r"$\tilde u_w$", "mu_w_tilde": r"$\tilde\mu_w$",
    "u_w_inf": r"$\tilde u_w^\infty$", "eta": r"$\eta=\tilde y/2\Delta\mu\sqrt{\tilde t}$",
    "u/u_w": r"$\tilde u/\tilde u_w(\tilde t)$", "u/(u_w_inf*sqrt(t))": r"$\tilde u/\tilde u_w^\infty\sqrt{\tilde t}$",
    "mu_tilde": r"$\tilde\mu=(\mu_d-\mu)/\Delta\mu$", "mu_w": r"$\mu_w(\tilde t)$",
    "t/u_w^2": r"$\tilde t/\tilde u_w^2$", "mu_w-mu_s": r"$\mu_w(\tilde t)-\mu_s$",
    "t*(mu_w_inf-mu_s)^2/u_w^2": r"$\tilde t\,(\mu_w^\infty-\mu_s)^2/\tilde u_w^2$",
    "(mu_w-mu_s)/(mu_w_inf-mu_s)": r"$(\mu_w(\tilde t)-\mu_s)/(\mu_w^\infty-\mu_s)$",
}
STEADY = dict(color="k", ls="--", lw=2.5, alpha=0.6, label="steady")


@dataclass(frozen=True)
class FigureNumerics:
    """The figures' numerics, chosen for plotting accuracy (a line is ~1e-3 of a panel): the stresses at the
    solver's defaults on 64 cells; the speeds on 64 cells of the exponential map of the layer at T_MIN (the
    speed's, solver.map_for, without its wall cluster: stretch 6.02) at rtol 1e-5: within 3e-4 in mu_w and 5e-4
    in delta of 256 clustered cells at the output times, in 220-250 BDF steps (~850 at the defaults, whose map
    follows the first output time, 1e-3, and leaves fig. 7's per-step delta 4.2 % low at t~ = 1e-4, against
    0.2 % here);
    bench/RESULTS.md "The paper's figure set"."""

    stress: Numerics = Numerics()
    speed: Numerics = Numerics(stretch=stretch_for(SELF_SIMILAR_DELTA * FRICTION.dmu * math.sqrt(T_MIN)), rtol=1e-5)


FIGURE_NUMERICS = FigureNumerics()


@dataclass(frozen=True)
class Runs:
    """Every numerical result the figures use, computed once."""

    stress: dict[float, Solution]           # keyed by mu~_w
    speed: dict[float, Solution]            # keyed by u~_w
    wkb: dict[float, WKB]                   # eq. (3.5) of each stress case
    long_time: dict[float, float]           # u~_w(t~ = FIG4_T) keyed by mu~_w


def solve_cases(numerics: FigureNumerics = FIGURE_NUMERICS) -> Runs:
    fr, stress_numerics = FRICTION, numerics.stress
    stress = {mt: solve_stress(fr, fr.mu_w_from_tilde(mt), DECADES, stress_numerics) for mt in STRESS_CASES}
    return Runs(stress, {uw: solve_speed(fr, uw, DECADES[1:], numerics.speed) for uw in SPEED_CASES},
                {mt: WKB(fr, sol.mu_w_inf) for mt, sol in stress.items()},
                {mt: float(solve_stress(fr, fr.mu_w_from_tilde(mt), [FIG4_T], stress_numerics).u_w[-1])
                 for mt in FIG4_CASES})


# --- layout helpers ---------------------------------------------------------------------------------
class Sheet:
    """One figure: a grid of axes; every curve drawn is also recorded as long-format CSV rows."""

    def __init__(self, name: str, title: str, nrows: int, ncols: int, panel=(4.4, 3.5)):
        self.name, self.rows, self.frames = name, [], {}
        self.fig = Figure(figsize=(panel[0] * ncols, panel[1] * nrows + 0.5), layout="constrained")
        width = panel[0] * ncols  # inches; about 11 characters of the 10 pt title per inch
        self.fig.suptitle(textwrap.fill(" ".join(title.split()) + " [dimensionless tilde variables]", int(11 * width)),
                          fontsize=10)
        self.axes = self.fig.subplots(nrows, ncols, squeeze=False)

    def frame(self, ax, panel: str, x: str, y: str, title: str = "", log: str = "", case: str = "all", **limits):
        """Label ``ax`` with the tilde variables x, y (keys of LABELS); ``log`` in {"", "x", "y", "xy"}."""
        ax.set(xlabel=LABELS[x], ylabel=LABELS[y], title=title, xscale="log" if "x" in log else "linear",
               yscale="log" if "y" in log else "linear", **limits)
        self.frames[ax] = (panel, x, y, case)

    def curve(self, ax, x, y, *, curve: str, t=np.nan, case: str | None = None, **style):
        """Plot y(x) on ``ax`` and record it (``case`` defaults to the panel's)."""
        panel, xv, yv, panel_case = self.frames[ax]
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        ax.plot(x, y, **style)
        self.rows.append(pd.DataFrame({"panel": panel, "case": case or panel_case, "curve": curve, "t": t,
                                       "x_var": xv, "x": x, "y_var": yv, "y": y}))

    def save(self, out: Path) -> Path:
        for ax in self.frames:
            ax.legend(fontsize=7, handlelength=3)
        png = out / f"{self.name}.png"
        self.fig.savefig(png, dpi=110)
        pd.concat(self.rows, ignore_index=True).to_csv(out / f"{self.name}.csv", index=False)
        return png


FIGURES = []  # (draw(sheet, runs), nrows, ncols, panel size) in figure order


def figure(nrows: int, ncols: int, panel=(4.4, 3.5)):
    """Register ``draw(sheet, runs)`` with its panel grid; its docstring is the figure's title line."""
    def register(draw):
        FIGURES.append((draw, nrows, ncols, panel))
        return draw
    return register


def key(ax, label: str, **style):
    """Legend-only entry (a line style shared by curves of several colours)."""
    ax.plot([], [], color="k", label=label, **style)


def at(t, label=True) -> dict:
    """Colour (one per decade t~ = 1e-4 ... 10, the same in every figure) and legend label of time t~."""
    return dict(color=colormaps["viridis"]((np.log10(t) + 4.0) / 5.5),
                label=rf"$\tilde t=10^{{{round(np.log10(t))}}}$" if label else None)


def panel_title(j: int, var: str, value) -> str:
    return f"({'abc'[j]}) {LABELS[var]} = {value}"


def case_style(j: int, uw: float) -> dict:
    """Imposed-speed case j: the paper's symbol (square, circle, diamond) and a colour."""
    return dict(case=f"u_w={uw}", color=f"C{j}", marker="soD"[j], ms=5, mfc="none", markevery=0.05,
                label=rf"$\tilde u_w={uw}$")


def late(sol: Solution) -> pd.DataFrame:
    return sol.series[sol.series.t >= T_MIN * (1 - 1e-9)]


def eta(y, t) -> np.ndarray:
    return y / (2.0 * FRICTION.dmu * np.sqrt(t))


def self_similar_velocity(mu_w: float, eta_out):
    """u~/sqrt(t~) of eq. (3.3) for beta_w y~ -> 0: eq. (3.10) in eta gives
    2 int_eta^inf (1/mu~ - 1) ds with mu~ = 1 - (1 - mu~_w) erfc(s)."""
    s = np.linspace(0.0, 7.0, 20001)
    a = 1.0 - FRICTION.tilde(mu_w)
    cum = cumulative_trapezoid(a * erfc(s) / (1.0 - a * erfc(s)), s, initial=0.0)
    return np.interp(eta_out, s, 2.0 * (cum[-1] - cum))


# --- the figures --------------------------------------------------------------------------------------
@figure(2, 3)
def fig1_shear_stress(sh: Sheet, runs: Runs):
    """Fig. 1: tau~ of eq. (2.15), the stress diffusion equation; delta/delta_s vs 4.653 Dmu sqrt(t~) (eq. (3.3),
    the short-time erfc solution) and steady"""
    for j, (mt, sol) in enumerate(runs.stress.items()):
        (top, bottom), y, ser, case = sh.axes[:, j], sol.mesh.y, late(sol), f"mu_w_tilde={mt}"
        initial = FRICTION.mu_s * (1.0 + sol.beta_w * y) / sol.mu_w_inf
        sh.frame(top, f"{'abc'[j]}_top", "y", "tau", panel_title(j, "mu_w_tilde", mt), case=case, xlim=(0, 1),
                 ylim=(initial[0] - 0.02, 1.01))
        sh.frame(bottom, f"{'abc'[j]}_bottom", "t", "delta", log="xy", case=case)
        top.fill_between(y, 0.0, initial, color="0.88", label=r"no flow, $\tau<\mu_s p$")
        sh.curve(top, y, initial, curve="initial condition", t=0.0, color="k", ls="--", label="initial condition")
        for t, tau in zip(sol.t, sol.tau):
            sh.curve(top, y, tau, curve="numerics", t=t, **at(t))
        sh.curve(bottom, ser.t, ser.delta, curve="numerics", color="k", label="numerics")
        sh.curve(bottom, ser.t, SELF_SIMILAR_DELTA * FRICTION.dmu * np.sqrt(ser.t), curve=eq("SolutionSS"),
                 color="C3", ls="--", label=r"$4.653\,\Delta\mu\sqrt{\tilde t}$")
        sh.curve(bottom, ser.t.iloc[[0, -1]], sol.steady["delta"], curve="steady", color="0.4", ls=":", label="steady")
        bottom.set_ylim(top=2.0)


@figure(2, 3)
def fig2_friction_profiles(sh: Sheet, runs: Runs):
    """Fig. 2: mu, numerics (solid) vs eq. (3.3), the short-time erfc solution (top), and eq. (3.5), the long-time
    WKB series, 40 modes, t~ >= 1e-2 (bottom)"""
    for j, (mt, sol) in enumerate(runs.stress.items()):
        y, wkb = sol.mesh.y, runs.wkb[mt]
        approx = ((eq("SolutionSS"), "--", 0.0, lambda t: self_similar_mu(FRICTION, sol.mu_w_inf, y, t)),
                  (eq("SolutionLONG"), "-.", WKB_T_MIN, lambda t: wkb.mu(y, t)))
        for ax, row, (name, ls, t_min, mu_of_t) in zip(sh.axes[:, j], ("top", "bottom"), approx):
            sh.frame(ax, f"{'abc'[j]}_{row}", "y", "mu", panel_title(j, "mu_w_tilde", mt), case=f"mu_w_tilde={mt}",
                     xlim=(0, 1), ylim=(FRICTION.mu_s - 0.005, sol.mu_w_inf + 0.01))
            for t, mu in zip(sol.t, sol.mu):
                sh.curve(ax, y, mu, curve="numerics", t=t, **at(t))
                if t >= t_min:
                    sh.curve(ax, y, mu_of_t(t), curve=name, t=t, ls=ls, lw=2, **at(t, label=False))
            key(ax, name, ls=ls, lw=2)


@figure(1, 3)
def fig3_wall_speed(sh: Sheet, runs: Runs):
    """Fig. 3: u~_w, numerics (dots) vs eq. (3.3), the short-time erfc solution (squares), and eq. (3.5), the
    long-time WKB series (+, t~ >= 1e-2)"""
    t_ss = np.logspace(-4, 1, 11)
    t_wkb = t_ss[t_ss >= WKB_T_MIN]
    for j, (mt, sol) in enumerate(runs.stress.items()):
        ax, ser = sh.axes[0, j], late(sol)
        sh.frame(ax, "abc"[j], "t", "u_w", panel_title(j, "mu_w_tilde", mt), log="xy", case=f"mu_w_tilde={mt}")
        sh.curve(ax, ser.t, ser.u_w, curve="numerics", color="k", marker="o", ms=2.5, ls="none", label="numerics")
        sh.curve(ax, t_ss, [self_similar_wall_speed(FRICTION, sol.mu_w_inf, t) for t in t_ss], curve=eq("SolutionSS"),
                 color="C0", marker="s", ms=8, mfc="none", ls="none", label=eq("SolutionSS"))
        sh.curve(ax, t_wkb, [runs.wkb[mt].wall_speed(t) for t in t_wkb], curve=eq("SolutionLONG"), color="C3",
                 marker="+", ms=11, mew=1.5, ls="none", label=eq("SolutionLONG"))
        sh.curve(ax, t_ss, self_similar_velocity(sol.mu_w_inf, 0.0) * np.sqrt(t_ss), curve="sqrt(t~) limit",
                 color="0.5", ls="--", label=rf"$\propto\sqrt{{\tilde t}}$ ({eq('SolutionSS')}, $\tilde t\to0$)")
        sh.curve(ax, t_ss[[0, -1]], sol.steady["u_w"], curve="steady", color="0.3", ls=":", label="steady")
        ax.set_ylim(top=3 * sol.steady["u_w"])


@figure(1, 2, (5.5, 4.2))
def fig4_steady_wall_speed(sh: Sheet, runs: Runs):
    """Fig. 4: steady u~_w^inf, exact vs eq. (3.12), its asymptote, eq. (3.13), its form near yield, and the
    numerics at t~ = 50 (circles)"""
    mt = np.linspace(0.002, 0.998, 499)  # step 0.002, includes 0.5
    mu_w = FRICTION.mu_d - mt * FRICTION.dmu
    exact = np.array([steady_wall_speed(FRICTION, m) for m in mu_w])
    b2 = 2.0 * FRICTION.mu_s / (3.0 * FRICTION.dmu) - 1.0 / 6.0  # uwall_mus's default
    circles = np.array(list(runs.long_time.items()))
    for ax, panel, title, lim in zip(sh.axes[0], "ab", ("(a)", r"(b) zoom, $\mu_w\to\mu_s$"), ((0, 1), (0.8, 1))):
        sh.frame(ax, panel, "mu_w_tilde", "u_w_inf", title, case="steady")
        sh.curve(ax, mt, exact, curve="exact", color="k", lw=1, label="exact steady")
        sh.curve(ax, mt, uwall_asymp(FRICTION, mt), curve=eq("Uwall_asymp"), color="C0", label=eq("Uwall_asymp"))
        sh.curve(ax, mt, uwall_mus(FRICTION, mu_w, UWALL_MUS_PRINTED_B2), curve=eq("Uwall_muS"), color="C3", ls="--",
                 label=rf"{eq('Uwall_muS')}, printed $-\frac{{5}}{{2}}\beta_w^2$")
        sh.curve(ax, mt, uwall_mus(FRICTION, mu_w), curve=f"{eq('Uwall_muS')}, derived b2", color="C1", ls=":", lw=2,
                 label=rf"{eq('Uwall_muS')}, derived ${b2:+.3f}\,\beta_w^2$")
        sh.curve(ax, circles[:, 0], circles[:, 1], curve="numerics", t=FIG4_T, color="k", marker="o", ms=7,
                 mfc="none", mew=1.5, ls="none", label=rf"numerics, $\tilde t={FIG4_T:g}$")
        top = exact[(mt >= lim[0]) & (mt <= lim[1])].max()
        ax.set(xlim=lim, ylim=(-0.05 * top, 1.05 * top))


@figure(3, 3)
def fig5_velocity_profiles(sh: Sheet, runs: Runs):
    """Fig. 5: u~ and its collapse in eta (u~_w^inf of eq. (3.12)) vs eq. (3.3), the short-time erfc solution
    (beta_w y~ -> 0)"""
    e = np.linspace(0.0, ETA_MAX, 200)
    for j, (mt, sol) in enumerate(runs.stress.items()):
        y, (top, mid, bottom), case = sol.mesh.y, sh.axes[:, j], f"mu_w_tilde={mt}"
        u_inf, f = float(uwall_asymp(FRICTION, mt)), self_similar_velocity(sol.mu_w_inf, e)
        sh.frame(top, f"{'abc'[j]}_top", "y", "u", panel_title(j, "mu_w_tilde", mt), case=case, xlim=(0, 1))
        sh.frame(mid, f"{'abc'[j]}_middle", "eta", "u/u_w", case=case)
        sh.frame(bottom, f"{'abc'[j]}_bottom", "eta", "u/(u_w_inf*sqrt(t))", case=case)
        for t, u in zip(sol.t[1:], sol.velocity[1:]):
            keep = eta(y, t) <= ETA_MAX
            sh.curve(top, y, u, curve="numerics", t=t, **at(t))
            sh.curve(mid, eta(y, t)[keep], u[keep] / u[0], curve="numerics", t=t, **at(t))
            sh.curve(bottom, eta(y, t)[keep], u[keep] / (u_inf * np.sqrt(t)), curve="numerics", t=t, **at(t))
        sh.curve(top, y, steady_velocity(FRICTION, sol.mu_w_inf, y), curve="steady", **STEADY)
        for ax, norm in ((mid, f[0]), (bottom, u_inf)):
            sh.curve(ax, e, f / norm, curve=eq("SolutionSS"), color="C3", ls="--", lw=2, label=eq("SolutionSS"))


@figure(2, 3)
def fig6_speed_profiles(sh: Sheet, runs: Runs):
    """Fig. 6: imposed u~_w, eq. (3.14) with the integral condition eq. (3.15); thick dashed: the steady state,
    eq. (2.10)"""
    for j, (uw, sol) in enumerate(runs.speed.items()):
        (top, bottom), case = sh.axes[:, j], f"u_w={uw}"
        title = panel_title(j, "u_w", uw) + rf", $\tilde\mu_w^\infty$ = {FRICTION.tilde(sol.mu_w_inf):.3f}"
        sh.frame(top, f"{'abc'[j]}_top", "y", "u", title, case=case, xlim=(0, 1))
        sh.frame(bottom, f"{'abc'[j]}_bottom", "y", "mu_tilde", case=case, xlim=(0, 1), ylim=(-0.02, 1.02))
        y = sol.mesh.y
        for t, u, mt in zip(sol.t, sol.velocity, sol.mu_tilde):
            sh.curve(top, y, u, curve="numerics", t=t, **at(t))
            sh.curve(bottom, y, mt, curve="numerics", t=t, **at(t))
        sh.curve(top, y, steady_velocity(FRICTION, sol.mu_w_inf, y), curve="steady", **STEADY)
        sh.curve(bottom, y, FRICTION.tilde(steady_mu(FRICTION, sol.mu_w_inf, y)), curve="steady", **STEADY)


@figure(1, 1, (6.5, 4.5))
def fig7_speed_layer(sh: Sheet, runs: Runs):
    """Fig. 7: imposed u~_w, delta/delta_s vs 4.653 Dmu sqrt(t~) (eq. (3.20), the imposed-speed erfc profile)
    and 3.66 Dmu sqrt(t~) (quoted with eq. (3.16))"""
    ax = sh.axes[0, 0]
    sh.frame(ax, "a", "t", "delta", log="xy")
    for j, (uw, sol) in enumerate(runs.speed.items()):
        ser = late(sol)
        sh.curve(ax, ser.t, ser.delta, curve="numerics", **case_style(j, uw))
        sh.curve(ax, ser.t.iloc[[0, -1]], sol.steady["delta"], case=f"u_w={uw}", curve="steady", color=f"C{j}", ls=":")
    t = np.logspace(-4, 1, 50)
    for k, ls in ((SELF_SIMILAR_DELTA, "--"), (PAPER_SPEED_DELTA, "-.")):
        sh.curve(ax, t, k * FRICTION.dmu * np.sqrt(t), curve=f"{k:.2f} Dmu sqrt(t)", color="k", ls=ls,
                 label=rf"${k:.2f}\,\Delta\mu\sqrt{{\tilde t}}$")
    ax.set_ylim(top=2.0)


@figure(1, 3)
def fig8_speed_wall_friction(sh: Sheet, runs: Runs):
    """Fig. 8: imposed u~_w, mu_w(t~) against t~ rescaled with the time scales t~_mud (eq. (3.17)) and t~_muw
    (eq. (3.18)); dashed: eq. (3.16) as printed, mu_w - mu_s = u~_w/(3.66 Dmu sqrt(t~))"""
    ax_t, ax_d, ax_w = sh.axes[0]
    sh.frame(ax_t, "a", "t", "mu_w", "(a) wall friction", log="x")
    sh.frame(ax_d, "b", "t/u_w^2", "mu_w-mu_s", f"(b) {eq('TimeScaleMuD')}", log="xy", ylim=(1e-2, 0.5))
    sh.frame(ax_w, "c", "t*(mu_w_inf-mu_s)^2/u_w^2", "(mu_w-mu_s)/(mu_w_inf-mu_s)", f"(c) {eq('TimeScaleMuW')}",
             log="xy", ylim=(0.5, 30))
    for j, (uw, sol) in enumerate(runs.speed.items()):
        ser, excess = late(sol), sol.mu_w_inf - FRICTION.mu_s
        scales, style = speed_time_scales(FRICTION, uw, sol.mu_w_inf), dict(curve="numerics", **case_style(j, uw))
        sh.curve(ax_t, ser.t, ser.mu_w, **style)
        sh.curve(ax_d, ser.t / scales["t_mud"], ser.mu_w - FRICTION.mu_s, **style)
        sh.curve(ax_w, ser.t / scales["t_muw"], (ser.mu_w - FRICTION.mu_s) / excess, **style)
        sh.curve(ax_t, ser.t.iloc[[0, -1]], sol.mu_w_inf, case=f"u_w={uw}", curve="steady", color=f"C{j}", ls=":")
    for ax, plateau in ((ax_t, FRICTION.mu_d), (ax_d, FRICTION.dmu), (ax_w, 1.0)):
        ax.axhline(plateau, color="0.5", lw=0.8)
    scaled = np.logspace(-2, 3, 50)
    for ax in (ax_d, ax_w):
        sh.curve(ax, scaled, 1.0 / (PAPER_SPEED_DELTA * FRICTION.dmu * np.sqrt(scaled)), curve=eq("TimeScaleMu"),
                 color="k", ls="--", label=eq("TimeScaleMu"))


@figure(1, 3)
def fig9_speed_self_similar(sh: Sheet, runs: Runs):
    """Fig. 9: imposed u~_w, mu~ vs eq. (3.20), the imposed-speed erfc profile (dashed), with the numerical
    mu_w(t~)"""
    for j, (uw, sol) in enumerate(runs.speed.items()):
        ax = sh.axes[0, j]
        sh.frame(ax, "abc"[j], "eta", "mu_tilde", panel_title(j, "u_w", uw), case=f"u_w={uw}", xlim=(0, ETA_MAX),
                 ylim=(-0.02, 1.02))
        y = sol.mesh.y
        for t, mu_w, mt in zip(sol.t, sol.mu_w, sol.mu_tilde):
            keep = eta(y, t) <= ETA_MAX
            approx = FRICTION.tilde(speed_short_time_mu(FRICTION, mu_w, y, t))
            sh.curve(ax, eta(y, t)[keep], mt[keep], curve="numerics", t=t, **at(t))
            sh.curve(ax, eta(y, t)[keep], approx[keep], curve=eq("muShortTime_VelocityImposed"), t=t, ls="--",
                     lw=2, **at(t, label=False))
        key(ax, eq("muShortTime_VelocityImposed"), ls="--", lw=2)


def paper_figures(out_dir, numerics: FigureNumerics = FIGURE_NUMERICS) -> dict:
    """Write the nine figures, their CSVs and paper_figures.json into ``out_dir``; return
    {figure name: png path, ..., "timing": {"compute": ..., "plot": ...}}."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    clocks = [(time.perf_counter(), time.process_time())]
    runs = solve_cases(numerics)
    clocks.append((time.perf_counter(), time.process_time()))
    pngs = {}
    for draw, *layout in FIGURES:
        sheet = Sheet(draw.__name__, draw.__doc__, *layout)
        draw(sheet, runs)
        pngs[draw.__name__] = sheet.save(out)
    clocks.append((time.perf_counter(), time.process_time()))
    timing = {phase: {"wall_s": b[0] - a[0], "cpu_s": b[1] - a[1]}
              for phase, a, b in zip(("compute", "plot"), clocks, clocks[1:])}
    timing["note"] = "compute: all solves and WKB projections; plot: other closed forms, drawing, PNG/CSV writing"
    meta = {"friction": {"mu_s": FRICTION.mu_s, "mu_d": FRICTION.mu_d, "dmu": FRICTION.dmu},
            "imposed_stress": {f"mu_w_tilde={mt}": s.metadata() for mt, s in runs.stress.items()},
            "imposed_speed": {f"u_w={uw}": {**s.metadata(), **speed_time_scales(FRICTION, uw, s.mu_w_inf)}
                              for uw, s in runs.speed.items()},
            "fig4_long_time": {"t": FIG4_T, "u_w": {str(k): v for k, v in runs.long_time.items()}},
            "numerics": asdict(numerics), "units": UNITS, "timing": timing,
            "csv_columns": "panel, case, curve (numerics, steady or equation label), t (nan: none), x_var, x, y_var, y",
            "figures": {name: [p.name, p.with_suffix(".csv").name] for name, p in pngs.items()}}
    (out / "paper_figures.json").write_text(json.dumps(meta, indent=2))
    return {**pngs, "timing": timing}
