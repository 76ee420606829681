"""Scheduling a study's beds: MPI ranks from measured strong scaling, and the order of the beds over two slots.

    .venv/bin/python bench/dem_schedule.py scaling [--out FILE]
    .venv/bin/python bench/dem_schedule.py schedule [--out FILE]

``scaling``: one bed (``seeds = [1]``) of each shipped scene preset (smoke, quick: 2D; spheres: 3D, its drives
shortened to SPHERES_DRIVE time units) run alone at 1 and 2 ranks in turn, REPEATS times (``dem.runner.run
--jobs 1``).  A bed's speed-up compares the same steps: the fastest bed's wall time per step of each stage
(run.json) at one rank over that at two, both times the first one-rank bed's steps (a preparation ends on its
own convergence, so its steps vary between runs); the strong-scaling model of dem.sizing.speedup,
S = 2 N / (N + N*), gives the grain count N* = N (2 / S - 1) at which two ranks break even
(dem.sizing.BREAK_EVEN).

``schedule``: the smoke study preset with ``seeds = [1, 2, 3, 4]`` (3 runs x 4 seeds: 12 beds of 3 sizes, sized
from the smoke preset's nominal material, as ``study --dry-run`` does before its calibration; ``--seeds 3``: 9
beds, an odd count, where the order decides which bed ends alone), its beds given to granstokes.lib.executor as
a study gives them: one at a time on one rank, two slots longest first (the executor's order), two slots
shortest first (the costs mirrored, for contrast), alternated REPEATS times.  Wall time of each executor call;
the cost model's makespan of each order beside it.

Both write JSON beside this file (dem_schedule_scaling.json, dem_schedule_{N}seeds.json) and print the rows for
bench/RESULTS.md ("Schedule").
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import tempfile
import time
from pathlib import Path

from granstokes.dem import config as dem_config
from granstokes.dem.runner import allow_lammps, begin, run
from granstokes.dem.sizing import BREAK_EVEN, OVERHEAD, makespan, plan, speedup
from granstokes.dem.throughput import measured

from granstokes.lib.executor import Executor
from granstokes.lib.toml_text import with_entries
from granstokes.study import config as study_config
from granstokes.study.plan import plan_study

HERE = Path(__file__).resolve().parent
SPHERES_DRIVE = 2.0
SCENES = {"smoke": [], "quick": [], "spheres": [("drive.0.duration", SPHERES_DRIVE),
                                                ("drive.1.duration", SPHERES_DRIVE)]}
REPEATS = 2  # 1 and 2 ranks, or the orders, alternated; the fastest of each kept
STUDY, SEEDS = "smoke", 4
ORDERS = {"one at a time, 1 rank": (1, False), "2 slots, longest first": (2, False),
          "2 slots, shortest first": (2, True)}


def bed_seconds(result) -> float:
    return sum(st["wall_time"] for st in result.stages.values())


def stage_steps(result) -> dict:
    """Each stage's steps as LAMMPS ran them (a preparation ends on its own convergence: its count varies)."""
    return {k: (st["info"]["lammps"] if "/" not in k else st["info"])["last_step"] for k, st in result.stages.items()}


def per_step(result) -> dict:
    return {k: result.stages[k]["wall_time"] / n for k, n in stage_steps(result).items()}


def scaling(root: Path) -> dict:
    rows = {}
    for name, entries in SCENES.items():
        text = with_entries(dem_config.preset_text(name), [("seeds", [1]), *entries])
        cfg = dem_config.parse(text)
        p = plan(cfg)
        walls, steps, runs = {}, {}, []
        for rep in range(REPEATS):
            for np_ in (1, 2):
                result = run(p, text, root / f"{name}-np{np_}-{rep}", np=np_, jobs=1, progress=False)
                assert result.ok, result.message
                runs.append({"np": np_, "wall": bed_seconds(result), "steps": stage_steps(result)})
                if bed_seconds(result) < walls.get(np_, math.inf):
                    walls[np_], steps[np_] = bed_seconds(result), per_step(result)
                print(f"{name} ({p.n_grains} grains) at {np_} rank(s): {bed_seconds(result):.1f} s, steps "
                      f"{stage_steps(result)}", flush=True)
        # the two-rank bed's wall time at the one-rank bed's step counts
        same_steps = sum(steps[2][k] * n for k, n in runs[0]["steps"].items()) if runs[0]["np"] == 1 else walls[2]
        s = sum(steps[1][k] * n for k, n in runs[0]["steps"].items()) / same_steps
        rows[name] = {"dimension": p.dimension, "grains": p.n_grains, "walls": walls, "runs": runs, "speedup": s,
                      "break_even": p.n_grains * (2 / s - 1),
                      "modelled": speedup(p.n_grains, p.dimension, 2, cores=2)}
    return rows


