"""Singly diagonally implicit Runge-Kutta (DIRK) time stepping of  M x' = F(x)  (diagonal mass M,
zero on algebraic rows), adaptive steps from an embedded error estimate.

Every implicit stage solves  M X - h a_ii F(X) = M x_n + h sum_j a_ij F_j  (algebraic rows:
F(X) = 0) by simplified Newton: one factorisation of M - h a_ii J per step (all SDIRK stages share
a_ii).  J is banded (a ``Jacobian``), except that row 0 may be dense (the imposed-speed integral
condition); the system is solved by bordering with LAPACK gbtrf/gbtrs.  All tableaux are stiffly accurate
(x_{n+1} is the last stage), so algebraic rows hold at every step (index-1 DAEs).

Methods (``TABLEAUX``), plus ``explicit_euler`` (first order, conditionally stable: the
stability map's foil):
* ``sdirk4``: Hairer & Wanner (1996, Table IV.6.5) 5-stage SDIRK, order 4, L-stable, embedded
  order 3.  The default: cheapest to 1e-6 in the work-precision benchmark (bench/).
* ``tr-bdf2``: trapezoidal stage then BDF2 (Bank et al. 1985) as a 3-stage ESDIRK, order 2,
  L-stable, embedded order 3 (Hosea & Shampine 1996).
* ``crank-nicolson``: the paper's scheme, order 2, A-stable but not L-stable (stiff modes excited
  by the impulsive start ring with amplification -> -1); no error estimate, fixed steps only.

and ``bdf``: scipy's variable-order (1-5) BDF/NDF on the differential rows, the algebraic wall row
eliminated by the problem's exact ``project`` (an ODE on a constraint manifold).  The DIRKs have stage
order 1, so on the imposed-speed DAE their accuracy drops (measured: steps grow as rtol^-0.55 during the
lift-off of mu_w); BDF has no stages and keeps its order: the imposed speed's default.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .lapack import dgbtrf, dgbtrs, dpttrf, dpttrs


@dataclass(frozen=True)
class Tableau:
    """Butcher tableau of a stiffly accurate DIRK method; ``err`` = b - b_hat (None: no estimate)."""

    name: str
    A: tuple[tuple[float, ...], ...]
    order: int
    err: tuple[float, ...] | None = None
    err_order: int = 0  # the local error estimate is O(h^err_order): step-size exponent 1/err_order

    @property
    def explicit_first(self) -> bool:
        return self.A[0][0] == 0.0

    @cached_property
    def matrix(self) -> np.ndarray:
        """A as an array (the stage sums are products with its rows)."""
        return np.array(self.A)

    @cached_property
    def error_weights(self) -> np.ndarray:
        return np.array(self.err)

    @cached_property
    def stage_weights(self) -> np.ndarray:
        """W[i] = (S_i, P_i) on K = (F(x_n), F_1, ..., F_s): the right-hand side of stage i is
        M x_n + h S_i @ K (the explicit stage sum), its Newton guess  M X_i = M x_n + h P_i @ K: the
        stage sum plus a_ii times a predicted F_i.  Implicit first stage: F_i interpolated in c
        through the PREDICTOR_POINTS known (0, F(x_n)), (c_j, F_j) nearest to c_i (the least
        amplification of their errors; three points make wild guesses at large steps).  Explicit
        first stage (F_1 = F(x_n)): F_i ~ F_{i-1}, and no prediction for stage 2 (after CN steps
        F(x_n) carries the undamped stiff modes and would make a wild guess)."""
        A = self.matrix
        s = len(A)
        P = np.zeros((s, s + 1))
        P[:, 1:] = A
        P[:, 1:] -= np.diag(np.diag(A))
        stage_sums = P.copy()
        if self.explicit_first:
            for i in range(2, s):
                P[i, i] += A[i, i]
            P[1] = 0.0
            return np.stack([stage_sums, P], axis=1)
        nodes = np.concatenate(([0.0], A.sum(axis=1)))
        for i in range(s):
            known = np.argsort(np.abs(nodes[:i + 1] - nodes[i + 1]), kind="stable")[:PREDICTOR_POINTS]
            for j in known:
                others = nodes[known[known != j]]
                P[i, j] += A[i, i] * np.prod((nodes[i + 1] - others) / (nodes[j] - others))
        return np.stack([stage_sums, P], axis=1)


_G = 2.0 - np.sqrt(2.0)
_D, _W = _G / 2.0, np.sqrt(2.0) / 4.0
TABLEAUX = {
    "sdirk4": Tableau(
        "sdirk4",
        ((1 / 4, 0, 0, 0, 0),
         (1 / 2, 1 / 4, 0, 0, 0),
         (17 / 50, -1 / 25, 1 / 4, 0, 0),
         (371 / 1360, -137 / 2720, 15 / 544, 1 / 4, 0),
         (25 / 24, -49 / 48, 125 / 16, -85 / 12, 1 / 4)),
        order=4,
        err=(25 / 24 - 59 / 48, -49 / 48 + 17 / 96, 125 / 16 - 225 / 32, 0.0, 1 / 4),
        err_order=4),
    "tr-bdf2": Tableau(
        "tr-bdf2",
        ((0, 0, 0), (_D, _D, 0), (_W, _W, _D)),
        order=2,
        err=(_W - (1 - _W) / 3, _W - (3 * _W + 1) / 3, _D - _D / 3),
        err_order=3),
    "crank-nicolson": Tableau("crank-nicolson", ((0, 0), (0.5, 0.5)), order=2),
}
#: every method of ``integrate``
METHODS = (*TABLEAUX, "bdf")
#: the first Newton iterate of a stage is judged with the previous stage's contraction estimate,
#: eta_0 = max(eta, ETA_FLOOR)^ETA_DECAY (Hairer & Wanner 1996, IV.8)
ETA_FLOOR, ETA_DECAY = 1e-16, 0.8
#: the stage predictor interpolates the stage derivatives through this many points (Tableau.stage_weights)
PREDICTOR_POINTS = 2
#: a Newton failure cuts the step to NEWTON_CUT h; a repeat (one within REPEAT_BAND of the previous failure's
#: h) caps the steps at CAP_START h, the cap growing CAP_GROWTH per accepted step, which breaks the
#: fail-quarter-regrow loop (mu~_w = 0.1, 64 cells, rtol 1e-4: 14x fewer Newton iterations; unchanged at
#: mu~_w = 0.1 and 0.5, 96 cells, rtol 1e-6), bench/RESULTS.md "The paper's figure set"
NEWTON_CUT, REPEAT_BAND, CAP_START, CAP_GROWTH = 0.25, 0.05, 0.5, 1.1
#: a stage's simplified Newton: most iterations on the step's matrix, and of the full-Newton fallback; the
#: contraction at which each gives up; an update below SMALL_UPDATE of the tolerance is converged
NEWTON_ITERATIONS, FULL_NEWTON_ITERATIONS = 8, 15
NO_CONTRACTION, NO_CONTRACTION_FULL, SMALL_UPDATE = 1.0, 0.99, 1e-3
#: the DIRKs' step control: a step that would leave less than LANDING_SHARE of itself before an output time is
#: stretched onto it; the new step is STEP_SAFETY err^(-1/order) times the last, within [STEP_SHRINK, STEP_GROW];
#: the error norm is floored at ERROR_FLOOR
LANDING_SHARE, STEP_SAFETY, STEP_SHRINK, STEP_GROW, ERROR_FLOOR = 0.05, 0.9, 0.2, 4.0, 1e-10
#: a stage's Newton is converged when its contraction-corrected update is below NEWTON_TOL (weighted RMS); an
#: integration stops with StepperFailure after MAX_STEPS steps (accepted and rejected)
NEWTON_TOL, MAX_STEPS = 0.03, 200_000
#: a step ends on an output time within this relative distance of it
OUTPUT_RTOL = 1e-13
#: bdf hands over to HANDOVER when its step has stayed below BDF_STALL t for STALL_STEPS steps in a row after
#: the problem's lift-off (``_integrate_bdf``), counted afresh after each output time: scipy cuts the step that
#: lands on one and keeps that size for order + 1 steps before it may grow, no stall (a handover there, SDIRK4
#: on the speed's DAE, crawls: u~_w = 0.02 on 256 cells, 199 000 steps to t~ = 1.1; BDF goes on to 10 in 77)
BDF_STALL, STALL_STEPS, HANDOVER = 1e-3, 50, "sdirk4"
#: bdf's reduced Jacobian is dense up to this many unknowns: scipy's dense LU path costs less than
#: SuperLU with its sparse bookkeeping there (measured, u~_w = 1.334: 64 cells 1.4x, 128 cells 1.4x less CPU;
#: 256 cells 4x more), bench/RESULTS.md "The paper's figure set"
DENSE_BDF_MAX = 128
#: what the bordered bdf hands scipy for its Jacobian (``_integrate_bdf``)
BORDERED_MARKER = -1.0


@dataclass
class StepStats:
    steps: int = 0
    rejected: int | None = 0    # None: not reported (bdf)
    newton_iterations: int = 0
    newton_failures: int = 0
    cpu_seconds: float = 0.0

    def add(self, other: StepStats) -> StepStats:
        """The counts of two consecutive integrations (rejected None if either did not report it)."""
        rejected = None if None in (self.rejected, other.rejected) else self.rejected + other.rejected
        return StepStats(self.steps + other.steps, rejected, self.newton_iterations + other.newton_iterations,
                         self.newton_failures + other.newton_failures, self.cpu_seconds + other.cpu_seconds)


class StepperFailure(RuntimeError):
    """A time integration that cannot go on (its step limit, or Newton's failure at the smallest step)."""


class NewtonFailure(StepperFailure):
    pass


class NewtonMatrix:
    """LU factors of A = M - dh J(x), reused for every Newton iteration and stage of a step.

    A is banded (LAPACK gbtrf/gbtrs, partial pivoting), except that row 0 may be dense (the
    imposed-speed integral condition); then it is eliminated by bordering:
    [[a, c], [b, T]] [x0; z] = [r0; r]  =>  x0 = (r0 - c.T^-1 r)/(a - c.T^-1 b).
    A dissipative Jacobian makes A symmetric positive definite: L D L^T (LAPACK pttrf/pttrs).
    """

    def __init__(self, problem, x, dh, jac=None):
        jac = problem.jacobian(x) if jac is None else jac  # J(x), or that Jacobian already at hand
        mass = problem.mass
        kl, ku = jac.kl, jac.ku
        self.dh, self.dense, self.kl, self.ku = dh, jac.row0 is not None, kl, ku
        self.dissipative = jac.dissipative
        if self.dissipative:
            self.d, self.e, info = dpttrf(mass - dh * jac.bands[1], -dh * jac.bands[0, 1:])
            if info != 0:
                raise NewtonFailure("Newton matrix not positive definite")
            return
        first = 1 if self.dense else 0
        ab = np.zeros((2 * kl + ku + 1, len(mass) - first))
        ab[kl:] = -dh * jac.bands[:, first:]
        ab[kl + ku] += mass[first:]
        self.lu, self.piv, info = dgbtrf(ab, kl, ku, overwrite_ab=True)
        if info != 0:
            raise NewtonFailure("singular Newton matrix")
        if self.dense:
            column0 = np.zeros(len(mass) - 1)
            column0[:kl] = -dh * jac.bands[ku + 1:, 0][:len(column0)]
            self.zb = self._solve(column0)
            self.refresh_row0(mass[0], jac.row0)

    def _solve(self, r):
        if self.dissipative:
            return dpttrs(self.d, self.e, r)[0]
        return dgbtrs(self.lu, self.kl, self.ku, r, self.piv)[0]

    def refresh_wall(self, mass0, row0, column):
        """Replace the dense row 0 and column 0 (rows 1..kl: ``column``) by their values at the current iterate:
        one more band solve (T is unchanged)."""
        column0 = np.zeros(len(self.zb))
        column0[:len(column)] = -self.dh * column
        self.zb = self._solve(column0)
        self.refresh_row0(mass0, row0)

    def refresh_row0(self, mass0, row0):
        """Replace the dense row 0 by its value at the current iterate (cheap: T is unchanged)."""
        self.row0 = -self.dh * row0
        self.row0[0] += mass0
        self.pivot = self.row0[0] - self.row0[1:] @ self.zb

    def solve(self, r):
        if not self.dense:
            return self._solve(r)
        zr = self._solve(r[1:])
        x0 = (r[0] - self.row0[1:] @ zr) / self.pivot
        return np.concatenate(([x0], zr - x0 * self.zb))


def solve_stage(problem, matrix, x, rhs, weights, tol, stats, eta=1.0, max_iter=NEWTON_ITERATIONS, full=False):
    """Solve M X - dh F(X) = rhs by simplified Newton from the guess x.

    Stops when the contraction-corrected update eta |dx| (weighted RMS, eta = theta/(1-theta); at the
    first iterate the given ``eta``, carried from the previous stage) is below ``tol`` (Hairer & Wanner
    1996, IV.8), then applies the problem's exact projection onto its algebraic constraints (if any);
    returns (X, F(X), eta).  ``full``: refactorise at every iterate (full Newton, the fallback when the
    frozen matrix does not contract)."""
    x = x.copy()
    mass, dh = problem.mass, matrix.dh
    rate = problem.rate(x)
    previous = None
    for _ in range(max_iter):
        stats.newton_iterations += 1
        if full:
            matrix = NewtonMatrix(problem, x, dh)
        elif problem.dense_wall:  # the integral condition's row changes fast: keep it current
            matrix.refresh_row0(mass[0], problem.wall_gradient(x))
        residual = rhs - mass * x
        residual += dh * rate
        dx = matrix.solve(residual)
        scaled = dx / weights
        size = math.sqrt(scaled @ scaled / len(scaled))
        if not math.isfinite(size):
            break
        fraction = problem.step_fraction(x, dx)
        if fraction == 1.0:
            x += dx
        else:
            x += fraction * dx
        if previous is not None:
            theta = size / previous
            if theta >= (NO_CONTRACTION_FULL if full else NO_CONTRACTION):  # give up (the caller tries full Newton)
                break
            eta = theta / (1.0 - theta)
        if eta * size < tol or size < SMALL_UPDATE * tol:
            x = problem.project(x)
            return x, problem.rate(x), eta
        rate = problem.rate(x)
        previous = size
    stats.newton_failures += 1
    raise NewtonFailure("Newton did not converge")


def mass_rows(mass):
    """The algebraic rows (indices) and 1/M on the differential rows (0 on the algebraic ones)."""
    return np.flatnonzero(mass == 0), np.divide(1.0, mass, out=np.zeros(len(mass)), where=mass != 0)


def dirk_step(problem, tab: Tableau, x, f, h, weights, newton_tol, stats, eta=1.0, rows=None):
    """One step of size h from (x, f = F(x)).  Returns x_{n+1}, F(x_{n+1}), the local error
    estimate filtered through (M - h a_ss J)^-1 (Hosea & Shampine 1996) or None, and the Newton
    contraction estimate ``eta`` to carry to the next step.  ``rows``: ``mass_rows(problem.mass)``.
    A problem with ``carries_contraction = False`` (its Newton contracts unevenly from one stage to the
    next) judges every stage's first iterate with eta = 1 instead."""
    matrix = NewtonMatrix(problem, x, h * tab.A[-1][-1])
    mass, A, hW = problem.mass, tab.matrix, h * tab.stage_weights
    algebraic, inverse_mass = rows if rows is not None else mass_rows(mass)
    carry = problem.carries_contraction
    rates = np.empty((len(A) + 1, len(x)))  # F(x_n), then the stages' F_i
    rates[0] = f
    first = 1 if tab.explicit_first else 0
    if first:
        rates[1] = f
    base = mass * x
    X = x
    for i in range(first, len(A)):
        rhs, guess = hW[i, :, :i + 1] @ rates[:i + 1]
        rhs += base
        rhs[algebraic] = 0.0
        guess += base
        guess *= inverse_mass
        guess[algebraic] = X[algebraic]  # from the last stage
        try:
            X, rates[i + 1], eta = solve_stage(problem, matrix, guess, rhs, weights, newton_tol, stats,
                                               max(eta, ETA_FLOOR) ** ETA_DECAY if carry else 1.0)
        except NewtonFailure:
            X, rates[i + 1], eta = solve_stage(problem, matrix, guess, rhs, weights, newton_tol, stats,
                                               max_iter=FULL_NEWTON_ITERATIONS, full=True)
    if tab.err is None:
        return X, rates[-1], None, eta
    est = h * (tab.error_weights @ rates[1:])
    est[algebraic] = 0.0
    return X, rates[-1], matrix.solve(est), eta


def integrate(problem, t_out, *, method="sdirk4", rtol=1e-6, atol=1e-8, h0=1e-9, newton_tol=NEWTON_TOL,
              fixed_times=None, observer=None, max_steps=MAX_STEPS, resume=None, bordered=True, wall_newton=True,
              repeat_cap=True):
    """Integrate ``problem`` from t = 0 (or from ``resume`` = (t0, x0)), returning the state at each time
    of the sorted ``t_out``.

    Adaptive steps keep the RMS local error over the differential rows, weighted by
    atol + rtol |x|, below 1; with ``fixed_times`` (an increasing array containing every t_out) the
    steps are those, with no error control (refinement studies, stability maps).
    ``observer(t, x)`` is called after every accepted step.  ``bordered``, ``wall_newton``: bdf's Newton systems
    (``_integrate_bdf``); ``repeat_cap``: the DIRKs' cap after a repeated Newton failure (REPEAT_BAND; False:
    none).  Returns (states, stats), states of shape (len(t_out), n).
    """
    if method == "bdf":
        if fixed_times is not None:
            raise ValueError("method 'bdf' chooses its own steps: fixed_times needs a DIRK method")
        return _integrate_bdf(problem, t_out, rtol=rtol, atol=atol, h0=h0, observer=observer,
                              max_steps=max_steps, resume=resume, bordered=bordered, wall_newton=wall_newton)
    tab = TABLEAUX[method]
    if fixed_times is None and tab.err is None:
        raise ValueError(f"method {method!r} has no error estimate: give fixed_times")
    t_out = np.asarray(t_out, dtype=float)
    differential = problem.mass > 0
    rows = mass_rows(problem.mass)
    stats = StepStats()
    start = time.process_time()
    t, x = resume if resume is not None else (0.0, problem.initial())
    f = problem.rate(x)
    h, eta = h0, 1.0
    h_fail, cap = math.inf, math.inf  # the last Newton failure's step, the step cap after a repeat
    states = np.empty((len(t_out), len(x)))
    k = 0
    schedule = None if fixed_times is None else iter(np.asarray(fixed_times, dtype=float))
    if observer is not None and resume is None:
        observer(t, x)
    while k < len(t_out):
        if stats.steps + stats.rejected >= max_steps:
            raise StepperFailure(f"max_steps = {max_steps} reached at t = {t:.3e}")
        if schedule is not None:
            h_try = next(schedule) - t
        else:
            h_try = min(h, t_out[k] - t)
            if t_out[k] - (t + h_try) < LANDING_SHARE * h_try:
                h_try = t_out[k] - t
        weights = atol + rtol * np.abs(x)
        try:
            x1, f1, err_vec, eta = dirk_step(problem, tab, x, f, h_try, weights, newton_tol, stats, eta, rows)
        except NewtonFailure:
            if schedule is not None:
                raise
            eta = 1.0
            stats.rejected += 1
            if repeat_cap and abs(h_try / h_fail - 1.0) < REPEAT_BAND:
                cap = CAP_START * h_try
            h, h_fail = NEWTON_CUT * h_try, h_try
            continue
        if schedule is None:
            scaled = err_vec[differential] / weights[differential]
            err = max(np.sqrt(scaled @ scaled / len(scaled)), ERROR_FLOOR)
            factor = STEP_SAFETY * err ** (-1.0 / tab.err_order)
            if err > 1.0:
                stats.rejected += 1
                h = h_try * max(STEP_SHRINK, factor)
                continue
            h = min(h_try * min(STEP_GROW, max(STEP_SHRINK, factor)), cap)
            cap *= CAP_GROWTH
        stats.steps += 1
        x, f, t = x1, f1, t + h_try
        if observer is not None:
            observer(t, x)
        while k < len(t_out) and abs(t - t_out[k]) <= OUTPUT_RTOL * abs(t_out[k]):
            states[k] = x
            k += 1
        if schedule is not None and k < len(t_out) and t > t_out[k]:
            raise ValueError("fixed_times must contain every output time")
    stats.cpu_seconds = time.process_time() - start
    return states, stats


def _reduced_jacobian(problem, x):
    """d/dz of the rate of the differential rows z = x[1:] with the wall x[0] = x0(z) eliminated by
    the constraint g(x0, z) = 0: J_zz - J_z0 (dg/dz)/(dg/dx0), a band plus kl dense rows; a dense
    array up to DENSE_BDF_MAX rows (scipy's BDF then factorises it by LAPACK getrf), else CSC (SuperLU)."""
    jac = problem.jacobian(x)
    n = len(x) - 1
    grad = problem.wall_gradient(x)
    coupling = jac.bands[jac.ku + 1:, 0][:n]  # J[1..kl, 0]
    dense = -coupling[:, None] * (grad[1:] / grad[0])[None, :]
    if n <= DENSE_BDF_MAX:
        out = np.zeros((n, n))
        for k in range(-jac.kl, jac.ku + 1):  # diagonal k = column - row, band row ku - k
            values = jac.bands[jac.ku - k, 1:]
            np.fill_diagonal(out[:, k:] if k >= 0 else out[-k:, :], values[k:] if k >= 0 else values[:n + k])
        out[:len(coupling)] += dense
        return out
    import scipy.sparse as sp

    rows = np.repeat(np.arange(len(coupling)), n)
    cols = np.tile(np.arange(n), len(coupling))
    return (jac.interior() + sp.coo_matrix((dense.ravel(), (rows, cols)), shape=(n, n))).tocsc()


def _integrate_bdf(problem, t_out, *, rtol, atol, h0, observer, max_steps, resume=None, bordered=True,
                   wall_newton=True):
    """``integrate`` with scipy's BDF on z = x[1:] (``problem.interior_rate``), x[0] from ``problem.project``
    (unit mass rows).

    BDF steps onto every output time (its bound moved on to the next one, no restart: scipy cuts the
    last step to the bound): its dense output is ~1e4 rtol off through an imposed speed's lift-off, where
    the landed steps are within ~1-20 rtol (bench/RESULTS.md "Remeshing the speed in time").
    Near a steady state at tight tolerances the round-off of the rate (|tau~|/h^2 eps) stops scipy's
    Newton from converging and the steps shrink without end: once the step has stayed below BDF_STALL t
    for STALL_STEPS steps, after the problem's ``lift_off_end`` (the DAE's stiff transient, where BDF is
    needed), the rest goes to HANDOVER (whose Newton accepts an update at round-off).

    ``bordered``: Newton's systems I - c J are solved by the bordered band of NewtonMatrix (the unreduced M - c J)
    instead of scipy's own LU of the reduced J, whose fill-in from the wall's dense rows dominates (1.1-2.8x less
    CPU at 64-512 cells; False: the baseline of bench/speed_solver.py).  ``wall_newton``: Newton takes the imposed
    speed's wall row and column at each iterate and the band at the step's Jacobian: the wall unknown as a function
    of the interior curves with a sensitivity ~1/h_0 once the first cell's share of u~_w is small, and with all of
    it frozen Newton contracts too slowly and holds BDF at order 1 through the lift-off (bench/bdf_wall_newton.py)."""
    if not np.all(problem.mass[1:] == 1.0) or problem.mass[0] != 0.0:
        raise ValueError("method 'bdf' needs an algebraic row 0 and unit mass elsewhere")
    from scipy.integrate import BDF

    t_out = np.asarray(t_out, dtype=float)
    stats = StepStats(rejected=None)
    start = time.process_time()

    def state(z):
        return problem.project(np.concatenate(([0.0], z)))

    lift_off_end = getattr(problem, "lift_off_end", 0.0)
    iterate = [None]  # the state of the last rate evaluation: in scipy's Newton, the iterate the next solve is at

    def rate(t, z):
        x = state(z)
        iterate[0] = x
        return problem.interior_rate(x) if np.isfinite(x[0]) else np.full(len(z), np.nan)

    t0, x0 = resume if resume is not None else (0.0, problem.initial())
    admissible = [state(x0[1:])]

    unreduced = []  # the last Jacobian of the unreduced problem (``bordered``)

    def jacobian(t, z):
        x = state(z)
        if np.isfinite(x[0]):
            admissible[0] = x
        if not bordered:
            return _reduced_jacobian(problem, admissible[0])
        unreduced[:] = [problem.jacobian(admissible[0])]
        return BORDERED_MARKER

    x = admissible[0]
    if bordered:
        # scipy's BDF uses its Jacobian J only to hand I - c J to lu. Handed J = BORDERED_MARKER = -1 and I = 0 (after
        # its set-up has seen an empty sparse n x n), it hands over c itself, and lu factorises the unreduced M - c J
        # by the bordered band (NewtonMatrix): I - c J is never formed (sparse, with its CSC bookkeeping, it would
        # cost ~0.3 ms a factorisation, a quarter of a 64-cell solve)
        import scipy.sparse as sp

        solver = BDF(rate, t0, x[1:], t_out[0], rtol=rtol, atol=atol, first_step=h0,
                     jac=lambda t, z: sp.csc_matrix((len(z), len(z))))
        solver.jac, solver.I, solver.J = jacobian, 0.0, jacobian(t0, x[1:])

        def lu(c):
            solver.nlu += 1
            return NewtonMatrix(problem, None, float(c), jac=unreduced[0])

        def solve_lu(factors, b):
            """Newton's correction; the wall's row and column (of an imposed speed) at the current iterate if
            ``wall_newton``."""
            x = iterate[0]
            if wall_newton and factors.dense and np.isfinite(x[0]):
                factors.refresh_wall(problem.mass[0], *problem.wall_jacobian(x))
            return factors.solve(np.concatenate(([0.0], b)))[1:]

        solver.lu, solver.solve_lu = lu, solve_lu
    else:
        solver = BDF(rate, t0, x[1:], t_out[0], rtol=rtol, atol=atol, jac=jacobian, first_step=h0)
    states = np.empty((len(t_out), len(x)))
    if observer is not None and resume is None:
        observer(t0, x)
    k = small = 0  # the output times reached, the small steps in a row
    while k < len(t_out):
        if stats.steps >= max_steps:
            raise StepperFailure(f"max_steps = {max_steps} reached at t = {solver.t:.3e}")
        message = solver.step()
        if solver.status == "failed":
            raise NewtonFailure(f"BDF failed at t = {solver.t:.3e}: {message}")
        stats.steps += 1
        x = state(solver.y)
        if observer is not None:
            observer(solver.t, x)
        if solver.status == "finished":  # the step was cut to land on t_out[k]: the next bound, no restart
            states[k] = x
            k += 1
            if k < len(t_out):
                solver.t_bound, solver.status = t_out[k], "running"
            small = 0  # the landing's cut steps are no stall
            continue
        after = solver.t > lift_off_end
        small = small + 1 if after and solver.step_size < BDF_STALL * solver.t else 0
        if small >= STALL_STEPS:
            states[k:], rest = integrate(problem, t_out[k:], method=HANDOVER, rtol=rtol, atol=atol,
                                         h0=solver.step_size, observer=observer, max_steps=max_steps - stats.steps,
                                         resume=(solver.t, x))
            stats.steps += rest.steps
            stats.newton_iterations += rest.newton_iterations
            break
    stats.newton_iterations += solver.nfev
    stats.cpu_seconds = time.process_time() - start
    return states, stats


def explicit_euler(problem, t_out, fixed_times, observer=None):
    """Forward Euler on the differential rows, x += dt F(x)/M, then the problem's projection onto
    its algebraic rows; stable only for dt < 2/|lambda_max(M^-1 J)| (continuum.stability)."""
    t_out = np.asarray(t_out, dtype=float)
    differential = problem.mass > 0
    stats = StepStats()
    start = time.process_time()
    x = problem.project(problem.initial())
    states = np.empty((len(t_out), len(x)))
    t, k = 0.0, 0
    for t_next in np.asarray(fixed_times, dtype=float):
        f = problem.rate(x)
        x = x.copy()
        x[differential] += (t_next - t) * f[differential] / problem.mass[differential]
        x = problem.project(x)
        t = t_next
        stats.steps += 1
        if not np.all(np.isfinite(x)):
            raise FloatingPointError(f"explicit Euler blew up at t = {t:.3e}")
        if observer is not None:
            observer(t, x)
        while k < len(t_out) and np.isclose(t, t_out[k], rtol=1e-13, atol=0.0):
            states[k] = x
            k += 1
    stats.cpu_seconds = time.process_time() - start
    return states[:k], stats
