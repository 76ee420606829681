"""The experiment pipeline: the registry picks an experiment by the drives' loads (never by a flag), options an
experiment does not take are refused, one verdict rule, one calibration band, and a new experiment is a subclass
and nothing else (a toy one runs through the shared stages and the report shell)."""
import ast
import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from granstokes.compare import band, rows
from granstokes.compare.experiment import Experiment, Section, experiment_for, experiments
from granstokes.compare.oscillation_experiment import OscillatingPlate
from granstokes.compare.stokes_experiment import StokesDrives
from granstokes.continuum.load import Load
from scipy import stats

ROOT = Path(__file__).resolve().parents[2]
HELD = Load("stress", 10.0, mu_w=0.4)
SINE = Load("speed", 10.0, u_w=1.0, omega=0.3)


def test_the_registry_picks_the_experiment_by_the_loads():
    assert experiment_for([HELD, Load("speed", 5.0, u_w=2.0)]) is StokesDrives
    assert experiment_for([SINE]) is OscillatingPlate
    with pytest.raises(ValueError, match="RUN_DIR.*one experiment"):
        experiment_for([HELD, SINE])
    assert {k.name for k in experiments()} >= {"stokes", "oscillating"}


def test_an_option_the_experiment_does_not_take_is_refused_before_any_work(tmp_path):
    with pytest.raises(ValueError, match="--ngf-from.*stokes"):
        StokesDrives.create(tmp_path / "none.json", ngf_from=tmp_path / "m.json")
    with pytest.raises(ValueError, match="--fit-on-drives.*oscillating"):
        OscillatingPlate.create(None, fit_on_drives=True)
    with pytest.raises(ValueError, match="--calibration is required"):
        OscillatingPlate.create(None)
    with pytest.raises(ValueError, match="--any-pair-style.*oscillating"):
        OscillatingPlate.create(tmp_path / "none.json", any_pair_style=True)
    with pytest.raises(ValueError, match="^--any-pair-style must be with --calibration"):
        StokesDrives.create(None, fit_on_drives=True, any_pair_style=True)


def test_no_pipeline_branch_on_the_oscillating_plate_outside_the_experiments():
    """The comparison, the study and the commands never test whether drives oscillate: the registry does."""
    allowed = {"compare/oscillation_experiment.py", "compare/stokes_experiment.py", "continuum/load.py"}
    found = []
    for folder in ("compare", "granstokes", "continuum", "dem"):
        for path in (ROOT / folder).rglob("*.py"):
            rel = str(path.relative_to(ROOT))
            if rel in allowed:
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.If | ast.IfExp) and "oscillat" in ast.unparse(node.test):
                    found.append(f"{rel}:{node.lineno}")
    assert not found, found


Z95, T3 = stats.norm.ppf(0.975), stats.t.ppf(0.975, 3)  # 1.96; 3.18 (four samples)


@pytest.mark.parametrize(("sigma", "note", "dof", "verdict"), [
    (Z95, "", np.inf, "consistent"), (-Z95, "", np.inf, "consistent"), (Z95 + 1e-4, "", np.inf, "disagrees"),
    (2.0, "", np.inf, "disagrees"), (np.nan, "", np.inf, "disagrees"),
    (-3.0, "", 3, "consistent"), (T3, "", 3, "consistent"), (T3 + 1e-4, "", 3, "disagrees"),
    (0.1, "not scored: the flow reaches the base", 3, "not scored"),
    (0.1, "not measurable: one bed", np.nan, "not measurable"),
    (0.1, "not predicted: no amplitude", 3, "not predicted")])
def test_one_verdict_rule(sigma, note, dof, verdict):
    """Consistent within Student-t's 97.5 % quantile at the row's dof (the normal one at infinitely many); a note's
    head decides whatever the dof."""
    assert rows.verdict(sigma, note, dof) == verdict


def test_a_note_that_does_not_say_why_is_refused():
    with pytest.raises(ValueError, match="must start with"):
        rows.verdict(0.0, "censored by the base")


def test_sigma_adds_the_errors_in_quadrature():
    assert rows.sigma(5.0, 3.0, 4.0) == pytest.approx(1.0)
    assert np.isnan(rows.sigma(1.0, 0.0, 0.0)) and np.isnan(rows.sigma(1.0, np.nan))


