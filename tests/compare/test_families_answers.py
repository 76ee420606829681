"""The words and the bookkeeping of an estimator family (compare.families): how a choice is named, which entry a law
row's numbers come from, the note of a split family and its systematic, on hand-made entries (no drive, no solver).

The names are compared as whole phrases, written out here: they are what the report prints.  The split family's
threshold is Student-t's 97.5 % quantile at the entry's dof (scipy), so a sigma of 2.5 at 4 dof (threshold 2.78) is
consistent and would not be at infinitely many (1.96); the systematic is half the range of DEM - predicted over the
measured entries, worked out by hand.
"""
import numpy as np
import pytest
from granstokes.compare.drive import TRANSITS_BEFORE_COMPARISON
from granstokes.compare.families import (
    FAMILIES,
    PRIMARY_ESTIMATOR,
    Choice,
    _family,
    describe,
    entry,
    family_note,
    headline,
    measured,
    systematic,
)
from granstokes.compare.rows import ESTIMATOR_DEPENDENT
from scipy import stats


def test_a_choice_is_named_by_its_quantity_its_reference_and_its_start():
    assert Choice("speed", "plate", 1.0).describe() == "the plate's speed from 1 transit"
    assert Choice("speed", "contact", 10.0).describe() == "the contact layer's speed from 10 transits"
    assert Choice("mu_w", "plate", 2.0).describe() == "the plate's friction from 2 transits"
    assert Choice("mu_w", "contact", None).describe() == "the contact layer's friction"
    assert Choice("creep", "contact", None).describe() == "the creep length below delta_s"
    assert Choice("creep_deep", "contact", None).describe() == "the creep length from 2 d below delta_s"
    assert Choice("creep_wide", "contact", None).describe() == "the creep length over 6 d below delta_s"
    assert Choice("t75", "plate", None).describe() == "the time to 75 % of the plate's speed"
    assert Choice("final half", "contact", None).describe() == "the contact layer's speed over the record's final half"
    assert Choice("delta_20", "contact", 0.5).describe() == "delta_20 of the contact layer's speed from 0.5 transits"
    assert Choice("moment", "plate", None).describe() == "moment of the plate's speed"


def test_a_family_lists_its_primary_first_and_once():
    assert FAMILIES["friction"] == (Choice("mu_w"), Choice("mu_w", "plate", 5.0), Choice("mu_w", "plate", 10.0))
    # no window starts inside the elastic start (the load still carried by the wave no rigid-plastic model has)
    starts = {c.from_transits for family in FAMILIES.values() for c in family} - {None}
    assert min(starts) == TRANSITS_BEFORE_COMPARISON == 3.0
    assert FAMILIES["response time"] == (Choice("t90", "plate", None), Choice("t90", "contact", None),
                                         Choice("t75", "plate", None))
    assert [c.estimator for c in FAMILIES["creep"]] == ["creep", "creep_deep", "creep_wide"]
    assert FAMILIES["steady speed"][0] == Choice("final quarter", "plate", None)
    assert all(len(family) >= 3 for family in FAMILIES.values())
    assert FAMILIES["layer"][0] == Choice(PRIMARY_ESTIMATOR) and FAMILIES["layer"].count(Choice(PRIMARY_ESTIMATOR)) == 1
    a, b, c = Choice("speed"), Choice("speed", "plate", 1.0), Choice("speed", "contact", None)
    assert _family(a, [b, a, c]) == (a, b, c)


def _e(choice, dem, predicted, sigma, dof=np.inf, note=""):
    return {"estimator": choice.estimator, "reference": choice.reference, "from_transits": choice.from_transits,
            "dem": dem, "predicted": predicted, "sigma": sigma, "dof": dof, "note": note}


def test_an_entry_with_a_note_has_no_sigma_and_is_not_measured():
    e = entry(Choice("speed"), 2.0, 0.1, 1.0, 0.2, "not measurable: two drives", np.inf)
    assert np.isnan(e["sigma"]) and not measured(e)
    assert entry(Choice("speed"), 2.0, 0.3, 1.0, 0.4, "", np.inf)["sigma"] == pytest.approx(1.0 / 0.5, rel=1e-12)
    assert not measured(_e(Choice("speed"), 1.0, 1.0, 1.5, note="not scored: slips"))
    assert not measured(_e(Choice("speed"), 1.0, 1.0, np.nan))


def test_an_entry_is_described_with_its_own_start():
    assert describe(_e(Choice("mu_w", "plate", 10.0), 1.0, 1.0, 0.0)) == "the plate's friction from 10 transits"


def test_the_headline_entry_is_the_primary_when_measured_else_the_first_measured():
    primary, second, third = Choice("speed"), Choice("speed", "plate", 1.0), Choice("speed", "plate", 10.0)
    unmeasured = _e(primary, 1.0, 1.0, np.nan, note="not measurable: no window")
    assert headline([unmeasured, _e(second, 1.0, 0.5, 1.0), _e(third, 1.0, 0.5, 1.0)]) == 1
    assert headline([_e(primary, 1.0, 0.5, 1.0), _e(second, 1.0, 0.5, 1.0)]) == 0
    assert headline([unmeasured, unmeasured]) == 0


def test_the_systematic_is_half_the_range_of_dem_minus_predicted():
    entries = [_e(Choice("speed"), 3.0, 1.0, 1.0), _e(Choice("speed", "plate", 1.0), 2.0, 1.5, 1.0),
               _e(Choice("speed", "plate", 10.0), 9.0, 0.0, np.nan)]  # not measured: left out
    assert systematic(entries) == pytest.approx(((3.0 - 1.0) - (2.0 - 1.5)) / 2, rel=1e-12)


def test_a_split_family_s_note_lists_each_side_at_its_own_dof():
    dof = 4
    assert 1.96 < 2.5 <= stats.t.ppf(0.975, dof)  # consistent at 4 dof, not at infinitely many
    a, b, c = Choice("speed", "plate", 1.0), Choice("speed", "plate", 10.0), Choice("speed", "contact", None)
    entries = [_e(a, 2.0, 1.0, 2.5, dof), _e(b, 2.0, 1.2, -0.4, dof), _e(c, 5.0, 1.0, 6.0)]
    assert family_note(entries) == (
        f"{ESTIMATOR_DEPENDENT}: 2 of 3 measured choices consistent (the plate's speed from 1 transit +2.5 sigma; "
        "the plate's speed from 10 transits -0.4 sigma), 1 disagree (the contact layer's speed +6.0 sigma); "
        f"systematic {((5.0 - 1.0) - (2.0 - 1.2)) / 2:.3g}")
