"""granstokes dem calibrate: the [calibration] table, the plan, bad input, and the smoke calibration
through LAMMPS (the CI check)."""
import json
import math
import re

import numpy as np
import pandas as pd
import pytest
from granstokes.dem import config, layout
from granstokes.dem.calibrate import (
    FINITE_SIZE_START,
    KINETIC_MAX,
    analyse,
    completed_points,
    finite_size_record,
    not_dense,
    plan_calibration,
)
from granstokes.dem.sizing import OVERHEAD
from granstokes.dem.throughput import measured

from granstokes.cli import main as granstokes_main

#: the smoke grains calibrated at four points log-spaced over I in [0.02, 0.3]: the protocol's mechanics at a third
#: of the smoke preset's cost (too narrow to determine mu_d and I0, which the preset's own seven points do)
SMOKE4 = re.sub(r"^I = \[.*\]$", "I_min = 0.02\nI_max = 0.3\npoints = 4", config.preset_text("smoke"), flags=re.M)
#: with a finite-size cell at its largest inertial number
FINITE_SIZE = ["--set", "calibration.finite_size=[0.3]"]


def smoke4_file(folder):
    """SMOKE4 as a config file in ``folder``."""
    path = folder / "smoke4.toml"
    path.write_text(SMOKE4)
    return str(path)


def test_calibration_table_is_validated_before_anything_runs():
    text = SMOKE4
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
    smoke = config.parse(SMOKE4)
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


def test_finite_size_names_points_of_the_calibration():
    text = SMOKE4
    assert config.parse(text).calibration.finite_size == ()
    I = config.parse(text).calibration.inertial_numbers
    cal = config.parse(text.replace("width = 10.0\n", f"width = 10.0\nfinite_size = [{I[1]!r}, 0.3]\n")).calibration
    assert cal.finite_size == (I[1], 0.3)
    for bad in ("[0.1]", "[0.3, 0.3]", "0.3", "[\"a\"]"):
        with pytest.raises(ValueError, match=r"^calibration.finite_size must be"):
            config.parse(text.replace("width = 10.0\n", f"width = 10.0\nfinite_size = {bad}\n"))


def test_finite_size_cells_are_planned_costed_and_resumed_but_not_fitted(tmp_path):
    """A doubled cell per finite_size point, first seed, twice the width (4x the disks), a start FINITE_SIZE_START
    times longer; outside the fit's tasks, inside the cost and the resume's count."""
    cfg = config.parse(SMOKE4.replace("width = 10.0\n", "width = 10.0\nfinite_size = [0.3]\n"))
    plan = plan_calibration(cfg)
    assert plan.finite_size == (3,) and len(plan.tasks()) == 4 and len(plan.cells()) == 5
    assert plan.doubled_config.calibration.width == 20.0 and plan.n_doubled == pytest.approx(4 * plan.n_grains, abs=2)
    assert plan.point(3, True).start_steps == round(FINITE_SIZE_START * plan.points[3].start_steps)
    assert plan.point(3, True).measure_steps == plan.points[3].measure_steps
    work = [plan.task_seconds(k, dbl) for k, _, dbl in plan.cells()]
    assert work == sorted(work, reverse=True) and plan.task_seconds(3, True) > 4 * plan.task_seconds(3)
    modulus = [plan.modulus_seconds()] * len(plan.modulus_seeds)  # the shear modulus's cells run beside them
    assert plan.cost_seconds(jobs=1, speed=measured()) == pytest.approx(OVERHEAD + sum(work) + sum(modulus))
    assert "and 1 finite-size cell(s) of" in plan.cost_estimate()
    assert plan.as_dict()["finite_size"]["I"] == [pytest.approx(0.3)]
    key = plan.key(3, 1, True)
    assert key == "finite-size/I-3/seed-1" and key not in {plan.key(k, s) for k, s in plan.tasks()}
    fit_keys = {plan.key(k, s) for k, s in plan.tasks()}
    modulus_keys = {plan.modulus_key(s) for s in plan.modulus_seeds}
    assert plan.cost_estimate(done=fit_keys | modulus_keys) != "cost: none, every point is complete"
    assert plan.cost_estimate(done=fit_keys | modulus_keys | {key}) == "cost: none, every point is complete"
    (tmp_path / layout.CALIBRATION_STATE).write_text(json.dumps({"points": {key: {"status": "complete"}}}))
    done, left = completed_points(tmp_path, plan)
    assert done == [key] and sorted(left) == sorted(fit_keys | modulus_keys)


