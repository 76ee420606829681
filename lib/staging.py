"""Output folders that never lose a user's file.

Every command that writes a folder claims it first (``claim``, before any work):

* a new or empty folder is taken;
* a folder holding a manifest of the same command (``MANIFEST``, written with every output) is taken,
  and only the files that manifest lists may be replaced or removed, each only while unchanged since the
  command wrote it;
* anything else is refused with one line naming the option: a file, a folder holding files granstokes
  did not write there, a listed file that was changed since it was written, or a folder equal to, inside
  or containing one of the command's inputs.

The manifest lists the files a command owns (``files``) and records each one's ``checksum`` (sha256 and size,
under ``checksums``) as written.  A listed file whose content no longer matches its record was changed by
someone else, and no command replaces or removes it (``require_unchanged``: one line naming the file); a
listed file that is gone is not there to replace.  A listed file without a record is owned as listed:
manifests written by earlier versions have no records, and a progressive output's files have none while its
command writes them.

An all-at-once output (a report, figures, a saved solve) is then written through ``staged``: the work
goes into a hidden folder inside the target; on success each file moves into place with ``os.replace``
(atomic per file), files the previous manifest listed and the new output lacks are removed, and the new
manifest, with the new files' records, is written last.  Just before the moves, under the folder's lock, the
files to be replaced or removed are checked again (one changed while the command ran is refused, nothing
moved).  On failure only the hidden folder goes.  A file no manifest lists is never touched, and a new
output that would overwrite one (or need one out of the way to make a folder) is refused.
A manifest names only paths inside its folder: an entry that is absolute, climbs with ``..`` or resolves
outside the folder through a link is ignored.  Concurrent commits into one folder take turns (a lock on
the folder), so neither loses the other's entries.

A progressive output (a DEM run, a calibration, a study, the demo: written as it goes, resumed with
``--resume``) writes its manifest when it starts (``start``), so that a resumed or repeated command
recognises the folder as its own.  A resume checks the recorded files before any work
(``require_unchanged``), then drops the records (``resume``): it rewrites its own partial files, and a run
killed before its end leaves files changed since their records.  Each invocation ends with ``seal``: the
manifest lists every file of the folder (files added while it ran included; a nested output, a subfolder
with its own manifest, excepted) and records the checksums of the finished ones: all of them once the
command completed, those of its finished stages when it stopped (a stopped run's tasks may still be ending
elsewhere).

Files are created with the mode the user's umask gives (``_create``; ``tempfile``'s are private, 0600, and
a rename keeps the mode).
"""
from __future__ import annotations

import datetime as _dt
import fcntl
import hashlib
import json
import os
import secrets
import shutil
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path

from .validate import output_dir, require

#: the manifest each output folder carries: the command that wrote it, the files it owns there and their checksums
MANIFEST = "granstokes-manifest.json"
#: prefix of the hidden folders and files an output is written through (only granstokes names them so)
STAGE_PREFIX = ".granstokes-stage-"
#: bytes read at a time when a file is hashed
CHUNK = 1 << 20


def read_manifest(folder) -> dict | None:
    """The manifest of ``folder`` as a dict, or None if there is none (or it is unreadable)."""
    path = Path(folder) / MANIFEST
    try:
        doc = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return doc if isinstance(doc, dict) and isinstance(doc.get("command"), str) else None


def checksum(path) -> dict:
    """The record of the file ``path``: ``{"sha256": hex digest of its content, "size": bytes}``."""
    digest, size = hashlib.sha256(), 0
    with open(path, "rb") as f:
        while chunk := f.read(CHUNK):
            digest.update(chunk)
            size += len(chunk)
    return {"sha256": digest.hexdigest(), "size": size}


def _inside(folder: Path, rel: str) -> bool:
    """Whether the manifest entry ``rel`` names a path inside ``folder`` (links followed)."""
    parts = Path(rel).parts
    if not parts or Path(rel).is_absolute() or ".." in parts:
        return False
    top = folder.resolve()
    return top in (folder / rel).resolve().parents


def _listed(folder: Path, doc: dict | None) -> set[str]:
    """The files the manifest ``doc`` of ``folder`` lists, those that are safely inside it."""
    if doc is None or not isinstance(doc.get("files"), list):
        return set()
    return {rel for rel in doc["files"] if isinstance(rel, str) and _inside(folder, rel)}


