"""The local mu(I) steady state of the DEM's own scene (continuum.velocity.BedScene), in its units.

The paper's exact steady state (continuum.steady, eq. (2.10)) scaled with continuum.scales:
u(y) = U [u~(y/delta_s) - u~(H/delta_s)] on a bed of depth H with a no-slip base (the layer is cut at
the base when H < delta_s: the velocity there is then zero, not U u~(H/delta_s)).  For an imposed speed
mu_w is the root of u(0) = u_w.  Exact up to rounding."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from granstokes.lib.validate import require

from .scales import Scales
from .steady import steady_velocity
from .velocity import BedScene

#: profile points of the steady velocity (plus delta_s when it lies inside the bed)
PROFILE_POINTS = 201
#: bracket of mu_w for an imposed speed, as fractions of mu_s above mu_s and of Dmu below mu_d
_BRACKET = 1e-12


@dataclass(frozen=True, eq=False)
class SceneSteady:
    """Steady state: depths ``y`` (from the plate), velocity ``u``, plate friction and speed, delta_s."""

    y: np.ndarray
    u: np.ndarray
    mu_w: float
    u_w: float
    delta_s: float


def scene_steady(scene: BedScene, *, mu_w=None, u_w=None, n_points: int = PROFILE_POINTS) -> SceneSteady:
    """The local steady state under an imposed mu_w (= tau_w/p_w) or plate speed u_w."""
    require((mu_w is None) != (u_w is None), "mu_w/u_w", "exactly one of them", (mu_w, u_w))
    m, fr = scene.material, scene.material.friction

    def profile(mw, y):
        sc = Scales(m, scene.p_w, mw)
        return sc.U * (steady_velocity(fr, mw, y / sc.delta_s) - steady_velocity(fr, mw, scene.depth / sc.delta_s))

    if mu_w is None:
        lo, hi = fr.mu_s * (1 + _BRACKET), fr.mu_d - _BRACKET * fr.dmu
        f = lambda mw: float(profile(mw, 0.0)) - u_w  # noqa: E731
        require(f(hi) > 0, "u_w", f"a speed reachable with mu_w < mu_d = {fr.mu_d:.6g}", u_w)
        mu_w = brentq(f, lo, hi, xtol=1e-15, rtol=1e-15)
    sc = Scales(m, scene.p_w, mu_w)
    y = np.linspace(0.0, scene.depth, n_points)
    y = np.unique(np.append(y, sc.delta_s if sc.delta_s < scene.depth else []))
    u = profile(mu_w, y)
    return SceneSteady(y, u, float(mu_w), float(u[0]), float(sc.delta_s))
