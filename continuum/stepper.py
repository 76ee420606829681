"""Singly diagonally implicit Runge-Kutta (DIRK) time stepping of  M x' = F(x, t)  (diagonal mass M,
zero on algebraic rows), adaptive steps from an embedded error estimate.

Every implicit stage solves  M X - h a_ii F(X, t + c_i h) = M x_n + h sum_j a_ij F_j  (algebraic rows:
F(X) = 0; c_i = sum_j a_ij the stage's node) by simplified Newton: one factorisation of M - h a_ii J per step
(all SDIRK stages share a_ii), through the problem's kernels (continuum.kernels.DirkKernels): its own, or its
``rate`` and ``jacobian`` factorised by ``NewtonMatrix`` (a band, bordered where row 0 is dense, by LAPACK).  All
tableaux are stiffly accurate (x_{n+1} is the last stage), so algebraic rows hold at every step (index-1 DAEs).

Methods (``TABLEAUX``), plus ``explicit_euler`` (first order, conditionally stable: the
stability map's foil):
* ``sdirk4``: Hairer & Wanner (1996, Table IV.6.5) 5-stage SDIRK, order 4, L-stable, embedded
  order 3.  The default: cheapest to 1e-6 in the work-precision benchmark (bench/).
* ``tr-bdf2``: trapezoidal stage then BDF2 (Bank et al. 1985) as a 3-stage ESDIRK, order 2,
  L-stable, embedded order 3 (Hosea & Shampine 1996).
* ``crank-nicolson``: the paper's scheme, order 2, A-stable but not L-stable (stiff modes excited
  by the impulsive start ring with amplification -> -1); no error estimate, fixed steps only.

The loop (``dirk_loop``) is written once and runs as Python or compiled by numba with the problem's kernels
(``compiled``); what it carries between calls and what it reads are named tuples (``DirkState``, ``DirkSetup``).
The DIRKs have stage order 1, so on the imposed-speed DAE their accuracy drops (measured: steps grow as
rtol^-0.55 during the lift-off of mu_w); continuum.bdf keeps its order there: the imposed speed's default.
"""
from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

from .kernels import DirkKernels, jitable, rms, source_key
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
    def nodes(self) -> np.ndarray:
        """c_i = sum_j a_ij: stage i is taken at the time t + c_i h."""
        return self.matrix.sum(axis=1)

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
        nodes = np.concatenate(([0.0], self.nodes))
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
#: integration stops with StepperFailure after MAX_STEPS steps (accepted and rejected); its first step is FIRST_STEP
#: unless given
NEWTON_TOL, MAX_STEPS, FIRST_STEP = 0.03, 200_000, 1e-9
#: a step ends on an output time within this relative distance of it
OUTPUT_RTOL = 1e-13
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
    """LU factors of A = M - dh J of a problem's Jacobian J (continuum.jacobian), reused for every Newton iteration
    and stage of a step.

    A is banded (LAPACK gbtrf/gbtrs, partial pivoting), except that row 0 may be dense (the
    imposed-speed integral condition); then it is eliminated by bordering:
    [[a, c], [b, T]] [x0; z] = [r0; r]  =>  x0 = (r0 - c.T^-1 r)/(a - c.T^-1 b).
    A dissipative Jacobian makes A symmetric positive definite: L D L^T (LAPACK pttrf/pttrs).
    """

    def __init__(self, problem, jac, dh):
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


def mass_rows(mass):
    """The algebraic rows (indices) and 1/M on the differential rows (0 on the algebraic ones)."""
    return np.flatnonzero(mass == 0), np.divide(1.0, mass, out=np.zeros(len(mass)), where=mass != 0)


def _numpy_rate(x, t, f, problem):
    f[:] = problem.rate(x, t)


def _numpy_factor(x, t, dh, lu, problem):
    try:
        lu[0] = NewtonMatrix(problem, problem.jacobian(x, t), dh)
    except NewtonFailure:
        return False
    return True


def _numpy_refresh(lu, x, t, problem):
    if problem.dense_wall:  # the integral condition's row changes fast: keep it current
        lu[0].refresh_row0(problem.mass[0], problem.wall_gradient(x))


def _numpy_solve(lu, r, problem):
    r[:] = lu[0].solve(r)


def _numpy_project(x, problem):
    problem.project(x)


def _numpy_fraction(x, dx, problem):
    return problem.step_fraction(x, dx)


