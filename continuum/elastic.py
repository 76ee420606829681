"""Elasto-plastic mu(I) on the DEM's scene: the velocity form (continuum.velocity) with an elastic shear stress.

The local mu(I) law is rigid below yield: the plate's stress reaches every depth at once.  A bed of grains is not:
below yield it shears elastically and carries the stress down as a wave of speed c_s = sqrt(G/(phi rho_p)).  A
Maxwell-type elasto-plastic law (as in Dunatunga & Kamrin, J. Fluid Mech. 779, 2015, in one dimension) keeps the
momentum equation and lets the stress relax with the elastic shear modulus G:

    phi rho_p du/dt = d sigma_xy/dy + b,                          0 < y < H (y downward from the plate), u(H) = 0,
    (1/G) d sigma_xy/dt = du/dy - gamma_p(sigma_xy, p),           p = p_w + phi rho_p g y (hydrostatic, eq. (2.6)),
    gamma_p = sign(sigma) 2 I(|sigma|/p) sqrt(p/rho_p)/d  for |sigma| > mu_s p, else 0,

I(mu) = I0 (mu - mu_s)/(mu_d - mu) the inverse of eq. (2.1) in the paper's convention (|gamma_dot| = 1/2 |du/dy|,
so the plastic du/dy is twice I sqrt(p/rho_p)/d).  The plate is the velocity form's: an imposed speed u(0) = u_w(t),
or an imposed stress moving the plate's mass.  Below yield the stress obeys the wave equation; above it the stress
relaxes towards mu(I) p in a time of order mu_d/(G (d gamma_p/d sigma)), so G -> infinity recovers local mu(I) and
its steady state is local mu(I)'s (continuum.scene_models.local_steady) whatever G.

Discretisation: velocities at the nodes of a Mesh scaled to [0, H] (u_N = 0 at the base), stresses at the faces;
unknowns interleaved (u_0, s_0, u_1, s_1, ...; the speed drive's u_0 is a boundary value), so the Jacobian is
tridiagonal and the system M x' = F(x, t) (M: node masses, 1/G on the stress rows) goes through the method
registry (continuum.integrators: TR-BDF2, L-stable, by default).  The plastic rate is stiff near mu_d (its slope
diverges there): the implicit stages solve it, and a Newton step is cut short so that no face's |s| reaches mu_d p
(``step_fraction``).  The elastic wave is resolved in time by the error control: a drive costs steps of order its
duration over the wave's transit of a cell while the bed rings (bench/RESULTS.md "Elasto-plastic model").
Dimensional: the material's units (DEM units d = rho_p = g = 1 by default).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pandas as pd

from .integrators import integrate
from .jacobian import Jacobian
from .load import Load
from .mesh import Mesh
from .rheology import require
from .scales import Material, pressure
from .scene import BedScene, SceneNumerics
from .solver import check_times
from .stepper import FIRST_STEP, StepStats
from .velocity import PlateReadings

#: the elastic model's numerics: a mildly graded mesh (the wave crosses it at one speed), TR-BDF2
ELASTIC_NUMERICS = SceneNumerics(n_cells=200, stretch=2.0, rtol=1e-4, atol=1e-7, method="tr-bdf2")
#: a Newton step may take a face's |s| at most this fraction of the way from where it is to mu_d p
BARRIER_FRACTION = 0.9
#: the plastic rate is evaluated at most 1 - UNREACHED of mu_d (a safeguard: step_fraction keeps states below it)
UNREACHED = 1e-9


class ElasticProblem:
    """M x' = F(x, t) of the interleaved unknowns (u_0, s_0, u_1, s_1, ..., u_{N-1}, s_{N-1}); under an imposed speed
    u_0 = u_w(t) is a boundary value and the unknowns start at s_0.  Tridiagonal Jacobian (the wave couples each
    node to its two faces; the plastic rate each face to itself)."""

    carries_contraction = False
    dense_wall = False

    def __init__(self, material: Material, scene: BedScene, load: Load, mesh_unit: Mesh, G: float):
        require(np.isfinite(G) and G > 0, "G", "a finite shear modulus > 0", G)
        self.material, self.scene, self.load, self.G = material, scene, load, float(G)
        self.y = mesh_unit.y * scene.depth
        self.h = np.diff(self.y)
        self.p_face = pressure(material, load.p_w, self.y[:-1] + self.h / 2)
        fr = material.friction
        self.mu_s, self.mu_d = fr.mu_s, fr.mu_d
        #: d(gamma_p)/d(mu) per unit I(mu)/I0 on each face: 2 I0 sqrt(p/rho_p)/d
        self.rate_scale = 2 * material.I0_paper * np.sqrt(self.p_face / material.rho_p) / material.d
        rho_b = material.phi * material.rho_p
        n = len(self.h)
        node_mass = np.empty(n)
        node_mass[0] = rho_b * self.h[0] / 2
        node_mass[1:] = rho_b * (self.h[:-1] + self.h[1:]) / 2
        self.first = 0 if load.kind == "stress" else 1
        if load.kind == "speed":
            node_mass[1] += node_mass[0]  # the wall half-cell moves with the bed (continuum.velocity)
        self.body = scene.body_force / rho_b * node_mass if scene.body_force else None
        node_mass[0] += scene.plate_mass
        self.n = n
        mass = np.empty(2 * n)
        mass[0::2], mass[1::2] = node_mass, 1.0 / self.G
        self.mass = mass[self.first:]

    # --- the state's parts ---------------------------------------------------------------------------------
    def _full(self, x):
        """The interleaved (u_0, s_0, ..., u_{N-1}, s_{N-1}) with u_0 a placeholder under an imposed speed."""
        full = np.zeros((*np.shape(x)[:-1], 2 * self.n))
        full[..., self.first:] = x
        return full

    def nodes(self, x, t):
        """u at every node 0..N (u_N = 0) of the unknowns x (the last axis) at the time(s) t."""
        full = self._full(x)
        u = np.zeros((*np.shape(x)[:-1], self.n + 1))
        u[..., :-1] = full[..., 0::2]
        if self.load.kind == "speed":
            u[..., 0] = self.load.wall(t)
        return u

    def stress(self, x, t=None):
        """sigma_xy at the faces (any leading axes)."""
        return self._full(x)[..., 1::2]

    def plastic(self, s):
        """gamma_p(s) on the faces and its slope d gamma_p/d s (zero below yield); |s|/p is read at most
        1 - UNREACHED of mu_d (an accepted state never reaches mu_d: ``step_fraction``)."""
        mu = np.minimum(np.abs(s) / self.p_face, self.mu_d * (1 - UNREACHED))
        room = self.mu_d - mu
        rate = self.rate_scale * np.maximum(mu - self.mu_s, 0.0) / room
        slope = np.where(mu > self.mu_s, self.rate_scale * (self.mu_d - self.mu_s) / room**2 / self.p_face, 0.0)
        return np.sign(s) * rate, slope

    # --- the integrator's interface -------------------------------------------------------------------------
    def initial(self) -> np.ndarray:
        """The bed at rest and stress-free (the DEM's deposited bed before the plate moves)."""
        return np.zeros(len(self.mass))

    def rate(self, x, t):
        full = self._full(x)
        u = np.append(full[0::2], 0.0)
        if self.load.kind == "speed":
            u[0] = self.load.wall(t)
        s = full[1::2]
        f = np.empty(2 * self.n)
        f[2::2] = s[1:] - s[:-1]
        f[0] = self.load.wall(t) + s[0]  # the plate (its row is dropped under an imposed speed)
        if self.body is not None:
            f[0::2] += self.body
        gp, _ = self.plastic(s)
        f[1::2] = (u[1:] - u[:-1]) / self.h - gp
        return f[self.first:]

    def jacobian(self, x, t):
        s = self._full(x)[1::2]
        _, slope = self.plastic(s)
        m = 2 * self.n
        diag, sup, sub = np.zeros(m), np.zeros(m - 1), np.zeros(m - 1)
        # node rows 2j: dF/ds_j = +1 (super), dF/ds_{j-1} = -1 (sub); the plate's row 0 has s_0 only
        sup[0::2] = 1.0
        sub[1::2] = -1.0
        # face rows 2j+1: dF/du_j = -1/h_j (sub), dF/du_{j+1} = 1/h_j (super, none at the base), dF/ds_j = -slope
        sub[0::2] = -1.0 / self.h
        sup[1::2] = 1.0 / self.h[:-1]
        diag[1::2] = -slope
        f = self.first
        return Jacobian.tridiagonal(sub[f:], diag[f:], sup[f:])

    def project(self, x):
        return x

    def step_fraction(self, x, dx):
        """The largest fraction (<= 1) of the Newton step dx that keeps every face's |s| below mu_d p:
        BARRIER_FRACTION of the way to it where the full step would cross it."""
        s, ds = self._full(x)[1::2], self._full(dx)[1::2]
        limit = self.mu_d * self.p_face
        new = np.abs(s + ds)
        crossing = (new >= limit) & (ds != 0)
        if not crossing.any():
            return 1.0
        room = limit[crossing] - np.abs(s[crossing])
        return float(max(np.min(BARRIER_FRACTION * room / np.abs(ds[crossing])), 0.0))


@dataclass(frozen=True, eq=False)
class ElasticSolution(PlateReadings):
    """u at the nodes and sigma_xy at the faces at the requested times, the state after every accepted step;
    dimensional (the material's units)."""

    problem: ElasticProblem
    y: np.ndarray
    y_face: np.ndarray
    t: np.ndarray
    u: np.ndarray
    s: np.ndarray
    step_t: np.ndarray
    step_x: np.ndarray
    stats: StepStats

    @cached_property
    def series(self) -> pd.DataFrame:
        """Every accepted step: t, u_w, mu_w."""
        pr = self.problem
        return pd.DataFrame({"t": self.step_t, "u_w": pr.nodes(self.step_x, self.step_t)[:, 0],
                             "mu_w": pr.load.plate_friction(self.step_t, pr.stress(self.step_x)[:, 0])})


def solve_elastic(material: Material, scene: BedScene, load: Load, times, G: float, *,
                  numerics: SceneNumerics = ELASTIC_NUMERICS) -> ElasticSolution:
    """The elasto-plastic bed from rest under a held or oscillating load (an imposed stress or speed), shear modulus
    ``G`` (the material's stress units), at the output ``times``; the first step a fraction of the wave's transit."""
    t = check_times(times)
    problem = ElasticProblem(material, scene, load, numerics.mesh(), G)
    steps_t, steps_x = [], []

    def observe(time, x):
        steps_t.append(time)
        steps_x.append(x)

    transit = scene.depth / np.sqrt(G / (material.phi * material.rho_p))
    states, stats = integrate(problem, t, method=numerics.method, rtol=numerics.rtol, atol=numerics.atol,
                              h0=FIRST_STEP * transit, observer=observe)
    y_face = problem.y[:-1] + problem.h / 2
    return ElasticSolution(problem, problem.y, y_face, t, problem.nodes(states, t), problem.stress(states),
                           np.array(steps_t), np.array(steps_x), stats)
