"""The paper's shear-stress diffusion problem (the evolution rate), apart from the numerics.

Unknowns x are tau~ at nodes 0..N-1 of a Mesh; tau~(y~=1) = 1 is fixed.  The mesh's d2/dy~2 and
quadrature are of ``order`` 2 (three-point, trapezoid) or 4 (continuum.mesh).  Written as
M x' = F(x, t) for the integrators (continuum.integrators; F does not depend on t here: the wall is held), the
interior rows eq. (2.15),

    d tau~/d t~ = D(y~, tau~) d2 tau~/dy~2,   D = (mu_d p~ - mu_w tau~)^2 / p~^(3/2),  p~ = 1 + beta_w y~,

and row 0 is algebraic (mass 0): tau~(0) = 1 for an imposed stress, or the integral condition
eq. (3.15) for an imposed speed.  With an imposed speed, mu_w is the steady
mu_w^inf and tau~ = mu p~/mu_w^inf; the interior equation is then exactly
eq. (3.14) written for tau~ instead of mu~ (same scaling, same steady state).
"""
from __future__ import annotations

import math

import numpy as np

from .jacobian import Jacobian
from .kernels import BdfKernels, DirkKernels, band_lu, band_solve, jitable, laplacians
from .mesh import Mesh
from .rheology import Friction, finite, require
from .steady import mu_w_for_speed


class ShearStressDiffusion:
    """Interior rate of eq. (2.15) and its banded Jacobian; row 0 is the wall."""

    imposed: str
    dense_wall: bool
    #: the stepper may judge a stage's first Newton iterate by the previous stage's contraction (stepper.dirk_step)
    carries_contraction = True

    def __init__(self, friction: Friction, mu_w: float, mesh: Mesh, order: int = 4):
        self.friction = friction
        self.mu_w = friction.check_mu_w(mu_w)
        self.beta = friction.beta(self.mu_w)
        self.mesh, self.order = mesh, order
        self.p = 1.0 + self.beta * mesh.y
        self._p32 = self.p[1:-1] ** 1.5
        self._mud_p = friction.mu_d * self.p[1:-1]
        self.mass = np.ones(mesh.n_cells)
        self.mass[0] = 0.0
        self.lap = mesh.second_derivative(order)
        # the Laplacian on the unknowns and its column on the fixed node tau~_N = 1
        lap, dense = self.lap.matrix, isinstance(self.lap.matrix, np.ndarray)
        self._lap_x = lap[:, :-1].copy() if dense else lap[:, :-1]
        self._lap_fixed = lap[:, -1].copy() if dense else lap[:, [-1]].toarray().ravel()
        # band positions of the Laplacian's entries on the unknowns (node N is fixed)
        n = mesh.n_cells
        rows = np.broadcast_to(np.arange(1, n)[:, None], self.lap.cols.shape)
        on_unknowns = self.lap.cols < n
        self.kl = self.ku = int(np.max(np.abs(self.lap.cols - rows)))
        self._band_at = np.ravel_multi_index(((self.ku + rows - self.lap.cols)[on_unknowns],
                                              self.lap.cols[on_unknowns]), (self.kl + self.ku + 1, n))
        self._band_row, self._band_weights = np.nonzero(on_unknowns)[0], self.lap.weights[on_unknowns]
        wall = np.arange(min(self.ku + 1, n))
        self._wall_at = self.ku - wall, wall

    def initial(self) -> np.ndarray:
        """tau~(y~, 0) = mu_s p~/mu_w at nodes 0..N-1 (eq. (2.7))."""
        return self.friction.mu_s * self.p[:-1] / self.mu_w

    def full(self, x: np.ndarray) -> np.ndarray:
        """tau~ at all nodes 0..N."""
        return np.append(x, 1.0)

    def nodal(self, x: np.ndarray) -> np.ndarray:
        """tau~ at nodes 0..N-1 (the unknowns themselves here)."""
        return x

    def _terms(self, x: np.ndarray):
        tau = self.nodal(x)
        lap = self._lap_x.dot(tau)
        lap += self._lap_fixed
        s = self._mud_p - self.mu_w * tau[1:]
        return lap, s, s * s / self._p32

    def rate(self, x: np.ndarray, t: float) -> np.ndarray:
        """F(x, t): the wall residual in row 0, d tau~/d t~ at the interior nodes (eq. (2.15); t does not enter)."""
        lap, _, diff = self._terms(x)
        out = np.empty(len(x))
        out[0] = self.wall_residual(x)
        np.multiply(diff, lap, out=out[1:])
        return out

    def interior_rate(self, x: np.ndarray, t: float) -> np.ndarray:
        """F(x, t) without row 0: d tau~/d t~ at the interior nodes (the rows bdf integrates, stepper)."""
        lap, _, diff = self._terms(x)
        return diff * lap

    def jacobian(self, x: np.ndarray, t: float) -> Jacobian:
        """dF/dx at time t: the Laplacian's band times the diffusivity, its derivative on the diagonal; row 0
        is the wall (dense for the imposed speed)."""
        lap, s, diff = self._terms(x)
        bands = np.zeros((self.kl + self.ku + 1, len(x)))
        bands.reshape(-1)[self._band_at] = diff[self._band_row] * self._band_weights
        bands[self.ku, 1:] -= 2 * self.mu_w * s / self._p32 * lap
        row0 = self.wall_gradient(x)
        bands[self._wall_at] = row0[self._wall_at[1]]
        return Jacobian(bands, self.kl, self.ku, row0 if self.dense_wall else None)

    def stencil(self) -> tuple:
        """The interior rate's data as the compiled kernels take it: the Laplacian's columns and weights per
        interior node (contiguous), mu_d p~ and p~^(3/2) at the interior nodes, and mu_w."""
        return (np.ascontiguousarray(self.lap.cols), np.ascontiguousarray(self.lap.weights), self._mud_p, self._p32,
                self.mu_w)

    def mu(self, x: np.ndarray) -> np.ndarray:
        """Local friction mu = mu_w tau~/p~ at all nodes."""
        return self.mu_w * self.full(x) / self.p


