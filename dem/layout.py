"""The run-folder format, defined once: written by dem/, read by compare/.

Run folder (``granstokes dem run``)::

    RUN/config.toml                     the config as given (presets: the preset text)
    RUN/run.json                        metadata: status, units, conventions, contact law, sizing, plate, provenance
    RUN/seed-S/prepare/                 prepare.in, log.lammps, prepared.restart, grains.csv (id, type, radius, mass)
    RUN/seed-S/DRIVE/                   plate.csv, profiles.csv, atoms.dump, contacts.dump, log.lammps
    RUN/seed-S/DRIVE/restart/           drive.<step>.restart (latest kept)
    RUN/seed-S/DRIVE/segments/NNN/      raw LAMMPS output of each start/resume (removed once complete)

Calibration folder (``granstokes dem calibrate``)::

    DIR/config.toml                     the config as given (presets: the preset text)
    DIR/calibration.json                the fitted mu(I), phi(I), intervals, bootstrap replicates, grains, provenance
    DIR/points.csv                      one row per steady point and seed (``POINT_COLUMNS``)
    DIR/state.json                      status of every point and seed, messages, timings
    DIR/I-K/seed-S/                     in.lammps, log.lammps, series.csv (``SHEAR_SERIES_COLUMNS``), profile.txt
                                        (u_x in bins across L_y), blocks.csv (``BLOCK_COLUMNS``: block means)
    DIR/finite-size/I-K/seed-S/         the same files of a cell twice as wide (``FINITE_SIZE``: the finite-size check)
    DIR/modulus/seed-S/                 the shear modulus's cell (dem.modulus): in.lammps, log.lammps, static.csv
                                        (``STATIC_COLUMNS``), oscillation-K.csv (``MODULUS_SERIES_COLUMNS``)
    DIR/modulus.png                     G and c_s against p with the affine estimate

Atom types: ``BED`` grains (the coarse-grained material), ``BASE`` (frozen rough base), ``PLATE``
(one rigid body).  Dump columns: ``ATOM_COLUMNS`` (atoms.dump, sorted by id) and ``CONTACT_COLUMNS``
(contacts.dump: every pair closer than r_1 + r_2; (dx, dy, dz) = x_1 - x_2, normal force on grain 1 =
fn (dx, dy, dz)/dist, (ft_x, ft_y, ft_z) the tangential force on grain 1).
"""
from __future__ import annotations

import io
from collections.abc import Iterator
from pathlib import Path

import pandas as pd

# --- atom types ----------------------------------------------------------------------------------
BED, BASE, PLATE = 1, 2, 3
N_TYPES = 3

# --- file names ----------------------------------------------------------------------------------
RUN_JSON, CONFIG_TOML = "run.json", "config.toml"
PREPARE, PREPARED_RESTART, GRAINS_CSV, GRAINS_DUMP = "prepare", "prepared.restart", "grains.csv", "grains.dump"
PLATE_CSV, PROFILES_CSV, ATOMS, CONTACTS, LOG = "plate.csv", "profiles.csv", "atoms.dump", "contacts.dump", "log.lammps"
SEGMENTS, RESTART_DIR = "segments", "restart"
CALIBRATION_JSON, POINTS_CSV, CALIBRATION_STATE = "calibration.json", "points.csv", "state.json"
SHEAR_SERIES_CSV, SHEAR_PROFILE_TXT, SHEAR_IN, BLOCKS_CSV = "series.csv", "profile.txt", "in.lammps", "blocks.csv"
FINITE_SIZE = "finite-size"
MODULUS, STATIC_CSV, MODULUS_PNG = "modulus", "static.csv", "modulus.png"

