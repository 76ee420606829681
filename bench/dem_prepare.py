"""Preparation before and after its speed-up, on the shipped presets' beds: steps, time and the prepared bed.

    .venv/bin/python bench/dem_prepare.py [--presets smoke quick spheres] [--seeds N] [--denser] [--out DIR]

For each preset (smoke, quick: 2D; spheres: 3D) and each of its seeds (``--seeds N``: 1 to N), one rank, one
after the other, three variants of the preparation script:

* ``before``: the scene as it was at BEFORE (dem/scene.py read from git): settling until the kinetic energy
  per grain is below ``prepare.ke_per_grain``, the plate let down against a drag of terminal speed 1 (2D;
  0.5 d/√(d/g) in 3D), relax's check on the bed's kinetic energy alone;
* ``before + plate KE``: the same, its relax check counting the plate's kinetic energy (the fair baseline:
  without it relax may end before the plate has landed);
* ``after``: the scene as the harness writes it now (settling until the pile has landed and is below
  ``prepare.settle_ke_per_grain``, the plate brought down at PLATE_APPROACH_SPEED, the plate counted);
* ``after, denser column`` (``--denser``, not adopted): the same with the column inserted DENSER times as
  densely (dem.sizing.INSERT_FRACTION), so shorter: less fall, slower impacts.

Prints per variant the steps LAMMPS ran (settling, relaxing), the loop time, and the prepared bed: the bulk
packing fraction phi (grain volume cut by the planes over the band BULK_ABOVE_BASE d above the base to
BULK_BELOW_PLATE d below the plate's centre) and the plate's height plate_y, mean ± sd over the beds; the
speed-ups are ratios of loop times in the same run.  Writes bench/dem_prepare.json (merged per preset).
"""
from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from granstokes.dem import config, lammps_env, scene, sizing
from granstokes.dem.sizing import plan

HERE = Path(__file__).resolve().parent
PRESETS = ("smoke", "quick", "spheres")
#: the last commit of dem/scene.py before the preparation's speed-up
BEFORE = "b6e11b5"
VARIANTS = ("before", "before + plate KE", "after")
DENSER_VARIANT, DENSER = "after, denser column", 1.5
#: bulk band for phi: from this far above the base's top to this far below the plate's centre (d)
BULK_ABOVE_BASE, BULK_BELOW_PLATE = 2.0, 3.0
POSITIONS = "bulk.dump"


def _scene_before():
    """dem/scene.py as it was at BEFORE, imported beside the current one."""
    text = subprocess.run(["git", "show", f"{BEFORE}:dem/scene.py"], cwd=HERE.parent, check=True,
                          capture_output=True, text=True).stdout
    path = Path(tempfile.mkdtemp(prefix="scene-before-")) / "scene_before.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("granstokes.dem.scene_before", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def plate_counted(script: str, dim: int) -> str:
    """The old script with relax's kinetic energy per grain counting the plate's (as the scene does now)."""
    mass = re.search(r"variable ke_grain equal c_ke_bed/count\(bed\)/(\S+)", script).group(1)
    marker = "variable plate_y equal f_plate[1][2]\n"
    assert marker in script and dim in (2, 3)
    return script.replace(marker, marker + "compute ke_plate plate ke\n"
                          f"variable ke_grain equal (c_ke_bed+c_ke_plate)/count(bed)/{mass}\n", 1)


def with_positions(script: str) -> str:
    """The script writing the prepared grains' positions (bed and base) for phi."""
    return script + f"write_dump all custom {POSITIONS} type x y z radius modify sort id\n"


def bulk_phi(path: Path, p, plate_y: float) -> float:
    """Solid fraction of bed and base grains between BULK_ABOVE_BASE above the base and BULK_BELOW_PLATE
    below the plate's centre: each disk's or sphere's volume cut by the two planes."""
    rows = np.loadtxt(path, skiprows=9)
    rows = rows[rows[:, 0] != 3]  # plate grains out
    y, r = rows[:, 2], rows[:, 4]
    lo, hi = p.config.box.base_thickness + BULK_ABOVE_BASE, plate_y - BULK_BELOW_PLATE

    def below(u):  # volume of a grain below height u above its centre
        u = np.clip(u, -r, r)
        if p.dimension == 2:
            return r ** 2 * (np.arcsin(u / r) + np.pi / 2) + u * np.sqrt(r ** 2 - u ** 2)
        return np.pi * (r ** 2 * u - u ** 3 / 3 + 2 * r ** 3 / 3)

    return float((below(hi - y) - below(lo - y)).sum() / (p.area * (hi - lo)))


def denser_script(cfg, seed: int) -> str:
    """The current script with the insertion column DENSER times as dense (a shorter box)."""
    usual = dict(sizing.INSERT_FRACTION)
    sizing.INSERT_FRACTION.update({d: DENSER * f for d, f in usual.items()})
    try:
        return scene.prepare_script(plan(cfg), seed)
    finally:
        sizing.INSERT_FRACTION.update(usual)


