"""compare/: calibration, plate observables, delta_u, and the report on a smoke DEM run."""
import json

import numpy as np
import pandas as pd
import pytest
from granstokes.compare.calibrate import fit, load
from granstokes.compare.comparison import IGNORABLE, check_grains, pair_style_clause, run_grains
from granstokes.compare.plate import block_estimate, friction, pooled, power_law, steady_state, trend
from granstokes.continuum.calibration import IN_DRIVE, PLANE_SHEAR, fit_blocks, mu_law
from granstokes.continuum.crossing import depth_at_fraction

from granstokes.cli import main as granstokes_main
from granstokes.lib.statistics import autocorrelation_time


def test_calibration_recovers_a_known_law_within_its_interval():
    rng = np.random.default_rng(1)
    I = np.geomspace(3e-3, 0.5, 300)
    truth = (0.26, 0.62, 0.28)
    mu = mu_law(I, *truth) + rng.normal(0, 0.01, I.size)
    phi = 0.82 - 0.3 * I + rng.normal(0, 0.002, I.size)
    cal = fit(pd.DataFrame({"I_dem": I, "mu": mu, "phi": phi}), n_boot=200)
    assert cal.kind == IN_DRIVE and not cal.is_prediction
    for name, value in zip(("mu_s", "mu_d", "I0_dem"), truth):
        lo, hi = cal.ci95[name]
        assert lo < value < hi and hi - lo < 0.3 * value
        assert len(cal.replicates[name]) >= 190
    assert cal.phi_max == pytest.approx(0.82, abs=0.002) and cal.phi_slope == pytest.approx(0.3, abs=0.02)
    assert cal.rms_mu == pytest.approx(0.01, rel=0.15)
    assert cal.I0_paper == pytest.approx(cal.I0_dem / 2)


def _synthetic_blocks(truth, seeds=(1, 2), n_blocks=12, noise=0.01, seed=3):
    """Block means of a plane-shear calibration that follows the Jop law ``truth`` exactly (p = 20)."""
    rng = np.random.default_rng(seed)
    rows = []
    for k, I in enumerate(np.geomspace(1e-3, 1.0, 10)):
        for s in seeds:
            for b in range(n_blocks):
                p = 20 * (1 + rng.normal(0, 0.01))
                mu = mu_law(I, *truth) + rng.normal(0, noise)
                rows.append({"point": k, "seed": s, "block": b, "p": p, "tau": mu * p,
                             "phi": 0.81 - 0.25 * I + rng.normal(0, 0.002), "rate": I * np.sqrt(p)})
    return pd.DataFrame(rows)


def test_plane_shear_bootstrap_intervals_cover_the_truth_and_shrink_with_data():
    """Seeds-and-blocks bootstrap: the 95 % intervals contain the law the blocks were drawn from, and
    four times the blocks narrow them by about two (the statistical error, not a model floor)."""
    truth = (0.27, 0.62, 0.3)
    cal = fit_blocks(_synthetic_blocks(truth), "synthetic", n_boot=200)
    big = fit_blocks(_synthetic_blocks(truth, n_blocks=48), "synthetic", n_boot=200)
    assert cal.kind == PLANE_SHEAR and cal.is_prediction
    for name, value in zip(("mu_s", "mu_d", "I0_dem"), truth):
        lo, hi = cal.ci95[name]
        assert lo < value < hi
        width = hi - lo
        assert 0.3 < (big.ci95[name][1] - big.ci95[name][0]) / width < 0.75
    assert cal.points.mu_err.iloc[0] == pytest.approx(0.01 / np.sqrt(24), rel=0.4)
    assert cal.phi_max == pytest.approx(0.81, abs=0.002) and cal.phi_slope == pytest.approx(0.25, abs=0.03)


