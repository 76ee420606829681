"""One finding per effect: rows of one effect make one finding with its strongest robust evidence, unscored rows a
finding "not measurable", rows against the effect's sign a "mixed" one; every law and observable of the studies
belongs to exactly one effect; and the report opens with the verdict and the findings, in words, before any figure,
its contents linking to pages that exist."""
import re
from dataclasses import dataclass
from html.parser import HTMLParser

import numpy as np
import pandas as pd
import pytest
from granstokes.compare import findings as fd
from granstokes.compare import rows
from granstokes.compare.experiment import DRIVES, INDEX, SCORECARD, Experiment, FigureFile, Section
from granstokes.compare.laws import LAWS
from granstokes.compare.oscillation import OBSERVABLES as OSC_OBSERVABLES
from granstokes.compare.oscillation_report import _periodic
from granstokes.compare.scorecard import OBSERVABLES, SLIP_MAX
from granstokes.compare.words import LAW_WORDS, OBSERVABLE_WORDS

#: the oscillating plate's laws (compare.oscillation.laws names them in its rows)
OSC_LAWS = ("yielded_depth_exponent", "phase_lag_slope")
LAYER = fd.EFFECTS[0]
STEADY = next(e for e in fd.EFFECTS if e.name.startswith("The steady plate speed"))


def score(drive, observable, model, sigma, note="", **extra):
    """A scorecard row with DEM 1 +- 0.1 and the prediction sigma standard errors away."""
    return rows.score_row(drive=drive, observable=observable, unit="d", dem=1.0, dem_err=0.1, dem_how="seeds",
                          model=model, model_label=model, predicted=1.0 - 0.1 * sigma, band=[0.0, 2.0],
                          numerical_err=0.0, calibration_sd=0.0, sigma=sigma, dof=np.inf, note=note, blind=True,
                          **extra)


def law(name, quantity, model, sigma, note="", **extra):
    extra = {"kind": "stress", "chi2_dof": np.nan, "choices": [], "systematic": np.nan, **extra}
    return rows.law_row(law=name, quantity=quantity, unit="1", model=model, dem=1.0, dem_err=0.1,
                        predicted=1.0 - 0.1 * sigma, predicted_err=0.0, sigma=sigma, dof=np.inf, n_drives=3, window="",
                        note=note, **extra)


def test_three_rows_of_one_effect_make_one_finding_with_the_strongest_robust_evidence():
    """The layer's steady depth (+5), creep (+12) and early depth (+30, but +8 at its most lenient estimator): one
    finding, shown by all three, its evidence the creep at +12 (the early depth's robust sigma is 8 < 12)."""
    card = pd.DataFrame([score("a", "delta_u", "local", 5.0), score("a", "creep_length", "local", 12.0)])
    choices = [{"estimator": "delta_05", "reference": "plate", "from_transits": 3, "sigma": 30.0},
               {"estimator": "delta_50", "reference": "plate", "from_transits": 10, "sigma": 8.0},
               {"estimator": "delta_50", "reference": "contact layer", "from_transits": 1, "sigma": np.nan}]
    laws = pd.DataFrame([law("delta_growth_prefactor", "delta_u / sqrt(nu_g t)", "paper", 30.0, choices=choices)])
    found = fd.findings(card, laws)
    assert [f.effect for f in found] == [LAYER.name]
    (f,) = found
    assert (f.status, f.scored, f.backing, f.against, f.unscored) == ("shown", 3, 3, 0, 0)
    assert f.evidence["observable"] == "creep_length" and f.robust == 12.0 and f.choice is None
    assert fd.robust_sigma(laws.iloc[0].to_dict()) == (8.0, choices[1])
    assert fd.rows_text(f) == "3 of 3 scored rows disagree as it says"


def test_an_effect_whose_rows_are_all_unscored_is_not_measurable_and_says_why():
    why = "not measurable: 2 drive(s) with a t90 and a t_s (at least 3, 2 values)"
    laws = pd.DataFrame([law("t_s_collapse", "slope of log t90 against log t_s", "paper", np.nan, note=why)])
    card = pd.DataFrame([score("a", "t90", "ngf", 3.0, note="not predicted: assumed time scale", kind="stress")])
    (f,) = fd.findings(card, laws)
    assert f.effect.startswith("Under an imposed stress") and f.status == "not measurable"
    assert f.evidence is None and (f.scored, f.unscored) == (0, 2)
    assert f.why == ("not predicted: assumed time scale", why) and fd.evidence_text(f) == ""
    assert fd.as_dict(f)["evidence_row"] is None


