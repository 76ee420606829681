"""Output files of a drive, assembled from its LAMMPS segments (one per start or resume).

Segment k (its script kept as in.lammps, then in.resume<k>.lammps) starts at step S_k (the prepared
bed, or the restart it resumed from) and is valid up to S_(k+1): whatever it wrote after that
restart is dropped (it was redone by segment k+1), and every step appears once.  Files (all under
the drive folder):

* ``plate.csv``: step, t, x (unwrapped), y (at the output step), u_x, u_y, f_x, f_y (force of the bed
  on the plate per plate area), u_c, n_c (x velocity and number of the bed grains touching a plate
  grain), all averaged over the output interval, sampled every half contact time (row 0: the prepared state),
  mu_w = -f_x/f_y (empty while the plate is out of contact, f_y <= 0);
* ``atoms.dump``: LAMMPS text dump (id type x y z vx vy vz radius), sorted by id;
* ``contacts.dump``: LAMMPS local dump, one line per contact (r < r_1 + r_2, plate and base
  contacts included): id1 id2 dist dx dy dz fn ft_x ft_y ft_z, (dx, dy, dz) = x_1 - x_2 (branch
  vector), normal force on grain 1 = fn (dx, dy, dz)/dist, (ft_x, ft_y, ft_z) the tangential force
  (``pair granular`` single() values);
* ``profiles.csv``: bed grains (not base, not plate) in 1 d bins in y, averaged over each output
  interval: step, t, y, count, n (number density), phi, u_x, p = -(s_xx + s_yy [+ s_zz])/D and
  tau = -s_xy (contact stress from the per-atom virial, kinetic part excluded), s_xx, s_yy, s_zz,
  s_xy; and at the plane y_plane = y - 1/2 the method-of-planes stresses p_mop (normal) and tau_mop
  (shear): the contact force through the plane per area, free of the bin-to-bin scatter that the
  virial estimator shows in a static packing.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from .layout import ATOMS, CONTACTS, LOG, PLATE_CSV, PROFILE_BIN, PROFILES_CSV, dump_snapshots, snapshot_table

#: bytes of one row of each output as written, by dimension where it differs (measured on the presets' runs by
#: bench/dem_costs.py, bench/RESULTS.md "DEM cost estimates"): an atoms.dump row (a grain), a
#: contacts.dump row (a contact), a profiles.csv row (a 1 d bin at one time), a plate.csv row, a restart's bytes per
#: grain, a log.lammps thermo line, a grains.csv row
ROW_BYTES = {"atom": {2: 64, 3: 82}, "contact": {2: 79, 3: 97}, "profile": {2: 146, 3: 168}, "plate": 117,
             "restart": 270, "thermo": 230, "grain": 24}
#: contacts per grain in a loaded bed's contacts.dump frame (base and plate contacts included), same runs
CONTACTS_PER_GRAIN = {2: 1.13, 3: 1.58}
#: profile bins beyond the bed's depth (the base, the plate, the box's headroom), and a preparation's log
PROFILE_EXTRA_BINS, PREPARE_LOG_BYTES = 10, 6e4

PROFILE_RAW = ["chunk", "y", "count", "n", "volume", "u_x", "s_xx", "s_yy", "s_zz", "s_xy", "fc_x", "fc_y"]


def _ranges(starts: list[int]) -> list[float]:
    return [float(s) for s in starts[1:]] + [math.inf]


def merge_table(frames: list[pd.DataFrame], starts: list[int]) -> pd.DataFrame:
    """Concatenate per-segment tables (column ``step``), each cut at the next segment's start."""
    kept, last = [], -math.inf
    for df, hi in zip(frames, _ranges(starts)):
        df = df[(df["step"] > last) & (df["step"] <= hi)]
        if len(df):
            kept.append(df)
            last = df["step"].max()
    return pd.concat(kept, ignore_index=True) if kept else (frames[0].iloc[0:0] if frames else pd.DataFrame())


def merge_dump(paths: list[Path], starts: list[int], target: Path) -> int:
    """Write the valid snapshots of per-segment dumps to ``target``; returns their number."""
    n, last = 0, -math.inf
    with target.open("w") as out:
        for path, hi in zip(paths, _ranges(starts)):
            for step, text in dump_snapshots(path):
                if last < step <= hi:
                    out.write(text)
                    last, n = step, n + 1
    return n


def read_chunk_file(path: Path) -> pd.DataFrame:
    """Parse a ``fix ave/chunk`` file (bins in y) into a long table."""
    rows = []
    if path.exists():
        step = None
        for line in path.read_text().splitlines():
            if not line or line.startswith("#"):
                continue
            parts = line.split()
            if len(parts) == 3:
                step = int(parts[0])
            else:
                rows.append([step, *map(float, parts)])
    return pd.DataFrame(rows, columns=["step", *PROFILE_RAW])


