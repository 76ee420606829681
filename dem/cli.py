"""``granstokes dem``: run a DEM scene, or calibrate its grains' mu(I), from a TOML config or a preset.

    granstokes dem run (CONFIG.toml | --preset NAME) --out DIR [--jobs 2] [--np N] [--launcher 'srun -n {np}']
    granstokes dem run --resume --out DIR                 (continues the run with the config stored in DIR;
                                                          --set seeds=[...] adds beds after its seeds)
    granstokes dem calibrate (CONFIG.toml | --preset NAME) --out DIR [--jobs 2] [--np 1]
    granstokes dem calibrate --resume --out DIR

``--dry-run`` validates, prints the plan and its cost estimate, and writes nothing.
"""
from __future__ import annotations

import os
import shlex
import signal
import sys
from pathlib import Path

from granstokes.lib.toml_text import parse_assignment, with_entries
from granstokes.lib.validate import require

from . import config as config_mod
from .estimate import STARTUP
from .lammps_env import DEFAULT_JOBS, DEFAULT_NP, PLAIN_FRACTION, PLAIN_SECONDS

QUIET_HELP = (f"no progress report (otherwise a bar per LAMMPS process on a terminal, or a line every "
              f"{PLAIN_FRACTION * 100:g} %% or {PLAIN_SECONDS:g} s when stderr is a file or a pipe)")


def _config(args, command: str):
    """The config and its text: CONFIG.toml or --preset with the --set entries (and, for a run, the material of
    --calibration), or (with --resume and neither) the one stored in --out."""
    from .layout import CONFIG_TOML  # pandas: imported when a command runs, not when the parser is built

    given = [x for x in (args.config, args.preset) if x is not None]
    require(len(given) <= 1, "CONFIG.toml / --preset", "given once (a config file or a preset, not both)", given)
    if given:
        text = (config_mod.load(args.config)[1] if args.config is not None else config_mod.preset_text(args.preset))
        text = with_entries(text, [parse_assignment(a) for a in args.set or ()],
                            header=f"{args.config or args.preset} with --set " + " ".join(args.set or ()))
        if getattr(args, "calibration", None):
            from .calibrate import calibrated_text

            text = calibrated_text(text, args.calibration)
        return config_mod.parse(text), text
    require(not getattr(args, "calibration", None), "--calibration",
            "given with CONFIG.toml or --preset (a resume continues the stored config)", "a resume without either")
    require(args.resume, "CONFIG.toml / --preset", "given (or --resume, to continue the folder in --out)", "neither")
    stored = Path(args.out) / CONFIG_TOML
    require(stored.is_file(), "--resume", f"given with a folder holding the {CONFIG_TOML} of an earlier "
            f"granstokes dem {command}", str(args.out))
    if not args.set:
        return config_mod.load(stored)
    text = with_entries(stored.read_text(), [parse_assignment(a) for a in args.set],  # a resume that adds beds
                        header=f"{stored} with --set " + " ".join(args.set))
    return config_mod.parse(text), text


def _resume_line(done: list[str], left: list[str], what: str) -> str:
    return (f"resume: {len(done)} of {len(done) + len(left)} {what} complete ({', '.join(done) or 'none'}); "
            f"left: {', '.join(left) or 'none'}")


def _interrupted_line(prefix: str, command: str, args, signum: int, defaults: dict) -> str:
    """The last line of an interrupted run or calibration: the signal and the command that continues it (with the
    options given that are not stored in the folder: --jobs, --np, --launcher)."""
    again = [x for option, default in (*defaults.items(), ("--launcher", None))
             if (value := getattr(args, option[2:])) != default for x in (option, str(value))]
    return (f"{prefix}: interrupted ({signal.Signals(signum).name}); continue with: "
            + shlex.join(["granstokes", "dem", command, "--resume", "--out", str(args.out), *again]))


def _speed():
    """This machine's LAMMPS throughput for the cost estimates: cached, or probed now (a few seconds, said)."""
    from .throughput import measured

    return measured(announce=lambda line: print(f"  {line}", file=sys.stderr))


