"""The BDF time stepping of an index-1 DAE  0 = g(x_0, z),  z' = F(x_0, z)  (an imposed speed: the wall unknown
x_0 fixed by the integral condition, the interior z = x[1:]), landing on every output time.

The loop is scipy.integrate.BDF's algorithm, step for step (variable order 1-5 with the NDF coefficients,
quasi-constant step size, Shampine & Reichelt 1997; its constants and update rules) on z, with x_0 from the
constraint after every iterate (the problem's ``project``: an ODE on the constraint manifold).  Newton's systems
I - c dF/dz are solved on the unreduced problem by a band LU bordered with the wall's row and column, which are taken
at each iterate: the wall unknown as a function of the interior curves with a sensitivity ~1/h_0 once the first
cell's share of u~_w is small, and with them frozen Newton contracts too slowly and holds BDF at order 1 through the
lift-off (bench/bdf_wall_newton.py).  One deviation from scipy: after the lift-off, where its Newton would give up,
an update within the wall unknown's round-off is accepted (ROUND_OFF_UPDATES).

The loop is written once (``bdf_loop``) on the problem's kernels (``BdfKernels``, continuum.kernels) and runs as
Python or compiled by numba (``compiled``); what it carries between calls and what it reads are named tuples
(``BdfState``, ``BdfSetup``).  The rates are taken at the step's end time (scipy's fun(t_new, y)).
tests/continuum/bdf_oracle.py keeps scipy's own BDF on the same system as the test of its steps.
"""
from __future__ import annotations

import functools
import math
import time
from typing import NamedTuple

import numpy as np

from .kernels import BdfKernels, band_lu, band_solve, jitable, rms, source_key
from .stepper import FIRST_STEP, MAX_STEPS, RECORD_ROWS, NewtonFailure, StepperFailure, StepStats

#: the stall that hands over to HANDOVER: steps below STALL_FRACTION t for STALL_STEPS in a row after the lift-off,
#: counted afresh after each output time (the BDF cuts the step that lands on one and keeps that size for order + 1
#: steps before it may grow, no stall; a handover there, SDIRK4 on the speed's DAE, crawls: u~_w = 0.02 on 256 cells,
#: 199 000 steps to t~ = 1.1, where BDF goes on to 10 in 77)
STALL_FRACTION, STALL_STEPS, HANDOVER = 1e-3, 50, "sdirk4"
#: scipy.integrate.BDF's constants (scipy/integrate/_ivp/bdf.py): most order, Newton iterations, step factors
MAX_ORDER, NEWTON_MAXITER, MIN_FACTOR, MAX_FACTOR = 5, 4, 0.2, 10.0
KAPPA = np.array([0.0, -0.1850, -1 / 9, -0.0823, -0.0415, 0.0])
GAMMA = np.concatenate(([0.0], np.cumsum(1.0 / np.arange(1, MAX_ORDER + 1))))
ALPHA = (1.0 - KAPPA) * GAMMA
ERROR_CONST = KAPPA * GAMMA + 1.0 / np.arange(1, MAX_ORDER + 2)
EPS = np.finfo(float).eps
#: Newton's floor: the wall unknown's round-off is this many eps of the constraint's terms (``advance``)
ROUND_OFF_UPDATES = 4.0
#: the loop's exits
LANDED, RECORDS_FULL, STALLED, TOO_SMALL, FAILED = range(5)


# --- scipy's BDF ------------------------------------------------------------------------------------------------

@jitable
def change_d(d, order, factor):
    """scipy's change_D: rescale the differences array to a step ``factor`` times the last."""
    r = np.zeros((order + 1, order + 1))
    u = np.zeros((order + 1, order + 1))
    for m, f in ((r, factor), (u, 1.0)):
        m[0, :] = 1.0
        for i in range(1, order + 1):
            for j in range(1, order + 1):
                m[i, j] = m[i - 1, j] * (i - 1 - f * j) / i
    ru = r @ u
    d[:order + 1] = ru.T @ d[:order + 1].copy()


#: clock slots between calls: time, step, Newton tolerance, c of the factors in ab, the last step
T, H_ABS, NEWTON_TOL, C_LU, H_STEP = range(5)
#: counts between calls: order, steps of equal size, whether the factors are current, rate evaluations, LU
#: factorisations, Jacobians, steps, small steps in a row, rows recorded in this call, U's upper bandwidth
ORDER, N_EQUAL, LU_VALID, NFEV, NLU, NJEV, STEPS, SMALL, RECORDED, UPPER = range(10)


