"""The set-up's warm-up (continuum.warmup) fills numba's disk cache with every kernel that ``granstokes continuum``
calls, and a kernel that must compile at run time says so in one stderr line (continuum.compiled.DRIVES), only then."""
import os
import subprocess
import sys

import pytest
from granstokes.continuum.compiled import DRIVES

NOTICES = [f"granstokes: compiling the {drive} solver's kernels once" for drive, _ in DRIVES.values()]
BEADS = ["--mu-s", "0.3839", "--mu-d", "0.6494", "--times", "1"]


def run(cache, *args):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    return subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True, check=True)


@pytest.mark.slow
def test_a_cold_cache_says_it_compiles_once_and_the_warm_up_leaves_nothing_to_compile(tmp_path):
    # numba's cache in an empty folder: both drives compile
    warm_up = run(tmp_path, "-m", "granstokes.continuum.warmup")
    # the drives compile side by side: their notices in either order
    assert sorted(line.split(" (")[0] for line in warm_up.stderr.splitlines()) == sorted(NOTICES)
    assert "solver kernels ready" in warm_up.stdout
    for case in (["--mu-w-tilde", "0.5"], ["--u-w", "1.334"]):  # the command's defaults: nothing left to compile
        solve = run(tmp_path, "-m", "granstokes.cli", "continuum", *BEADS, *case)
        assert solve.stderr == "" and "steady" in solve.stdout
