"""An output file the user changed is never replaced or removed (granstokes.staging's checksum records): a rerun
or a resume over a changed file is refused with one line naming it and exit status 2, leaving every file as it
was; an unchanged output is replaced and its manifest records each file's sha256; a resume accepts its own
partial files; outputs get the mode the umask gives."""
import hashlib
import json
import os
import stat

import pytest
from granstokes.dem import config, layout
from granstokes.dem.runner import Runner, adds_beds, begin, completed_stages
from granstokes.dem.sizing import plan

from granstokes.cli import main
from granstokes.lib import staging
from granstokes.lib.executor import Outcome

SOLVE = ["continuum", "--mu-s", "0.38", "--mu-d", "0.64", "--mu-w-tilde", "0.5", "--times", "0.1", "1"]


def _snapshot(root):
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def _run(argv, capsys):
    try:
        code = main([str(a) for a in argv])
    except SystemExit as stop:
        code = stop.code
    return code, capsys.readouterr().err.strip()


def _write(out, files, command="cmd", keep=False):
    with staging.staged(out, command, keep=keep) as work:
        for rel, text in files.items():
            (work / rel).parent.mkdir(parents=True, exist_ok=True)
            (work / rel).write_text(text)


def test_a_saved_csv_the_user_edited_is_not_replaced_by_a_second_save(tmp_path, capsys):
    out = tmp_path / "saved"
    assert _run([*SOLVE, "--save", out], capsys)[0] == 0
    csv = sorted(out.glob("*_profiles.csv"))[0]
    csv.write_text(csv.read_text() + "my own row\n")
    before = _snapshot(tmp_path)
    code, err = _run([*SOLVE, "--save", out], capsys)
    assert code == 2
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert "--save" in err and str(csv) in err and "changed since granstokes continuum wrote it" in err
    assert _snapshot(tmp_path) == before  # the edited file byte for byte, nothing half-written


def test_a_second_save_without_edits_replaces_the_files_and_records_their_sha256(tmp_path, capsys):
    out = tmp_path / "saved"
    assert _run([*SOLVE, "--save", out], capsys)[0] == 0
    first = {p.name: p.stat().st_ino for p in out.iterdir()}
    assert _run([*SOLVE, "--save", out], capsys)[0] == 0
    manifest = staging.read_manifest(out)
    files = sorted(p.name for p in out.iterdir() if p.name != staging.MANIFEST)
    assert manifest["files"] == files and sorted(manifest["checksums"]) == files
    for name in files:
        data = (out / name).read_bytes()
        assert manifest["checksums"][name] == {"sha256": hashlib.sha256(data).hexdigest(), "size": len(data)}
        assert (out / name).stat().st_ino != first[name]  # replaced, not left


def test_a_stale_file_the_user_edited_is_not_removed(tmp_path):
    out = tmp_path / "report"
    _write(out, {"a.csv": "1", "figs/b.png": "2"})
    (out / "figs" / "b.png").write_text("the user's version")
    before = _snapshot(out)
    with pytest.raises(ValueError, match="figs/b.png was changed since granstokes cmd wrote it"):
        staging.claim(out, "--out", "cmd")
    with pytest.raises(ValueError, match="figs/b.png was changed"):  # the commit checks again, before any move
        _write(out, {"a.csv": "3"})
    assert _snapshot(out) == before
    (out / "figs" / "b.png").unlink()  # moved away: the rest of the output is the command's to replace
    _write(out, {"a.csv": "3"})
    assert _snapshot(out).keys() == {"a.csv", staging.MANIFEST} and (out / "a.csv").read_text() == "3"


def test_a_file_edited_while_the_command_ran_is_not_replaced(tmp_path):
    out = tmp_path / "report"
    _write(out, {"a.csv": "1", "b.csv": "1"})
    staging.claim(out, "--out", "cmd")
    with pytest.raises(ValueError, match="a.csv was changed"), staging.staged(out, "cmd") as work:
        (work / "a.csv").write_text("2")
        (work / "b.csv").write_text("2")
        (out / "a.csv").write_text("edited during the solve")
    assert (out / "a.csv").read_text() == "edited during the solve" and (out / "b.csv").read_text() == "1"


