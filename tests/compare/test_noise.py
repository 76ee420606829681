"""compare.noise: the error law's fit recovers known exponents, the shipped table covers every scored observable,
and ``granstokes study --dry-run`` prints each drive's predicted errors (1/sqrt(beds)) and writes nothing."""
from __future__ import annotations

import itertools
import re
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from granstokes.compare import noise
from granstokes.dem import config as dem_config
from scipy import stats

from granstokes.cli import main as granstokes_main
from granstokes.study import config
from granstokes.study.plan import plan_study

TRUE = {"c": 3.0, "r": 0.6, "a": 0.3, "b": 0.8}


def _synthetic(scatter: float, seed: int = 1):
    grid = np.array(list(itertools.product([1, 2, 4, 8], [16.0, 32.0, 64.0], [5.0, 20.0, 80.0], [5.0, 10.0, 20.0],
                                           [0.5, 2.0, 8.0])))
    seeds, area, duration, p_w, x = grid.T
    err = (TRUE["c"] * x ** TRUE["r"] * (seeds * area) ** -noise.AVERAGING * duration ** -TRUE["a"]
           * p_w ** -TRUE["b"])
    return err * np.exp(scatter * np.random.default_rng(seed).standard_normal(len(err))), x, seeds, area, duration, p_w


def test_fit_recovers_known_exponents():
    err, x, seeds, area, duration, p_w = _synthetic(scatter=0.0)
    law = noise.fit(err, x, seeds, area, duration, p_w)
    assert law == pytest.approx(TRUE, rel=1e-9)
    err, *rest = _synthetic(scatter=0.2)  # 20 % lognormal scatter over 324 drives
    law = noise.fit(err, *rest)
    assert law["r"] == pytest.approx(TRUE["r"], abs=0.03) and law["a"] == pytest.approx(TRUE["a"], abs=0.03)
    assert law["b"] == pytest.approx(TRUE["b"], abs=0.04) and law["c"] == pytest.approx(TRUE["c"], rel=0.15)
    held = noise.fit(err, *rest, a=TRUE["a"], b=TRUE["b"])  # held exponents stay; the others are refitted
    assert held["a"] == TRUE["a"] and held["b"] == TRUE["b"] and held["r"] == pytest.approx(TRUE["r"], abs=0.03)
    wrong = noise.fit(err, *rest, a=0.0)  # a wrong duration exponent moves the prefactor, not r or b
    assert wrong["c"] < 0.5 * law["c"]


def test_the_shipped_laws_cover_every_scored_observable():
    table = noise.laws()
    for kind, observables in noise.SCORED.items():
        for obs in observables:
            law = table[(obs, kind)]
            assert law.c2 > 0 and law.c3 > 0 and 0 <= law.a <= 1
    size = noise.DriveSize("speed", 2, 4, 32.0, 20.0, 10.0, {"u_w": 3.0, "mu_w": 0.5, "delta_s": 10.0, "t_s": 2.0})
    law = table[("mu_w_inf", "speed")]
    assert law.error(size) == pytest.approx(law.c2 * 0.5**law.r * 128**-0.5 * 20.0**-law.a * 10.0**-law.b)
    assert law.error(noise.DriveSize(**{**size.__dict__, "duration": 40.0})) == pytest.approx(
        law.error(size) * 2**-law.a)


ROOT = Path(__file__).resolve().parents[2]
#: a cell's spread beyond this two-sided chi-square interval of the law's sigma is a miss (lack of fit)
LACK_OF_FIT_LEVEL = 0.99


@pytest.fixture(scope="module")
def cost_noise():
    """bench/dem_cost_noise.py, which fits compare/noise.csv to the committed studies."""
    sys.path.insert(0, str(ROOT / "bench"))
    try:
        import dem_cost_noise
    finally:
        sys.path.remove(str(ROOT / "bench"))
    return dem_cost_noise


