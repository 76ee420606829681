"""Nonlocal granular fluidity (NGF) in the DEM's own scene: a bed of depth H on a no-slip base under a
plate of mass m_p per unit area (continuum.scene.BedScene), pressed with p_w and driven by an imposed shear stress
tau_w = mu_w p_w or an imposed speed u_w, held or oscillating (continuum.load.Load: its value at time t).

Model (Kamrin & Koval, PRL 108, 178301, 2012; Henann & Kamrin, PNAS 110, 6730, 2013), 1D, y the depth
below the plate, material units (DEM units d = rho_p = g = 1 by default):

    phi rho_p du/dt = -d tau/dy,      p = p_w + phi rho_p g y,      u(H) = 0,
    gamma_dot = -du/dy = g mu,        mu = tau/p   (so tau = p gamma_dot/g: 1/g is a viscosity/p),
    steady fluidity   A^2 d^2 g'' = |mu - mu_s| (g - g_loc),
    g_loc(mu, p) = sqrt(p/rho_p)/d * I_loc(mu)/mu,   I_loc = I0 (mu - mu_s)/(mu_d - mu) for mu > mu_s, 0 below,

the inverse of the Jop law the local model uses, with gamma_dot = |du/dy| and I0 in the DEM
convention (I = |du/dy| d/sqrt(p/rho_p); the Material converts its I0 once, ``Material`` ->
``i0_dem``).  Boundary conditions: dg/dy = 0 at the plate and at the base (Henann & Kamrin 2013; the
default, ``boundary="neumann"``) or g = g_loc at both walls (``boundary="dirichlet"``, an option).
With tau uniform in a steady state, mu = tau_w/p(y) falls with depth and reaches mu_s at the yield
depth delta_s = (mu_w/mu_s - 1) p_w/(phi rho_p g): above it the fluidity is fed by g_loc, below it
g decays like exp(-int sqrt(mu_s - mu) dy/(A d)) (WKB): the creep below the layer.
As A -> 0, g -> g_loc: the local mu(I) model (continuum.velocity, continuum.steady).

The local fluidity is capped for the transient only: for mu above mu_max = mu(I_max) (Jop law,
I_max = ``i_max`` in the DEM convention, default 10, far above dense flow) g_loc is held at its value
there, so an impulsive imposed speed, which briefly loads the plate above mu_d, has a finite target
fluidity.  No steady state with mu_w < mu_max sees the cap; the steady solvers refuse mu_w >= mu_max.

Transient fluidity (our choice; stated):

    t0 dg/dt = A^2 d^2 g'' - |mu - mu_s| (g - g_loc),     t0 = t0_hat d sqrt(rho_p/p),

whose steady state is exactly the equation above.  t0 is the fluidity's relaxation time, taken as
t0_hat local inertial times d sqrt(rho_p/p) (the microscopic rearrangement time; t0_hat = 1 by
default, a free parameter of the transient only): a uniform perturbation of g relaxes at the rate
|mu - mu_s|/t0, a perturbation of wavelength 2 pi l at (|mu - mu_s| + A^2 d^2/l^2)/t0.
Henann & Kamrin (PRL 2014, arXiv:1408.5205; Kamrin & Henann, Soft Matter 11, 179, 2015) use
t0 dg/dt = A^2 d^2 g'' - (mu_s - mu) g - b sqrt(rho_s d^2/p) mu g^2 instead, which has the same
non-trivial steady state (for the linear law mu = mu_s + b I) but also g = 0: from a bed at rest
(g = 0) nothing ever flows, and from a seed g = g_seed the start is delayed by about
t0 ln(g_loc/g_seed)/(mu - mu_s), so the onset depends on an arbitrary seed.  The relaxation form
used here has the source |mu - mu_s| g_loc, which starts g from zero linearly in time at any seed;
its transient from rest does not depend on the seed as the seed -> 0 (tested).

Numerics
--------
* Steady (``solve_steady``): for an imposed stress tau is uniform, so mu(y) is known and the g equation
  is linear; Chebyshev collocation (numpy.polynomial.chebyshev) on [0, delta_s] and [delta_s, H], with
  g and g' continuous at delta_s, where |mu - mu_s| and g_loc have a kink (g''' jumps): each piece is
  analytic, so the error falls exponentially in the number of points (measured in the tests).
  u(y) = int_y^H g mu dy' by Chebyshev quadrature of the same interpolant.  For an imposed speed,
  tau_w is the root (brentq) of u(0; tau_w) = u_w.  The error estimate is the change from n/2 points.
* Transient (``solve_transient``): finite volumes on a graded mesh, u at the nodes (u_N = 0), ln g at
  the cell centres (g > 0 by construction; the bed "at rest" starts from g = g_rest, tiny), stress and
  mu at the cells; 2N coupled ODEs (``FluidityProblem``, M = 1) integrated through the method registry
  (continuum.integrators) by scipy's Radau (the baseline solve_ivp-Radau, L-stable, order 5) on a sparse Jacobian
  pattern with finite differences (the problem has no analytic Jacobian, which the package's DIRKs would need; it
  is block-banded).  Radau, not BDF: on the impulsive imposed-speed start (mu ~ 1e7 in the first cell) BDF's
  Newton iterations land on a spurious branch (g far above the capped g_loc); Radau's do not, and its
  transient is the same for g_rest = 1e-8 and 1e-4.  The mesh has a face at the steady yield depth
  (``aligned_mesh``), which makes the O(h^2) error smooth in h (measured ratios 3.9-4.1 per halving);
  the error estimates of u_w and mu_w are Richardson's, |u_N - u_N/2|/3 (continuum.richardson).

What is known of A (check at the sources):
* 3D glass beads: A = 0.48 (Henann & Kamrin, PNAS 2013, with mu_s = 0.3819, b = 0.9377).
* 2D disks: Kamrin & Koval (PRL 2012) calibrated the model on 2D DEM of polydisperse disks in annular
  shear (Koval et al., PRE 79, 021306, 2009) and Liu & Henann (Soft Matter 2018) compared it with 2D
  DEM of planar shear with gravity; the values of A they report were not found in the public material
  searched here (see the README): A is calibrated on the DEM creep profile in compare/, and no
  literature value is built in (``NonlocalFluidity.A`` has no physical default for disks).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np
from numpy.polynomial import chebyshev as C
from scipy.optimize import brentq
from scipy.sparse import lil_matrix

from granstokes.lib.validate import finite, require

from .integrators import METHODS, integrate
from .load import Load
from .rheology import convert_I
from .richardson import REFINEMENT, richardson
from .scales import UNITS, Material, pressure
from .scene import BedScene, SceneNumerics
from .solver import check_times

BOUNDARIES = ("neumann", "dirichlet")
#: Chebyshev intervals per piece of a steady state (``solve_steady``'s default)
STEADY_INTERVALS = 64
#: ... of the steady state that places an imposed speed's mesh face at its yield depth (``solve_transient``)
KINK_INTERVALS = 32
#: the transient's first step (the material's time unit): the impulsive start's
FIRST_STEP = 1e-10
#: the fewest cells of the transient's error estimate's companion
MIN_COMPANION_CELLS = 8


@dataclass(frozen=True)
class NonlocalFluidity:
    """The NGF parameters beyond the local law: nonlocal amplitude ``A`` (dimensionless; the length is
    A d), the fluidity's boundary condition at plate and base, the transient's relaxation time in local
    inertial times ``t0_hat`` and the transient-only cap ``i_max`` of I_loc (DEM convention)."""

    A: float
    boundary: str = "neumann"
    t0_hat: float = 1.0
    i_max: float = 10.0

    def __post_init__(self):
        require(finite(self.A) and self.A >= 0, "A", "a finite number >= 0 (0: the local model)", self.A)
        require(self.boundary in BOUNDARIES, "boundary", f"one of {BOUNDARIES}", self.boundary)
        require(finite(self.t0_hat) and self.t0_hat > 0, "t0_hat", "a finite number > 0", self.t0_hat)
        require(finite(self.i_max) and self.i_max > 0, "i_max", "a finite number > 0", self.i_max)


def i0_dem(material: Material) -> float:
    """I0 in the DEM convention (gamma_dot = |du/dy|), the one NGF's g_loc uses."""
    return float(convert_I(material.I0, material.I_convention, "dem"))


