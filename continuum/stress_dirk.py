"""An imposed stress's adaptive DIRK solve (sdirk4, tr-bdf2), compiled (numba): what stepper.integrate does for an
ImposedStress, rule for rule, in one kernel call per stretch between output times.

The same steps: stepper.dirk_step's stages (the tableau's stage sums and Newton guesses, Tableau.stage_weights),
solve_stage's simplified Newton (the contraction estimate carried between stages, the full-Newton fallback on a
fresh Jacobian), the embedded estimate filtered through (M - h a_ss J)^-1, and integrate's step control (the
Newton-failure cut, the repeat cap, landing on the output times), with the constants read from continuum.stepper at
each call.  The rate and the Newton matrix are the stencil sums of ImposedStress.rate and .jacobian (tests/continuum
hold them equal); the band LU is continuum.compiled's.  Profiled, the Python solve spends its ~22 us a Newton
iteration in call overhead on 96 values (bench/RESULTS.md "Continuum: work-precision").
"""
from __future__ import annotations

import math
import time

import numpy as np

from . import stepper
from .compiled import band_lu, band_solve, jit, laplacians, rms
from .stepper import StepperFailure, StepStats

#: compiled.digest(compiled): these kernels build in its code, and numba's cache checks only this file, so this line
#: changes with it (tests/continuum/test_compiled_cache.py gives the new value)
BUILT_FROM = "ccdb4c6a4e3ad703"
#: per-step rows kept between two returns to Python (the observer's), per kernel call
RECORD_ROWS = 1024
#: the kernel's exits
LANDED, RECORDS_FULL, MAX_STEPS = range(3)
#: counters: accepted steps, rejected steps, Newton iterations, Newton failures, rows recorded in this call
STEPS, REJECTED, ITERATIONS, FAILURES, RECORDED = range(5)


@jit
def _rate(x, f, tau, lap, cols, weights, mud_p, p32, mu_w):
    """ImposedStress.rate: the wall row x_0 - 1, then D(tau~) d2 tau~/dy~2 at nodes 1..N-1."""
    laplacians(x, x[0], tau, lap, cols, weights)
    f[0] = x[0] - 1.0
    for i in range(len(lap)):
        s = mud_p[i] - mu_w * x[i + 1]
        f[i + 1] = s * s / p32[i] * lap[i]


@jit
def _newton_matrix(x, dh, ab, piv, kl, ku, tau, lap, cols, weights, mud_p, p32, mu_w):
    """LU of M - dh J(x) into ab (stepper.NewtonMatrix; ImposedStress.jacobian, whose wall row is e_0 with mass 0);
    U's upper bandwidth (compiled.band_lu; -1: singular)."""
    laplacians(x, x[0], tau, lap, cols, weights)
    n = len(x)
    kv = kl + ku
    ab[:] = 0.0
    ab[kv, 0] = -dh
    for i in range(1, n):
        s = mud_p[i - 1] - mu_w * x[i]
        diff = s * s / p32[i - 1]
        for k in range(cols.shape[1]):
            c = cols[i - 1, k]
            if c < n:
                ab[kv + i - c, c] -= dh * diff * weights[i - 1, k]
        ab[kv, i] += 1.0 + dh * 2 * mu_w * s / p32[i - 1] * lap[i - 1]
    return band_lu(ab, piv, kl, ku)


@jit
def _solve_stage(x, f, rhs, weights, tol, eta, max_iter, full, dh, ab, piv, upper, full_ab, full_piv, kl, ku,
                 counters, work, problem, newton):
    """stepper.solve_stage: x (the guess) becomes the stage X, f its F(X); returns (converged, eta).  newton =
    stepper's (NO_CONTRACTION, NO_CONTRACTION_FULL, SMALL_UPDATE)."""
    tau, lap, dx, cols, weights_lap, mud_p, p32, mu_w = (work[0], work[1], work[2], problem[0], problem[1],
                                                         problem[2], problem[3], problem[4])
    _rate(x, f, tau, lap, cols, weights_lap, mud_p, p32, mu_w)
    previous = -1.0
    n = len(x)
    full_upper = upper
    for _ in range(max_iter):
        counters[ITERATIONS] += 1
        if full:
            full_upper = _newton_matrix(x, dh, full_ab, full_piv, kl, ku, tau, lap, cols, weights_lap, mud_p, p32, mu_w)
            if full_upper < 0:  # stepper.NewtonMatrix raises: a failed step, no Newton failure counted
                return False, eta
        dx[0] = rhs[0] + dh * f[0]  # mass 0 on the wall row
        for i in range(1, n):
            dx[i] = rhs[i] - x[i] + dh * f[i]
        if full:
            band_solve(full_ab, full_piv, kl, ku, full_upper, dx)
        else:
            band_solve(ab, piv, kl, ku, upper, dx)
        size = rms(dx, weights)
        if not math.isfinite(size):
            break
        x += dx
        if previous >= 0:
            theta = size / previous
            if theta >= (newton[1] if full else newton[0]):  # no contraction
                break
            eta = theta / (1.0 - theta)
        if eta * size < tol or size < newton[2] * tol:
            x[0] = 1.0  # ImposedStress.project
            _rate(x, f, tau, lap, cols, weights_lap, mud_p, p32, mu_w)
            return True, eta
        _rate(x, f, tau, lap, cols, weights_lap, mud_p, p32, mu_w)
        previous = size
    counters[FAILURES] += 1
    return False, eta


