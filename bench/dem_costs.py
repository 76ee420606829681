"""The cost estimates against the measured wall time and disk: every shipped DEM preset and study preset, the total
``--dry-run`` prints against the command then run, on the same machine, one row after the other; with
``--shared``, each row again beside one busy process per core (the stretch a shared machine gives).

    .venv/bin/python bench/dem_costs.py [--rows NAME ...] [--shared] [--constants]

Each row takes the CPU lock (/work/runs/cpu.lock, as ``flock`` does) for itself only: a fresh probe
(``granstokes dem probe``, before any busy process starts: the estimate is the idle machine's), the dry run (its
"total: about ... and N MB of disk" line read back, with its stages), then the real command into a new folder,
timed from start to exit, and the folder's size; the load average before and after.  The presets of hours (the
paper scene, the disks and spheres studies) are measured on a subset, and the estimate is the dry run of that
same subset: one bed with its drives shortened; one seed of every run with a committed calibration; a
calibration at one pressure with three inertial numbers and one seed.  A study's comparison stage is also timed
on its own (from the line announcing it to the exit) against the total's comparison stage.

``--constants`` measures the comparison's two constants (compare/stokes_experiment.py) instead: the
coarse-graining rate (bench/cg_rate.py) and the model side of the disks study on one process
(bench/compare_cost.py), each between two probes, under one lock.
Writes bench/dem_costs.json (merged: rows not rerun are kept; shared rows under "shared") and prints the tables
for bench/RESULTS.md.
"""
from __future__ import annotations

import argparse
import fcntl
import json
import os
import re
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LOCK = Path("/work/runs/cpu.lock")
SCRATCH = Path("/work/runs/cost")
GS = [sys.executable, "-m", "granstokes.cli"]
DISKS_CALIBRATION = ROOT / "results" / "calibration-disks" / "p20" / "calibration.json"
SPHERES_CALIBRATION = SCRATCH / "study-spheres-calibration" / "calibration.json"
#: the paper scene's subset: one bed, each of its six drives this long (time units; the preset's 20-57)
PAPER_DRIVE = 0.5
#: the disks study's subset: its drives this many t_s long (the preset's 10)
DISKS_TS = 4.0
#: the spheres calibration's subset: its inertial numbers at one seed, no finite-size cell
CAL_SUBSET = ["calibration.seeds=[1]", "calibration.finite_size=[]"]


def _sets(*entries: str) -> list[str]:
    return [x for e in entries for x in ("--set", e)]


def _calibration_config(study: str, p_w: float) -> Path:
    """The study's calibration config at p_w (granstokes.study.plan.calibration_config), written for dem calibrate."""
    from granstokes.study.config import parse, preset_text
    from granstokes.study.plan import calibration_config

    path = SCRATCH / f"calibration-{study}-p{p_w:g}.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(calibration_config(parse(preset_text(study)), p_w)[1])
    return path


#: name -> (what is measured, the command without --out / --dry-run)
ROWS = {
    "dem smoke": ("the preset", lambda: ["dem", "run", "--preset", "smoke"]),
    "dem quick": ("the preset", lambda: ["dem", "run", "--preset", "quick"]),
    "dem spheres": ("the preset", lambda: ["dem", "run", "--preset", "spheres"]),
    "dem paper": (f"one bed, its 6 drives {PAPER_DRIVE:g} time units each",
                  lambda: ["dem", "run", "--preset", "paper",
                           *_sets("seeds=[1]", *(f"drive.{k}.duration={PAPER_DRIVE}" for k in range(6)))]),
    "dem calibrate quick": ("the preset's calibration", lambda: ["dem", "calibrate", "--preset", "quick"]),
    "study smoke": ("the preset", lambda: ["study", "--preset", "smoke"]),
    "study oscillating-smoke": ("the preset", lambda: ["study", "--preset", "oscillating-smoke"]),
    "study disks": (f"seed 1 of every run, drives of {DISKS_TS:g} t_s, the committed calibration",
                    lambda: ["study", "--preset", "disks",
                             *_sets("seeds=[1]", f"duration_ts={DISKS_TS}",
                                    f"calibration={{file = \"{DISKS_CALIBRATION}\"}}")]),
    "study disks: calibration": ("its calibration at p = 20 (one of its two)",
                                 lambda: ["dem", "calibrate", str(_calibration_config("disks", 20.0))]),
    "study spheres: calibration": ("at p = 10, one seed, no finite-size cell",
                                   lambda: ["dem", "calibrate", str(_calibration_config("spheres", 10.0)),
                                            *_sets(*CAL_SUBSET)]),
    "study spheres": ("p_w = 10 only, seed 1, the calibration of the row above",
                      lambda: ["study", "--preset", "spheres",
                               *_sets("seeds=[1]", "pressures=[10.0]",
                                      f"calibration={{file = \"{SPHERES_CALIBRATION}\"}}")]),
}
UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0}
BYTES = {"B": 1.0, "kB": 1e3, "MB": 1e6, "GB": 1e9}
TOTAL = re.compile(r"total: about ([\d.]+) (s|min|h) on this machine \((.*)\) and ([\d.]+) (B|kB|MB|GB) of disk")
STAGE = re.compile(r"([a-z-]+) ([\d.]+) (s|min|h)")
#: the rows the acceptance of the estimates names (idle within 30 %, and their stretch when shared)
ACCEPTANCE = ("dem smoke", "dem quick", "dem spheres", "dem calibrate quick", "study smoke", "study oscillating-smoke")