def _synthetic_cell(folder, kinetic, n=600, rate=1.0, mu=0.4, p=20.0, seed=0):
    """series.csv and profile.txt of a steady cell (uncorrelated noise, linear profile) whose kinetic part of
    P_yy is ``kinetic`` P_yy."""
    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True)
    t, ly = np.arange(n) * 0.02, 11.0
    p_yy = p + rng.normal(0, 0.5, n)
    series = pd.DataFrame({"step": np.arange(n) * 10, "t": t, "lx": 10.0, "ly": ly, "xy": rate * ly * t,
                           "p_xx": p_yy, "p_yy": p_yy, "p_xy": -(mu + rng.normal(0, 0.01, n)) * p_yy,
                           "p_yy_kin": kinetic * p_yy, "phi": 0.78 + rng.normal(0, 0.002, n), "T": 0.1})
    assert tuple(series.columns) == layout.SHEAR_SERIES_COLUMNS
    series.to_csv(folder / layout.SHEAR_SERIES_CSV, index=False)
    bins = [f"{i + 1} {(i + 0.5) / 8} 12 {rate * ly * ((i + 0.5) / 8 - 0.5)}" for i in range(8)]
    (folder / layout.SHEAR_PROFILE_TXT).write_text("# chunk y count vx\n100 8 96\n" + "\n".join(bins) + "\n")


def test_a_cell_is_dense_flow_if_contacts_carry_at_least_90_percent_of_p(tmp_path):
    """The kinetic fraction of P_yy, measured from the series, decides dense flow at KINETIC_MAX; a cell above it
    fails like a cell failing any other check, its other checks passing."""
    cfg = config.parse(SMOKE4)
    point = plan_calibration(cfg).points[0]
    assert KINETIC_MAX == 0.1
    for kinetic, dense in ((0.02, True), (0.099, True), (0.101, False), (0.3, False)):
        folder = tmp_path / f"k{kinetic}"
        _synthetic_cell(folder, kinetic)
        row, _, checks = analyse(folder, cfg, point, 1)
        assert checks["kinetic_fraction"] == pytest.approx(kinetic)
        assert checks["dense_ok"] is dense and checks["passed"] is dense
        assert all(checks[k] for k in ("strain_ok", "drift_ok", "pressure_ok", "homogeneous_ok", "blocks_ok"))
        assert row["mu"] == pytest.approx(0.4, abs=0.005)


def _entry(I, mu, mu_err, phi, phi_err, kinetic=0.05, passed=True):
    return {"status": "complete", "row": {"I": I, "I_err": 0.001, "mu": mu, "mu_err": mu_err, "phi": phi,
                                          "phi_err": phi_err},
            "checks": {"kinetic_fraction": kinetic, "dense_ok": kinetic <= KINETIC_MAX, "passed": passed}}


def test_not_dense_cells_are_listed_with_their_indicator_and_the_finite_size_record_gives_z():
    cfg = config.parse(SMOKE4.replace("width = 10.0\n",
                                                           "width = 10.0\nseeds = [4, 2]\nfinite_size = [0.3]\n"))
    plan = plan_calibration(cfg)
    points = {plan.key(k, s): _entry(p.I, 0.3, 0.01, 0.8, 0.002) for k, p in enumerate(plan.points) for s in (4, 2)}
    points[plan.key(3, 2)] = _entry(0.31, 0.5, 0.01, 0.7, 0.002, kinetic=0.15, passed=False)
    points[plan.key(3, 4)] = _entry(0.30, 0.40, 0.03, 0.80, 0.003)
    points[plan.key(3, 4, True)] = _entry(0.30, 0.45, 0.04, 0.79, 0.004, kinetic=0.12, passed=False)
    state = {"points": points}
    listed = not_dense(plan, state)  # the doubled cell is no cell of the fit: not listed
    assert [(e["key"], e["kinetic_fraction"], e["threshold"]) for e in listed] == [("I-3/seed-2", 0.15, 0.1)]
    assert listed[0]["I"] == 0.31 and listed[0]["I_target"] == pytest.approx(0.3) and "not dense" in listed[0]["reason"]
    record = finite_size_record(plan, state)
    assert record["seed"] == 4 and record["width"] == [10.0, 20.0] and record["n_grains"][0] == plan.n_grains
    (r,) = record["points"]
    assert r["normal"]["key"] == "I-3/seed-4" and r["doubled"]["key"] == "finite-size/I-3/seed-4"
    assert (r["normal"]["mu"], r["doubled"]["mu"], r["doubled"]["mu_err"], r["doubled"]["passed"]) == (0.4, 0.45, 0.04,
                                                                                                        False)
    assert r["z_mu"] == pytest.approx(1.0) and r["z_phi"] == pytest.approx(-2.0)


