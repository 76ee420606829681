"""Seeds side by side: the demo's DEM wall time (quick + smoke presets) run one bed at a time on 2 MPI
ranks (``--jobs 1 --np 2``) against independent beds run concurrently as separate LAMMPS processes
(``--jobs 2 --np 1``, the default).  ``--keep DIR`` keeps the default's run folders (DIR/quick, DIR/smoke:
the demo's DEM, for its comparison report).

    .venv/bin/python bench/dem_concurrency.py [--out FILE] [--keep DIR]

All configurations run in this one process, one after another (interleaved ``REPEATS`` times, best
kept: the machine is shared); wall time is the whole ``dem.runner.run`` call (prepare + drives +
output merging).  Prints a Markdown block for bench/RESULTS.md and writes bench/dem_concurrency.json.
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from granstokes.dem import config
from granstokes.dem.runner import run
from granstokes.dem.sizing import plan

HERE = Path(__file__).resolve().parent
REPEATS = 1  # each configuration costs ~2 min of both cores: one interleaved pass
DEMO = ("quick", "smoke")
BEFORE, AFTER = "jobs 1, np 2 (before)", "jobs 2, np 1 (after)"
CONFIGS = {BEFORE: (1, 2), AFTER: (2, 1)}


def demo_dem(root: Path, jobs: int, np_: int) -> float:
    """Wall time of the demo's DEM presets run with ``jobs`` beds at a time on ``np_`` ranks each."""
    t0 = time.monotonic()
    for name in DEMO:
        cfg, text = config.preset(name)
        result = run(plan(cfg), text, root / name, np=np_, jobs=jobs, progress=False)
        assert result.ok, result.message
    return time.monotonic() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=HERE / "dem_concurrency.json")
    ap.add_argument("--keep", type=Path, help="keep the default's run folders here")
    args = ap.parse_args()
    best = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(REPEATS):
            for label, (jobs, np_) in CONFIGS.items():
                root = args.keep if (args.keep and label == AFTER and r == 0) else Path(tmp) / f"{r}-{jobs}-{np_}"
                wall = demo_dem(root, jobs, np_)
                best[label] = min(best.get(label, wall), wall)
                print(f"{label}: {wall:.1f} s", flush=True)
    before, after = best[BEFORE], best[AFTER]
    out = {"walls": best, "speedup": before / after, "presets": DEMO, "repeats": REPEATS}
    args.out.write_text(json.dumps(out, indent=2))
    print("\n| configuration | demo DEM wall time (quick + smoke) |\n|---|---|")
    for label, wall in best.items():
        print(f"| {label} | {wall:.0f} s |")
    print(f"\nspeed-up of jobs 2 / np 1 over jobs 1 / np 2: {before / after:.2f}x")


if __name__ == "__main__":
    main()