def mu_max(material: Material, fluidity: NonlocalFluidity) -> float:
    """mu(I_max) of the Jop law: above it g_loc is held constant (transient overshoot only)."""
    return float(material.friction.mu_of_I(fluidity.i_max, i0_dem(material)))


def local_fluidity(material: Material, fluidity: NonlocalFluidity, mu, p):
    """g_loc(mu, p) = sqrt(p/rho_p)/d I_loc(mu)/mu (0 for mu <= mu_s; held above mu_max)."""
    mu = np.abs(np.asarray(mu, dtype=float))
    p = np.asarray(p, dtype=float)
    top = mu_max(material, fluidity)
    m = np.clip(mu, material.mu_s, top)
    i_loc = material.friction.I_of_mu(m, i0_dem(material))
    return np.sqrt(p / material.rho_p) / material.d * i_loc / np.maximum(m, 1e-300)


def yield_depth(material: Material, p_w: float, tau_w: float) -> float:
    """delta_s = (tau_w/mu_s - p_w)/(phi rho_p g): where tau_w/p = mu_s (may exceed H, or be <= 0)."""
    return (tau_w / material.mu_s - p_w) / material.weight_gradient


# --- steady state ------------------------------------------------------------------------------------

@lru_cache(maxsize=8)
def _cheb_reference(n: int):
    """Chebyshev-Lobatto nodes on [-1, 1] (ascending) and the derivative matrices there (read-only)."""
    t = -np.cos(np.pi * np.arange(n + 1) / n)
    V = C.chebvander(t, n)
    eye = np.eye(n + 1)
    inv = np.linalg.inv(V)
    d1 = C.chebvander(t, n - 1) @ C.chebder(eye, 1, axis=0) @ inv
    d2 = C.chebvander(t, n - 2) @ C.chebder(eye, 2, axis=0) @ inv
    for m in (t, d1, d2):
        m.flags.writeable = False
    return t, d1, d2


