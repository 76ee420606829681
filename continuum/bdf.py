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
Python or compiled by numba (``compiled``).  tests/continuum/bdf_oracle.py keeps scipy's own BDF on the same system
as the test of its steps.
"""
from __future__ import annotations

import functools
import math
import time

import numpy as np

from .kernels import BdfKernels, band_lu, band_solve, jitable, rms, source_key
from .stepper import MAX_STEPS, RECORD_ROWS, NewtonFailure, StepperFailure, StepStats

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


@functools.cache
def bdf_loop(kernels: BdfKernels, compiled: bool):
    """The BDF loop on ``kernels``: ``advance(...)`` steps until an output time, a full record, a stall or a failure
    (its exits).  Written once; ``compiled``: numba compiles it with the kernels (continuum.compiled), else it runs as
    Python."""
    project, interior_rate, jacobian, wall = kernels
    sources = source_key(*kernels, bdf_loop)

    def advance(state, d, ints, jband, ab, piv, units, t_bound, control, record, kl, ku, data):
        """Step until t_bound is reached (LANDED), the record is full, BDF stalls after the lift-off (``control``'s
        stall_fraction and stall_steps), or fails.  BDF's state between calls: d (the differences array),
        state = [t, h_abs, newton_tol, c of the factors in ab, the last step], ints = [order, n_equal_steps, lu_valid,
        nfev, nlu, njev, steps, small steps in a row, rows recorded in this call, U's upper bandwidth]."""
        sources  # noqa: B018 -- the cache key (kernels.source_key): numba hashes a closure's cells
        rtol, atol, max_steps, lift_off_end, stall_fraction, stall_steps = control
        rec_t, rec_x = record
        m = d.shape[1]
        x, f, row0, column = np.empty(m + 1), np.empty(m), np.empty(m + 1), np.zeros(m)
        zb, dy, y, y_new = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
        dsum, scale, psi = np.empty(m), np.empty(m), np.empty(m)
        lap_wall_n = units.shape[0]
        t, h_abs, newton_tol = state[0], state[1], state[2]
        order, n_equal = ints[0], ints[1]
        lu_valid = ints[2] == 1
        ints[8] = 0
        c_lu = state[3]
        while True:
            if ints[6] >= max_steps:
                state[0], state[1], state[3], ints[0], ints[1], ints[2] = t, h_abs, c_lu, order, n_equal, int(lu_valid)
                return FAILED
            min_step = 10 * abs(np.nextafter(t, np.inf) - t)
            if h_abs < min_step:
                change_d(d, order, min_step / h_abs)
                h_abs, n_equal = min_step, 0
            current_jac = False
            accepted = False
            n_iter = 0
            while not accepted:
                if h_abs < min_step:
                    state[0], state[1], ints[0] = t, h_abs, order
                    return TOO_SMALL
                t_new = t + h_abs
                if t_new - t_bound > 0:
                    t_new = t_bound
                    change_d(d, order, abs(t_new - t) / h_abs)
                    n_equal, lu_valid = 0, False
                h_abs = abs(t_new - t)
                y[:] = d[0]
                for k in range(1, order + 1):
                    y += d[k]
                for i in range(m):
                    scale[i] = atol + rtol * abs(y[i])
                converged = False
                c = h_abs / ALPHA[order]
                while not converged:
                    if not lu_valid:
                        ab[kl:] = -c * jband
                        ab[kl + ku] += 1.0
                        ab[:kl] = 0.0
                        ints[4] += 1
                        ints[9] = band_lu(ab, piv, kl, ku)
                        if ints[9] < 0:
                            return FAILED
                        for w in range(lap_wall_n):  # T^-1 e_w: the wall column's share of every solve
                            units[w] = 0.0
                            units[w, w] = 1.0
                            band_solve(ab, piv, kl, ku, ints[9], units[w])
                        lu_valid, c_lu = True, c
                    # scipy's solve_bdf_system
                    psi[:] = 0.0
                    for k in range(1, order + 1):
                        psi += d[k] * GAMMA[k]
                    psi /= ALPHA[order]
                    dsum[:] = 0.0
                    y_new[:] = y
                    dy_norm_old, converged = -1.0, False
                    for k in range(NEWTON_MAXITER):
                        n_iter = k + 1
                        magnitude = project(y_new, x, data)
                        ints[3] += 1
                        if not math.isfinite(x[0]):
                            break
                        interior_rate(x, f, data)
                        finite = True
                        for i in range(m):
                            finite = finite and math.isfinite(f[i])
                        if not finite:
                            break
                        # the bordered system at this iterate (stepper.NewtonMatrix.refresh_wall, .solve)
                        wall(x, row0, column[:lap_wall_n], data)
                        zb[:] = 0.0
                        for w in range(lap_wall_n):
                            zb -= c_lu * column[w] * units[w]
                        for i in range(m):
                            dy[i] = c * f[i] - psi[i] - dsum[i]
                        band_solve(ab, piv, kl, ku, ints[9], dy)
                        pivot, top = -c_lu * row0[0], 0.0
                        for i in range(m):
                            pivot += c_lu * row0[i + 1] * zb[i]
                            top += c_lu * row0[i + 1] * dy[i]
                        x0 = top / pivot
                        for i in range(m):
                            dy[i] -= x0 * zb[i]
                        dy_norm = rms(dy, scale)
                        rate = dy_norm / dy_norm_old if dy_norm_old >= 0 else -1.0
                        if rate >= 0 and (rate >= 1
                                          or rate ** (NEWTON_MAXITER - k) / (1 - rate) * dy_norm > newton_tol):
                            # not scipy's: after the lift-off, an iteration that stalls within the wall unknown's
                            # round-off (felt by z through zb) is converged. There q is fixed by u~_w less the
                            # interior's share over w_0 ~ 1e-9, and its noise keeps scipy's Newton from converging at
                            # the steady state's tight tolerances: the step would collapse
                            if t > lift_off_end and dy_norm <= ROUND_OFF_UPDATES * EPS * magnitude / abs(
                                    row0[0]) * rms(zb, scale):
                                y_new += dy
                                dsum += dy
                                converged = True
                            break
                        for i in range(m):
                            y_new[i] += dy[i]
                            dsum[i] += dy[i]
                        if dy_norm == 0 or (rate >= 0 and rate / (1 - rate) * dy_norm < newton_tol):
                            converged = True
                            break
                        dy_norm_old = dy_norm
                    if not converged:
                        if current_jac:
                            break
                        project(y, x, data)  # J at the prediction
                        if math.isfinite(x[0]):
                            jacobian(x, jband, data)
                        ints[5] += 1
                        lu_valid, current_jac = False, True
                if not converged:
                    h_abs *= 0.5
                    change_d(d, order, 0.5)
                    n_equal, lu_valid = 0, False
                    continue
                safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
                for i in range(m):
                    scale[i] = atol + rtol * abs(y_new[i])
                error_norm = ERROR_CONST[order] * rms(dsum, scale)
                if error_norm > 1:
                    factor = max(MIN_FACTOR, safety * error_norm ** (-1 / (order + 1)))
                    h_abs *= factor
                    change_d(d, order, factor)
                    n_equal = 0
                else:
                    accepted = True
            # accepted: the differences array (scipy's update)
            n_equal += 1
            h_step = t_new - t
            t = t_new
            d[order + 2] = dsum - d[order + 1]
            d[order + 1] = dsum
            for i in range(order, -1, -1):
                d[i] += d[i + 1]
            if n_equal >= order + 1:
                e_m = ERROR_CONST[order - 1] * rms(d[order], scale) if order > 1 else math.inf
                e_p = ERROR_CONST[order + 1] * rms(d[order + 2], scale) if order < MAX_ORDER else math.inf
                norms = (e_m, error_norm, e_p)
                best, delta_order = -1.0, 0
                for k in range(3):
                    fk = norms[k] ** (-1 / (order + k)) if norms[k] > 0 else math.inf
                    if fk > best:
                        best, delta_order = fk, k - 1
                order += delta_order
                factor = min(MAX_FACTOR, safety * best)
                h_abs *= factor
                change_d(d, order, factor)
                n_equal, lu_valid = 0, False
            ints[6] += 1
            project(y_new, x, data)  # scipy's y (d[0] sums it in another order)
            rec_t[ints[8]] = t
            rec_x[ints[8]] = x
            ints[8] += 1
            state[0], state[1], state[3], ints[0], ints[1], ints[2] = t, h_abs, c_lu, order, n_equal, int(lu_valid)
            state[4] = h_step
            if t - t_bound >= 0:
                ints[7] = 0  # the landing's cut steps are no stall
                return LANDED
            ints[7] = ints[7] + 1 if t > lift_off_end and h_step < stall_fraction * t else 0
            if ints[7] >= stall_steps:
                return STALLED
            if ints[8] == len(rec_t):
                return RECORDS_FULL

    if not compiled:
        return advance
    from .compiled import compile_loop

    return compile_loop(advance)


def integrate(problem, t_out, *, compiled=True, rtol=1e-6, atol=1e-8, h0=1e-9, observer=None,
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
    x0 = problem.initial()
    n = len(x0)
    m = n - 1
    kl, ku = problem.kl, problem.ku
    x = np.empty(n)
    kernels.project(x0[1:].copy(), x, data)
    f = np.empty(m)
    kernels.rate(x, f, data)
    d = np.zeros((MAX_ORDER + 3, m))
    d[0], d[1] = x[1:], f * h0
    jband = np.zeros((kl + ku + 1, m), order="F")  # columns contiguous, as the band solves walk them
    kernels.jacobian(x, jband, data)
    ab, piv = np.zeros((2 * kl + ku + 1, m), order="F"), np.zeros(m, dtype=np.int64)
    units = np.zeros((n_wall, m))  # T^-1 e_k of the factors in ab
    newton_tol = max(10 * EPS / rtol, min(0.03, rtol**0.5))  # scipy's BDF.__init__
    state = np.array([0.0, h0, newton_tol, 0.0, 0.0])
    ints = np.array([1, 0, 0, 1, 0, 1, 0, 0, 0, 0], dtype=np.int64)
    record = (np.empty(RECORD_ROWS), np.empty((RECORD_ROWS, n)))
    rec_t, rec_x = record
    control = (float(rtol), float(atol), int(max_steps), float(getattr(problem, "lift_off_end", 0.0)),
               float(stall[0]), int(stall[1]))
    if observer is not None:
        observer(0.0, x.copy())
    states = np.empty((len(t_out), n))
    k = 0
    while k < len(t_out) and t_out[k] <= 0.0:  # output times at the start: the initial state
        states[k] = x
        k += 1
    while k < len(t_out):
        if k > 0 and t_out[k] == state[0]:  # a repeated output time: the solver is already there
            states[k] = states[k - 1]
            k += 1
            continue
        exit_ = advance(state, d, ints, jband, ab, piv, units, t_out[k], control, record, kl, ku, data)
        if observer is not None:
            for row in range(ints[8]):
                observer(rec_t[row], rec_x[row].copy())
        if exit_ == LANDED:
            states[k] = rec_x[ints[8] - 1]
            k += 1
        elif exit_ == STALLED:
            from .stepper import integrate as integrate_dirk

            t, x = rec_t[ints[8] - 1], rec_x[ints[8] - 1].copy()
            states[k:], rest = integrate_dirk(problem, t_out[k:], method=handover, compiled=compiled, rtol=rtol,
                                              atol=atol, h0=state[4], observer=observer,
                                              max_steps=max_steps - int(ints[6]), resume=(t, x),
                                              repeat_cap=repeat_cap)
            stats = stats.add(rest)
            break
        elif exit_ == TOO_SMALL:
            raise NewtonFailure(f"BDF failed at t = {state[0]:.3e}: Required step size is less than spacing between "
                                "numbers.")
        elif exit_ == FAILED:
            if ints[6] >= max_steps:
                raise StepperFailure(f"max_steps = {max_steps} reached at t = {state[0]:.3e}")
            raise NewtonFailure(f"BDF failed at t = {state[0]:.3e}: singular Newton matrix")
    stats.steps += int(ints[6])
    stats.newton_iterations += int(ints[3])
    stats.cpu_seconds = time.process_time() - start
    return states, stats
