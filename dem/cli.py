"""``granstokes dem run``: run a DEM scene from a TOML config or a preset.

    granstokes dem run CONFIG.toml --out DIR [--jobs 2] [--np 1] [--resume] [--launcher 'srun -n {np}']
    granstokes dem run --preset smoke|quick|paper --out DIR
    granstokes dem calibrate (CONFIG.toml | --preset NAME) --out DIR [--jobs N] [--np N] [--resume]
"""
from __future__ import annotations

import os
import signal
import sys

from . import config as config_mod
from .lammps_env import DEFAULT_JOBS, DEFAULT_NP, LammpsNotFound


def _cmd_run(args) -> int:
    from .runner import check_request, run

    try:
        if (args.config is None) == (args.preset is None):
            raise ValueError("give exactly one of CONFIG.toml or --preset")
        cfg, text = config_mod.load(args.config) if args.config else config_mod.preset(args.preset)
        runner = check_request(cfg, text, args.out, np=args.np, resume=args.resume, launcher=args.launcher,
                               jobs=args.jobs)
    except (ValueError, OSError, LammpsNotFound) as exc:
        print(f"granstokes dem run: error: {exc}", file=sys.stderr)
        return 2
    print(f"dem: scene '{cfg.name}' -> {args.out}", file=sys.stderr)
    for reason in runner.plan.reasons:
        print(f"  {reason}", file=sys.stderr)
    print(f"  {runner.plan.cost_estimate(runner.jobs)}", file=sys.stderr)
    cores = os.cpu_count() or 1
    if args.np * runner.jobs > cores:
        print(f"dem: warning: --np {args.np} x {runner.jobs} job(s) = {args.np * runner.jobs} ranks on {cores} cores: "
              "oversubscribed, every rank waits for the others (slower than fewer ranks)", file=sys.stderr)
    if args.dry_run:
        return 0
    result = run(cfg, text, args.out, np=args.np, resume=args.resume, launcher=args.launcher,
                 progress=not args.quiet, jobs=args.jobs)
    print(f"dem: {result.status}" + (f": {result.message}" if result.message else "")
          + f" (see {result.out / 'run.json'})", file=sys.stderr)
    if result.status == "interrupted":
        return 128 + int(result.metadata.get("signal", signal.SIGINT))  # 130 SIGINT, 143 SIGTERM
    return 0 if result.ok else 1


def _cmd_calibrate(args) -> int:
    from .calibrate import DEFAULT_JOBS, calibrate

    try:
        if (args.config is None) == (args.preset is None):
            raise ValueError("give exactly one of CONFIG.toml or --preset")
        cfg, text = config_mod.load(args.config) if args.config else config_mod.preset(args.preset)
        result = calibrate(cfg, text, args.out, jobs=DEFAULT_JOBS if args.jobs is None else args.jobs, np=args.np,
                           resume=args.resume, launcher=args.launcher, progress=not args.quiet,
                           announce=lambda line: print(line, file=sys.stderr))
    except (ValueError, OSError, LammpsNotFound) as exc:
        print(f"granstokes dem calibrate: error: {exc}", file=sys.stderr)
        return 2
    print(f"dem calibrate: {result.status}" + (f": {result.message}" if result.message else "")
          + f" (see {result.out})", file=sys.stderr)
    return {"complete": 0, "interrupted": 130}.get(result.status, 1)


def register(subparsers) -> None:
    """Add the ``dem`` subcommand to the ``granstokes`` parser."""
    dem = subparsers.add_parser("dem", help="LAMMPS DEM scenes (plate over a granular bed)")
    sub = dem.add_subparsers(dest="dem_command", required=True)
    r = sub.add_parser("run", help="run a scene from a TOML config or a preset",
                       description="Run a DEM scene: prepare the bed(s), then each drive; outputs in --out.")
    r.add_argument("config", nargs="?", help="TOML config file (see dem/config.py)")
    r.add_argument("--preset", help=f"one of {list(config_mod.PRESETS)}")
    r.add_argument("--out", required=True, help="run folder (must be new or empty unless --resume)")
    r.add_argument("--np", type=int, default=DEFAULT_NP, help=f"MPI ranks per LAMMPS process (default {DEFAULT_NP})")
    r.add_argument("--jobs", type=int, default=DEFAULT_JOBS,
                   help=f"seeds' beds run side by side as separate LAMMPS processes (default {DEFAULT_JOBS})")
    r.add_argument("--resume", action="store_true", help="continue an interrupted run in --out")
    r.add_argument("--launcher", help="launcher template with {np}, e.g. 'srun -n {np}' (default: the "
                                      "mpich wheel's mpirun)")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.add_argument("--dry-run", action="store_true", help="validate, print the sizing and the cost estimate, run nothing")
    r.set_defaults(func=_cmd_run)
    c = sub.add_parser("calibrate", help="mu(I) of a config's grains by plane shear at controlled pressure",
                       description="Calibrate mu(I) and phi(I) by homogeneous (Lees-Edwards) plane shear of the "
                                   "config's grains at p = p_w; writes calibration.json and points.csv in --out.")
    c.add_argument("config", nargs="?", help="TOML config file with a [calibration] table (see dem/config.py)")
    c.add_argument("--preset", help=f"one of {list(config_mod.PRESETS)}")
    c.add_argument("--out", required=True, help="calibration folder (must be new or empty unless --resume)")
    c.add_argument("--jobs", type=int, help="points run concurrently (default 2: two single-rank processes "
                                            "on 2 cores)")
    c.add_argument("--np", type=int, default=1, help="MPI ranks per point (default 1: cells of ~100 grains)")
    c.add_argument("--resume", action="store_true", help="continue an interrupted calibration in --out")
    c.add_argument("--launcher", help="launcher template with {np} (default: the mpich wheel's mpirun)")
    c.add_argument("--quiet", action="store_true", help="no progress bars")
    c.set_defaults(func=_cmd_calibrate)
