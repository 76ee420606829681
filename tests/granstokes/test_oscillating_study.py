"""The oscillating plate end to end: ``granstokes study --preset oscillating-smoke`` (cut to one bed and one
frequency, predicted from the committed calibration of its grains: the calibration stage is the Stokes study's
test's) runs its beds and the oscillation comparison; the plate of the speed drive follows the imposed u_w(t)
within 1 %; metrics.json's rows and drives carry omega, amplitude and the phase lag."""
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from granstokes.cli import main as granstokes_main

pytestmark = pytest.mark.slow

#: the smoke grains' plane-shear calibration (the quick preset's grains)
CALIBRATION = Path(__file__).resolve().parents[2] / "results" / "quick-calibration" / "calibration.json"
OMEGA_TS = 8.0
#: a bed half the preset's width: the plate's tracking and the rows' keys do not depend on it, the run takes half
SMALL = ["seeds=[1]", f"omega_ts=[{OMEGA_TS}]", "cycles=3", "width=10", f'calibration={{file = "{CALIBRATION}"}}']
#: the plate's x speed within this fraction of the imposed amplitude
TRACKING = 0.01


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("osc") / "study"
    args = ["study", "--preset", "oscillating-smoke", "--out", str(out), "--jobs", "2", "--quiet"]
    assert granstokes_main(args + [x for s in SMALL for x in ("--set", s)]) == 0
    return out


def test_the_plate_follows_the_imposed_speed(study):
    run = study / "runs" / f"p20-w{OMEGA_TS:g}"
    meta = json.loads((run / "run.json").read_text())
    (drive,) = [d for d in meta["sizing"]["drives"] if d["kind"] == "speed"]
    dt, every, sample = meta["sizing"]["dt"], *(meta["sizing"]["intervals_steps"][k] for k in ("plate", "sample"))
    plate = pd.read_csv(run / "seed-1" / drive["name"] / "plate.csv")
    plate = plate[plate.step > 0]
    # each row averages the samples every `sample` steps over the interval ending at its step
    steps = plate.step.to_numpy()[:, None] - np.arange(0, every, sample)[None, :]
    expected = drive["u_w"] * np.sin(drive["omega"] * steps * dt).mean(axis=1)
    assert drive["omega"] > 0 and len(plate) > 100
    assert np.max(np.abs(plate.u_x - expected)) < TRACKING * drive["u_w"]


def test_the_stress_drive_moves_the_plate_behind_the_stress(study):
    metrics = json.loads((study / "metrics.json").read_text())
    rows = pd.DataFrame(metrics["scorecard"])
    stress = rows[(rows.kind == "stress") & (rows.model == "local")].set_index("observable")
    assert stress.loc["response_amplitude", "dem"] > 0.1  # tau_a > mu_s p_w: the plate moves
    assert 0 < stress.loc["phase_lag", "dem"] < np.pi / 2  # and its speed lags the stress


def test_rows_and_drives_carry_the_frequency_amplitude_and_lag(study):
    metrics = json.loads((study / "metrics.json").read_text())
    assert metrics["problem"].startswith("oscillating plate")
    assert len(metrics["scorecard"]) == 2 * 5 * 2  # drives x observables x models (NGF not predicted: no A)
    for row in metrics["scorecard"]:
        assert {"drive", "observable", "dem", "dem_err", "model", "predicted", "sigma", "verdict", "omega",
                "amplitude", "phase_lag"} <= set(row)
        assert row["omega"] > 0 and row["amplitude"] > 0
    for drive in metrics["drives"].values():
        assert drive["omega"] > 0 and drive["amplitude"] > 0 and drive["omega_ts"] == pytest.approx(OMEGA_TS, rel=1e-6)
    record = json.loads((study / "study.json").read_text())
    assert record["status"] == "complete"
    assert (study / "index.html").exists() and (study / "map.png").exists()
