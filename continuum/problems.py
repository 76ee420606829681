"""The paper's shear-stress diffusion problem (the evolution rate), apart from the numerics.

Unknowns x are tau~ at nodes 0..N-1 of a Mesh; tau~(y~=1) = 1 is fixed.  The mesh's d2/dy~2 and
quadrature are of ``order`` 2 (three-point, trapezoid) or 4 (continuum.mesh).  Written as
M x' = F(x) for continuum.stepper: the interior rows are eq. GranularStokesEqn,

    d tau~/d t~ = D(y~, tau~) d2 tau~/dy~2,   D = (mu_d p~ - mu_w tau~)^2 / p~^(3/2),  p~ = 1 + beta_w y~,

and row 0 is algebraic (mass 0): tau~(0) = 1 for an imposed stress, or the integral condition
eq. GranularStokesEqn_muBIS_BCs for an imposed speed.  With an imposed speed, mu_w is the steady
mu_w^inf and tau~ = mu p~/mu_w^inf; the interior equation is then exactly
eq. GranularStokesEqn_muBIS written for tau~ instead of mu~ (same scaling, same steady state).
"""
from __future__ import annotations

import numpy as np

from .mesh import Mesh
from .rheology import Friction, finite, require
from .steady import mu_w_for_speed
from .stepper import Jacobian


class ShearStressDiffusion:
    """Interior rate of eq. GranularStokesEqn and its banded Jacobian; row 0 is the wall."""

    imposed: str
    dense_wall: bool

    def __init__(self, friction: Friction, mu_w: float, mesh: Mesh, order: int = 4):
        self.friction = friction
        self.mu_w = friction.check_mu_w(mu_w)
        self.beta = friction.beta(self.mu_w)
        self.mesh, self.order = mesh, order
        self.p = 1.0 + self.beta * mesh.y
        self._p32 = self.p[1:-1] ** 1.5
        self.mass = np.ones(mesh.n_cells)
        self.mass[0] = 0.0
        self.lap = mesh.second_derivative(order)
        # band positions of the Laplacian's entries on the unknowns (node N is fixed)
        n = mesh.n_cells
        rows = np.broadcast_to(np.arange(1, n)[:, None], self.lap.cols.shape)
        self._on_unknowns = self.lap.cols < n
        self.kl = self.ku = int(np.max(np.abs(self.lap.cols - rows)))
        self._band_at = (self.ku + rows - self.lap.cols)[self._on_unknowns], self.lap.cols[self._on_unknowns]

    def initial(self) -> np.ndarray:
        """tau~(y~, 0) = mu_s p~/mu_w at nodes 0..N-1 (eq. InitStokesEqn)."""
        return self.friction.mu_s * self.p[:-1] / self.mu_w

    def full(self, x: np.ndarray) -> np.ndarray:
        """tau~ at all nodes 0..N."""
        return np.append(x, 1.0)

    def _terms(self, x: np.ndarray):
        tau = self.full(x)
        lap = self.lap.matrix @ tau
        s = self.friction.mu_d * self.p[1:-1] - self.mu_w * tau[1:-1]
        return lap, s, s * s / self._p32

    def rate(self, x: np.ndarray) -> np.ndarray:
        """F(x): the wall residual in row 0, d tau~/d t~ at the interior nodes."""
        lap, _, diff = self._terms(x)
        return np.concatenate(([self.wall_residual(x)], diff * lap))

    def jacobian(self, x: np.ndarray) -> Jacobian:
        """dF/dx: the Laplacian's band times the diffusivity, its derivative on the diagonal; row 0
        is the wall (dense for the imposed speed)."""
        lap, s, diff = self._terms(x)
        bands = np.zeros((self.kl + self.ku + 1, len(x)))
        bands[self._band_at] = (diff[:, None] * self.lap.weights)[self._on_unknowns]
        bands[self.ku, 1:] -= 2 * self.mu_w * s / self._p32 * lap
        row0 = self.wall_gradient(x)
        j = np.arange(min(self.ku + 1, len(x)))
        bands[self.ku - j, j] = row0[j]
        return Jacobian(bands, self.kl, self.ku, row0 if self.dense_wall else None)

    def mu(self, x: np.ndarray) -> np.ndarray:
        """Local friction mu = mu_w tau~/p~ at all nodes."""
        return self.mu_w * self.full(x) / self.p