def _cmd_probe(args) -> int:
    from .throughput import cache_path, measured

    speed = measured(renew=True)
    for dim in (2, 3):
        print(f"{dim}D: {speed.describe(dim)}")
    print(f"cached in {cache_path()}")
    return 0


def _oversubscribed(np_: int, jobs: int) -> None:
    cores = os.cpu_count() or 1
    if np_ * jobs > cores:
        print(f"dem: warning: --np {np_} x {jobs} job(s) = {np_ * jobs} ranks on {cores} cores: "
              "oversubscribed, every rank waits for the others (slower than fewer ranks)", file=sys.stderr)


def _cmd_run(args) -> int:
    from .runner import check_request, completed_stages, run
    from .sizing import plan

    cfg, text = _config(args, "run")  # bad input raises, before any work (granstokes.cli's error policy)
    sized = plan(cfg)  # a load outside mu(I)'s range raises too
    runner = check_request(sized, text, args.out, np=args.np, resume=args.resume, launcher=args.launcher,
                           jobs=args.jobs)
    print(f"dem: scene '{cfg.name}' -> {args.out}", file=sys.stderr)
    for reason in runner.plan.reasons:
        print(f"  {reason}", file=sys.stderr)
    done = []
    if args.resume:
        done, left = completed_stages(runner.out, runner.plan)
        print(f"  {_resume_line(done, left, 'stages')}", file=sys.stderr)
    _speed()
    print(f"  {runner.plan.cost_estimate(runner.jobs, runner.lmp.np, done)}", file=sys.stderr)
    print(f"  {runner.plan.estimate(runner.jobs, runner.lmp.np, done).plus('start-up', STARTUP['dem']).line()}",
          file=sys.stderr)
    _oversubscribed(runner.lmp.np, runner.jobs)
    if args.dry_run:
        return 0
    result = run(sized, text, args.out, np=args.np, resume=args.resume, launcher=args.launcher,
                 progress=not args.quiet, jobs=args.jobs)
    if result.status == "interrupted":
        signum = int(result.metadata.get("signal", signal.SIGINT))
        print(_interrupted_line("dem", "run", args, signum, {"--np": None, "--jobs": DEFAULT_JOBS}), file=sys.stderr)
        return 128 + signum  # 130 SIGINT, 143 SIGTERM
    print(f"dem: {result.status}" + (f": {result.message}" if result.message else "")
          + f" (see {result.out / 'run.json'})", file=sys.stderr)
    return 0 if result.ok else 1


def _cmd_calibrate(args) -> int:
    from .calibrate import calibrate, check_calibration, completed_points

    cfg, text = _config(args, "calibrate")
    plan = check_calibration(cfg, args.out, jobs=args.jobs, np=args.np, resume=args.resume, launcher=args.launcher)
    print(plan.summary(args.out), file=sys.stderr)
    print(f"  {cfg.describe()[1]}", file=sys.stderr)
    done = []
    if args.resume:
        done, left = completed_points(args.out, plan)
        print(f"  {_resume_line(done, left, 'points')}", file=sys.stderr)
    _speed()
    print(f"  {plan.cost_estimate(args.jobs, args.np, done)}", file=sys.stderr)
    print(f"  {plan.estimate(args.jobs, args.np, done).plus('start-up', STARTUP['dem']).line()}",
          file=sys.stderr)
    _oversubscribed(args.np, args.jobs)
    if args.dry_run:
        return 0
    result = calibrate(cfg, text, args.out, jobs=args.jobs, np=args.np, resume=args.resume, launcher=args.launcher,
                       progress=not args.quiet)
    if result.status == "interrupted":
        signum = int(result.signal or signal.SIGINT)
        print(_interrupted_line("dem calibrate", "calibrate", args, signum,
                                {"--np": DEFAULT_NP, "--jobs": DEFAULT_JOBS}), file=sys.stderr)
        return 128 + signum  # 130 SIGINT, 143 SIGTERM
    print(f"dem calibrate: {result.status}" + (f": {result.message}" if result.message else "")
          + f" (see {result.out})", file=sys.stderr)
    return 0 if result.status == "complete" else 1


