"""TR-BDF2 time integration (Bank et al. 1985; Hosea & Shampine 1996) with Newton on the
bordered tridiagonal system.

Why TR-BDF2 and not plain Crank-Nicolson: the wall condition switches on impulsively at t~ = 0
(tau~ jumps from mu_s/mu_w to 1, or u~ from 0 to u~_w), and CN does not damp the stiff
high-wavenumber modes this excites (amplification -> -1), so it rings on the graded mesh once
D dt/h^2 >> 1.  TR-BDF2 is a trapezoidal stage to t_n + gamma h followed by a BDF2 stage: second
order, L-stable, one-step (so variable steps are free), both stages with the same matrix
I - d h J (d = gamma/2, gamma = 2 - sqrt 2), and an embedded local error estimate.

Each stage solves x - d h F(x) = rhs on interior rows plus the wall row g(x) = 0 by full Newton.
The Newton matrix is tridiagonal except for the (dense) wall row; it is solved by bordering:
one LAPACK gttrf factorisation and one gttrs with two right-hand sides per iteration.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.linalg.lapack import dgttrf, dgttrs

GAMMA = 2.0 - np.sqrt(2.0)
D = GAMMA / 2.0
C_ERR = (-3 * GAMMA**2 + 4 * GAMMA - 2) / (12 * (2 - GAMMA))
W_XG = 1.0 / (GAMMA * (2.0 - GAMMA))
W_XN = (1.0 - GAMMA) ** 2 / (GAMMA * (2.0 - GAMMA))


@dataclass
class StepStats:
    steps: int = 0
    rejected: int = 0
    newton_iterations: int = 0
    newton_failures: int = 0
    cpu_seconds: float = 0.0


class NewtonFailure(RuntimeError):
    pass


def bordered_solve(a, c, b1, dl, d, du, r0, r):
    """Solve [[a, c], [b1 e_1, T]] [x0; z] = [r0; r], T = tridiag(dl, d, du)."""
    dl_, d_, du_, du2, ipiv, info = dgttrf(dl, d, du)
    if info != 0:
        raise NewtonFailure("singular Newton matrix")
    rhs = np.zeros((len(d), 2))
    rhs[:, 0] = r
    rhs[0, 1] = b1
    sol, info = dgttrs(dl_, d_, du_, du2, ipiv, rhs)
    zr, zb = sol[:, 0], sol[:, 1]
    x0 = (r0 - c @ zr) / (a - c @ zb)
    return np.concatenate(([x0], zr - x0 * zb))


def _newton_matrix(problem, x, dh):
    rate, sub, diag, sup = problem.rate_and_jacobian(x)
    return rate, -dh * sub, 1.0 - dh * diag, -dh * sup


def solve_stage(problem, x, dh, rhs, weights, tol, stats, max_iter=10):
    """Solve x - dh F(x) = rhs (interior rows), g(x) = 0 (wall row) by Newton from guess x.

    Converged when the weighted RMS norm of the update is below ``tol``; returns (x, F(x))."""
    x = x.copy()
    for _ in range(max_iter):
        stats.newton_iterations += 1
        rate, sub, diag, sup = _newton_matrix(problem, x, dh)
        g, grad = problem.wall(x)
        res = x[1:] - dh * rate - rhs
        dx = bordered_solve(grad[0], grad[1:], sub[0], sub[1:], diag, sup, -g, -res)
        if not np.all(np.isfinite(dx)):
            break
        x += problem.step_fraction(x, dx) * dx
        if np.sqrt(np.mean((dx / weights) ** 2)) < tol:
            return x, problem.rate(x)
    stats.newton_failures += 1
    raise NewtonFailure("Newton did not converge")


def tr_bdf2_step(problem, x, f, h, xg_guess, weights, newton_tol, stats):
    """One TR-BDF2 step of size h from (x, f = F(x)); returns x_{n+1}, F_{n+1} and the
    filtered local error estimate (Hosea & Shampine 1996, eq. for the TR-BDF2 pair)."""
    dh = D * h
    xg, fg = solve_stage(problem, xg_guess, dh, x[1:] + dh * f, weights, newton_tol, stats)
    guess = x + (xg - x) / GAMMA
    x1, f1 = solve_stage(problem, guess, dh, W_XG * xg[1:] - W_XN * x[1:], weights, newton_tol, stats)
    est = 2 * C_ERR * h * (f / GAMMA - fg / (GAMMA * (1 - GAMMA)) + f1 / (1 - GAMMA))
    _, sub, diag, sup = _newton_matrix(problem, x1, dh)
    _, grad = problem.wall(x1)
    err = bordered_solve(grad[0], grad[1:], sub[0], sub[1:], diag, sup, 0.0, est)
    return x1, f1, err, xg


def integrate(problem, t_out, *, rtol=1e-6, atol=1e-8, h0=1e-9, newton_tol=1e-3, fixed_times=None,
              observer=None, max_steps=200_000):
    """Integrate ``problem`` from t~ = 0, returning the state at each time of the sorted ``t_out``.

    Adaptive steps keep the RMS local error (atol + rtol |x|)-weighted below 1; with
    ``fixed_times`` (an increasing array that contains every t_out) the steps are those, with no
    error control (for refinement studies).  ``observer(t, x)`` is called after every accepted step.
    Returns (states, stats) with states of shape (len(t_out), N).
    """
    t_out = np.asarray(t_out, dtype=float)
    stats = StepStats()
    start = time.process_time()
    x = problem.initial()
    f = problem.rate(x)
    t, h = 0.0, h0
    x_prev, h_prev = None, None
    states = np.empty((len(t_out), len(x)))
    k = 0
    schedule = None if fixed_times is None else iter(np.asarray(fixed_times, dtype=float))
    if observer is not None:
        observer(t, x)
    while k < len(t_out):
        if stats.steps + stats.rejected >= max_steps:
            raise RuntimeError(f"max_steps = {max_steps} reached at t~ = {t:.3e}")
        if schedule is not None:
            h_try = next(schedule) - t
        else:
            h_try = min(h, t_out[k] - t)
            if t_out[k] - (t + h_try) < 0.05 * h_try:
                h_try = t_out[k] - t
        weights = atol + rtol * np.abs(x[1:])
        weights = np.concatenate(([weights[0]], weights))
        # predictor for the TR stage: linear extrapolation of the last step
        xg_guess = x if x_prev is None else x + (x - x_prev) * (GAMMA * h_try / h_prev)
        try:
            x1, f1, err_vec, _ = tr_bdf2_step(problem, x, f, h_try, xg_guess, weights, newton_tol, stats)
        except NewtonFailure:
            if schedule is not None:
                raise
            stats.rejected += 1
            h = 0.25 * h_try
            continue
        err = np.sqrt(np.mean((err_vec[1:] / weights[1:]) ** 2))
        if schedule is None and err > 1.0:
            stats.rejected += 1
            h = h_try * max(0.2, 0.9 * err ** (-1 / 3))
            continue
        stats.steps += 1
        x_prev, h_prev = x, h_try
        x, f, t = x1, f1, t + h_try
        if observer is not None:
            observer(t, x)
        if schedule is None:
            h = h_try * min(4.0, max(0.2, 0.9 * max(err, 1e-10) ** (-1 / 3)))
        while k < len(t_out) and np.isclose(t, t_out[k], rtol=1e-13, atol=0.0):
            states[k] = x
            k += 1
        if schedule is not None and k < len(t_out) and t > t_out[k]:
            raise ValueError("fixed_times must contain every output time")
    stats.cpu_seconds = time.process_time() - start
    return states, stats
