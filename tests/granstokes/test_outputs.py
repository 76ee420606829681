"""No command deletes or replaces a file it did not write (granstokes.staging): every command that writes a
folder refuses a non-empty folder that is not its own earlier output, the working folder, an input's own folder
and its parent, with one line and exit status 2, leaving every file as it was; an earlier output of the same
command has only the files its manifest lists replaced."""
import json

import pytest

from granstokes.cli import main
from granstokes.lib import staging

BEADS = ["--mu-s", "0.3839", "--mu-d", "0.6494"]
SOLVE = ["continuum", *BEADS, "--mu-w-tilde", "0.5", "--times", "1"]


def _snapshot(root):
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def _run(argv, capsys):
    try:
        code = main(argv)
    except SystemExit as stop:
        code = stop.code
    return code, capsys.readouterr().err.strip()


@pytest.fixture
def user_folder(tmp_path, monkeypatch):
    """A working folder with the user's own files, a DEM run folder among them."""
    (tmp_path / "notes.txt").write_text("my notes")
    run = tmp_path / "run"
    run.mkdir()
    (run / "run.json").write_text(json.dumps({"status": "complete"}))
    (run / "dump.bin").write_bytes(b"\x00" * 1000)
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "thesis.tex").write_text("chapter 1")
    monkeypatch.chdir(tmp_path)
    return tmp_path


#: each command that writes a folder, with the option naming it (the folder is substituted for OUT)
WRITERS = [
    (["paper-figures", "--out", "OUT"], "--out"),
    (["stability", "--out", "OUT"], "--out"),
    ([*SOLVE, "--save", "OUT"], "--save"),
    (["compare", "run", "--out", "OUT"], "--out"),
    (["demo", "--out", "OUT"], "--out"),
    (["dem", "run", "--preset", "smoke", "--out", "OUT"], "--out"),
    (["dem", "calibrate", "--preset", "smoke", "--out", "OUT"], "--out"),
]
TARGETS = {"a folder of the user's": "mine", "the working folder": ".", "an input's own folder": "run",
           "an input's parent": "."}


@pytest.mark.parametrize("target", TARGETS)
@pytest.mark.parametrize("argv, option", WRITERS, ids=[a[0] if a[0] != "dem" else " ".join(a[:2]) for a, _ in WRITERS])
def test_a_folder_the_command_did_not_write_is_refused_untouched(argv, option, target, user_folder, capsys):
    before = _snapshot(user_folder)
    code, err = _run([TARGETS[target] if a == "OUT" else a for a in argv], capsys)
    assert code == 2
    assert len(err.splitlines()) == 1 and "Traceback" not in err and option in err, err
    assert _snapshot(user_folder) == before


def test_an_output_inside_or_holding_an_input_is_refused(user_folder, capsys):
    code, err = _run(["compare", "run", "--out", "run/report"], capsys)
    assert code == 2 and "--out" in err and "apart from the inputs" in err
    assert not (user_folder / "run" / "report").exists()


def test_a_second_save_keeps_the_first_and_a_repeat_replaces_only_its_own_files(user_folder, capsys):
    out = user_folder / "saved"
    assert _run([*SOLVE, "--save", "saved"], capsys)[0] == 0
    first = _snapshot(out)
    assert _run(["continuum", *BEADS, "--mu-w-tilde", "0.3", "--times", "1", "--save", "saved"], capsys)[0] == 0
    both = _snapshot(out)
    assert {k: v for k, v in both.items() if k in first and k != staging.MANIFEST} == \
        {k: v for k, v in first.items() if k != staging.MANIFEST}
    assert len(both) == 2 * (len(first) - 1) + 1  # each solve's three files, one manifest
    manifest = json.loads((out / staging.MANIFEST).read_text())
    assert (manifest["command"] == "continuum"
            and sorted(manifest["files"]) == sorted(k for k in both if k != staging.MANIFEST))
    (out / "my_plot.png").write_bytes(b"user")
    assert _run([*SOLVE, "--save", "saved"], capsys)[0] == 0  # the same case again: its own files replaced
    assert (out / "my_plot.png").read_bytes() == b"user"
    assert set(_snapshot(out)) == set(both) | {"my_plot.png"}


# --- the mechanism itself ------------------------------------------------------------------------------

def test_staged_replaces_listed_files_removes_stale_ones_and_keeps_the_users(tmp_path):
    out = tmp_path / "report"
    with staging.staged(staging.claim(out, "--out", "cmd"), "cmd") as work:
        (work / "a.csv").write_text("1")
        (work / "figs").mkdir()
        (work / "figs" / "b.png").write_text("2")
    (out / "user.txt").write_text("mine")
    with staging.staged(staging.claim(out, "--out", "cmd"), "cmd") as work:
        (work / "a.csv").write_text("3")
    assert (out / "a.csv").read_text() == "3"
    assert not (out / "figs").exists()  # the earlier output's file the new one lacks, and its emptied folder
    assert (out / "user.txt").read_text() == "mine"
    assert staging.read_manifest(out)["files"] == ["a.csv"]


def test_a_failed_write_leaves_the_earlier_output_as_it_was(tmp_path):
    out = tmp_path / "report"
    with staging.staged(out, "cmd") as work:
        (work / "a.csv").write_text("1")
    before = _snapshot(out)
    with pytest.raises(RuntimeError), staging.staged(out, "cmd") as work:
        (work / "a.csv").write_text("half")
        raise RuntimeError("the solve failed")
    assert _snapshot(out) == before
    with pytest.raises(RuntimeError), staging.staged(tmp_path / "new", "cmd") as work:
        raise RuntimeError("failed at once")
    assert not (tmp_path / "new").exists()


def test_a_new_output_never_overwrites_a_file_it_did_not_list(tmp_path):
    out = tmp_path / "report"
    with staging.staged(out, "cmd") as work:
        (work / "a.csv").write_text("1")
    (out / "b.csv").write_text("the user's")
    with pytest.raises(ValueError, match="b.csv"), staging.staged(out, "cmd") as work:
        (work / "a.csv").write_text("2")
        (work / "b.csv").write_text("would replace the user's")
    assert (out / "b.csv").read_text() == "the user's" and (out / "a.csv").read_text() == "1"


def test_another_commands_output_is_refused(tmp_path):
    out = tmp_path / "figs"
    with staging.staged(out, "paper-figures") as work:
        (work / "f.png").write_text("1")
    with pytest.raises(ValueError, match="did not write"):
        staging.claim(out, "--out", "stability")
    assert staging.claim(out, "--out", "paper-figures") == out