def _cheb(n: int, a: float, b: float):
    """Chebyshev-Lobatto nodes on [a, b] (ascending) and the first/second derivative matrices."""
    t, d1, d2 = _cheb_reference(n)
    s = 2.0 / (b - a)
    return a + (t + 1) * (b - a) / 2, s * d1, s * s * d2


@dataclass(frozen=True, eq=False)
class SteadyNGF:
    """Steady NGF state: u, g, mu, g_loc at the nodes y (depth below the plate; the two Chebyshev pieces
    share the node at delta_s, kept once), the wall values and their error estimates, metadata."""

    material: Material
    scene: BedScene
    load: Load
    fluidity: NonlocalFluidity
    y: np.ndarray
    u: np.ndarray
    g: np.ndarray
    mu: np.ndarray
    g_loc: np.ndarray
    tau_w: float
    u_w: float
    u_w_err: float
    mu_w_err: float
    delta_s: float
    n: int

    @property
    def imposed(self) -> str:
        return self.load.kind

    @property
    def mu_w(self) -> float:
        return self.tau_w / self.load.p_w

    @property
    def p(self) -> np.ndarray:
        return pressure(self.material, self.load.p_w, self.y)


def _pieces(material: Material, scene: BedScene, load: Load):
    H = scene.depth
    ys = yield_depth(material, load.p_w, load.tau_w)
    if 1e-6 * H < ys < (1 - 1e-6) * H:
        return [(0.0, ys), (ys, H)]
    return [(0.0, H)]