def test_the_shipped_laws_are_the_fit_to_the_committed_studies(cost_noise):
    """compare/noise.csv is what its bench fits to the committed studies' drives, in the forms it records: a law
    left behind by a new study or a changed fit fails."""
    full2, full3, short = cost_noise.measured_windows()
    table = pd.read_csv(noise.NOISE_CSV)
    fitted = cost_noise.fit_laws(full2, short, {(r.observable, r.kind): r.form for r in table.itertuples()})
    assert set(fitted) == {(r.observable, r.kind) for r in table.itertuples()}
    for r in table.itertuples():
        law = fitted[(r.observable, r.kind)]
        assert [law["c"], law["r"], law["a"], law["b"], law["p_min"], law["p_max"]] == pytest.approx(
            [r.c2, r.r, r.a, r.b, r.p_min, r.p_max], rel=1e-4, abs=1e-6), (r.observable, r.kind)


def test_the_shipped_laws_show_no_lack_of_fit(cost_noise):
    """Each committed drive's spread of n beds against the law's sigma: (n - 1) s^2 / sigma^2 ~ chi2(n - 1). The
    cells outside the two-sided LACK_OF_FIT_LEVEL interval are no more than chance allows at 99.9 % (binomial, 4
    of 72): a law with 3D prefactors from 2 beds' block errors has 9 there (bench/RESULTS.md)."""
    rows = cost_noise.check_law(noise.NOISE_CSV)
    assert len(rows) == sum(len(noise.SCORED[k]) for k in rows.kind[rows.observable.isin(noise.RESPONSES)])
    dof = rows.seeds - 1
    p = stats.chi2.cdf(dof * (rows.err / rows.predicted) ** 2, dof)
    tail = (1 - LACK_OF_FIT_LEVEL) / 2
    misses = int(((p < tail) | (p > 1 - tail)).sum())
    assert misses <= stats.binom.ppf(0.999, len(rows), 1 - LACK_OF_FIT_LEVEL), rows[(p < tail) | (p > 1 - tail)]


def test_the_spread_of_few_beds_is_low_in_log_space():
    """compare.noise.log_spread_bias against sampled spreads of Gaussian beds."""
    rng = np.random.default_rng(3)
    for beds in (2, 4, 7):
        sampled = np.log(rng.standard_normal((200_000, beds)).std(axis=1, ddof=1)).mean()
        assert noise.log_spread_bias(beds) == pytest.approx(sampled, abs=0.01)
    assert noise.log_spread_bias(4) == pytest.approx(-0.1845, abs=1e-4)


def test_a_drive_beyond_the_fitted_ranges_is_flagged():
    law = noise.NoiseLaw("t90", "stress", 2.0, 3.0, -0.1, 0.0, -1.1, (10.0, 20.0), (1.5, 13.0))
    size = noise.DriveSize("stress", 2, 4, 32.0, 20.0, 20.0, {"u_w": 3.0, "mu_w": 0.5, "delta_s": 10.0, "t_s": 2.0})
    assert law.extrapolated(size) == []
    assert law.extrapolated(replace(size, p_w=40.0)) == ["p_w 40 beyond 10-20"]
    assert law.extrapolated(replace(size, p_w=20.9)) == []  # within RANGE_SLACK
    assert law.extrapolated(replace(size, scales={**size.scales, "t_s": 0.5})) == ["t_s 0.5 beyond 1.5-13"]
    assert replace(law, b=0.0, r=0.0).extrapolated(replace(size, p_w=40.0, scales={"t_s": 0.5})) == []
    # printed beside the one observable whose law is applied beyond its range (the others record no range)
    table = {(obs, "stress"): replace(law, observable=obs, p_range=(np.nan, np.nan), x_range=(np.nan, np.nan))
             for obs in noise.SCORED["stress"]}
    table[("t90", "stress")] = law
    line = noise.error_line("x", replace(size, p_w=40.0), table)
    assert line.count("(extrapolated") == 1 and line.endswith("sqrt(d/g) (extrapolated: p_w 40 beyond 10-20)")


