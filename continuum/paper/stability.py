"""Stability map: where each method stops being trustworthy.

For each method, a grid of the physical parameter (mu~_w for an imposed stress, u~_w for an imposed
speed) against a numerical one (cells, time step or eps); every cell runs the method at that
setting and at a refined one, and is classified (first match wins):

* ``blown up``: an exception (Newton failure, overflow), non-finite or |tau~| > 1e3;
* ``out of bounds``: mu outside [mu_s, mu_d] where the model keeps it inside (stress-diffusion);
* ``constraint-violating``: the returned mu_w off the imposed-speed integral condition's by more than 1e-8 Dmu;
* ``oscillating``: the final tau~ profile has more extrema than the reference (ringing);
* ``inaccurate``: u~_w at the final time more than 1e-3 (relative) from the reference, or grid
  dependence with an observed order below 1.5;
* ``converged``: otherwise (the observed order is kept).

The observed order is measured only where both errors are ORDER_MARGIN times above the reference's
estimated error; below that the runs have converged to the reference (order nan, ``at_reference``).

The explicit scheme's bound is derived, not guessed: dt* = 2/|lambda_min(D L)| with the largest
diffusivity a state can have, D = Dmu^2 sqrt(p~) (mu = mu_s, since D = sqrt(p~)(mu_d - mu)^2), and
L the mesh's second difference (a symmetrisable tridiagonal matrix: eigvalsh_tridiagonal).
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.linalg import eigvalsh_tridiagonal

from .. import observables as obs
from ..load import Load
from ..mesh import Mesh
from ..problems import ImposedSpeed, ImposedStress
from ..rheology import Friction
from ..richardson import REFINEMENT, richardson
from ..rules import YieldRule, wellposedness
from ..scales import Material, Scales
from ..scene import BedScene
from ..solver import CONVERGENCE_ORDER, ORDER_GAIN, SAFETY, Numerics, map_for, solve_speed, solve_stress
from ..steady import mu_w_for_speed, steady_mu
from ..stepper import explicit_euler
from ..velocity import VELOCITY_NUMERICS, solve_velocity

CLASSES = ("converged", "inaccurate", "oscillating", "constraint-violating", "out of bounds", "blown up")
COLORS = {"converged": "#2ca02c", "inaccurate": "#ffbf00", "oscillating": "#9467bd",
          "constraint-violating": "#17becf", "out of bounds": "#8c564b", "blown up": "#d62728"}
MU_W_TILDE = (0.01, 0.03, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99)
U_W = (0.01, 0.1, 1.0, 5.0, 20.0)
T_END = 1.0
VELOCITY_T_TILDE = 0.1  # the velocity-form maps stop here (the yield front has reached the bed)
VELOCITY_P_W = 10.0     # plate pressure of the velocity-form maps (the tilde results do not depend on it)


def explicit_bound(fr: Friction, mu_w: float, mesh: Mesh) -> float:
    """Largest stable forward-Euler step for eq. (2.15) on ``mesh``: 2/|lambda_min(D L)|
    with D = Dmu^2 sqrt(p~) (the largest diffusivity any admissible state has)."""
    p = 1.0 + fr.beta(mu_w) * mesh.y[1:-1]
    D = fr.dmu**2 * np.sqrt(p)
    cl, cd, cu = mesh.d2
    off = np.sqrt((D[1:] * cl[1:]) * (D[:-1] * cu[:-1]))
    lam = eigvalsh_tridiagonal(D * cd, off, select="i", select_range=(0, 0))[0]
    return 2.0 / abs(lam)


def extrema(profile: np.ndarray) -> int:
    """Number of interior extrema (sign changes of the first difference, ignoring round-off)."""
    d = np.diff(profile)
    d = d[np.abs(d) > 1e-12 * max(1.0, np.abs(profile).max())]
    return int(np.sum(np.sign(d[1:]) != np.sign(d[:-1])))


@dataclass
class Outcome:
    u_w: float = math.nan
    tau: np.ndarray | None = None
    mu_range: tuple[float, float] = (math.nan, math.nan)
    constraint: float = 0.0
    error: str = ""
    estimate: float = 0.0  # a reference's estimated relative error of u_w


def _estimated(run: Callable, setting, companion, order: int) -> Outcome:
    """``run(setting)`` as a reference, with the solver's error estimate of u_w (relative): Richardson's with
    SAFETY (continuum.richardson), ``other = run(companion)`` having every error that counts REFINEMENT^order
    times larger."""
    out, other = run(setting), run(companion)
    out.estimate = float(richardson(other.u_w / out.u_w, 1.0, order, SAFETY))
    return out


def _stress_outcome(sol) -> Outcome:
    return Outcome(float(sol.u_w[-1]), sol.tau[-1], (float(sol.mu.min()), float(sol.mu.max())))


def _explicit(fr, mu_w, n, factor) -> Outcome:
    mesh = Mesh.graded(n, 0.0)
    pb = ImposedStress(fr, mu_w, mesh, order=2)  # the three-point scheme of explicit_bound
    dt = factor * explicit_bound(fr, mu_w, mesh)
    steps = int(math.ceil(T_END / dt))
    states, _ = explicit_euler(pb, [steps * dt], np.arange(1, steps + 1) * dt)
    tau = pb.full(states[-1])
    mu = obs.friction_profile(fr, mu_w, mesh, tau)
    return Outcome(float(mesh.weights @ obs.shear_rate(fr, mu_w, mesh, tau)), tau, (mu.min(), mu.max()))


def _speed(fr, u_w, n) -> Outcome:
    sol = solve_speed(fr, u_w, [T_END], _speed_numerics(fr, u_w, n, **SPEED_ADAPTIVE))
    pb = ImposedSpeed(fr, u_w, sol.mesh)
    implied = pb.mu(pb.project(np.concatenate(([0.0], sol.tau[-1, 1:-1]))))[0]  # the condition's mu_w
    out = _stress_outcome(sol)
    out.u_w = float(sol.mu_w[-1])  # the speed is imposed: the wall friction is the result
    out.constraint = abs(implied - out.u_w) / fr.dmu
    return out


def _velocity(fr, mu_w, rule, n, t_tilde=VELOCITY_T_TILDE) -> Outcome:
    m = Material(mu_s=fr.mu_s, mu_d=fr.mu_d)
    sc = Scales(m, VELOCITY_P_W, mu_w)
    load = Load("stress", VELOCITY_P_W, mu_w=mu_w)
    scene = BedScene(sc.delta_s, body_force=m.mu_s * m.phi * m.rho_p * m.g)
    sol = solve_velocity(m, scene, load, [t_tilde * sc.t_s], rule=rule, initial="yield",
                         numerics=replace(VELOCITY_NUMERICS, n_cells=n))
    mu = sol.mu[-1]
    return Outcome(float(sol.u_w[-1] / sc.U), np.abs(sol.s[-1]) / (mu_w * load.p_w),
                   (float(mu.min()), float(mu.max())))


TIGHT = dict(rtol=1e-8, atol=1e-10)
#: the imposed-speed maps: SDIRK4 (the time-step map of the DIRK the stress maps use; the default bdf is
#: charted in bench/speed_solver.py) at a tolerance whose steps (~rtol^-0.55) stay affordable on 400 cells
SPEED_ADAPTIVE = dict(rtol=1e-6, atol=1e-8, method="sdirk4")


def _speed_numerics(fr, u_w, n, **tolerances) -> Numerics:
    """The speed maps' mesh: the exponential map of the layer at T_END (solver.map_for), without the speed's
    wall cluster, whose wall cells stall the reference's tight steps on REFERENCE_CELLS cells (mu_w then
    converges at first order: solver.UNGRADED_SPEED_ORDER)."""
    stretch, _ = map_for(fr, mu_w_for_speed(fr, u_w), "stress", T_END)
    return Numerics(n_cells=n, stretch=stretch, **tolerances)

REFERENCE_CELLS = 400


def _stress_sdirk4(fr, mu_w, n):
    return _stress_outcome(solve_stress(fr, mu_w, [T_END], Numerics(n_cells=n)))


def _stress_cn(fr, mu_w, dt):
    n = max(1, int(round(T_END / dt)))
    steps = T_END * np.arange(1, n + 1) / n
    return _stress_outcome(solve_stress(fr, mu_w, [T_END], Numerics(n_cells=CN_CELLS, method="crank-nicolson"),
                                        fixed_times=steps))


def _stress_bdf(fr, mu_w, n):
    return _stress_outcome(solve_stress(fr, mu_w, [T_END], Numerics(n_cells=n, order=2, method="solve_ivp-BDF")))


def _stress_reference(cells, t_end=T_END):
    """The stress-diffusion solution on ``cells`` cells at the mesh-matched tolerance, with the solver's
    error estimate (space and time, from half the cells)."""
    def reference(fr, mu_w):
        sol = solve_stress(fr, mu_w, [t_end], Numerics(n_cells=cells), estimate=True)
        out = _stress_outcome(sol)
        out.estimate = float(sol.errors["u_w"][-1]) / abs(out.u_w)
        return out
    return reference


def _same_mesh_reference(numerics: Numerics):
    """The reference of a time-step map, on the runs' own mesh: only its time error counts, estimated
    from ORDER_GAIN times the tolerances (the time error is proportional to them)."""
    loose = replace(numerics, rtol=numerics.rtol * ORDER_GAIN, atol=numerics.atol * ORDER_GAIN)
    return lambda fr, mu_w: _estimated(lambda num: _stress_outcome(solve_stress(fr, mu_w, [T_END], num)),
                                       numerics, loose, CONVERGENCE_ORDER["stress"])


def _speed_reference(fr, u_w):
    """The imposed-speed solution at rtol 1e-8 on REFERENCE_CELLS cells with the solver's estimate of
    mu_w, raised to the runs' own time error (SPEED_ADAPTIVE on this mesh), which no refinement removes."""
    sol = solve_speed(fr, u_w, [T_END], _speed_numerics(fr, u_w, REFERENCE_CELLS, **TIGHT), estimate=True)
    runs = solve_speed(fr, u_w, [T_END], _speed_numerics(fr, u_w, REFERENCE_CELLS, **SPEED_ADAPTIVE))
    mu_w = float(sol.mu_w[-1])
    return Outcome(mu_w, sol.tau[-1], estimate=max(float(sol.errors["mu_w"][-1]), abs(runs.mu_w[-1] - mu_w)) / mu_w)