@jit
def _dirk_step(x, f, h, weights, newton_tol, eta, tableau, rates, est, stage, guess, ab, piv, full_ab, full_piv,
               kl, ku, counters, work, problem, newton):
    """stepper.dirk_step: the stage X (and F(X) in rates[-1]) from (x, f), the filtered error estimate in est;
    returns (ok, eta)."""
    a, w, err, explicit_first = tableau
    s = a.shape[0]
    dh = h * a[s - 1, s - 1]
    upper = _newton_matrix(x, dh, ab, piv, kl, ku, work[0], work[1], problem[0], problem[1], problem[2], problem[3],
                           problem[4])
    if upper < 0:
        return False, eta
    rates[0] = f
    first = 1 if explicit_first else 0
    if first:
        rates[1] = f
    stage[:] = x
    for i in range(first, s):
        est[:] = x  # the stage's right-hand side M x_n + h S_i . K (est is free until the end)
        guess[:] = x  # its Newton guess M x_n + h P_i . K
        for j in range(i + 1):
            hs, hp = h * w[i, 0, j], h * w[i, 1, j]
            for m in range(len(x)):
                est[m] += hs * rates[j, m]
                guess[m] += hp * rates[j, m]
        est[0] = 0.0
        guess[0] = stage[0]  # the wall row from the last stage
        start = work[3]  # the guess, for the full-Newton fallback
        start[:] = guess
        ok, eta = _solve_stage(guess, rates[i + 1], est, weights, newton_tol, max(eta, newton[3]) ** newton[4],
                               newton[5], False, dh, ab, piv, upper, full_ab, full_piv, kl, ku, counters, work, problem,
                               newton)
        if not ok:
            guess[:] = start
            ok, eta = _solve_stage(guess, rates[i + 1], est, weights, newton_tol, 1.0, newton[6], True, dh, ab, piv,
                                   upper, full_ab, full_piv, kl, ku, counters, work, problem, newton)
            if not ok:
                return False, eta
        stage[:] = guess
    est[:] = 0.0
    for j in range(s):
        he = h * err[j]
        for m in range(len(x)):
            est[m] += he * rates[j + 1, m]
    est[0] = 0.0
    band_solve(ab, piv, kl, ku, upper, est)
    return True, eta