#: the kernels of a problem that has none of its own: its rate, jacobian (factorised by NewtonMatrix), project and
#: step_fraction methods, with the problem itself as the data
NUMPY_KERNELS = DirkKernels(_numpy_rate, _numpy_factor, _numpy_refresh, _numpy_solve, _numpy_project, _numpy_fraction)


def problem_kernels(problem, compiled: bool):
    """(Kernels, data, a factors factory) of ``problem``: its own (``dirk_kernels``) if it has them, else
    NUMPY_KERNELS; and whether they compile."""
    own = getattr(problem, "dirk_kernels", None)
    if own is not None:
        kernels, data, factors = own()
        return kernels, data, factors, compiled
    return NUMPY_KERNELS, problem, lambda: [None], False


# --- the vector operations of the loop, in two summation orders -------------------------------------------------
# The compiled loop sums in index order (element loops); the Python one by numpy and BLAS, as fast as Python gets.
# The two orders round differently: the velocity form (continuum.velocity, Python only) moves by 1e-7 relative at its
# rtol 1e-5 if summed in index order, so each backend keeps its own.

def _numpy_stage_sums(hw, count, rates, base, rhs, guess):
    sums = hw[:, :count] @ rates[:count]
    rhs[:] = sums[0]
    rhs += base
    guess[:] = sums[1]
    guess += base


def _numpy_error_sum(h, err, rates, est):
    est[:] = h * (err @ rates[1:])


def _numpy_norm(v, scale):
    scaled = v / scale
    return math.sqrt(scaled @ scaled / len(scaled))


def _numpy_residual(rhs, mass, x, dh, f, out):
    np.subtract(rhs, mass * x, out=out)
    out += dh * f


@jitable
def _loop_stage_sums(hw, count, rates, base, rhs, guess):
    rhs[:] = base
    guess[:] = base
    for j in range(count):
        hs, hp = hw[0, j], hw[1, j]
        for m in range(len(base)):
            rhs[m] += hs * rates[j, m]
            guess[m] += hp * rates[j, m]


@jitable
def _loop_error_sum(h, err, rates, est):
    est[:] = 0.0
    for j in range(len(err)):
        he = h * err[j]
        for m in range(len(est)):
            est[m] += he * rates[j + 1, m]


@jitable
def _loop_residual(rhs, mass, x, dh, f, out):
    for i in range(len(x)):
        out[i] = rhs[i] - mass[i] * x[i] + dh * f[i]


class VectorOps(NamedTuple):
    """The loop's vector operations in one summation order: stage_sums(hw, count, rates, base, rhs, guess),
    error_sum(h, err, rates, est), norm(v, scale), residual(rhs, mass, x, dh, f, out)."""

    stage_sums: Callable
    error_sum: Callable
    norm: Callable
    residual: Callable


NUMPY_OPS = VectorOps(_numpy_stage_sums, _numpy_error_sum, _numpy_norm, _numpy_residual)
LOOP_OPS = VectorOps(_loop_stage_sums, _loop_error_sum, rms, _loop_residual)

#: the loop's exits
LANDED, RECORDS_FULL, MAX_STEPS_REACHED, FIXED_STEP_FAILED, FIXED_STEP_PASSED = range(5)
#: clock slots between calls: time, next step, Newton contraction, the last Newton failure's step, the step cap,
#: the next fixed step
T, H, ETA, H_FAIL, CAP, NEXT_FIXED = range(6)
#: counters: accepted steps, rejected steps, Newton iterations, Newton failures, rows recorded in this call
STEPS, REJECTED, ITERATIONS, FAILURES, RECORDED = range(5)
#: per-step rows kept between two returns to Python (the observer's), per loop call
RECORD_ROWS = 1024


class StageTableau(NamedTuple):
    """A Tableau as the loop takes it: A, the stage weights (Tableau.stage_weights), the error weights b - b_hat
    (zeros without an estimate), the stage nodes c, whether the first stage is explicit, the local error's order and
    whether there is an estimate."""

    a: np.ndarray
    weights: np.ndarray
    err: np.ndarray
    nodes: np.ndarray
    explicit_first: bool
    err_order: int
    estimates: bool


class Rows(NamedTuple):
    """The diagonal mass M, 1/M on the differential rows (0 on the algebraic ones) and the two sets of rows."""

    mass: np.ndarray
    inverse_mass: np.ndarray
    algebraic: np.ndarray
    differential: np.ndarray