def test_a_calibration_of_other_grains_is_refused(tmp_path):
    """compare --calibration refuses, in one line naming the difference, a calibration whose grain table
    is not the runs'."""
    cal = fit_blocks(_synthetic_blocks((0.27, 0.62, 0.3)), "synthetic", n_boot=20)
    doc = {**cal.contract(), "grains": {"dimension": 2, "mu_p": 0.5, "polydispersity": 0.2}, "provenance": {}}
    (tmp_path / "calibration.json").write_text(json.dumps(doc))
    loaded = load(tmp_path / "calibration.json")
    assert loaded.mu_s == pytest.approx(cal.mu_s) and loaded.is_prediction
    assert np.allclose(loaded.replicates["I0_dem"], cal.replicates["I0_dem"])
    run = tmp_path / "run"
    run.mkdir()
    (run / "run.json").write_text(json.dumps({"config": {"grains": {"dimension": 2, "mu_p": 0.4,
                                                                    "polydispersity": 0.2}}}))
    with pytest.raises(ValueError, match=r"mu_p calibrated 0.5 vs run 0.4") as err:
        check_grains(loaded, run_grains([run]))
    assert "\n" not in str(err.value)
    (run / "run.json").write_text(json.dumps({"config": {"grains": doc["grains"]}}))
    check_grains(loaded, run_grains([run]))
    # a record without a pair style ran pair granular: another contact implementation is other grains
    (run / "run.json").write_text(json.dumps({"config": {"grains": {**doc["grains"], "pair_style": "granular"}}}))
    check_grains(loaded, run_grains([run]))
    (run / "run.json").write_text(json.dumps({"config": {"grains": {**doc["grains"], "pair_style": "classic"}}}))
    with pytest.raises(ValueError, match=r"pair_style calibrated 'granular' vs run 'classic'"):
        check_grains(loaded, run_grains([run]))
    # compare --any-pair-style: the other implementation of the same law is accepted, and said in the source
    check_grains(loaded, run_grains([run]), ignore=IGNORABLE)
    assert pair_style_clause(loaded, run_grains([run])) == \
        ", calibrated in pair style granular, the drives run in classic"
    assert pair_style_clause(loaded, {"r": ({"pair_style": "granular"}, 20.0)}) == ""
    (run / "run.json").write_text(json.dumps({"config": {"grains": {**doc["grains"], "pair_style": "classic",
                                                                    "mu_p": 0.4}}}))
    with pytest.raises(ValueError, match=r"grains: mu_p calibrated 0.5 vs run 0.4'$"):  # nothing else is ignored
        check_grains(loaded, run_grains([run]), ignore=IGNORABLE)
    # one material at two pressures: the same k_n = kappa p (Hooke) is the same grains, another k_n is not
    from granstokes.dem.calibrate import grains_difference
    grains = {**doc["grains"], "pair_style": "classic"}
    assert grains_difference({**grains, "kappa": 1e4}, 20.0, {**grains, "kappa": 2e4}, 10.0) == {}
    assert grains_difference({**grains, "kappa": 1e4}, 20.0, {**grains, "kappa": 1e4}, 10.0) == \
        {"k_n": (pytest.approx(2e5), pytest.approx(1e5))}


def test_too_few_points_are_refused():
    with pytest.raises(ValueError, match="^calibration points must be"):
        fit(pd.DataFrame({"I_dem": [0.1, 0.2], "mu": [0.3, 0.4], "phi": [0.8, 0.8]}))


def test_steady_state_and_power_law_on_known_series():
    rng = np.random.default_rng(2)
    t = np.linspace(0, 50, 5001)
    y = 3 * (1 - np.exp(-t / 4)) + rng.normal(0, 0.05, t.size)
    st = steady_state(t, y)
    assert st["value"] == pytest.approx(3, abs=0.02)
    # steady once the remaining change 3 exp(-t/4), averaged over the next quarter of the rest, is within 3 errors
    # (~0.01): near t = 4 ln(3/0.01) - a few, and no trend is left after it
    after = t >= st["t_steady"]
    assert 12 < st["t_steady"] < 25 and abs(trend(t[after], y[after])["z"]) <= 3
    growing = steady_state(t, t)
    assert np.isnan(growing["t_steady"])
    fit_ = power_law(t, 0.7 * np.sqrt(t), 0.1, 10)
    assert fit_["alpha"] == pytest.approx(0.5, abs=1e-9)


