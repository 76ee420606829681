"""Velocity-form mu(I) solver for the DEM's own scene: a bed of finite depth H on a rough base,
a plate with mass, any initial state (paper eqs. (2.5)-(2.6) without the stress-diffusion rewrite).

    phi rho_p du/dt = d sigma_xy/dy + b   on 0 < y < H (y downward from the plate),   u(H) = 0,
    sigma_xy = s(g, p) from a YieldRule (continuum.rules), g = 1/2 du/dy, p = p_w + phi rho_p g y,
    plate:  imposed speed u(0) = u_w(t),  or imposed stress  (m_p + phi rho_p h_0/2) du_w/dt = tau_w(t) + sigma_xy(0+),

the wall's value at time t the load's (continuum.load.Load.wall: held, or a sine).  Finite volumes: velocities at
the nodes of a Mesh scaled to [0, H], stresses at the faces; the Jacobian is tridiagonal and the system goes through
the method registry (continuum.integrators; TR-BDF2 by default).
Dimensional: the material's units (DEM units d = rho_p = g = 1 by default).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pandas as pd

from .crossing import crossing_depth
from .integrators import integrate
from .jacobian import Jacobian
from .load import Load
from .mesh import Mesh
from .rheology import require
from .rules import ShearLaw, YieldRule
from .scales import Material, Scales, pressure
from .scene import BedScene, SceneNumerics
from .solver import check_times
from .steady import DELTA_THRESHOLD
from .stepper import FIRST_STEP, StepStats

#: the velocity form's defaults: a milder wall grading than the paper's (no singular wall layer),
#: tolerances for dimensional velocities of O(1-10) in DEM units, and TR-BDF2 (2 implicit stages a step to
#: SDIRK4's 5).  bench/velocity_form.py: 400 cells at stretch 4 put the quick stress drive within 1e-4
#: (200 cells at stretch 2 with SDIRK4: 2-4e-4); atol 1e-8 instead of 1e-9 stops resolving
#: to 1e-5 relative the creep (|g| ~ eps) that runs ahead of the yield front through the whole bed in the
#: first ~0.01 time units (0.7x the steps, errors equal to 2 digits; 1e-7 and 1e-6 raise delta_u's error)
VELOCITY_NUMERICS = SceneNumerics(n_cells=400, stretch=4.0, rtol=1e-5, atol=1e-8, method="tr-bdf2")


#: the initial states of the velocity form: a bed at rest (the DEM's), or at yield (the paper's, eq. (2.7))
STARTS = ("rest", "yield")


class VelocityProblem:
    """M u' = F(u, t) for the nodal velocities u_0..u_{N-1} (u_N = 0 at the base) of an imposed stress, or
    u_1..u_{N-1} of an imposed speed (u_0 = u_w(t) is then a boundary value, not an unknown), the wall's value at
    time t from the load.  The Jacobian is symmetric tridiagonal with -J a weighted Laplacian (ds/dg > 0): M - dh J
    is positive definite.  ``law``: a face law (stress(g), slope(g) on the faces, as rules.FaceLaw) in place of the
    rule's mu(I), e.g. continuum.oscillation.Newtonian."""

    #: the simplified Newton contracts unevenly as faces cross the regularised law's kink |g| ~ eps, so a
    #: stage's contraction estimate says nothing about the next stage's (carried over, the quick stress
    #: drive takes 785 step attempts instead of 304, bench/RESULTS.md)
    carries_contraction = False
    dense_wall = False

    def __init__(self, material: Material, scene: BedScene, load: Load, mesh_unit: Mesh, *,
                 rule: YieldRule = YieldRule(), law=None, start: str = "rest"):
        require(start in STARTS, "initial", f"one of {STARTS}", start)
        self.material, self.scene, self.load, self.rule, self.start = material, scene, load, rule, start
        self.y = mesh_unit.y * scene.depth
        self.h = np.diff(self.y)
        self.half_over_h = 0.5 / self.h
        self.p_face = pressure(material, load.p_w, self.y[:-1] + self.h / 2)
        self.law = law if law is not None else ShearLaw(rule, material.friction, material.I0_paper, material.d,
                                                        material.rho_p).on_faces(self.p_face)
        rho_b = material.phi * material.rho_p
        self.imposed = load.kind
        self.first = 0 if load.kind == "stress" else 1  # the first unknown node
        n = len(self.y) - 1
        node_mass = np.empty(n)
        node_mass[0] = rho_b * self.h[0] / 2
        node_mass[1:] = rho_b * (self.h[:-1] + self.h[1:]) / 2
        if load.kind == "speed":
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
        self._full = np.zeros(n + 1)  # u with u_N = 0 (and u_0 = u_w(t)), the workspace of every evaluation

    def initial(self) -> np.ndarray:
        """The bed at rest (u = 0, sigma_xy = 0), or at yield (tau = mu_s p: ``initial_at_yield``)."""
        if self.start == "yield":
            return initial_at_yield(self)[self.first:]
        return np.zeros(len(self.mass))

    def nodes(self, x, t):
        """The velocity at every node 0..N of the unknowns x (the last axis) at the time(s) t (one per row of x)."""
        full = np.zeros((*np.shape(x)[:-1], len(self._full)))
        full[..., self.first:-1] = x
        if self.load.kind == "speed":
            full[..., 0] = self.load.wall(t)
        return full

    def shear(self, x, t):
        """Face shear rates g = 1/2 du/dy of the unknowns x (the last axis) at the time(s) t."""
        if x.ndim > 1:
            return np.diff(self.nodes(x, t), axis=-1) * self.half_over_h
        full = self._full
        full[self.first:-1] = x
        if self.load.kind == "speed":
            full[0] = self.load.wall(t)
        return (full[1:] - full[:-1]) * self.half_over_h

    def stress(self, x, t):
        """sigma_xy at the faces (any leading axes) at the time(s) t."""
        return self.law.stress(self.shear(x, t))

    def rate(self, x, t):
        s = self.stress(x, t)
        f = np.empty(len(x))
        np.subtract(s[1:], s[:-1], out=f[1 - self.first:])  # the interior nodes 1..N-1
        if self.first == 0:
            f[0] = self.load.wall(t) + s[0]
        if self.body is not None:
            f += self.body
        return f

    def jacobian(self, x, t):
        k = self.law.slope(self.shear(x, t)) * self.half_over_h  # d s_j / d u_{j+1} = k_j, d s_j / d u_j = -k_j
        diag = -k[self.first:]
        diag[1 - self.first:] -= k[:-1]
        return Jacobian.dissipative_tridiagonal(diag, k[self.first:-1])

    def project(self, x):
        return x

    def step_fraction(self, x, dx):
        return 1.0


