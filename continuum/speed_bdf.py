"""The imposed speed's BDF solve, compiled (numba): what stepper._integrate_bdf does with scipy's BDF, in one
kernel per stretch between output times.

Same algorithm, step for step: scipy.integrate.BDF (variable order 1-5 with the NDF coefficients, quasi-constant
step size, Shampine & Reichelt 1997; its constants and update rules) on the same system, the interior z = x[1:]
with the wall unknown q = x[0] from the constraint (ImposedSpeed.project, by the compiled ``wall_unknown`` and
``first_cell`` of continuum.problems: the same functions), Newton's systems by the bordered band (stepper.NewtonMatrix)
with the wall's row and column at each iterate (stepper.BDF_WALL_NEWTON).  Profiled, the Python solve spends its
~0.55 ms a step in call overhead: the band solves of ~256 values (12 us each, f2py), the projection's scalar
Newton, scipy's bookkeeping (bench/RESULTS.md "The speed compiled").  The rate and Jacobian here are the
stencil sums of ImposedSpeed.interior_rate and .jacobian, asserted equal to them (tests/continuum).  One
deviation from scipy: after the lift-off, where its Newton would give up, an update within the wall unknown's
round-off is accepted (``advance``, ROUND_OFF_UPDATES).
"""
from __future__ import annotations

import math
import time

import numpy as np

from . import problems, stepper
from .compiled import band_lu, band_solve, compile_function, jit, laplacians, rms
from .stepper import NewtonFailure, StepperFailure, StepStats

#: compiled.digest(compiled, problems): these kernels build in code from both, and numba's cache checks only this
#: file, so this line changes with them (tests/continuum/test_compiled_cache.py gives the new value)
BUILT_FROM = "b850fe3c5913fb5c"
#: scipy.integrate.BDF's constants (scipy/integrate/_ivp/bdf.py): most order, Newton iterations, step factors
MAX_ORDER, NEWTON_MAXITER, MIN_FACTOR, MAX_FACTOR = 5, 4, 0.2, 10.0
KAPPA = np.array([0.0, -0.1850, -1 / 9, -0.0823, -0.0415, 0.0])
GAMMA = np.concatenate(([0.0], np.cumsum(1.0 / np.arange(1, MAX_ORDER + 1))))
ALPHA = (1.0 - KAPPA) * GAMMA
ERROR_CONST = KAPPA * GAMMA + 1.0 / np.arange(1, MAX_ORDER + 2)
EPS = np.finfo(float).eps
#: per-step rows kept between two returns to Python (the observer's), per kernel call
RECORD_ROWS = 1024
#: Newton's floor: the wall unknown's round-off is this many eps of the constraint's terms (``advance``)
ROUND_OFF_UPDATES = 4.0
#: the kernel's exits
LANDED, RECORDS_FULL, STALLED, TOO_SMALL, FAILED = range(5)


first_cell = compile_function(problems.first_cell)
wall_unknown = compile_function(problems.wall_unknown, first_cell=first_cell)


# --- the problem: ImposedSpeed's projection, rate and Jacobian on arrays --------------------------------------

@jit
def _project(z, x, u_w, w_first, mu_w, mu_d, mu_s, dmu, p, wq):
    """x = (q, z) with q from the constraint (ImposedSpeed.project); q = NaN where inadmissible.  Returns the
    interior's share of u~_w summed in absolute value (the scale of its round-off)."""
    integral, magnitude, admissible = 0.0, 0.0, True
    for j in range(len(z)):
        mu = mu_w * z[j] / p[j + 1]
        gap = mu_d - mu
        admissible = admissible and gap > 0
        term = wq[j + 1] * ((mu - mu_s) / gap)
        integral += term
        magnitude += abs(term)
        x[j + 1] = z[j]
    b = (mu_d - mu_w * z[0] / p[1]) / dmu
    target = (u_w + w_first - integral) / w_first
    x[0] = wall_unknown(target, b) if admissible and target > 0 else math.nan
    return magnitude


@jit
def _tau0(q, mu_w, mu_d, dmu, p0):
    return (mu_d - dmu * math.exp(min(-q, problems.EXP_MAX))) * p0 / mu_w


@jit
def _rate(x, f, tau, cols, weights, mud_p, p32, mu_w, mu_d, dmu, p0):
    """ImposedSpeed.interior_rate: f = D(tau~) d2 tau~/dy~2 at nodes 1..N-1 (``tau``: workspace of N + 1)."""
    laplacians(x, _tau0(x[0], mu_w, mu_d, dmu, p0), tau, f, cols, weights)
    for i in range(len(f)):
        s = mud_p[i] - mu_w * x[i + 1]
        f[i] *= s * s / p32[i]


