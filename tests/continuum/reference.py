"""Independent converged reference for the continuum solver: test-only code.

Imposed stress: eq. (3.1) (the paper's equation for mu, not the solver's tau~ form)
for v = (mu - mu_s)/(mu_w - mu_s), the quantity that defines delta,

    dv/dt~ = (Dmu - (mu_w - mu_s) v)^2 (2 beta_w/sqrt(p~) dv/dy~ + sqrt(p~) d2v/dy~2),   p~ = 1 + beta_w y~,

v(0) = 1, v(1) = 0, v(y~ > 0, 0) = 0 (eqs. (2.7), (2.8)-(2.9)).  Space: Chebyshev collocation
of degree n in s in [0, 1] under y~ = (e^(a s) - 1)/(e^a - 1), whose stretch a puts the wall diffusion
length Dmu mu~_w sqrt(t~_min) at s = WALL_SHARE; time: scipy's Radau IIA (order 5) with the analytic
Jacobian from t~ = 0.  Observables with the solver's definitions (continuum.observables):
u~_w = int_0^1 sqrt(p~)/Dmu (mu - mu_s)/(mu_d - mu) dy~ (eq. (3.10)) by Clenshaw-Curtis,
mu_w = mu(0), delta = the first depth where v = DELTA_THRESHOLD, a root of the interpolant.

Converged means: the degree-COARSE_DEGREE, rtol-COARSE_RTOL companion differs by less than CONVERGED
(relative) in every quantity at every time.  Imposed speed (``speed_reference``): the same collocation
of eq. (3.14), converged at every time by pieces (``pieces``): on wall-clustered maps before
and through the lift-off of mu_w from mu_d, on the exponential map after it (see there).  The
values of both, at both resolutions, are cached in data/reference.csv, written by
``python -m tests.continuum.reference [CASE-PREFIX ...]`` (tests/continuum/test_reference.py checks the cache).

Shared with the solver (so not checked by this reference): continuum.rheology.Friction (beta_w, mu~ and
mu_w from mu~_w), DELTA_THRESHOLD and the steady mu_w^inf of a speed (continuum.steady, tested against
its closed forms in tests/continuum/test_steady_and_scales.py).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from granstokes.continuum.rheology import Friction
from granstokes.continuum.steady import DELTA_THRESHOLD, mu_w_for_speed
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from threadpoolctl import threadpool_limits

#: reference degree and time tolerance, and those of its refinement companion
DEGREE, RTOL = 160, 1e-12
COARSE_DEGREE, COARSE_RTOL = 128, 1e-11
#: atol = ATOL_PER_RTOL rtol (v is in [0, 1]; delta is read where v = 1e-3)
ATOL_PER_RTOL = 1e-2
#: the reference's relative accuracy: the companion's largest change is asserted below it
CONVERGED = 1e-9
#: the map's s at the wall diffusion length Dmu mu~_w sqrt(t~_min) (tuned: mu~_w = 0.1 needs the wall
#: sub-layer resolved, mu~_w = 0.9 the erfc tail where delta is read)
WALL_SHARE = 0.036
#: the stretch of a map that is uniform to 0.1 % (a layer already thick at t~_min)
UNIFORM_STRETCH = 1e-3
#: Radau's first step (t~ = 0 is an incompatible start: v jumps from 0 to 1 at the wall)
FIRST_STEP = 1e-14
#: the paper's times (section 3) and the stress cases, the paper's three and the disks': (name, mu_s, mu_d, mu~_w)
TIMES = (1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0)
PAPER = Friction(math.tan(math.radians(21.0)), math.tan(math.radians(33.0)))
DISKS = Friction(0.28, 0.77)
STRESS_CASES = {"paper-0.9": (PAPER, 0.9), "paper-0.5": (PAPER, 0.5), "paper-0.1": (PAPER, 0.1),
                "disks-0.3": (DISKS, 0.3)}
#: imposed speed (SPEED_CASES): the map's stretch
#: (geometric clustering at the wall down to e^-8, for the wall sub-layer) and the degrees of the
#: reference and its companion (10-40 s of CPU per solve)
SPEED_STRETCH = 8.0
SPEED_DEGREE, SPEED_COARSE_DEGREE = 96, 64
#: before and through the lift-off (``speed_early_case``): the map of SPEED_STRETCH plus a wall cluster of
#: EARLY_WALL_FOLDS e-folds within CLUSTER_WIDTH of the wall (the solver's map, continuum.mesh); the degrees of
#: the reference and its companion (8-200 s of CPU per solve).  Measured, degree 128 against 160: u~_w, mu_w,
#: delta within 2e-10 (with 14 e-folds delta moves 1.4e-7 at t~ = 1e-4), through the lift-off too (1.334 and
#: the disks at t~ = 0.1, 4.629 at 1: within 2.7e-11), where the map of SPEED_STRETCH alone is off by 2e-8-8e-8
EARLY_WALL_FOLDS, CLUSTER_WIDTH = 12.0, 0.1
EARLY_DEGREE, EARLY_COARSE_DEGREE = 160, 128
#: u~_w = 0.198's lift-off (t~_mud = 0.039) is a solve apart on a shallower cluster (``speed_lift_off_case``):
#: on EARLY_WALL_FOLDS, and on 9, Radau fails in it ("step size less than spacing"); on 6 it passes, converged
#: at t~ = 1e-2 and 0.1 (degree 128 against 160 within 1.2e-10), not before (4.6e-8 at 1e-3: the early solve's)
LIFT_OFF_WALL_FOLDS = 6.0
#: from its first converged time on, 0.198 is carried to the exponential map of this stretch (``speed_reference``
#: ``remap``): on SPEED_STRETCH the wall unknown, stiff through the wall node's weight ~ 1e-8, stalls Radau
#: between t~ = 1 and 10 (mu~_w ~ 0.9); on stretch 2 degree 96 against 128 agree within 2e-13 at t~ = 3 and 10
REMAP_STRETCH = 2.0


@dataclass(frozen=True)
class SpeedCase:
    """An imposed-speed case: its friction and u~_w, the output times of its reference, those solved on the
    wall-clustered map (before and through its lift-off, t~_mud = u~_w^2) and on the lift-off's own map, the time
    from which the exponential map's reference is converged to CONVERGED (measured, test_reference.py) and,
    if set, the time from which it runs on REMAP_STRETCH; cached as speed-early-LABEL, speed-lift-off-LABEL
    and speed-LABEL (``pieces``)."""

    friction: Friction
    u_w: float
    times: tuple
    early_times: tuple
    converged_from: float
    lift_off_times: tuple = ()
    remap_from: float | None = None


#: the paper's three wall speeds (section 3.4; t~_mud = 0.039, 1.8, 21) and a second parameter set, the disks
#: (DISKS) at u~_w = 1 (t~_mud = 1, mu~_w^inf = 0.34).  The exponential map's reference is converged after the
#: lift-off (2e-9 at t~ = 0.1 for 0.198, 3e-8 at t~ = 1 for 4.629, 2.6e-8 at 0.1 for the disks), so from the
#: next time on; the times before on the clustered maps
SPEED_CASES = {"0.198": SpeedCase(PAPER, 0.198, TIMES, TIMES[:2], 1.0, TIMES[2:4], 1.0),
               "1.334": SpeedCase(PAPER, 1.334, TIMES, TIMES[:4], 1.0),
               "4.629": SpeedCase(PAPER, 4.629, TIMES, TIMES[:5], 10.0),
               "disks-1": SpeedCase(DISKS, 1.0, TIMES, TIMES[:4], 1.0)}


def pieces(label: str) -> dict:
    """The cached solves that cover one of SPEED_CASES, each where it is converged: {cache name: its times}."""
    case = SPEED_CASES[label]
    out = {f"speed-early-{label}": case.early_times, f"speed-lift-off-{label}": case.lift_off_times,
           f"speed-{label}": tuple(t for t in case.times if t >= case.converged_from)}
    return {name: times for name, times in out.items() if times}


DATA = Path(__file__).parent / "data" / "reference.csv"
QUANTITIES = ("u_w", "mu_w", "delta")


@dataclass(frozen=True)
class Reference:
    """u~_w, mu_w and delta/delta_s at the times t~, from one solve of ``degree`` and ``rtol``."""

    t: np.ndarray
    u_w: np.ndarray
    mu_w: np.ndarray
    delta: np.ndarray
    degree: int
    rtol: float
    cpu: float  # seconds of CPU time of the solve


class ChebyshevMap:
    """Chebyshev points x_j = (1 - cos(pi j/n))/2 (x_0 = 0 at the wall) mapped to y~ = expm1(s(x))/expm1(s(1)),
    s(x) = a x + E (1 - e^(-x/w))/(1 - e^(-1/w)) (stretch a, wall cluster of E e-folds, width w = CLUSTER_WIDTH;
    E = 0: the exponential map); d/dy~, d2/dy~2 (y~''/y~' = s' + s''/s') and Clenshaw-Curtis weights in y~."""

    def __init__(self, degree: int, stretch: float, wall_folds: float = 0.0):
        n = degree
        theta = np.pi * np.arange(n + 1) / n
        x = np.cos(theta)
        self.stretch, self.wall_folds = stretch, wall_folds
        self.s = (1 - x) / 2
        self.y = self.depth(self.s)
        cluster = wall_folds / -math.expm1(-1 / CLUSTER_WIDTH) * np.exp(-self.s / CLUSTER_WIDTH)
        ds, dds = stretch + cluster / CLUSTER_WIDTH, -cluster / CLUSTER_WIDTH**2
        dy_ds = np.exp(self._exponent(self.s)) * ds / math.expm1(self._exponent(1.0))
        c = np.r_[2.0, np.ones(n - 1), 2.0] * (-1.0) ** np.arange(n + 1)
        dx = x[:, None] - x[None, :] + np.eye(n + 1)
        d = np.outer(c, 1 / c) / dx
        d -= np.diag(d.sum(axis=1))  # d/dx (Trefethen, Spectral Methods in MATLAB, cheb)
        d_ds = -2.0 * d
        self.d1 = d_ds / dy_ds[:, None]
        self.d2 = (d_ds @ d_ds - (ds + dds / ds)[:, None] * d_ds) / dy_ds[:, None] ** 2
        self.weights = _clenshaw_curtis(theta) / 2 * dy_ds
        self.bary = (-1.0) ** np.arange(n + 1) * np.r_[0.5, np.ones(n - 1), 0.5]  # barycentric, Chebyshev points

    def _exponent(self, s):
        """s(x) of the map (class docstring)."""
        return self.stretch * s + self.wall_folds * np.expm1(-s / CLUSTER_WIDTH) / math.expm1(-1 / CLUSTER_WIDTH)

    def depth(self, s):
        """y~ at the map's coordinate s (x above)."""
        total = self._exponent(1.0)
        return np.expm1(self._exponent(s)) / math.expm1(total) if total > 0 else s

    def interpolate(self, f: np.ndarray, s: float) -> float:
        """The degree-n interpolant of nodal values ``f`` at s (barycentric formula)."""
        diff = s - self.s
        hit = diff == 0
        if hit.any():
            return float(f[hit][0])
        w = self.bary / diff
        return float(w @ f / w.sum())

    def crossing(self, f: np.ndarray, level: float) -> float:
        """First depth y~ where the interpolant of ``f`` falls to ``level``."""
        j = int(np.argmax(f < level))
        s = brentq(lambda s: self.interpolate(f, s) - level, self.s[j - 1], self.s[j], xtol=1e-16, rtol=1e-15)
        return float(self.depth(s))


def _clenshaw_curtis(theta: np.ndarray) -> np.ndarray:
    """Clenshaw-Curtis weights on [-1, 1] at the points cos(theta_j), theta_j = pi j/n (Waldvogel 2006)."""
    n = len(theta) - 1
    v = np.ones(n - 1)
    for k in range(1, n // 2 + 1):
        v -= (1.0 if 2 * k < n else 0.5) * 2 * np.cos(2 * k * theta[1:-1]) / (4 * k * k - 1)
    end = 1.0 / (n * n - 1) if n % 2 == 0 else 1.0 / (n * n)
    return np.r_[end, 2 * v / n, end]


def wall_stretch(fr: Friction, mu_w: float, t_min: float) -> float:
    """The a with s(l) = WALL_SHARE for l = Dmu mu~_w sqrt(t~_min), i.e. ln(1 + l (e^a - 1)) = WALL_SHARE a
    (a root below 2 ln(1/l)/(1 - WALL_SHARE)); UNIFORM_STRETCH where l is not below WALL_SHARE."""
    length = fr.dmu * fr.tilde(mu_w) * math.sqrt(t_min)
    if length >= WALL_SHARE:
        return UNIFORM_STRETCH
    return brentq(lambda a: math.log1p(length * math.expm1(a)) - WALL_SHARE * a, UNIFORM_STRETCH,
                  2 * math.log(1 / length) / (1 - WALL_SHARE))


def stress_reference(fr: Friction, mu_w: float, times=TIMES, degree: int = DEGREE, rtol: float = RTOL) -> Reference:
    """u~_w(t~), mu_w(t~) = mu_w and delta(t~) for an imposed wall stress (eq. (3.1))."""
    t = np.asarray(times, dtype=float)
    beta, excess = fr.beta(mu_w), mu_w - fr.mu_s
    grid = ChebyshevMap(degree, wall_stretch(fr, mu_w, t[0]))
    p = 1 + beta * grid.y
    op = ((2 * beta / np.sqrt(p))[:, None] * grid.d1 + np.sqrt(p)[:, None] * grid.d2)[1:-1]
    op_in, op_wall = op[:, 1:-1], op[:, 0]  # v(0) = 1, v(1) = 0

    def rate(_, v):
        return (fr.dmu - excess * v) ** 2 * (op_in @ v + op_wall)

    def jacobian(_, v):
        g = fr.dmu - excess * v
        jac = (g * g)[:, None] * op_in
        jac[np.diag_indices_from(jac)] -= 2 * excess * g * (op_in @ v + op_wall)
        return jac

    start = time.process_time()
    with threadpool_limits(1):  # dense LU of ~160 unknowns: threads only contend on a shared machine
        sol = solve_ivp(rate, (0.0, t[-1]), np.zeros(degree - 1), method="Radau", t_eval=t, rtol=rtol,
                        atol=ATOL_PER_RTOL * rtol, jac=jacobian, first_step=FIRST_STEP)
    cpu = time.process_time() - start
    if not sol.success:
        raise RuntimeError(sol.message)
    v = np.column_stack([np.ones(len(t)), sol.y.T, np.zeros(len(t))])
    mu = fr.mu_s + excess * v
    u_w = (np.sqrt(p) / fr.dmu * (mu - fr.mu_s) / (fr.mu_d - mu)) @ grid.weights
    delta = np.array([grid.crossing(row, DELTA_THRESHOLD) for row in v])
    return Reference(t, u_w, mu[:, 0], delta, degree, rtol, cpu)


def _speed_system(fr: Friction, u_w: float, grid: ChebyshevMap):
    """Rate and Jacobian of x = (q, mu~ at the interior nodes) on ``grid`` (speed_reference), and sqrt(p~) w_j."""
    degree = len(grid.y) - 1
    beta, dmu = fr.beta(mu_w_for_speed(fr, u_w)), fr.dmu
    p = 1 + beta * grid.y
    op = ((2 * beta / np.sqrt(p))[:, None] * grid.d1 + np.sqrt(p)[:, None] * grid.d2)[1:-1]
    op_wall, op_in, op_bottom = op[:, 0], op[:, 1:-1], op[:, -1]
    weights = grid.weights * np.sqrt(p)
    gain, inner = dmu**2 / weights[0], weights[1:-1]

    def rate(_, x):
        wall, m = math.exp(-x[0]), x[1:]
        lap = op_wall * wall + op_in @ m + op_bottom
        out = np.empty(degree)
        out[0], out[1:] = gain * wall * (inner @ lap), dmu**2 * m * m * lap
        return out

    def jacobian(_, x):
        wall, m = math.exp(-x[0]), x[1:]
        lap = op_wall * wall + op_in @ m + op_bottom
        jac = np.empty((degree, degree))
        jac[0, 0] = -gain * wall * (inner @ lap + wall * (inner @ op_wall))
        jac[0, 1:] = gain * wall * (inner @ op_in)
        jac[1:, 0] = -dmu**2 * m * m * op_wall * wall
        jac[1:, 1:] = dmu**2 * (m * m)[:, None] * op_in
        jac[1:, 1:][np.diag_indices(degree - 1)] += 2 * dmu**2 * m * lap
        return jac

    return rate, jacobian, weights


def _remapped(old: ChebyshevMap, x: np.ndarray, new: ChebyshevMap, weights: np.ndarray, target: float) -> np.ndarray:
    """The state x on ``old`` carried to ``new``: mu~ interpolated at the new nodes, q from the integral condition
    (``weights`` sqrt(p~) w_j of ``new``, ``target`` = u~_w Dmu)."""
    m = np.r_[math.exp(-x[0]), x[1:], 1.0]
    s_old = np.log1p(new.y * math.expm1(old.stretch)) / old.stretch  # old.wall_folds == 0
    m_new = np.array([old.interpolate(m, s) for s in s_old])
    share = weights[1:-1] @ (1 / m_new[1:-1] - 1)
    return np.r_[math.log1p((target - share) / weights[0]), m_new[1:-1]]


def speed_reference(fr: Friction, u_w: float, times=TIMES, degree: int = SPEED_DEGREE, rtol: float = RTOL,
                    wall_folds: float = 0.0, remap: tuple | None = None) -> Reference:
    """u~_w(t~), mu_w(t~) and delta(t~) for an imposed wall speed: eq. (3.14) for mu~ at the
    interior nodes (mu~(1) = 1, mu~(y~, 0) = 1, beta_w from the steady mu_w^inf) and q = ln(1/mu~_w) at the
    wall, from eq. (3.15) (Clenshaw-Curtis weights w_j) differentiated in time,

        w_0 sqrt(p~_0) e^q dq/dt~ = sum_j>0 w_j sqrt(p~_j) (dmu~_j/dt~)/mu~_j^2,

    from the q that puts all of u~_w in the wall node's weight at t~ = 0 (the discrete form of the
    singular start); the returned u~_w is the quadrature, so shows the drift.  Before t~_mud ~ u~_w^2 the
    continuum's mu~_w is exponentially small (below e^-700 at t~ = 1e-4 for the larger speeds) in a wall
    sub-layer no grid resolves: there the discrete mu~_w is set by the wall node's weight and the
    reference converges slowly (measured, test_reference.py).  ``remap`` = (t~_r, stretch): from the output
    time t~_r on, the exponential map of this stretch (SpeedCase.remap_from, REMAP_STRETCH), the state carried
    over by ``_remapped``."""
    t = np.asarray(times, dtype=float)
    grids, spans = [ChebyshevMap(degree, SPEED_STRETCH, wall_folds)], [t]
    if remap is not None:
        assert remap[0] in t and not wall_folds, "remap at an output time, from the exponential map"
        grids.append(ChebyshevMap(degree, remap[1]))
        spans = [t[t <= remap[0]], t[t > remap[0]]]
    start = time.process_time()
    out = []
    with threadpool_limits(1):
        for k, (grid, t_seg) in enumerate(zip(grids, spans)):
            rate, jacobian, weights = _speed_system(fr, u_w, grid)
            if k == 0:
                x, t0, first = np.r_[math.log1p(u_w * fr.dmu / weights[0]), np.ones(degree - 1)], 0.0, FIRST_STEP
            else:
                x, t0, first = _remapped(grids[k - 1], x, grid, weights, u_w * fr.dmu), spans[k - 1][-1], None
            sol = solve_ivp(rate, (t0, t_seg[-1]), x, method="Radau", t_eval=t_seg, rtol=rtol,
                            atol=ATOL_PER_RTOL * rtol, jac=jacobian, first_step=first)
            if not sol.success:
                raise RuntimeError(sol.message)
            out.append(_speed_observables(fr, grid, weights, sol.y))
            x = sol.y[:, -1]
    cpu = time.process_time() - start
    u, mu_w, delta = (np.concatenate(parts) for parts in zip(*out))
    return Reference(t, u, mu_w, delta, degree, rtol, cpu)


def _speed_observables(fr: Friction, grid: ChebyshevMap, weights: np.ndarray, y: np.ndarray):
    """u~_w (the quadrature with ``weights`` sqrt(p~) w_j), mu_w and delta of the states y (columns) on ``grid``."""
    mt = np.column_stack([np.exp(-y[0]), y[1:].T, np.ones(y.shape[1])])
    v = (1 - mt) / (1 - mt[:, :1])  # (mu - mu_s)/(mu_w - mu_s)
    delta = np.array([grid.crossing(row, DELTA_THRESHOLD) for row in v])
    return (1 / mt - 1) @ weights / fr.dmu, fr.mu_d - fr.dmu * mt[:, 0], delta


def stress_case(name: str, degree: int = DEGREE, rtol: float = RTOL) -> Reference:
    """The reference of one of STRESS_CASES at TIMES."""
    fr, mu_w_tilde = STRESS_CASES[name]
    return stress_reference(fr, fr.mu_w_from_tilde(mu_w_tilde), TIMES, degree, rtol)


def tabulate(name: str, ref: Reference):
    """Rows of the cache for one solve."""
    import pandas as pd

    return pd.DataFrame({"case": name, "degree": ref.degree, "rtol": ref.rtol, "t": ref.t, "u_w": ref.u_w,
                         "mu_w": ref.mu_w, "delta": ref.delta, "cpu_s": ref.cpu})


def load():
    """The cache (data/reference.csv) as a DataFrame: one row per case, resolution and time."""
    import pandas as pd

    return pd.read_csv(DATA)


def cached(case: str, degree: int | None = None, times=TIMES, table=None) -> dict:
    """u~_w, mu_w and delta (arrays at ``times``) of one cached case, at the reference degree (default) or
    ``degree``, from ``table`` (default: ``load()``)."""
    table = load() if table is None else table
    degree = degree or (EARLY_DEGREE if case.startswith(("speed-early", "speed-lift-off")) else
                        SPEED_DEGREE if case.startswith("speed") else DEGREE)
    rows = table[(table.case == case) & (table.degree == degree)]
    if not np.array_equal(rows.t, times):
        raise KeyError(f"{case} at degree {degree} is not cached at t~ = {list(times)}")
    return {q: rows[q].to_numpy() for q in QUANTITIES}


def assembled(label: str, table=None) -> dict:
    """u~_w, mu_w and delta (arrays at its times) of one of SPEED_CASES, each time from its converged piece
    (``pieces``; the exponential map's solve is cached at all the case's times)."""
    table = load() if table is None else table
    times = np.array(SPEED_CASES[label].times)
    out = {q: np.full(len(times), np.nan) for q in QUANTITIES}
    for name, piece in pieces(label).items():
        solved = times if name == f"speed-{label}" else np.array(piece)
        values = cached(name, times=solved, table=table)
        for q in QUANTITIES:
            out[q][np.isin(times, piece)] = values[q][np.isin(solved, piece)]
    return out


def speed_case(label: str, degree: int = SPEED_DEGREE) -> Reference:
    """The reference of one of SPEED_CASES at its times (on REMAP_STRETCH from its ``remap_from``)."""
    case = SPEED_CASES[label]
    remap = None if case.remap_from is None else (case.remap_from, REMAP_STRETCH)
    return speed_reference(case.friction, case.u_w, case.times, degree, remap=remap)


def speed_early_case(label: str, degree: int = EARLY_DEGREE) -> Reference:
    """The reference of one of SPEED_CASES at its early_times, on the wall-clustered map."""
    case = SPEED_CASES[label]
    return speed_reference(case.friction, case.u_w, case.early_times, degree, wall_folds=EARLY_WALL_FOLDS)


def speed_lift_off_case(label: str, degree: int = EARLY_DEGREE) -> Reference:
    """The reference of one of SPEED_CASES at its lift_off_times, on the map of LIFT_OFF_WALL_FOLDS."""
    case = SPEED_CASES[label]
    return speed_reference(case.friction, case.u_w, case.lift_off_times, degree, wall_folds=LIFT_OFF_WALL_FOLDS)


def main(only: list[str]) -> None:
    """Recompute every case at both resolutions and write the cache; ``only``: the cases whose names start
    with one of these, replaced in the cache, the others kept."""
    import pandas as pd

    solves = [(name, degree, lambda name=name, degree=degree, rtol=rtol: stress_case(name, degree, rtol))
              for name in STRESS_CASES for degree, rtol in ((COARSE_DEGREE, COARSE_RTOL), (DEGREE, RTOL))]
    solves += [(f"speed-{label}", degree, lambda label=label, degree=degree: speed_case(label, degree))
               for label in SPEED_CASES for degree in (SPEED_COARSE_DEGREE, SPEED_DEGREE)]
    solves += [(f"speed-early-{label}", degree, lambda label=label, degree=degree: speed_early_case(label, degree))
               for label in SPEED_CASES for degree in (EARLY_COARSE_DEGREE, EARLY_DEGREE)]
    solves += [(f"speed-lift-off-{label}", degree,
                lambda label=label, degree=degree: speed_lift_off_case(label, degree))
               for label, case in SPEED_CASES.items() if case.lift_off_times
               for degree in (EARLY_COARSE_DEGREE, EARLY_DEGREE)]
    solves = [solve for solve in solves if not only or solve[0].startswith(tuple(only))]
    frames = [] if not only else [load()[lambda table: ~table.case.str.startswith(tuple(only))]]
    for name, degree, solve in solves:
        frames.append(tabulate(name, solve()))
        print(f"{name} degree {degree}: {frames[-1].cpu_s.iloc[0]:.1f} s", flush=True)
    DATA.parent.mkdir(exist_ok=True)
    pd.concat(frames).to_csv(DATA, index=False)  # floats as repr: round-trip exact


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
