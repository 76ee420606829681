"""Bad input across every subcommand: one line on stderr naming the parameter, exit status 2, no
traceback, and nothing left behind (the working folder is unchanged)."""
import json
import re

import pytest

from granstokes.cli import main

BEADS = ["--mu-s", "0.3839", "--mu-d", "0.6494"]
SCENE = ["--mu-s", "0.28", "--mu-d", "0.58", "--I0", "0.3", "--phi", "0.8", "--p-w", "20", "--depth", "30"]


def _files(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def _case(tmp_path, monkeypatch, capsys, argv, name):
    (tmp_path / "a_file.txt").write_text("not a folder")
    (tmp_path / "not_json.toml").write_text("mu_s = 0.3\n")
    (tmp_path / "lacks_keys.json").write_text(json.dumps({"mu_s": 0.3}))
    (tmp_path / "not_a_run").mkdir()
    (tmp_path / "a_run").mkdir()
    (tmp_path / "a_run" / "run.json").write_text(json.dumps({"status": "complete"}))
    from granstokes.dem import config
    (tmp_path / "forever.toml").write_text(config.preset_text("smoke").replace("duration = 7.0", "duration = 1e9"))
    material = "[material]\nmu_s = 0.28\nmu_d = 0.58\nI0 = 0.3\nI_convention = \"dem\"\nphi = 0.8\n"
    assert material in config.preset_text("smoke")
    (tmp_path / "no_material.toml").write_text(config.preset_text("smoke").replace(material, ""))
    (tmp_path / "no_I0.toml").write_text(config.preset_text("smoke").replace("I0 = 0.3\n", ""))
    monkeypatch.chdir(tmp_path)
    before = _files(tmp_path)
    try:
        code = main(argv)
    except SystemExit as stop:  # argparse usage errors
        code = stop.code
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert name in err, err
    assert _files(tmp_path) == before


CASES = [
    # continuum
    (["continuum", *BEADS, "--u-w", "-1", "--times", "1"], "u_w"),
    (["continuum", *BEADS, "--u-w", "nan", "--times", "1"], "u_w"),
    (["continuum", *BEADS, "--mu-w", "0.2", "--times", "1"], "mu_w"),
    (["continuum", *BEADS, "--mu-w", "0.7", "--times", "1"], "mu_w"),
    (["continuum", *BEADS, "--mu-w-tilde", "0", "--times", "1"], "mu_w_tilde"),
    (["continuum", *BEADS, "--mu-w-tilde", "1.5", "--times", "1"], "mu_w_tilde"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "1", "0.5"], "times"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "-1"], "times"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "inf"], "times"),
    (["continuum", "--mu-s", "0.5", "--mu-d", "0.4", "--mu-w-tilde", "0.5", "--times", "1"], "mu_d"),
    (["continuum", "--mu-s", "-0.5", "--mu-d", "0.4", "--mu-w-tilde", "0.5", "--times", "1"], "mu_s"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "1", "--n-cells", "3"], "n_cells"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "1", "--rtol", "2"], "rtol"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "1", "--method", "euler"], "method"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "1", "--plot", "p.jpg"], "--plot"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "1", "--plot", "a_file.txt/p.png"], "--plot"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "1", "--save", "a_file.txt"], "--save"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "1", "--save", "/proc/granstokes"], "--save"),
    (["continuum", *BEADS, "--times", "1"], "--mu-w"),
    (["continuum", *BEADS, "--mu-w-tilde", "0.5"], "--times"),
    # predict
    (["predict", "--model", "ngf", *SCENE, "--mu-w", "0.43", "--steady"], "--A"),
    (["predict", "--model", "local", "--A", "0.5", *SCENE, "--mu-w", "0.43", "--steady"], "--A"),
    (["predict", "--model", "local", *SCENE, "--mu-w", "0.6", "--steady"], "--mu-w"),
    (["predict", "--model", "local", *SCENE, "--u-w", "0", "--steady"], "--u-w"),
    (["predict", "--model", "local", *SCENE, "--mu-w", "0.43", "--times", "2", "1"], "--times"),
    (["predict", "--model", "local", *SCENE, "--mu-w", "0.43", "--steady", "--plate-mass", "-1"], "--plate-mass"),
    (["predict", "--model", "nonlocal", *SCENE, "--mu-w", "0.43", "--steady"], "--model"),
    (["predict", "--model", "ngf", "--A", "0.5", *SCENE, "--mu-w", "0.43", "--steady", "--boundary", "dirchlet"],
     "--boundary"),
    # paper-figures, stability
    (["paper-figures", "--out", "a_file.txt"], "--out"),
    (["paper-figures", "--out", "/proc/granstokes-figures"], "--out"),
    (["stability", "--out", "a_file.txt"], "--out"),
    (["stability", "--out", "maps", "--calibration", "not_json.toml"], "--calibration"),
    (["stability", "--out", "maps", "--calibration", "lacks_keys.json"], "--calibration"),
    (["stability", "--out", "maps", "--calibration", "missing.json"], "--calibration"),
    # dem run
    (["dem", "run", "--preset", "huge", "--out", "r"], "preset"),
    (["dem", "run", "--out", "r"], "CONFIG.toml"),
    (["dem", "run", "not_json.toml", "--out", "r"], "drive"),
    (["dem", "run", "--preset", "smoke", "--out", "r", "--np", "0"], "--np"),
    (["dem", "run", "--preset", "smoke", "--out", "r", "--resume"], "--resume"),
    (["dem", "run", "--preset", "smoke", "--out", "r", "--launcher", "srun"], "--launcher"),
    (["dem", "run", "--preset", "smoke", "--out", "r", "--jobs", "0"], "--jobs"),
    (["dem", "run", "--preset", "smoke", "--out", "a_file.txt"], "--out"),
    (["dem", "run", "forever.toml", "--out", "r"], "duration"),
    (["dem", "run", "no_material.toml", "--out", "r"], "[material]"),
    (["dem", "run", "no_I0.toml", "--out", "r", "--dry-run"], "[material]"),
    (["dem", "run", "--resume", "--out", "not_a_run"], "--resume"),
    (["dem", "run", "--resume", "--out", "missing_run", "--dry-run"], "--resume"),
    (["dem", "run", "forever.toml", "--preset", "smoke", "--out", "r"], "--preset"),
    # dem calibrate
    (["dem", "calibrate", "--preset", "smoke", "--out", "c", "--dry-run", "--jobs", "0"], "--jobs"),
    (["dem", "calibrate", "--preset", "smoke", "--out", "c", "--dry-run", "--np", "0"], "--np"),
    (["dem", "calibrate", "--preset", "smoke", "--out", "a_file.txt", "--dry-run"], "--out"),
    (["dem", "calibrate", "--preset", "smoke", "--out", "c", "--dry-run", "--launcher", "srun"], "--launcher"),
    (["dem", "calibrate", "--preset", "tiny", "--out", "c", "--dry-run"], "--preset"),
    (["dem", "calibrate", "no_material.toml", "--out", "c", "--dry-run"], "[material]"),
    (["dem", "calibrate", "--resume", "--out", "not_a_run"], "--resume"),
    (["dem", "calibrate", "--preset", "smoke", "--resume", "--out", "not_a_run", "--dry-run"], "--resume"),
    # compare
    (["compare", "not_a_run", "--out", "report"], "RUN_DIR"),
    (["compare", "missing_run", "--out", "report"], "RUN_DIR"),
    (["compare", "a_run", "--out", "report"], "--calibration"),
    (["compare", "a_run", "--out", "report", "--calibration", "lacks_keys.json", "--fit-on-drives"], "--fit-on-drives"),
    (["compare", "a_run", "--out", "a_run/report", "--fit-on-drives"], "--out"),
    # demo
    (["demo", "--out", "a_file.txt"], "--out"),
]


@pytest.mark.parametrize("argv, name", CASES, ids=[" ".join(a)[:60] for a, _ in CASES])
def test_bad_input(argv, name, tmp_path, monkeypatch, capsys):
    _case(tmp_path, monkeypatch, capsys, argv, name)


def test_at_least_forty_cases_over_every_subcommand():
    commands = {argv[0] for argv, _ in CASES}
    assert len(CASES) >= 40 and commands >= {"continuum", "predict", "paper-figures", "stability", "dem", "compare",
                                             "demo"}


def test_dry_run_prints_the_cost_and_writes_nothing(tmp_path, capsys):
    from granstokes.dem import config
    from granstokes.dem.estimate import duration_text
    from granstokes.dem.sizing import plan

    assert main(["dem", "run", "--preset", "quick", "--out", str(tmp_path / "r"), "--dry-run", "--np", "64"]) == 0
    err = capsys.readouterr().err
    p = plan(config.preset("quick")[0])
    assert f"about {duration_text(p.cost_seconds(2, 64))} with 2 job(s) x 64 rank(s)" in err and "h with" in err
    assert re.search(r"cost: \d+ grains x 3 bed\(s\)", err) and "oversubscribed" in err
    assert not (tmp_path / "r").exists()
