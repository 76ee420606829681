"""granstokes dem calibrate: the [calibration] table, the plan, bad input, and the smoke calibration
through LAMMPS (the CI check)."""
import json

import numpy as np
import pandas as pd
import pytest
from granstokes.dem import config, layout
from granstokes.dem.calibrate import plan_calibration

from granstokes.cli import main as granstokes_main


def test_calibration_table_is_validated_before_anything_runs():
    text = config.preset_text("smoke")
    with pytest.raises(ValueError, match="^calibration.strain must be"):
        config.parse(text.replace("width = 10.0\n", "width = 10.0\nstrain = 2.0\n"))
    with pytest.raises(ValueError, match="^calibration.I_max must be"):
        config.parse(text.replace("I_max = 0.3", "I_max = 0.01"))
    with pytest.raises(ValueError, match=r"^\[calibration\] keys must be"):
        config.parse(text.replace("width = 10.0\n", "width = 10.0\nwalls = 2\n"))
    listed = text.replace("I_min = 0.02\nI_max = 0.3\npoints = 4\n", "I = [0.02, 0.05, 0.3]\n")
    assert config.parse(listed).calibration.inertial_numbers == (0.02, 0.05, 0.3)
    for bad in ("[0.02, 0.3]", "[0.05, 0.02, 0.3]", "[0.02, 0.05, 1.5]", "[0.02, 0.05, \"a\"]", "0.1"):
        with pytest.raises(ValueError, match="^calibration.I must be"):
            config.parse(listed.replace("[0.02, 0.05, 0.3]", bad))
    with pytest.raises(ValueError, match=r"^calibration.I must be given without \['points'\]"):
        config.parse(listed.replace("I = [", "points = 3\nI = ["))


def test_plan_follows_the_table_and_measures_at_least_the_strain():
    smoke, _ = config.preset("smoke")
    I = np.array([p.I for p in plan_calibration(smoke).points])
    assert I[0] == pytest.approx(0.02) and I[-1] == pytest.approx(0.3) and len(I) == 4
    assert np.allclose(np.diff(np.log(I)), np.log(I[1] / I[0]))  # log-spaced in [I_min, I_max]
    cfg, _ = config.preset("quick")
    plan = plan_calibration(cfg)
    I = np.array([p.I for p in plan.points])  # the listed I: >= 8 points over >= 2.5 decades
    assert list(I) == list(cfg.calibration.I) and len(I) >= 8 and np.log10(I[-1] / I[0]) >= 2.5
    for p in plan.points:
        assert p.rate == pytest.approx(p.I * np.sqrt(cfg.p_w))  # I_dem = gamma_dot d / sqrt(p / rho_p)
        assert p.measure_steps * p.rate * p.dt >= cfg.calibration.strain
        assert p.dt == cfg.time_step and p.measure_steps % p.profile == 0 and p.profile % p.sample == 0
    # longest (smallest I) first, each seed of a point together
    seeds = list(cfg.calibration.seeds)
    assert plan.tasks()[0][0] == 0 and [s for _, s in plan.tasks()[:len(seeds)]] == seeds


def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "cal"
    assert granstokes_main(["dem", "calibrate", "--preset", "smoke", "--out", str(out), "--jobs", "0"]) == 2
    assert "--jobs must be an integer >= 1" in capsys.readouterr().err
    assert not out.exists()
    assert granstokes_main(["dem", "calibrate", "--preset", "smoke", "--out", str(out), "--resume"]) == 2
    assert not out.exists()


@pytest.fixture(scope="module")
def smoke(tmp_path_factory):
    out = tmp_path_factory.mktemp("cal") / "smoke"
    assert granstokes_main(["dem", "calibrate", "--preset", "smoke", "--out", str(out), "--quiet"]) == 0
    return out


@pytest.mark.slow
def test_smoke_calibration_files_follow_the_contract(smoke):
    doc = json.loads((smoke / layout.CALIBRATION_JSON).read_text())
    for key in ("mu_s", "mu_d", "I0", "I_convention", "ci95", "linear", "phi", "replicates", "grains", "provenance"):
        assert key in doc
    assert doc["I_convention"] == "dem" and set(doc["ci95"]) == {"mu_s", "mu_d", "I0"}
    assert set(doc["linear"]) >= {"mu_1", "b", "ci95"} and set(doc["phi"]) >= {"phi_max", "a", "ci95"}
    assert set(doc["replicates"]) == {"mu_s", "mu_d", "I0", "phi_max", "a"}
    assert len({len(v) for v in doc["replicates"].values()}) == 1 and len(doc["replicates"]["mu_s"]) >= 100
    cfg, _ = config.preset("smoke")
    assert doc["grains"] == json.loads(json.dumps(cfg.as_dict()["grains"]))
    assert doc["provenance"]["seeds"] == [1] and doc["provenance"]["lammps_version"] > 0
    for name in ("mu_s", "mu_d", "I0"):
        lo, hi = doc["ci95"][name]
        assert lo <= doc[name] <= hi
    points = pd.read_csv(smoke / layout.POINTS_CSV)
    assert tuple(points.columns) == layout.POINT_COLUMNS and len(points) == 4


