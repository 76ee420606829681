"""The tally behind the headline's ranking (compare/rows.py): its share is consistent rows over rows, its order is
by share then median |sigma| with a fresh index, and an empty scorecard gives an empty table with the same columns."""
import pandas as pd
import pytest
from granstokes.compare.rows import tally
from scipy import stats

COLUMNS = ["model", "label", "n", "consistent", "share", "median_abs_sigma"]


def _row(drive, model, sigma):
    return {"drive": drive, "observable": "u_w_inf", "model": model, "model_label": f"{model} model", "sigma": sigma,
            "scored": True, "blind": True,
            "verdict": "consistent" if abs(sigma) <= stats.norm.ppf(0.975) else "disagrees"}  # the threshold at inf dof


def test_the_share_is_consistent_rows_over_rows_and_orders_the_models():
    rows = pd.DataFrame([_row(d, "b", s) for d, s in zip("xyz", (0.5, 3.0, 4.0))]
                        + [_row(d, "a", s) for d, s in zip("xyz", (1.0, 1.5, 5.0))]
                        + [_row(d, "c", s) for d, s in zip("xyz", (0.1, 0.2, 0.3))])
    t = tally(rows)
    assert list(t.columns) == ["model", "label", "n", "consistent", "median_abs_sigma", "share"]
    assert list(t.model) == ["c", "a", "b"] and list(t.index) == [0, 1, 2]
    assert t.share.tolist() == pytest.approx([1.0, 2 / 3, 1 / 3])
    assert list(t.label) == ["c model", "a model", "b model"]


def test_an_empty_scorecard_gives_an_empty_tally_with_its_columns():
    for rows in (pd.DataFrame(), pd.DataFrame([{**_row("x", "a", 0.1), "scored": False}])):
        t = tally(rows)
        assert t.empty and list(t.columns) == COLUMNS


def test_models_tied_exactly_keep_the_order_they_were_given():
    """Equal share and median |sigma|: the order of the scorecard's models, not the alphabet (z before a)."""
    rows = pd.DataFrame([_row(d, "z", s) for d, s in zip("xy", (0.5, 3.0))]
                        + [_row(d, "a", s) for d, s in zip("xy", (3.0, 0.5))])
    assert list(tally(rows).model) == ["z", "a"]