def test_a_manifest_without_checksums_owns_its_files_as_listed(tmp_path):
    out = tmp_path / "report"
    _write(out, {"a.csv": "1", "b.csv": "1"})
    doc = staging.read_manifest(out)
    del doc["checksums"]
    (out / staging.MANIFEST).write_text(json.dumps(doc))
    (out / "a.csv").write_text("changed, but nothing records what was written")
    _write(out, {"a.csv": "2"})
    assert _snapshot(out).keys() == {"a.csv", staging.MANIFEST} and (out / "a.csv").read_text() == "2"
    assert staging.read_manifest(out)["checksums"]["a.csv"]["sha256"] == hashlib.sha256(b"2").hexdigest()


def test_a_changed_file_in_a_nested_output_is_found_when_asked(tmp_path):
    study = tmp_path / "study"
    staging.start(study, "study")
    run = staging.start(study / "runs" / "p10", "dem run")
    (run / "plate.csv").write_text("step\n1\n")
    staging.seal(run, "dem run")
    staging.seal(study, "study")
    assert staging.read_manifest(study)["files"] == []  # the run is its own output
    (run / "plate.csv").write_text("step\n2\n")
    staging.require_unchanged(study, "--out")
    with pytest.raises(ValueError, match=r"--out: .*runs/p10/plate.csv was changed since granstokes dem run"):
        staging.require_unchanged(study, "--out", nested=True)


# --- progressive outputs: a DEM run folder (no LAMMPS run) ---------------------------------------------------------

def _stopped_run(folder):
    """A smoke run folder begun, its bed prepared, its drive interrupted part-way, ended as a run ends
    (``Runner.finish``: the manifest records what is finished)."""
    text = config.preset_text("smoke")
    staging.start(folder, "dem run")
    (folder / layout.CONFIG_TOML).write_text(text)
    prepare, drive = layout.prepare_dir(folder, 1), layout.drive_dir(folder, 1, "speed")
    stages = {"seed-1": {"status": "complete", "path": str(prepare.relative_to(folder))},
              "seed-1/speed": {"status": "interrupted", "path": str(drive.relative_to(folder))}}
    (folder / layout.RUN_JSON).write_text(json.dumps({"status": "running", "stages": stages}))
    prepare.mkdir(parents=True)
    (prepare / layout.PREPARED_RESTART).write_text("the prepared bed")
    (prepare / layout.GRAINS_CSV).write_text("id,type,radius,mass\n")
    (drive / layout.SEGMENTS / "000").mkdir(parents=True)
    (drive / layout.SEGMENTS / "000" / layout.PLATE_CSV).write_text("step,t\n0,0\n")
    runner = Runner(plan(config.parse(text)), text, folder, 1, None, False)
    runner.finish({"status": "running", "message": "", "timings": {}}, [Outcome("interrupted", "SIGINT")], 0.0)
    return folder


def test_a_stopped_run_records_its_config_and_finished_stages_only(tmp_path):
    run = _stopped_run(tmp_path / "run")
    manifest = staging.read_manifest(run)
    assert manifest["command"] == "dem run" and manifest["progressive"]
    assert set(manifest["files"]) == {p for p in _snapshot(run) if p != staging.MANIFEST}
    assert set(manifest["checksums"]) == {"config.toml", "seed-1/prepare/prepared.restart",
                                          "seed-1/prepare/grains.csv"}


def test_a_resume_over_an_edited_finished_file_is_refused_untouched(tmp_path, capsys):
    run = _stopped_run(tmp_path / "run")
    edited = layout.prepare_dir(run, 1) / layout.GRAINS_CSV
    edited.write_text("id,type,radius,mass\n1,1,0.5,0.8\n")
    before = _snapshot(run)
    code, err = _run(["dem", "run", "--resume", "--out", run, "--dry-run"], capsys)
    assert code == 2 and len(err.splitlines()) == 1 and "Traceback" not in err
    assert f"--out: {edited} was changed since granstokes dem run wrote it" in err
    assert _snapshot(run) == before


