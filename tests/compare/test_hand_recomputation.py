"""docs/hand-recomputation.md: its code, run on the committed 2D study, finds the report's numbers."""
import math
import os
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_note_s_hand_recomputation_finds_the_committed_report_s_numbers(capsys):
    text = (ROOT / "docs" / "hand-recomputation.md").read_text()
    code = "\n".join(re.findall(r"```python\n(.*?)```", text, flags=re.S))
    namespace = {}
    cwd = os.getcwd()
    try:
        os.chdir(ROOT)
        exec(compile(code, "hand-recomputation.md", "exec"), namespace)
    finally:
        os.chdir(cwd)
    for (observable, label), (value, err) in namespace["by_hand"].items():
        dem, dem_err = namespace["reported"](observable, label)
        assert math.isclose(value, dem, rel_tol=1e-5) and math.isclose(err, dem_err, rel_tol=1e-4), (label, observable)
    law = namespace["law"]
    assert len(namespace["clear"]) >= 6
    assert math.isclose(namespace["slope"], law["slope"], rel_tol=1e-5)
    assert math.isclose(namespace["offset"], law["offset"], rel_tol=1e-5, abs_tol=1e-6)
    printed = capsys.readouterr().out
    assert printed.count("by hand") == 3