# --- columns -------------------------------------------------------------------------------------
PLATE_COLUMNS = ("step", "t", "x", "y", "u_x", "u_y", "f_x", "f_y", "u_c", "n_c")
ATOM_COLUMNS = ("id", "type", "x", "y", "z", "vx", "vy", "vz", "radius")
CONTACT_COLUMNS = ("id1", "id2", "dist", "dx", "dy", "dz", "fn", "ft_x", "ft_y", "ft_z")
GRAIN_COLUMNS = ("id", "type", "radius", "mass")
#: calibration: points.csv's columns (its contract with compare), and a point's time series (stresses compressive
#: positive; p_yy_kin the kinetic part of p_yy)
POINT_COLUMNS = ("I", "I_err", "mu", "mu_err", "phi", "phi_err", "p", "strain", "seed")
SHEAR_SERIES_COLUMNS = ("step", "t", "lx", "ly", "xy", "p_xx", "p_yy", "p_xy", "p_yy_kin", "phi", "T")
BLOCK_COLUMNS = ("block", "tau", "p", "phi", "rate", "seed", "point")
#: the modulus cell's oscillation series (ke: kinetic energy per grain, Z: contacts per grain) and its static packing
#: before it (rattlers: the fraction of grains with fewer than 2 contacts)
MODULUS_SERIES_COLUMNS = ("step", "t", "lx", "ly", "xy", "p_xx", "p_yy", "p_xy", "phi", "ke", "Z")
STATIC_COLUMNS = ("step", "t", "ly", "p_xx", "p_yy", "p_xy", "phi", "Z", "rattlers", "ke")

#: profile bin height in d (LAMMPS in-run chunk averages, profiles.csv)
PROFILE_BIN = 1.0


def seed_dir(run: Path, seed: int) -> Path:
    return Path(run) / f"seed-{seed}"


def drive_dir(run: Path, seed: int, drive: str) -> Path:
    return seed_dir(run, seed) / drive


def prepare_dir(run: Path, seed: int) -> Path:
    return seed_dir(run, seed) / PREPARE


def point_dir(folder: Path, index: int, seed: int) -> Path:
    """Folder of calibration point ``index`` (0-based, increasing I) and seed."""
    return Path(folder) / f"I-{index}" / f"seed-{seed}"


def modulus_dir(folder: Path, seed: int) -> Path:
    """Folder of the calibration's modulus cell of ``seed``."""
    return Path(folder) / MODULUS / f"seed-{seed}"


def modulus_series_csv(k: int) -> str:
    """The modulus cell's series at its ``k``-th amplitude."""
    return f"oscillation-{k}.csv"


def stage_key(seed: int, drive: str | None = None) -> str:
    """run.json's key of a stage: ``seed-S`` (preparation) or ``seed-S/DRIVE``."""
    return f"seed-{seed}" if drive is None else f"seed-{seed}/{drive}"


def plate_surface(plate_y, offset: float):
    """Height of the plate's contact plane: the plate's centre-of-mass height minus ``offset``
    (run.json ``plate.surface_offset``, set by the scene that built the plate)."""
    return plate_y - offset


def dump_snapshots(path: Path) -> Iterator[tuple[int, str]]:
    """(step, text) of each snapshot of a LAMMPS text dump, in file order."""
    if not Path(path).exists():
        return
    with Path(path).open() as fh:
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


def snapshot_table(text: str) -> pd.DataFrame:
    """One dump snapshot's rows as a table named by its ``ITEM: ATOMS``/``ENTRIES`` header."""
    header, body = text.split("ITEM: ", 4)[-1].split("\n", 1)
    return pd.read_csv(io.StringIO(body), sep=r"\s+", names=header.split()[1:], index_col=False)


def grains_table(folder: Path) -> pd.DataFrame:
    """The per-grain table (``GRAIN_COLUMNS``) of a drive or prepare folder: grains.csv, else the
    LAMMPS ``write_dump`` text grains.dump, here or in ../prepare/."""
    folder = Path(folder)
    for p in (folder / GRAINS_CSV, folder / GRAINS_DUMP, folder.parent / PREPARE / GRAINS_CSV,
              folder.parent / PREPARE / GRAINS_DUMP):
        if p.exists():
            if p.suffix == ".csv":
                return pd.read_csv(p)
            return snapshot_table(next(t for _, t in dump_snapshots(p)))
    raise FileNotFoundError(f"{folder}: no grains table ({GRAINS_CSV} or {GRAINS_DUMP} here or in ../{PREPARE}/): "
                            "needed for the grain masses and radii")
