"""The DEM scenes as a user runs them against the shared yardsticks, all in one invocation.

    .venv/bin/python bench/dem_as_run.py [--repeats R] [--out DIR] [--shared DIR]

* the shared 2D yardstick (``../shared/bench/yardstick2d/``, ``--shared``), built exactly as its README says:
  800 disks settled by ``in.settle2d``, base and chute profile by ``base_and_flow.py``, flowed by ``in.chute2d`` for
  CHUTE2D_STEPS steps, best of R; and the same disks at rest: the same base at zero speed, ``in.chute2d`` with its
  gravity untilted (REST_GRAVITY), a dense packing under its own weight in the yardstick's own contact law, skin and
  time step: what its pair style costs where every grain touches its neighbours;
* the 3D chute (LAMMPS's granular chute benchmark of 32,000 spheres, ``bench/dem_yardstick.py``), best of R;
* the smoke and spheres presets run as a user runs them, ``granstokes dem run --preset P --np 1 --jobs 1 --out DIR``
  (every output; one LAMMPS process at a time), R times each: the rate of each drive from its ``log.lammps``
  (atoms x steps / loop time / ranks), the best drive log, and the whole run's drives together (their atom-steps
  over their summed loop time);
* the smoke preset with its recording cut to the least the comparison reads (recording_off: the atoms, contacts
  and profiles written at the drive's first and last step only, one restart at its end; the plate still sampled as
  always), R times: what a smoke drive costs without the dumps' frames.

Ratios are to the yardstick of the scene's dimension measured in the same invocation. CPU use is LAMMPS's own
figure for a run (below 100 % when it waited for a core); the ``granstokes`` command's CPU use is its process
tree's CPU time over its wall time. On a machine shared with other sessions (the kernel's autogroup shares the
cores between sessions whatever their nice value), the rate per CPU-second (the rate over LAMMPS's CPU use) is
printed too: the runs' shares of a core differ, their work per CPU-second much less. The load average is read
before and after. Writes bench/dem_as_run.json and prints the table for bench/RESULTS.md ("DEM yardstick").
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from dem_yardstick import BREAKDOWN, LARGE, best_of, chute, timed
from granstokes.dem import config as dem_config
from granstokes.dem import lammps_env

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SHARED = ROOT.parent / "shared" / "bench" / "yardstick2d"
#: the shared yardstick's README: 800 disks, 20 d wide, chute speed 14.6, 40,000 timed steps
CHUTE2D_GRAINS, CHUTE2D_WIDTH, CHUTE2D_SPEED, CHUTE2D_STEPS = 800, 20, 14.6, 40000
CHUTE3D_STEPS = 1000
#: the yardstick's tilted gravity, and the untilted one of its disks at rest
CHUTE2D_GRAVITY, REST_GRAVITY = "vector 0.438371 -0.898794 0", "vector 0 -1 0"
REST2D = "2D chute's disks at rest (its script, gravity untilted)"
#: the presets run as a user runs them, and the yardstick each is compared with
PRESETS = {"smoke": "2D chute (shared yardstick)", "spheres": "3D chute, 32k spheres"}
#: the outputs the smoke preset writes at its drive's first and last step only (recording_off); the plate's series
#: is kept
RECORDED = ("atoms", "contacts", "profiles", "restart")
SMOKE_BARE = "smoke, recording at the drive's first and last step only"


def recording_off(preset: str) -> tuple[str, ...]:
    """``--set`` values setting each of RECORDED's interval to the preset's longest drive (a dump is also written at
    a drive's first step)."""
    end = max(d.duration for d in dem_config.preset(preset)[0].drives)
    return tuple(f"output.{name}={end!r}" for name in RECORDED)


def lammps(args: list[str], cwd: Path) -> None:
    subprocess.run([str(lammps_env.lmp_binary()), *args, "-nocite", "-screen", "none"], cwd=cwd,
                   env=lammps_env.child_env(), check=True)


def shared_yardstick(shared: Path, work: Path, repeats: int) -> tuple[dict, dict]:
    """The 2D chute built and run by the commands of its README, and its disks at rest (module docstring): the
    fastest of ``repeats`` timed runs of each, the two interleaved."""
    work.mkdir(parents=True)
    lammps(["-in", str(shared / "in.settle2d"), "-var", "n", str(CHUTE2D_GRAINS), "-var", "lx", str(CHUTE2D_WIDTH),
            "-var", "out", "settle.data", "-log", "log.settle"], work)
    for data, speed in (("chute.data", CHUTE2D_SPEED), ("rest.data", 0.0)):
        subprocess.run([sys.executable, str(shared / "base_and_flow.py"), "settle.data", data, "2", str(speed)],
                       cwd=work, check=True, stdout=subprocess.DEVNULL)
    script = (shared / "in.chute2d").read_text()
    if CHUTE2D_GRAVITY not in script:
        raise SystemExit(f"dem_as_run: {shared / 'in.chute2d'} no longer tilts gravity by '{CHUTE2D_GRAVITY}'")
    (work / "in.rest2d").write_text(script.replace(CHUTE2D_GRAVITY, REST_GRAVITY))
    runs = {"chute": [], "rest": []}
    for k in range(repeats):
        for name, script_path in (("chute", shared / "in.chute2d"), ("rest", work / "in.rest2d")):
            lammps(["-in", str(script_path), "-var", "data", f"{name}.data", "-var", "nsteps", str(CHUTE2D_STEPS),
                    "-log", f"log.{name}{k}"], work)
            runs[name].append(timed((work / f"log.{name}{k}").read_text()))
    return tuple({"dimension": 2, **max(r, key=lambda x: x["rate"])} for r in runs.values())


def as_run(preset: str, out: Path, overrides: tuple[str, ...] = ()) -> dict:
    """``granstokes dem run --preset P --np 1 --jobs 1`` into ``out`` (``overrides``: its ``--set`` values): each
    drive's timing, the whole run's drives together, the command's wall time and its process tree's CPU use."""
    before, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.monotonic()
    sets = [arg for value in overrides for arg in ("--set", value)]
    subprocess.run([str(ROOT / ".venv" / "bin" / "granstokes"), "dem", "run", "--preset", preset, "--np", "1",
                    "--jobs", "1", "--out", str(out), "--quiet", *sets], check=True, stdout=subprocess.DEVNULL)
    wall, after = time.monotonic() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    drives = {str(log.parent.relative_to(out)): timed(log.read_text())
              for log in sorted(out.glob("seed-*/*/log.lammps")) if log.parent.name != "prepare"}
    atom_steps = sum(d["atoms"] * d["steps"] for d in drives.values())
    loop = sum(d["loop"] * d["ranks"] for d in drives.values())
    return {"drives": drives, "all_drives": {"atom_steps": atom_steps, "loop": loop, "rate": atom_steps / loop},
            "wall": wall, "command_cpu": 100 * cpu / wall}


def load() -> list[float]:
    return [float(x) for x in Path("/proc/loadavg").read_text().split()[:3]]


def machine() -> dict:
    lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    model = next((line.split(":", 1)[1].strip() for line in lscpu.splitlines() if line.startswith("Model name")), "")
    return {"nproc": os.cpu_count(), "model": model}


def main() -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="runs of each yardstick and preset (default 3)")
    ap.add_argument("--out", type=Path, default=None, help="scratch folder (default: a temporary one)")
    ap.add_argument("--shared", type=Path, default=SHARED, help=f"the shared 2D yardstick (default {SHARED})")
    args = ap.parse_args()
    root = args.out or Path(tempfile.mkdtemp(prefix="dem-as-run-"))
    load_before, t0 = load(), time.monotonic()
    flow, rest = shared_yardstick(args.shared, root / "yardstick2d", args.repeats)
    sticks = {PRESETS["smoke"]: flow,
              PRESETS["spheres"]: {"dimension": 3, **best_of(chute(3, LARGE, CHUTE3D_STEPS), root / "chute3d",
                                                             args.repeats)}}
    presets = {name: [as_run(name, root / f"{name}-{k}") for k in range(args.repeats)] for name in PRESETS}
    bare = [as_run("smoke", root / f"smoke-bare-{k}", recording_off("smoke")) for k in range(args.repeats)]
    res = {"machine": machine(), "load_before": load_before, "load_after": load(), "lammps": lammps_env.lammps_info(),
           "repeats": args.repeats, "yardsticks": sticks, "rest": rest, "presets": presets, "smoke_bare": bare,
           "seconds": time.monotonic() - t0}
    (HERE / "dem_as_run.json").write_text(json.dumps(res, indent=2))
    print(markdown(res))
    return res


