"""compare/: calibration, plate observables, delta_u, and the report on a smoke DEM run."""
import json

import numpy as np
import pandas as pd
import pytest

from compare.calibrate import fit, mu_law
from compare.plate import autocorrelation_time, block_estimate, friction, power_law, pooled, steady_state
from compare.predict import depth_at_fraction
from granstokes.cli import main as granstokes_main


def test_calibration_recovers_a_known_law_within_its_interval():
    rng = np.random.default_rng(1)
    I = np.geomspace(3e-3, 0.5, 300)
    truth = (0.26, 0.62, 0.28)
    mu = mu_law(I, *truth) + rng.normal(0, 0.01, I.size)
    phi = 0.82 - 0.3 * I + rng.normal(0, 0.002, I.size)
    cal = fit(pd.DataFrame({"I_dem": I, "mu": mu, "phi": phi}))
    for name, value in zip(("mu_s", "mu_d", "I0_dem"), truth):
        lo, hi = cal.ci95[name]
        assert lo < value < hi and hi - lo < 0.3 * value
    assert cal.phi_max == pytest.approx(0.82, abs=0.002) and cal.phi_slope == pytest.approx(0.3, abs=0.02)
    assert cal.rms_mu == pytest.approx(0.01, rel=0.15)
    assert cal.I0_paper == pytest.approx(cal.I0_dem / 2)


def test_too_few_points_are_refused():
    with pytest.raises(ValueError, match="^calibration points must be"):
        fit(pd.DataFrame({"I_dem": [0.1, 0.2], "mu": [0.3, 0.4], "phi": [0.8, 0.8]}))


def test_steady_state_and_power_law_on_known_series():
    rng = np.random.default_rng(2)
    t = np.linspace(0, 50, 5001)
    y = 3 * (1 - np.exp(-t / 4)) + rng.normal(0, 0.05, t.size)
    st = steady_state(t, y)
    assert st["value"] == pytest.approx(3, abs=0.02)
    # the running mean enters the band max(3 stderr, 5 % of 3) = 0.15 near t = 4 ln(3/0.15) = 12
    assert st["t_steady"] == pytest.approx(4 * np.log(3 / st["band"]), abs=1.5)
    growing = steady_state(t, t)
    assert np.isnan(growing["t_steady"])
    fit_ = power_law(t, 0.7 * np.sqrt(t), 0.1, 10)
    assert fit_["alpha"] == pytest.approx(0.5, abs=1e-9)


def test_friction_is_a_ratio_of_means_and_the_mean_of_ratios_is_biased():
    """Single-step plate forces: p = p_w G with G ~ Gamma(k, 1/k) (relative spread 1/sqrt(k) = 50 %, as
    when the plate rests on a few grains), tau = mu p_w (rho G + (1 - rho) G') with G' independent.
    The true friction <tau>/<p> is mu; the mean of tau/p is mu (rho + (1 - rho) E[1/G]) =
    mu (rho + (1 - rho) k/(k - 1)): +16.7 % here.  The old estimator misses by ~100 standard errors,
    the ratio of means is within 3."""
    rng = np.random.default_rng(3)
    mu, p_w, k, rho, n = 0.4, 20.0, 4.0, 0.5, 200_000
    g, g2 = rng.gamma(k, 1 / k, n), rng.gamma(k, 1 / k, n)
    p, tau = p_w * g, mu * p_w * (rho * g + (1 - rho) * g2)
    ratio_of_means = block_estimate({"tau": tau, "p": p}, lambda m: m["tau"] / m["p"])
    mean_of_ratios = block_estimate({"r": tau / p})
    assert ratio_of_means["value"] == pytest.approx(friction(tau, p))
    assert abs(ratio_of_means["value"] - mu) < 3 * ratio_of_means["stderr"]
    assert mean_of_ratios["value"] == pytest.approx(mu * (rho + (1 - rho) * k / (k - 1)), rel=0.01)
    assert (mean_of_ratios["value"] - mu) / mean_of_ratios["stderr"] > 50


