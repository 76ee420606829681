import numpy as np
import pytest

from continuum.rheology import Friction


@pytest.fixture(scope="session")
def paper_friction():
    """The paper's glass beads: mu_s = tan 21 deg, mu_d = tan 33 deg."""
    return Friction(np.tan(np.radians(21.0)), np.tan(np.radians(33.0)))
