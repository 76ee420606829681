"""The oscillating plate's comparison (compare.oscillation): a model confronted with its own solution, sampled
like a DEM record with noise, scores consistent and a model of another material does not; the tables give back the
records; metrics.json's rows and drives carry the keys the report promises."""
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from granstokes.compare import oscillation as osc
from granstokes.compare import oscillation_tables
from granstokes.compare.drive import DriveSpec
from granstokes.compare.oscillation_experiment import OscillatingPlate
from granstokes.continuum.load import Load
from granstokes.continuum.scales import Material

MATERIAL = Material(mu_s=0.27, mu_d=0.7, I0=0.24, I_convention="dem", phi=0.8)
P_W, DEPTH, BEDS, CYCLES = 20.0, 12.0, 3, 3
NUMERICS = replace(osc.NUMERICS, n_cells=40)  # the test's: percent-level, a few seconds
NOISE = 0.01  # relative noise of a bed's plate record


def _drive(kind: str) -> DriveSpec:
    held = Load(kind, P_W, mu_w=0.45) if kind == "stress" else Load(kind, P_W, u_w=2.0)
    t_s = held.scales(MATERIAL).t_s
    load = replace(held, omega=1.0 / t_s)
    return DriveSpec(Path("runs/p20"), f"{kind}-wave", load, DEPTH, plate_mass=1.0, surface_offset=0.0, steps=0,
                     transit_time=np.nan, seeds=BEDS, grains=0, dimension=2, t_s=t_s, duration=CYCLES * load.period)


def _beds(drive: DriveSpec, material: Material) -> list[osc.Record]:
    """BEDS noisy copies of the local model's solution (its profiles at 1 d planes), as dem_record gives them."""
    rec = osc.model_record(drive, material, "local", None, np.arange(0.5, DEPTH, 1.0), NUMERICS)
    rng = np.random.default_rng(7)
    beds = []
    for _ in range(BEDS):
        plate = rec.plate.copy()
        for col in ("u_w", "mu_w", "tau_w"):
            plate[col] += NOISE * plate[col].abs().max() * rng.standard_normal(len(plate))
        profiles = rec.profiles.assign(mu=rec.profiles.mu + NOISE * rng.standard_normal(len(rec.profiles)))
        beds.append(osc.Record(plate, profiles, rec.velocity.copy()))
    return beds


@pytest.fixture(scope="module")
def scored():
    """A speed drive's local solution as 3 noisy beds, predicted by the same model and by a model with mu_d x 1.2
    (about 10 s: 13 solves of 3 cycles through the regularised law's kink)."""
    drive = _drive("speed")
    dem = osc.analyse_dem(drive, _beds(drive, MATERIAL), MATERIAL.mu_s)
    cov = pd.DataFrame(np.diag([1e-6] * 4), index=list(osc.PARAMETERS), columns=list(osc.PARAMETERS))
    setup = osc.ModelSetup(MATERIAL, cov, numerics=NUMERICS)
    other = osc.ModelSetup(replace(MATERIAL, mu_d=1.2 * MATERIAL.mu_d), cov, numerics=NUMERICS)
    return dem, osc.predict(dem, setup, "local"), osc.predict(dem, other, "local"), setup


@pytest.mark.slow
def test_a_model_against_its_own_noisy_solution_is_consistent(scored):
    dem, same, _, _ = scored
    for name in ("response_amplitude", "phase_lag", "dissipation", "yielded_depth"):
        v, err, *_ = dem.values[name]
        p, num, s_cal = same.values[name]
        assert err > 0 and abs(osc._difference(name, v, p)) <= 3 * np.sqrt(err ** 2 + num ** 2 + s_cal ** 2), name
    # the speed's friction leads the imposed speed (lag < 0, a visco-plastic layer) and yields a layer of some d
    assert -np.pi / 2 < dem.values["phase_lag"][0] < 0
    assert 1.0 < dem.values["yielded_depth"][0] < DEPTH
    assert dem.values["dissipation"][0] > 0