def _per_cpu(r: dict) -> float:
    """Atom-steps per CPU-second of a run: its rate over LAMMPS's CPU use."""
    return r["rate"] / (r["cpu"] / 100)


def _shares(r: dict) -> str:
    return " / ".join(f"{r['breakdown'].get(k, 0):.0f}" for k in BREAKDOWN)


def markdown(res: dict) -> str:
    m, before, after = res["machine"], res["load_before"], res["load_after"]
    lines = [f"Command: `.venv/bin/python bench/dem_as_run.py --repeats {res['repeats']}` ({m['model']}, nproc "
             f"{m['nproc']}; LAMMPS {res['lammps']['lammps_version']}; load average {before[0]:.1f} / {before[1]:.1f} "
             f"before, {after[0]:.1f} / {after[1]:.1f} after (1 / 5 min); {res['seconds'] / 60:.0f} min).", "",
             "| run | grains | atom-steps/s per rank | ratio to its yardstick | LAMMPS CPU use % | command CPU use % | "
             "per CPU-second: atom-steps, ratio | Pair / Neigh / Comm / Modify / Output % |",
             "|---|---|---|---|---|---|---|---|"]
    for label, r in res["yardsticks"].items():
        lines.append(f"| {label}, best of {res['repeats']} | {r['atoms']} | {r['rate'] / 1e6:.2f} M | 1.00 | "
                     f"{r['cpu']:.0f} | | {_per_cpu(r) / 1e6:.2f} M, 1.00 | {_shares(r)} |")
    flow, rest = res["yardsticks"][PRESETS["smoke"]], res["rest"]
    lines.append(f"| {REST2D}, best of {res['repeats']} | {rest['atoms']} | {rest['rate'] / 1e6:.2f} M | "
                 f"{rest['rate'] / flow['rate']:.2f} | {rest['cpu']:.0f} | | {_per_cpu(rest) / 1e6:.2f} M, "
                 f"{_per_cpu(rest) / _per_cpu(flow):.2f} | {_shares(rest)} |")
    for name, runs in res["presets"].items():
        lines += _preset_rows(f"{name} as run", runs, res["yardsticks"][PRESETS[name]])
    if "smoke_bare" in res:
        lines += _preset_rows(SMOKE_BARE, res["smoke_bare"], flow)
    return "\n".join(lines)


def _preset_rows(label: str, runs: list[dict], stick: dict) -> list[str]:
    """The best drive log of ``runs`` and the best run's drives together, each against the yardstick ``stick``."""
    ref = stick["rate"]
    logs = [(d, run) for run in runs for d in run["drives"].values()]
    best, run = max(logs, key=lambda x: x[0]["rate"])
    whole = max(runs, key=lambda r: r["all_drives"]["rate"])
    return [f"| {label}, best drive log of {len(logs)} | {best['atoms']} | {best['rate'] / 1e6:.2f} M | "
            f"{best['rate'] / ref:.2f} | {best['cpu']:.0f} | {run['command_cpu']:.0f} | {_per_cpu(best) / 1e6:.2f} M, "
            f"{_per_cpu(best) / _per_cpu(stick):.2f} | {_shares(best)} |",
            f"| {label}, every drive of the best run together | {best['atoms']} | "
            f"{whole['all_drives']['rate'] / 1e6:.2f} M | {whole['all_drives']['rate'] / ref:.2f} | | "
            f"{whole['command_cpu']:.0f} | | |"]


if __name__ == "__main__":
    main()
