"""Richardson's estimate of a solution's spatial error, the one every continuum solve reports.

A quantity x_N computed on N cells by a scheme of order p in space has the error c h^p + O(h^(p+1)); its
companion x_N/REFINEMENT, on REFINEMENT times coarser cells, has REFINEMENT^p times that error, so

    error of x_N ~ |x_N - x_N/REFINEMENT| / (REFINEMENT^p - 1)

(exact when the error is c h^p alone).  Every estimate of that kind calls ``richardson`` with its scheme's
order and any safety factor (continuum.solver and continuum.paper.stability: the scheme's order, SAFETY;
continuum.ngf's transient, continuum.oscillation and continuum.predict_cli: second order); a nodal field whose
companion lives on other nodes goes through ``richardson_on_nodes``.  The estimate lives here, below the
solvers, so that each of them imports it and none defines its own.
"""
from __future__ import annotations

import numpy as np

#: the companion solve of an estimate has 1/REFINEMENT of the cells
REFINEMENT = 2


def richardson(fine, coarse, order: int = 2, safety: float = 1.0):
    """safety |fine - coarse| / (REFINEMENT^order - 1): the error of ``fine`` (order ``order`` in space)
    estimated from ``coarse``, its companion on 1/REFINEMENT of the cells."""
    return safety * np.abs(np.subtract(fine, coarse)) / (REFINEMENT**order - 1)


def richardson_on_nodes(y, fine, y_coarse, coarse, order: int = 2) -> np.ndarray:
    """``richardson`` of a nodal field ``fine`` at the nodes ``y`` from ``coarse`` at the nodes ``y_coarse``:
    ``fine`` interpolated (linearly) onto the coarse nodes, the estimate formed there and interpolated back
    onto ``y``."""
    return np.interp(y, y_coarse, richardson(np.interp(y_coarse, y, fine), coarse, order))


__all__ = ["REFINEMENT", "richardson", "richardson_on_nodes"]