class PlateReadings:
    """What a scene solution with u at the nodes (``u``: one row per time ``t``) and sigma_xy at the faces (``s``) of
    its ``problem`` (``p_face``, ``load``) reads off the plate and the bed."""

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
        return self.problem.load.plate_friction(self.t, self.s[:, 0])


@dataclass(frozen=True, eq=False)
class VelocitySolution(PlateReadings):
    """u at the nodes and sigma_xy at the faces at the requested times, the state after every accepted
    step (``step_t``, ``step_x``: the problem's unknowns), metadata.  Dimensional (the material's units);
    ``scales`` converts to the paper's variables."""

    material: Material
    scene: BedScene
    load: Load
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

    @cached_property
    def series(self) -> pd.DataFrame:
        """Every accepted step: t, u_w, tau_w, mu_w, delta (layer thickness), yield_front (built on first use)."""
        problem, mu_s = self.problem, self.material.mu_s
        s = problem.stress(self.step_x, self.step_t)
        mu = np.abs(s) / problem.p_face
        mu_wall = self.load.plate_friction(self.step_t, s[:, 0])
        return pd.DataFrame({"t": self.step_t, "u_w": problem.nodes(self.step_x, self.step_t)[:, 0],
                             "tau_w": mu_wall * self.load.p_w,
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
    excess = lambda a: -problem.law.stress(-a) - problem.material.mu_s * p
    lo, hi = np.zeros_like(p), np.full_like(p, problem.rule.eps)
    while np.any(short := excess(hi) < 0):
        lo, hi = np.where(short, hi, lo), np.where(short, 10 * hi, hi)
    for _ in range(YIELD_BISECTIONS):
        mid = 0.5 * (lo + hi)
        up = excess(mid) < 0
        lo, hi = np.where(up, mid, lo), np.where(up, hi, mid)
    du = -2 * (0.5 * (lo + hi)) * problem.h
    return -np.cumsum(du[::-1])[::-1]


def solve_velocity(material: Material, scene: BedScene, load: Load, times, *, rule: YieldRule = YieldRule(),
                   initial: str = "rest", numerics: SceneNumerics = VELOCITY_NUMERICS,
                   compare_steady: bool = True, fixed_times=None) -> VelocitySolution:
    """Solve the velocity form under a held load (Stokes' first problem): an imposed plate stress
    (tau_w = mu_w p_w) or speed (u_w); an oscillating load is continuum.oscillation's.

    ``initial``: "rest" (unsheared bed, u = 0, sigma_xy = 0) or "yield" (tau = mu_s p, the paper's
    state).  ``compare_steady`` requires H >= delta_s so the steady state is the paper's
    (eq. (2.10)); set it False to run a shallower bed.
    """
    require(not load.oscillating, "load", "a held load (omega = 0; an oscillating one: continuum.oscillation)", load)
    if load.kind == "stress":
        scales = Scales(material, load.p_w, material.friction.check_mu_w(load.mu_w))
    else:
        scales = Scales.for_speed(material, load.p_w, load.u_w)
    if compare_steady:
        require(scene.depth >= scales.delta_s, "depth",
                f">= delta_s = {scales.delta_s:.6g} for a steady comparison (or compare_steady=False)", scene.depth)
    t = check_times(times)
    problem = VelocityProblem(material, scene, load, numerics.mesh(), rule=rule, start=initial)
    y_face = problem.y[:-1] + problem.h / 2
    steps_t, steps_x = [], []

    def observe(time, x):
        steps_t.append(time)
        steps_x.append(x)

    states, stats = integrate(problem, t, method=numerics.method, rtol=numerics.rtol, atol=numerics.atol,
                              h0=FIRST_STEP * scales.t_s, fixed_times=fixed_times, observer=observe)
    return VelocitySolution(material, scene, load, rule, problem, problem.y, y_face, t, problem.nodes(states, t),
                            problem.stress(states, t), np.array(steps_t), np.array(steps_x), stats, scales)
