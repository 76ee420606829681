"""Drive folders of dem/ runs: metadata, per-grain table, and the atom and contact dumps streamed snapshot
by snapshot (never a whole trajectory in memory).  The folder layout, file names, dump columns and atom
types are dem.layout's.  A *drive folder* is RUN/seed-K/DRIVE (any folder holding atoms.dump).

Reading and precision.  Atom snapshots go through MDAnalysis (``format="LAMMPSDUMP"``), which parses
positions and velocities as float32 and shifts positions by the box's lower corner.  ``Frame`` holds
float64 copies with the corner added back (positions to within 2^-24 |y|, about 4e-6 d at y = 60:
negligible against kernel widths >= 0.05 d).  Everything where float32 would matter comes from float64
sources instead: radius and mass from the grains table (so mass integrals hold to round-off), and the
contact geometry (dist, branch vector) and forces from contacts.dump read by pandas: overlaps are ~1e-4 d
(kappa = 1e4), so a branch vector rebuilt from float32 positions would carry percent-level errors.

Truncation.  Both dumps are indexed by a byte scan for ``ITEM: TIMESTEP``; a snapshot counts only when
its header is complete and its rows are all there, newline-terminated, with a full last row.  A cut-off
tail is dropped with a ``warnings.warn`` naming the file and the last whole step.
"""
from __future__ import annotations

import io
import json
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.dem.layout import (
    ATOMS,
    CONTACT_COLUMNS,
    CONTACTS,
    PLATE_CSV,
    PROFILES_CSV,
    RUN_JSON,
    SEGMENTS,
    grains_table,
)

_MARK = b"ITEM: TIMESTEP"
_CHUNK = 1 << 24


@dataclass(frozen=True)
class DumpIndex:
    """Whole snapshots of a LAMMPS text dump: byte ranges [start, end), steps, row counts, box bounds
    (rows of (lo, hi) per axis), and the column names of the ``ITEM: ATOMS/ENTRIES`` line."""

    path: Path
    steps: np.ndarray
    start: np.ndarray
    end: np.ndarray
    rows: np.ndarray
    box: np.ndarray  # (n, 3, 2)
    columns: tuple
    dropped: int = 0  # trailing snapshots cut off (a truncated or partly written dump)

    def __len__(self) -> int:
        return len(self.steps)

    def position(self, step: int) -> int | None:
        """Snapshot number of ``step``, or None if the dump has no whole snapshot at that step."""
        k = int(np.searchsorted(self.steps, step))
        return k if k < len(self.steps) and self.steps[k] == step else None

    def table(self, k: int) -> pd.DataFrame:
        """Snapshot ``k`` as a float64/int64 table (pandas), read from its byte range only."""
        with self.path.open("rb") as fh:
            fh.seek(int(self.start[k]))
            text = fh.read(int(self.end[k] - self.start[k]))
        body = text.split(b"\n", 9)[9]
        return pd.read_csv(io.BytesIO(body), sep=r"\s+", names=list(self.columns), index_col=False,
                           header=None)


def _marks(path: Path) -> list[int]:
    """Byte offsets of the ``ITEM: TIMESTEP`` lines (chunked C-speed scan for newline + marker)."""
    mark = b"\n" + _MARK
    offsets, base, tail = [], 0, b"\n"  # the file start counts as a line start
    with path.open("rb") as fh:
        while chunk := fh.read(_CHUNK):
            buf = tail + chunk
            at = buf.find(mark)
            while at >= 0:
                offsets.append(base - len(tail) + at + 1)
                at = buf.find(mark, at + 1)
            tail = buf[-len(mark) + 1:] if len(buf) >= len(mark) else buf
            base += len(chunk)
    return sorted(set(offsets))