def profiles_table(raw: pd.DataFrame, plate: pd.DataFrame, every: int, dt: float, dimension: int) -> pd.DataFrame:
    """Per-volume fields from per-atom chunk averages (value per volume = atom average x n), and the
    method-of-planes stresses at each bin's lower edge y - 1/2: the contact force that the grains
    below exert on the grains and the plate above, per area, averaged over the same samples:
    p_mop = F_y/A (compressive > 0) and tau_mop = -F_x/A (exact momentum balance, kinetic flux aside).
    ``plate`` is the plate time series (its contact force completes the sum) and ``every`` the
    profile interval in steps."""
    n = raw["n"]
    trace = raw["s_xx"] + raw["s_yy"] + (raw["s_zz"] if dimension == 3 else 0.0)
    out = pd.DataFrame({
        "step": raw["step"].astype(int), "t": raw["step"] * dt, "y": raw["y"], "count": raw["count"], "n": n,
        "phi": raw["volume"] * n, "u_x": raw["u_x"], "p": -trace / dimension * n, "tau": -raw["s_xy"] * n,
        "s_xx": raw["s_xx"] * n, "s_yy": raw["s_yy"] * n, "s_zz": raw["s_zz"] * n, "s_xy": raw["s_xy"] * n,
    })
    window = (plate["step"] - 1) // every * every + every  # profile output step that averages each row
    mean_plate = plate[plate["step"] > 0].groupby(window)[["f_x", "f_y"]].mean()
    per_area = raw[["fc_x", "fc_y"]].mul(n * PROFILE_BIN, axis=0)  # contact force on the bin's grains per area
    per_area["step"], per_area["y"] = out["step"], out["y"]
    above = (per_area.sort_values(["step", "y"], ascending=[True, False])
             .groupby("step")[["fc_x", "fc_y"]].cumsum().sort_index())
    f_plate = mean_plate.reindex(out["step"]).to_numpy()
    out["y_plane"] = out["y"] - PROFILE_BIN / 2
    out["p_mop"] = above["fc_y"].to_numpy() + f_plate[:, 1]
    out["tau_mop"] = -(above["fc_x"].to_numpy() + f_plate[:, 0])
    return out


def merge_drive(drive_dir: Path, segments: list[Path], starts: list[int], profile_every: int, dt: float,
                dimension: int) -> dict:
    """Assemble the drive's output files from its segments; returns a summary for run.json."""
    # a segment killed at its start may have no plate.csv yet, or an empty one
    plates = [pd.read_csv(s / PLATE_CSV) if (s / PLATE_CSV).exists() and (s / PLATE_CSV).stat().st_size
              else pd.DataFrame(columns=["step"]) for s in segments]
    plate = merge_table(plates, starts)
    if len(plate):  # no friction coefficient while the plate is out of contact
        plate["mu_w"] = (-plate["f_x"] / plate["f_y"]).where(plate["f_y"] > 0)
    plate.to_csv(drive_dir / PLATE_CSV, index=False)
    profiles = merge_table([read_chunk_file(s / "profiles.txt") for s in segments], starts)
    if len(profiles) and len(plate):  # interrupted before the first profile interval: nothing to assemble yet
        profiles_table(profiles, plate, profile_every, dt, dimension).to_csv(drive_dir / PROFILES_CSV, index=False)
    n_atoms = merge_dump([s / ATOMS for s in segments], starts, drive_dir / ATOMS)
    n_contacts = merge_dump([s / CONTACTS for s in segments], starts, drive_dir / CONTACTS)
    with (drive_dir / LOG).open("w") as log:
        for k, s in enumerate(segments):
            if (s / LOG).exists():
                log.write((s / LOG).read_text())
            if (s / "in.lammps").exists():
                name = "in.lammps" if k == 0 else f"in.resume{k}.lammps"
                (drive_dir / name).write_text((s / "in.lammps").read_text())
    return {"plate_rows": len(plate), "last_step": int(plate["step"].max()) if len(plate) else None,
            "profile_rows": len(profiles), "atom_snapshots": n_atoms, "contact_snapshots": n_contacts}


def plane_stress(drive_dir: Path, planes, area: float) -> pd.DataFrame:
    """Contact stress through horizontal planes (method of planes), one row per plane and snapshot.

    For a plane at height y0, p_yy = (1/A) sum of F_y and tau_xy = -(1/A) sum of F_x over contacts that
    cross it, F the force on the upper grain of the pair (normal fn (dx, dy, dz)/dist plus tangential
    (ft_x, ft_y, ft_z) on grain 1).  In a static region p_yy is exactly p_w plus the weight above per
    area; the kinetic momentum flux is not included.  Needs atom and contact snapshots at the same steps.
    """
    atoms = {step: text for step, text in dump_snapshots(drive_dir / ATOMS)}
    planes = np.asarray(planes, dtype=float)
    rows = []
    for step, text in dump_snapshots(drive_dir / CONTACTS):
        if step not in atoms:
            continue
        y = snapshot_table(atoms[step]).set_index("id")["y"]
        c = snapshot_table(text)
        y1 = y.reindex(c["id1"]).to_numpy()
        y2 = y1 - c["dy"].to_numpy()
        f = c[["dx", "dy"]].to_numpy() * (c["fn"] / c["dist"]).to_numpy()[:, None] + c[["ft_x", "ft_y"]].to_numpy()
        sign = np.where(y1 > y2, 1.0, -1.0)[:, None]  # force on the upper grain
        f_up = sign * f
        lo, hi = np.minimum(y1, y2), np.maximum(y1, y2)
        crossing = (lo[None, :] < planes[:, None]) & (planes[:, None] < hi[None, :])
        rows.append(pd.DataFrame({"step": step, "y": planes, "p_yy": crossing @ f_up[:, 1] / area,
                                  "tau_xy": -(crossing @ f_up[:, 0]) / area}))
    return pd.concat(rows, ignore_index=True) if rows else pd.DataFrame(columns=["step", "y", "p_yy", "tau_xy"])