def test_a_resume_accepts_its_own_partial_files(tmp_path, capsys):
    run = _stopped_run(tmp_path / "run")
    # a bed stopped elsewhere went on writing its drive and run.json after the run ended
    segment = layout.drive_dir(run, 1, "speed") / layout.SEGMENTS / "000"
    (segment / layout.PLATE_CSV).write_text("step,t\n0,0\n100,0.1\n")
    (run / layout.RUN_JSON).write_text((run / layout.RUN_JSON).read_text().replace("running", "interrupted"))
    assert _run(["dem", "run", "--resume", "--out", run, "--dry-run"], capsys)[0] == 0
    # a resume reopens the folder; killed before its end, its files (finished ones too) are its own to go on with
    staging.resume(run, "dem run")
    assert staging.read_manifest(run)["checksums"] == {}
    (layout.prepare_dir(run, 1) / layout.GRAINS_CSV).write_text("rewritten by the killed resume\n")
    assert _run(["dem", "run", "--resume", "--out", run, "--dry-run"], capsys)[0] == 0


def test_a_complete_run_records_every_file(tmp_path):
    run = _stopped_run(tmp_path / "run")
    text = (run / layout.CONFIG_TOML).read_text()
    Runner(plan(config.parse(text)), text, run, 1, None, False).finish(
        {"status": "running", "message": "", "timings": {}}, [Outcome("complete")], 0.0)
    manifest = staging.read_manifest(run)
    assert set(manifest["checksums"]) == set(manifest["files"]) == {p for p in _snapshot(run) if p != staging.MANIFEST}


# --- modes ---------------------------------------------------------------------------------------------------------

@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def test_outputs_get_the_mode_the_umask_gives(tmp_path, capsys, umask_022):
    out, plot = tmp_path / "saved", tmp_path / "profiles.png"
    assert _run([*SOLVE, "--save", out, "--plot", plot], capsys)[0] == 0
    staging.write_json(tmp_path / "record.json", {"a": 1})
    staging.seal(staging.start(tmp_path / "run", "dem run"), "dem run")
    files = [*out.iterdir(), plot, tmp_path / "record.json", tmp_path / "run" / staging.MANIFEST]
    assert staging.MANIFEST in {p.name for p in files} and len(files) == 7
    assert {p.name: oct(stat.S_IMODE(p.stat().st_mode)) for p in files} == {p.name: "0o644" for p in files}


def test_a_resume_that_adds_seeds_keeps_every_bed_run_and_runs_only_the_new_ones(tmp_path, capsys):
    """Sequential design: ``dem run --resume --set seeds=[...]`` with seeds that continue the stored ones adds their
    beds (config.toml and run.json then hold them; the stages done stay done); any other change, reordered seeds
    included, is refused by name and the folder left as it was."""
    run = _stopped_run(tmp_path / "run")
    stored = config.parse((run / layout.CONFIG_TOML).read_text())
    more = [*stored.seeds, max(stored.seeds) + 1, max(stored.seeds) + 2]
    before = _snapshot(run)
    for change in ([f"seeds={list(reversed(more))}"], ["load.p_w=7.0"], [f"seeds={more}", "load.p_w=7.0"]):
        code, err = _run(["dem", "run", "--resume", "--out", run, "--dry-run", *sum((["--set", c] for c in change),
                                                                                   [])], capsys)
        assert code == 2 and "--resume must be given with the config stored in" in err and _snapshot(run) == before
    code, err = _run(["dem", "run", "--resume", "--out", run, "--dry-run", "--set", f"seeds={more}"], capsys)
    stages = len(plan(stored).stage_keys(1)) * len(more)  # a preparation and the drives, per bed
    assert code == 0 and f"resume: 1 of {stages} stages complete (seed-1)" in err and _snapshot(run) == before
    text = config_text_with(run, more)
    begin(plan(config.parse(text)), text, run, resume=True, progress=False)
    assert config.parse((run / layout.CONFIG_TOML).read_text()).seeds == tuple(more)
    assert json.loads((run / layout.RUN_JSON).read_text())["seeds"] == more
    done, left = completed_stages(run, plan(config.parse(text)))
    assert done == ["seed-1"] and {f"seed-{s}" for s in more[len(stored.seeds):]} <= set(left)
    assert adds_beds(stored, config.parse(text)) and not adds_beds(config.parse(text), stored)


def config_text_with(run, seeds) -> str:
    """The run's stored config with ``seeds``, as ``--set`` writes it."""
    from granstokes.lib.toml_text import with_entries

    return with_entries((run / layout.CONFIG_TOML).read_text(), [("seeds", seeds)], header="more beds")
