"""A study run in parts (`granstokes compare --tables A --tables B`): the committed 3D tables split by pressure
read back, merged, as the whole (every run, grain table and drive, in order, the same plate records), and a run in two
parts or parts of two experiments are refused by name."""
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from granstokes.compare import tables
from granstokes.compare.stokes_experiment import StokesDrives

from granstokes.cli import main as granstokes_main

ROOT = Path(__file__).resolve().parents[2]
WHOLE = ROOT / "results" / "study-spheres" / "tables"


def _part(whole: Path, folder: Path, run: str) -> Path:
    """The tables of ``whole`` restricted to the run ``run`` (its drives, its grains), as that part's report wrote
    them; the coarse-graining checks those of the part's first drive."""
    meta = json.loads((whole / tables.DEM_JSON).read_text())
    drives = [d for d in meta["drives"] if d.split("-", 1)[1].startswith(Path(run).name + "-")]
    shutil.copytree(whole, folder, ignore=lambda d, names: [n for n in names if Path(d) == whole
                                                            and n.startswith("drive") and n not in drives])
    meta.update(runs=[run], grains={run: meta["grains"][run]}, drives=drives)
    if not meta["checks_drive"].startswith(run + "/"):
        meta["checks_drive"] = f"{run}/{drives[0].split('-', 2)[2]}"
    (folder / tables.DEM_JSON).write_text(json.dumps(meta))
    return folder


def test_the_parts_of_a_study_merge_into_the_whole(tmp_path):
    whole = tables.read(WHOLE)
    assert len(whole.runs) >= 2
    parts = [_part(WHOLE, tmp_path / f"part{k}", str(run)) for k, run in enumerate(whole.runs)]
    merged = StokesDrives.create(None, fit_on_drives=True).read_parts(parts)
    assert merged.runs == whole.runs and merged.grains == whole.grains
    assert [d.label for d in merged.drives] == [d.label for d in whole.drives] and len(merged.drives) == 2 * len(
        whole.runs)  # a stress and a speed drive per pressure
    for m, w in zip(merged.drives, whole.drives):
        assert repr(m.spec) == repr(w.spec) and np.array_equal(m.plates[0].u_w, w.plates[0].u_w)  # NaN t_s in both
        assert m.steady_profile.equals(w.steady_profile)
    assert merged.checks.drive == whole.checks.drive and merged.mass_error == whole.mass_error
    with pytest.raises(ValueError, match="--tables must be tables of distinct runs"):
        tables.merge([tables.read(parts[0]), tables.read(parts[0])])


def test_compare_refuses_parts_of_two_experiments_before_any_work(tmp_path, capsys):
    oscillating = ROOT / "results" / "study-oscillating-disks" / "tables"
    out = tmp_path / "report"
    assert granstokes_main(["compare", "--tables", str(WHOLE), "--tables", str(oscillating), "--out", str(out),
                            "--calibration", str(ROOT / "results/calibration-spheres/p10/calibration.json")]) == 2
    assert "--tables must be tables folders of one experiment" in capsys.readouterr().err and not out.exists()
