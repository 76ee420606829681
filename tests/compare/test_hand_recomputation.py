"""docs/hand-recomputation.md: its numpy code, run on the committed 2D study's tables, finds the report's numbers
(the committed metrics.json) and today's code run on the same tables finds the same numbers."""
import math
import os
import re
from pathlib import Path

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
    assert len(namespace["kept"]) == law["n_drives"]  # the depth, grip and calibration-range rules, by hand
    assert (len(namespace["short"]) + len(namespace["slipping"]) + len(namespace["beyond"]) + law["n_drives"]
            == len(namespace["clear"]))
    offsets = [namespace["family"][k] for k in ("delta_05", "delta_10", "delta_20", "delta_50")]
    assert offsets == sorted(offsets, reverse=True)  # the offset falls with the threshold: a creep tail
    reported = next(r for r in namespace["METRICS"]["laws"]
                    if r["law"] == "delta_s_scaling" and r["model"] == "paper" and r["quantity"].startswith("offset"))
    measured = [c for c in reported["choices"] if c["dem"] is not None and math.isfinite(c["dem"])]
    assert measured  # every measured choice's offset is the hand's (unweighted) within its error
    assert all(abs(namespace["family"][c["estimator"]] - c["dem"]) < c["dem_err"] for c in measured
               if c["estimator"] in namespace["family"])
    printed = capsys.readouterr().out
    assert printed.count("by hand") == 7


@pytest.mark.slow
def test_today_s_compare_on_the_committed_tables_finds_the_hand_numbers():
    """The same numbers from today's code: each drive's tables read back (compare.tables.read_drive), the steady
    response and its error from the plate records (compare.plate through plate_estimates), the steady layer of every
    drive from the DEM's samples (compare.scorecard.dem_observables) and the depth rule (compare.scorecard.short_bed):
    equal to the note's numpy."""
    from granstokes.compare.scorecard import dem_observables, short_bed
    from granstokes.compare.tables import read_drive

    namespace = _hand_recomputation()
    drives = namespace["METRICS"]["drives"]
    for (observable, label), (value, err) in namespace["by_hand"].items():
        a = read_drive(namespace["drive_folder"](label))
        measured = dem_observables(a, delta_s=drives[label]["delta_s"])[observable]
        assert math.isclose(measured.value, value, rel_tol=1e-9) and math.isclose(measured.err, err, rel_tol=1e-9)
    for label in namespace["clear"]:
        a = read_drive(namespace["drive_folder"](label))
        delta_s = drives[label]["delta_s"]
        today = dem_observables(a, delta_s=delta_s)["delta_u"].value
        assert math.isclose(today, namespace["steady_delta_u"](label), rel_tol=1e-9), label
        assert bool(short_bed(a, delta_s)) == (label in namespace["short"]), label
