"""A study folder names the files it reads (its calibration, NGF's source) relative to itself, never by this
machine's absolute paths, and a resume reads them back as the same study."""
import json
import tomllib
from pathlib import Path

from granstokes.study import config, runner

ROOT = Path(__file__).resolve().parents[2]


def test_a_study_folder_names_its_inputs_relative_to_itself(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)  # the preset names the committed calibration and NGF's source from the repository's root
    study, text = config.load(None, "oscillating-disks")
    monkeypatch.setattr(runner, "allow_lammps", lambda: None)
    monkeypatch.setattr(runner.StudyRunner, "run", lambda self: (self.calibration(), self.record(lambda d: None))[1])
    out = tmp_path / "study"
    record = runner.run_study(study, text, out, progress=False)
    stored = tomllib.loads((out / runner.STUDY_TOML).read_text())
    named = {"study.toml calibration.file": stored["calibration"]["file"], "study.toml ngf_from": stored["ngf_from"],
             "study.json calibration.source": record["calibration"]["source"]}
    assert not [k for k, v in named.items() if Path(v).is_absolute()], named
    assert (out / named["study.json calibration.source"]).resolve() == Path(study.calibration_file)
    assert (out / named["study.toml ngf_from"]).resolve() == Path(study.ngf_from)
    assert config.parse((out / runner.STUDY_TOML).read_text(), out) == study
    assert json.loads((out / runner.STUDY_JSON).read_text())["calibration"] == record["calibration"]
