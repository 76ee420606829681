"""The row comparison that checks a committed study's regeneration (bench/regenerate.py regenerates all three from
their tables by their READMEs' commands before results are committed; the tables' round trip on a run is
tests/compare/test_report.py's): it finds a changed number, a missing row and a changed word."""
import copy
import json
from pathlib import Path

import pytest
from granstokes.compare.metrics import row_differences

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


def test_a_law_s_choices_are_compared_as_words():
    """A law row's choices (dicts with words) are equal or a word difference, never a number to subtract."""
    committed = {"scorecard": [], "laws": [{"law": "growth", "quantity": "n", "kind": "stress", "model": "local",
                                            "dem": 0.5, "choices": [{"estimator": "delta_05", "dem": 0.5}]}]}
    assert row_differences(committed, copy.deepcopy(committed))["laws"]["words_differ"] == []
    changed = copy.deepcopy(committed)
    changed["laws"][0]["choices"][0]["dem"] = 0.6
    d = row_differences(committed, changed)["laws"]
    assert d["words_differ"] == ["choices"] and d["max_relative"] == 0