@contextmanager
def cpu_lock():
    LOCK.parent.mkdir(parents=True, exist_ok=True)
    with open(LOCK, "a") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def estimate(lines: list[str]) -> dict:
    """The dry run's total line: seconds, disk, and each stage's seconds."""
    value, unit, stages, size, size_unit = TOTAL.search(next(x for x in lines if "total: about" in x)).groups()
    return {"total": float(value) * UNITS[unit], "disk": float(size) * BYTES[size_unit],
            **{what: float(v) * UNITS[u] for what, v, u in STAGE.findall(stages)}}


@contextmanager
def busy(processes: int):
    """``processes`` busy Python loops (another user's CPU work), stopped on exit."""
    loops = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(processes)]
    try:
        yield
    finally:
        for p in loops:
            p.kill()
            p.wait()


def folder_bytes(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())


def probe() -> dict:
    subprocess.run([*GS, "dem", "probe"], check=True, capture_output=True)
    from granstokes.dem.throughput import cache_path

    return json.loads(cache_path().read_text())["probe"]


def measure(name: str, shared: bool = False) -> dict:
    what, command = ROWS[name]
    argv = command()
    out = SCRATCH / re.sub(r"\W+", "-", name)
    subprocess.run(["rm", "-rf", str(out)], check=True)
    with cpu_lock():
        load = [os.getloadavg()[0]]
        speed = probe()
        dry = subprocess.run([*GS, *argv, "--out", str(out), "--dry-run"], capture_output=True, text=True, check=True)
        est = estimate(dry.stderr.splitlines())
        with busy(os.cpu_count() if shared else 0):
            t0 = time.perf_counter()
            proc = subprocess.Popen([*GS, *argv, "--out", str(out)], stderr=subprocess.PIPE,
                                    stdout=subprocess.DEVNULL, text=True)
            compare_start, log = None, []
            for line in proc.stderr:
                log.append(f"{time.perf_counter() - t0:8.1f} {line.rstrip()}")
                if compare_start is None and "comparing every drive" in line:
                    compare_start = time.perf_counter() - t0
            proc.wait()
            wall = time.perf_counter() - t0
            load.append(os.getloadavg()[0])
    (SCRATCH / f"{out.name}{'-shared' if shared else ''}.log").write_text("\n".join(log) + "\n")
    if proc.returncode != 0:
        raise SystemExit(f"{name}: exit {proc.returncode} (log in {SCRATCH / out.name}.log)")
    row = {"what": what, "command": "granstokes " + " ".join(argv), "estimate": est, "measured": wall,
           "ratio": est["total"] / wall, "disk": folder_bytes(out), "probe": speed, "load": load,
           "when": time.strftime("%Y-%m-%d %H:%M")}
    if compare_start is not None:
        row["measured_comparison"] = wall - compare_start
    subprocess.run(["rm", "-rf", str(out)], check=True)
    return row