def steady_profile(material: Material, scene: BedScene, load: Load, fluidity: NonlocalFluidity,
                   n: int = STEADY_INTERVALS):
    """(y, u, g, mu, g_loc) of the steady state under the uniform stress tau_w of an imposed-stress ``load``, n
    Chebyshev intervals per piece.  A = 0 gives g = g_loc (the local model) with the same quadrature."""
    require(isinstance(n, (int, np.integer)) and n >= 4, "n", "an integer >= 4", n)
    require(load.kind == "stress", "load", "an imposed stress (tau is uniform in the steady state)", load)
    m, tau_w = material, load.tau_w
    A2 = (fluidity.A * m.d) ** 2
    pieces = [(a, b, *_cheb(n, a, b)) for a, b in _pieces(material, scene, load)]
    ys, mus, glocs, cs = [], [], [], []
    for _a, _b, y, _d1, _d2 in pieces:
        p = pressure(material, load.p_w, y)
        mu = tau_w / p
        ys.append(y)
        mus.append(mu)
        glocs.append(local_fluidity(m, fluidity, mu, p))
        cs.append(np.abs(mu - m.mu_s))
    if fluidity.A == 0:
        gs = [gl.copy() for gl in glocs]
    else:
        k = n + 1
        size = k * len(pieces)
        M = np.zeros((size, size))
        rhs = np.zeros(size)
        for i, (_a, _b, _y, _d1, d2) in enumerate(pieces):
            sl = slice(i * k, (i + 1) * k)
            M[sl, sl] = A2 * d2 - np.diag(cs[i])
            rhs[sl] = -cs[i] * glocs[i]
        # boundary rows: plate (first node of piece 0), base (last node of the last piece)
        first, last = 0, size - 1
        M[first], M[last] = 0.0, 0.0
        rhs[first] = rhs[last] = 0.0
        if fluidity.boundary == "neumann":
            M[first, :k] = pieces[0][3][0]
            M[last, size - k:] = pieces[-1][3][-1]
        else:
            M[first, first], rhs[first] = 1.0, glocs[0][0]
            M[last, last], rhs[last] = 1.0, glocs[-1][-1]
        if len(pieces) == 2:  # interface at delta_s: g and g' continuous
            r1, r2 = k - 1, k
            M[r1], M[r2] = 0.0, 0.0
            rhs[r1] = rhs[r2] = 0.0
            M[r1, k - 1], M[r1, k] = 1.0, -1.0
            M[r2, :k] = pieces[0][3][-1]
            M[r2, k:] -= pieces[1][3][0]
        sol = np.linalg.solve(M, rhs)
        gs = [sol[i * k:(i + 1) * k] for i in range(len(pieces))]
    # u(y) = int_y^H g mu dy', piece by piece from the base up
    us = [None] * len(pieces)
    below = 0.0
    for i in reversed(range(len(pieces))):
        a, b, y = pieces[i][:3]
        F = C.Chebyshev.fit(y, gs[i] * mus[i], n, domain=[a, b]).integ()
        us[i] = F(b) - F(y) + below
        below = float(us[i][0])
    keep = [slice(None)] + [slice(1, None)] * (len(pieces) - 1)
    cat = lambda parts: np.concatenate([q[s] for q, s in zip(parts, keep)])
    return cat(ys), cat(us), cat(gs), cat(mus), cat(glocs)


def _check_mu_w(material: Material, fluidity: NonlocalFluidity, mu_w: float) -> float:
    m = material
    top = mu_max(m, fluidity)
    require(finite(mu_w) and m.mu_s < mu_w < top, "mu_w",
            f"in the open interval (mu_s, mu(I_max)) = ({m.mu_s:.6g}, {top:.6g}) (mu_d = {m.mu_d:.6g})", mu_w)
    return float(mu_w)