class Work(NamedTuple):
    """The loop's workspace: the stage rates (s + 1 rows: F(x_n), F_1..F_s), the error estimate, the last stage,
    a stage's Newton iterate and its start, the stage's right-hand side, M x_n, a Newton update, the error weights."""

    rates: np.ndarray
    est: np.ndarray
    stage: np.ndarray
    guess: np.ndarray
    start: np.ndarray
    rhs: np.ndarray
    base: np.ndarray
    dx: np.ndarray
    weights: np.ndarray


class Control(NamedTuple):
    """The step control: tolerances, the Newton tolerance, most steps, and the rules of the module's constants
    (NEWTON_CUT, REPEAT_BAND (0: no cap), CAP_START, CAP_GROWTH, OUTPUT_RTOL, LANDING_SHARE, STEP_SAFETY,
    STEP_SHRINK, STEP_GROW, ERROR_FLOOR)."""

    rtol: float
    atol: float
    newton_tol: float
    max_steps: int
    newton_cut: float
    repeat_band: float
    cap_start: float
    cap_growth: float
    output_rtol: float
    landing: float
    safety: float
    shrink: float
    grow: float
    floor: float


class NewtonRules(NamedTuple):
    """A stage's Newton: NO_CONTRACTION, NO_CONTRACTION_FULL, SMALL_UPDATE, whether a stage starts from the last
    stage's contraction (the problem's ``carries_contraction``), NEWTON_ITERATIONS, the full-Newton fallback's
    iterations, ETA_FLOOR, ETA_DECAY."""

    no_contraction: float
    no_contraction_full: float
    small_update: float
    carry: bool
    iterations: int
    full_iterations: int
    eta_floor: float
    eta_decay: float


class StageNewton(NamedTuple):
    """What a stage's Newton works with besides its iterate, right-hand side and rate (``solve_stage``): the update's
    workspace, the error weights, the mass, the counters, the factors (the step's, the full Newton's), its rules and
    tolerance and the kernels' data.  A few arrays only, not the whole setup: the loop calls it at every stage."""

    dx: np.ndarray
    weights: np.ndarray
    mass: np.ndarray
    counters: np.ndarray
    lu: object
    full_lu: object
    rules: NewtonRules
    tol: float
    data: object


class DirkSetup(NamedTuple):
    """What a loop call reads (and the workspace it writes): the tableau, the controls, the rows, the workspace, the
    fixed step ends (empty: adaptive), the stages' Newton and the kernels' data."""

    tableau: StageTableau
    control: Control
    rows: Rows
    work: Work
    fixed: np.ndarray
    newton: StageNewton
    data: object


class DirkState(NamedTuple):
    """What the loop carries from call to call: the state x and f = F(x, t), the clock (slots T..NEXT_FIXED), the
    counters (STEPS..RECORDED), the Newton matrix's factors (the step's and the full Newton's) and the record of the
    accepted steps since the call began."""

    x: np.ndarray
    f: np.ndarray
    clock: np.ndarray
    counters: np.ndarray
    lu: object
    full_lu: object
    record_t: np.ndarray
    record_x: np.ndarray


def _stage_solver(kernels: DirkKernels, ops: VectorOps):
    """``solve_stage`` on these kernels and vector operations."""
    rate, factor, refresh, solve, project, fraction = kernels
    norm, residual = ops.norm, ops.residual

    def solve_stage(x, f, rhs, t, dh, eta, full, newton):
        """Solve M X - dh F(X, t) = rhs by simplified Newton from the guess X = x (in place; f gets F(X, t)).

        Stops when the contraction-corrected update eta |dx| (weighted RMS, eta = theta/(1-theta); at the first
        iterate the given ``eta``, carried from the previous stage) is below the Newton tolerance (Hairer & Wanner
        1996, IV.8), then projects onto the algebraic constraints.  ``full``: refactorise at every iterate (full
        Newton, the fallback when the frozen matrix does not contract).  Returns (converged, eta)."""
        rules, data, counters, dx, tol = newton.rules, newton.data, newton.counters, newton.dx, newton.tol
        lu = newton.full_lu if full else newton.lu
        rate(x, t, f, data)
        previous = -1.0
        for _ in range(rules.full_iterations if full else rules.iterations):
            counters[ITERATIONS] += 1
            if full:
                if not factor(x, t, dh, lu, data):  # a failed step; no Newton failure counted
                    return False, eta
            else:
                refresh(lu, x, t, data)
            residual(rhs, newton.mass, x, dh, f, dx)
            solve(lu, dx, data)
            size = norm(dx, newton.weights)
            if not math.isfinite(size):
                break
            share = fraction(x, dx, data)
            if share == 1.0:
                x += dx
            else:
                x += share * dx
            if previous >= 0:
                theta = size / previous
                if theta >= (rules.no_contraction_full if full else rules.no_contraction):  # no contraction
                    break
                eta = theta / (1.0 - theta)
            if eta * size < tol or size < rules.small_update * tol:
                project(x, data)
                rate(x, t, f, data)
                return True, eta
            rate(x, t, f, data)
            previous = size
        counters[FAILURES] += 1
        return False, eta

    return solve_stage


