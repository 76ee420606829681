"""``granstokes study``: run a study (a grid of pressures x drives x seeds of one material, sized from an
independent calibration) on Dask, and ``granstokes preset``: print a DEM or study preset to edit.

    granstokes study (STUDY.toml | --preset NAME) --out DIR [--jobs N | --scheduler ADDRESS] [--dry-run] [--resume]
    granstokes preset (dem | study) [NAME]
"""
from __future__ import annotations

import json
import shlex
import signal
import sys
from dataclasses import asdict
from pathlib import Path

from granstokes.dem.lammps_env import DEFAULT_JOBS
from granstokes.lib.toml_text import parse_assignment, with_entries
from granstokes.lib.validate import require

from . import config


def _complete(folder: Path) -> bool:
    """Whether the calibration folder of a study holds a complete calibration."""
    from granstokes.dem.layout import CALIBRATION_STATE

    state = folder / CALIBRATION_STATE
    return state.is_file() and json.loads(state.read_text()).get("status") == "complete"


def final_line(record: dict, args) -> str:
    """The study's last line: the report (complete), why and the record (failed), or the command that continues it
    (interrupted); paths as given in --out."""
    out, said = Path(args.out), f": {record['message']}" if record.get("message") else ""
    if record["status"] == "complete":
        return f"study: complete{said} (report: {out / 'index.html'}; record: {out / 'study.json'})"
    if record["status"] == "interrupted":
        name = signal.Signals(int(record.get("signal") or signal.SIGINT)).name
        again = ["--scheduler", args.scheduler] if args.scheduler else \
            ["--jobs", str(args.jobs)] if args.jobs != DEFAULT_JOBS else []
        return f"study: interrupted ({name}); continue with: " + shlex.join(
            ["granstokes", "study", "--resume", "--out", str(out), *again])
    return f"study: {record['status']}{said} (see {out / 'study.json'})"


def target_lines(sp, measured: dict | None = None) -> list[str]:
    """The beds each scored drive needs for the study's error target (none without one), as the study plans them
    (from a first round's ``measured`` one-bed errors where given)."""
    target = sp.study.target
    if target is None:
        return []
    from granstokes.compare import noise

    from .plan import WIDE, drive_label

    table, measured = noise.laws(), measured or {}
    return [f"the error target: beds for a {target.confidence:.0%} decision (compare/noise.csv), at most "
            f"{target.beds_max} a run:"] + [
        noise.target_line(f"{label}, {d.drive.name}", noise.drive_size(r.plan, d, r.p_w), target,
                          len(r.plan.config.seeds), table, measured.get(drive_label(label, d.drive.name)))
        for label, r in sp.runs.items() if not label.endswith(WIDE) for d in r.plan.drives]


