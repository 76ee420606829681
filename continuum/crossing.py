"""The one threshold crossing used to find a depth from a profile (layer thickness, yield fronts,
delta_u of the DEM): the first node where f falls below ``level``, interpolated between it and the
node before."""
from __future__ import annotations

import numpy as np


def crossing_depth(y, f, level: float, *, order: int = 1) -> float:
    """First y where f(y) < level, y increasing; ``order`` 1: linear interpolation of f between the
    bracketing nodes (for noisy data).  nan if f never falls below ``level``; y[0] if f[0] already does."""
    y, f = np.asarray(y, dtype=float), np.asarray(f, dtype=float)
    below = np.nonzero(f < level)[0]
    if len(below) == 0:
        return float("nan")
    j = below[0]
    if j == 0:
        return float(y[0])
    a, b = f[j - 1] - level, f[j] - level
    return float(y[j - 1] + a / (a - b) * (y[j] - y[j - 1]))