class BdfControl(NamedTuple):
    """The loop's controls: tolerances, most steps, the problem's lift-off end and the stall rule (continuum.bdf's
    ``integrate``), the band's widths."""

    rtol: float
    atol: float
    max_steps: int
    lift_off_end: float
    stall_fraction: float
    stall_steps: int
    kl: int
    ku: int


class BdfWork(NamedTuple):
    """The loop's workspace (``workspace``): the full state x, F at the interior, the wall's row and column, T^-1 of
    the wall's column, a Newton update, the prediction and the iterate, the sum of the updates, the error weights and
    scipy's psi."""

    x: np.ndarray
    f: np.ndarray
    row0: np.ndarray
    column: np.ndarray
    zb: np.ndarray
    dy: np.ndarray
    y: np.ndarray
    y_new: np.ndarray
    dsum: np.ndarray
    scale: np.ndarray
    psi: np.ndarray


class BdfSetup(NamedTuple):
    """What a loop call reads: the controls and the kernels' data."""

    control: BdfControl
    data: tuple


class BdfState(NamedTuple):
    """What the loop carries from call to call: the clock (slots T..H_STEP), the counts (ORDER..UPPER), the
    differences array d, the Jacobian's band, the factors of I - c J (ab, piv), T^-1 e_w of the wall's column's rows
    (units) and the record of the accepted steps since the call began."""

    clock: np.ndarray
    counts: np.ndarray
    d: np.ndarray
    jband: np.ndarray
    ab: np.ndarray
    piv: np.ndarray
    units: np.ndarray
    record_t: np.ndarray
    record_x: np.ndarray


@jitable
def workspace(m):
    """The loop's workspace for m interior unknowns (allocated by each call, as local arrays)."""
    return BdfWork(np.empty(m + 1), np.empty(m), np.empty(m + 1), np.zeros(m), np.empty(m), np.empty(m), np.empty(m),
                   np.empty(m), np.empty(m), np.empty(m), np.empty(m))


@jitable
def factorise(state, control, c):
    """The band LU of I - c J into ab and T^-1 e_w of the wall column's rows into units: U's upper bandwidth, or -1
    if singular."""
    kl, ku, ab = control.kl, control.ku, state.ab
    ab[kl:] = -c * state.jband
    ab[kl + ku] += 1.0
    ab[:kl] = 0.0
    upper = band_lu(ab, state.piv, kl, ku)
    if upper < 0:
        return upper
    units = state.units
    for w in range(units.shape[0]):  # T^-1 e_w: the wall column's share of every solve
        units[w] = 0.0
        units[w, w] = 1.0
        band_solve(ab, state.piv, kl, ku, upper, units[w])
    return upper


@jitable
def predict(d, order, y, scale, control):
    """scipy's prediction y = sum of d[0..order] and the error weights atol + rtol |y|."""
    y[:] = d[0]
    for k in range(1, order + 1):
        y += d[k]
    for i in range(len(y)):
        scale[i] = control.atol + control.rtol * abs(y[i])


@jitable
def accept(d, dsum, order):
    """scipy's update of the differences array after an accepted step."""
    d[order + 2] = dsum - d[order + 1]
    d[order + 1] = dsum
    for i in range(order, -1, -1):
        d[i] += d[i + 1]


@jitable
def next_order(d, order, error_norm, scale, safety):
    """scipy's choice among order - 1, order, order + 1 after order + 1 equal steps: (the new order, the step
    factor)."""
    e_m = ERROR_CONST[order - 1] * rms(d[order], scale) if order > 1 else math.inf
    e_p = ERROR_CONST[order + 1] * rms(d[order + 2], scale) if order < MAX_ORDER else math.inf
    norms = (e_m, error_norm, e_p)
    best, delta_order = -1.0, 0
    for k in range(3):
        fk = norms[k] ** (-1 / (order + k)) if norms[k] > 0 else math.inf
        if fk > best:
            best, delta_order = fk, k - 1
    return order + delta_order, min(MAX_FACTOR, safety * best)