def _dry_run_errors(tmp_path, capsys, seeds: str) -> dict[tuple[str, str], float]:
    out = tmp_path / f"study-{len(seeds)}"
    assert granstokes_main(["study", "--preset", "smoke", "--out", str(out), "--dry-run", "--set",
                            f"seeds={seeds}"]) == 0
    assert not out.exists()
    err = capsys.readouterr().err
    found = {}
    for line in err.splitlines():
        m = re.match(r"\s+(p[\d.]+(?:-wide)?), ([\w.-]+): expected errors at", line)
        if m:
            for obs, value in re.findall(r"(\w+) \+- ([\d.e+-]+)", line):
                found[(f"{m[1]}, {m[2]}", obs)] = float(value)
    return found


def test_dry_run_prints_errors_that_halve_with_four_times_the_beds(tmp_path, capsys):
    two = _dry_run_errors(tmp_path, capsys, "[1, 2]")
    four = _dry_run_errors(tmp_path, capsys, "[1, 2, 3, 4]")
    study, _ = config.load(None, "smoke", ["seeds=[1, 2]"])
    drives = {f"{label}, {d.drive.name}" for label, r in plan_study(study, _material(study), "").runs.items()
              for d in r.plan.drives}
    assert {drive for drive, _ in two} == drives and set(two) == set(four)
    assert {obs for _, obs in two} == set(noise.SCORED["stress"]) | set(noise.SCORED["speed"])
    for key, e in two.items():
        assert four[key] == pytest.approx(e / np.sqrt(2), rel=0.01)  # printed to 3 digits
    # the printed number is the law's at the planned drive
    sp = plan_study(study, _material(study), "")
    r = sp.runs["p10"]
    d = next(d for d in r.plan.drives if d.load.kind == "stress")
    size = noise.drive_size(r.plan, d, r.p_w)
    law = noise.laws()[("u_w_inf", "stress")]
    expected = law.c2 * size.scales["u_w"] ** law.r * (2 * r.plan.area) ** -0.5 * d.duration ** -law.a * 10.0**-law.b
    assert two[(f"p10, {d.drive.name}", "u_w_inf")] == pytest.approx(expected, rel=0.005)


def _material(study) -> dict:
    material = dem_config.preset(study.dem)[0].material
    return {k: getattr(material, k) for k in dem_config.MATERIAL_KEYS}


# --- the error target: beds from the law turned around ---------------------------------------------------------

def _unit_law(observable: str, kind: str, one_bed: float, area: float) -> noise.NoiseLaw:
    """A synthetic law whose one-bed error (a fraction of the scale for a relative observable) is ``one_bed`` on a
    plate of ``area``, at any duration and pressure."""
    return noise.NoiseLaw(observable, kind, one_bed * area**0.5, one_bed * area**0.5,
                          1.0 if noise.relative(observable) else 0.0, 0.0, 0.0)