def index_dump(path) -> DumpIndex:
    """Index the whole snapshots of a LAMMPS text dump (atoms or local); warns if the tail is cut off.
    Raises ``ValueError`` if there is no whole snapshot."""
    path = Path(path)
    size = path.stat().st_size
    offsets = _marks(path) + [size]
    steps, start, end, rows, boxes, columns = [], [], [], [], [], None
    last_ok = None
    with path.open("rb") as fh:
        for a, b in zip(offsets[:-1], offsets[1:]):
            fh.seek(a)
            block = fh.read(b - a)
            lines = block.split(b"\n", 9)
            try:
                step, n = int(lines[1]), int(lines[3])
                box = np.array([[float(v) for v in lines[5 + i].split()[:2]] for i in range(3)])
                cols = tuple(lines[8].decode().split()[2:])
            except (IndexError, ValueError):
                break
            body = lines[9] if len(lines) > 9 else b""
            last = body[:-1].rsplit(b"\n", 1)[-1]
            whole = (block.endswith(b"\n") and body.count(b"\n") == n
                     and (n == 0 or len(last.split()) == len(cols)))
            if not whole:
                break
            columns = columns or cols
            steps.append(step), start.append(a), end.append(b), rows.append(n), boxes.append(box)
            last_ok = step
    dropped = max(len(offsets) - 1 - len(steps), 1 if (len(offsets) == 1 and size) else 0)
    if dropped:
        where = f"last whole snapshot at step {last_ok}" if last_ok is not None else "no whole snapshot"
        warnings.warn(f"{path}: truncated or partly written dump, read up to the last whole snapshot "
                      f"({where}); {dropped} trailing snapshot(s) dropped", stacklevel=2)
    if not steps:
        raise ValueError(f"{path}: no whole snapshot in the dump")
    return DumpIndex(path, np.array(steps, dtype=np.int64), np.array(start, dtype=np.int64),
                     np.array(end, dtype=np.int64), np.array(rows, dtype=np.int64), np.array(boxes), columns,
                     dropped)


@dataclass(frozen=True)
class Frame:
    """One atom snapshot in float64, sorted by id: positions ``x`` (N, 3) in the box frame (box lower
    corner added back), velocities ``v`` (N, 3), and per-grain ``ids``, ``types``, ``radius``, ``mass``
    (from the grains table); ``box`` (3, 2) lo/hi bounds; ``t`` = step dt."""

    step: int
    t: float
    ids: np.ndarray
    types: np.ndarray
    x: np.ndarray
    v: np.ndarray
    radius: np.ndarray
    mass: np.ndarray
    box: np.ndarray