def _newton_on(kernels: BdfKernels):
    """``newton`` on these kernels."""
    project, interior_rate, wall = kernels.project, kernels.rate, kernels.wall

    def newton(state, setup, work, t, t_new, c, order):
        """scipy's solve_bdf_system at the step to t_new (from the prediction work.y): the iterate into work.y_new,
        the sum of the updates into work.dsum.  Each iterate takes x_0 from the constraint (``project``) and solves
        the bordered system with the wall's row and column at that iterate (stepper.NewtonMatrix.refresh_wall,
        .solve).  Returns (converged, iterations)."""
        control, data, counts = setup.control, setup.data, state.counts
        x, f, row0, column, zb, dy = work.x, work.f, work.row0, work.column, work.zb, work.dy
        y_new, dsum, scale, psi, units, d = work.y_new, work.dsum, work.scale, work.psi, state.units, state.d
        c_lu, newton_tol, m = state.clock[C_LU], state.clock[NEWTON_TOL], len(f)
        psi[:] = 0.0
        for k in range(1, order + 1):
            psi += d[k] * GAMMA[k]
        psi /= ALPHA[order]
        dsum[:] = 0.0
        y_new[:] = work.y
        dy_norm_old, n_iter = -1.0, 0
        for k in range(NEWTON_MAXITER):
            n_iter = k + 1
            magnitude = project(y_new, x, data)
            counts[NFEV] += 1
            if not math.isfinite(x[0]):
                break
            interior_rate(x, t_new, f, data)
            finite = True
            for i in range(m):
                finite = finite and math.isfinite(f[i])
            if not finite:
                break
            wall(x, t_new, row0, column[:units.shape[0]], data)
            zb[:] = 0.0
            for w in range(units.shape[0]):
                zb -= c_lu * column[w] * units[w]
            for i in range(m):
                dy[i] = c * f[i] - psi[i] - dsum[i]
            band_solve(state.ab, state.piv, control.kl, control.ku, counts[UPPER], dy)
            pivot, top = -c_lu * row0[0], 0.0
            for i in range(m):
                pivot += c_lu * row0[i + 1] * zb[i]
                top += c_lu * row0[i + 1] * dy[i]
            x0 = top / pivot
            for i in range(m):
                dy[i] -= x0 * zb[i]
            dy_norm = rms(dy, scale)
            rate = dy_norm / dy_norm_old if dy_norm_old >= 0 else -1.0
            if rate >= 0 and (rate >= 1 or rate ** (NEWTON_MAXITER - k) / (1 - rate) * dy_norm > newton_tol):
                # not scipy's: after the lift-off, an iteration that stalls within the wall unknown's round-off (felt
                # by z through zb) is converged. There q is fixed by u~_w less the interior's share over w_0 ~ 1e-9,
                # and its noise keeps scipy's Newton from converging at the steady state's tight tolerances: the step
                # would collapse
                if t > control.lift_off_end and dy_norm <= ROUND_OFF_UPDATES * EPS * magnitude / abs(
                        row0[0]) * rms(zb, scale):
                    y_new += dy
                    dsum += dy
                    return True, n_iter
                return False, n_iter
            for i in range(m):
                y_new[i] += dy[i]
                dsum[i] += dy[i]
            if dy_norm == 0 or (rate >= 0 and rate / (1 - rate) * dy_norm < newton_tol):
                return True, n_iter
            dy_norm_old = dy_norm
        return False, n_iter

    return newton


