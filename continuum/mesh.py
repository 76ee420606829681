"""Graded finite-difference mesh on y~ in [0, 1], refined at the moving wall.

At t~ = 1e-4 the layer is ~0.01 thick; at t~ = 10 it fills the domain.  A smooth exponential
map y~(xi) = (exp(a xi) - 1)/(exp(a) - 1) of a uniform xi-grid keeps the three-point second
difference second-order accurate globally (Kalnay de Rivas 1972), with cells growing by the
constant factor exp(a/N) from the wall.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .rheology import require


@dataclass(frozen=True, eq=False)
class Mesh:
    """Nodes y[0] = 0 (wall) < ... < y[N] = 1 (bottom of the steady layer, y = delta_s)."""

    y: np.ndarray

    @classmethod
    def graded(cls, n_cells: int = 200, stretch: float = 6.0) -> "Mesh":
        """Exponentially graded mesh; ``stretch`` = a, largest/smallest cell = exp(a) (about)."""
        require(isinstance(n_cells, (int, np.integer)) and n_cells >= 8, "n_cells", "an integer >= 8", n_cells)
        require(0 <= stretch <= 30, "stretch", "in [0, 30]", stretch)
        xi = np.linspace(0.0, 1.0, n_cells + 1)
        y = xi if stretch == 0 else np.expm1(stretch * xi) / np.expm1(stretch)
        y[-1] = 1.0
        return cls(y)

    @property
    def n_cells(self) -> int:
        return len(self.y) - 1

    @cached_property
    def h(self) -> np.ndarray:
        return np.diff(self.y)

    @cached_property
    def weights(self) -> np.ndarray:
        """Trapezoidal quadrature weights: integral f dy ~ weights @ f."""
        w = np.zeros_like(self.y)
        w[:-1] += self.h / 2
        w[1:] += self.h / 2
        return w

    @cached_property
    def d2(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Coefficients (lower, diag, upper) of d2/dy2 at the interior nodes 1..N-1."""
        hm, hp = self.h[:-1], self.h[1:]
        return 2 / (hm * (hm + hp)), -2 / (hm * hp), 2 / (hp * (hm + hp))
