from pathlib import Path

import numpy as np
import pytest
from granstokes.continuum.rheology import Friction


@pytest.fixture(scope="session")
def paper_friction():
    """The paper's glass beads: mu_s = tan 21 deg, mu_d = tan 33 deg."""
    return Friction(np.tan(np.radians(21.0)), np.tan(np.radians(33.0)))


@pytest.fixture(scope="session")
def smoke_run(tmp_path_factory):
    """One smoke DEM run (granstokes dem run --preset smoke) shared by the slow compare tests."""
    from granstokes.cli import main

    run = tmp_path_factory.mktemp("smoke") / "run"
    assert main(["dem", "run", "--preset", "smoke", "--out", str(run), "--quiet"]) == 0
    return run


@pytest.fixture(scope="session")
def smoke_calibration():
    """The committed plane-shear calibration of the quick preset's grains, which the smoke preset shares."""
    return Path(__file__).resolve().parents[1] / "results" / "quick-calibration" / "calibration.json"


@pytest.fixture(scope="session", autouse=True)
def canned_speed(tmp_path_factory):
    """A probe of this machine's LAMMPS speed, canned in a private cache: the tests' cost estimates and task
    orders never start a probe or touch the user's ~/.cache (the probe's own tests call it explicitly)."""
    import dataclasses
    import json
    import time

    from granstokes.dem import throughput

    cache = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("XDG_CACHE_HOME", str(cache))
        rates = {str(d): {k: r * 1e7 for k, r in throughput.PHASE_RATIO[d].items()} for d in (2, 3)}
        speed = throughput.Throughput(rates, 1.5, {"2": 1e7, "3": 1e7}, throughput._host(), "canned", time.time())
        path = throughput.cache_path()
        path.parent.mkdir(parents=True)
        path.write_text(json.dumps(dataclasses.asdict(speed)))
        yield speed
