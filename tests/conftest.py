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
