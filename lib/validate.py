"""Input validation shared by every package: one ``ValueError`` naming the parameter and its valid
range, which the command line prints as one line with exit status 2 (granstokes.cli)."""
from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np


def require(ok: bool, name: str, valid: str, value) -> None:
    """Raise ``ValueError`` naming the parameter and its valid range unless ``ok``."""
    if not ok:
        raise ValueError(f"{name} must be {valid}, got {value!r}")


def finite(x) -> bool:
    """A real, finite number (bools excluded)."""
    return (isinstance(x, (int, float, np.floating, np.integer)) and not isinstance(x, bool)
            and math.isfinite(float(x)))


def output_dir(path, name: str) -> Path:
    """``path`` as an output folder: not an existing file, and creatable (its nearest existing
    ancestor is a writable folder).  Checked before any work; nothing is created here."""
    path = Path(path)
    require(not path.exists() or path.is_dir(), name, "a folder (this path is an existing file)", str(path))
    ancestor = path
    while not ancestor.exists():
        ancestor = ancestor.parent
    require(ancestor.is_dir() and _can_write(ancestor), name,
            f"a folder that can be created (cannot write in {ancestor})", str(path))
    return path


def _can_write(folder: Path) -> bool:
    """Whether a file can be created in ``folder`` (tried: permissions alone say yes to root in /proc)."""
    try:
        with tempfile.TemporaryFile(dir=folder):
            return True
    except OSError:
        return False


def output_file(path, name: str, suffix: str) -> Path:
    """``path`` as a new output file with ``suffix`` whose folder can be created: not an existing folder,
    and not an existing file (or link), which granstokes never replaces."""
    path = Path(path)
    require(path.suffix.lower() == suffix, name, f"a file name ending in {suffix}", str(path))
    require(not path.is_dir(), name, "a file (this path is an existing folder)", str(path))
    require(not os.path.lexists(path), name, "a file that does not exist yet (granstokes replaces no file)",
            str(path))
    output_dir(path.parent, name)
    return path


def read_json(path, name: str, keys, what: str) -> dict:
    """A JSON object from ``path`` holding ``keys``; a one-line error naming ``name`` and the file otherwise."""
    path = Path(path)
    require(path.is_file(), name, f"an existing file: {what}", str(path))
    try:
        doc = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise ValueError(f"{name} must be {what}; {path} is not JSON ({err})") from None
    missing = [k for k in keys if not isinstance(doc, dict) or k not in doc]
    require(not missing, name, f"{what} with keys {list(keys)}", f"{path} lacks {missing}")
    return doc
