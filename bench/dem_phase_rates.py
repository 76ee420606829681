"""The phases' throughput as fractions of the probe chute (dem.throughput.PHASE_RATIO), measured in one invocation.

    .venv/bin/python bench/dem_phase_rates.py [--out DIR]

Runs, one process at a time on one rank: one bed of each shipped scene preset (smoke, quick: 2D; spheres: 3D;
``--set seeds=[1]``) with ``granstokes dem run --jobs 1 --np 1``, and the calibration cells of the smoke grains (2D) and
of a short 3D protocol with ``dem calibrate --jobs 1``, each between two throughput probes of its dimension
(dem.throughput.probe, alone).  A phase's rate is grains x steps / wall time of its stages (run.json,
state.json: LAMMPS's own start-up included, as in a real run); its ratio is that over the mean of the probes
around it, so that a machine whose load drifts during the bench still gives the ratio of one moment.
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
    _granstokes("dem", "run", "--preset", name, "--set", "seeds=[1]", "--jobs", "1", "--np", "1", "--out", str(out))
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


def bracketed(dim: int, measure) -> dict:
    """``measure()`` between two probes of dimension ``dim``: its rates and the probes' mean (``chute``)."""
    before = throughput.probe((dim,), together=False).probe[str(dim)]
    rates = measure()
    after = throughput.probe((dim,), together=False).probe[str(dim)]
    return {"dimension": dim, **rates, "chute": (before + after) / 2, "probes": [before, after]}


def main() -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="scratch folder (default: a temporary one)")
    args = ap.parse_args()
    root = args.out or Path(tempfile.mkdtemp(prefix="dem-phase-rates-"))
    t0 = time.monotonic()
    phases = {name: bracketed(dim, lambda n=name: scene_rates(n, root / n)) for name, dim in SCENES.items()}
    shears = {name: bracketed(dim, lambda n=name, s=sets: shear_rate(n, s, root / f"cal-{n}"))
              for name, (dim, sets) in CALIBRATIONS.items()}
    ratios = {}
    for dim in (2, 3):
        rows = [r for r in phases.values() if r["dimension"] == dim]
        ratios[dim] = {ph: statistics.mean(r[ph] / r["chute"] for r in rows) for ph in ("prepare", "drive")}
        ratios[dim]["shear"] = statistics.mean(r["shear"] / r["chute"] for r in shears.values()
                                               if r["dimension"] == dim)
    res = {"machine": {"cpus": os.cpu_count(), "load_average": os.getloadavg()}, "scenes": phases,
           "calibrations": shears, "ratios": ratios, "seconds": time.monotonic() - t0}
    (HERE / "dem_phase_rates.json").write_text(json.dumps(res, indent=2))
    print(markdown(res))
    return res


def markdown(res: dict) -> str:
    lines = ["| phase (scene) | dimension | grain-steps/s | ratio to the probe chute (probes before, after) |",
             "|---|---|---|---|"]
    for name, r in res["scenes"].items():
        for ph in ("prepare", "drive"):
            lines.append(f"| {ph} ({name}) | {r['dimension']}D | {r[ph] / 1e6:.2f} M | {r[ph] / r['chute']:.2f} "
                         f"(probes {r['probes'][0] / 1e6:.1f}, {r['probes'][1] / 1e6:.1f} M) |")
    for name, r in res["calibrations"].items():
        lines.append(f"| shear cells ({name}) | {r['dimension']}D | {r['shear'] / 1e6:.2f} M | "
                     f"{r['shear'] / r['chute']:.2f} (probes {r['probes'][0] / 1e6:.1f}, "
                     f"{r['probes'][1] / 1e6:.1f} M) |")
    lines.append("")
    lines.append("PHASE_RATIO = " + json.dumps({d: {k: round(v, 2) for k, v in r.items()}
                                                for d, r in res["ratios"].items()}))
    lines.append(f"load {res['machine']['load_average'][0]:.1f} at the end; {res['seconds'] / 60:.0f} min")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
