"""The phases' throughput as fractions of the probe chute (dem.throughput.PHASE_RATIO), measured in one invocation.

    .venv/bin/python bench/dem_phase_rates.py [--out DIR]

Runs, one process at a time on one rank: the throughput probe (dem.throughput.probe), one bed of each shipped
scene preset (smoke, quick: 2D; spheres: 3D; ``--set seeds=[1]``) with ``granstokes dem run --jobs 1``, the
calibration cells of the smoke grains (2D) and of a short 3D protocol with ``dem calibrate --jobs 1``, then the
probe again.  A phase's rate is grains x steps / wall time of its stages (run.json, state.json: LAMMPS's own
start-up included, as in a real run); its ratio is that over the mean of the two probes of its dimension.
Writes bench/dem_phase_rates.json and prints the rows for bench/RESULTS.md.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from granstokes.dem import config, throughput
from granstokes.dem.calibrate import plan_calibration
from granstokes.dem.sizing import plan

HERE = Path(__file__).resolve().parent
SCENES = {"smoke": 2, "quick": 2, "spheres": 3}
#: calibration protocols timed: the smoke grains' own table, and spheres at three cheap inertial numbers
CALIBRATIONS = {"smoke": (2, []), "spheres": (3, ["calibration.I=[0.1, 0.2, 0.4]", "calibration.width=8.0"])}


def _granstokes(*args: str, check: bool = True) -> None:
    """A granstokes command into a folder it has not yet filled (a rerun of the bench reuses what is there)."""
    out = Path(args[args.index("--out") + 1])
    if not out.exists():
        subprocess.run([sys.executable, "-m", "granstokes.cli", *args, "--quiet"], check=check,
                       stderr=subprocess.DEVNULL)


def scene_rates(name: str, out: Path) -> dict:
    """Grain-steps/s of a preset's preparation and drives (one bed, alone)."""
    _granstokes("dem", "run", "--preset", name, "--set", "seeds=[1]", "--jobs", "1", "--out", str(out))
    meta = json.loads((out / "run.json").read_text())
    p = plan(config.parse((out / "config.toml").read_text()))
    prep = meta["stages"]["seed-1"]
    drives = [st for k, st in meta["stages"].items() if "/" in k]
    drive_steps = sum(d.steps for d in p.drives)
    return {"grains": p.n_grains,
            "prepare": p.n_grains * prep["info"]["lammps"]["last_step"] / prep["wall_time"],
            "drive": p.n_grains * drive_steps / sum(d["wall_time"] for d in drives)}


def shear_rate(name: str, sets: list, out: Path) -> dict:
    """Grain-steps/s of a calibration's cells (their compression included), each alone (the fit may fail: the
    cells' timings are what counts here)."""
    _granstokes("dem", "calibrate", "--preset", name, *[x for s in sets for x in ("--set", s)], "--jobs", "1",
                "--out", str(out), check=False)
    state = json.loads((out / "state.json").read_text())
    cp = plan_calibration(config.parse((out / "config.toml").read_text()))
    cells = [c for c in state["points"].values() if c["status"] == "complete"]
    steps = sum(c["steps"] for c in cells)
    return {"grains": cp.n_grains, "shear": cp.n_grains * steps / sum(c["wall_time"] for c in cells)}


def main() -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="scratch folder (default: a temporary one)")
    args = ap.parse_args()
    root = args.out or Path(tempfile.mkdtemp(prefix="dem-phase-rates-"))
    t0 = time.monotonic()
    probes = [throughput.probe()]
    phases = {name: {"dimension": dim, **scene_rates(name, root / name)} for name, dim in SCENES.items()}
    shears = {name: {"dimension": dim, **shear_rate(name, sets, root / f"cal-{name}")}
              for name, (dim, sets) in CALIBRATIONS.items()}
    probes.append(throughput.probe())
    chute = {dim: statistics.mean(p.probe[str(dim)] for p in probes) for dim in (2, 3)}
    ratios = {}
    for dim in (2, 3):
        rows = [r for r in phases.values() if r["dimension"] == dim]
        ratios[dim] = {ph: statistics.mean(r[ph] for r in rows) / chute[dim] for ph in ("prepare", "drive")}
        shear = [r["shear"] for r in shears.values() if r["dimension"] == dim]
        ratios[dim]["shear"] = statistics.mean(shear) / chute[dim]
    res = {"machine": {"cpus": os.cpu_count(), "load_average": os.getloadavg()}, "probes": [p.probe for p in probes],
           "chute": chute, "scenes": phases, "calibrations": shears, "ratios": ratios,
           "seconds": time.monotonic() - t0}
    (HERE / "dem_phase_rates.json").write_text(json.dumps(res, indent=2))
    print(markdown(res))
    return res


def markdown(res: dict) -> str:
    lines = ["| phase (scene) | dimension | grain-steps/s | ratio to the probe chute |", "|---|---|---|---|"]
    for name, r in res["scenes"].items():
        for ph in ("prepare", "drive"):
            lines.append(f"| {ph} ({name}) | {r['dimension']}D | {r[ph] / 1e6:.2f} M | "
                         f"{r[ph] / res['chute'][r['dimension']]:.2f} |")
    for name, r in res["calibrations"].items():
        lines.append(f"| shear cells ({name}) | {r['dimension']}D | {r['shear'] / 1e6:.2f} M | "
                     f"{r['shear'] / res['chute'][r['dimension']]:.2f} |")
    lines.append("")
    lines.append("PHASE_RATIO = " + json.dumps({d: {k: round(v, 2) for k, v in r.items()}
                                                for d, r in res["ratios"].items()}))
    lines.append(f"probe chutes (mean of {len(res['probes'])}): 2D {res['chute'][2] / 1e6:.2f} M, 3D "
                 f"{res['chute'][3] / 1e6:.2f} M atom-steps/s; load {res['machine']['load_average'][0]:.1f}; "
                 f"{res['seconds'] / 60:.0f} min")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
