"""Coarse-grained depth profiles (1D in y, averaged over x and z) of a DEM drive (Goldhirsch 2010;
Weinhart et al. 2012, "From discrete particles to continuum fields near a boundary").

Material and walls.  The coarse-grained material is the bed grains (type 1).  Base (type 2) and plate
(type 3) grains are walls: they enter only through their contacts with bed grains (boundary term).

Fields on a grid y_g, with a normalised kernel K of width w (``kernels.Kernel``) and A = L_x L_z the
horizontal area (L_x in 2D: everything is per unit thickness), sums over bed grains i and contacts c:

* density rho = sum_i m_i K(y - y_i) / A; solid fraction phi = sum_i V_i K(y - y_i) / A with V_i the
  grain volume (2D: disk area pi r^2, so phi is the area fraction) -- Goldhirsch eq. 3;
* momentum j = sum_i m_i v_i K / A, velocity u = j / rho (mass-weighted) -- eq. 4;
* kinetic stress sigma_k_ab = sum_i m_i v'_ia v'_ib K(y - y_i) / A with v'_i = v_i - u(y_i), u taken at
  each grain's own height (linear interpolation on the grid) -- Weinhart et al. 2012 eq. 17;
  granular temperature T = tr(sigma_k) / (D rho) (velocity^2 units, D = dimension);
* contact stress, stress line between bed grains (eq. 30): sigma_c_ab = sum_c f_a r_b
  int_0^1 K(y - y_2 - l r_y) dl / A, f the force on grain 1, r = x_1 - x_2 the branch vector (exact
  for the kernel: the b = y components are f_a (F(y - y_2) - F(y - y_1)) / A, F the kernel's CDF);
* boundary term (Weinhart et al. 2012 eqs. 25-26): a bed grain b touching a wall grain at the contact
  point c (mid-overlap, c = x_b - (r_b - delta/2) n, n the unit vector from the wall grain to b,
  delta = r_1 + r_2 - dist) carries its contact force f_b along the line from c to x_b only:
  sigma_c_ab += f_b,a a_b int_0^1 K(y - c_y - l a_y) dl / A, a = x_b - c; and f_b is deposited at c as
  the boundary force density b_a = sum f_b,a K(y - c_y) / A (the wall's force on the material, b_y < 0
  under the plate).  With it the static momentum balance holds exactly: d sigma_ay / dy = b_a + rho g_a.

Sign conventions (stated in every output's metadata): stresses are *compressive positive* (the
pressure-tensor convention, sigma = -Cauchy); the second index is the branch (flux) direction, so
d/dy sigma_ay is the momentum balance and sigma_xy = sum f_x r_y (sigma_yx = sum f_y r_x, which differs
by the contact torque density).  At the plate sigma_yy = f_y and sigma_xy = f_x of plate.csv (force of
the bed on the plate per area).  Derived: p = sigma_yy (normal stress on horizontal planes, > 0 in
compression), p_mean = tr(sigma)/D, tau = -sigma_xy (x force per area of the material above a plane on the
material below, = tau_w > 0 at the plate for a drive along +x), mu = tau / p, dudy = du_x/dy,
gamma_dot_dem = |du/dy|, gamma_dot_paper = |du/dy| / 2 (the paper's strain rate),
I_dem = |du/dy| d / sqrt(p / rho_p), I_paper = I_dem / 2 (I0_dem = 2 I0_paper).

Default width w = 0.5 d (kernel standard deviation; Lucy cutoff 1.62 d): small enough to resolve the
near-wall slip layer (~1-2 d) and a shear band of ~10 d, wide enough to smooth the grain-scale layering.
Measured with ``checks.width_check`` on the smoke run (window t in [5, 10], rtol 5 %, bulk = 4 d above
the base to 3 d below the plate): from w = 0.25 to 0.5, phi, tau and u_x plateau at 94 %, 100 % and 89 %
of the bulk points; from 0.5 to 1, phi and tau still do (100 %) but u_x only at 50 % (the kernel starts
to average over the curvature of the velocity profile); from 1 to 2, u_x at 3 %.  Grid spacing
defaults to w/4.

Time.  ``DepthProfiles`` keeps per-frame (instantaneous) additive fields; ``window(t0, t1)`` averages
the frames with t0 <= t <= t1 (contact fields over the frames that have a contact snapshot);
``ensemble`` pools several drives (seeds).  Derived fields (u, T, p, tau, mu, I) are always computed
from averaged additive fields (u = <j>/<rho>, mu = <tau>/<p>), never averaged themselves; the band is
mean +- t_{0.975, n-1} standard error of the per-sample derived value, samples = seeds when there are
>= 2, else frames (frames are treated as independent: an underestimate if they are correlated).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd
from granstokes.dem.layout import BED, CONTACT_COLUMNS
from MDAnalysis.analysis.base import AnalysisBase
from scipy import stats

from granstokes.lib.validate import finite, require

from .kernels import Kernel
from .reader import DriveFolder, Frame

COMPONENTS = ("xx", "yy", "zz", "xy")
ADDITIVE = ("rho", "phi", "j_x", "j_y", "j_z", *(f"sigma_k_{c}" for c in COMPONENTS),
            *(f"sigma_c_{c}" for c in COMPONENTS), "sigma_c_yx", "b_x", "b_y")
DERIVED = ("u_x", "u_y", "u_z", "T", "sigma_xx", "sigma_yy", "sigma_zz", "sigma_xy", "sigma_yx", "p", "p_mean",
           "tau", "mu", "dudy", "gamma_dot_dem", "gamma_dot_paper", "I_dem", "I_paper")
FIELDS = ADDITIVE + DERIVED
_AXIS = {"x": 0, "y": 1, "z": 2}

UNITS = {
    "units": "DEM units: lengths in d, time in sqrt(d/g), velocity in sqrt(g d), stress in rho_p g d, "
             "density in rho_p (mass per volume; per area in 2D)",
    "stress": "compressive positive (sigma = -Cauchy); sigma_ab = sum f_a r_b ...: b is the flux direction; "
              "sigma_xy = f_x at the plate (plate.csv), p = sigma_yy, tau = -sigma_xy, mu = tau/p",
    "phi": "volume fraction in 3D, area fraction of disks in 2D",
    "inertial_number": "I_dem = |du/dy| d/sqrt(p/rho_p); I_paper = (1/2)|du/dy| d/sqrt(p/rho_p) "
                       "(gamma_dot_paper = |du/dy|/2); I0_dem = 2 I0_paper",
    "temperature": "T = tr(sigma_k)/(D rho), velocity^2",
    "averaging": "derived fields from averaged additive fields (u = <j>/<rho>); band: mean +- t_0.975 "
                 "standard error over seeds (>= 2 seeds) or frames (1 seed)",
}


@dataclass(frozen=True)
class Grid:
    """Uniform y grid y_k = lo + k spacing, k = 0..n-1 (in d)."""

    lo: float
    hi: float
    spacing: float

    def __post_init__(self):
        require(finite(self.spacing) and self.spacing > 0, "spacing", "a finite number > 0 (in d)", self.spacing)
        require(finite(self.lo) and finite(self.hi) and self.hi > self.lo, "grid", "finite lo < hi",
                (self.lo, self.hi))

    @property
    def y(self) -> np.ndarray:
        return self.lo + self.spacing * np.arange(int(round((self.hi - self.lo) / self.spacing)) + 1)


@dataclass(frozen=True)
class CGSettings:
    """Kernel name (``gaussian`` or ``lucy``), width w (its standard deviation, in d) and grid spacing
    (default w/4)."""

    kernel: str = "lucy"
    width: float = 0.5
    spacing: float | None = None

    def __post_init__(self):
        Kernel(self.kernel, self.width)  # validates kernel and width
        require(self.spacing is None or (finite(self.spacing) and 0 < self.spacing <= self.width),
                "spacing", f"None or a number in (0, width = {self.width}]", self.spacing)

    @property
    def K(self) -> Kernel:
        return Kernel(self.kernel, self.width)

    @property
    def h(self) -> float:
        return self.spacing or self.width / 4

    def grid_for(self, frame: Frame | list[Frame], margin: float = 2.0, rise: float = 0.0) -> Grid:
        """Grid covering every grain of ``frame`` (or of each of several frames: every bed's first) plus the kernel
        cutoff and ``margin`` d, its top ``rise`` d higher still (the most a plate rises later: a sheared bed
        dilates), on multiples of h."""
        frames = frame if isinstance(frame, list) else [frame]
        c, h = self.K.cutoff, self.h
        lo = math.floor((min(f.x[:, 1].min() for f in frames) - c - margin) / h) * h
        hi = math.ceil((max(f.x[:, 1].max() for f in frames) + rise + c + margin) / h) * h
        return Grid(lo, hi, h)


class _Spread:
    """Weights w(y_g, i) of N items on the grid points within ``reach`` of each centre (compact support):
    (N, S) heights ``yg`` and weights ``w`` = ``weights(yg)`` (0 off the grid); ``sum`` scatters all
    fields with one ``np.bincount``."""

    def __init__(self, grid: Grid, centres: np.ndarray, weights, reach: float):
        h, n = grid.spacing, len(grid.y)
        s = int(math.ceil(2 * reach / h)) + 2
        idx = np.floor((centres - reach - grid.lo) / h).astype(np.int64)[:, None] + np.arange(s)
        self.inside = (idx >= 0) & (idx < n)
        self.yg = grid.lo + idx * h
        self.w = weights(self.yg) if len(centres) else np.zeros((0, s))
        self.w[~self.inside] = 0.0
        self._idx, self._n = np.clip(idx, 0, n - 1), n

    def sum(self, values: dict, w: np.ndarray | None = None) -> dict:
        """sum_i values[i] w(y_g, i) on the grid for every entry of ``values`` (``w``: other weights on the
        same support)."""
        w = self.w if w is None else w
        k, n = len(values), self._n
        v = np.array([np.asarray(x, dtype=float) for x in values.values()]).reshape(k, len(w))
        idx = self._idx[None] + n * np.arange(k)[:, None, None]
        out = np.bincount(idx.ravel(), weights=(v[:, :, None] * w[None]).ravel(), minlength=k * n)
        return dict(zip(values, out.reshape(k, n)))


def _check_reach(grid: Grid, ymin: float, ymax: float, c: float) -> None:
    if ymin - c < grid.lo - 1e-9 or ymax + c > grid.hi + 1e-9:
        raise ValueError(f"grid [{grid.lo}, {grid.hi}] does not cover the grains' y range [{ymin:.4g}, {ymax:.4g}] "
                         f"plus the kernel cutoff {c:.4g}: widen the grid")


def coarse_grain(frame: Frame, contacts: pd.DataFrame | None, settings: CGSettings, grid: Grid,
                 dimension: int) -> dict:
    """Additive fields (``ADDITIVE``) of one snapshot on ``grid.y``: dict of float64 arrays.

    ``frame``: grains sorted by id (all types; bed = type 1 is the material); ``contacts``: table with
    id1 id2 dist dx dy dz fn ft_x ft_y ft_z (contacts.dump), or None (contact fields NaN).
    """
    require(dimension in (2, 3), "dimension", "2 or 3", dimension)
    K = settings.K
    c = K.cutoff
    lx = frame.box[0, 1] - frame.box[0, 0]
    area = lx * (frame.box[2, 1] - frame.box[2, 0] if dimension == 3 else 1.0)
    bed = frame.types == BED
    m, x, v, r = frame.mass[bed], frame.x[bed], frame.v[bed], frame.radius[bed]
    if len(m):
        _check_reach(grid, x[:, 1].min(), x[:, 1].max(), c)
    vol = np.pi * r ** 2 if dimension == 2 else 4.0 / 3.0 * np.pi * r ** 3
    yb = x[:, 1]
    spread = _Spread(grid, yb, lambda yg: K(yg - yb[:, None]), c)
    out = spread.sum({"rho": m, "phi": vol, "j_x": m * v[:, 0], "j_y": m * v[:, 1], "j_z": m * v[:, 2]})
    rho = out["rho"]
    u = [np.divide(out[f"j_{a}"], rho, out=np.zeros_like(rho), where=rho > 0) for a in "xyz"]
    vp = v - np.stack([np.interp(yb, grid.y, ua) for ua in u], axis=1)
    out.update(spread.sum({f"sigma_k_{ab}": m * vp[:, _AXIS[ab[0]]] * vp[:, _AXIS[ab[1]]] for ab in COMPONENTS}))
    out.update(contact_stress(frame, contacts, K, grid))
    return {k: out[k] / area for k in ADDITIVE}


def contact_stress(frame: Frame, contacts: pd.DataFrame | None, K: Kernel, grid: Grid) -> dict:
    """Contact stress lines (bed-bed and bed-wall) and the wall force density, times the area A
    (``coarse_grain`` divides); all NaN when ``contacts`` is None."""
    names = [f"sigma_c_{c}" for c in COMPONENTS] + ["sigma_c_yx", "b_x", "b_y"]
    if contacts is None:
        return {k: np.full(len(grid.y), np.nan) for k in names}
    cols = list(CONTACT_COLUMNS)
    table = (contacts if list(contacts.columns) == cols else contacts[cols]).to_numpy(np.float64)
    id1, id2 = table[:, 0].astype(np.int64), table[:, 1].astype(np.int64)
    pos, pos2 = np.searchsorted(frame.ids, id1), np.searchsorted(frame.ids, id2)
    if len(table) and (max(pos.max(), pos2.max()) >= len(frame.ids) or (frame.ids[pos] != id1).any()
                       or (frame.ids[pos2] != id2).any()):
        raise ValueError(f"step {frame.step}: contact ids not in the atom snapshot")
    t1, t2 = frame.types[pos] == BED, frame.types[pos2] == BED
    dist, rvec, fn, ft = table[:, 2], table[:, 3:6], table[:, 6], table[:, 7:10]
    f = rvec * (fn / dist)[:, None] + ft
    y1 = frame.x[pos, 1]
    y2 = y1 - rvec[:, 1]
    delta = frame.radius[pos] + frame.radius[pos2] - dist
    # bed-bed: line from x_2 to x_1, force f on grain 1
    # grain 1 bed, 2 wall: line from c = x_1 - (r_1 - delta/2) r/dist to x_1, force f
    # grain 1 wall, 2 bed: line from c = x_2 + (r_2 - delta/2) r/dist to x_2, force -f
    w1 = t1 & ~t2
    w2 = ~t1 & t2
    a1 = (frame.radius[pos] - delta / 2)[:, None] * rvec / dist[:, None]
    a2 = -(frame.radius[pos2] - delta / 2)[:, None] * rvec / dist[:, None]
    keep = t1 | t2
    branch = np.where(w1[:, None], a1, np.where(w2[:, None], a2, rvec))[keep]
    force = np.where(w2[:, None], -f, f)[keep]
    top = np.where(w2, y2, y1)[keep]  # the bed grain's end of the line (grain 1 for bed-bed)
    start = top - branch[:, 1]
    wall = (w1 | w2)[keep]
    mid = 0.5 * (start + top)
    reach = 0.5 * np.abs(branch[:, 1]).max(initial=0.0) + K.cutoff
    lines = _Spread(grid, mid, lambda yg: K.line_ry(yg, start[:, None], top[:, None]), reach)
    out = lines.sum({f"sigma_c_{a}y": force[:, _AXIS[a]] for a in "xyz"})
    full = np.where(lines.inside, K.line(lines.yg, start[:, None], top[:, None], lines.w), 0.0)
    out.update(lines.sum({"sigma_c_xx": force[:, 0] * branch[:, 0], "sigma_c_zz": force[:, 2] * branch[:, 2],
                          "sigma_c_yx": force[:, 1] * branch[:, 0]}, w=full))
    cy = start[wall]
    out.update(_Spread(grid, cy, lambda yg: K(yg - cy[:, None]), K.cutoff).sum(
        {"b_x": force[wall, 0], "b_y": force[wall, 1]}))
    return {k: out[k] for k in names}


def derive(fields: dict, y: np.ndarray, dimension: int, d: float = 1.0, rho_p: float = 1.0) -> dict:
    """Derived fields (``DERIVED``) from additive ones; arrays (..., len(y)), y along the last axis."""
    rho = np.asarray(fields["rho"])
    with np.errstate(invalid="ignore", divide="ignore"):
        out = {f"u_{a}": np.where(rho > 0, fields[f"j_{a}"] / rho, np.nan) for a in "xyz"}
        out["T"] = (fields["sigma_k_xx"] + fields["sigma_k_yy"] + fields["sigma_k_zz"]) / (dimension * rho)
        for ab in COMPONENTS:
            out[f"sigma_{ab}"] = fields[f"sigma_k_{ab}"] + fields[f"sigma_c_{ab}"]
        out["sigma_yx"] = fields["sigma_k_xy"] + fields["sigma_c_yx"]
        out["p"] = out["sigma_yy"]
        out["p_mean"] = (out["sigma_xx"] + out["sigma_yy"] + (out["sigma_zz"] if dimension == 3 else 0.0)) / dimension
        out["tau"] = -out["sigma_xy"]
        out["mu"] = np.where(out["p"] > 0, out["tau"] / out["p"], np.nan)
        out["dudy"] = np.gradient(out["u_x"], y, axis=-1)
        out["gamma_dot_dem"] = np.abs(out["dudy"])
        out["gamma_dot_paper"] = 0.5 * out["gamma_dot_dem"]
        scale = np.where(out["p"] > 0, d / np.sqrt(out["p"] / rho_p), np.nan)
        out["I_dem"] = out["gamma_dot_dem"] * scale
        out["I_paper"] = out["gamma_dot_paper"] * scale
    return out


def band_quantile(count):
    """The profiles' band is central -+ band_quantile(m) x the standard error over m samples: Student-t's 97.5 %
    quantile at m - 1 degrees of freedom (``standard_error`` undoes it)."""
    return stats.t.ppf(0.975, np.maximum(np.asarray(count) - 1, 1))


def standard_error(lo, hi, count):
    """The standard error a profile band (lo, hi) over ``count`` samples was built from."""
    return (np.asarray(hi) - np.asarray(lo)) / (2 * band_quantile(count))


def _band(central: dict, samples: dict, n: int, band_over: str) -> dict:
    """Central fields plus ``<f>_lo``/``<f>_hi`` = central -+ t_{0.975, m-1} std(samples)/sqrt(m), m the
    number of non-NaN samples at each y (n samples in all)."""
    out = dict(central)
    for k in FIELDS:
        count = np.sum(~np.isnan(samples[k]), axis=0)  # frames without contacts are NaN in contact fields
        with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns (no material, no contacts)
            se = np.nanstd(samples[k], axis=0, ddof=1) / np.sqrt(count) if n > 1 else np.full_like(central[k], np.nan)
            half = np.where(count > 1, band_quantile(count) * se, np.nan)
        out[f"{k}_lo"], out[f"{k}_hi"] = central[k] - half, central[k] + half
    out["n"], out["band_over"] = n, band_over
    return out


def _nanmean(a: np.ndarray) -> np.ndarray:
    """Mean over axis 0 ignoring frames without a contact snapshot (NaN rows)."""
    ok = ~np.isnan(a).all(axis=1) if a.ndim == 2 else slice(None)
    return a[ok].mean(axis=0) if np.any(ok) else np.full(a.shape[1:], np.nan)


class DepthProfiles(AnalysisBase):
    """Coarse-grained depth profiles of one drive folder, MDAnalysis style::

        prof = DepthProfiles(DriveFolder(path), CGSettings("lucy", 0.5)).run()      # all whole frames
        prof = DepthProfiles(drive).run(frames=drive.frames_between(5.0, 10.0))
        prof.results.frames      # long DataFrame: step, t, y, ADDITIVE + DERIVED (instantaneous)
        prof.window(5.0, 10.0)   # DataFrame: t0, t1, y, fields, <f>_lo, <f>_hi, n, band_over
        prof.results.meta        # JSON-ready dict: kernel, width, grid, units, conventions, frames

    ``results``: ``y`` (grid), ``steps``, ``t``, ``has_contacts`` (per frame), ``additive`` (dict of
    (n_frames, n_y) arrays), ``frames``, ``meta``.  ``grid`` defaults to ``settings.grid_for`` the first
    whole snapshot.  Frames are read one at a time (MDAnalysis) with the contact snapshot of the same
    step (pandas); truncated dumps are cut at their last whole snapshot (see reader.py).
    """

    def __init__(self, drive: DriveFolder, settings: CGSettings = CGSettings(), grid: Grid | None = None,
                 verbose: bool = False):
        self.drive, self.settings = drive, settings
        self._u = drive.universe()
        super().__init__(self._u.trajectory, verbose=verbose)
        self.grid = grid or settings.grid_for(drive.frame_from(self._u, 0))

    def run(self, start=None, stop=None, step=None, frames=None, verbose=None, **kwargs):
        """Like ``AnalysisBase.run``, restricted to the dump's whole snapshots."""
        whole = range(len(self.drive.atoms))
        frames = list(whole[start:stop:step]) if frames is None else [int(k) for k in frames]
        require(all(0 <= k < len(whole) for k in frames), "frames", f"indices in [0, {len(whole)})", frames)
        return super().run(frames=frames, verbose=verbose, **kwargs)

    def _prepare(self):
        self._rows = []

    def _single_frame(self):
        fr = self.drive.frame_from(self._u, self._ts.frame)
        cg = coarse_grain(fr, self.drive.contacts_at(fr.step), self.settings, self.grid, self.drive.dimension)
        self._rows.append((fr.step, fr.t, cg))

    def _conclude(self):
        r, d = self.results, self.drive
        r.y = self.grid.y
        r.steps = np.array([s for s, _, _ in self._rows], dtype=np.int64)
        r.t = np.array([t for _, t, _ in self._rows])
        r.additive = {k: np.array([cg[k] for _, _, cg in self._rows]).reshape(len(self._rows), len(r.y))
                      for k in ADDITIVE}
        r.has_contacts = ~np.isnan(r.additive["sigma_c_yy"]).all(axis=1)
        der = derive(r.additive, r.y, d.dimension, d.d, d.rho_p)
        n, g = len(r.steps), len(r.y)
        table = {"step": np.repeat(r.steps, g), "t": np.repeat(r.t, g), "y": np.tile(r.y, n)}
        table.update({k: v.ravel() for k, v in {**r.additive, **der}.items()})
        r.frames = pd.DataFrame(table)
        r.meta = self.meta(frames=[int(s) for s in r.steps], frames_without_contacts=int((~r.has_contacts).sum()))

    def meta(self, **extra) -> dict:
        """JSON-ready metadata of these profiles."""
        d = self.drive
        return {"drive": str(d.path), "name": d.name, "dimension": d.dimension, "dt": d.dt, "d": d.d,
                "rho_p": d.rho_p, **self.settings.K.describe(), "grid": asdict(self.grid), **UNITS,
                "material": "bed grains (type 1); base (2) and plate (3) are walls (boundary term)", **extra}

    def window(self, t0: float, t1: float) -> pd.DataFrame:
        """Profiles averaged over the frames with t0 <= t <= t1, with a band over those frames."""
        r = self.results
        sel = (r.t >= t0 - 1e-9) & (r.t <= t1 + 1e-9)
        require(sel.any(), "window", f"an interval containing a frame time (frames at {np.round(r.t, 4).tolist()})",
                (t0, t1))
        add = {k: v[sel] for k, v in r.additive.items()}
        mean = {k: _nanmean(v) for k, v in add.items()}
        central = {**mean, **derive(mean, r.y, self.drive.dimension, self.drive.d, self.drive.rho_p)}
        samples = {**add, **derive(add, r.y, self.drive.dimension, self.drive.d, self.drive.rho_p)}
        out = pd.DataFrame(_band(central, samples, int(sel.sum()), "frames"))
        out.insert(0, "y", r.y)
        out.insert(0, "t1", t1)
        out.insert(0, "t0", t0)
        return out


def ensemble(profiles: list[DepthProfiles], t0: float | None = None, t1: float | None = None) -> pd.DataFrame:
    """Ensemble over drives (seeds) sharing one grid and settings.

    With (t0, t1): each drive's window average, pooled; columns t0, t1, y, fields, bands, n, band_over.
    Without: instantaneous profiles at the steps every drive has; columns step, t, y, fields, bands.
    Band over seeds if >= 2 drives, else over frames (window) or none (instantaneous, NaN).
    """
    require(len(profiles) >= 1, "profiles", "a non-empty list of DepthProfiles", profiles)
    p0 = profiles[0]
    for p in profiles[1:]:
        require(p.grid == p0.grid and p.settings == p0.settings, "profiles", "drives analysed on one grid and settings",
                (p.grid, p.settings))
    dim, d, rho_p, y = p0.drive.dimension, p0.drive.d, p0.drive.rho_p, p0.results.y
    if len(profiles) == 1 and t0 is not None:
        return p0.window(t0, t1)
    if t0 is not None:
        per = []
        for p in profiles:
            sel = (p.results.t >= t0 - 1e-9) & (p.results.t <= t1 + 1e-9)
            require(sel.any(), "window", f"an interval containing frames of {p.drive.name}", (t0, t1))
            per.append({k: _nanmean(v[sel]) for k, v in p.results.additive.items()})
        add = {k: np.array([m[k] for m in per]) for k in ADDITIVE}
        mean = {k: _nanmean(v) for k, v in add.items()}
        out = pd.DataFrame(_band({**mean, **derive(mean, y, dim, d, rho_p)}, {**add, **derive(add, y, dim, d, rho_p)},
                                 len(profiles), "seeds"))
        out.insert(0, "y", y)
        out.insert(0, "t1", t1)
        out.insert(0, "t0", t0)
        return out
    common = sorted(set.intersection(*(set(p.results.steps.tolist()) for p in profiles)))
    rows = []
    for s in common:
        add = {k: np.array([p.results.additive[k][np.searchsorted(p.results.steps, s)] for p in profiles])
               for k in ADDITIVE}
        mean = {k: _nanmean(v) for k, v in add.items()}
        block = pd.DataFrame(_band({**mean, **derive(mean, y, dim, d, rho_p)}, {**add, **derive(add, y, dim, d, rho_p)},
                                   len(profiles), "seeds" if len(profiles) > 1 else "none"))
        block.insert(0, "y", y)
        block.insert(0, "t", s * p0.drive.dt)
        block.insert(0, "step", s)
        rows.append(block)
    return pd.concat(rows, ignore_index=True)
