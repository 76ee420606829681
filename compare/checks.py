"""Checks of the coarse-grained profiles: width plateau, and LAMMPS's own in-run chunk averages.

``width_check``: the same frames coarse-grained with several widths w (one read of the dump); a field
at height y *plateaus* between successive widths when
    |f_w - f_w'| / max(|f_w|, |f_w'|, floor max_y |f_w|) <= rtol,
the floor (default 5 % of the profile's largest magnitude) keeping zeros of the field from flagging.
Near walls and in steep gradients no plateau is expected (the field varies on the kernel scale).

``lammps_crosscheck``: profiles.csv (dem/outputs.py) against the coarse-grained fields, contact parts
only, evaluated at the LAMMPS bin centres y (and bin edges y_plane for the method-of-planes values).
Why they differ:
* bins vs kernel: LAMMPS counts each grain in the 1 d bin of its centre (top hat, no overlap), the CG
  spreads it with K; both conserve the integral, the local values differ where fields vary within ~1 d
  (walls, layering, the shear band's edge);
* no stress line: the LAMMPS virial (compute stress/atom ... pair) puts half of r_ij (x) f_ij at each
  grain's centre, so a contact's stress sits at the two centres instead of along the branch; it carries
  the same integral but scatters from bin to bin (the CG stress line is exactly a kernel-smoothed method
  of planes: sigma_c_ay(y) = int K(y - y') MOP_a(y') dy');
* no wall term: a bed-wall contact keeps only the bed grain's half of r (x) f, placed at the bed grain's
  centre; the CG puts f (x) a (a = bed centre minus contact point, ~ r/2 for equal radii) on the line from
  the contact point to the centre, and the wall force density b at the contact point;
* no kinetic stress in profiles.csv (pair part only): compared with sigma_c only;
* u_x there is the number average of v_x in the bin, the CG velocity is mass weighted (j/rho);
* time sampling: LAMMPS averages every plate-output step within each profile interval, the CG only the
  atom-dump frames in the same interval (intervals with no frame are skipped): in a transient or with
  sparse dumps (smoke: 1 frame per 2 intervals) this dominates the difference;
* component and sign: profiles.csv ``tau`` = -s_xy n is sum r_x f_y per volume = sigma_c_yx here
  (compressive positive), negative for a +x drive; tau_mop = -F_x/A = tau_c = -sigma_c_xy.

Measured (smoke scene with atoms and contacts every 0.02, t in [5, 10], Lucy w = 0.5, bulk = 4 d above
the base to 3 d below the plate; mean |CG - LAMMPS| relative to the mean LAMMPS value): p_mop 0.8 %,
tau_mop 2.1 % (same quantity, smoothed: only the sampling differs), phi 3.2 %, u_x 4.7 %, virial p 4.4 %,
virial tau 8.8 % (bin-to-bin scatter of the centre-localised virial).  At the walls they part: in the
base bin (y = 1.5) phi 0.30 vs 0.38 and p_mop at y_plane = 1 19.4 vs 3.6 (LAMMPS's plane counts the
base contacts, the CG material ends at their contact points); under the plate (y = 13.5) phi 0.57 vs
0.43 and virial p 7.6 vs 5.7 (bin vs kernel across the free-surface-like drop of phi).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from granstokes.lib.validate import finite, require

from .kernels import KERNELS
from .profiles import ADDITIVE, CGSettings, DepthProfiles, _nanmean, coarse_grain, derive
from .reader import DriveFolder

#: the cross-check's bulk: this far (d) above the lowest and below the highest grid point
CROSSCHECK_MARGIN = 4.0


def width_check(drive: DriveFolder, t0: float, t1: float, widths=(0.25, 0.5, 1.0, 2.0), fields=("phi", "sigma_xy"),
                kernel: str = "lucy", rtol: float = 0.05, floor: float = 0.05) -> pd.DataFrame:
    """Window-averaged profiles (frames with t0 <= t <= t1) for each width; returns a long table
    y, field, width, value, rel_change (to the next smaller width; NaN for the smallest), plateau
    (rel_change <= rtol; True for the smallest width).  One grid (spacing min(w)/4) for all widths."""
    widths = tuple(sorted(widths))
    require(len(widths) >= 2 and all(finite(w) and w > 0 for w in widths), "widths", "at least two numbers > 0",
            widths)
    require(kernel in KERNELS, "kernel", f"one of {KERNELS}", kernel)
    require(finite(rtol) and rtol > 0, "rtol", "a number > 0", rtol)
    require(finite(floor) and 0 <= floor < 1, "floor", "a number in [0, 1)", floor)
    frames = drive.frames_between(t0, t1)
    require(len(frames) > 0, "t0, t1", "an interval containing an atom snapshot", (t0, t1))
    settings = [CGSettings(kernel, w, min(widths) / 4) for w in widths]
    sums = [{k: [] for k in ADDITIVE} for _ in widths]
    grid = None
    for fr in drive.frames(frames):
        grid = grid or settings[-1].grid_for(fr)
        contacts = drive.contacts_at(fr.step)
        for s, acc in zip(settings, sums):
            for k, v in coarse_grain(fr, contacts, s, grid, drive.dimension).items():
                acc[k].append(v)
    rows, prev = [], None
    for w, acc in zip(widths, sums):
        mean = {k: _nanmean(np.array(v)) for k, v in acc.items()}
        allf = {**mean, **derive(mean, grid.y, drive.dimension, drive.d, drive.rho_p)}
        for f in fields:
            require(f in allf, "fields", "names of profile fields (profiles.FIELDS)", f)
            val = allf[f]
            if prev is None:
                rel = np.full_like(val, np.nan)
            else:
                old = prev[f]
                scale = np.maximum(np.maximum(np.abs(val), np.abs(old)), floor * np.nanmax(np.abs(val)))
                with np.errstate(invalid="ignore", divide="ignore"):
                    rel = np.abs(val - old) / scale
            rows.append(pd.DataFrame({"y": grid.y, "field": f, "width": w, "value": val, "rel_change": rel,
                                      "plateau": np.isnan(rel) | (rel <= rtol) if prev is not None else True}))
        prev = allf
    return pd.concat(rows, ignore_index=True)


def lammps_crosscheck(profiles: DepthProfiles) -> pd.DataFrame:
    """profiles.csv against the CG fields of ``profiles`` (a run ``DepthProfiles``), per LAMMPS output
    interval (s - every, s] holding at least one atom frame.  Columns: step, t, y, n_frames and, for
    q in phi, u_x, p (= -tr(s)/D n vs the CG contact part tr(sigma_c)/D), tau_yx (profiles.csv ``tau``
    vs sigma_c_yx), p_mop and tau_mop (at y_plane, vs sigma_c_yy and -sigma_c_xy): ``<q>_lammps``,
    ``<q>_cg``, ``<q>_diff`` = cg - lammps.  Rows with count = 0 in LAMMPS (empty bins) are dropped."""
    r, drive = profiles.results, profiles.drive
    lp = drive.lammps_profiles()
    steps = np.sort(lp["step"].unique())
    require(len(steps) >= 1, "profiles.csv", "at least one output interval", str(drive.path))
    every = int(np.diff(steps).min()) if len(steps) > 1 else int(steps[0])
    dim = drive.dimension
    out = []
    for s in steps:
        sel = (r.steps > s - every) & (r.steps <= s)
        if not sel.any():
            continue
        mean = {k: _nanmean(v[sel]) for k, v in r.additive.items()}
        der = derive(mean, r.y, dim, drive.d, drive.rho_p)
        block = lp[(lp["step"] == s) & (lp["count"] > 0)]
        y, yp = block["y"].to_numpy(), block["y_plane"].to_numpy()
        at = lambda f, where: np.interp(where, r.y, f)  # noqa: E731
        p_c = (mean["sigma_c_xx"] + mean["sigma_c_yy"] + (mean["sigma_c_zz"] if dim == 3 else 0.0)) / dim
        pairs = {"phi": (block["phi"], at(mean["phi"], y)), "u_x": (block["u_x"], at(der["u_x"], y)),
                 "p": (block["p"], at(p_c, y)), "tau_yx": (block["tau"], at(mean["sigma_c_yx"], y)),
                 "p_mop": (block["p_mop"], at(mean["sigma_c_yy"], yp)),
                 "tau_mop": (block["tau_mop"], at(-mean["sigma_c_xy"], yp))}
        table = {"step": s, "t": s * drive.dt, "y": y, "y_plane": yp, "n_frames": int(sel.sum())}
        for q, (lam, cg) in pairs.items():
            lam = np.asarray(lam, dtype=float)
            table.update({f"{q}_lammps": lam, f"{q}_cg": cg, f"{q}_diff": cg - lam})
        out.append(pd.DataFrame(table))
    require(len(out) > 0, "profiles", "frames inside at least one profiles.csv interval", str(drive.path))
    return pd.concat(out, ignore_index=True)
