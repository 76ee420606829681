"""granstokes: Stokes' first problem in a dense granular medium, mu(I) and nonlocal continuum models
cross-validated against LAMMPS DEM.  This package is the thin layer on top of ``continuum``, ``dem``
and ``compare``: the command line, the demo, and what all three share (validation, provenance, the
HTML page shell).  It imports none of them at import time."""
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("granstokes")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"
