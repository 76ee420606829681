"""Output folders that never lose a user's file.

Every command that writes a folder claims it first (``claim``, before any work):

* a new or empty folder is taken;
* a folder holding a manifest of the same command (``MANIFEST``, written with every output) is taken,
  and only the files that manifest lists may be replaced;
* anything else is refused with one line naming the option: a file, a folder holding files granstokes
  did not write there, or a folder equal to, inside or containing one of the command's inputs.

An all-at-once output (a report, figures, a saved solve) is then written through ``staged``: the work
goes into a hidden folder inside the target; on success each file moves into place with ``os.replace``
(atomic per file), files the previous manifest listed and the new output lacks are removed, and the new
manifest is written last.  On failure only the hidden folder goes.  A file no manifest lists is never
touched, and a new output that would overwrite one (or need one out of the way to make a folder) is refused.
A manifest names only paths inside its folder: an entry that is absolute, climbs with ``..`` or resolves
outside the folder through a link is ignored.  Concurrent commits into one folder take turns (a lock on
the folder), so neither loses the other's entries.

A progressive output (a DEM run, a calibration, the demo: written as it goes, resumed with
``--resume``) writes its manifest when it starts (``start``), so that a resumed or repeated command
recognises the folder as its own.
"""
from __future__ import annotations

import datetime as _dt
import fcntl
import json
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

from .validate import output_dir, require

#: the manifest each output folder carries: the command that wrote it and the files it owns there
MANIFEST = "granstokes-manifest.json"
#: prefix of the hidden folders a staged output is written into (only granstokes names folders so)
STAGE_PREFIX = ".granstokes-stage-"


def read_manifest(folder) -> dict | None:
    """The manifest of ``folder`` as a dict, or None if there is none (or it is unreadable)."""
    path = Path(folder) / MANIFEST
    try:
        doc = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return doc if isinstance(doc, dict) and isinstance(doc.get("command"), str) else None


def _inside(folder: Path, rel: str) -> bool:
    """Whether the manifest entry ``rel`` names a path inside ``folder`` (links followed)."""
    parts = Path(rel).parts
    if not parts or Path(rel).is_absolute() or ".." in parts:
        return False
    top = folder.resolve()
    return top in (folder / rel).resolve().parents


def _owned(folder: Path, command: str) -> set[str]:
    """The files of ``folder``'s manifest when ``command`` wrote it, those that are safely inside it."""
    doc = read_manifest(folder)
    if doc is None or doc.get("command") != command or not isinstance(doc.get("files"), list):
        return set()
    return {rel for rel in doc["files"] if isinstance(rel, str) and _inside(folder, rel)}


def _content(folder: Path) -> list[Path]:
    return [p for p in folder.iterdir() if not p.name.startswith(STAGE_PREFIX)]


def _related(a: Path, b: Path) -> bool:
    """Whether ``a`` and ``b`` are the same path or one contains the other."""
    return a == b or a in b.parents or b in a.parents


def claim(path, option: str, command: str, inputs=()) -> Path:
    """``path`` as the output folder of ``granstokes COMMAND`` (see the module's rules); ``ValueError``
    naming ``option`` otherwise.  Nothing is created here."""
    path = output_dir(path, option)
    resolved = path.resolve()
    for given in inputs:
        require(not _related(resolved, Path(given).resolve()), option,
                "a folder apart from the inputs (not one of them, inside one, or holding one)",
                f"{path} and input {given}")
    if path.is_dir() and _content(path):
        manifest = read_manifest(path)
        require(manifest is not None and manifest.get("command") == command, option,
                f"a new or empty folder, or an earlier output of 'granstokes {command}' "
                f"(this one holds files that granstokes {command} did not write)", str(path))
    return path


def _manifest(command: str, files, inputs, progressive: bool) -> dict:
    return {"command": command, "progressive": progressive,
            "written": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
            "inputs": [str(p) for p in inputs], "files": sorted(files),
            "note": f"written by granstokes {command}; a later run of it may replace the files listed here, "
                    "and nothing else in this folder"}


def _write_manifest(folder: Path, doc: dict) -> None:
    fd, tmp = tempfile.mkstemp(prefix=STAGE_PREFIX, dir=folder)
    with os.fdopen(fd, "w") as f:
        f.write(json.dumps(doc, indent=2))
    os.replace(tmp, folder / MANIFEST)