def test_block_errors_follow_the_autocorrelation_time():
    """AR(1) noise y_t = a y_(t-1) + e_t: integrated autocorrelation time (1 + a)/(2 (1 - a)) samples and
    standard error of the mean sigma_y sqrt(2 tau/N); both recovered within 10 % (blocks of 10 tau: the
    neighbouring blocks' correlation lowers the error by 5 %; its own scatter is ~1/sqrt(2 blocks) = 2 %).  Pooling: with >= 3 seeds the error is their
    spread, with fewer the combined block errors."""
    rng = np.random.default_rng(4)
    a, n = 0.9, 100_000
    e = rng.normal(0, 1, n)
    y = np.empty(n)
    y[0] = e[0]
    for i in range(1, n):
        y[i] = a * y[i - 1] + e[i]
    tau = (1 + a) / (2 * (1 - a))
    assert autocorrelation_time(y) == pytest.approx(tau, rel=0.1)
    est = block_estimate({"y": y})
    assert est["stderr"] == pytest.approx(np.sqrt(1 / (1 - a**2)) * np.sqrt(2 * tau / n), rel=0.1)
    assert est["enough_blocks"] and "autocorrelation" in est["method"]
    three = pooled([{"value": v, "stderr": 0.01, "method": "blocks"} for v in (1.0, 2.0, 3.0)])
    assert three["stderr"] == pytest.approx(1 / np.sqrt(3)) and "spread over 3 seeds" in three["method"]
    two = pooled([{"value": v, "stderr": 0.3, "method": "blocks"} for v in (1.0, 2.0)])
    assert two["stderr"] == pytest.approx(0.3 / np.sqrt(2)) and "combined over 2 seeds" in two["method"]


def test_depth_at_fraction_interpolates():
    depth = np.linspace(0, 10, 11)
    u = 10 - depth  # u_w = 10: 5 % (0.5) at depth 9.5
    assert depth_at_fraction(depth, u, 10.0) == pytest.approx(9.5)
    assert np.isnan(depth_at_fraction(depth, u + 5, 10.0))


@pytest.mark.slow
def test_compare_report_on_a_smoke_run(tmp_path, capsys):
    """granstokes compare on a real (smoke) run: strict JSON with the issue's keys, numbers that
    check the coarse-graining (mass to round-off, pressure slope phi rho g within 15 %), a
    calibration with mu_s < mu_d, and the report's page and figures."""
    run = tmp_path / "run"
    assert granstokes_main(["dem", "run", "--preset", "smoke", "--out", str(run), "--quiet"]) == 0
    capsys.readouterr()
    assert granstokes_main(["compare", str(run), "--out", str(tmp_path / "report"), "--json"]) == 0
    m = json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))
    for key in ("phi_bulk", "pressure_slope", "tau_uniformity", "mass_error", "mu_s", "mu_d", "I0",
                "u_w_inf", "delta_s", "alpha_delta", "alpha_u"):
        assert key in m
    assert m["I0_convention"] == "dem"
    assert abs(m["mass_error"]) < 1e-6
    assert m["pressure_slope"] == pytest.approx(m["phi_bulk"], rel=0.15)
    assert 0 < m["mu_s"] < m["mu_d"]
    assert m["u_w_inf"]["dem"] > 0 and m["u_w_inf"]["velocity_form"] > 0
    (d,) = m["drives"].values()
    # the steady window's coarse-grained bulk tau is the plate's <tau_w> within 2 standard errors of the
    # difference (block errors of the frames and of the plate record over the same window: ~10 % of tau
    # for the smoke's 3 time units; the pre-issue-9 estimators missed by 18 %)
    tb = d["tau_bulk"]
    assert tb["agree"] and abs(tb["cg"] - tb["plate"]) <= 2 * tb["difference_stderr"]
    assert tb["difference_stderr"] < 0.15 * tb["plate"]
    # the plate grips: slip consistent with <= 5 % (the old plate of touching grains: 46 %)
    assert 0 < d["slip_err"] and d["slip"] - 2 * d["slip_err"] < 0.05 and "autocorrelation" in d["slip_method"]
    for key in ("mu_w_inf", "delta_s"):  # u_w_inf is the imposed speed here
        assert d[key]["dem_stderr"] > 0 and d[key]["dem_method"]
    assert 0 < d["elastic_start"]["transit_time"] < d["elastic_start"]["compared_from"]
    page = (tmp_path / "report" / "index.html").read_text()
    assert "continuum vs DEM" in page and page.count("<img") >= 5
    assert json.loads((tmp_path / "report" / "metrics.json").read_text())["mu_s"] == m["mu_s"]


def test_compare_refuses_a_folder_that_is_not_a_run(tmp_path, capsys):
    assert granstokes_main(["compare", str(tmp_path), "--out", str(tmp_path / "r")]) == 2
    assert "RUN_DIR must be" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()