def _owned(folder: Path, command: str) -> set[str]:
    """The files of ``folder``'s manifest when ``command`` wrote it, those that are safely inside it."""
    doc = read_manifest(folder)
    return _listed(folder, doc) if doc is not None and doc.get("command") == command else set()


def _records(folder: Path, doc: dict | None) -> dict[str, dict]:
    """The well-formed checksum records of the files the manifest ``doc`` of ``folder`` lists."""
    raw = doc.get("checksums") if doc is not None else None
    if not isinstance(raw, dict):
        return {}
    listed = _listed(folder, doc)
    return {rel: {"sha256": r["sha256"], "size": r["size"]} for rel, r in raw.items()
            if rel in listed and isinstance(r, dict) and isinstance(r.get("sha256"), str)
            and isinstance(r.get("size"), int) and not isinstance(r.get("size"), bool)}


def _changed(path: Path, record: dict) -> bool:
    """Whether the file ``path`` no longer is what ``record`` says (gone: not changed, nothing to replace)."""
    try:
        st = path.lstat()
    except FileNotFoundError:
        return False
    if not stat.S_ISREG(st.st_mode) or st.st_size != record["size"]:
        return True
    try:
        return checksum(path)["sha256"] != record["sha256"]
    except FileNotFoundError:
        return False


def _changed_error(option: str, path: Path, command: str) -> ValueError:
    return ValueError(f"{option}: {path} was changed since granstokes {command} wrote it; move it away or choose "
                      "another folder")


def require_unchanged(folder, option: str, nested: bool = False) -> None:
    """``ValueError`` naming ``option`` and the first file of ``folder``'s manifest (``nested``: of every manifest
    below it too) that was changed since its command wrote it (its checksum record differs)."""
    folder = Path(folder)
    found = [folder]
    if nested:
        found += sorted(Path(root) for root, _, files in os.walk(folder) if MANIFEST in files and Path(root) != folder)
    for place in found:
        doc = read_manifest(place)
        for rel, record in sorted(_records(place, doc).items()):
            if _changed(place / rel, record):
                raise _changed_error(option, place / rel, doc["command"])


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
        require_unchanged(path, option)
    return path


def _manifest(command: str, files, inputs, progressive: bool, records: dict) -> dict:
    files = sorted(files)
    return {"command": command, "progressive": progressive,
            "written": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
            "inputs": [str(p) for p in inputs], "files": files,
            "checksums": {rel: records[rel] for rel in files if rel in records},
            "note": f"written by granstokes {command}; a later run of it may replace the files listed here while each "
                    "is as written (its sha256 and size under checksums), and nothing else in this folder"}


def _create(folder: Path, prefix: str = STAGE_PREFIX, suffix: str = "") -> tuple[int, Path]:
    """A new file in ``folder`` named ``prefix``, a random part and ``suffix``, open for writing, with the mode the
    umask gives (``tempfile.mkstemp``'s is 0600, which a rename into place would keep)."""
    for _ in range(100):
        path = folder / f"{prefix}{secrets.token_hex(6)}{suffix}"
        try:
            return os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666), path
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary file name {prefix}*{suffix} in {folder}")


def _write_manifest(folder: Path, doc: dict) -> None:
    fd, tmp = _create(folder)
    with os.fdopen(fd, "w") as f:
        f.write(json.dumps(doc, indent=2))
    os.replace(tmp, folder / MANIFEST)


def start(path, command: str, inputs=()) -> Path:
    """Create ``path`` (already claimed) as a progressive output of ``command`` and write its manifest."""
    path = Path(path)
    path.mkdir(parents=True, exist_ok=True)
    old = read_manifest(path)
    if old is None:
        _write_manifest(path, _manifest(command, [], inputs, progressive=True, records={}))
    return path