def _stepper(kernels: DirkKernels, ops: VectorOps, solve_stage):
    """``dirk_step`` on these kernels and vector operations."""
    factor, solve = kernels.factor, kernels.solve
    stage_sums, error_sum = ops.stage_sums, ops.error_sum

    def dirk_step(t, h, eta, setup, state):
        """One step of size h from (x, f = F(x, t)) of the state: the stages into the work (the last one, x_{n+1}, in
        ``stage``, its rate in rates[-1]), stage i at t + c_i h, the local error estimate filtered through
        (M - h a_ss J)^-1 (Hosea & Shampine 1996) in ``est``.  Returns (ok, eta): ok False if a stage's Newton
        failed."""
        tab, rows, work, newton, data = setup.tableau, setup.rows, setup.work, setup.newton, setup.data
        rules = newton.rules
        x, f, rates, guess = state.x, state.f, work.rates, work.guess
        s = tab.a.shape[0]
        dh = h * tab.a[s - 1, s - 1]
        if not factor(x, t, dh, state.lu, data):
            return False, eta
        rates[0] = f
        first = 1 if tab.explicit_first else 0
        if first:
            rates[1] = f
        work.stage[:] = x
        np.multiply(rows.mass, x, work.base)
        for i in range(first, s):
            stage_sums(h * tab.weights[i], i + 1, rates, work.base, work.rhs, guess)
            for r in rows.algebraic:
                work.rhs[r] = 0.0
            guess *= rows.inverse_mass
            for r in rows.algebraic:
                guess[r] = work.stage[r]  # from the last stage
            work.start[:] = guess  # the full-Newton fallback's guess
            t_stage = t + tab.nodes[i] * h
            carried = max(eta, rules.eta_floor) ** rules.eta_decay if rules.carry else 1.0
            ok, eta = solve_stage(guess, rates[i + 1], work.rhs, t_stage, dh, carried, False, newton)
            if not ok:
                guess[:] = work.start
                ok, eta = solve_stage(guess, rates[i + 1], work.rhs, t_stage, dh, 1.0, True, newton)
                if not ok:
                    return False, eta
            work.stage[:] = guess
        if tab.estimates:
            error_sum(h, tab.err, rates, work.est)
            for r in rows.algebraic:
                work.est[r] = 0.0
            solve(state.lu, work.est, data)
        return True, eta

    return dirk_step


def _advancer(norm, dirk_step, sources: str):
    """``advance`` on this norm and step; ``sources``: the compiled cache's key (kernels.source_key)."""

    def advance(state, setup, t_bound):
        """Step from (t = clock[T], x, f = F(x, t)) until t_bound is reached (LANDED, within the output rtol), the
        record is full, or max_steps.  Adaptive steps keep the RMS local error over the differential rows, weighted
        by atol + rtol |x|, below 1; setup's ``fixed`` (not empty): the steps end at those times, with no error
        control."""
        sources  # noqa: B018 -- the cache key (kernels.source_key): numba hashes a closure's cells
        control, work, fixed = setup.control, setup.work, setup.fixed
        differential = setup.rows.differential
        s = setup.tableau.a.shape[0]
        clock, counters, x = state.clock, state.counters, state.x
        t, h, eta, h_fail, cap = clock[T], clock[H], clock[ETA], clock[H_FAIL], clock[CAP]
        counters[RECORDED] = 0
        while True:
            if counters[STEPS] + counters[REJECTED] >= control.max_steps:
                clock[T], clock[H], clock[ETA], clock[H_FAIL], clock[CAP] = t, h, eta, h_fail, cap
                return MAX_STEPS_REACHED
            if len(fixed):
                h_try = fixed[int(clock[NEXT_FIXED])] - t
            else:
                h_try = min(h, t_bound - t)
                if t_bound - (t + h_try) < control.landing * h_try:
                    h_try = t_bound - t
            work.weights[:] = control.atol + control.rtol * np.abs(x)
            ok, eta_step = dirk_step(t, h_try, eta, setup, state)
            if not ok:
                if len(fixed):
                    clock[T] = t
                    return FIXED_STEP_FAILED
                eta = 1.0
                counters[REJECTED] += 1
                if abs(h_try / h_fail - 1.0) < control.repeat_band:
                    cap = control.cap_start * h_try
                h, h_fail = control.newton_cut * h_try, h_try
                continue
            eta = eta_step
            if len(fixed):
                clock[NEXT_FIXED] += 1
            else:
                err = max(norm(work.est[differential], work.weights[differential]), control.floor)
                factor_ = control.safety * err ** (-1.0 / setup.tableau.err_order)
                if err > 1.0:
                    counters[REJECTED] += 1
                    h = h_try * max(control.shrink, factor_)
                    continue
                h = min(h_try * min(control.grow, max(control.shrink, factor_)), cap)
                cap *= control.cap_growth
            counters[STEPS] += 1
            x[:] = work.stage
            state.f[:] = work.rates[s]
            t += h_try
            state.record_t[counters[RECORDED]] = t
            state.record_x[counters[RECORDED]] = x
            counters[RECORDED] += 1
            clock[T], clock[H], clock[ETA], clock[H_FAIL], clock[CAP] = t, h, eta, h_fail, cap
            if abs(t - t_bound) <= control.output_rtol * abs(t_bound):
                return LANDED
            if len(fixed) and t > t_bound:
                return FIXED_STEP_PASSED
            if counters[RECORDED] == len(state.record_t):
                return RECORDS_FULL

    return advance