@jit
def _jacobian_band(x, band, ku, tau, lap, cols, weights, mud_p, p32, mu_w, mu_d, dmu, p0):
    """ImposedSpeed.jacobian's rows and columns 1..N-1, band[ku + i - j, j] = dF_i/dz_j (z = x[1:]; ``tau``,
    ``lap``: workspaces of N + 1 and N - 1)."""
    laplacians(x, _tau0(x[0], mu_w, mu_d, dmu, p0), tau, lap, cols, weights)
    n = len(x)
    band[:] = 0.0
    for i in range(n - 1):
        s = mud_p[i] - mu_w * x[i + 1]
        diff = s * s / p32[i]
        for k in range(cols.shape[1]):
            c = cols[i, k]
            if 0 < c < n:
                band[ku + i - (c - 1), c - 1] += diff * weights[i, k]
        band[ku, i] -= 2 * mu_w * s / p32[i] * lap[i]


@jit
def _wall(x, row0, column, cols, weights, lap_wall, u_w, w_first, mu_w, mu_d, dmu, p, wq, mud_p, p32):
    """ImposedSpeed.wall_jacobian: the constraint's gradient (row0) and dF_i/dq at rows 1..kl (column)."""
    n = len(x)
    mt1 = 0.0
    for j in range(1, n):
        mt = (mu_d - mu_w * x[j] / p[j]) / dmu
        dmt = -mu_w / (p[j] * dmu)
        row0[j] = -wq[j] / (mt * mt) * dmt
        if j == 1:
            mt1 = mt
    _, dq, db = first_cell(x[0], mt1)
    row0[0] = w_first * dq
    row0[1] += w_first * db * (-mu_w / (p[1] * dmu))
    dtau0 = dmu * math.exp(min(-x[0], problems.EXP_MAX)) * p[0] / mu_w
    for k in range(len(column)):
        s = mud_p[k] - mu_w * x[k + 1]
        column[k] = s * s / p32[k] * lap_wall[k] * dtau0


# --- scipy's BDF ------------------------------------------------------------------------------------------------

@jit
def _change_d(d, order, factor):
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


