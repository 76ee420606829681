"""The one threshold crossing that finds a depth from a profile: the layer thickness delta (paper
section 3.3), the yield front of the velocity form, and the DEM's delta_u (compare/).

``crossing_depth(y, f, level)``: along the last axis (leading axes are times or samples), the depth
where f falls below ``level``, interpolated between the bracketing nodes j-1 and j:

* ``log=False``: linearly in f (noisy data, a simple zero);
* ``log=True``: linearly in log f where both nodes are positive (exact for an exponential tail, the
  erfc-like tail of delta), linearly where the lower node is not;
* ``cubic=True``: instead, the cubic through the nodes j-2..j+1 (in log f where those are positive and
  ``log``), solved for the level by safeguarded Newton in [y_j-1, y_j]: fourth-order accurate for a
  smooth profile (the continuum solver's delta; the linear forms are second-order); ``end_zero=True``
  (a profile that vanishes linearly at y[-1], the continuum's mu = mu_s at y~ = 1): the cubic in
  log(f/(y[-1] - y)), smooth up to that end where log f is not (measured: delta at u~_w = 1.334, t~ = 1,
  0.989, erratic by 4e-5 between meshes whose stencil neared the end); there f[-1] is taken as 0 (its
  round-off, 5.6e-17 from mu_w/p~(1) - mu_s, would put log(f/0) into a cubic through the end node: delta of
  u~_w = 0.02 at t~ = 10 would read 0.979 on 256 cells, 0.989 on 512, for 0.999): a crossing in the last two
  cells then takes the cubic in f (through that 0), fourth order as well;
* ``first=True``: j is the first node below ``level`` (nan where f never falls below it, y[0] where
  f[0] already does); ``first=False``: j - 1 is the last node at or above ``level`` (y[0] where none is,
  y[-1] where the last node is).
"""
from __future__ import annotations

import numpy as np


def crossing_depth(y, f, level: float, *, log: bool = False, first: bool = True, cubic: bool = False,
                   end_zero: bool = False):
    """Depth(s) where ``f`` crosses ``level`` downward; a float for a 1-D ``f``, an array otherwise."""
    y, f = np.asarray(y, dtype=float), np.asarray(f, dtype=float)
    f2 = f.reshape(-1, f.shape[-1])
    if end_zero:
        f2 = f2.copy()
        f2[:, -1] = 0.0
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
    if cubic and n >= 4:
        out = _cubic_crossing(y, f2, jj, level, log, out, end_zero)
    out = np.where(at_top, y[0], np.where(at_bottom, y[-1], np.where(never, np.nan, out)))
    return float(out[0]) if f.ndim == 1 else out.reshape(f.shape[:-1])


def _cubic_crossing(y, f2, jj, level, log, guess, end_zero):
    """Refine the crossing in [y_j-1, y_j] on the cubic through nodes j-2..j+1 (see the module)."""
    n = f2.shape[-1]
    cols = np.clip(jj - 2, 0, n - 4)[:, None] + np.arange(4)
    rows = np.arange(len(f2))[:, None]
    fv = f2[rows, cols]
    use_log = log & np.all(fv > 0, axis=-1)
    gap = y[-1] - y if end_zero else np.ones_like(y)  # the log form interpolates log(f/gap)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(use_log[:, None], np.log(np.where(fv > 0, fv / gap[cols], 1.0)), fv) - np.where(
            use_log, np.log(level), level)[:, None]
    lo, hi = y[jj - 1], y[jj]
    scale = hi - lo
    z = (y[cols] - lo[:, None]) / scale[:, None]
    coef = np.linalg.solve(z[..., None] ** np.arange(4), g[..., None])[..., 0]  # g(z) = sum_k coef_k z^k
    s = (guess - lo) / scale
    for _ in range(8):
        # the level is met where cubic(s) + log(gap(s)) = 0 (gap = 1 unless end_zero)
        at = np.maximum(y[-1] - lo - s * scale, np.finfo(float).tiny) if end_zero else np.ones_like(s)
        value = ((coef[:, 3] * s + coef[:, 2]) * s + coef[:, 1]) * s + coef[:, 0] + np.where(use_log, np.log(at), 0.0)
        slope = ((3 * coef[:, 3] * s + 2 * coef[:, 2]) * s + coef[:, 1]
                 - np.where(use_log & end_zero, scale / at, 0.0))
        s = np.clip(s - value / np.where(slope != 0, slope, np.inf), 0.0, 1.0)
    return np.where(np.isfinite(s), lo + s * scale, guess)


#: the layer thickness compared between models and DEM, delta_u: the depth where u falls to U_FRACTION of u_w
U_FRACTION = 0.05


def depth_at_fraction(depth, u, u_w: float, frac: float = U_FRACTION) -> float:
    """delta_u: the first depth (from the plate) where u falls below frac u_w (linear crossing); nan if never or
    if u_w is not a positive number."""
    if not (np.isfinite(u_w) and u_w > 0):
        return np.nan
    return crossing_depth(depth, np.asarray(u) / u_w, frac)


#: the layer's depths by threshold of u/u_w (transient observables, compare.families' estimators): where u falls to
#: half the plate's speed (the least sensitive to a creep tail, whose depth grows as ln(1/f)), to a fifth and a tenth
#: of it, and delta_u's U_FRACTION
LAYER_FRACTIONS = {"delta_50": 0.5, "delta_20": 0.2, "delta_10": 0.1, "delta_05": U_FRACTION}


def layer_measures(depth, u, u_w: float) -> dict:
    """The layer of one velocity profile u(depth) under a plate moving at u_w: its depth at each LAYER_FRACTIONS
    of u_w and its first moment int u d(depth) / u_w over depth >= 0 (nan where u_w is not positive)."""
    depth, u = np.asarray(depth, dtype=float), np.asarray(u, dtype=float)
    keep = (depth >= 0) & np.isfinite(u)
    depth, u = depth[keep], u[keep]
    order = np.argsort(depth)
    depth, u = depth[order], u[order]
    out = {k: depth_at_fraction(depth, u, u_w, f) for k, f in LAYER_FRACTIONS.items()}
    out["moment"] = float(np.trapezoid(u, depth) / u_w) if np.isfinite(u_w) and u_w > 0 else np.nan
    return out
