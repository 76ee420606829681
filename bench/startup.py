"""Start-up time of the ``granstokes`` command: wall and CPU time (user + system of the child) of
``--version``, of the ``continuum ... --json`` command up to its solve (the parser, the arguments and the
solver's imports: what runs before ``solve_stress``) and of the whole command, against ``python -c pass``
(the interpreter alone), best of REPEATS fresh processes each, run in this checkout or in each CHECKOUT
given (before/after in one run; the working directory, which python puts first on sys.path, is the checkout).

    .venv/bin/python bench/startup.py [CHECKOUT ...]
"""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REPEATS = 7
CONTINUUM = ["continuum", "--mu-s", "0.38", "--mu-d", "0.64", "--mu-w-tilde", "0.5", "--times", "1", "--json"]
COMMANDS = {
    "python -c pass": ["-c", "pass"],
    "granstokes --version": ["-m", "granstokes.cli", "--version"],
    # the parser's other subcommands, without continuum.cli (whose module imports its solver)
    "register compare, dem, paper, predict": ["-c", "import argparse, granstokes.cli, granstokes.compare.cli, "
                                              "granstokes.dem.cli, granstokes.continuum.paper.cli, "
                                              "granstokes.continuum.predict_cli as p; "
                                              "s = argparse.ArgumentParser().add_subparsers(); "
                                              "[m.register(s) for m in (granstokes.compare.cli, granstokes.dem.cli, "
                                              "granstokes.continuum.paper.cli, p)]"],
    "granstokes continuum ... --json, up to the solve": ["-c", "import granstokes.cli as c; "
                                                         "c.build_parser().parse_args("
                                                         f"{CONTINUUM!r}); import granstokes.continuum.solver"],
    "granstokes continuum ... --json": ["-m", "granstokes.cli", *CONTINUUM],
}


def timed(args, root: Path) -> tuple[float, float]:
    """(wall, CPU) seconds of a fresh process, each the best of REPEATS."""
    env = {**os.environ, "PYTHONPATH": str(root)}
    wall = cpu = float("inf")
    for _ in range(REPEATS):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        subprocess.run([sys.executable, *args], cwd=root, env=env, check=True, capture_output=True)
        wall = min(wall, time.perf_counter() - start)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = min(cpu, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    return wall, cpu


def main(roots) -> None:
    print("| checkout | command | wall [s] | / python -c pass | CPU [s] | / python -c pass |\n"
          "|---|---|---|---|---|---|")
    for root in roots:
        times = {name: timed(args, root) for name, args in COMMANDS.items()}
        base = times["python -c pass"]
        for name, (wall, cpu) in times.items():
            print(f"| {root} | `{name}` | {wall:.3f} | {wall / base[0]:.1f} | {cpu:.3f} | {cpu / base[1]:.1f} |")


if __name__ == "__main__":
    main([Path(a).resolve() for a in sys.argv[1:]] or [ROOT])