def test_the_trend_test_flags_a_drift_and_ignores_the_prepared_state():
    """The referee's cases: a final quarter drifting by 0.045 per time unit under noise that hides it from a
    band is not steady; the prepared state at t = 0 (a spike: mu_w = 5.26 before the plate moves) neither
    widens the band nor delays t_steady; stationary noise passes at the stated rate."""
    rng = np.random.default_rng(7)
    t = np.linspace(0, 10, 501)
    noise = rng.normal(0, 0.05, t.size)
    drifting = steady_state(t, 2.0 + 0.045 * t + noise)
    assert np.isnan(drifting["t_steady"]) and drifting["drift"] == pytest.approx(0.045, abs=0.02)
    assert abs(drifting["drift_z"]) > 3
    spiked = 0.5 + noise
    spiked[0] = 5.26
    st = steady_state(t, spiked)
    assert abs(st["value"] - 0.5) < 4 * st["stderr"] and st["t_steady"] < 1.0
    passes = [np.isfinite(steady_state(t, 0.5 + rng.normal(0, 0.05, t.size))["t_steady"]) for _ in range(40)]
    assert sum(passes) >= 37  # |z| <= 3 of a t-like statistic: a false alarm in a few percent at most


def test_friction_is_a_ratio_of_means_and_the_mean_of_ratios_is_biased():
    """Single-step plate forces: p = p_w G with G ~ Gamma(k, 1/k) (relative spread 1/sqrt(k) = 50 %, as
    when the plate rests on a few grains), tau = mu p_w (rho G + (1 - rho) G') with G' independent.
    The true friction <tau>/<p> is mu; the mean of tau/p is mu (rho + (1 - rho) E[1/G]) =
    mu (rho + (1 - rho) k/(k - 1)): +16.7 % here.  The mean of the ratios misses by ~100 standard errors,
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
    neighbouring blocks' correlation lowers the error by 5 %; its own scatter is ~1/sqrt(2 blocks) = 2 %).
    Pooling: with >= 3 seeds the error is their spread, with fewer the combined block errors."""
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
    two = pooled([{"value": v, "stderr": 0.3, "dof": 3, "method": "blocks"} for v in (1.0, 2.0)])
    assert two["stderr"] == pytest.approx(0.3 / np.sqrt(2)) and "combined over 2 seeds" in two["method"]
    assert two["dof"] == pytest.approx(6.0)  # two equal block errors of 3 dof each (Welch-Satterthwaite)


def test_depth_at_fraction_interpolates():
    depth = np.linspace(0, 10, 11)
    u = 10 - depth  # u_w = 10: 5 % (0.5) at depth 9.5
    assert depth_at_fraction(depth, u, 10.0) == pytest.approx(9.5)
    assert np.isnan(depth_at_fraction(depth, u + 5, 10.0))