def _cmd_study(args) -> int:
    from granstokes.dem import config as dem_config
    from granstokes.dem.calibrate import completed_points, grains_difference, material_table, plan_calibration
    from granstokes.dem.estimate import Estimate
    from granstokes.dem.layout import CALIBRATION_JSON, CALIBRATION_STATE

    from .plan import calibration_config, calibration_folder, first_round, measured_c_s, plan_study
    from .runner import STUDY_TOML, check_folder, run_study

    require(args.scheduler is None or args.jobs is None, "--jobs / --scheduler", "one of them (a scheduler's "
            "workers set the concurrency)", [args.jobs, args.scheduler])
    args.jobs = DEFAULT_JOBS if args.jobs is None else args.jobs
    require(isinstance(args.jobs, int) and args.jobs >= 1, "--jobs", "an integer >= 1 (LAMMPS processes at once)",
            args.jobs)
    if args.resume and args.config is None and args.preset is None:
        stored = Path(args.out) / STUDY_TOML
        require(stored.is_file(), "--resume", f"given with a study folder (holding {STUDY_TOML})", args.out)
        text = stored.read_text()
        if args.set:  # a resume that adds beds (more seeds, a stricter target): check_folder allows only that
            text = with_entries(text, [parse_assignment(a) for a in args.set],
                                header=f"{stored} with --set " + " ".join(args.set))
        study = config.parse(text, Path(args.out))
    else:
        study, text = config.load(args.config, args.preset, args.set or ())
    check_folder(study, Path(args.out), args.resume)
    if args.scheduler is not None:  # a dry run checks the address's form; a run, that its scheduler answers
        from granstokes.lib.executor import check_scheduler, scheduler_address

        (scheduler_address if args.dry_run else check_scheduler)(args.scheduler)
        print(f"study: on the scheduler {args.scheduler}, its workers set the concurrency (the estimates below "
              f"assume {args.jobs} job(s))", file=sys.stderr)
    from granstokes.dem.throughput import measured

    measured(announce=lambda line: print(f"study: {line}", file=sys.stderr))
    out = Path(args.out)
    calibration = Estimate()
    if study.calibration_file is None:  # the stage's cost: the pressures not yet calibrated, what is left of them
        seconds = disk = 0.0
        for p_w in study.calibration_pressures:
            folder = calibration_folder(out, p_w)
            if args.resume and _complete(folder):
                continue
            cp = plan_calibration(calibration_config(study, p_w)[0])
            done = completed_points(folder, cp)[0] if args.resume and (folder / CALIBRATION_STATE).is_file() else ()
            print(f"study: calibration at p = {p_w:g}: {cp.cost_estimate(args.jobs, done=done)}", file=sys.stderr)
            part = cp.estimate(args.jobs, done=done)
            seconds, disk = seconds + part.seconds, disk + part.disk
        calibration = calibration.plus("calibration", seconds, disk)
    reference = calibration_folder(out, study.reference_pressure)
    elasticity_source = None  # the calibration whose measured shear-wave speed times the elastic start
    if study.calibration_file is not None:
        material, source = material_table(study.calibration_file)[0], study.calibration_file
        elasticity_source = study.calibration_file
    elif args.resume and _complete(reference):  # a resume past the calibration sizes from it, as the runs were
        material, source = material_table(reference / CALIBRATION_JSON)[0], str(reference.relative_to(out))
        elasticity_source = reference / CALIBRATION_JSON
    else:  # the calibration runs first: the dry run sizes from the DEM preset's nominal material
        material = dem_config.preset(study.dem)[0].material
        material = {k: getattr(material, k) for k in dem_config.MATERIAL_KEYS}
        source = f"(not yet run: sized here from the {study.dem} preset's nominal material)"
    measured = first_round(out) if args.resume else None  # a resume that adds beds plans from the last report
    sp = plan_study(study, material, source, measured=measured)
    if args.resume:
        sp = sp.as_begun(out)
    if study.calibration_file is not None:  # a calibration of other grains is refused before any work
        _, grains, p_cal = material_table(study.calibration_file)
        for label, r in sp.runs.items():
            diff = grains_difference(grains, p_cal, asdict(r.plan.config.grains), r.p_w)
            require(not diff, "calibration.file", f"a calibration of the grains of run {label}", "different grains: "
                    + ", ".join(f"{k} calibrated {a!r} vs run {b!r}" for k, (a, b) in diff.items()))
    print(f"study '{study.name}': {len(study.pressures)} pressure(s) x {len(study.drives)} drive(s) x "
          f"{len(study.seeds)} seed(s), sized from {source} -> {args.out}", file=sys.stderr)
    for line in sp.lines(args.jobs, out if args.resume else None, measured_c_s(elasticity_source)):
        print(line, file=sys.stderr)
    print(f"  {sp.estimate(args.jobs, out if args.resume else None, calibration).line()}", file=sys.stderr)
    for line in target_lines(sp, measured):
        print(line, file=sys.stderr)
    if args.dry_run:
        from granstokes.compare import noise

        print("the DEM's standard errors this size buys (compare/noise.csv, fitted by bench/dem_cost_noise.py):",
              file=sys.stderr)
        table = noise.laws()
        for label, r in sp.runs.items():
            for d in r.plan.drives:
                print(noise.error_line(f"{label}, {d.drive.name}", noise.drive_size(r.plan, d, r.p_w), table),
                      file=sys.stderr)
        return 0
    record = run_study(study, text, args.out, jobs=args.jobs, scheduler=args.scheduler, resume=args.resume,
                       progress=not args.quiet)
    print(final_line(record, args), file=sys.stderr)
    if record["status"] == "interrupted":
        return 128 + int(record.get("signal") or 2)  # 130 SIGINT, 143 SIGTERM
    return 0 if record["status"] == "complete" else 1


def _cmd_preset(args) -> int:
    from granstokes.dem import config as dem_config

    names = dem_config.PRESETS if args.kind == "dem" else config.PRESETS
    if args.name is None:
        print("\n".join(names))
        return 0
    print(dem_config.preset_text(args.name) if args.kind == "dem" else config.preset_text(args.name), end="")
    return 0


def register(subparsers) -> None:
    s = subparsers.add_parser("study", help="a grid of DEM drives over pressures, sized from a calibration, on Dask",
                              description="Run a study: the calibration (a file, or plane shear at the lowest and "
                                          "highest pressure), every pressure's run (all drives, all seeds), and the "
                                          "comparison of every drive with every model. Start from a preset: "
                                          "granstokes preset study NAME.")
    s.add_argument("config", nargs="?", help="STUDY.toml (schema: granstokes/study/config.py)")
    s.add_argument("--preset", choices=config.PRESETS, help="a shipped study (granstokes/study/presets/)")
    s.add_argument("--out", required=True, help="study folder (new or empty, or with --resume an unfinished one)")
    s.add_argument("--jobs", type=int, help=f"LAMMPS processes at once on this machine (default {DEFAULT_JOBS})")
    s.add_argument("--scheduler", help="address of a running Dask scheduler (e.g. tcp://host:8786) whose workers "
                                       "run the LAMMPS processes; the folder must be on a file system they share")
    s.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override one entry of the study (dotted key, TOML value; repeatable), e.g. seeds=[1,2,3]")
    s.add_argument("--resume", action="store_true", help="continue the unfinished study in --out")
    s.add_argument("--dry-run", action="store_true", help="print the plan and its cost, run and write nothing")
    s.add_argument("--quiet", action="store_true", help="no progress bar")
    s.set_defaults(func=_cmd_study)
    p = subparsers.add_parser("preset", help="print a DEM or study preset (a config to edit), or list them")
    p.add_argument("kind", choices=("dem", "study"))
    p.add_argument("name", nargs="?", help="the preset (none: list them)")
    p.set_defaults(func=_cmd_preset)