@pytest.mark.slow
def test_another_material_disagrees(scored):
    dem, _, other, _ = scored
    v, err, *_ = dem.values["response_amplitude"]
    p, num, s_cal = other.values["response_amplitude"]
    assert abs(v - p) > 5 * np.sqrt(err ** 2 + num ** 2 + s_cal ** 2)
    assert p > v  # a larger mu_d resists more: a larger friction amplitude


@pytest.mark.slow
def test_rows_and_drives_carry_the_frequency_amplitude_and_lag(scored, tmp_path):
    dem, same, _, setup = scored
    label = dem.drive.label
    rows = osc.scorecard([dem], {(label, "local"): same}, setup, "no NGF amplitude given")
    choices = osc.choice_rows([dem], {(label, "local"): same}, setup, "no NGF amplitude given")
    comparison = osc.OscillationComparison(("runs/p20",), setup, "test", "no NGF", (dem,),
                                           {(label, "local"): same}, rows, osc.laws(choices), choices)
    m = OscillatingPlate.write(comparison, tmp_path)
    keys = {"drive", "observable", "unit", "dem", "dem_err", "model", "predicted", "band", "sigma", "verdict",
            "scored", "note", "omega", "amplitude", "phase_lag"}
    for row in m["scorecard"]:
        assert keys <= set(row)
        assert row["omega"] == pytest.approx(dem.drive.load.omega) and row["amplitude"] == 2.0
    local = [r for r in m["scorecard"] if r["model"] == "local"]
    verdicts = {r["observable"]: r["verdict"] for r in local}
    assert {verdicts[o] for o in ("response_amplitude", "phase_lag", "dissipation", "yielded_depth")} == {"consistent"}
    assert all(r["verdict"] == "not predicted" for r in m["scorecard"] if r["model"] == "ngf")
    drive = m["drives"][label]
    assert drive["omega"] == pytest.approx(dem.drive.load.omega) and drive["amplitude"] == 2.0
    # u_c is the model's u_w, u_w carries noise NOISE max|u_w|: slip = NOISE sqrt(2) for a sine
    assert drive["seeds"] == BEDS and drive["slip"] == pytest.approx(NOISE * np.sqrt(2), rel=0.15)
    html = (tmp_path / "index.html").read_text() + (tmp_path / "drives.html").read_text()
    for png in ("map.png", "zones_speed.png", "loops.png"):
        assert (tmp_path / png).stat().st_size > 10_000 and f"src='{png}'" in html
    back = oscillation_tables.read(tmp_path / "tables")
    (drive_back, records), = back
    assert drive_back.load == dem.drive.load and len(records) == BEDS
    np.testing.assert_allclose(records[0].plate.u_w, dem.records[0].plate.u_w, rtol=1e-8)


def test_laws_fit_a_power_of_omega():
    """A yielded depth ~ omega^-1/2 and a lag linear in ln omega, the same for every estimator choice, are recovered
    by the law's fit."""
    omega_ts = np.array([0.1, 0.3, 1.0, 3.0, 10.0])
    rows = []
    for w in omega_ts:
        for obs, dem, pred in (("yielded_depth", 8 * w ** -0.5, 8 * w ** -0.4), ("phase_lag", 0.2 + 0.1 * np.log(w),
                                                                                     0.2 + 0.1 * np.log(w))):
            rows += [{"kind": "speed", "amplitude": 2.0, "model": "local", "scored": True, "observable": obs,
                      "estimator": c.estimator, "reference": c.reference, "skip": c.skip, "omega_ts": w, "dem": dem,
                      "dem_err": 0.01 * abs(dem) + 1e-3, "predicted": pred, "numerical_err": 0.0,
                      "calibration_sd": 0.0} for c in osc.LAW_FAMILIES[obs]]
    laws = osc.laws(pd.DataFrame(rows)).set_index("law")
    assert laws.loc["yielded_depth_exponent", "dem"] == pytest.approx(-0.5, abs=1e-9)
    assert laws.loc["yielded_depth_exponent", "predicted"] == pytest.approx(-0.4, abs=1e-9)
    assert laws.loc["yielded_depth_exponent", "verdict"] == "disagrees"
    assert laws.loc["phase_lag_slope", "dem"] == pytest.approx(0.1, abs=1e-9)
    assert laws.loc["phase_lag_slope", "verdict"] == "consistent"