def constants() -> dict:
    """The coarse-graining rate and the model side's seconds per drive and model, each between two probes."""
    SCRATCH.mkdir(parents=True, exist_ok=True)
    with cpu_lock():
        before = probe()["2"]
        cg = subprocess.run([sys.executable, str(ROOT / "bench" / "cg_rate.py")], capture_output=True, text=True,
                            check=True).stdout
        rate = float(re.search(r"coarse-graining, end to end.*?\| [\d.]+ \| ([\d,]+) \|", cg).group(1).replace(",", ""))
        middle = probe()["2"]
        cost = SCRATCH / "compare_cost.json"
        subprocess.run([sys.executable, str(ROOT / "bench" / "compare_cost.py"), "--out", str(cost)], check=True,
                       capture_output=True)
        after = probe()["2"]
        load = os.getloadavg()[0]
    side = json.loads(cost.read_text())
    pairs = side["drives"] * len(side["models"])
    return {"cg_rate": rate, "cg_probes": [before, middle], "model_seconds_one_process": side["seconds"]["1"],
            "model_seconds_jobs": side["seconds"], "drive_models": pairs, "model_probes": [middle, after],
            "load": load, **relative(rate, (before + middle) / 2, side["seconds"]["1"] / pairs, (middle + after) / 2),
            "when": time.strftime("%Y-%m-%d %H:%M")}


def relative(cg_rate: float, cg_probe: float, model_seconds: float, model_probe: float) -> dict:
    """The constants as compare/stokes_experiment.py holds them: per grain-step/s of a 2D drive at the probe's speed."""
    from granstokes.dem.throughput import PHASE_RATIO

    drive = PHASE_RATIO[2]["drive"]
    return {"CG_PER_DRIVE_STEP": cg_rate / (drive * cg_probe), "MODEL_DRIVE_STEPS": model_seconds * drive * model_probe}


def table(rows: dict, shared: dict) -> str:
    lines = ["| preset (what is run) | estimate | measured idle | estimate against measured | disk estimated, "
             "measured | load before, after | measured shared | stretch |", "|---|---|---|---|---|---|---|---|"]
    for name in ROWS:
        if name not in rows:
            continue
        r, s = rows[name], shared.get(name)
        est = r["estimate"]
        disk = (f"{est['disk'] / 1e6:.3g}, {r['disk'] / 1e6:.3g} MB" if "disk" in r and "disk" in est else "")
        wide = (f"{s['measured']:.0f} s | {s['measured'] / r['measured']:.2f}x" if s else " | ")
        lines.append(f"| {name} ({r['what']}) | {est['total']:.0f} s | {r['measured']:.0f} s | "
                     f"{100 * (r['ratio'] - 1):+.0f} % | {disk} | {r['load'][0]:.1f}, {r['load'][1]:.1f} | {wide} |")
    comparisons = [(n, r) for n, r in rows.items() if "measured_comparison" in r and "comparison" in r["estimate"]]
    if comparisons:
        lines += ["", "| study, its comparison stage | estimate | measured | estimate against measured |",
                  "|---|---|---|---|"]
        for name, r in comparisons:
            e, m = r["estimate"]["comparison"], r["measured_comparison"]
            lines.append(f"| {name} | {e:.0f} s | {m:.0f} s | {100 * (e / m - 1):+.0f} % |")
    stretch = [shared[n]["measured"] / rows[n]["measured"] for n in ACCEPTANCE if n in rows and n in shared]
    if stretch:
        lines += ["", f"Stretch beside one busy process per core: {min(stretch):.2f}-{max(stretch):.2f}x "
                      "(dem/estimate.py SHARED_STRETCH)."]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", nargs="*", choices=list(ROWS), default=list(ACCEPTANCE))
    ap.add_argument("--shared", action="store_true", help="run each row beside one busy process per core")
    ap.add_argument("--constants", action="store_true", help="measure the comparison's constants instead")
    ap.add_argument("--json", type=Path, default=ROOT / "bench" / "dem_costs.json")
    args = ap.parse_args()
    stored = json.loads(args.json.read_text()) if args.json.is_file() else {"rows": {}}
    stored.setdefault("shared", {})
    if args.constants:
        stored["constants"] = constants()
        print(json.dumps(stored["constants"], indent=2))
    else:
        for name in args.rows:
            row = measure(name, args.shared)
            stored["shared" if args.shared else "rows"][name] = row
            print(f"{name}{' (shared)' if args.shared else ''}: estimate {row['estimate']['total']:.0f} s, measured "
                  f"{row['measured']:.0f} s ({100 * (row['ratio'] - 1):+.0f} %), disk {row['disk'] / 1e6:.3g} MB "
                  f"(estimate {row['estimate']['disk'] / 1e6:.3g})", flush=True)
            args.json.write_text(json.dumps(stored, indent=2))
        print(table(stored["rows"], stored["shared"]))
    args.json.write_text(json.dumps(stored, indent=2))


if __name__ == "__main__":
    main()