EXPLICIT_CELLS, CN_CELLS, BARKER_GRAY_EPS = 40, 100, 1e-5
EPS, EPS_CELLS = (1e-2, 1e-3, 1e-4, 1e-5), 200  # the regularised velocity form's map
#: the velocity form's order in space (the error estimates of its runs)
VELOCITY_ORDER = 2


def _barker_gray(fr, mu_w, n):
    return _velocity(fr, mu_w, YieldRule("barker-gray", BARKER_GRAY_EPS), n)


def _regularised(fr, mu_w, eps, n=EPS_CELLS):
    return _velocity(fr, mu_w, YieldRule("regularised", eps), n)


def _regularised_reference(fr, mu_w):
    """The eps -> 0 limit (the stress solution at VELOCITY_T_TILDE), its estimate raised to the runs'
    own space error (EPS_CELLS cells at the finest eps, from half the cells), which no eps removes."""
    ref = _stress_reference(REFERENCE_CELLS, VELOCITY_T_TILDE)(fr, mu_w)
    space = _estimated(lambda n: _regularised(fr, mu_w, EPS[-1] / REFINEMENT, n), EPS_CELLS,
                       EPS_CELLS // REFINEMENT, VELOCITY_ORDER)
    ref.estimate = max(ref.estimate, space.estimate)
    return ref


@dataclass(frozen=True)
class MethodMap:
    """One method: the physical parameter, the numerical axis, the runner and its reference.

    ``run(friction, param, value)`` and ``reference(friction, param)`` return an ``Outcome``; for
    ``param = "mu_w_tilde"`` they receive mu_w, for ``"u_w"`` the speed.  ``design_order``: the order
    expected along the axis; ``tolerance``: the relative error of u~_w (of mu_w for an imposed speed)
    at the final time above which a run is inaccurate; ``bounded``: the model keeps mu_s <= mu."""

    name: str
    param: str
    params: tuple
    axis: str
    values: tuple
    refine: tuple  # the refined setting for each value (order/grid dependence)
    run: Callable
    reference: Callable
    design_order: float = 2.0
    tolerance: float = 1e-3
    bounded: bool = True

    def physical(self, fr: Friction, param):
        return fr.mu_w_from_tilde(param) if self.param == "mu_w_tilde" else param


METHODS = (
    MethodMap("stress SDIRK4 (adaptive)", "mu_w_tilde", MU_W_TILDE, "n_cells", (25, 50, 100, 200), (50, 100, 200, 400),
              _stress_sdirk4, _stress_reference(REFERENCE_CELLS)),
    MethodMap("stress Crank-Nicolson (uniform dt)", "mu_w_tilde", MU_W_TILDE, "dt", (0.1, 0.03, 0.01, 0.003),
              (0.05, 0.015, 0.005, 0.0015), _stress_cn,
              _same_mesh_reference(Numerics(n_cells=CN_CELLS, **TIGHT))),
    MethodMap("stress explicit Euler (dt / dt*)", "mu_w_tilde", MU_W_TILDE, "dt/dt*", (2.0, 1.1, 0.9, 0.5),
              (1.0, 0.55, 0.45, 0.25), lambda fr, mu_w, f: _explicit(fr, mu_w, EXPLICIT_CELLS, f),
              _same_mesh_reference(Numerics(n_cells=EXPLICIT_CELLS, stretch=0.0, order=2, **TIGHT)),
              design_order=1.0),
    MethodMap("stress solve_ivp BDF (baseline)", "mu_w_tilde", MU_W_TILDE, "n_cells", (25, 50, 100, 200),
              (50, 100, 200, 400), _stress_bdf, _stress_reference(REFERENCE_CELLS)),
    MethodMap("speed SDIRK4 (adaptive)", "u_w", U_W, "n_cells", (25, 50, 100, 200), (50, 100, 200, 400),
              _speed, _speed_reference),
    MethodMap("velocity form, regularised (eps)", "mu_w_tilde", MU_W_TILDE[1::2], "eps", EPS,
              tuple(eps / REFINEMENT for eps in EPS), _regularised, _regularised_reference,
              design_order=2 / 3, tolerance=1e-2, bounded=False),
    MethodMap("velocity form, Barker-Gray", "mu_w_tilde", MU_W_TILDE[1::2], "n_cells", (50, 100, 200),
              (100, 200, 400), _barker_gray,
              lambda fr, mu_w: _estimated(lambda n: _barker_gray(fr, mu_w, n), REFINEMENT * REFERENCE_CELLS,
                                          REFERENCE_CELLS, VELOCITY_ORDER),
              design_order=VELOCITY_ORDER, bounded=False),
)

#: an order is observed only where both errors exceed this multiple of the reference's estimate (which
#: is about SAFETY times its true error): the reference's error then shifts a 4th-order estimate by < 0.2
ORDER_MARGIN = 3.0


def classify(fr: Friction, method: MethodMap, out: Outcome, fine: Outcome, ref: Outcome) -> tuple[str, float]:
    """The class of a run and its observed order along the axis (nan when not measurable)."""
    for o in (out, fine):
        if o.error or not np.isfinite(o.u_w) or o.tau is None or not np.all(np.isfinite(o.tau)) \
                or np.abs(o.tau).max() > 1e3:
            return "blown up", math.nan
    if out.mu_range[1] > fr.mu_d or (method.bounded and out.mu_range[0] < fr.mu_s - 1e-9):
        return "out of bounds", math.nan
    if out.constraint > 1e-8:
        return "constraint-violating", math.nan
    if extrema(out.tau) > extrema(ref.tau) + 1:
        return "oscillating", math.nan
    err, err_fine = abs(out.u_w / ref.u_w - 1), abs(fine.u_w / ref.u_w - 1)
    ratio = abs(math.log(method.values[0] / method.refine[0]))
    measurable = min(err, err_fine) > ORDER_MARGIN * ref.estimate
    order = math.log(err / err_fine) / ratio if measurable else math.nan  # else: converged to the reference
    if err > method.tolerance or order < method.design_order - 0.5:
        return "inaccurate", order
    return "converged", order


def _safe(method, fr, param, value) -> Outcome:
    try:
        with np.errstate(all="ignore"):
            return method.run(fr, method.physical(fr, param), value)
    except (RuntimeError, FloatingPointError, ValueError, ArithmeticError) as err:
        return Outcome(error=f"{type(err).__name__}: {err}")


def stability_table(fr: Friction, methods=METHODS) -> pd.DataFrame:
    rows = []
    for method in methods:
        for param in method.params:
            ref = method.reference(fr, method.physical(fr, param))
            for value, finer in zip(method.values, method.refine):
                start = time.process_time()
                out, fine = _safe(method, fr, param, value), _safe(method, fr, param, finer)
                label, order = classify(fr, method, out, fine, ref)
                rows.append({"method": method.name, "param": method.param, "param_value": param, "axis": method.axis,
                             "axis_value": value, "class": label, "order": order,
                             "at_reference": label in ("converged", "inaccurate") and math.isnan(order),
                             "ref_estimate": ref.estimate,
                             "rel_error": abs(out.u_w / ref.u_w - 1) if np.isfinite(out.u_w) else math.nan,
                             "cpu_s": time.process_time() - start, "error": out.error or fine.error})
    return pd.DataFrame(rows)


def plot_maps(table: pd.DataFrame, out: Path) -> list[Path]:
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch, Rectangle

    paths = []
    for name, g in table.groupby("method", sort=False):
        params, values = sorted(g.param_value.unique()), list(dict.fromkeys(g.axis_value))
        fig = Figure(figsize=(7.5, 3.6), layout="constrained")
        ax = fig.subplots()
        for _, r in g.iterrows():
            i, j = params.index(r.param_value), values.index(r.axis_value)
            ax.add_patch(Rectangle((i - 0.5, j - 0.5), 1, 1, color=COLORS[r["class"]]))
            label = f"{r.order:.1f}" if np.isfinite(r.order) else "ref" if r.at_reference else ""
            ax.text(i, j, label, ha="center", va="center", fontsize=8)
        ax.set(xlim=(-0.5, len(params) - 0.5), ylim=(-0.5, len(values) - 0.5),
               xticks=range(len(params)), yticks=range(len(values)),
               xlabel={"mu_w_tilde": "mu~_w = (mu_d - mu_w)/Dmu", "u_w": "u~_w"}[g.param.iloc[0]],
               ylabel=g.axis.iloc[0],
               title=f"{name}\nnumbers: observed order; ref: errors at the reference's accuracy (no order)")
        ax.set_xticklabels([f"{p:g}" for p in params])
        ax.set_yticklabels([f"{v:g}" for v in values])
        present = [c for c in CLASSES if c in set(g["class"])]
        ax.legend(handles=[Patch(color=COLORS[c], label=c) for c in present], fontsize=7,
                  loc="upper left", bbox_to_anchor=(1.01, 1))
        path = out / f"stability_{''.join(ch if ch.isalnum() else '_' for ch in name.lower()).strip('_')}.png"
        fig.savefig(path, dpi=120)
        paths.append(path)
    return paths


def wellposedness_profiles(materials: dict[str, Material], mu_w_tildes=(0.9, 0.5, 0.1), n=400) -> pd.DataFrame:
    """Barker et al. (2015) eq. 3.9 along the steady layer y~ in [0, 1]: I(y~) from the steady
    mu(y~) (eq. (2.10)) through the inverse mu(I) law; negative = well posed."""
    rows = []
    y = np.linspace(0.0, 1.0, n + 1)[:-1]
    for label, m in materials.items():
        fr = m.friction
        for mt in mu_w_tildes:
            mu = steady_mu(fr, fr.mu_w_from_tilde(mt), y)
            I = fr.I_of_mu(mu, m.I0_paper)
            rows.append(pd.DataFrame({"material": label, "mu_w_tilde": mt, "y": y, "I_paper": I,
                                      "criterion": wellposedness(fr, m.I0_paper, I)}))
    return pd.concat(rows, ignore_index=True)


def plot_wellposedness(df: pd.DataFrame, path: Path) -> Path:
    from matplotlib.figure import Figure

    materials = list(dict.fromkeys(df.material))
    fig = Figure(figsize=(5 * len(materials), 4), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(materials), sharey=True))
    for ax, label in zip(axes, materials):
        for mt, g in df[df.material == label].groupby("mu_w_tilde"):
            ax.plot(g.criterion, g.y, label=f"mu~_w = {mt:g}")
        ax.axvline(0.0, color="k", lw=0.8)
        ax.axvspan(0.0, max(df.criterion.max(), 0.01), color="r", alpha=0.08, label="ill posed (> 0)")
        ax.set(xlabel="4nu^2 - 4nu + mu^2(1 - nu/2)^2, nu = I mu'/mu",
               title=f"{label}\nBarker et al. 2015 eq. 3.9: > 0 ill posed")
    axes[0].set_ylabel("y~ = y/delta_s (steady layer)")
    axes[0].invert_yaxis()
    axes[0].legend(fontsize=8)
    fig.savefig(path, dpi=120)
    return path


def write_stability(out_dir, calibrated: Material | None = None) -> dict:
    """Run every map; write PNGs, stability.csv and the well-posedness plot into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paper = Material()
    fr = paper.friction
    table = stability_table(fr)
    table.to_csv(out / "stability.csv", index=False)
    maps = plot_maps(table, out)
    materials = {"paper's beads (tan 21°, tan 33°, I0_dem 0.279)": paper}
    if calibrated is not None:
        m = calibrated
        materials[f"DEM-calibrated ({m.mu_s:.3f}, {m.mu_d:.3f}, I0_{m.I_convention} {m.I0:.3g})"] = m
    wp = wellposedness_profiles(materials)
    wp.to_csv(out / "wellposedness.csv", index=False)
    return {"table": table, "maps": maps, "wellposedness": plot_wellposedness(wp, out / "wellposedness.png")}
