"""granstokes: Stokes' first problem in a dense granular medium, mu(I) and nonlocal continuum models
cross-validated against LAMMPS DEM.  This package is the thin layer on top of ``continuum``, ``dem``
and ``compare``: the command line, the demo, and what all three share (validation, provenance, the
HTML page shell).  It imports none of them at import time."""

def __getattr__(name):
    """``__version__``, looked up on first use (importlib.metadata costs a start-up 20-80 ms)."""
    if name != "__version__":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from importlib.metadata import PackageNotFoundError, version

    try:
        value = version("granstokes")
    except PackageNotFoundError:  # running from a source tree that is not installed
        value = "0+unknown"
    globals()["__version__"] = value
    return value