def _advancer(kernels: BdfKernels, newton, sources: str):
    """``advance`` on these kernels and ``newton``; ``sources``: the compiled cache's key (kernels.source_key)."""
    project, jacobian = kernels.project, kernels.jacobian

    def advance(state, setup, t_bound):
        """Step until t_bound is reached (LANDED), the record is full, BDF stalls after the lift-off (the control's
        stall_fraction and stall_steps), or fails.  BDF's state between calls: the clock, the counts and the
        differences array d."""
        sources  # noqa: B018 -- the cache key (kernels.source_key): numba hashes a closure's cells
        control, data = setup.control, setup.data
        clock, counts, d = state.clock, state.counts, state.d
        work = workspace(d.shape[1])
        t, h_abs, c_lu = clock[T], clock[H_ABS], clock[C_LU]
        order, n_equal, lu_valid = counts[ORDER], counts[N_EQUAL], counts[LU_VALID] == 1
        counts[RECORDED] = 0
        while True:
            if counts[STEPS] >= control.max_steps:
                clock[T], clock[H_ABS], clock[C_LU] = t, h_abs, c_lu
                counts[ORDER], counts[N_EQUAL], counts[LU_VALID] = order, n_equal, int(lu_valid)
                return FAILED
            min_step = 10 * abs(np.nextafter(t, np.inf) - t)
            if h_abs < min_step:
                change_d(d, order, min_step / h_abs)
                h_abs, n_equal = min_step, 0
            current_jac, accepted, n_iter, error_norm, safety, t_new = False, False, 0, 0.0, 0.0, t
            while not accepted:
                if h_abs < min_step:
                    clock[T], clock[H_ABS], counts[ORDER] = t, h_abs, order
                    return TOO_SMALL
                t_new = t + h_abs
                if t_new - t_bound > 0:
                    t_new = t_bound
                    change_d(d, order, abs(t_new - t) / h_abs)
                    n_equal, lu_valid = 0, False
                h_abs = abs(t_new - t)
                predict(d, order, work.y, work.scale, control)
                converged = False
                c = h_abs / ALPHA[order]
                while not converged:
                    if not lu_valid:
                        counts[NLU] += 1
                        counts[UPPER] = factorise(state, control, c)
                        if counts[UPPER] < 0:
                            return FAILED
                        lu_valid, c_lu = True, c
                        clock[C_LU] = c_lu
                    converged, n_iter = newton(state, setup, work, t, t_new, c, order)
                    if not converged:
                        if current_jac:
                            break
                        project(work.y, work.x, data)  # J at the prediction
                        if math.isfinite(work.x[0]):
                            jacobian(work.x, t_new, state.jband, data)
                        counts[NJEV] += 1
                        lu_valid, current_jac = False, True
                if not converged:
                    h_abs *= 0.5
                    change_d(d, order, 0.5)
                    n_equal, lu_valid = 0, False
                    continue
                safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
                for i in range(len(work.scale)):
                    work.scale[i] = control.atol + control.rtol * abs(work.y_new[i])
                error_norm = ERROR_CONST[order] * rms(work.dsum, work.scale)
                if error_norm > 1:
                    factor = max(MIN_FACTOR, safety * error_norm ** (-1 / (order + 1)))
                    h_abs *= factor
                    change_d(d, order, factor)
                    n_equal = 0
                else:
                    accepted = True
            n_equal += 1
            h_step = t_new - t
            t = t_new
            accept(d, work.dsum, order)
            if n_equal >= order + 1:
                order, factor = next_order(d, order, error_norm, work.scale, safety)
                h_abs *= factor
                change_d(d, order, factor)
                n_equal, lu_valid = 0, False
            counts[STEPS] += 1
            project(work.y_new, work.x, data)  # scipy's y (d[0] sums it in another order)
            state.record_t[counts[RECORDED]] = t
            state.record_x[counts[RECORDED]] = work.x
            counts[RECORDED] += 1
            clock[T], clock[H_ABS], clock[C_LU], clock[H_STEP] = t, h_abs, c_lu, h_step
            counts[ORDER], counts[N_EQUAL], counts[LU_VALID] = order, n_equal, int(lu_valid)
            if t - t_bound >= 0:
                counts[SMALL] = 0  # the landing's cut steps are no stall
                return LANDED
            counts[SMALL] = counts[SMALL] + 1 if t > control.lift_off_end and h_step < control.stall_fraction * t else 0
            if counts[SMALL] >= control.stall_steps:
                return STALLED
            if counts[RECORDED] == len(state.record_t):
                return RECORDS_FULL

    return advance


@functools.cache
def bdf_loop(kernels: BdfKernels, compiled: bool):
    """The BDF loop on ``kernels``: ``advance(state, setup, t_bound)`` steps until an output time, a full record, a
    stall or a failure (its exits).  Written once; ``compiled``: numba compiles it with the kernels
    (continuum.compiled), else it runs as Python."""
    newton = _newton_on(kernels)
    advance = _advancer(kernels, newton, source_key(*kernels, bdf_loop))
    if not compiled:
        return advance
    from .compiled import compile_loop

    return compile_loop(advance, newton)


def _start(problem, kernels: BdfKernels, data, n_wall: int, h0: float, rtol: float):
    """BDF's state at t = 0 (scipy's BDF.__init__: d from the initial state and its rate, the Jacobian there) and the
    initial state."""
    x0 = problem.initial()
    n = len(x0)
    m, kl, ku = n - 1, problem.kl, problem.ku
    x, f = np.empty(n), np.empty(m)
    kernels.project(x0[1:].copy(), x, data)
    kernels.rate(x, 0.0, f, data)
    d = np.zeros((MAX_ORDER + 3, m))
    d[0], d[1] = x[1:], f * h0
    jband = np.zeros((kl + ku + 1, m), order="F")  # columns contiguous, as the band solves walk them
    kernels.jacobian(x, 0.0, jband, data)
    newton_tol = max(10 * EPS / rtol, min(0.03, rtol**0.5))  # scipy's BDF.__init__
    clock = np.array([0.0, h0, newton_tol, 0.0, 0.0])
    counts = np.array([1, 0, 0, 1, 0, 1, 0, 0, 0, 0], dtype=np.int64)
    state = BdfState(clock, counts, d, jband, np.zeros((2 * kl + ku + 1, m), order="F"), np.zeros(m, dtype=np.int64),
                     np.zeros((n_wall, m)), np.empty(RECORD_ROWS), np.empty((RECORD_ROWS, n)))
    return state, x


