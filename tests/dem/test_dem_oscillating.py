"""Oscillating drives in a 3D scene (the spheres preset, a shallow bed): the plate follows an imposed
u_w(t) = u_w sin(omega t) within 1 % through its tracking force, and an oscillating stress above the yield stress
moves it back and forth; the scripts carry the time-dependent force."""
import json

import numpy as np
import pandas as pd
import pytest

from granstokes.cli import main as granstokes_main

pytestmark = pytest.mark.slow

OMEGA, U_W = 4.0, 1.0
DRIVES = (f'drive=[{{name = "w", kind = "speed", u_w = {U_W}, omega = {OMEGA}, cycles = 2}}, '
          f'{{name = "s", kind = "stress", mu_w_tilde = 0.5, omega = {OMEGA}, cycles = 2}}]')


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("dem3d") / "run"
    args = ["dem", "run", "--preset", "spheres", "--set", DRIVES, "--set", "box.depth=6.0", "--set", "seeds=[1]",
            "--out", str(out), "--quiet"]
    assert granstokes_main(args) == 0
    return out


def test_the_3d_plate_follows_the_imposed_speed(run):
    meta = json.loads((run / "run.json").read_text())
    dt, every, sample = meta["sizing"]["dt"], *(meta["sizing"]["intervals_steps"][k] for k in ("plate", "sample"))
    plate = pd.read_csv(run / "seed-1" / "w" / "plate.csv")
    plate = plate[plate.step > 0]
    steps = plate.step.to_numpy()[:, None] - np.arange(0, every, sample)[None, :]
    expected = U_W * np.sin(OMEGA * steps * dt).mean(axis=1)
    assert np.max(np.abs(plate.u_x - expected)) < 0.01 * U_W
    assert "compute plate_pull plate reduce sum fx" in (run / "seed-1" / "w" / "in.lammps").read_text()


def test_the_3d_oscillating_stress_moves_the_plate_both_ways(run):
    script = (run / "seed-1" / "s" / "in.lammps").read_text()
    assert f"*sin({OMEGA:.10g}*step*" in script and "fix load plate addforce v_fx_plate" in script
    plate = pd.read_csv(run / "seed-1" / "s" / "plate.csv")
    second = plate[plate.t > 2 * np.pi / OMEGA]  # the second period
    assert second.u_x.max() > 0.1 and second.u_x.min() < -0.1
    # the friction the bed exerts follows the load's sign: positive while the plate moves forward
    assert np.corrcoef(second.u_x, second.mu_w)[0, 1] > 0.5