class DriveFolder:
    """One drive of one seed: metadata, grains, plate and LAMMPS profile tables, and snapshot streams.

    ``DriveFolder(path)`` checks that atoms.dump, contacts.dump and a grains table exist (else
    ``FileNotFoundError`` naming the folder and the missing file) and reads run.json from the run
    folder two levels up.  ``dimension``, ``dt``, ``d`` and ``rho_p`` default to run.json's values and
    may be given explicitly (then run.json is optional).

    Attributes: ``path``, ``name`` (seed-K/DRIVE), ``meta`` (run.json dict or {}), ``dimension``, ``dt``,
    ``d`` (mean diameter, the length unit), ``rho_p``, ``p_w``, ``grains`` (DataFrame id, type, radius,
    mass, indexed by id), ``atoms`` and ``contacts`` (``DumpIndex``).  Methods: ``universe()``,
    ``frame(k)``, ``frames(indices)``, ``contacts_at(step)``, ``plate()``, ``lammps_profiles()``,
    ``frames_between(t0, t1)``.
    """

    def __init__(self, path, dimension: int | None = None, dt: float | None = None, d: float | None = None,
                 rho_p: float | None = None):
        self.path = Path(path)
        if not self.path.is_dir():
            raise FileNotFoundError(f"drive folder {self.path} does not exist")
        for name in (ATOMS, CONTACTS):
            if not (self.path / name).exists():
                raise FileNotFoundError(f"drive folder {self.path}: no {name} (the coarse-graining needs both "
                                        f"{ATOMS} and {CONTACTS}; was the drive run with outputs?)")
        run_json = self.path.parent.parent / RUN_JSON
        self.meta = json.loads(run_json.read_text()) if run_json.exists() else {}
        cfg = self.meta.get("config", {})
        self.dimension = int(dimension or cfg.get("grains", {}).get("dimension", 0))
        self.dt = float(dt or self.meta.get("sizing", {}).get("dt", 0.0))
        if self.dimension not in (2, 3) or not self.dt > 0:
            raise ValueError(f"drive folder {self.path}: dimension (2 or 3) and dt (> 0) are needed: "
                             f"no run.json at {run_json}; pass dimension= and dt=")
        material = cfg.get("material", {})
        self.d = float(d or material.get("d", 1.0))
        self.rho_p = float(rho_p or material.get("rho_p", 1.0))
        self.p_w = cfg.get("p_w")
        self.name = f"{self.path.parent.name}/{self.path.name}"
        self.grains = grains_table(self.path).set_index("id").sort_index()
        self.atoms = index_dump(self.path / ATOMS)
        self.contacts = index_dump(self.path / CONTACTS)
        if self.contacts.columns != CONTACT_COLUMNS:
            raise ValueError(f"{self.path / CONTACTS}: columns {self.contacts.columns}, expected {CONTACT_COLUMNS}")

    def universe(self):
        """MDAnalysis Universe on atoms.dump (all snapshots in the file; use ``len(self.atoms)`` whole ones)."""
        import MDAnalysis as mda

        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="Guessed all Masses")
            return mda.Universe(str(self.path / ATOMS), format="LAMMPSDUMP", dt=self.dt)

    def times(self) -> np.ndarray:
        """Times of the whole atom snapshots (step dt)."""
        return self.atoms.steps * self.dt

    def frames_between(self, t0: float, t1: float) -> list[int]:
        """Indices of the whole atom snapshots with t0 <= t <= t1."""
        t = self.times()
        return [int(k) for k in np.flatnonzero((t >= t0 - 1e-9) & (t <= t1 + 1e-9))]

    def frames(self, indices=None):
        """Yield ``Frame`` for each whole atom snapshot in ``indices`` (default: all), streaming."""
        u = self.universe()
        for k in range(len(self.atoms)) if indices is None else indices:
            yield self.frame_from(u, int(k))

    def frame_from(self, u, k: int) -> Frame:
        """Snapshot ``k`` of Universe ``u`` as a ``Frame``."""
        if not 0 <= k < len(self.atoms):
            raise IndexError(f"{self.path / ATOMS}: snapshot {k} is not one of the {len(self.atoms)} whole ones")
        ts = u.trajectory.ts if u.trajectory.ts.frame == k else u.trajectory[k]
        ids, types, radius, mass = self._per_grain(u)
        box = self.atoms.box[k]
        return Frame(step=int(self.atoms.steps[k]), t=float(self.atoms.steps[k] * self.dt), ids=ids, types=types,
                     x=ts.positions.astype(np.float64) + box[:, 0], v=ts.velocities.astype(np.float64),
                     radius=radius, mass=mass, box=box)

    def _per_grain(self, u) -> tuple:
        """Sorted ids (MDAnalysis orders each snapshot by atom id) and their type, radius, mass (float64)."""
        if getattr(self, "_grain_arrays", (None,))[0] is not u:
            ids = np.sort(u.atoms.ids)
            g = self.grains.reindex(ids)
            if g["mass"].isna().any():
                raise ValueError(f"{self.path}: atom ids missing from the grains table")
            self._grain_arrays = (u, ids, g["type"].to_numpy(np.int64), g["radius"].to_numpy(np.float64),
                                  g["mass"].to_numpy(np.float64))
        return self._grain_arrays[1:]

    def contacts_at(self, step: int) -> pd.DataFrame | None:
        """The contact table (float64) written at ``step``, or None if contacts.dump has none there."""
        k = self.contacts.position(step)
        return None if k is None else self.contacts.table(k)

    def plate(self) -> pd.DataFrame:
        """plate.csv: step, t, x, y, u_x, u_y, f_x, f_y (force of the bed on the plate per area), mu_w."""
        return pd.read_csv(self.path / PLATE_CSV)

    def lammps_profiles(self) -> pd.DataFrame:
        """profiles.csv: LAMMPS in-run 1 d bin averages (see dem/outputs.py)."""
        return pd.read_csv(self.path / PROFILES_CSV)


def find_drives(*paths, **kwargs) -> list[DriveFolder]:
    """Drive folders under ``paths`` (run folders, seed folders or drive folders): every folder holding
    atoms.dump, except the raw per-segment outputs of an unfinished run (``DRIVE/segments/NNN``, see
    dem/runner.py), sorted by path; ``kwargs`` go to ``DriveFolder``.  ``FileNotFoundError`` if none."""
    found = []
    for p in map(Path, paths):
        found += [p] if (p / ATOMS).exists() else sorted(q.parent for q in p.glob(f"**/{ATOMS}")
                                                         if SEGMENTS not in q.relative_to(p).parts)
    if not found:
        raise FileNotFoundError(f"no drive folder ({ATOMS}) under {', '.join(map(str, paths))}")
    return [DriveFolder(p, **kwargs) for p in sorted(set(found))]
