"""Input validation shared by every package: one ``ValueError`` naming the parameter and its valid
range, which the command line prints as one line with exit status 2 (granstokes.cli)."""
from __future__ import annotations

import math

import numpy as np


def require(ok: bool, name: str, valid: str, value) -> None:
    """Raise ``ValueError`` naming the parameter and its valid range unless ``ok``."""
    if not ok:
        raise ValueError(f"{name} must be {valid}, got {value!r}")


def finite(x) -> bool:
    """A real, finite number (bools excluded)."""
    return (isinstance(x, (int, float, np.floating, np.integer)) and not isinstance(x, bool)
            and math.isfinite(float(x)))