def test_a_row_that_disagrees_against_the_effect_s_sign_makes_it_mixed_and_a_consistent_one_not_shown():
    """The layer deeper in the DEM (+): a steady depth at +4 backs it, a creep at -3 goes against it; a growth
    exponent at -1.5 is consistent (neither)."""
    card = pd.DataFrame([score("a", "delta_u", "paper", 4.0), score("b", "creep_length", "local", -3.0)])
    f, = fd.findings(card, pd.DataFrame([law("delta_growth_exponent", "n", "paper", -1.5)]))
    assert (f.status, f.backing, f.against, f.scored) == ("mixed", 1, 1, 3) and f.robust == 4.0
    quiet, = fd.findings(pd.DataFrame([score("a", "delta_u", "paper", 1.9)]), None)
    assert quiet.status == "not shown"


def test_the_rigid_plastic_models_and_ngf_are_separate_findings_and_the_stronger_is_listed_first():
    card = pd.DataFrame([score("a", "delta_u", "ngf", -14.0), score("a", "delta_u", "local", 20.0),
                         score("a", "u_w_inf", "local", 0.5)])
    found = fd.findings(card, None)
    assert [(f.effect, f.status, f.robust) for f in found] == [
        (LAYER.name, "shown", 20.0), ("NGF's layer differs from the DEM's", "shown", -14.0),
        (STEADY.name, "not shown", 0.5)]


def test_the_scene_names_the_drives_that_fail_and_whether_the_evidence_s_drive_is_one():
    card = pd.DataFrame([score("runs/p5/a", "delta_u", "local", 9.0), score("runs/p10/b", "delta_u", "local", 3.0)])
    scene = [{"check": "slip", "drive": "runs/p5/a", "holds": False, "detail": "slip 9 %"},
             {"check": "slip", "drive": "runs/p10/b", "holds": True, "detail": "slip 2 %"},
             {"check": "base", "drive": "runs/p5/a", "holds": True, "detail": ""},
             {"check": "base", "drive": "runs/p10/b", "holds": True, "detail": ""},
             {"check": "depth", "drive": "runs/p5/a", "holds": True, "detail": ""},
             {"check": "depth", "drive": "runs/p10/b", "holds": False, "detail": "the bed (26 d) is shorter"}]
    (f,) = fd.findings(card, None, scene, names={"runs/p5/a": "p5: a"})
    assert {s.check.key: s.text() for s in f.scene if s.check.key not in ("slip", "depth")} == {
        "transit": "the elastic transit: not known", "record": "the record's length: not known",
        "base": "the base: holds"}
    assert fd.scene_text(f) == ("the bed leaves less than the depth study's clearance below delta_s in 1 of 2 drives "
                                "(runs/p10/b: the bed (26 d) is shorter); "
                                f"the plate slips by more than {SLIP_MAX * 100:g} % in 1 of 2 drives (p5: a: slip "
                                "9 %), the evidence's drive among them; the base: holds in every drive; the elastic "
                                "transit, the record's length: not known")
    slip = next(s for s in f.scene if s.check.key == "slip")
    assert slip.holds is False and slip.evidence_fails and slip.failing == ("p5: a: slip 9 %",)


@pytest.mark.parametrize("model", ["local", "paper", "ngf", "elastic"])
def test_every_law_and_observable_of_the_studies_belongs_to_exactly_one_effect(model):
    observables = [{"observable": o, "model": model} for o in OBSERVABLES]
    observables += [{"observable": o, "model": model, "kind": k, "omega_ts": w} for o in OSC_OBSERVABLES
                    for k in ("stress", "speed") for w in (0.1, 10.0)]
    observables += [{"observable": "t90", "model": model, "kind": k} for k in ("stress", "speed")]
    laws = [{"law": x.name, "quantity": x.quantity, "model": model} for x in LAWS]
    laws += [{"law": name, "quantity": "", "model": model} for name in OSC_LAWS]
    for row in observables + laws:
        claims = [e.name for e in fd.EFFECTS if e.member(row) is not None]
        if row.get("observable") == "t90" and "kind" not in row:
            assert claims == [], row  # a t90 row without its drive's kind is claimed by neither kind's effect
        else:
            assert len(claims) == 1, (row, claims)


def test_the_layer_rows_of_every_model_rigid_below_yield_are_one_effect():
    """local mu(I), the paper's and the elasto-plastic model have no flow below yield: the DEM's creep beside each is
    one effect (one finding), NGF's layer another."""
    effect = lambda model: next(e.name for e in fd.EFFECTS if e.member({"observable": "creep_length", "model": model}))  # noqa: E731
    assert effect("local") == effect("paper") == effect("elastic") != effect("ngf")