def test_the_calibration_band_of_a_linear_prediction_is_exact():
    """F = a . p: sd = sqrt(a C a) whatever the step; F = p0^2: the one-sided difference errs by STEP/2."""
    cov = pd.DataFrame([[0.04, 0.01], [0.01, 0.09]], index=["x", "y"], columns=["x", "y"])
    a = np.array([3.0, -2.0])
    sens = band.Sensitivity.of(lambda q: a @ np.array([q["x"], q["y"]]), {"x": 1.5, "y": 0.7}, cov)
    assert sens.sd_of(lambda j: sens.shifted[j], a @ [1.5, 0.7]) == pytest.approx(np.sqrt(a @ cov.to_numpy() @ a),
                                                                                   rel=1e-9)
    square = band.Sensitivity.of(lambda q: q["x"] ** 2, {"x": 2.0}, cov)
    assert square.steps == (band.STEP * 2.0,)
    assert square.sd_of(lambda j: square.shifted[j], 4.0) == pytest.approx(2 * 2.0 * 0.2 * (1 + band.STEP / 2),
                                                                            rel=1e-9)
    assert square.cov[0, 0] == pytest.approx(0.04)  # names the covariance lacks have no variance: "A" alone
    alone = band.Sensitivity.of(lambda q: q["A"], {"A": 1.0}, cov)
    assert alone.sd_of(lambda j: alone.shifted[j], 1.0) == 0.0


@dataclass(frozen=True)
class ToyResult:
    rows: pd.DataFrame
    laws: pd.DataFrame
    runs: tuple
    calibration_source: str


class ToyPlate(Experiment):
    """A third experiment in twenty lines: loads of kind "toy" (none exist, so it never takes a real drive)."""

    name, title, problem, tables_marker = "toy", "a toy plate", "a toy", "toy.json"
    titles, how_to_read, definitions = {}, {}, {"gap": ("d", "a toy observable")}

    @classmethod
    def accepts(cls, load) -> bool:
        return load.kind == "toy"

    def _prepare(self, dem):
        return 2.0

    def _units(self, dem, setup):
        return list(dem)

    def _predict(self, unit, setup):
        label, value, err = unit
        return rows.score_row(drive=label, observable="gap", unit="d", dem=value, dem_err=err, dem_how="toy",
                              model="double", model_label="twice one", predicted=setup, band=rows.band(setup, 0.0),
                              numerical_err=0.0, calibration_sd=0.0, sigma=rows.sigma(value - setup, err),
                              dof=np.inf, note="", blind=True)

    def _conclude(self, dem, setup, predicted):
        law = rows.law_row(law="toy_law", quantity="gap", unit="d", kind="toy", model="double", dem=1.0, dem_err=0.8,
                           predicted=2.0, predicted_err=0.0, sigma=-1.25, dof=np.inf, chi2_dof=np.nan,
                           n_drives=len(dem), window="", note="",
                           choices=[], systematic=np.nan)
        return ToyResult(pd.DataFrame(predicted), pd.DataFrame([law]), ("runs/toy",), "none")

    @classmethod
    def write_tables(cls, result, folder):
        folder.mkdir(parents=True)
        (folder / cls.tables_marker).write_text("[]")

    @classmethod
    def verdict(cls, result):
        return f"{int((result.rows.verdict == 'consistent').sum())} of {len(result.rows)} consistent"

    @classmethod
    def sections(cls, result, metrics):
        return [Section("Toy", "<p>toy section</p>", "toy")]


def test_a_new_experiment_is_a_subclass_and_nothing_else(tmp_path):
    experiment = ToyPlate(progress=False, jobs=2)
    result = experiment.run([("a", 2.1, 0.1), ("b", 2.5, 0.1)])  # two forked processes
    assert list(result.rows.verdict) == ["consistent", "disagrees"]
    assert list(result.rows.columns[:len(rows.ROW_KEYS)]) == list(rows.ROW_KEYS)
    m = ToyPlate.write(result, tmp_path)
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["experiment"] == "toy" and saved["verdict"] == "1 of 2 consistent" == m["verdict"]
    assert saved["scorecard"][1]["sigma"] == pytest.approx(5.0) and saved["laws"][0]["band"] == [2.0, 2.0]
    assert saved["definitions"]["gap"] == {"unit": "d", "definition": "a toy observable"}
    assert saved["tally"][0]["n"] == 2 and "provenance" in saved and "units" in saved
    page = (tmp_path / "index.html").read_text()
    assert "<h1>A toy plate</h1>" in page and "toy section" in page and "a toy observable" in page
    assert "<a href='#toy'>Toy</a>" in page and [(f["finding"], f["status"]) for f in saved["findings"]] == [
        ("Gap", "shown"), ("Toy law", "not shown")]  # rows no effect claims: a finding each, by their name
    assert (tmp_path / "tables" / "toy.json").is_file() and (tmp_path / "scorecard.csv").is_file()
    assert re.search(r"consistent", (tmp_path / "scorecard.csv").read_text())