def _common(p, what: str, config_help: str) -> None:
    p.add_argument("config", nargs="?", help=f"TOML config file ({config_help}; see dem/config.py)")
    p.add_argument("--preset", choices=config_mod.PRESETS, help="a shipped config (dem/presets/)")
    p.add_argument("--out", required=True, help=f"{what} folder (new or empty, or with --resume an unfinished one)")
    p.add_argument("--resume", action="store_true",
                   help=f"continue the unfinished {what} in --out with the config stored there (a CONFIG.toml "
                        "or --preset given too must match it)")
    p.add_argument("--launcher", help="launcher template with {np}, e.g. 'srun -n {np}' (default: the "
                                      "mpich wheel's mpirun)")
    p.add_argument("--dry-run", action="store_true",
                   help="validate, print the plan and its cost estimate, run and write nothing (a probe of this "
                        "machine's speed may be cached, outside the project)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override one entry of the config (dotted key, TOML value; repeatable), e.g. load.p_w=10 "
                        "or drive.0.mu_w_tilde=0.3; granstokes preset dem NAME prints a preset to start from")


def register(subparsers) -> None:
    """Add the ``dem`` subcommand to the ``granstokes`` parser."""
    dem = subparsers.add_parser("dem", help="LAMMPS DEM scenes (plate over a granular bed)",
                                description="LAMMPS DEM scenes (plate over a granular bed) and the plane-shear "
                                            "calibration of their grains' mu(I).")
    dem.set_defaults(func=lambda args: dem.print_help() or 0)
    sub = dem.add_subparsers(dest="dem_command", metavar="{run,calibrate,probe}")
    r = sub.add_parser("run", help="run a scene from a TOML config or a preset",
                       description="Run a DEM scene: prepare the bed(s), then each drive; outputs in --out.")
    _common(r, "run", "a scene")
    r.add_argument("--np", type=int, help="MPI ranks per LAMMPS process (default: 2 for a bed that runs alone when "
                                          "the measured scaling says they pay, dem/sizing.py RANKS_GAIN; else 1)")
    r.add_argument("--jobs", type=int, default=DEFAULT_JOBS,
                   help=f"seeds' beds run side by side as separate LAMMPS processes (default {DEFAULT_JOBS})")
    r.add_argument("--quiet", action="store_true", help=QUIET_HELP)
    r.add_argument("--calibration", metavar="CALIBRATION.json",
                   help="size the scene from this calibration of the config's grains (its mu_s, mu_d, I0 and "
                        "phi_max replace the config's [material] table; refused for other grains)")
    r.set_defaults(func=_cmd_run)
    c = sub.add_parser("calibrate", help="mu(I) of a config's grains by plane shear at controlled pressure",
                       description="Calibrate mu(I) and phi(I) by homogeneous (Lees-Edwards) plane shear of the "
                                   "config's grains at p = p_w; writes calibration.json and points.csv in --out.")
    _common(c, "calibration", "with a [calibration] table")
    c.add_argument("--jobs", type=int, default=DEFAULT_JOBS,
                   help=f"points run side by side as separate LAMMPS processes (default {DEFAULT_JOBS})")
    c.add_argument("--np", type=int, default=DEFAULT_NP,
                   help=f"MPI ranks per point (default {DEFAULT_NP})")
    c.add_argument("--quiet", action="store_true", help=QUIET_HELP)
    c.set_defaults(func=_cmd_calibrate)
    p = sub.add_parser("probe", help="measure LAMMPS's speed on this machine for the cost estimates (a few seconds)",
                       description="Time LAMMPS's chute benchmark alone and two at once, and cache the rates the "
                                   "cost estimates use (dem/throughput.py); run it again when the machine changes.")
    p.set_defaults(func=_cmd_probe)
