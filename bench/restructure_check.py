"""Behaviour before and after the restructure (issue 8): the same inputs must give the same numbers.

    python bench/restructure_check.py [--smoke-run DIR]

Reruns ``granstokes continuum --json`` for the paper's three imposed stresses and one imposed speed
and compares every number with the JSON saved before the restructure in bench/baseline/
(continuum_*.json).  With ``--smoke-run DIR`` (a smoke run of the scene as it was then: the plate,
disk inertia and plate-force averaging changed afterwards, issue 9) it also compares ``granstokes
compare``'s metrics with smoke_metrics.json; at the restructure commit (3b556af) both were identical.
Prints each number whose relative change exceeds the tolerance; exit status 1 if any.  Tolerances:
1e-9 for the continuum (same arithmetic), 1e-6 for the DEM metrics (same seed, same ranks; LAMMPS
granular runs are reproducible on one machine, not across machines).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

BASE = Path(__file__).parent / "baseline"
PAPER = ["--mu-s", "0.3839", "--mu-d", "0.6494"]
CASES = {f"continuum_{mt}": [*PAPER, "--mu-w-tilde", mt, "--times", "1e-4", "1e-2", "1", "10"]
         for mt in ("0.1", "0.5", "0.9")}
CASES["continuum_speed"] = [*PAPER, "--u-w", "1.334", "--times", "1e-3", "1"]


def numbers(obj, prefix=""):
    """Flatten nested dicts/lists into {path: number}."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from numbers(v, f"{prefix}.{k}" if prefix else k)
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from numbers(v, f"{prefix}[{i}]")
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        yield prefix, float(obj)


def by_run_name(m: dict) -> dict:
    """Drives keyed RUN_NAME/DRIVE (before the restructure the key was the run folder's name; now
    it is its path, so that two runs named alike stay apart)."""
    return {**m, "drives": {"/".join(Path(k).parts[-2:]): v for k, v in m.get("drives", {}).items()}}


def diff(old: dict, new: dict, rtol: float) -> list[str]:
    a, b = dict(numbers(by_run_name(old))), dict(numbers(by_run_name(new)))
    out = [f"  {k}: only before" for k in sorted(set(a) - set(b))]
    for k in sorted(set(a) & set(b)):
        if abs(b[k] - a[k]) > rtol * max(abs(a[k]), 1e-12):
            out.append(f"  {k}: {a[k]:.10g} -> {b[k]:.10g}")
    return out


def granstokes(*args) -> str:
    return subprocess.run([sys.executable, "-m", "granstokes.cli", *args], capture_output=True, text=True,
                          check=True).stdout


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--smoke-run", type=Path, help="an existing smoke run folder (default: run one)")
    args = ap.parse_args()
    failures = 0
    for name, argv in CASES.items():
        rows = diff(json.loads((BASE / f"{name}.json").read_text()), json.loads(granstokes("continuum", *argv, "--json")),
                    1e-9)
        print(f"{name}: {'same' if not rows else f'{len(rows)} changed'}", *rows, sep="\n")
        failures += len(rows)
    if args.smoke_run is not None:
        with tempfile.TemporaryDirectory() as tmp:
            new = json.loads(granstokes("compare", str(args.smoke_run), "--out", str(Path(tmp) / "report"), "--json",
                                         "--fit-on-drives"))
        rows = diff(json.loads((BASE / "smoke_metrics.json").read_text()), new, 1e-6)
        print(f"smoke metrics: {'same' if not rows else f'{len(rows)} changed'}", *rows, sep="\n")
        failures += len(rows)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