class ImposedStress(ShearStressDiffusion):
    """Imposed wall shear stress tau_w = mu_w p_w: tau~(0, t~) = 1."""

    imposed = "stress"
    dense_wall = False

    def wall_residual(self, x: np.ndarray) -> float:
        return x[0] - 1.0

    def wall_gradient(self, x: np.ndarray) -> np.ndarray:
        g = np.zeros(len(x))
        g[0] = 1.0
        return g

    def project(self, x: np.ndarray) -> np.ndarray:
        """Satisfy the wall row exactly."""
        x[0] = 1.0
        return x

    def step_fraction(self, x: np.ndarray, dx: np.ndarray) -> float:
        """Largest fraction of a Newton update to take (1: no limit)."""
        return 1.0


class ImposedSpeed(ShearStressDiffusion):
    """Imposed wall speed u~_w: the wall stress is the extra unknown fixed by
    eq. GranularStokesEqn_muBIS_BCs, u~_w = int_0^1 sqrt(p~)/Dmu (1/mu~ - 1) dy~, with the first cell
    by the trapezoidal rule and the others by the mesh's rule of the problem's order on nodes 1..N
    (the quadrature that gives the velocity profile, so the constraint holds to round-off).

    The wall unknown is v = 1/mu~(0) (the wall shear rate, up to a factor), in which the
    constraint is linear: it is solved exactly after each Newton solve.

    Singular start: the initial state mu~ = 1 carries no velocity, so at t~ = 0+ the whole jump
    u~_w sits in a wall sub-layer where mu~ -> 0 (mu -> mu_d).  In the continuum that sub-layer is
    exponentially thin for t~ << t_mud ~ u~_w^2 (the velocity form du/dt ~ d/dy(-1/u_y) is a heat
    equation for y(u) in the hodograph plane); on the mesh it is carried by the first cell, where
    the constraint gives mu~_w ~ h_0/(2 Dmu u~_w), i.e. mu_w = mu_d - O(h_0): the wall friction is
    as close to mu_d as the mesh can show (first order in h_0 until t~ ~ t_mud).  Newton updates are
    limited to keep mu~ > 0.
    """

    imposed = "speed"
    dense_wall = True

    def __init__(self, friction: Friction, u_w: float, mesh: Mesh, order: int = 4):
        require(finite(u_w) and u_w > 0, "u_w", "a finite number > 0", u_w)
        self.u_w = float(u_w)
        super().__init__(friction, mu_w_for_speed(friction, u_w), mesh, order)
        q = mesh.quadrature_from_node1(order).copy()
        q[:2] += mesh.h[0] / 2
        self._wq = q[:-1] * np.sqrt(self.p[:-1]) / friction.dmu

    def initial(self) -> np.ndarray:
        x = super().initial()
        x[0] = 1.0  # v = 1/mu~ = 1: mu = mu_s at the wall
        return x

    def full(self, x: np.ndarray) -> np.ndarray:
        fr = self.friction
        tau0 = (fr.mu_d - fr.dmu / x[0]) * self.p[0] / self.mu_w
        return np.concatenate(([tau0], x[1:], [1.0]))

    def jacobian(self, x: np.ndarray) -> Jacobian:
        jac = super().jacobian(x)
        k = np.arange(1, min(self.kl, len(x) - 1) + 1)
        jac.bands[self.ku + k, 0] *= self.friction.dmu * self.p[0] / (self.mu_w * x[0] ** 2)  # d tau~_0 / d v
        return jac

    def mu_tilde(self, x: np.ndarray) -> np.ndarray:
        """mu~ at nodes 0..N-1."""
        mt = (self.friction.mu_d - self.mu_w * x / self.p[:-1]) / self.friction.dmu
        mt[0] = 1.0 / x[0]
        return mt

    def wall_residual(self, x: np.ndarray) -> float:
        mt = self.mu_tilde(x)
        return self._wq[0] * (x[0] - 1.0) + self._wq[1:] @ (1.0 / mt[1:] - 1.0) - self.u_w

    def wall_gradient(self, x: np.ndarray) -> np.ndarray:
        grad = self._wq / self.mu_tilde(x) ** 2 * self.mu_w / (self.p[:-1] * self.friction.dmu)
        grad[0] = self._wq[0]
        return grad

    def project(self, x: np.ndarray) -> np.ndarray:
        """Satisfy the constraint exactly: it is linear in v = x[0]."""
        x[0] -= self.wall_residual(x) / self._wq[0]
        return x

    def step_fraction(self, x: np.ndarray, dx: np.ndarray) -> float:
        """At most halve mu~ at an interior node, or v at the wall, in one Newton update."""
        mt = self.mu_tilde(x)[1:]
        dmt = -self.mu_w / (self.p[1:-1] * self.friction.dmu) * dx[1:]
        limits = [1.0]
        if dx[0] < 0:
            limits.append(-0.5 * x[0] / dx[0])
        falling = dmt < 0
        if falling.any():
            limits.append(np.min(-0.5 * mt[falling] / dmt[falling]))
        return float(min(limits))