class ImposedStress(ShearStressDiffusion):
    """Imposed wall shear stress tau_w = mu_w p_w: tau~(0, t~) = 1."""

    imposed = "stress"
    dense_wall = False

    def dirk_kernels(self):
        """The DIRK loop's kernels of this problem (continuum.kernels.DirkKernels), their data, and a factory of the
        Newton matrix's factors (a band LU's storage, columns contiguous)."""
        n = self.mesh.n_cells
        cols, weights, mud_p, p32, mu_w = self.stencil()
        data = (cols, weights, mud_p, p32, float(mu_w), self.kl, self.ku, np.empty(n + 1), np.empty(n - 1))

        def factors():
            return (np.empty((n, 2 * self.kl + self.ku + 1)).T, np.zeros(n, dtype=np.int64),
                    np.zeros(1, dtype=np.int64))

        return DirkKernels(stress_rate, stress_factor, no_refresh, band_factors_solve, stress_project, whole_update), \
            data, factors

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
    eq. (3.15), u~_w = int_0^1 sqrt(p~)/Dmu (1/mu~ - 1) dy~: the first cell by
    product integration, exact for mu~ linear in the cell (``first_cell``), the others by the mesh's
    rule of the problem's order on nodes 1..N (the quadrature that gives the velocity profile, so the
    constraint holds to round-off).

    The wall unknown is q = ln(1/mu~(0)).  Singular start: the initial state mu~ = 1 carries no
    velocity, so at t~ = 0+ the whole jump u~_w sits in a wall sub-layer where mu~ -> 0 (mu -> mu_d).
    With mu~ = a + (b - a) y/h_0 in the first cell, its share of u~_w is h_0 ln(b/a)/(b - a): the
    constraint then gives a ~ b exp(-b u~_w Dmu/h_0), exponentially small for t~ << t_mud ~ u~_w^2
    (the sub-layer of the continuum), and q stays of moderate size where mu~_w itself underflows.
    ``project`` solves the constraint for q (Newton: it is increasing in q) after every stage.
    """

    imposed = "speed"
    dense_wall = True

    def __init__(self, friction: Friction, u_w: float, mesh: Mesh, order: int = 4):
        require(finite(u_w) and u_w > 0, "u_w", "a finite number > 0", u_w)
        self.u_w = float(u_w)
        super().__init__(friction, mu_w_for_speed(friction, u_w), mesh, order)
        self._wq = mesh.quadrature_from_node1(order)[:-1] * np.sqrt(self.p[:-1]) / friction.dmu
        self._w_first = mesh.h[0] * np.sqrt(1.0 + self.beta * mesh.h[0] / 2) / friction.dmu
        self.lift_off_end = LIFT_OFF_SPAN * self.u_w**2
        #: the Laplacian's weights on the wall node, rows 1..kl
        lap = self.lap.matrix
        self._lap_wall = (lap[:self.kl, 0].copy() if isinstance(lap, np.ndarray)
                          else lap[:self.kl, [0]].toarray().ravel())

    def initial(self) -> np.ndarray:
        x = super().initial()
        x[0] = 0.0  # q = ln(1/mu~) = 0: mu = mu_s at the wall
        return x

    def _tau0(self, q: float) -> float:
        fr = self.friction
        return (fr.mu_d - fr.dmu * np.exp(-q)) * self.p[0] / self.mu_w

    def full(self, x: np.ndarray) -> np.ndarray:
        return np.concatenate(([self._tau0(x[0])], x[1:], [1.0]))

    def nodal(self, x: np.ndarray) -> np.ndarray:
        tau = x.copy()
        tau[0] = self._tau0(x[0])
        return tau

    def jacobian(self, x: np.ndarray, t: float) -> Jacobian:
        jac = super().jacobian(x, t)
        k = np.arange(1, min(self.kl, len(x) - 1) + 1)
        jac.bands[self.ku + k, 0] *= self._dtau0_dq(x[0])
        return jac

    def _dtau0_dq(self, q: float) -> float:
        """d tau~_0/d q (tau~_0 = (mu_d - Dmu e^-q) p~_0/mu_w)."""
        return self.friction.dmu * math.exp(min(-q, EXP_MAX)) * self.p[0] / self.mu_w

    def wall_jacobian(self, x: np.ndarray, t: float):
        """dF/dx's row 0 (wall_gradient) and column 0 at rows 1..kl (the first nodes' coupling to q), the parts
        of the Jacobian the wall unknown's curvature changes fastest (refreshed at every Newton iterate by BDF)."""
        k = len(self._lap_wall)
        s = self._mud_p[:k] - self.mu_w * x[1:k + 1]
        return self.wall_gradient(x), s * s / self._p32[:k] * self._lap_wall * self._dtau0_dq(x[0])

    def mu_tilde(self, x: np.ndarray) -> np.ndarray:
        """mu~ at nodes 0..N-1."""
        mt = (self.friction.mu_d - self.mu_w * x / self.p[:-1]) / self.friction.dmu
        mt[0] = np.exp(-x[0])
        return mt

    def _interior(self, x: np.ndarray):
        """mu_d - mu at nodes 1..N-1 (> 0 where admissible), mu~ at node 1, and the quadrature over nodes 1..N-1
        of 1/mu~ - 1 taken as (mu - mu_s)/(mu_d - mu): no cancellation where mu ~ mu_s, whose round-off
        (eps/Dmu), times the weights sqrt(p~) of a deep bed, can swamp a small u~_w (a calibration with mu_s ~ 0
        and beta_w ~ 1e9: noise of 1e-2 u~_w)."""
        mu = self.mu_w * x[1:] / self.p[1:-1]
        gap = self.friction.mu_d - mu
        return gap, gap[0] / self.friction.dmu, self._wq[1:].dot((mu - self.friction.mu_s) / gap)

    def wall_terms(self) -> tuple:
        """The integral condition's data as the compiled kernels take it: the Laplacian's column on the wall unknown
        (rows 1..kl), p~ at the nodes, the quadrature weights of nodes 0..N-1 (times sqrt(p~)/Dmu), u~_w and the
        first cell's weight."""
        return self._lap_wall, self.p, self._wq, self.u_w, self._w_first

    def bdf_kernels(self):
        """The BDF loop's kernels of this problem (continuum.kernels.BdfKernels), their data, and the number of rows of
        the wall's column."""
        fr, n = self.friction, self.mesh.n_cells
        cols, weights, mud_p, p32, mu_w = self.stencil()
        data = (cols, weights, self._lap_wall, mud_p, p32, self.p, self._wq, self.u_w, self._w_first, float(mu_w),
                fr.mu_d, fr.mu_s, fr.dmu, self.kl, self.ku, np.empty(n + 1), np.empty(n - 1))
        return BdfKernels(speed_project, speed_rate, speed_jacobian, speed_wall), data, len(self._lap_wall)

    def wall_residual(self, x: np.ndarray) -> float:
        _, b, integral = self._interior(x)
        return self._w_first * (first_cell(x[0], b)[0] - 1.0) + integral - self.u_w

    def wall_gradient(self, x: np.ndarray) -> np.ndarray:
        mt = self.mu_tilde(x)
        dmt_dx = -self.mu_w / (self.p[:-1] * self.friction.dmu)
        _, dq, db = first_cell(x[0], mt[1])
        grad = np.empty(len(x))
        grad[1:] = -self._wq[1:] / mt[1:] ** 2 * dmt_dx[1:]
        grad[0] = self._w_first * dq
        grad[1] += self._w_first * db * dmt_dx[1]
        return grad

    def project(self, x: np.ndarray) -> np.ndarray:
        """Satisfy the constraint exactly: solve L(q) = target for q (L increases with q) by Newton
        kept inside the bracket of the iterates so far (bisection when it leaves it); NaN where the
        interior is inadmissible (mu~ <= 0 at a node) or Newton fails."""
        gap, b, integral = self._interior(x)
        target = (self.u_w + self._w_first - integral) / self._w_first
        if not (gap.min() > 0 and target > 0):
            x[0] = np.nan
            return x
        x[0] = wall_unknown(target, b)
        return x

    def step_fraction(self, x: np.ndarray, dx: np.ndarray) -> float:
        """At most halve mu~ at an interior node in one Newton update (q is unbounded)."""
        mt = self.mu_tilde(x)[1:]
        dmt = -self.mu_w / (self.p[1:-1] * self.friction.dmu) * dx[1:]
        falling = dmt < 0
        return float(min(1.0, np.min(-0.5 * mt[falling] / dmt[falling]))) if falling.any() else 1.0


