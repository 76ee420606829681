"""Quantities derived from a shear-stress profile tau~(y~) on a Mesh (paper section 3.3).

All take the friction law, the reference wall friction mu_w (imposed, or mu_w^inf for an imposed
speed), the mesh and tau~ at every node (last axis; leading axes are times).
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import cumulative_trapezoid

from .crossing import crossing_depth
from .mesh import Mesh
from .rheology import Friction
from .steady import DELTA_THRESHOLD


def friction_profile(fr: Friction, mu_w: float, mesh: Mesh, tau):
    """mu = mu_w tau~ / p~ with p~ = 1 + beta_w y~."""
    return mu_w * np.asarray(tau) / (1.0 + fr.beta(mu_w) * mesh.y)


def shear_rate(fr: Friction, mu_w: float, mesh: Mesh, tau):
    """-du~/dy~ = sqrt(p~)/Dmu (1/mu~ - 1) (eq. IreWrittenNonDim)."""
    mt = fr.tilde(friction_profile(fr, mu_w, mesh, tau))
    return np.sqrt(1.0 + fr.beta(mu_w) * mesh.y) / fr.dmu * (1.0 / mt - 1.0)


def velocity(fr: Friction, mu_w: float, mesh: Mesh, tau):
    """u~(y~) integrated from u~(1) = 0 upwards with the trapezoidal rule (second order)."""
    rate = shear_rate(fr, mu_w, mesh, tau)
    up = cumulative_trapezoid(rate[..., ::-1], -mesh.y[::-1], axis=-1, initial=0.0)
    return up[..., ::-1]


def layer_thickness(fr: Friction, mu_w: float, mesh: Mesh, tau, threshold: float = DELTA_THRESHOLD):
    """delta(t~)/delta_s: first depth where (mu - mu_s) falls to ``threshold`` of the wall excess
    (mu(0) - mu_s), log-linear between nodes (exact for an exponential tail; continuum.crossing)."""
    mu = friction_profile(fr, mu_w, mesh, tau)
    return crossing_depth(mesh.y, (mu - fr.mu_s) / (mu[..., :1] - fr.mu_s), threshold, log=True)


class SeriesRecorder:
    """Observer: records t~, u~_w, mu_w and delta after every accepted time step."""

    def __init__(self, problem):
        self.problem = problem
        self.rows: list[tuple[float, float, float, float]] = []

    def __call__(self, t, x):
        pb = self.problem
        tau = pb.full(x)
        u_w = float(pb.mesh.weights @ shear_rate(pb.friction, pb.mu_w, pb.mesh, tau))
        delta = float(layer_thickness(pb.friction, pb.mu_w, pb.mesh, tau)) if t > 0 else 0.0
        self.rows.append((t, u_w, pb.mu_w * tau[0], delta))
