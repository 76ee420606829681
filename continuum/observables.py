"""Quantities derived from a shear-stress profile tau~(y~) on a Mesh (paper section 3.3).

All take the friction law, the reference wall friction mu_w (imposed, or mu_w^inf for an imposed
speed), the mesh and tau~ at every node (last axis; leading axes are times), and the ``order`` of
the discretisation (continuum.mesh: 2 or 4), to which the integrals and the crossing are matched.
"""
from __future__ import annotations

import numpy as np

from .crossing import crossing_depth
from .mesh import Mesh
from .rheology import Friction
from .steady import DELTA_THRESHOLD


def friction_profile(fr: Friction, mu_w: float, mesh: Mesh, tau):
    """mu = mu_w tau~ / p~ with p~ = 1 + beta_w y~."""
    return mu_w * np.asarray(tau) / (1.0 + fr.beta(mu_w) * mesh.y)


def shear_rate(fr: Friction, mu_w: float, mesh: Mesh, tau):
    """-du~/dy~ = sqrt(p~)/Dmu (1/mu~ - 1) (eq. (3.10)), as (mu - mu_s)/(mu_d - mu): no
    cancellation where mu ~ mu_s."""
    mu = friction_profile(fr, mu_w, mesh, tau)
    with np.errstate(divide="ignore"):  # mu = mu_d at an imposed speed's wall before t~_mud: infinite
        return np.sqrt(1.0 + fr.beta(mu_w) * mesh.y) / fr.dmu * (mu - fr.mu_s) / (fr.mu_d - mu)


def velocity(fr: Friction, mu_w: float, mesh: Mesh, tau, order: int = 4, wall_speed: float | None = None):
    """u~(y~) integrated from u~(1) = 0 upwards (the mesh's rule of that order).  With an imposed
    ``wall_speed`` the wall node may be singular (continuum.problems.ImposedSpeed): the profile is
    integrated from nodes 1..N, and u~(0) is the imposed speed (the constraint, which holds to
    round-off, carries the first cell)."""
    rate = shear_rate(fr, mu_w, mesh, tau)
    if wall_speed is None:
        return mesh.integral_from_bottom(rate, order)
    rate[..., 0] = 0.0  # not used (and possibly infinite)
    pieces = mesh.cell_integrals_from_node1(order)(rate)
    up = np.cumsum(pieces[..., ::-1], axis=-1)[..., ::-1]
    return np.concatenate([np.full_like(up[..., :1], wall_speed), up, np.zeros_like(up[..., :1])], axis=-1)


def layer_thickness(fr: Friction, mu_w: float, mesh: Mesh, tau, order: int = 4, threshold: float = DELTA_THRESHOLD):
    """delta(t~)/delta_s: first depth where (mu - mu_s) falls to ``threshold`` of the wall excess
    (mu(0) - mu_s), interpolated in log (mu - mu_s) between nodes (continuum.crossing): linearly for
    order 2 (exact for an exponential tail), on a cubic for order 4, of log((mu - mu_s)/(1 - y~)) (mu = mu_s
    at y~ = 1, the bottom of the steady layer)."""
    mu = friction_profile(fr, mu_w, mesh, tau)
    return crossing_depth(mesh.y, (mu - fr.mu_s) / (mu[..., :1] - fr.mu_s), threshold, log=True, cubic=order > 2,
                          end_zero=True)


class SeriesRecorder:
    """Observer: keeps t~ and the state after every accepted time step; ``table()`` derives u~_w,
    mu_w and delta from them in one vectorised pass."""

    def __init__(self, problem):
        self.problem = problem
        self.times: list[float] = []
        self.states: list[np.ndarray] = []

    def __call__(self, t, x):
        self.times.append(t)
        self.states.append(x.copy())

    def table(self) -> np.ndarray:
        """Rows (t, u_w, mu_w, delta); delta = 0 at t = 0."""
        pb = self.problem
        t = np.array(self.times)
        tau = np.array([pb.full(x) for x in self.states]).reshape(len(t), -1)
        delta = np.zeros(len(t))
        if len(t):
            late = t > 0
            delta[late] = layer_thickness(pb.friction, pb.mu_w, pb.mesh, tau[late], pb.order)
        u_w = velocity(pb.friction, pb.mu_w, pb.mesh, tau, pb.order, getattr(pb, "u_w", None))[:, 0]
        return np.column_stack([t, u_w,
                                pb.mu_w * tau[:, 0], delta]) if len(t) else np.empty((0, 4))


class JoinedSeries:
    """The per-step rows of two solves from t~ = 0 (SeriesRecorder or arrays): ``early``'s up to
    ``t_split``, ``late``'s after it (continuum.solver: the early output times on a deeper map)."""

    def __init__(self, early, t_split: float, late):
        self.early, self.t_split, self.late = early, t_split, late

    def table(self) -> np.ndarray:
        rows = [r.table() if hasattr(r, "table") else r for r in (self.early, self.late)]
        return np.vstack([rows[0][rows[0][:, 0] <= self.t_split], rows[1][rows[1][:, 0] > self.t_split]])