@jitable
def first_cell(q: float, b: float):
    """L = int_0^1 ds/(a + (b - a) s) = ln(b/a)/(b - a) with a = exp(-q), and dL/dq, dL/db (plain math: a
    compiled loop compiles it, continuum.kernels)."""
    if not b > 0:  # an inadmissible Newton iterate
        return math.nan, math.nan, math.nan
    a = math.exp(min(-q, EXP_MAX))  # scalars by math: this runs a few times per rate evaluation
    d = b - a
    r = d / (b + a)
    if abs(r) < SERIES_BELOW:  # atanh(r)/r and the derivatives' limits, to O(r^4)
        lam = 2.0 / (a + b) * (1.0 + r * r / 3.0)
        return lam, 1.0 / (2 * a) - d / (3 * a * a), -1.0 / (2 * a * a) + 2 * d / (3 * a**3)
    # ln(b/a) = 2 atanh(r) has no cancellation for a ~ b; ln b + q none for a << b
    lam = 2 * math.atanh(r) / d if abs(r) < ATANH_BELOW else (math.log(b) + q) / d
    return lam, (1.0 - a * lam) / d, (1.0 / b - lam) / d


@jitable
def wall_unknown(target: float, b: float) -> float:
    """The q with L(q) = target (``first_cell``; L increases with q) by Newton kept inside the bracket of the
    iterates so far (bisection when it leaves it); NaN if it fails (plain math: a compiled loop
    compiles it, continuum.kernels)."""
    q = max(target * b - math.log(b), math.log(target))  # L's limits for a << b and a >> b
    lo, hi = -math.inf, math.inf
    for _ in range(PROJECTION_ITERATIONS):
        lam, dq, _ = first_cell(q, b)
        if lam > target:
            hi = q
        else:
            lo = q
        new = q - (lam - target) / dq
        if not lo < new < hi:
            away = (int(target > lam) - int(target < lam)) * max(1.0, abs(q))  # unbracketed: step out
            new = 0.5 * (lo + hi) if math.isfinite(lo + hi) else q + away
        if abs(new - q) <= PROJECTION_TOL * max(1.0, abs(q)):
            return new
        q = new
    return math.nan


