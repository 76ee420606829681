"""docs/hand-recomputation.md: its numpy code, run on the committed 2D study's tables, finds the report's numbers
(the committed metrics.json) and today's code run on the same tables finds the same numbers."""
import math
import os
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _hand_recomputation() -> dict:
    """The note's code run from the repository's top folder (its paths are relative): its names."""
    text = (ROOT / "docs" / "hand-recomputation.md").read_text()
    code = "\n".join(re.findall(r"```python\n(.*?)```", text, flags=re.S))
    namespace = {}
    cwd = os.getcwd()
    try:
        os.chdir(ROOT)
        exec(compile(code, "hand-recomputation.md", "exec"), namespace)
    finally:
        os.chdir(cwd)
    namespace["STUDY"] = ROOT / namespace["STUDY"]
    return namespace


def test_the_note_s_hand_recomputation_finds_the_committed_report_s_numbers(capsys):
    namespace = _hand_recomputation()
    for (observable, label), (value, err) in namespace["by_hand"].items():
        dem, dem_err = namespace["reported"](observable, label)
        assert math.isclose(value, dem, rel_tol=1e-5) and math.isclose(err, dem_err, rel_tol=1e-4), (label, observable)
    law = namespace["law"]
    assert len(namespace["clear"]) >= 6
    assert math.isclose(namespace["slope"], law["slope"], rel_tol=1e-5)
    assert math.isclose(namespace["offset"], law["offset"], rel_tol=1e-5, abs_tol=1e-6)
    for name, offset in namespace["family"].items():  # the estimator family's choices, each by hand
        assert math.isclose(offset, namespace["offsets"][name], rel_tol=1e-5), name
    assert namespace["family"]["delta_05"] > namespace["family"]["delta_50"]  # the offset depends on the threshold
    printed = capsys.readouterr().out
    assert printed.count("by hand") == 7


@pytest.mark.slow
def test_today_s_compare_on_the_committed_tables_finds_the_hand_numbers():
    """The same numbers from today's code: each drive's tables read back (compare.tables.read_drive), the steady
    response and its error from the plate records (compare.plate through plate_estimates), the steady layer of every
    drive clear of the base from the DEM's samples (compare.scorecard.dem_observables): equal to the note's numpy."""
    from granstokes.compare.scorecard import dem_observables
    from granstokes.compare.tables import read_drive

    namespace = _hand_recomputation()
    for (observable, label), (value, err) in namespace["by_hand"].items():
        a = read_drive(namespace["drive_folder"](label))
        measured = dem_observables(a, delta_s=namespace["METRICS"]["drives"][label]["delta_s"])[observable]
        assert math.isclose(measured.value, value, rel_tol=1e-9) and math.isclose(measured.err, err, rel_tol=1e-9)
    today = []
    for label, hand in zip(namespace["clear"], namespace["delta_u"]):
        a = read_drive(namespace["drive_folder"](label))
        today.append(dem_observables(a, delta_s=namespace["METRICS"]["drives"][label]["delta_s"])["delta_u"].value)
        assert math.isclose(today[-1], hand, rel_tol=1e-9), label
    slope, offset = np.polyfit(namespace["delta_s"], today, 1)
    assert math.isclose(slope, namespace["slope"], rel_tol=1e-9)