@jit
def advance(x, f, state, counters, t_bound, rtol, atol, newton_tol, max_steps, control, newton, tableau, rec_t, rec_x,
            kl, ku, problem):
    """Step until t_bound is reached (LANDED; within control's OUTPUT_RTOL), the record is full, or max_steps.
    state = [t, h, eta, h_fail, cap]; control = stepper's step control (NEWTON_CUT, REPEAT_BAND, CAP_START, CAP_GROWTH,
    OUTPUT_RTOL, LANDING_SHARE, STEP_SAFETY, STEP_SHRINK, STEP_GROW, ERROR_FLOOR), newton its Newton rules
    (NO_CONTRACTION, NO_CONTRACTION_FULL, SMALL_UPDATE, ETA_FLOOR, ETA_DECAY, NEWTON_ITERATIONS,
    FULL_NEWTON_ITERATIONS); x, f: the state and its rate, carried."""
    newton_cut, repeat_band, cap_start, cap_growth, output_rtol, landing, safety, shrink, grow, floor = control
    n = len(x)
    s = tableau[0].shape[0]
    err_order = tableau[4]
    rates, est = np.empty((s + 1, n)), np.empty(n)
    stage, guess, weights = np.empty(n), np.empty(n), np.empty(n)
    ab, full_ab = np.empty((n, 2 * kl + ku + 1)).T, np.empty((n, 2 * kl + ku + 1)).T  # columns contiguous
    piv, full_piv = np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64)
    work = (np.empty(n + 1), np.empty(n - 1), np.empty(n), np.empty(n))  # tau~ at all nodes, Laplacian, update, guess
    t, h, eta, h_fail, cap = state[0], state[1], state[2], state[3], state[4]
    counters[RECORDED] = 0
    while True:
        if counters[STEPS] + counters[REJECTED] >= max_steps:
            state[0], state[1], state[2], state[3], state[4] = t, h, eta, h_fail, cap
            return MAX_STEPS
        h_try = min(h, t_bound - t)
        if t_bound - (t + h_try) < landing * h_try:
            h_try = t_bound - t
        for i in range(n):
            weights[i] = atol + rtol * abs(x[i])
        ok, eta_step = _dirk_step(x, f, h_try, weights, newton_tol, eta, tableau[:4], rates, est, stage, guess, ab, piv,
                                  full_ab, full_piv, kl, ku, counters, work, problem, newton)
        if not ok:  # stepper.integrate's NewtonFailure
            eta = 1.0
            counters[REJECTED] += 1
            if abs(h_try / h_fail - 1.0) < repeat_band:
                cap = cap_start * h_try
            h, h_fail = newton_cut * h_try, h_try
            continue
        eta = eta_step
        err = max(rms(est[1:], weights[1:]), floor)
        factor = safety * err ** (-1.0 / err_order)
        if err > 1.0:
            counters[REJECTED] += 1
            h = h_try * max(shrink, factor)
            continue
        h = min(h_try * min(grow, max(shrink, factor)), cap)
        cap *= cap_growth
        counters[STEPS] += 1
        x[:] = stage
        f[:] = rates[s]
        t += h_try
        rec_t[counters[RECORDED]] = t
        rec_x[counters[RECORDED]] = x
        counters[RECORDED] += 1
        state[0], state[1], state[2], state[3], state[4] = t, h, eta, h_fail, cap
        if abs(t - t_bound) <= output_rtol * abs(t_bound):
            return LANDED
        if counters[RECORDED] == len(rec_t):
            return RECORDS_FULL


def integrate_stress(problem, t_out, tab, *, rtol, atol, h0, newton_tol, observer, max_steps, repeat_cap=True):
    """stepper.integrate for an ImposedStress with an adaptive DIRK ``tab``, compiled: (states at t_out, StepStats)."""
    t_out = np.asarray(t_out, dtype=float)
    start = time.process_time()
    n = problem.mesh.n_cells
    cols, weights, mud_p, p32, mu_w = problem.stencil()
    data = (cols, weights, mud_p, p32, float(mu_w))
    tableau = (tab.matrix, tab.stage_weights, tab.error_weights, tab.explicit_first, int(tab.err_order))
    control = (stepper.NEWTON_CUT, stepper.REPEAT_BAND if repeat_cap else 0.0, stepper.CAP_START, stepper.CAP_GROWTH,
               stepper.OUTPUT_RTOL, stepper.LANDING_SHARE, stepper.STEP_SAFETY, stepper.STEP_SHRINK, stepper.STEP_GROW,
               stepper.ERROR_FLOOR)
    newton = (stepper.NO_CONTRACTION, stepper.NO_CONTRACTION_FULL, stepper.SMALL_UPDATE, stepper.ETA_FLOOR,
              stepper.ETA_DECAY, stepper.NEWTON_ITERATIONS, stepper.FULL_NEWTON_ITERATIONS)
    x = problem.initial().astype(float)
    f = np.empty(n)
    _rate(x, f, np.empty(n + 1), np.empty(n - 1), *data)
    state = np.array([0.0, h0, 1.0, math.inf, math.inf])
    counters = np.zeros(5, dtype=np.int64)
    rec_t, rec_x = np.empty(RECORD_ROWS), np.empty((RECORD_ROWS, n))
    if observer is not None:
        observer(0.0, x.copy())
    states = np.empty((len(t_out), n))
    k = 0
    while k < len(t_out):
        exit_ = advance(x, f, state, counters, t_out[k], rtol, atol, newton_tol, max_steps, control, newton, tableau,
                        rec_t, rec_x, problem.kl, problem.ku, data)
        if observer is not None:
            for row in range(counters[RECORDED]):
                observer(rec_t[row], rec_x[row].copy())
        if exit_ == MAX_STEPS:
            raise StepperFailure(f"max_steps = {max_steps} reached at t = {state[0]:.3e}")
        while exit_ == LANDED and k < len(t_out) and abs(state[0] - t_out[k]) <= stepper.OUTPUT_RTOL * abs(t_out[k]):
            states[k] = x
            k += 1
    stats = StepStats(int(counters[STEPS]), int(counters[REJECTED]), int(counters[ITERATIONS]),
                      int(counters[FAILURES]), time.process_time() - start)
    return states, stats