def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "cal"
    assert granstokes_main(["dem", "calibrate", "--preset", "smoke", "--out", str(out), "--jobs", "0"]) == 2
    assert "--jobs must be an integer >= 1" in capsys.readouterr().err
    assert not out.exists()
    assert granstokes_main(["dem", "calibrate", "--preset", "smoke", "--out", str(out), "--resume"]) == 2
    assert not out.exists()


@pytest.fixture(scope="module")
def smoke(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cal")
    out = folder / "smoke"
    assert granstokes_main(["dem", "calibrate", smoke4_file(folder), "--out", str(out), "--quiet", *FINITE_SIZE]) == 0
    return out


@pytest.mark.slow
def test_smoke_calibration_files_follow_the_contract(smoke):
    doc = json.loads((smoke / layout.CALIBRATION_JSON).read_text())
    for key in ("mu_s", "mu_d", "I0", "I_convention", "ci95", "linear", "phi", "replicates", "grains", "provenance",
                "excluded", "not_dense", "finite_size", "elasticity"):
        assert key in doc
    assert doc["I_convention"] == "dem" and set(doc["ci95"]) == {"mu_s", "mu_d", "I0"}
    assert set(doc["linear"]) >= {"mu_1", "b", "ci95"} and set(doc["phi"]) >= {"phi_max", "a", "ci95"}
    assert set(doc["replicates"]) == {"mu_s", "mu_d", "I0", "phi_max", "a"}
    assert len({len(v) for v in doc["replicates"].values()}) == 1 and len(doc["replicates"]["mu_s"]) >= 100
    cfg = config.parse(SMOKE4)
    assert doc["grains"] == json.loads(json.dumps(cfg.as_dict()["grains"]))
    assert doc["provenance"]["seeds"] == [1] and doc["provenance"]["lammps_version"] > 0
    for name in ("mu_s", "mu_d", "I0"):
        lo, hi = doc["ci95"][name]
        assert lo <= doc[name] <= hi
    # the shear modulus (dem.modulus): the preset's one seed and the next two, errors over them, below the affine bound
    e = doc["elasticity"]
    assert e["seeds"] == [1, 2, 3] and e["G_dof"] == 2 and len(e["per_seed"]) == 3 and e["convention"].startswith("G =")
    assert 0 < e["G"] < e["G_affine"] and e["c_s"] == pytest.approx(math.sqrt(e["G"] / e["phi"]))
    assert (smoke / layout.MODULUS_PNG).is_file() and (layout.modulus_dir(smoke, 3) / layout.STATIC_CSV).is_file()
    points = pd.read_csv(smoke / layout.POINTS_CSV)
    assert tuple(points.columns) == layout.POINT_COLUMNS and len(points) == 4


@pytest.mark.slow
def test_smoke_points_are_steady_and_at_the_imposed_pressure(smoke):
    """Every point passed the strain and drift checks, and the bulk sigma_yy equals the imposed p
    within 3 of its standard errors (block errors)."""
    cfg = config.parse(SMOKE4)
    state = json.loads((smoke / layout.CALIBRATION_STATE).read_text())
    assert state["status"] == "complete" and len(state["points"]) == 5
    for key in (plan_calibration(cfg).key(k, s) for k, s in plan_calibration(cfg).tasks()):
        ch = state["points"][key]["checks"]
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
def test_smoke_cells_are_dense_flow_with_a_kinetic_part_growing_with_I(smoke):
    """Contacts carry the stress in every smoke cell (I <= 0.3): the kinetic part of P_yy is positive, grows with I
    and stays below KINETIC_MAX; none is listed as not dense."""
    doc = json.loads((smoke / layout.CALIBRATION_JSON).read_text())
    state = json.loads((smoke / layout.CALIBRATION_STATE).read_text())
    kinetic = [state["points"][f"I-{k}/seed-1"]["checks"]["kinetic_fraction"] for k in range(4)]
    assert 0 < kinetic[0] and np.all(np.diff(kinetic) > 0) and kinetic[-1] < KINETIC_MAX
    assert doc["not_dense"] == [] and doc["excluded"] == []
    series = pd.read_csv(smoke / "I-3" / "seed-1" / layout.SHEAR_SERIES_CSV)
    assert ((series.p_yy_kin > 0) & (series.p_yy_kin < series.p_yy)).all()


@pytest.mark.slow
def test_smoke_finite_size_record_compares_a_cell_twice_as_wide_outside_the_fit(smoke):
    """The doubled cell at I = 0.3 has 4x the disks, runs at the imposed rate, and its record holds both cells' mu and
    phi with z = difference / combined error; points.csv holds the fit's four cells only."""
    doc = json.loads((smoke / layout.CALIBRATION_JSON).read_text())
    record = doc["finite_size"]
    assert record["width"] == [10.0, 20.0] and record["seed"] == 1
    (r,) = record["points"]
    a, b = r["normal"], r["doubled"]
    script = (smoke / layout.FINITE_SIZE / "I-3" / "seed-1" / layout.SHEAR_IN).read_text()
    assert f"create_atoms 1 random {record['n_grains'][1]} 1 " in script and "width" not in a
    assert record["n_grains"][1] == pytest.approx(4 * record["n_grains"][0], abs=2)
    assert a["I"] == pytest.approx(0.3, rel=0.03) and b["I"] == pytest.approx(0.3, rel=0.03)
    for q in ("mu", "phi"):
        assert r[f"z_{q}"] == pytest.approx((b[q] - a[q]) / math.hypot(a[f"{q}_err"], b[f"{q}_err"]))
    assert abs(b["mu"] - a["mu"]) < 0.1 and abs(b["phi"] - a["phi"]) < 0.03  # the same material
    points = pd.read_csv(smoke / layout.POINTS_CSV)
    assert len(points) == 4 and b["mu"] not in list(points.mu)


@pytest.mark.slow
def test_killed_calibration_resumes_without_redoing_finished_points(tmp_path):
    """SIGKILL the whole calibration (runner and LAMMPS) once a cell is complete (the finite-size cell, the longest,
    runs first); --resume keeps that cell (same wall time), reruns the others and fits (4 fast points of 5 strains:
    two may fail a check by chance, and then the fit has too few points: the resume itself is what is tested)."""
    import os
    import signal
    import subprocess
    import sys
    import time

    text = SMOKE4.replace("I_min = 0.02", "I_min = 0.1").replace(
        "width = 10.0\n", "width = 10.0\nfinite_size = [0.3]\nmodulus = false\n")  # the modulus's resume: test_modulus
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
    assert "finite-size/I-3/seed-1" in done and not (out / layout.CALIBRATION_JSON).exists()
    code = granstokes_main(["dem", "calibrate", str(path), "--out", str(out), "--resume", "--quiet"])
    state = json.loads(state_path.read_text())
    assert len(state["resumes"]) == 1 and all(p["status"] == "complete" for p in state["points"].values())
    for key, wall in done.items():
        assert state["points"][key]["wall_time"] == wall
    passed = sum(p["checks"]["passed"] for key, p in state["points"].items() if not key.startswith(layout.FINITE_SIZE))
    if passed >= 3:
        assert code == 0 and state["status"] == "complete" and len(pd.read_csv(out / layout.POINTS_CSV)) == passed
    else:
        assert code == 1 and state["message"].startswith("fit:") and not (out / layout.CALIBRATION_JSON).exists()

