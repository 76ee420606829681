"""Output files of a drive, assembled from its LAMMPS segments (one per start or resume).

Segment k starts at step S_k (the prepared bed, or the restart it resumed from) and is valid up to
S_(k+1): whatever it wrote after that restart is dropped (it was redone by segment k+1), and every
step appears once.  Files (all under the drive folder):

* ``plate.csv``: step, t, x (unwrapped), y, u_x, u_y, f_x, f_y (force of the bed on the plate per
  plate area), mu_w = -f_x/f_y;
* ``atoms.dump``: LAMMPS text dump (id type x y z vx vy vz radius), sorted by id;
* ``contacts.dump``: LAMMPS local dump, one line per contact (r < r_1 + r_2, plate and base
  contacts included): id1 id2 dist dx dy dz fn ft_x ft_y ft_z, (dx, dy, dz) = x_1 - x_2 (branch
  vector), normal force on grain 1 = fn (dx, dy, dz)/dist, (ft_x, ft_y, ft_z) the tangential force
  (``pair granular`` single() values);
* ``profiles.csv``: 1 d bins in y, averaged over each output interval: step, t, y, count, n (number
  density), phi, u_x, p = -(s_xx + s_yy [+ s_zz])/D and tau = -s_xy (contact stress, kinetic part
  excluded), s_xx, s_yy, s_zz, s_xy.
"""
from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import pandas as pd

PROFILE_RAW = ["chunk", "y", "count", "n", "volume", "u_x", "s_xx", "s_yy", "s_zz", "s_xy"]


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


def _snapshots(path: Path):
    """Yield (step, text) of each snapshot of a LAMMPS text dump."""
    if not path.exists():
        return
    with path.open() as fh:
        block, step = [], None
        for line in fh:
            if line.startswith("ITEM: TIMESTEP"):
                if block:
                    yield step, "".join(block)
                block = [line]
                step = int(next(fh))
                block.append(f"{step}\n")
                continue
            block.append(line)
        if block:
            yield step, "".join(block)


def merge_dump(paths: list[Path], starts: list[int], target: Path) -> int:
    """Write the valid snapshots of per-segment dumps to ``target``; returns their number."""
    n, last = 0, -math.inf
    with target.open("w") as out:
        for path, hi in zip(paths, _ranges(starts)):
            for step, text in _snapshots(path):
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


def profiles_table(raw: pd.DataFrame, dt: float, dimension: int) -> pd.DataFrame:
    """Per-volume fields from per-atom chunk averages (value per volume = atom average x n)."""
    n = raw["n"]
    trace = raw["s_xx"] + raw["s_yy"] + (raw["s_zz"] if dimension == 3 else 0.0)
    return pd.DataFrame({
        "step": raw["step"].astype(int), "t": raw["step"] * dt, "y": raw["y"], "count": raw["count"], "n": n,
        "phi": raw["volume"] * n, "u_x": raw["u_x"], "p": -trace / dimension * n, "tau": -raw["s_xy"] * n,
        "s_xx": raw["s_xx"] * n, "s_yy": raw["s_yy"] * n, "s_zz": raw["s_zz"] * n, "s_xy": raw["s_xy"] * n,
    })


def merge_drive(drive_dir: Path, segments: list[Path], starts: list[int], dt: float, dimension: int) -> dict:
    """Assemble the drive's output files from its segments; returns a summary for run.json."""
    plates = [pd.read_csv(s / "plate.csv") if (s / "plate.csv").exists() else pd.DataFrame(columns=["step"])
              for s in segments]
    plate = merge_table(plates, starts)
    if len(plate):
        with np.errstate(divide="ignore", invalid="ignore"):
            plate["mu_w"] = -plate["f_x"] / plate["f_y"]
    plate.to_csv(drive_dir / "plate.csv", index=False)
    profiles = merge_table([read_chunk_file(s / "profiles.txt") for s in segments], starts)
    profiles_table(profiles, dt, dimension).to_csv(drive_dir / "profiles.csv", index=False)
    n_atoms = merge_dump([s / "atoms.dump" for s in segments], starts, drive_dir / "atoms.dump")
    n_contacts = merge_dump([s / "contacts.dump" for s in segments], starts, drive_dir / "contacts.dump")
    with (drive_dir / "log.lammps").open("w") as log:
        for s in segments:
            if (s / "log.lammps").exists():
                log.write((s / "log.lammps").read_text())
    return {"plate_rows": len(plate), "last_step": int(plate["step"].max()) if len(plate) else None,
            "profile_rows": len(profiles), "atom_snapshots": n_atoms, "contact_snapshots": n_contacts}


def grains_table(dump: Path) -> pd.DataFrame:
    """The one-off per-grain table (id, type, radius, mass) from ``write_dump`` text."""
    text = dump.read_text().split("ITEM: ATOMS", 1)[1]
    header, body = text.split("\n", 1)
    return pd.read_csv(io.StringIO(body), sep=r"\s+", names=header.split())
