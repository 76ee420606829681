"""A committed study's report is regenerated from its committed tables, by the command its README gives, with the
same scorecard and law rows (bench/regenerate.py does all three studies); and the row comparison itself finds a
changed number, a missing row and a changed word."""
import copy
import json
import re
import shlex
from pathlib import Path

import pytest
from granstokes.compare.metrics import row_differences

from granstokes.cli import main

ROOT = Path(__file__).resolve().parents[2]
#: regenerated rows equal the committed ones to this relative difference (the tables hold nine digits; the
#: comparison is deterministic)
REGENERATED_RTOL = 1e-9


def test_row_differences_find_a_changed_number_a_missing_row_and_a_changed_word():
    committed = json.loads((ROOT / "results" / "study-spheres" / "metrics.json").read_text())
    same = row_differences(committed, copy.deepcopy(committed))
    assert all(d["max_relative"] == 0 and not d["words_differ"] and d["rows"] > 0 for d in same.values())
    changed = copy.deepcopy(committed)
    changed["scorecard"][3]["sigma"] *= 1 + 1e-6
    changed["laws"][0]["verdict"] = "consistent" if changed["laws"][0]["verdict"] != "consistent" else "disagrees"
    del changed["laws"][1]
    d = row_differences(committed, changed)
    assert d["scorecard"]["max_relative"] == pytest.approx(1e-6, rel=1e-3)
    assert d["laws"]["words_differ"] == ["verdict"] and d["laws"]["only_committed"] == 1


@pytest.mark.slow
def test_the_spheres_study_regenerates_from_its_tables(tmp_path):
    text = (ROOT / "results" / "study-spheres" / "README.md").read_text()
    command = re.search(r"^\s+granstokes (compare --tables .*?) --out REPORT_DIR", text, flags=re.S | re.M).group(1)
    args = shlex.split(command.replace("\\\n", " "))
    args = [str(ROOT / a) if a.startswith("results/") else a for a in args]
    assert main([*args, "--out", str(tmp_path / "report")]) == 0
    committed = json.loads((ROOT / "results" / "study-spheres" / "metrics.json").read_text())
    d = row_differences(committed, json.loads((tmp_path / "report" / "metrics.json").read_text()))
    for section in ("scorecard", "laws"):
        assert d[section]["rows"] > 0 and d[section]["only_committed"] == d[section]["only_regenerated"] == 0
        assert d[section]["max_relative"] <= REGENERATED_RTOL and not d[section]["words_differ"], d


def test_a_law_s_choices_are_compared_as_words():
    """A law row's choices (dicts with words) are equal or a word difference, never a number to subtract."""
    committed = {"scorecard": [], "laws": [{"law": "growth", "quantity": "n", "kind": "stress", "model": "local",
                                            "dem": 0.5, "choices": [{"estimator": "delta_05", "dem": 0.5}]}]}
    assert row_differences(committed, copy.deepcopy(committed))["laws"]["words_differ"] == []
    changed = copy.deepcopy(committed)
    changed["laws"][0]["choices"][0]["dem"] = 0.6
    d = row_differences(committed, changed)["laws"]
    assert d["words_differ"] == ["choices"] and d["max_relative"] == 0