def test_every_law_and_observable_has_its_words():
    assert set(OBSERVABLES) | set(OSC_OBSERVABLES) <= set(OBSERVABLE_WORDS)
    assert {x.name for x in LAWS} | set(OSC_LAWS) <= set(LAW_WORDS)


@pytest.mark.parametrize(("stationary", "periodic"), [([True, True, True], True), ([True, False, None], False),
                                                      ([None, None], None), ([True, None], True)])
def test_a_drive_is_periodic_when_no_bed_fails_and_one_was_tested(stationary, periodic):
    assert _periodic(stationary) is periodic


# --- the report's first screen --------------------------------------------------------------------------------

@dataclass(frozen=True)
class LayerResult:
    rows: pd.DataFrame
    laws: pd.DataFrame
    runs: tuple
    calibration_source: str


class LayerReport(Experiment):
    """Just enough of an experiment to write its report: a figure on the index and on the drives' page, a section
    on the scorecard's."""

    name, title, problem, tables_marker = "layer", "a layer's report", "a layer", "layer.json"
    titles = {"map": "The map", "drive": "A drive"}
    how_to_read = {"map": "how to read the map", "drive": "how to read a drive"}
    definitions = {"delta_u": ("d", "the layer's depth")}

    @classmethod
    def accepts(cls, load) -> bool:
        return load.kind == "layer"  # no load is: it never takes a real drive from the registry

    @classmethod
    def write_tables(cls, result, folder):
        folder.mkdir(parents=True)

    @classmethod
    def verdict(cls, result):
        return "The layer is deeper in the DEM."

    @classmethod
    def files(cls, result, out):
        for png in ("map.png", "drive_a.png"):
            (out / png).write_bytes(b"\x89PNG")
        return [FigureFile("map", out / "map.png"), FigureFile("drive", out / "drive_a.png", "a", DRIVES)]

    @classmethod
    def sections(cls, result, metrics):
        return [Section("Laws", "<p>the laws</p>", "laws"),
                Section("The scorecard", "<p>every row</p>", "scorecard", SCORECARD)]


class Outline(HTMLParser):
    """The order of a page's headings, verdict, tables and images; its links, ids and table cells."""

    def __init__(self):
        super().__init__()
        self.order, self.links, self.ids, self.cells, self._cell = [], [], set(), [], None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.ids |= {a["id"]} if "id" in a else set()
        self.links += [a["href"]] if "href" in a else []
        if tag in ("h1", "h2", "table", "img") or a.get("class") == "verdict":
            self.order.append(a.get("id") or a.get("class") or tag)
        if tag == "td":
            self._cell = []

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)

    def handle_endtag(self, tag):
        if tag == "td":
            self.cells.append("".join(self._cell))
            self._cell = None


def test_the_index_opens_with_the_verdict_and_the_findings_in_words_before_any_figure(tmp_path):
    result = LayerResult(pd.DataFrame([score("a", "delta_u", "local", 9.0), score("a", "creep_length", "local", 4.0)]),
                         pd.DataFrame([law("delta_s_scaling", "offset of delta_u against delta_s", "paper", 6.0)]),
                         ("runs/a",), "none")
    m = LayerReport.write(result, tmp_path)
    page = Outline()
    page.feed((tmp_path / INDEX).read_text())
    assert page.order[:5] == ["h1", "verdict", "findings", "table", "contents"]
    assert page.order.index("table") < page.order.index("img")
    assert "<h1>A layer&#x27;s report</h1>" in (tmp_path / INDEX).read_text()
    for link in page.links:
        assert link[1:] in page.ids if link.startswith("#") else (tmp_path / link).is_file(), link
    assert {SCORECARD, DRIVES} <= set(page.links)
    finding, evidence = page.cells[:2]
    assert finding.startswith(LAYER.name) and finding.endswith("shown")
    assert evidence.startswith(f"{OBSERVABLE_WORDS['delta_u']}, a, local mu(I): DEM 1.00 ± 0.10 d against 0.1 d, "
                               "+9.0 σ")
    code = re.compile("|".join(re.escape(k) for k in [*OBSERVABLE_WORDS, *LAW_WORDS] if "_" in k or k == "t90"))
    assert not any(code.search(cell) for cell in page.cells[:4])
    assert m["findings"][0]["rows_backing"] == 3 and m["findings"][0]["evidence_row"]["robust_sigma"] == 9.0
    for other in (SCORECARD, DRIVES):
        sub = Outline()
        sub.feed((tmp_path / other).read_text())
        assert INDEX in sub.links and sub.order[0] == "h1"