def start(path, command: str, inputs=()) -> Path:
    """Create ``path`` (already claimed) as a progressive output of ``command`` and write its manifest."""
    path = Path(path)
    path.mkdir(parents=True, exist_ok=True)
    old = read_manifest(path)
    if old is None:
        _write_manifest(path, _manifest(command, [], inputs, progressive=True))
    return path


def _files(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file() or p.is_symlink())


@contextmanager
def staged(target, command: str, inputs=(), keep: bool = False):
    """Yield a hidden folder inside ``target`` (claimed for ``command``); on success its files replace
    the previous output's (``keep``: the previous output's files stay unless replaced by name)."""
    target = Path(target)
    created = not target.exists()
    target.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=STAGE_PREFIX, dir=target))
    try:
        yield work
        _commit(work, target, command, inputs, keep)
    finally:
        shutil.rmtree(work, ignore_errors=True)
        if created and not any(target.iterdir()):
            target.rmdir()


@contextmanager
def locked(folder: Path):
    """Hold an exclusive lock on ``folder`` (the directory itself: no file is added) while in the block; threads
    and processes (on one machine, or a shared file system with flock) take turns."""
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def write_json(path, doc: dict) -> None:
    """Write ``doc`` to ``path`` atomically (a hidden temporary file beside it, then a rename)."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    with os.fdopen(fd, "w") as f:
        json.dump(doc, f, indent=2, default=str)
    os.replace(tmp, path)


def update_json(path, change) -> dict:
    """Read the JSON record ``path`` (``{}`` if absent), apply ``change(doc)`` in place and write it back atomically,
    under the lock of its folder: concurrent writers of different entries lose none.  Returns the new record."""
    path = Path(path)
    with locked(path.parent):
        doc = json.loads(path.read_text()) if path.exists() else {}
        change(doc)
        write_json(path, doc)
    return doc


def _blocked(target: Path, rel: str, owned: set[str]) -> bool:
    """Whether writing ``rel`` would replace or move aside something ``owned`` does not list: the path
    itself (a file, a link, even a dangling one, or a folder) or a non-folder where a parent must be."""
    dest = target / rel
    if os.path.lexists(dest) and (rel not in owned or dest.is_dir()):
        return True
    parent = dest.parent
    while parent != target:
        if os.path.lexists(parent) and not (parent.is_dir() and not parent.is_symlink()):
            return True
        parent = parent.parent
    return not _inside(target, rel)


def _commit(work: Path, target: Path, command: str, inputs, keep: bool) -> None:
    with locked(target):
        owned = _owned(target, command)
        new = _files(work)
        foreign = [rel for rel in new if _blocked(target, rel, owned)]
        require(not foreign, "output", f"free of files granstokes {command} did not write (it would replace "
                "them)", f"{target}: {', '.join(foreign[:3])}")
        # listed before they move: an interruption between the moves leaves every file owned, none foreign
        _write_manifest(target, _manifest(command, owned | set(new), inputs, progressive=False))
        for rel in new:
            dest = target / rel
            dest.parent.mkdir(parents=True, exist_ok=True)
            os.replace(work / rel, dest)
        kept = owned - set(new) if keep else set()
        for rel in sorted(owned - set(new) - kept):
            stale = target / rel
            if stale.is_file() or stale.is_symlink():
                stale.unlink()
            _prune(stale.parent, target)
        _write_manifest(target, _manifest(command, set(new) | kept, inputs, progressive=False))


def _prune(folder: Path, top: Path) -> None:
    """Remove ``folder`` and its parents below ``top`` while they are empty."""
    while folder != top and top in folder.parents and not any(folder.iterdir()):
        folder.rmdir()
        folder = folder.parent


@contextmanager
def new_file(path):
    """Yield a hidden path beside ``path`` to write into; on success it becomes ``path`` by a hard link, which
    fails rather than replace a file that appeared meanwhile (``ValueError``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=STAGE_PREFIX, suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        try:
            os.link(tmp, path)
        except FileExistsError:
            raise ValueError(f"output must be a file that does not exist yet, got {str(path)!r}") from None
    finally:
        os.unlink(tmp)
