"""Before and after a restructure, the same inputs must give the same numbers.

    python bench/restructure_check.py [--smoke-run DIR] [--save] [--before CHECKOUT]

Reruns ``granstokes continuum --json`` (the paper's three imposed stresses, one imposed speed), ``granstokes
predict --json`` (local and NGF, steady and transient, both drives), the DEM sizing of every preset
(``granstokes.dem.sizing.plan(...).as_dict()``) and, with ``--smoke-run DIR``, ``granstokes compare --json``
of that run with the committed quick calibration; compares every number with the JSON in bench/baseline/ and
prints each whose relative change exceeds the tolerance (exit status 1 if any).  ``--save`` writes the
baseline instead (run it before the restructure).  ``--before CHECKOUT`` (a work tree of the commit before,
e.g. ``git worktree add``) also times SPEED_CASES, each solve at the default accuracy 1e-6 in a fresh process,
alternating between the two trees, best of REPEATS CPU seconds, and prints the ratio after/before.  Timings
and provenance are not compared.  Tolerances: 1e-9 for the continuum, sizing and predictions (same
arithmetic), 1e-6 for the comparison (coarse-graining sums in another order may move the last digits).
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASE = Path(__file__).parent / "baseline"
CALIBRATION = ROOT / "results" / "quick-calibration" / "calibration.json"
PAPER = ["--mu-s", "0.3839", "--mu-d", "0.6494"]
SCENE = ["--mu-s", "0.28", "--mu-d", "0.58", "--I0", "0.3", "--phi", "0.8", "--p-w", "20", "--depth", "30"]
CASES = {f"continuum_{mt}": ["continuum", *PAPER, "--mu-w-tilde", mt, "--times", "1e-4", "1e-2", "1", "10"]
         for mt in ("0.1", "0.5", "0.9")}
CASES["continuum_speed"] = ["continuum", *PAPER, "--u-w", "1.334", "--times", "1e-3", "1"]
for model in ("local", "ngf"):
    amplitude = ["--A", "0.5"] if model == "ngf" else []
    CASES[f"predict_{model}_stress"] = ["predict", "--model", model, *amplitude, *SCENE, "--mu-w", "0.43",
                                        "--times", "1", "10"]
    CASES[f"predict_{model}_speed_steady"] = ["predict", "--model", model, *amplitude, *SCENE, "--u-w", "1.0",
                                              "--steady"]
PRESETS = ("smoke", "quick", "spheres", "paper")
SPEED_CASES = {"stress, mu~_w = 0.5": CASES["continuum_0.5"], "stress, mu~_w = 0.1": CASES["continuum_0.1"],
               "speed, u~_w = 1.334": CASES["continuum_speed"]}
REPEATS = 3
#: keys whose numbers measure the machine, not the result
NOT_COMPARED = re.compile(r"(cpu|wall|seconds|timing|provenance|started|finished)", re.IGNORECASE)
TOLERANCE = {"compare": 1e-6}
DEFAULT_TOLERANCE = 1e-9


def numbers(obj, prefix=""):
    """Flatten nested dicts/lists into {path: number}, skipping NOT_COMPARED keys."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            if not NOT_COMPARED.search(str(k)):
                yield from numbers(v, f"{prefix}.{k}" if prefix else k)
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from numbers(v, f"{prefix}[{i}]")
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        yield prefix, float(obj)


def diff(old: dict, new: dict, rtol: float) -> list[str]:
    a, b = dict(numbers(old)), dict(numbers(new))
    out = [f"  {k}: only before" for k in sorted(set(a) - set(b))]
    out += [f"  {k}: only after" for k in sorted(set(b) - set(a))]
    for k in sorted(set(a) & set(b)):
        if abs(b[k] - a[k]) > rtol * max(abs(a[k]), 1e-12):
            out.append(f"  {k}: {a[k]:.10g} -> {b[k]:.10g}")
    return out


def granstokes(*args) -> dict:
    out = subprocess.run([sys.executable, "-m", "granstokes.cli", *args], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def sizing() -> dict:
    code = ("import json; from granstokes.dem import config, sizing; "
            f"print(json.dumps({{p: sizing.plan(config.preset(p)[0]).as_dict() for p in {PRESETS!r}}}, default=str))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(out.stdout)


def current(smoke_run: Path | None) -> dict:
    """Every case's numbers now: {name: JSON}."""
    out = {name: granstokes(*argv, "--json") for name, argv in CASES.items()}
    out["sizing"] = sizing()
    if smoke_run is not None:
        with tempfile.TemporaryDirectory() as tmp:
            metrics = granstokes("compare", str(smoke_run), "--out", str(Path(tmp) / "report"), "--json",
                                 "--calibration", str(CALIBRATION))
        metrics["drives"] = {Path(k).name: v for k, v in metrics["drives"].items()}
        metrics["scorecard"] = [{**r, "drive": Path(r["drive"]).name} for r in metrics["scorecard"]]
        out["compare"] = metrics
    return out


#: runs ``granstokes ARGV`` with the packages imported from the source tree TREE (argv[1]): the editable install
#: maps granstokes.continuum, .dem and .compare to this checkout's folders whatever PYTHONPATH says
FROM_TREE = """import importlib.util, runpy, sys
tree, args = sys.argv[1], sys.argv[2:]
for name, folder in (("granstokes", "granstokes"), ("granstokes.continuum", "continuum"), ("granstokes.dem", "dem"),
                     ("granstokes.compare", "compare")):
    spec = importlib.util.spec_from_file_location(name, f"{tree}/{folder}/__init__.py",
                                                  submodule_search_locations=[f"{tree}/{folder}"])
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
sys.argv = ["granstokes", *args]
runpy.run_module("granstokes.cli", run_name="__main__")
"""


def cpu_seconds(tree: Path, argv) -> float:
    """CPU seconds (user + system) of ``granstokes ARGV`` run from the source tree ``tree``."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-c", FROM_TREE, str(tree), *argv], cwd=tree, capture_output=True, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime


def speed(before: Path) -> None:
    """The table of SPEED_CASES' CPU before and after (each tree's kernels compiled first, not timed)."""
    trees = {"before": before.resolve(), "after": ROOT}
    for tree in trees.values():
        for argv in SPEED_CASES.values():
            cpu_seconds(tree, argv)
    print("| case | before [s CPU] | after [s CPU] | after / before |\n|---|---|---|---|")
    for name, argv in SPEED_CASES.items():
        best = {k: min(cpu_seconds(tree, argv) for _ in range(REPEATS)) for k, tree in trees.items()}
        print(f"| {name} | {best['before']:.2f} | {best['after']:.2f} | {best['after'] / best['before']:.2f} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--smoke-run", type=Path, help="a smoke run folder (granstokes dem run --preset smoke)")
    ap.add_argument("--save", action="store_true", help="write the baseline instead of comparing with it")
    ap.add_argument("--before", type=Path, help="a work tree of the commit before: time both")
    args = ap.parse_args()
    if args.before is not None:
        speed(args.before)
    now = current(args.smoke_run)
    if args.save:
        BASE.mkdir(exist_ok=True)
        for name, doc in now.items():
            (BASE / f"{name}.json").write_text(json.dumps(doc, indent=1, default=str))
        print(f"baseline written: {', '.join(now)}")
        return 0
    failures = 0
    for name, doc in now.items():
        rows = diff(json.loads((BASE / f"{name}.json").read_text()), doc, TOLERANCE.get(name, DEFAULT_TOLERANCE))
        print(f"{name}: {'same' if not rows else f'{len(rows)} changed'}", *rows, sep="\n")
        failures += len(rows)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
