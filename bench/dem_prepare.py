"""Preparation ending on its own convergence against a fixed free fall, on the shipped presets' beds.

    .venv/bin/python bench/dem_prepare.py [--out DIR]

For each preset (smoke, quick: 2D; spheres: 3D) and each of its seeds, the preparation script as the
harness writes it (the fall and settling end when the kinetic energy per grain is below the threshold)
and the same script with a fixed free fall of FALL_MARGIN free-fall times first (the scene before this
change), one rank, one after the other.  Prints, per variant, the steps LAMMPS ran, its loop time and the
prepared bed's height under the plate (plate_y: the packing the bed settled into), and writes
bench/dem_prepare.json.
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from granstokes.dem import config, lammps_env, scene
from granstokes.dem.sizing import FALL_MARGIN, plan

HERE = Path(__file__).resolve().parent
PRESETS = ("smoke", "quick", "spheres")


def fixed_fall(script: str, steps: int) -> str:
    """The preparation with a fixed free fall of ``steps`` before settling's checks."""
    return script.replace('print "PHASE settle"', f'run {steps}\nprint "PHASE settle"', 1)


def prepare(script: str, work: Path) -> dict:
    work.mkdir(parents=True)
    (work / "prepare.in").write_text(script)
    subprocess.run([str(lammps_env.lmp_binary()), "-in", "prepare.in", "-log", "log.lammps", "-nocite"],
                   cwd=work, env=lammps_env.child_env(), check=True, stdout=subprocess.DEVNULL)
    log = (work / "log.lammps").read_text()
    loops = [float(x) for x in re.findall(r"Loop time of (\S+)", log)]
    steps = [int(x) for x in re.findall(r"Loop time of \S+ on \d+ procs for (\d+) steps", log)]
    relaxed = re.findall(r"relaxed ke_grain=(\S+) plate_y=(\S+)", log)[-1]
    return {"steps": sum(steps), "loop": sum(loops), "ke_grain": float(relaxed[0]), "plate_y": float(relaxed[1])}


def main() -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="scratch folder (default: a temporary one)")
    root = ap.parse_args().out or Path(tempfile.mkdtemp(prefix="dem-prepare-"))
    res = {}
    for name in PRESETS:
        p = plan(config.preset(name)[0])
        old_fall = round(FALL_MARGIN * p.free_fall_steps)
        for seed in p.config.seeds:
            text = scene.prepare_script(p, seed)
            res[f"{name}/{seed}"] = {"grains": p.n_grains,
                                     "converged": prepare(text, root / name / f"{seed}-converged"),
                                     "fixed fall": prepare(fixed_fall(text, old_fall), root / name / f"{seed}-fixed")}
    (HERE / "dem_prepare.json").write_text(json.dumps(res, indent=2))
    print(markdown(res))
    return res


def markdown(res: dict) -> str:
    lines = ["| preset | grains | beds | steps: fixed fall / converged | loop time [s]: fixed fall / converged | "
             "speed-up | plate_y: fixed fall / converged (mean ± sd over beds) |", "|---|---|---|---|---|---|---|"]
    for name in PRESETS:
        beds = [v for k, v in res.items() if k.startswith(f"{name}/")]
        col = lambda variant, key: np.array([b[variant][key] for b in beds])
        fixed, conv = col("fixed fall", "loop").sum(), col("converged", "loop").sum()
        y_f, y_c = col("fixed fall", "plate_y"), col("converged", "plate_y")
        sd = lambda y: f"{y.std(ddof=1):.2f}" if len(y) > 1 else "-"
        lines.append(f"| {name} | {beds[0]['grains']} | {len(beds)} | {col('fixed fall', 'steps').sum()} / "
                     f"{col('converged', 'steps').sum()} | {fixed:.1f} / {conv:.1f} | {fixed / conv:.2f} | "
                     f"{y_f.mean():.2f} ± {sd(y_f)} / {y_c.mean():.2f} ± {sd(y_c)} |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