@functools.cache
def dirk_loop(kernels: DirkKernels, compiled: bool):
    """The DIRK loop on ``kernels``: ``advance(state, setup, t_bound)`` steps until an output time, a full record or a
    limit (its exits).  Written once; ``compiled``: numba compiles it with the kernels (continuum.compiled), else it
    runs as Python."""
    ops = LOOP_OPS if compiled else NUMPY_OPS
    solve_stage = _stage_solver(kernels, ops)
    dirk_step = _stepper(kernels, ops, solve_stage)
    advance = _advancer(ops.norm, dirk_step, source_key(*kernels, dirk_loop))
    if not compiled:
        return advance
    from .compiled import compile_loop

    return compile_loop(advance, solve_stage, dirk_step)


def _rules(problem, full_newton=FULL_NEWTON_ITERATIONS) -> NewtonRules:
    """The Newton's rules as the loop takes them."""
    return NewtonRules(NO_CONTRACTION, NO_CONTRACTION_FULL, SMALL_UPDATE, bool(problem.carries_contraction),
                       NEWTON_ITERATIONS, full_newton, ETA_FLOOR, ETA_DECAY)


def _setup(problem, tab: Tableau, control: Control, fixed, state: DirkState, data) -> DirkSetup:
    """The loop's setup of ``problem`` under the tableau ``tab`` (its workspace allocated; the stages' Newton on the
    state's counters and factors)."""
    mass = np.asarray(problem.mass, dtype=float)
    algebraic, inverse_mass = mass_rows(mass)
    s, n = len(tab.A), len(mass)
    tableau = StageTableau(tab.matrix, tab.stage_weights, tab.error_weights if tab.err is not None else np.zeros(s),
                           tab.nodes, tab.explicit_first, int(tab.err_order), tab.err is not None)
    work = Work(np.empty((s + 1, n)), *(np.empty(n) for _ in range(8)))
    newton = StageNewton(work.dx, work.weights, mass, state.counters, state.lu, state.full_lu, _rules(problem),
                         control.newton_tol, data)
    return DirkSetup(tableau, control, Rows(mass, inverse_mass, algebraic, np.flatnonzero(mass > 0)), work, fixed,
                     newton, data)