def solve_steady(material: Material, scene: BedScene, load: Load, *, fluidity: NonlocalFluidity,
                 n: int = STEADY_INTERVALS, rtol: float = 1e-14, error_estimate: bool = True) -> SteadyNGF:
    """Steady NGF state under a held load: an imposed wall friction mu_w = tau_w/p_w or an imposed speed u_w
    (mu_w to ``rtol``); ``error_estimate``: the free value's error from a solve at half the intervals (else nan)."""
    require(not load.oscillating, "load", "a held load (omega = 0)", load)
    require(isinstance(n, (int, np.integer)) and n >= 8, "n", "an integer >= 8", n)
    m, p_w = material, load.p_w
    coarse = n // 2
    if load.kind == "stress":
        _check_mu_w(material, fluidity, load.mu_w)
        tau_w = load.tau_w
        y, u, g, mu, gl = steady_profile(material, scene, load, fluidity, n)
        u_c = steady_profile(material, scene, load, fluidity, coarse)[1][0] if error_estimate else np.nan
        u_w_err, mu_w_err = abs(u[0] - u_c), 0.0
    else:
        lo, hi = m.mu_s * (1 + 1e-12), mu_max(m, fluidity) * (1 - 1e-12)
        held = lambda mw: Load("stress", p_w, mu_w=mw)

        def root(npts):
            f = lambda mw: steady_profile(material, scene, held(mw), fluidity, npts)[1][0] - load.u_w
            require(f(hi) > 0, "u_w", f"a speed reachable with mu_w < mu(I_max) = {hi:.6g}", load.u_w)
            return brentq(f, lo, hi, xtol=rtol * lo, rtol=rtol)

        mw = root(n)
        tau_w = held(mw).tau_w
        y, u, g, mu, gl = steady_profile(material, scene, held(mw), fluidity, n)
        u_w_err, mu_w_err = 0.0, abs(mw - root(coarse)) if error_estimate else np.nan
    return SteadyNGF(material, scene, load, fluidity, y, u, g, mu, gl, float(tau_w), float(u[0]), float(u_w_err),
                     float(mu_w_err), float(yield_depth(material, p_w, tau_w)), n)


# --- transient -----------------------------------------------------------------------------------------

def aligned_mesh(numerics: SceneNumerics, depth: float, y_kink=None) -> np.ndarray:
    """Graded nodes on [0, depth]; with ``y_kink`` in (0, depth) the nearest node is moved onto it by
    rescaling each side linearly (cell sizes jump by a relative O(1/N) there), so that the kink of
    |mu - mu_s| and g_loc at the steady yield depth lies on a cell face: without it the cell that
    straddles delta_s makes the O(h^2) error constant depend on where delta_s falls in it."""
    y = numerics.mesh().y * depth
    if y_kink is None or not 0 < y_kink < depth:
        return y
    k = int(np.clip(np.argmin(np.abs(y - y_kink)), 1, len(y) - 2))
    out = y.copy()
    out[:k + 1] = y[:k + 1] * y_kink / y[k]
    out[k:] = y_kink + (y[k:] - y[k]) * (depth - y_kink) / (depth - y[k])
    return out