def prepare(script: str, work: Path, p) -> dict:
    work.mkdir(parents=True)
    (work / "prepare.in").write_text(with_positions(script))
    subprocess.run([str(lammps_env.lmp_binary()), "-in", "prepare.in", "-log", "log.lammps", "-nocite"],
                   cwd=work, env=lammps_env.child_env(), check=True, stdout=subprocess.DEVNULL)
    log = (work / "log.lammps").read_text()
    settling, relaxing = log.split("PHASE relax\n", 1)
    steps = lambda text: sum(int(x) for x in re.findall(r"Loop time of \S+ on \d+ procs for (\d+) steps", text))
    loop = sum(float(x) for x in re.findall(r"Loop time of (\S+)", log))
    ke, plate_y = (float(x) for x in re.findall(r"relaxed ke_grain=(\S+) plate_y=(\S+)", log)[-1])
    return {"settle_steps": steps(settling), "relax_steps": steps(relaxing), "loop": loop, "ke_grain": ke,
            "plate_y": plate_y, "phi": bulk_phi(work / POSITIONS, p, plate_y)}


def main() -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", nargs="+", choices=PRESETS, default=list(PRESETS))
    ap.add_argument("--seeds", type=int, default=None, help="seeds 1 to N instead of each preset's")
    ap.add_argument("--denser", action="store_true", help=f"also the variant {DENSER_VARIANT!r}")
    ap.add_argument("--out", type=Path, default=None, help="scratch folder (default: a temporary one)")
    args = ap.parse_args()
    root = args.out or Path(tempfile.mkdtemp(prefix="dem-prepare-"))
    old = _scene_before()
    path = HERE / "dem_prepare.json"
    res = json.loads(path.read_text()) if path.is_file() else {}
    res = {k: v for k, v in res.items() if k in PRESETS}
    for name in args.presets:
        t0 = time.monotonic()
        cfg = config.preset(name)[0]
        p = plan(dataclasses.replace(cfg, seeds=tuple(range(1, args.seeds + 1))) if args.seeds else cfg)
        beds = {}
        for seed in p.config.seeds:
            before = old.prepare_script(p, seed)
            scripts = {"before": before, "before + plate KE": plate_counted(before, p.dimension),
                       "after": scene.prepare_script(p, seed)}
            if args.denser:
                scripts[DENSER_VARIANT] = denser_script(p.config, seed)
            beds[str(seed)] = {v: prepare(text, root / name / str(seed) / re.sub(r"\W", "", v), p)
                               for v, text in scripts.items()}
        res[name] = {"grains": p.n_grains, "dt": p.dt, "free_fall_steps": p.free_fall_steps, "beds": beds,
                     "load_average": os.getloadavg(), "seconds": time.monotonic() - t0}
        path.write_text(json.dumps(res, indent=2))
        print(f"{name} done in {res[name]['seconds']:.0f} s, load {os.getloadavg()[0]:.1f}", file=sys.stderr)
    print(markdown(res))
    return res


def _ms(x: np.ndarray, digits: int) -> str:
    sd = f"{x.std(ddof=1):.{digits}f}" if len(x) > 1 else "-"
    return f"{x.mean():.{digits}f} ± {sd}"


def markdown(res: dict) -> str:
    lines = ["| preset | beds | variant | steps: settle + relax | loop time [s] | speed-up over before, "
             "before + plate KE | phi (bulk) | plate_y | load |", "|---|---|---|---|---|---|---|---|---|"]
    expected = []
    for name in PRESETS:
        if name not in res:
            continue
        r = res[name]
        beds = list(r["beds"].values())
        col = lambda variant, key: np.array([b[variant][key] for b in beds])
        for v in [v for v in (*VARIANTS, DENSER_VARIANT) if v in beds[0]]:
            speed = ", ".join(f"{col(b, 'loop').sum() / col(v, 'loop').sum():.2f}" for b in VARIANTS[:2])
            lines.append(f"| {name} | {len(beds)} | {v} | {col(v, 'settle_steps').sum()} + "
                         f"{col(v, 'relax_steps').sum()} | {col(v, 'loop').sum():.1f} | "
                         f"{'' if v in VARIANTS[:2] else speed} | {_ms(col(v, 'phi'), 4)} | "
                         f"{_ms(col(v, 'plate_y'), 2)} | {r['load_average'][0]:.1f} |")
        total = col("after", "settle_steps") + col("after", "relax_steps")
        expected += list((total - r["free_fall_steps"]) * r["dt"])
    lines.append("")
    lines.append(f"after: steps beyond one free fall from the box's top, mean over the beds: "
                 f"{np.mean(expected):.1f} time units (range {min(expected):.1f} to {max(expected):.1f}; "
                 "dem.sizing.SETTLE_RELAX_EXPECTED)")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