@jit
def advance(state, d, ints, jband, ab, piv, units, t_bound, rtol, atol, max_steps, lift_off_end, stall, rec_t, rec_x,
            cols, weights, lap_wall, mud_p, p32, p, wq, u_w, w_first, mu_w, mu_d, mu_s, dmu, kl, ku):
    """Step until t_bound is reached (LANDED), the record is full, BDF stalls after the lift-off (stall =
    (stepper.BDF_STALL, stepper.STALL_STEPS)), or fails.  BDF's state between calls: d (the differences array),
    state = [t, h_abs, newton_tol, c of the factors in ab, the last step], ints = [order, n_equal_steps, lu_valid,
    nfev, nlu, njev, steps, small steps in a row, rows recorded in this call, U's upper bandwidth]."""
    m = d.shape[1]
    x, f, row0, column = np.empty(m + 1), np.empty(m), np.empty(m + 1), np.zeros(m)
    zb, dy, y, y_new = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    dsum, scale, psi, lap, tau = np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m + 2)
    lap_wall_n = len(lap_wall)
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
            _change_d(d, order, min_step / h_abs)
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
                _change_d(d, order, abs(t_new - t) / h_abs)
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
                    share = _project(y_new, x, u_w, w_first, mu_w, mu_d, mu_s, dmu, p, wq)
                    ints[3] += 1
                    if not math.isfinite(x[0]):
                        break
                    _rate(x, f, tau, cols, weights, mud_p, p32, mu_w, mu_d, dmu, p[0])
                    finite = True
                    for i in range(m):
                        finite = finite and math.isfinite(f[i])
                    if not finite:
                        break
                    # the bordered system at this iterate (stepper.NewtonMatrix.refresh_wall, .solve)
                    _wall(x, row0, column[:lap_wall_n], cols, weights, lap_wall, u_w, w_first, mu_w, mu_d, dmu, p,
                          wq, mud_p, p32)
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
                    if rate >= 0 and (rate >= 1 or rate ** (NEWTON_MAXITER - k) / (1 - rate) * dy_norm > newton_tol):
                        # NOT scipy's: after the lift-off, an iteration that stalls within the wall unknown's round-off
                        # (felt by z through zb) is converged. There q is fixed by u~_w less the interior's share over
                        # w_0 ~ 1e-9, and its noise keeps scipy's Newton from converging at the steady state's tight
                        # tolerances: the step would collapse
                        if t > lift_off_end and dy_norm <= ROUND_OFF_UPDATES * EPS * (u_w + share) / abs(
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
                    _project(y, x, u_w, w_first, mu_w, mu_d, mu_s, dmu, p, wq)  # J at the prediction
                    if math.isfinite(x[0]):
                        _jacobian_band(x, jband, ku, tau, lap, cols, weights, mud_p, p32, mu_w, mu_d, dmu, p[0])
                    ints[5] += 1
                    lu_valid, current_jac = False, True
            if not converged:
                h_abs *= 0.5
                _change_d(d, order, 0.5)
                n_equal, lu_valid = 0, False
                continue
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
            for i in range(m):
                scale[i] = atol + rtol * abs(y_new[i])
            error_norm = ERROR_CONST[order] * rms(dsum, scale)
            if error_norm > 1:
                factor = max(MIN_FACTOR, safety * error_norm ** (-1 / (order + 1)))
                h_abs *= factor
                _change_d(d, order, factor)
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
            _change_d(d, order, factor)
            n_equal, lu_valid = 0, False
        ints[6] += 1
        _project(y_new, x, u_w, w_first, mu_w, mu_d, mu_s, dmu, p, wq)  # scipy's y (d[0] sums it in another order)
        rec_t[ints[8]] = t
        rec_x[ints[8]] = x
        ints[8] += 1
        state[0], state[1], state[3], ints[0], ints[1], ints[2] = t, h_abs, c_lu, order, n_equal, int(lu_valid)
        state[4] = h_step
        if t - t_bound >= 0:
            ints[7] = 0  # the landing's cut steps are no stall
            return LANDED
        ints[7] = ints[7] + 1 if t > lift_off_end and h_step < stall[0] * t else 0
        if ints[7] >= stall[1]:
            return STALLED
        if ints[8] == len(rec_t):
            return RECORDS_FULL


def integrate_speed(problem, t_out, *, rtol, atol, h0, observer, max_steps):
    """stepper._integrate_bdf for an ImposedSpeed, compiled: (states at t_out, StepStats)."""
    t_out = np.asarray(t_out, dtype=float)
    start = time.process_time()
    stats = StepStats(rejected=None)
    x0 = problem.initial()
    n = len(x0)
    m = n - 1
    pb, fr = problem, problem.friction
    cols, weights, mud_p, p32, mu_w = pb.stencil()
    lap_wall, p, wq, u_w, w_first = pb.wall_terms()
    args = (cols, weights, lap_wall, mud_p, p32, p, wq, u_w, w_first, mu_w, fr.mu_d, fr.mu_s, fr.dmu, pb.kl, pb.ku)
    cols, weights, lap_wall, mud_p, p32, p, wq, u_w, w_first, mu_w, mu_d, mu_s, dmu, kl, ku = args
    x = np.empty(n)
    _project(x0[1:].copy(), x, u_w, w_first, mu_w, mu_d, mu_s, dmu, p, wq)
    f, tau, lap = np.empty(m), np.empty(n + 1), np.empty(m)
    _rate(x, f, tau, cols, weights, mud_p, p32, mu_w, mu_d, dmu, p[0])
    d = np.zeros((MAX_ORDER + 3, m))
    d[0], d[1] = x[1:], f * h0
    jband = np.zeros((kl + ku + 1, m), order="F")  # columns contiguous, as the band solves walk them
    _jacobian_band(x, jband, ku, tau, lap, cols, weights, mud_p, p32, mu_w, mu_d, dmu, p[0])
    ab, piv = np.zeros((2 * kl + ku + 1, m), order="F"), np.zeros(m, dtype=np.int64)
    units = np.zeros((len(lap_wall), m))  # T^-1 e_k of the factors in ab
    newton_tol = max(10 * EPS / rtol, min(0.03, rtol**0.5))  # scipy's BDF.__init__
    state = np.array([0.0, h0, newton_tol, 0.0, 0.0])
    ints = np.array([1, 0, 0, 1, 0, 1, 0, 0, 0, 0], dtype=np.int64)
    rec_t, rec_x = np.empty(RECORD_ROWS), np.empty((RECORD_ROWS, n))
    if observer is not None:
        observer(0.0, x.copy())
    states = np.empty((len(t_out), n))
    lift_off_end = getattr(problem, "lift_off_end", 0.0)
    k = 0
    while k < len(t_out):
        if k > 0 and t_out[k] == state[0]:  # a repeated output time: scipy's solver is already there
            states[k] = states[k - 1]
            k += 1
            continue
        exit_ = advance(state, d, ints, jband, ab, piv, units, t_out[k], rtol, atol, max_steps, lift_off_end,
                        (stepper.BDF_STALL, stepper.STALL_STEPS), rec_t, rec_x, *args)
        if observer is not None:
            for row in range(ints[8]):
                observer(rec_t[row], rec_x[row].copy())
        if exit_ == LANDED:
            states[k] = rec_x[ints[8] - 1]
            k += 1
        elif exit_ == STALLED:
            t, x = rec_t[ints[8] - 1], rec_x[ints[8] - 1].copy()
            states[k:], rest = stepper.integrate(problem, t_out[k:], method=stepper.HANDOVER, rtol=rtol, atol=atol,
                                                 h0=state[4], observer=observer, max_steps=max_steps - int(ints[6]),
                                                 resume=(t, x))
            stats.steps += rest.steps
            stats.newton_iterations += rest.newton_iterations
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
