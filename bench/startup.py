"""Start-up time of the ``granstokes`` command: wall time of ``--version`` and of a one-time
``continuum ... --json`` solve, against ``python -c pass`` (the interpreter alone), best of REPEATS
fresh processes each, run in this checkout or in each CHECKOUT given (before/after in one run; the
working directory, which python puts first on sys.path, is the checkout).

    .venv/bin/python bench/startup.py [CHECKOUT ...]
"""
from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REPEATS = 7
COMMANDS = {
    "python -c pass": ["-c", "pass"],
    "granstokes --version": ["-m", "granstokes.cli", "--version"],
    # the parser's other subcommands, without continuum.cli (whose module imports its solver)
    "register compare, dem, paper, predict": ["-c", "import argparse, granstokes.cli, compare.cli, dem.cli, "
                                              "continuum.paper.cli, continuum.predict_cli as p; "
                                              "s = argparse.ArgumentParser().add_subparsers(); "
                                              "[m.register(s) for m in (compare.cli, dem.cli, continuum.paper.cli, p)]"],
    "granstokes continuum ... --json": ["-m", "granstokes.cli", "continuum", "--mu-s", "0.38", "--mu-d", "0.64",
                                        "--mu-w-tilde", "0.5", "--times", "1", "--json"],
}


def wall(args, root: Path) -> float:
    env = {**os.environ, "PYTHONPATH": str(root)}
    best = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        subprocess.run([sys.executable, *args], cwd=root, env=env, check=True, capture_output=True)
        best = min(best, time.perf_counter() - start)
    return best


def main(roots) -> None:
    print("| checkout | command | wall [s] | / python -c pass |\n|---|---|---|---|")
    for root in roots:
        times = {name: wall(args, root) for name, args in COMMANDS.items()}
        for name, t in times.items():
            print(f"| {root} | `{name}` | {t:.3f} | {t / times['python -c pass']:.1f} |")


if __name__ == "__main__":
    main([Path(a).resolve() for a in sys.argv[1:]] or [ROOT])