def integrate(problem, t_out, *, method="sdirk4", compiled=True, rtol=1e-6, atol=1e-8, h0=FIRST_STEP,
              newton_tol=NEWTON_TOL, fixed_times=None, observer=None, max_steps=MAX_STEPS, resume=None,
              repeat_cap=True):
    """Integrate ``problem`` (M x' = F(x, t)) by the DIRK ``method`` from t = 0 (or from ``resume`` = (t0, x0)),
    returning the state at each time of the sorted ``t_out``.

    Adaptive steps keep the RMS local error over the differential rows, weighted by atol + rtol |x|, below 1; with
    ``fixed_times`` (an increasing array containing every t_out) the steps are those, with no error control
    (refinement studies, stability maps).  ``observer(t, x)`` is called after every accepted step.  ``compiled``:
    the loop and the problem's kernels compiled by numba, if the problem has its own (``dirk_kernels``); ``repeat_cap``:
    the cap after a repeated Newton failure (REPEAT_BAND; False: none).  Returns (states, stats), states of shape
    (len(t_out), n).
    """
    tab = TABLEAUX[method]
    if fixed_times is None and tab.err is None:
        raise ValueError(f"method {method!r} has no error estimate: give fixed_times")
    t_out = np.asarray(t_out, dtype=float)
    start_cpu = time.process_time()
    kernels, data, factors, compiled = problem_kernels(problem, compiled)
    advance = dirk_loop(kernels, compiled)
    t0, x = resume if resume is not None else (0.0, problem.initial())
    x = np.array(x, dtype=float)
    n = len(x)
    f = np.empty(n)
    kernels.rate(x, t0, f, data)
    control = Control(float(rtol), float(atol), float(newton_tol), int(max_steps), NEWTON_CUT,
                      REPEAT_BAND if repeat_cap else 0.0, CAP_START, CAP_GROWTH, OUTPUT_RTOL, LANDING_SHARE,
                      STEP_SAFETY, STEP_SHRINK, STEP_GROW, ERROR_FLOOR)
    fixed = np.asarray(fixed_times if fixed_times is not None else [], dtype=float)
    if fixed.size and (fixed[0] <= t0 or np.any(np.diff(fixed) <= 0)
                       or fixed[-1] < t_out[-1] * (1 - OUTPUT_RTOL)):
        raise ValueError("fixed_times must increase from the start time and reach the last output time")
    state = DirkState(x, f, np.array([t0, h0, 1.0, math.inf, math.inf, 0.0]), np.zeros(5, dtype=np.int64), factors(),
                      factors(), np.empty(RECORD_ROWS), np.empty((RECORD_ROWS, n)))
    setup = _setup(problem, tab, control, fixed, state, data)
    if observer is not None and resume is None:
        observer(t0, x.copy())
    states = np.empty((len(t_out), n))
    k = 0
    while k < len(t_out) and t_out[k] <= t0:  # output times at the start: the initial state
        states[k] = x
        k += 1
    while k < len(t_out):
        exit_ = advance(state, setup, t_out[k])
        if observer is not None:
            for row in range(state.counters[RECORDED]):
                observer(state.record_t[row], state.record_x[row].copy())
        if exit_ == MAX_STEPS_REACHED:
            raise StepperFailure(f"max_steps = {max_steps} reached at t = {state.clock[T]:.3e}")
        if exit_ == FIXED_STEP_FAILED:
            raise NewtonFailure(f"Newton did not converge at the fixed step from t = {state.clock[T]:.3e}")
        if exit_ == FIXED_STEP_PASSED:
            raise ValueError("fixed_times must contain every output time")
        while exit_ == LANDED and k < len(t_out) and abs(state.clock[T] - t_out[k]) <= OUTPUT_RTOL * abs(t_out[k]):
            states[k] = x
            k += 1
    counters = state.counters
    stats = StepStats(int(counters[STEPS]), int(counters[REJECTED]), int(counters[ITERATIONS]),
                      int(counters[FAILURES]), time.process_time() - start_cpu)
    return states, stats


def explicit_euler(problem, t_out, fixed_times, observer=None):
    """Forward Euler on the differential rows, x += dt F(x, t)/M, then the problem's projection onto
    its algebraic rows; stable only for dt < 2/|lambda_max(M^-1 J)| (continuum.stability)."""
    t_out = np.asarray(t_out, dtype=float)
    differential = problem.mass > 0
    stats = StepStats()
    start = time.process_time()
    x = problem.project(problem.initial())
    states = np.empty((len(t_out), len(x)))
    t, k = 0.0, 0
    for t_next in np.asarray(fixed_times, dtype=float):
        f = problem.rate(x, t)
        x = x.copy()
        x[differential] += (t_next - t) * f[differential] / problem.mass[differential]
        x = problem.project(x)
        t = t_next
        stats.steps += 1
        if not np.all(np.isfinite(x)):
            raise FloatingPointError(f"explicit Euler blew up at t = {t:.3e}")
        if observer is not None:
            observer(t, x)
        while k < len(t_out) and np.isclose(t, t_out[k], rtol=OUTPUT_RTOL, atol=0.0):
            states[k] = x
            k += 1
    stats.cpu_seconds = time.process_time() - start
    return states[:k], stats