def study_beds(root: Path, seeds: list[int], jobs: int, reverse: bool):
    """The study's beds as the study's runner gives them to its executor, in run folders under ``root``, and their
    expected seconds in the order they start (``reverse``: each cost mirrored within the range, so that the
    executor takes the shortest first)."""
    study, _ = study_config.load(None, STUDY, [f"seeds={seeds}"])
    material = dem_config.preset(study.dem)[0].material
    material = {k: getattr(material, k) for k in dem_config.MATERIAL_KEYS}
    sp = plan_study(study, material, "the smoke preset's nominal material")
    runners, tasks = {}, []
    for label, r in sp.runs.items():
        runner, meta = begin(r.plan, r.text, root / label, np=1, progress=False, jobs=jobs)
        runners[label] = runner
        tasks += runner.bed_tasks(meta, prefix=f"{label}/")
    costs = sorted((t.cost for t in tasks), reverse=not reverse)
    if reverse:
        top = max(costs) + min(costs)
        tasks = [dataclasses.replace(t, cost=top - t.cost) for t in tasks]
    return runners, tasks, costs


def schedule(root: Path, seeds: int) -> dict:
    """The study with ``seeds`` seeds in each order, the orders alternated REPEATS times; the fastest of each kept
    (the machine is shared: a disturbed repeat is slower, never faster)."""
    allow_lammps()
    speed = measured(renew=True)
    rows = {}
    for rep in range(REPEATS):
        for order, (jobs, reverse) in ORDERS.items():
            folder = root / f"{order.replace(' ', '_').replace(',', '')}-{rep}"
            runners, tasks, costs = study_beds(folder, list(range(1, seeds + 1)), jobs, reverse)
            t0 = time.monotonic()
            outcomes = Executor(jobs).run(tasks)
            wall = time.monotonic() - t0
            assert all(o.status == "complete" for o in outcomes.values()), outcomes
            print(f"{order}: {wall:.1f} s (load {os.getloadavg()[0]:.1f})", flush=True)
            row = rows.setdefault(order, {"walls": [], "beds": len(tasks), "loads": [],
                                          "model": OVERHEAD + makespan(costs, jobs, contention=speed.contention)})
            row["walls"].append(wall)
            row["loads"].append(os.getloadavg()[0])
            row[f"bed_walls_{rep}"] = {k: bed_seconds_of(runners, k) for k in outcomes}
    return {"seeds": seeds, "orders": rows, "probe": dataclasses.asdict(speed)}


def bed_seconds_of(runners: dict, key: str) -> float:
    label, bed = key.split("/", 1)
    stages = json.loads(runners[label].meta_path.read_text())["stages"]
    return sum(st["wall_time"] for k, st in stages.items() if k == bed or k.startswith(bed + "/"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("part", choices=("scaling", "schedule"))
    ap.add_argument("--seeds", type=int, default=SEEDS, help="schedule: the smoke study's seeds (3 runs each)")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()
    out = args.out or HERE / ("dem_schedule_scaling.json" if args.part == "scaling" else
                              f"dem_schedule_{args.seeds}seeds.json")
    with tempfile.TemporaryDirectory(prefix="dem-schedule-") as tmp:
        result = scaling(Path(tmp)) if args.part == "scaling" else schedule(Path(tmp), args.seeds)
    result["load_end"] = os.getloadavg()
    out.write_text(json.dumps(result, indent=2))
    if args.part == "scaling":
        print("\n| bed | grains | 1 rank [s] | 2 ranks [s] | speed-up | N* = N (2/S - 1) | model (N* of "
              "BREAK_EVEN) |\n|---|---|---|---|---|---|---|")
        for name, r in result.items():
            if name != "load_end":
                print(f"| {name} ({r['dimension']}D) | {r['grains']} | {r['walls'][1]:.1f} | {r['walls'][2]:.1f} | "
                      f"{r['speedup']:.2f}x | {r['break_even']:.0f} | {r['modelled']:.2f}x "
                      f"(N* {BREAK_EVEN[r['dimension']]}) |")
    else:
        rows = result["orders"]
        base = min(rows[next(iter(ORDERS))]["walls"])
        print("\n| schedule | beds | wall [s], each repeat | speed-up over one at a time (fastest) | cost model [s] |"
              "\n|---|---|---|---|---|")
        for order, r in rows.items():
            print(f"| {order} | {r['beds']} | {', '.join(f'{w:.1f}' for w in r['walls'])} | "
                  f"{base / min(r['walls']):.2f}x | {r['model']:.1f} |")
    print(f"load at the end: {result['load_end']}")


if __name__ == "__main__":
    main()