def resume(path, command: str) -> Path:
    """Reopen ``path``, a progressive output of ``command`` checked by ``require_unchanged``, to write in it: its
    manifest keeps listing its files, without checksum records until ``seal``.  ``ValueError`` naming --out if
    another command wrote it."""
    path = Path(path)
    with locked(path):
        old = read_manifest(path)
        require(old is None or old.get("command") == command, "--out", f"a folder of granstokes {command} to resume",
                f"{path} (written by granstokes {(old or {}).get('command')})")
        inputs = (old or {}).get("inputs", [])
        _write_manifest(path, _manifest(command, _listed(path, old), inputs if isinstance(inputs, list) else [],
                                        progressive=True, records={}))
    return path


def _tree(folder: Path) -> list[str]:
    """The files below ``folder`` (links not followed) except its manifest, hidden stage entries and nested outputs
    (subfolders holding their own manifest)."""
    found = []
    for root, dirs, files in os.walk(folder):
        here = Path(root)
        dirs[:] = [d for d in dirs if not d.startswith(STAGE_PREFIX) and not (here / d / MANIFEST).exists()]
        found += [str((here / name).relative_to(folder)) for name in files
                  if not name.startswith(STAGE_PREFIX) and not (here == folder and name == MANIFEST)]
    return sorted(found)


def _within(rel: str, places) -> bool:
    """Whether ``rel`` is one of ``places`` (relative paths of files or folders) or inside one."""
    return any(rel == p or rel.startswith(p.rstrip("/") + "/") for p in places)


def seal(path, command: str, finished=None) -> None:
    """End an invocation of the progressive output ``path`` of ``command``: its manifest lists every file in it
    (``_tree``) and records the checksums of the ``finished`` ones (relative paths of files or folders; None: all),
    keeping the records written meanwhile (``staged``) for the others."""
    path = Path(path)
    with locked(path):
        old = read_manifest(path)
        files = _tree(path)
        records = _records(path, old) if old is not None and old.get("command") == command else {}
        for rel in files:
            if finished is None or _within(rel, finished):
                try:
                    if stat.S_ISREG((path / rel).lstat().st_mode):
                        records[rel] = checksum(path / rel)
                except FileNotFoundError:  # removed meanwhile (a finished drive's clean-up)
                    records.pop(rel, None)
        inputs = (old or {}).get("inputs", [])
        _write_manifest(path, _manifest(command, files, inputs if isinstance(inputs, list) else [], progressive=True,
                                        records=records))


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
    fd, tmp = _create(path.parent, f"{STAGE_PREFIX}{path.name}-")
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
        old = read_manifest(target)
        mine = old is not None and old.get("command") == command
        owned = _owned(target, command)
        records = _records(target, old) if mine else {}
        progressive = bool(mine and old.get("progressive"))
        new = _files(work)
        foreign = [rel for rel in new if _blocked(target, rel, owned)]
        require(not foreign, "output", f"free of files granstokes {command} did not write (it would replace "
                "them)", f"{target}: {', '.join(foreign[:3])}")
        kept = {rel for rel in owned - set(new) if os.path.lexists(target / rel)} if keep else set()
        stale = owned - set(new) - kept
        for rel in sorted((owned & set(new)) | stale):
            if rel in records and _changed(target / rel, records[rel]):
                raise _changed_error("output", target / rel, command)
        fresh = {rel: checksum(work / rel) for rel in new if stat.S_ISREG((work / rel).lstat().st_mode)}
        # listed before they move, the moving ones without records: an interruption between the moves leaves
        # every file owned, none foreign
        _write_manifest(target, _manifest(command, owned | set(new), inputs, progressive,
                                          {rel: r for rel, r in records.items() if rel not in fresh}))
        for rel in new:
            dest = target / rel
            dest.parent.mkdir(parents=True, exist_ok=True)
            os.replace(work / rel, dest)
        for rel in sorted(stale):
            gone = target / rel
            if gone.is_file() or gone.is_symlink():
                gone.unlink()
            _prune(gone.parent, target)
        _write_manifest(target, _manifest(command, set(new) | kept, inputs, progressive, records | fresh))


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
    fd, tmp = _create(path.parent, suffix=path.suffix)
    os.close(fd)
    try:
        yield tmp
        try:
            os.link(tmp, path)
        except FileExistsError:
            raise ValueError(f"output must be a file that does not exist yet, got {str(path)!r}") from None
    finally:
        os.unlink(tmp)
