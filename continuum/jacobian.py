"""The Jacobian dF/dx of a problem's rate as the steppers use it: a band, optionally with a dense row 0."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Jacobian:
    """dF/dx as a band, ``bands[ku + i - j, j] = J[i, j]`` (scipy's solve_banded layout), and
    optionally a dense row 0 that replaces the band's row 0.  ``dissipative``: symmetric tridiagonal
    with M - dh J positive definite for dh > 0, factorised as L D L^T (LAPACK pttrf, no pivoting)."""

    bands: np.ndarray
    kl: int
    ku: int
    row0: np.ndarray | None = None
    dissipative: bool = False

    def sparse(self, first: int = 0):
        """The band's rows and columns first..n-1 as a sparse matrix (scipy's DIA)."""
        import scipy.sparse as sp

        n = self.bands.shape[1] - first
        return sp.dia_matrix((self.bands[:, first:], self.ku - np.arange(self.kl + self.ku + 1)), shape=(n, n))

    @classmethod
    def tridiagonal(cls, sub, diag, sup, row0=None) -> Jacobian:
        """From the sub-, main and super-diagonal (lengths n-1, n, n-1)."""
        bands = np.zeros((3, len(diag)))
        bands[0, 1:], bands[1], bands[2, :-1] = sup, diag, sub
        return cls(bands, 1, 1, row0)

    @classmethod
    def dissipative_tridiagonal(cls, diag, off) -> Jacobian:
        """A symmetric tridiagonal J with -J positive semidefinite (a discrete diffusion)."""
        bands = np.zeros((3, len(diag)))
        bands[0, 1:], bands[1], bands[2, :-1] = off, diag, off
        return cls(bands, 1, 1, dissipative=True)
