"""Velocity-form mu(I) solver for the DEM's own scene: a bed of finite depth H on a rough base,
a plate with mass, any initial state (paper eqs. (2.5)-(2.6) without the stress-diffusion rewrite).

    phi rho_p du/dt = d sigma_xy/dy + b   on 0 < y < H (y downward from the plate),   u(H) = 0,
    sigma_xy = s(g, p) from a YieldRule (continuum.rules), g = 1/2 du/dy, p = p_w + phi rho_p g y,
    plate:  imposed speed u(0) = u_w,  or imposed stress  (m_p + phi rho_p h_0/2) du_w/dt = tau_w + sigma_xy(0+).

Finite volumes: velocities at the nodes of a Mesh scaled to [0, H], stresses at the faces; the
Jacobian is tridiagonal and the system goes through the same DIRK stepper as the paper's problem
(TR-BDF2 by default).
Dimensional: the material's units (DEM units d = rho_p = g = 1 by default).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pandas as pd

from .crossing import crossing_depth
from .jacobian import Jacobian
from .mesh import Mesh
from .rheology import finite, require
from .rules import ShearLaw, YieldRule
from .scales import Material, Scales
from .solver import Numerics, check_times
from .steady import DELTA_THRESHOLD
from .stepper import StepStats, integrate


@dataclass(frozen=True)
class BedScene:
    """A bed of depth H under a plate of mass m_p per unit area, pressed with p_w; ``body_force``
    is a uniform horizontal force per unit volume (0 for the DEM's horizontal bed).

    The paper's initial state tau = mu_s p is a static equilibrium only with
    body_force = mu_s phi rho_p g (a bed tilted to tan(theta) = mu_s): a horizontal bed cannot hold a
    shear stress that grows with depth.  The stress-diffusion equation does not see this (it only
    involves d(du/dy)/dt, blind to a uniform acceleration), so to compare with it from that state
    the velocity form needs that body force (tests, report)."""

    material: Material
    p_w: float
    depth: float
    plate_mass: float = 0.0
    body_force: float = 0.0

    def __post_init__(self):
        require(finite(self.p_w) and self.p_w > 0, "p_w", "a finite number > 0", self.p_w)
        require(finite(self.depth) and self.depth > 0, "depth", "a finite number > 0", self.depth)
        require(finite(self.plate_mass) and self.plate_mass >= 0, "plate_mass",
                "a finite number >= 0 (mass per unit plate area)", self.plate_mass)
        require(finite(self.body_force), "body_force", "a finite number", self.body_force)

    @property
    def weight_gradient(self) -> float:
        m = self.material
        return m.phi * m.rho_p * m.g


#: the velocity form's defaults: a milder wall grading than the paper's (no singular wall layer),
#: tolerances for dimensional velocities of O(1-10) in DEM units, and TR-BDF2 (2 implicit stages a step to
#: SDIRK4's 5).  bench/velocity_form.py: 400 cells at stretch 4 put the quick stress drive within 1e-4
#: (200 cells at stretch 2 with SDIRK4: 2-4e-4); atol 1e-8 instead of 1e-9 stops resolving
#: to 1e-5 relative the creep (|g| ~ eps) that runs ahead of the yield front through the whole bed in the
#: first ~0.01 time units (0.7x the steps, errors equal to 2 digits; 1e-7 and 1e-6 raise delta_u's error)
VELOCITY_NUMERICS = Numerics(n_cells=400, stretch=4.0, rtol=1e-5, atol=1e-8, method="tr-bdf2")
#: the stepper of a Numerics that names none (the references of tests and bench: SDIRK4, fourth order in time)
VELOCITY_METHOD = "sdirk4"


class VelocityProblem:
    """M u' = F(u) for the nodal velocities u_0..u_{N-1} (u_N = 0 at the base) of an imposed stress, or
    u_1..u_{N-1} of an imposed speed (u_0 = u_w is then a boundary value, not an unknown).  The Jacobian
    is symmetric tridiagonal with -J a weighted Laplacian (ds/dg > 0): M - dh J is positive definite."""

    #: the simplified Newton contracts unevenly as faces cross the regularised law's kink |g| ~ eps, so a
    #: stage's contraction estimate says nothing about the next stage's (carried over, the quick stress
    #: drive takes 785 step attempts instead of 304, bench/RESULTS.md)
    carries_contraction = False
    dense_wall = False

    def __init__(self, scene: BedScene, rule: YieldRule, mesh_unit: Mesh, *, tau_w=None, u_w=None):
        m = scene.material
        self.scene, self.rule = scene, rule
        self.y = mesh_unit.y * scene.depth
        self.h = np.diff(self.y)
        self.half_over_h = 0.5 / self.h
        self.p_face = scene.p_w + scene.weight_gradient * (self.y[:-1] + self.h / 2)
        self.law = ShearLaw(rule, m.friction, m.I0_paper, m.d, m.rho_p).on_faces(self.p_face)
        rho_b = m.phi * m.rho_p
        self.tau_w, self.u_w = tau_w, u_w
        self.imposed = "stress" if tau_w is not None else "speed"
        self.first = 0 if tau_w is not None else 1  # the first unknown node
        n = len(self.y) - 1
        node_mass = np.empty(n)
        node_mass[0] = rho_b * self.h[0] / 2
        node_mass[1:] = rho_b * (self.h[:-1] + self.h[1:]) / 2
        if u_w is not None:
            # the wall half-cell's mass moves with the bed, not the plate: an impulsive start leaves a velocity
            # jump at the wall (the stress is bounded by mu_d p), which the first face's stress, the u-average
            # of the stress over the first cell, sees at the wall; node 1's control volume then starts at the
            # wall.  Once the layer is resolved this is an O(h_0) truncation at one node, O(h_0^2) globally
            # (bench/RESULTS.md "Velocity form: speed at 1e-4")
            node_mass[1] += node_mass[0]
        # force per node (None: no body force)
        self.body = (scene.body_force / rho_b * node_mass)[self.first:] if scene.body_force else None
        node_mass[0] += scene.plate_mass
        self.mass = node_mass[self.first:]
        self._full = np.zeros(n + 1)  # u with u_N = 0 (and u_0 = u_w), reused by every evaluation
        if u_w is not None:
            self._full[0] = u_w
        self.u0 = np.zeros(n - self.first)  # a bed at rest (solve_velocity may set the state at yield)

    def initial(self) -> np.ndarray:
        return self.u0.copy()

    def nodes(self, x):
        """The velocity at every node 0..N of the unknowns x (the last axis)."""
        full = np.zeros((*np.shape(x)[:-1], len(self._full)))
        full[..., self.first:-1] = x
        if self.u_w is not None:
            full[..., 0] = self.u_w
        return full

    def shear(self, x):
        """Face shear rates g = 1/2 du/dy of the unknowns x (the last axis)."""
        if x.ndim > 1:
            return np.diff(self.nodes(x), axis=-1) * self.half_over_h
        full = self._full
        full[self.first:-1] = x
        return (full[1:] - full[:-1]) * self.half_over_h

    def stress(self, x):
        """sigma_xy at the faces (any leading axes)."""
        return self.law.stress(self.shear(x))

    def rate(self, x):
        s = self.stress(x)
        f = np.empty(len(x))
        np.subtract(s[1:], s[:-1], out=f[1 - self.first:])  # the interior nodes 1..N-1
        if self.first == 0:
            f[0] = self.tau_w + s[0]
        if self.body is not None:
            f += self.body
        return f

    def jacobian(self, x):
        k = self.law.slope(self.shear(x)) * self.half_over_h  # d s_j / d u_{j+1} = k_j, d s_j / d u_j = -k_j
        diag = -k[self.first:]
        diag[1 - self.first:] -= k[:-1]
        return Jacobian.dissipative_tridiagonal(diag, k[self.first:-1])

    def project(self, x):
        return x

    def step_fraction(self, x, dx):
        return 1.0


@dataclass(frozen=True, eq=False)
class VelocitySolution:
    """u at the nodes and sigma_xy at the faces at the requested times, the state after every accepted
    step (``step_t``, ``step_x``: the problem's unknowns), metadata.  Dimensional (the material's units);
    ``scales`` converts to the paper's variables."""

    scene: BedScene
    rule: YieldRule
    problem: VelocityProblem
    y: np.ndarray
    y_face: np.ndarray
    t: np.ndarray
    u: np.ndarray
    s: np.ndarray
    step_t: np.ndarray
    step_x: np.ndarray
    stats: StepStats
    scales: Scales

    @property
    def imposed(self) -> str:
        return self.problem.imposed

    @property
    def mu(self) -> np.ndarray:
        """|sigma_xy|/p at the faces."""
        return np.abs(self.s) / self.problem.p_face

    @property
    def u_w(self) -> np.ndarray:
        return self.u[:, 0]

    @property
    def mu_w(self) -> np.ndarray:
        """tau_w/p_w at the requested times: imposed, or the stress the bed exerts on the plate."""
        tau = -self.s[:, 0] if self.imposed == "speed" else np.full(len(self.t), self.problem.tau_w)
        return tau / self.scene.p_w

    @cached_property
    def series(self) -> pd.DataFrame:
        """Every accepted step: t, u_w, tau_w, mu_w, delta (layer thickness), yield_front (built on first use)."""
        problem, mu_s = self.problem, self.scene.material.mu_s
        s = problem.stress(self.step_x)
        mu = np.abs(s) / problem.p_face
        tau_plate = -s[:, 0] if self.imposed == "speed" else np.full(len(s), problem.tau_w)
        mu_wall = tau_plate / self.scene.p_w
        return pd.DataFrame({"t": self.step_t, "u_w": problem.nodes(self.step_x)[:, 0], "tau_w": tau_plate,
                             "mu_w": mu_wall,
                             "delta": _layer_thickness(mu, self.y_face, mu_s, np.maximum(mu_wall, mu[:, 0])),
                             "yield_front": _yield_front(mu, self.y_face, mu_s)})


def _yield_front(mu, y_face, mu_s):
    """Deepest face where mu >= mu_s (continuum.crossing, linear in mu - mu_s), per row of ``mu``."""
    return crossing_depth(y_face, mu, mu_s, first=False)


def _layer_thickness(mu, y_face, mu_s, mu_wall):
    """Depth where (mu - mu_s) falls to DELTA_THRESHOLD of (mu_wall - mu_s), linear (continuum.crossing);
    the bed bottom where it never does.  Per row of ``mu`` (``mu_wall`` one per row)."""
    d = crossing_depth(y_face, (mu - mu_s) / (mu_wall - mu_s)[:, None], DELTA_THRESHOLD)
    return np.where(np.isnan(d), y_face[-1], d)


#: bisections of the creep rate at yield: the bracket [0, hi] shrinks to 2^-64 hi (below rounding)
YIELD_BISECTIONS = 64


def initial_at_yield(problem: VelocityProblem) -> np.ndarray:
    """The paper's initial state tau = mu_s p (eq. (2.7)) as a velocity field: on each
    face the creep rate g < 0 with |s(g)| = mu_s p (exists for the regularised law: |s| rises
    from 0 to mu(I) p >= mu_s p), integrated up from u(H) = 0.  Tends to u = 0 as eps -> 0.
    All faces at once: |s| is increasing in |g|, bracketed from eps up by decades, then bisected."""
    p = problem.p_face
    excess = lambda a: -problem.law.stress(-a) - problem.scene.material.mu_s * p
    lo, hi = np.zeros_like(p), np.full_like(p, problem.rule.eps)
    while np.any(short := excess(hi) < 0):
        lo, hi = np.where(short, hi, lo), np.where(short, 10 * hi, hi)
    for _ in range(YIELD_BISECTIONS):
        mid = 0.5 * (lo + hi)
        up = excess(mid) < 0
        lo, hi = np.where(up, mid, lo), np.where(up, hi, mid)
    du = -2 * (0.5 * (lo + hi)) * problem.h
    return -np.cumsum(du[::-1])[::-1]


def solve_velocity(scene: BedScene, times, *, mu_w=None, u_w=None, rule: YieldRule = YieldRule(),
                   initial: str = "rest", numerics: Numerics = VELOCITY_NUMERICS,
                   compare_steady: bool = True, fixed_times=None) -> VelocitySolution:
    """Solve the velocity form with an imposed plate stress (mu_w = tau_w/p_w) or speed (u_w).

    ``initial``: "rest" (unsheared bed, u = 0, sigma_xy = 0) or "yield" (tau = mu_s p, the paper's
    state).  ``compare_steady`` requires H >= delta_s so the steady state is the paper's
    (eq. (2.10)); set it False to run a shallower bed.
    """
    m, fr = scene.material, scene.material.friction
    require((mu_w is None) != (u_w is None), "mu_w/u_w", "exactly one of them", (mu_w, u_w))
    require(initial in ("rest", "yield"), "initial", "'rest' or 'yield'", initial)
    if mu_w is not None:
        scales = Scales(m, scene.p_w, fr.check_mu_w(mu_w))
    else:
        require(finite(u_w) and u_w > 0, "u_w", "a finite number > 0", u_w)
        scales = Scales.for_speed(m, scene.p_w, u_w)
    if compare_steady:
        require(scene.depth >= scales.delta_s, "depth",
                f">= delta_s = {scales.delta_s:.6g} for a steady comparison (or compare_steady=False)", scene.depth)
    t = check_times(times)
    mesh = numerics.mesh()
    tau_w = None if mu_w is None else mu_w * scene.p_w
    problem = VelocityProblem(scene, rule, mesh, tau_w=tau_w, u_w=u_w)
    if initial == "yield":
        problem.u0 = initial_at_yield(problem)[problem.first:]
    y_face = problem.y[:-1] + problem.h / 2
    steps_t, steps_x = [], []

    def observe(time, x):
        steps_t.append(time)
        steps_x.append(x)

    states, stats = integrate(problem, t, method=numerics.method or VELOCITY_METHOD,
                              rtol=numerics.rtol or VELOCITY_NUMERICS.rtol,
                              atol=numerics.atol or VELOCITY_NUMERICS.atol,
                              h0=1e-9 * scales.t_s, fixed_times=fixed_times, observer=observe)
    return VelocitySolution(scene, rule, problem, problem.y, y_face, t, problem.nodes(states), problem.stress(states),
                            np.array(steps_t), np.array(steps_x), stats, scales)