#: ImposedSpeed's exp(-q) is capped here (math.exp raises OverflowError above it, where numpy's exp gives inf)
EXP_MAX = 709.0
#: first_cell switches to its series below this |b - a|/(b + a)
SERIES_BELOW = 1e-4
#: ... and to the atanh form of ln(b/a) below this |r| (the plain logarithms above it)
ATANH_BELOW = 0.5
#: the projection's Newton on q: most iterations, relative step tolerance
PROJECTION_ITERATIONS, PROJECTION_TOL = 100, 1e-13
#: the lift-off of mu_w from mu_d is over by this many t_mud = u~_w^2 (continuum.closed_forms)
LIFT_OFF_SPAN = 10.0


# --- the imposed stress's kernels (continuum.kernels): data = (cols, weights, mud_p, p32, mu_w, kl, ku, tau, lap),
# tau and lap workspaces of N + 1 and N - 1 values

@jitable
def stress_rate(x, t, f, data):
    """ImposedStress.rate: the wall row x_0 - 1, then D(tau~) d2 tau~/dy~2 at nodes 1..N-1."""
    cols, weights, mud_p, p32, mu_w, tau, lap = data[0], data[1], data[2], data[3], data[4], data[7], data[8]
    laplacians(x, x[0], tau, lap, cols, weights)
    f[0] = x[0] - 1.0
    for i in range(len(lap)):
        s = mud_p[i] - mu_w * x[i + 1]
        f[i + 1] = s * s / p32[i] * lap[i]