class FluidityProblem:
    """NGF's transient as M x' = F(x, t) for the method registry (continuum.integrators): x = [u at the free nodes,
    ln g at the cells], M = 1 (every row differential; the nodes' masses are inside F), the wall's value at time t
    the load's (continuum.load.Load.wall).  No analytic Jacobian: ``sparsity()`` is its pattern, for a solve_ivp
    baseline's finite differences.

    Below yield the fluidity relaxes to ``g_floor``: 0 by default (the local law's); the oscillating plate
    (continuum.oscillation) gives the bed at rest's g_rest, since over a slow cycle's static phase ln g would fall
    without bound (at |mu - mu_s|/t0) and the stress p gamma/g of any creep blow up (solve_ivp's step collapsed on
    the oscillating-disks study's slowest stress drive)."""

    def __init__(self, material: Material, scene: BedScene, load: Load, fluidity: NonlocalFluidity,
                 numerics: SceneNumerics, y_kink=None, g_floor: float = 0.0):
        require(METHODS[numerics.method].kind == "baseline", "method",
                "a solve_ivp baseline (NGF has no analytic Jacobian: scipy's finite differences on its pattern)",
                numerics.method)
        m = material
        self.material, self.scene, self.load, self.fluidity = material, scene, load, fluidity
        self.y = aligned_mesh(numerics, scene.depth, y_kink)
        self.h = np.diff(self.y)
        self.yc = self.y[:-1] + self.h / 2
        self.pc = pressure(material, load.p_w, self.yc)
        n = len(self.h)
        self.n = n
        rho_b = m.phi * m.rho_p
        node_mass = np.empty(n)
        node_mass[1:] = rho_b * (self.h[:-1] + self.h[1:]) / 2
        node_mass[0] = scene.plate_mass + rho_b * self.h[0] / 2
        self.node_mass = node_mass
        self.first = 0 if load.kind == "stress" else 1   # first free velocity node
        nu = n - self.first
        self.mass = np.ones(nu + n)
        self.t0 = fluidity.t0_hat * m.d * np.sqrt(m.rho_p / self.pc)
        self.A2 = (fluidity.A * m.d) ** 2
        self.dyc = np.diff(self.yc)
        # boundary distances for the Dirichlet option (wall value at distance h/2 from the cell centre)
        self.p_wall = (load.p_w, pressure(material, load.p_w, scene.depth))
        self.g_rest = numerics.g_rest
        self.g_floor = g_floor
        #: the absolute tolerances: on u, and on ln g
        self.atol = np.concatenate([np.full(nu, numerics.atol), np.full(n, numerics.atol_lng)])

    def initial(self) -> np.ndarray:
        """The bed at rest: u = 0, g = g_rest."""
        return np.concatenate([np.zeros(self.n - self.first), np.full(self.n, math.log(self.g_rest))])

    def project(self, x):
        return x

    def split(self, x, t):
        """u at every node (u_0 = u_w(t) under an imposed speed, u_N = 0) and ln g at the cells."""
        nu = self.n - self.first
        u = np.zeros(self.n + 1)
        u[self.first:self.n] = x[:nu]
        if self.load.kind == "speed":
            u[0] = self.load.wall(t)
        return u, x[nu:]

    def cells(self, x, t):
        """u at the nodes, g, gamma_dot, tau, mu at the cells."""
        u, lng = self.split(x, t)
        g = np.exp(np.clip(lng, -200.0, 50.0))  # guards trial Newton iterates only; states stay inside
        gamma = (u[:-1] - u[1:]) / self.h
        mu = gamma / g
        return u, g, gamma, self.pc * mu, mu

    def rate(self, x, t):
        u, g, gamma, tau, mu = self.cells(x, t)
        m = self.material
        du = np.empty(self.n)
        du[1:] = (tau[:-1] - tau[1:]) / self.node_mass[1:]
        du[0] = (self.load.wall(t) - tau[0]) / self.node_mass[0] if self.load.kind == "stress" else 0.0
        amu = np.abs(mu)
        gl = np.maximum(local_fluidity(m, self.fluidity, amu, self.pc), self.g_floor)
        flux = np.zeros(self.n + 1)
        flux[1:-1] = np.diff(g) / self.dyc
        if self.fluidity.boundary == "dirichlet":
            top = local_fluidity(m, self.fluidity, amu[0], self.p_wall[0])
            bot = local_fluidity(m, self.fluidity, amu[-1], self.p_wall[1])
            flux[0] = (g[0] - top) / (self.h[0] / 2)
            flux[-1] = (bot - g[-1]) / (self.h[-1] / 2)
        lap = np.diff(flux) / self.h
        dg = (self.A2 * lap - np.abs(amu - m.mu_s) * (g - gl)) / self.t0
        return np.concatenate([du[self.first:], dg / g])

    def sparsity(self):
        n, f = self.n, self.first
        nu = n - f
        S = lil_matrix((nu + n, nu + n), dtype=int)
        for i in range(f, n):          # du_i: u_{i-1..i+1}, g_{i-1}, g_i
            r = i - f
            for j in (i - 1, i, i + 1):
                if f <= j < n:
                    S[r, j - f] = 1
            for c in (i - 1, i):
                if 0 <= c < n:
                    S[r, nu + c] = 1
        for c in range(n):             # d ln g_c: g_{c-1..c+1}, u_c, u_{c+1}
            r = nu + c
            for k in (c - 1, c, c + 1):
                if 0 <= k < n:
                    S[r, nu + k] = 1
            for j in (c, c + 1):
                if f <= j < n:
                    S[r, j - f] = 1
        return S.tocsr()