def integrate(problem, t_out, *, compiled=True, rtol=1e-6, atol=1e-8, h0=FIRST_STEP, observer=None,
              max_steps=MAX_STEPS, stall=(STALL_FRACTION, STALL_STEPS), handover=HANDOVER, repeat_cap=True):
    """Integrate ``problem`` (an algebraic row 0, unit mass elsewhere, and ``bdf_kernels``) by BDF from t = 0,
    landing on every output time of the sorted ``t_out``: (states at t_out, StepStats).

    Near a steady state at tight tolerances the round-off of the rate (|tau~|/h^2 eps) can stop Newton from
    converging and the steps shrink without end: once the step has stayed below ``stall`` = (fraction, steps) t for
    that many steps in a row, after the problem's ``lift_off_end`` (the DAE's stiff transient, where BDF is needed),
    the rest goes to the DIRK ``handover`` (whose Newton accepts an update at round-off; ``repeat_cap`` as in
    continuum.stepper.integrate).  ``compiled``: the loop and the kernels compiled by numba."""
    if not np.all(problem.mass[1:] == 1.0) or problem.mass[0] != 0.0:
        raise ValueError("method 'bdf' needs an algebraic row 0 and unit mass elsewhere")
    t_out = np.asarray(t_out, dtype=float)
    start = time.process_time()
    stats = StepStats(rejected=None)
    kernels, data, n_wall = problem.bdf_kernels()
    advance = bdf_loop(kernels, compiled)
    state, x = _start(problem, kernels, data, n_wall, h0, rtol)
    control = BdfControl(float(rtol), float(atol), int(max_steps), float(getattr(problem, "lift_off_end", 0.0)),
                         float(stall[0]), int(stall[1]), problem.kl, problem.ku)
    setup = BdfSetup(control, data)
    if observer is not None:
        observer(0.0, x.copy())
    states = np.empty((len(t_out), len(x)))
    k = 0
    while k < len(t_out) and t_out[k] <= 0.0:  # output times at the start: the initial state
        states[k] = x
        k += 1
    clock, counts = state.clock, state.counts
    while k < len(t_out):
        if k > 0 and t_out[k] == clock[T]:  # a repeated output time: the solver is already there
            states[k] = states[k - 1]
            k += 1
            continue
        exit_ = advance(state, setup, t_out[k])
        if observer is not None:
            for row in range(counts[RECORDED]):
                observer(state.record_t[row], state.record_x[row].copy())
        if exit_ == LANDED:
            states[k] = state.record_x[counts[RECORDED] - 1]
            k += 1
        elif exit_ == STALLED:
            from .stepper import integrate as integrate_dirk

            resume = (state.record_t[counts[RECORDED] - 1], state.record_x[counts[RECORDED] - 1].copy())
            states[k:], rest = integrate_dirk(problem, t_out[k:], method=handover, compiled=compiled, rtol=rtol,
                                              atol=atol, h0=clock[H_STEP], observer=observer,
                                              max_steps=max_steps - int(counts[STEPS]), resume=resume,
                                              repeat_cap=repeat_cap)
            stats = stats.add(rest)
            break
        elif exit_ == TOO_SMALL:
            raise NewtonFailure(f"BDF failed at t = {clock[T]:.3e}: Required step size is less than spacing between "
                                "numbers.")
        elif exit_ == FAILED:
            if counts[STEPS] >= max_steps:
                raise StepperFailure(f"max_steps = {max_steps} reached at t = {clock[T]:.3e}")
            raise NewtonFailure(f"BDF failed at t = {clock[T]:.3e}: singular Newton matrix")
    stats.steps += int(counts[STEPS])
    stats.newton_iterations += int(counts[NFEV])
    stats.cpu_seconds = time.process_time() - start
    return states, stats