@jitable
def stress_factor(x, t, dh, lu, data):
    """LU of M - dh J(x, t) into lu = (ab, piv, [U's upper bandwidth]) (ImposedStress.jacobian, whose wall row is e_0
    with mass 0; kernels.band_lu); False if singular."""
    cols, weights, mud_p, p32, mu_w, kl, ku, tau, lap = data
    ab, piv, info = lu
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
    info[0] = band_lu(ab, piv, kl, ku)
    return info[0] >= 0


@jitable
def band_factors_solve(lu, r, data):
    """r = (M - dh J)^-1 r from ``stress_factor``'s factors."""
    ab, piv, info = lu
    band_solve(ab, piv, data[5], data[6], info[0], r)


@jitable
def no_refresh(lu, x, t, data):
    """Nothing in the factors changes with the Newton iterate."""


@jitable
def stress_project(x, data):
    """ImposedStress.project: the wall row exactly."""
    x[0] = 1.0


@jitable
def whole_update(x, dx, data):
    """ImposedStress.step_fraction: the whole Newton update."""
    return 1.0


# --- the imposed speed's kernels for the BDF loop (continuum.kernels): data = (cols, weights, lap_wall, mud_p, p32, p,
# wq, u_w, w_first, mu_w, mu_d, mu_s, dmu, kl, ku, tau, lap), tau and lap workspaces of N + 1 and N - 1 values

