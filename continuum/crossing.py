"""The one threshold crossing that finds a depth from a profile: the layer thickness delta (paper
section 3.3), the yield front of the velocity form, and the DEM's delta_u (compare/).

``crossing_depth(y, f, level)``: along the last axis (leading axes are times or samples), the depth
where f falls below ``level``, interpolated between the bracketing nodes j-1 and j:

* ``log=False``: linearly in f (noisy data, a simple zero);
* ``log=True``: linearly in log f where both nodes are positive (exact for an exponential tail, the
  erfc-like tail of delta), linearly where the lower node is not;
* ``first=True``: j is the first node below ``level`` (nan where f never falls below it, y[0] where
  f[0] already does); ``first=False``: j - 1 is the last node at or above ``level`` (y[0] where none is,
  y[-1] where the last node is).
"""
from __future__ import annotations

import numpy as np


def crossing_depth(y, f, level: float, *, log: bool = False, first: bool = True):
    """Depth(s) where ``f`` crosses ``level`` downward; a float for a 1-D ``f``, an array otherwise."""
    y, f = np.asarray(y, dtype=float), np.asarray(f, dtype=float)
    f2 = f.reshape(-1, f.shape[-1])
    below = f2 < level
    n = f2.shape[-1]
    if first:
        j = np.argmax(below, axis=-1)
        never, at_top = ~below.any(axis=-1), below[:, 0]
        at_bottom = np.zeros_like(never)
    else:
        above = ~below
        j = n - np.argmax(above[:, ::-1], axis=-1)  # one past the last node at or above the level
        never = np.zeros(len(f2), dtype=bool)
        at_top, at_bottom = ~above.any(axis=-1), j >= n
    jj = np.clip(j, 1, n - 1)
    rows = np.arange(len(f2))
    f0, f1 = f2[rows, jj - 1], f2[rows, jj]
    y0, y1 = y[jj - 1], y[jj]
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = (f0 - level) / (f0 - f1)
        if log:
            frac = np.where((f1 > 0) & (f0 > 0), np.log(f0 / level) / np.log(f0 / f1), frac)
    out = y0 + frac * (y1 - y0)
    out = np.where(at_top, y[0], np.where(at_bottom, y[-1], np.where(never, np.nan, out)))
    return float(out[0]) if f.ndim == 1 else out.reshape(f.shape[:-1])
