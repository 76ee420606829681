"""The first ``granstokes continuum`` solve on a fresh clone: clone this repository's HEAD into a temporary folder (or,
with --source DIR, copy that working tree's files as git sees them: tracked and untracked, not ignored, so no .venv,
.git or numba cache), run README's set-up there (``make .venv/.installed-stamp``: its .venv, the install, the
kernels' warm-up), then time (wall) each drive's first solve in a fresh process, and again with numba's cache pointed
at an empty folder (the first solve without the warm-up).  Exits 1 if a first solve after set-up takes over LIMIT s.

    .venv/bin/python bench/first_run.py [--source DIR]
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LIMIT = 5.0
STAMP = ".venv/.installed-stamp"
BEADS = ["--mu-s", "0.3839", "--mu-d", "0.6494", "--times", "1"]
DRIVES = {"stress": ["--mu-w-tilde", "0.5"], "speed": ["--u-w", "1.334"]}
#: the caller's settings that would point the clone's commands elsewhere
ENV = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "NUMBA_CACHE_DIR")}


def copy_tree(source: Path, dest: Path) -> None:
    """The files of ``source`` that git sees (tracked and untracked, not ignored), as they are on disk."""
    names = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=source,
                           check=True, capture_output=True, text=True).stdout.split("\0")
    for name in filter(None, names):
        if (source / name).is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source / name, dest / name)


def first_solve(clone: Path, args, env) -> tuple[float, bool]:
    """(wall seconds, whether it said it compiles) of one ``granstokes continuum`` in a fresh process."""
    start = time.perf_counter()
    proc = subprocess.run([str(clone / ".venv/bin/granstokes"), "continuum", *BEADS, *args], cwd=clone, env=env,
                          check=True, capture_output=True, text=True)
    return time.perf_counter() - start, "compiling" in proc.stderr


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", type=Path, help="copy this working tree instead of cloning HEAD")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="granstokes-first-run-") as tmp:
        clone = Path(tmp) / "granstokes"
        if args.source is not None:
            clone.mkdir()
            copy_tree(args.source.resolve(), clone)
        else:
            subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
        start = time.perf_counter()
        setup = subprocess.run(["make", STAMP], check=False, cwd=clone, env=ENV, capture_output=True, text=True)
        setup_wall = time.perf_counter() - start
        if setup.returncode:
            sys.exit(f"set-up failed:\n{setup.stdout}{setup.stderr}")
        ready = [line for line in setup.stdout.splitlines() if "kernels ready" in line]
        print(f"set-up (`make {STAMP}`): {setup_wall:.0f} s wall; warm-up: {ready[0] if ready else 'not run'}\n")
        print("| drive | first solve after set-up [s] | said it compiles | first solve, empty numba cache [s] "
              "| said it compiles |\n|---|---|---|---|---|")
        worst = 0.0
        for drive, case in DRIVES.items():
            wall, told = first_solve(clone, case, ENV)
            cold_wall, cold_told = first_solve(clone, case, {**ENV, "NUMBA_CACHE_DIR": str(Path(tmp) / drive)})
            worst = max(worst, wall)
            said, cold_said = ("yes" if t else "no" for t in (told, cold_told))
            print(f"| {drive} | {wall:.2f} | {said} | {cold_wall:.1f} | {cold_said} |")
    if worst > LIMIT:
        print(f"a first solve after set-up took {worst:.1f} s > {LIMIT:g} s")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