@jitable
def speed_project(z, x, data):
    """x = (q, z) with q from the constraint (ImposedSpeed.project); q = NaN where inadmissible.  Returns u~_w plus
    the interior's share of it summed in absolute value (the scale of q's round-off)."""
    p, wq, u_w, w_first, mu_w, mu_d, mu_s, dmu = (data[5], data[6], data[7], data[8], data[9], data[10], data[11],
                                                  data[12])
    integral, magnitude, admissible = 0.0, 0.0, True
    for j in range(len(z)):
        mu = mu_w * z[j] / p[j + 1]
        gap = mu_d - mu
        admissible = admissible and gap > 0
        term = wq[j + 1] * ((mu - mu_s) / gap)
        integral += term
        magnitude += abs(term)
        x[j + 1] = z[j]
    b = (mu_d - mu_w * z[0] / p[1]) / dmu
    target = (u_w + w_first - integral) / w_first
    x[0] = wall_unknown(target, b) if admissible and target > 0 else math.nan
    return u_w + magnitude


@jitable
def wall_tau(q, mu_w, mu_d, dmu, p0):
    """tau~ at the wall from q = ln(1/mu~_w)."""
    return (mu_d - dmu * math.exp(min(-q, EXP_MAX))) * p0 / mu_w


@jitable
def speed_rate(x, t, f, data):
    """ImposedSpeed.interior_rate: f = D(tau~) d2 tau~/dy~2 at nodes 1..N-1."""
    cols, weights, mud_p, p32, p, mu_w, mu_d, dmu, tau = (data[0], data[1], data[3], data[4], data[5], data[9],
                                                          data[10], data[12], data[15])
    laplacians(x, wall_tau(x[0], mu_w, mu_d, dmu, p[0]), tau, f, cols, weights)
    for i in range(len(f)):
        s = mud_p[i] - mu_w * x[i + 1]
        f[i] *= s * s / p32[i]


@jitable
def speed_jacobian(x, t, band, data):
    """ImposedSpeed.jacobian's rows and columns 1..N-1, band[ku + i - j, j] = dF_i/dz_j (z = x[1:])."""
    cols, weights, mud_p, p32, p, mu_w, mu_d, dmu, ku, tau, lap = (data[0], data[1], data[3], data[4], data[5],
                                                                   data[9], data[10], data[12], data[14], data[15],
                                                                   data[16])
    laplacians(x, wall_tau(x[0], mu_w, mu_d, dmu, p[0]), tau, lap, cols, weights)
    n = len(x)
    band[:] = 0.0
    for i in range(n - 1):
        s = mud_p[i] - mu_w * x[i + 1]
        diff = s * s / p32[i]
        for k in range(cols.shape[1]):
            c = cols[i, k]
            if 0 < c < n:
                band[ku + i - (c - 1), c - 1] += diff * weights[i, k]
        band[ku, i] -= 2 * mu_w * s / p32[i] * lap[i]


@jitable
def speed_wall(x, t, row0, column, data):
    """ImposedSpeed.wall_jacobian: the constraint's gradient (row0) and dF_i/dq at rows 1..kl (column)."""
    lap_wall, mud_p, p32, p, wq, w_first, mu_w, mu_d, dmu = (data[2], data[3], data[4], data[5], data[6], data[8],
                                                             data[9], data[10], data[12])
    n = len(x)
    mt1 = 0.0
    for j in range(1, n):
        mt = (mu_d - mu_w * x[j] / p[j]) / dmu
        dmt = -mu_w / (p[j] * dmu)
        row0[j] = -wq[j] / (mt * mt) * dmt
        if j == 1:
            mt1 = mt
    _, dq, db = first_cell(x[0], mt1)
    row0[0] = w_first * dq
    row0[1] += w_first * db * (-mu_w / (p[1] * dmu))
    dtau0 = dmu * math.exp(min(-x[0], EXP_MAX)) * p[0] / mu_w
    for k in range(len(column)):
        s = mud_p[k] - mu_w * x[k + 1]
        column[k] = s * s / p32[k] * lap_wall[k] * dtau0
