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


def _write(out, files, command="cmd"):
    with staging.staged(out, command) as work:
        for rel, text in files.items():
            (work / rel).parent.mkdir(parents=True, exist_ok=True)
            (work / rel).write_text(text)


def test_a_plot_file_that_exists_is_refused_and_a_new_one_is_written(user_folder, capsys):
    before = _snapshot(user_folder)
    code, err = _run([*SOLVE, "--plot", "notes.png"], capsys)
    assert code == 0 and (user_folder / "notes.png").read_bytes()[:4] == b"\x89PNG"
    (user_folder / "mine.png").write_text("the user's figure")
    code, err = _run([*SOLVE, "--plot", "mine.png"], capsys)
    assert code == 2 and "--plot" in err and "does not exist yet" in err
    assert (user_folder / "mine.png").read_text() == "the user's figure"
    after = {k: v for k, v in _snapshot(user_folder).items() if k != "notes.png"}
    assert after == {**before, "mine.png": b"the user's figure"}


def test_a_rerun_never_deletes_through_a_link_an_owned_folder_became(tmp_path):
    out, elsewhere = tmp_path / "report", tmp_path / "elsewhere"
    _write(out, {"figs/a.png": "1"})
    elsewhere.mkdir()
    (elsewhere / "a.png").write_text("the user's, outside the output")
    (out / "figs" / "a.png").unlink()
    (out / "figs").rmdir()
    (out / "figs").symlink_to(elsewhere)
    _write(out, {"b.csv": "2"})
    assert (elsewhere / "a.png").read_text() == "the user's, outside the output"
    with pytest.raises(ValueError, match="figs/a.png"):
        _write(out, {"figs/a.png": "would write through the link"})
    assert (elsewhere / "a.png").read_text() == "the user's, outside the output"


@pytest.mark.parametrize("entry", ["../victim.txt", "/ABS/victim.txt"])
def test_a_manifest_entry_outside_its_folder_is_ignored(tmp_path, entry):
    out, victim = tmp_path / "report", tmp_path / "victim.txt"
    victim.write_text("the user's")
    _write(out, {"a.csv": "1"})
    doc = staging.read_manifest(out)
    doc["files"].append(entry.replace("/ABS", str(tmp_path)))
    (out / staging.MANIFEST).write_text(json.dumps(doc))
    _write(out, {"a.csv": "2"})
    assert victim.read_text() == "the user's" and staging.read_manifest(out)["files"] == ["a.csv"]


def test_the_manifest_is_written_beside_a_user_file_of_its_temporary_name(tmp_path):
    out = tmp_path / "report"
    out.mkdir()
    (out / f"{staging.MANIFEST}.tmp").write_text("the user's")
    _write(out, {"a.csv": "1"})
    assert (out / f"{staging.MANIFEST}.tmp").read_text() == "the user's"
    assert [p.name for p in out.iterdir() if p.name.startswith(staging.STAGE_PREFIX)] == []


def test_a_user_file_where_an_output_folder_must_go_is_refused_before_any_move(tmp_path):
    out = tmp_path / "report"
    _write(out, {"a.csv": "1"})
    (out / "figs").write_text("the user's file named figs")
    before = _snapshot(out)
    with pytest.raises(ValueError, match="figs/b.png"):
        _write(out, {"a.csv": "2", "figs/b.png": "2"})
    assert _snapshot(out) == before


def test_a_dangling_user_link_is_not_replaced(tmp_path):
    out = tmp_path / "report"
    _write(out, {"a.csv": "1"})
    (out / "b.csv").symlink_to(tmp_path / "nowhere")
    with pytest.raises(ValueError, match="b.csv"):
        _write(out, {"b.csv": "2"})
    assert (out / "b.csv").is_symlink() and not (tmp_path / "nowhere").exists()


def test_an_interrupted_commit_leaves_every_moved_file_owned(tmp_path, monkeypatch):
    out = tmp_path / "report"
    _write(out, {"a.csv": "1"})
    moves = []

    def replace_then_fail(src, dst):
        if len(moves) == 1 and staging.MANIFEST not in str(dst):
            raise KeyboardInterrupt
        moves.append(dst) if staging.MANIFEST not in str(dst) else None
        return real(src, dst)

    real = staging.os.replace
    monkeypatch.setattr(staging.os, "replace", replace_then_fail)
    with pytest.raises(KeyboardInterrupt):
        _write(out, {"a.csv": "2", "b.csv": "2"})
    monkeypatch.undo()
    assert set(staging.read_manifest(out)["files"]) == {"a.csv", "b.csv"}
    _write(out, {"a.csv": "3", "b.csv": "3"})  # the rerun recognises both as its own
    assert (out / "b.csv").read_text() == "3"


def test_concurrent_commits_into_one_folder_keep_each_others_entries(tmp_path):
    import threading

    out = tmp_path / "report"
    _write(out, {"first.csv": "0"})
    errors = []

    def save(name):
        try:
            with staging.staged(out, "cmd", keep=True) as work:
                (work / name).write_text(name)
        except Exception as err:  # noqa: BLE001 - collected for the assertion
            errors.append(err)

    threads = [threading.Thread(target=save, args=(f"s{k}.csv",)) for k in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert set(staging.read_manifest(out)["files"]) == {"first.csv", *(f"s{k}.csv" for k in range(8))}
