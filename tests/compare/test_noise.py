"""compare.noise: the error law's fit recovers known exponents, the shipped table covers every scored observable,
and ``granstokes study --dry-run`` prints each drive's predicted errors (1/sqrt(beds)) and writes nothing."""
from __future__ import annotations

import itertools
import re

import numpy as np
import pytest
from granstokes.compare import noise
from granstokes.dem import config as dem_config

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