@dataclass(frozen=True, eq=False)
class TransientNGF:
    """u at the nodes y and g, mu at the cell centres y_cell, at the times t; wall speed and friction
    (mu_w = tau at the first cell / p_w for an imposed speed, as continuum.velocity) with the
    spatial error estimate of u_w (Richardson from n_cells/2), solver statistics."""

    material: Material
    scene: BedScene
    load: Load
    fluidity: NonlocalFluidity
    y: np.ndarray
    y_cell: np.ndarray
    t: np.ndarray
    u: np.ndarray
    g: np.ndarray
    mu: np.ndarray
    mu_w: np.ndarray
    u_w_err: np.ndarray
    mu_w_err: np.ndarray
    nfev: int

    @property
    def imposed(self) -> str:
        return self.load.kind

    @property
    def u_w(self) -> np.ndarray:
        return self.u[:, 0]


def _transient(problem: FluidityProblem, times, numerics: SceneNumerics):
    """u, g, mu, mu_w at ``times`` (continuum.ngf's held loads) and scipy's evaluations of the rate."""
    load = problem.load
    states, stats = integrate(problem, times, method=numerics.method, rtol=numerics.rtol, atol=problem.atol,
                              h0=FIRST_STEP)
    nfev = stats.newton_iterations  # a baseline's: scipy's evaluations of the rate
    cells = [problem.cells(x, t) for t, x in zip(times, states)]
    u = np.array([c[0] for c in cells])
    g = np.array([c[1] for c in cells])
    mu = np.array([c[4] for c in cells])
    tau0 = np.array([c[3][0] for c in cells])
    mu_w = np.full(len(times), load.tau_w / load.p_w) if load.kind == "stress" else tau0 / load.p_w
    return u, g, mu, mu_w, nfev


def solve_transient(material: Material, scene: BedScene, load: Load, times, *, fluidity: NonlocalFluidity,
                    numerics: SceneNumerics = SceneNumerics(), error_estimate: bool = True,
                    y_kink=None) -> TransientNGF:
    """NGF transient from a bed at rest (u = 0, g = g_rest) under a held load: an imposed mu_w or speed u_w (an
    oscillating load: continuum.oscillation).

    ``y_kink``: the depth given a mesh face (default: the steady yield depth of the drive; pass the
    same value to compare two drives on the same mesh)."""
    require(not load.oscillating, "load", "a held load (omega = 0; an oscillating one: continuum.oscillation)", load)
    t = check_times(times)
    if load.kind == "stress":
        _check_mu_w(material, fluidity, load.mu_w)
    # the mesh gets a face at the steady yield depth (for an imposed speed, that of the steady NGF state)
    if y_kink is None:
        tau_w = load.tau_w if load.kind == "stress" else solve_steady(
            material, scene, load, fluidity=fluidity, n=KINK_INTERVALS, error_estimate=False).tau_w
        y_kink = yield_depth(material, load.p_w, tau_w)
    problem = FluidityProblem(material, scene, load, fluidity, numerics, y_kink)
    u, g, mu, mw, nfev = _transient(problem, t, numerics)
    u_err, mu_err = np.zeros(len(t)), np.zeros(len(t))
    if error_estimate:
        coarse = replace(numerics, n_cells=max(MIN_COMPANION_CELLS, numerics.n_cells // REFINEMENT))
        u_c, _, _, mw_c, nf = _transient(FluidityProblem(material, scene, load, fluidity, coarse, y_kink), t, coarse)
        u_err, mu_err = richardson(u[:, 0], u_c[:, 0]), richardson(mw, mw_c)
        nfev += nf
    return TransientNGF(material, scene, load, fluidity, problem.y, problem.yc, t, u, g, mu, mw, u_err, mu_err,
                        nfev)


__all__ = ["FluidityProblem", "NonlocalFluidity", "SteadyNGF", "TransientNGF", "local_fluidity", "mu_max",
           "solve_steady", "solve_transient", "steady_profile", "yield_depth", "i0_dem", "UNITS"]
