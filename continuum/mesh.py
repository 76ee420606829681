"""Graded finite-difference mesh on y~ in [0, 1], refined at the moving wall, and its operators.

At t~ = 1e-4 the layer is ~0.01 thick; at t~ = 10 it fills the domain.  A smooth map of a uniform
xi-grid, y~ = expm1(s(xi))/expm1(s(1)) with

    s(xi) = a xi + E (1 - exp(-xi/w))/(1 - exp(-1/w)),   w = WALL_CLUSTER_WIDTH,

grows the cells geometrically from the wall: with E = 0 (the exponential map, stretch a) by the constant
factor exp(a/N), so that a layer of any thickness above the first cell spans about the same number of
cells; E > 0 packs E more e-folds of grading into the first ~w of the grid (a wall cluster: an imposed
speed's sub-layer, continuum.solver.speed_map) and leaves the layer a's even grading.  Two
discretisations of d2/dy~2 and of the quadrature:

* order 2: the three-point second difference on the nodes (Kalnay de Rivas 1972) and the trapezoidal
  rule, the standard method of lines (the baseline, the stability maps);
* order 4: five-point differences in xi, with the map's exact derivatives
  (d2/dy2 = (d2/dxi2 - (y''/y') d/dxi)/y'^2), six-point one-sided rows next to the ends,
  and the four-point (cubic) rule on each cell in xi for the integrals.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cache, cached_property, wraps
from math import factorial

import numpy as np

from .rheology import require

ORDERS = (2, 4)
#: operators on at most this many nodes are applied as dense matrices
DENSE_UP_TO = 300
CENTRED = (-2, -1, 0, 1, 2)


@cache
def fd_weights(offsets: tuple[int, ...], derivative: int) -> np.ndarray:
    """Weights w with sum_k w_k f(x + k h) = h^derivative f^(derivative)(x) + O(h^len(offsets)), for
    integer offsets k (the Taylor/Vandermonde conditions, exact in rationals up to round-off)."""
    k = np.asarray(offsets, dtype=float)
    vander = np.array([k**m / factorial(m) for m in range(len(k))])
    rhs = np.zeros(len(k))
    rhs[derivative] = 1.0
    return np.linalg.solve(vander, rhs)


def _per_order(method):
    """Memoise a Mesh operator per instance and order (the mesh is immutable)."""
    @wraps(method)
    def memoised(self, order: int):
        memo = self.__dict__.setdefault("_operators", {})
        key = (method.__name__, order)
        if key not in memo:
            require(order in ORDERS, "order", f"one of {ORDERS}", order)
            memo[key] = method(self, order)
        return memo[key]
    return memoised


@dataclass(frozen=True, eq=False)
class Stencil:
    """A linear operator on nodal values, row r = sum_k weights[r, k] f[cols[r, k]]; cols of a row
    are consecutive (a band)."""

    cols: np.ndarray
    weights: np.ndarray

    @cached_property
    def matrix(self):
        """The operator as a matrix: dense while small (fastest), else sparse (CSR)."""
        rows = np.broadcast_to(np.arange(len(self.cols))[:, None], self.cols.shape)
        shape = (len(self.cols), int(self.cols.max()) + 1)
        if shape[1] > DENSE_UP_TO:
            import scipy.sparse as sp  # here only: it adds ~0.2 s to the start-up (bench/startup.py)

            return sp.csr_matrix((self.weights.ravel(), (rows.ravel(), self.cols.ravel())), shape=shape)
        m = np.zeros(shape)
        m[rows, self.cols] = self.weights  # the columns of a row are distinct
        return m

    def __call__(self, f):
        f = np.asarray(f)
        return (self.matrix @ f.reshape(-1, f.shape[-1]).T).T.reshape(*f.shape[:-1], -1)


@dataclass(frozen=True, eq=False)
class Mesh:
    """Nodes y[0] = 0 (wall) < ... < y[N] = 1 (bottom of the steady layer, y = delta_s) of the map with
    stretch a and wall cluster E (module docstring)."""

    y: np.ndarray
    stretch: float = 0.0
    wall_folds: float = 0.0

    @classmethod
    def graded(cls, n_cells: int = 200, stretch: float = 6.0, wall_folds: float = 0.0) -> Mesh:
        """The map's nodes; ``stretch`` = a, ``wall_folds`` = E: largest/smallest cell = exp(a + E) (about)."""
        require(isinstance(n_cells, (int, np.integer)) and n_cells >= 8, "n_cells", "an integer >= 8", n_cells)
        require(0 <= stretch <= MAX_STRETCH, "stretch", f"in [0, {MAX_STRETCH:g}]", stretch)
        require(0 <= wall_folds <= MAX_STRETCH - stretch, "wall_folds", f"in [0, {MAX_STRETCH - stretch:g}]",
                wall_folds)
        mesh = cls(np.empty(n_cells + 1), float(stretch), float(wall_folds))
        s = mesh._s(0)
        mesh.y[:] = np.linspace(0.0, 1.0, n_cells + 1) if s[-1] == 0 else np.expm1(s) / np.expm1(s[-1])
        mesh.y[-1] = 1.0
        return mesh

    def _s(self, derivative: int, xi=None) -> np.ndarray:
        """The map's exponent s(xi) (module docstring), or its first or second derivative, at the nodes
        (or at ``xi``)."""
        xi = np.linspace(0.0, 1.0, len(self.y)) if xi is None else np.asarray(xi, dtype=float)
        w = WALL_CLUSTER_WIDTH
        cluster = self.wall_folds / -np.expm1(-1 / w) * np.exp(-xi / w)     # E exp(-xi/w)/(1 - exp(-1/w))
        if derivative == 0:
            return self.stretch * xi + self.wall_folds / -np.expm1(-1 / w) - cluster
        return self.stretch + cluster / w if derivative == 1 else -cluster / w**2

    @property
    def label(self) -> str:
        """The map in words (tables, figures)."""
        return f"stretch {self.stretch:.3g}" + (f" + wall cluster {self.wall_folds:.3g}" if self.wall_folds else "")

    def xi_at(self, y) -> np.ndarray:
        """The map's inverse: xi in [0, 1] at depths y~ in [0, 1], by Newton on the concave, increasing s
        from xi = 0 (its iterates rise monotonically to the root)."""
        y = np.asarray(y, dtype=float)
        s1 = self._s(0, 1.0)
        if s1 == 0:
            return y.copy()
        target, xi = np.log1p(y * np.expm1(s1)), np.zeros_like(y)
        for _ in range(INVERSE_ITERATIONS):
            step = (target - self._s(0, xi)) / self._s(1, xi)
            xi += step
            if np.all(np.abs(step) <= INVERSE_TOL):
                break
        return np.clip(xi, 0.0, 1.0)

    def resample(self, f, onto: Mesh) -> np.ndarray:
        """Nodal values f on this mesh (last axis) at the nodes of ``onto``: the quintic spline in this
        map's xi (where f is smooth), error O(N^-6)."""
        from scipy.interpolate import make_interp_spline

        spline = make_interp_spline(np.linspace(0.0, 1.0, len(self.y)), f, k=RESAMPLE_DEGREE, axis=-1)
        return spline(self.xi_at(onto.y))

    @property
    def n_cells(self) -> int:
        return len(self.y) - 1

    @cached_property
    def h(self) -> np.ndarray:
        return np.diff(self.y)

    @cached_property
    def dy_dxi(self) -> np.ndarray:
        """y'(xi) of the map at the nodes (exact)."""
        s = self._s(0)
        if s[-1] == 0:
            return np.ones_like(self.y)
        return np.exp(s) * self._s(1) / np.expm1(s[-1])

    @cached_property
    def curvature(self) -> np.ndarray:
        """y''(xi)/y'(xi) of the map at the nodes (exact): s' + s''/s' (the stretch a when E = 0)."""
        if self._s(0)[-1] == 0:
            return np.zeros_like(self.y)
        return self._s(1) + self._s(2) / self._s(1)

    @cached_property
    def weights(self) -> np.ndarray:
        """Trapezoidal quadrature weights: integral f dy ~ weights @ f (order 2)."""
        w = np.zeros_like(self.y)
        w[:-1] += self.h / 2
        w[1:] += self.h / 2
        return w

    @cached_property
    def d2(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Coefficients (lower, diag, upper) of the three-point d2/dy2 at the interior nodes 1..N-1."""
        hm, hp = self.h[:-1], self.h[1:]
        return 2 / (hm * (hm + hp)), -2 / (hm * hp), 2 / (hp * (hm + hp))

    @_per_order
    def second_derivative(self, order: int) -> Stencil:
        """d2/dy2 at the interior nodes 1..N-1, of the given order (ORDERS)."""
        n = self.n_cells
        rows = np.arange(1, n)
        if order == 2:
            return Stencil(rows[:, None] + np.arange(-1, 2), np.column_stack(self.d2))
        require(n >= 8, "n_cells", "an integer >= 8 for order 4", n)
        start = np.clip(rows - 2, 0, n - 5)            # six consecutive nodes holding each row's stencil
        cols = start[:, None] + np.arange(6)
        d2, d1 = np.zeros((n - 1, 6)), np.zeros((n - 1, 6))
        # one-sided rows next to the ends: d2 on all six nodes, d1 on five
        d2[0], d1[0, :5] = fd_weights(tuple(range(-1, 5)), 2), fd_weights(tuple(range(-1, 4)), 1)
        d2[-1], d1[-1, 1:] = fd_weights(tuple(range(-4, 2)), 2), fd_weights(tuple(range(-3, 2)), 1)
        inner = np.arange(1, n - 2)[:, None]
        window = (rows - start)[inner] + np.arange(-2, 3)  # node i sits at rows - start in its window
        d2[inner, window], d1[inner, window] = fd_weights(CENTRED, 2), fd_weights(CENTRED, 1)
        dxi = 1.0 / n
        yp, curvature = self.dy_dxi[rows], self.curvature[rows]
        return Stencil(cols, (d2 / dxi**2 - curvature[:, None] * d1 / dxi) / yp[:, None] ** 2)

    @_per_order
    def cell_integrals(self, order: int) -> Stencil:
        """integral of f over each cell [y_j, y_j+1] (rows j = 0..N-1), of the given order."""
        n = self.n_cells
        cells = np.arange(n)
        if order == 2:
            return Stencil(cells[:, None] + np.arange(2), np.column_stack([self.h / 2, self.h / 2]))
        start = np.clip(cells - 1, 0, n - 3)
        w = np.tile(np.array([-1.0, 13.0, 13.0, -1.0]) / 24, (n, 1))  # cubic through j-1..j+2
        w[0] = np.array([9.0, 19.0, -5.0, 1.0]) / 24
        w[-1] = w[0][::-1]
        cols = start[:, None] + np.arange(4)
        return Stencil(cols, w / n * self.dy_dxi[cols])

    @_per_order
    def cell_integrals_from_node1(self, order: int) -> Stencil:
        """As ``cell_integrals`` for the cells 1..N-1, using nodes 1..N only (the wall node may be
        singular: continuum.problems.ImposedSpeed)."""
        cells = self.cell_integrals(order)
        cols, w = cells.cols[1:].copy(), cells.weights[1:].copy()
        if order == 4:
            cols[0] = 1 + np.arange(4)
            w[0] = np.array([9.0, 19.0, -5.0, 1.0]) / 24 / self.n_cells * self.dy_dxi[cols[0]]
        return Stencil(cols, w)

    @_per_order
    def quadrature_from_node1(self, order: int) -> np.ndarray:
        """Weights q (q[0] = 0) with int_y1^1 f dy ~ q @ f."""
        cells = self.cell_integrals_from_node1(order)
        q = np.zeros_like(self.y)
        np.add.at(q, cells.cols, cells.weights)
        return q

    def integral_from_bottom(self, f, order: int):
        """int_y^1 f dy at every node (last axis), of the given order."""
        pieces = self.cell_integrals(order)(f)
        up = np.cumsum(pieces[..., ::-1], axis=-1)[..., ::-1]
        return np.concatenate([up, np.zeros_like(up[..., :1])], axis=-1)


#: the width in xi of the map's wall cluster (module docstring; measured for an imposed speed: with E = 7.3,
#: 0.1 gives delta fourth order through t~ = 1e-4 ... 10, bench/RESULTS.md "One map with a wall cluster")
WALL_CLUSTER_WIDTH = 0.1
#: the map's largest stretch: exp(40) ~ 2e17 between the largest and the smallest cell
MAX_STRETCH = 40.0
#: ``Mesh.xi_at``: most Newton iterations, and the step in xi at which they stop
INVERSE_ITERATIONS, INVERSE_TOL = 100, 1e-15
#: ``Mesh.resample``: the spline's degree
RESAMPLE_DEGREE = 5