@pytest.mark.slow
def test_compare_report_on_a_smoke_run(smoke_run, tmp_path, capsys):
    """granstokes compare on a real (smoke) run: strict JSON, numbers that check the coarse-graining
    (mass to round-off, pressure slope phi rho g within 15 %); the fit on the smoke's one drive does not
    determine mu(I) (a Jop parameter runs to a bound of its range): a failed fit, said, with nothing scored."""
    assert granstokes_main(["compare", str(smoke_run), "--out", str(tmp_path / "report")]) == 2
    assert "--calibration is required" in capsys.readouterr().err and not (tmp_path / "report").exists()
    assert granstokes_main(["compare", str(smoke_run), "--out", str(tmp_path / "report"), "--json",
                            "--fit-on-drives"]) == 0
    m = json.loads(capsys.readouterr().out, parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))
    assert m["I0_convention"] == "dem" and not m["blind"]
    # which Jop parameter runs away depends on the bed's trajectory (mu_s to 0 or mu_d to 3 on this drive)
    failure = m["calibration_failure"]
    name = failure.split(" = ")[0]
    assert name in ("mu_s", "mu_d", "I0_dem") and failure.endswith("the data do not determine it"), failure
    assert failure.startswith(f"{name} = {m[{'I0_dem': 'I0'}.get(name, name)]:.3g} ")  # the fit it reports
    assert m["scorecard"] == [] and m["tally"] == [] and m["verdict"].startswith("No verdict: the mu(I) calibration")
    assert abs(m["mass_error"]) < 1e-6
    (d,) = m["drives"].values()
    assert d["pressure_slope"] == pytest.approx(m["phi_bulk"], rel=0.15)
    assert d["u_w_inf"]["dem"] > 0 and "steady_local" not in d and "calibration failed" in d["prediction"]
    # the steady window's coarse-grained bulk tau is the plate's <tau_w> within 2 standard errors of the
    # difference (block errors of the frames and of the plate record over the same window: ~10 % of tau
    # for the smoke's 3 time units)
    tb = d["tau_bulk"]
    assert tb["agree"] and abs(tb["cg"] - tb["plate"]) <= 2 * tb["difference_err"]
    assert tb["difference_err"] < 0.15 * tb["plate"]
    # the plate grips: slip consistent with <= 5 % (a plate of touching grains: 46 %)
    assert 0 < d["slip_err"] and d["slip"] - 2 * d["slip_err"] < 0.05 and "autocorrelation" in d["slip_how"]
    assert d["mu_w_inf"]["dem_err"] > 0 and d["mu_w_inf"]["dem_how"]  # u_w_inf is the imposed speed here
    assert 0 < d["elastic_start"]["transit_time"] < d["elastic_start"]["compared_from"]
    assert json.loads((tmp_path / "report" / "metrics.json").read_text())["mu_s"] == m["mu_s"]
    page = (tmp_path / "report" / "index.html").read_text()
    assert "fit" in m["calibration"]["kind"] and "In-drive fit" in page and "No verdict" in page
    # blind: mu(I) and phi from a calibration.json of the same grains (here a synthetic one)
    truth = (0.28, 0.62, 0.3)
    cal = fit_blocks(_synthetic_blocks(truth), "synthetic", n_boot=50)
    grains = json.loads((smoke_run / "run.json").read_text())["config"]["grains"]
    (tmp_path / "cal").mkdir()
    (tmp_path / "cal" / "calibration.json").write_text(json.dumps({**cal.contract(), "grains": grains}))
    capsys.readouterr()
    assert granstokes_main(["compare", str(smoke_run), "--calibration", str(tmp_path / "cal" / "calibration.json"),
                            "--out", str(tmp_path / "blind"), "--json"]) == 0
    b = json.loads(capsys.readouterr().out)
    assert b["blind"] and b["mu_s"] == pytest.approx(cal.mu_s) and b["I0"] == pytest.approx(cal.I0_dem)
    assert b["calibration"]["source"].endswith("calibration.json") and b["calibration_test"]["n_pairs"] >= 3
    assert "Blind comparison" in (tmp_path / "blind" / "index.html").read_text()
    (tmp_path / "cal" / "calibration.json").write_text(json.dumps({**cal.contract(),
                                                                    "grains": {**grains, "mu_p": 0.3}}))
    assert granstokes_main(["compare", str(smoke_run), "--calibration", str(tmp_path / "cal" / "calibration.json"),
                            "--out", str(tmp_path / "refused")]) == 2
    assert "mu_p calibrated 0.3 vs run 0.5" in capsys.readouterr().err
    assert not (tmp_path / "refused").exists()


def test_compare_refuses_a_folder_that_is_not_a_run(tmp_path, capsys):
    assert granstokes_main(["compare", str(tmp_path), "--out", str(tmp_path / "r")]) == 2
    assert "RUN_DIR must be" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()
