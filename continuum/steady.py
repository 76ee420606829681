"""Exact steady state of the paper's problem, in its dimensionless variables.

Steady shear stress is uniform, tau~ = 1, so mu = mu_w / (1 + beta_w y~) on y~ <= 1
(eq. (2.10)) and mu = mu_s below (y~ >= 1, i.e. y >= delta_s, eq. (2.11)).
The velocity follows by integrating eq. (3.10) from u~(1) = 0; with
s = sqrt(1 + beta_w y~) the integrand is rational in s and integrates in closed form
(checked against scipy.integrate.quad in the tests).
"""
from __future__ import annotations

import math

import numpy as np

from .rheology import Friction, finite, require

#: delta is where (mu - mu_s) has fallen to this fraction of (mu_w - mu_s); the paper's
#: 0.999 criterion, since erfc(2.327) = 1e-3.
DELTA_THRESHOLD = 1e-3


def _erfc_inverse(q: float) -> float:
    """x with erfc(x) = q, by Newton from x = 1 (math.erfc: no scipy.special import at start-up)."""
    x = 1.0
    for _ in range(50):
        step = (math.erfc(x) - q) / (-2.0 / math.sqrt(math.pi) * math.exp(-x * x))
        x -= step
        if abs(step) < 1e-15:
            break
    return x


#: delta/(Dmu sqrt(t~)) of the erfc solution (eq. (3.3)): 2 erfc^-1(1e-3) = 4.653 (the paper prints 4.66)
SELF_SIMILAR_DELTA = 2.0 * _erfc_inverse(DELTA_THRESHOLD)


def steady_mu(fr: Friction, mu_w: float, y):
    """Steady friction profile mu(y~) (eq. (2.10)), mu_s for y~ >= 1."""
    y = np.asarray(y, dtype=float)
    return np.where(y <= 1.0, mu_w / (1.0 + fr.beta(mu_w) * np.minimum(y, 1.0)), fr.mu_s)


def _antiderivative(fr: Friction, mu_w: float, s):
    """F(s) with dF/dy~ = sqrt(p~)(1/mu~ - 1)/Delta mu on the steady profile, s = sqrt(1+beta y~)."""
    md, dmu, beta = fr.mu_d, fr.dmu, fr.beta(mu_w)
    root = np.sqrt(md * mu_w)
    log_term = np.log((np.sqrt(md) * s - np.sqrt(mu_w)) / (np.sqrt(md) * s + np.sqrt(mu_w))) / (2 * root)
    inner = dmu * (s**3 / (3 * md) + mu_w * s / md**2 + mu_w**2 / md**2 * log_term) - s**3 / 3
    return 2.0 / (beta * dmu) * inner


def steady_velocity(fr: Friction, mu_w: float, y):
    """Steady velocity u~(y~) from eq. (3.10) with u~(1) = 0; zero for y~ >= 1."""
    fr.check_mu_w(mu_w)
    y = np.clip(np.asarray(y, dtype=float), 0.0, 1.0)
    beta = fr.beta(mu_w)
    return _antiderivative(fr, mu_w, np.sqrt(1 + beta)) - _antiderivative(fr, mu_w, np.sqrt(1 + beta * y))


def steady_wall_speed(fr: Friction, mu_w: float) -> float:
    """u~_w^inf, the exact steady wall speed (integral of eq. (3.10) over the layer)."""
    return float(steady_velocity(fr, mu_w, 0.0))


def mu_w_for_speed(fr: Friction, u_w: float) -> float:
    """Steady wall friction mu_w^inf that sustains the wall speed u~_w (root of steady_wall_speed).

    u~_w^inf increases monotonically from 0 (mu_w -> mu_s) to infinity (mu_w -> mu_d,
    logarithmically, eq. (3.12)), so the root is unique; it is bracketed in
    log(mu~_w), since mu~_w ~ exp(-Delta mu u~_w) for large speeds.
    """
    require(finite(u_w) and u_w > 0, "u_w", "a finite number > 0", u_w)
    lo, hi = np.log(1e-13), np.log1p(-1e-12)

    def residual(log_mt):
        return steady_wall_speed(fr, fr.mu_d - np.exp(log_mt) * fr.dmu) - u_w

    require(residual(hi) < 0 < residual(lo), "u_w", "a speed reachable with mu_s < mu_w < mu_d", u_w)
    from scipy.optimize import brentq  # imported here: it would cost every CLI start-up ~0.3 s

    return fr.mu_d - np.exp(brentq(residual, lo, hi, xtol=1e-15, rtol=1e-15)) * fr.dmu


def steady_delta(fr: Friction, mu_w: float, threshold: float = DELTA_THRESHOLD) -> float:
    """Steady layer thickness delta/delta_s under the threshold definition used for delta(t).

    On the steady profile (mu - mu_s)/(mu_w - mu_s) = (1 - y~)/(1 + beta_w y~).
    """
    beta = fr.beta(mu_w)
    return (1.0 - threshold) / (1.0 + threshold * beta)