def test_beds_to_decide_pay_for_the_t_quantile_as_well_as_the_error():
    def beds(law, difference, **kw):  # the target of one observable on this drive
        return noise.Target(((law.observable, difference),), **kw).beds(size, {(law.observable, "stress"): law})[
            law.observable]

    size = noise.DriveSize("stress", 2, 3, 16.0, 5.0, 10.0, {"u_w": 2.0, "mu_w": 0.5, "delta_s": 5.0, "t_s": 1.0})
    creep = _unit_law("creep_length", "stress", 1.0, 16.0)
    # t(0.975, n - 1)/sqrt(n): n = 6 gives 2.571/2.449 = 1.050, n = 7 gives 2.447/2.646 = 0.925 (a Gaussian's
    # 1.96/sqrt(n) would stop at n = 4)
    assert beds(creep, 1.0) == 7
    # half the difference: n = 17 gives 2.120/4.123 = 0.514, n = 18 gives 2.110/4.243 = 0.497
    assert beds(creep, 0.5, beds_max=20) == 18
    assert beds(creep, 0.5, beds_max=17) is None
    # at 90 %: t(0.95, 3)/2 = 2.353/2 = 1.18, t(0.95, 4)/sqrt(5) = 2.132/2.236 = 0.953
    assert beds(creep, 1.0, confidence=0.90) == 5
    # a relative observable: the one-bed error over the expected speed (r = 1: the law's error is 0.5 u_w)
    speed = _unit_law("u_w_inf", "stress", 0.5, 16.0)
    assert speed.error(replace(size, seeds=1)) == pytest.approx(0.5 * size.scales["u_w"])
    # t/sqrt(n) <= 2: n = 3 gives 2.48, n = 4 gives 1.59
    assert beds(speed, 1.0) == 4
    target = noise.Target((("creep_length", 1.0), ("u_w_inf", 1.0), ("mu_w_inf", 1.0)))
    assert target.beds(size, {("creep_length", "stress"): creep, ("u_w_inf", "stress"): speed}) == {
        "creep_length": 7, "u_w_inf": 4}  # mu_w_inf: a speed drive's, not scored here


def test_a_study_target_sets_each_runs_beds_and_the_dry_run_says_what_it_cannot_decide(tmp_path, capsys,
                                                                                          monkeypatch):
    study, _ = config.load(None, "smoke", ["seeds=[1, 2]"])
    area = next(iter(plan_study(study, _material(study), "").runs.values())).plan.area
    one_bed = {"creep_length": 1.0, "delta_u": 1.0, "u_w_inf": 0.5, "mu_w_inf": 0.5, "t90": 10.0}
    table = {(obs, kind): _unit_law(obs, kind, one_bed[obs], area)
             for kind, observables in noise.SCORED.items() for obs in observables}
    monkeypatch.setattr(noise, "laws", lambda path=noise.NOISE_CSV: table)
    target = "target={creep_length = 1.0, u_w_inf = 1.0, mu_w_inf = 1.0, t90 = 1.0, beds_max = 9}"
    targeted, _ = config.load(None, "smoke", ["seeds=[1, 2]", target])
    sp = plan_study(targeted, _material(targeted), "", table)
    for label, r in sp.runs.items():  # creep 7 beds, the responses 4; t90 (10 t_s per bed) not within 9
        assert r.plan.config.seeds == ((1, 2, 3, 4, 5, 6, 7) if not label.endswith("-wide") else (1, 2))
    out = tmp_path / "targeted"
    assert granstokes_main(["study", "--preset", "smoke", "--out", str(out), "--dry-run", "--set", "seeds=[1, 2]",
                            "--set", target]) == 0
    assert not out.exists()
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "its run takes" in line]
    assert len(lines) == sum(len(r.plan.drives) for label, r in sp.runs.items() if not label.endswith("-wide"))
    for line in lines:
        assert "cannot decide t90 within 9 beds" in line and "creep_length 1 d: 7" in line
        assert ("u_w_inf 100 % of u_w: 4" in line) != ("mu_w_inf 100 % of mu_w: 4" in line)
        assert line.endswith("its run takes 7")
    assert "at 7 bed(s)" in err and "at 2 bed(s)" in err  # the errors printed at the runs' beds (the width check's 2)


@pytest.mark.parametrize("entry, name", [
    ("target={creep_length = -1.0}", "target.creep_length"),
    ("target={beds_max = 6}", "target keys"),
    ("target={creep_length = 0.3, beds_max = 1}", "target.beds_max"),
    ("target={creep_length = 0.3, confidence = 1.0}", "target.confidence"),
    ("target={layer = 0.3}", "target keys"),
])
def test_a_bad_target_is_named(entry, name):
    with pytest.raises(ValueError, match=name.replace(".", r"\.")):
        config.load(None, "smoke", [entry])