@pytest.mark.slow
def test_smoke_points_are_steady_and_at_the_imposed_pressure(smoke):
    """Every point passed the strain and drift checks, and the bulk sigma_yy equals the imposed p
    within 3 of its standard errors (block errors)."""
    cfg, _ = config.preset("smoke")
    state = json.loads((smoke / layout.CALIBRATION_STATE).read_text())
    assert state["status"] == "complete" and len(state["points"]) == 4
    for entry in state["points"].values():
        ch = entry["checks"]
        assert ch["strain"] >= cfg.calibration.strain and ch["strain_ok"] and ch["drift_ok"] and ch["passed"]
        assert abs(ch["p_mean"] - cfg.p_w) < 3 * ch["p_err"] and ch["p_err"] < 0.03 * cfg.p_w
        assert ch["blocks"] >= 6 and ch["block_strain"] >= ch["tau_int_strain"] and ch["blocks_ok"]


@pytest.mark.slow
def test_smoke_mu_rises_and_phi_falls_with_I(smoke):
    """mu(I) increases and phi(I) decreases (dilatancy), each step beyond its errors overall; the
    values sit in the published range for frictional disks (mu ~ 0.25-0.3 at small I, phi ~ 0.8)."""
    p = pd.read_csv(smoke / layout.POINTS_CSV).sort_values("I")
    assert np.all(np.diff(p.mu) > 0) and np.all(np.diff(p.phi) < 0)
    assert p.mu.iloc[-1] - p.mu.iloc[0] > 5 * np.hypot(p.mu_err.iloc[-1], p.mu_err.iloc[0])
    assert p.phi.iloc[0] - p.phi.iloc[-1] > 5 * np.hypot(p.phi_err.iloc[-1], p.phi_err.iloc[0])
    assert 0.22 < p.mu.iloc[0] < 0.36 and 0.77 < p.phi.iloc[0] < 0.84
    assert np.allclose(p.I, np.geomspace(0.02, 0.3, 4), rtol=0.05)  # the imposed I, measured from the box


@pytest.mark.slow
def test_killed_calibration_resumes_without_redoing_finished_points(tmp_path):
    """SIGKILL the whole calibration (runner and LAMMPS) once a point is complete; --resume keeps that
    point (same wall time), reruns the others and fits (4 fast points of 5 strains: two may fail a check by chance,
    and then the fit has too few points: the resume itself is what is tested)."""
    import os
    import signal
    import subprocess
    import sys
    import time

    text = config.preset_text("smoke").replace("I_min = 0.02", "I_min = 0.1")
    path = tmp_path / "fast.toml"
    path.write_text(text)
    out = tmp_path / "cal"
    args = [sys.executable, "-m", "granstokes.cli", "dem", "calibrate", str(path), "--out", str(out), "--jobs", "1",
            "--quiet"]
    proc = subprocess.Popen(args, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    state_path, done = out / layout.CALIBRATION_STATE, {}
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None and not done:
        if state_path.exists():
            try:
                points = json.loads(state_path.read_text())["points"]
            except json.JSONDecodeError:
                continue
            done = {k: v["wall_time"] for k, v in points.items() if v["status"] == "complete"}
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    assert done and not (out / layout.CALIBRATION_JSON).exists()
    code = granstokes_main(["dem", "calibrate", str(path), "--out", str(out), "--resume", "--quiet"])
    state = json.loads(state_path.read_text())
    assert len(state["resumes"]) == 1 and all(p["status"] == "complete" for p in state["points"].values())
    for key, wall in done.items():
        assert state["points"][key]["wall_time"] == wall
    passed = sum(p["checks"]["passed"] for p in state["points"].values())
    if passed >= 3:
        assert code == 0 and state["status"] == "complete" and len(pd.read_csv(out / layout.POINTS_CSV)) == passed
    else:
        assert code == 1 and state["message"].startswith("fit:") and not (out / layout.CALIBRATION_JSON).exists()


def test_demo_protocol_replaces_the_presets_listed_inertial_numbers():
    """make demo's reduced protocol overrides quick's list I (and its seeds), keeping the cell."""
    from granstokes.demo import demo_calibration_text
    cal = config.parse(demo_calibration_text("quick")).calibration
    assert cal.I is None and cal.seeds == (1,)
    assert cal.inertial_numbers == pytest.approx(tuple(np.geomspace(0.005, 0.5, 5)))
    assert cal.width == config.preset("quick")[0].calibration.width
