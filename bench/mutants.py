"""Mutation testing of the comparison's statistics and conventions: `make mutants`.

mutmut 3 names a mutant after its file's path (compare/rows.py -> compare.rows) and puts its mutated copies first on
sys.path, while the tests import granstokes.compare.rows through the editable install: run in place, no mutant would
ever be switched on. So this script lays the installed layout out in build/mutants/ (granstokes/ with lib/, continuum/,
dem/, compare/ inside it, the tests beside it), runs mutmut there (one pytest session, forked per mutant, each mutant
running only the fast-lane tests that reach its function), and writes a summary per file and the survivors.

    python bench/mutants.py [--digits 0123456789] [--files compare/rows.py ...] [--max-children 2]
                            [--out bench/mutants.json]
"""

from __future__ import annotations

import argparse
import ast
import fnmatch
import json
import re
import shutil
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STAGE = ROOT / "build" / "mutants"

# the files mutated, and in the big ones only the functions that estimate, make sigmas, differences and verdicts
TARGETS = {
    "compare/rows.py": ["*"],
    "compare/band.py": ["*"],
    "compare/phase.py": ["*"],
    "compare/plate.py": ["*"],
    "compare/scorecard.py": ["x_t90", "x_creep_length", "x__mean_err", "x_base_reach", "x_dem_observables",
                             "x_model_observables", "x__linearised", "x__final_quarter", "x__final_quarter_band",
                             "x__t90_numerical", "x__not_scored", "x__unmeasurable", "x_slipping", "x_extrapolated",
                             "x_score", "x_headline"],
    "compare/oscillation.py": ["x__difference", "x__row", "x__scene", "x__unmeasurable", "x__unpredicted",
                               "x_scorecard", "x_laws", "x__weighted_slope"],
    "compare/profiles.py": ["x_coarse_grain", "x_derive", "x_band_quantile", "x_standard_error", "x__band"],
    "compare/laws.py": ["x__slope", "x_growth_window", "x__in", "x__early", "x_growth", "x__spanning",
                        "x_local_exponents", "x_in_regime", "x_plateau_change"],
    "compare/families.py": ["*"],
    "continuum/crossing.py": ["*"],
    "continuum/rheology.py": ["*"],
    "continuum/scales.py": ["*"],
}
# the fast lane, restricted to the files that reach the targets; mutmut runs, per mutant, only those of these tests
# that called the mutated function. The one test dropped reads the repository's folder layout, which the stage changes.
TESTS = ["tests/compare", "tests/continuum/test_steady_and_scales.py", "tests/continuum/test_rheology.py",
         "tests/continuum/test_crossing.py"]
PYTEST_ARGS = ["-m", "not slow", "-p", "no:cacheprovider", "-x", "-q", "--deselect",
               "tests/compare/test_experiment.py::test_no_pipeline_branch_on_the_oscillating_plate_outside_the_experiments"]
PACKAGES = {"lib": "granstokes/lib", "continuum": "granstokes/continuum", "dem": "granstokes/dem",
            "compare": "granstokes/compare"}


def staged(path: str) -> str:
    top, rest = path.split("/", 1)
    return f"{PACKAGES[top]}/{rest}"


def module(path: str) -> str:
    return staged(path).removesuffix(".py").replace("/", ".")


def patterns(digits: str) -> list[str]:
    """mutmut's name filters: the target functions' mutants whose number ends in one of `digits` (a sample)."""
    return [f"{module(p)}.{f}__mutmut_*[{digits}]" for p, fs in TARGETS.items() for f in fs]


def sampled(key: str, funcs: list[str], digits: str) -> bool:
    short = key.rsplit(".", 1)[-1]
    return any(fnmatch.fnmatchcase(short, f"{f}__mutmut_*[{digits}]") for f in funcs)


def stage() -> None:
    if STAGE.exists():
        shutil.rmtree(STAGE)
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    shutil.copytree(ROOT / "granstokes", STAGE / "granstokes", ignore=ignore)
    for folder, target in PACKAGES.items():
        shutil.copytree(ROOT / folder, STAGE / target, ignore=ignore)
    shutil.copytree(ROOT / "tests", STAGE / "tests", ignore=ignore)
    def toml_list(xs):
        return "[" + ", ".join(json.dumps(x) for x in xs) + "]"
    (STAGE / "pyproject.toml").write_text(f"""[tool.mutmut]
source_paths = ["granstokes"]
only_mutate = {toml_list(staged(p) for p in TARGETS)}
also_copy = ["results", "docs", "bench"]
pytest_add_cli_args_test_selection = {toml_list(TESTS)}
pytest_add_cli_args = {toml_list(PYTEST_ARGS)}

[tool.pytest.ini_options]
testpaths = ["tests"]
markers = ["slow: runs LAMMPS or a long solve (still part of make test)"]
""")
    for folder in ("results", "docs", "bench"):  # read by a few tests; mutmut copies them into its mutants/
        (STAGE / folder).symlink_to(ROOT / folder)


def line_of(path: str, key: str, diff: str) -> int:
    """The line in the repository's file that the mutant changes: its first removed line within its function."""
    name = key.rsplit(".", 1)[-1].split("__mutmut_")[0]
    cls, func = (name.split("ǁ")[1:3] if name.startswith("xǁ") else (None, name.removeprefix("x_")))
    text = (ROOT / path).read_text()
    lines = text.splitlines()
    start = end = 1
    tree = ast.parse(text)
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and node.name == func:
            start, end = node.lineno, node.end_lineno
            if cls is None or any(isinstance(c, ast.ClassDef) and c.name == cls and node in c.body
                                  for c in ast.walk(tree)):
                break
    removed = [d[1:].strip() for d in diff.splitlines() if d.startswith("-") and not d.startswith("---")]
    for r in removed:
        for i in range(start, end + 1):
            if lines[i - 1].strip() == r:
                return i
    return start


def summarise(wall: float, max_children: int, digits: str) -> dict:
    from mutmut.mutation.diff_apply import get_diff_for_mutant
    from mutmut.stats import status_by_exit_code

    per_file, survivors = {}, []
    for path, funcs in TARGETS.items():
        meta = json.loads((STAGE / "mutants" / (staged(path) + ".meta")).read_text())
        counts = Counter()
        for key, code in meta["exit_code_by_key"].items():
            if not sampled(key, funcs, digits):
                continue
            status = status_by_exit_code[code]
            counts[status] += 1
            if status in ("survived", "no tests"):
                diff = get_diff_for_mutant(key, path=Path(staged(path)))
                change = [d for d in diff.splitlines() if d[:1] in "+-" and d[:3] not in ("+++", "---")]
                survivors.append({"where": f"{path}:{line_of(path, key, diff)}", "mutant": key, "status": status,
                                  "change": " => ".join(c[1:].strip() for c in change)})
        n = sum(counts.values())
        killed = counts["killed"] + counts["timeout"]
        per_file[path] = {"mutants": n, **counts, "kill_rate": round(killed / n, 3) if n else None}
    total = sum(f["mutants"] for f in per_file.values())
    killed = sum(f.get("killed", 0) + f.get("timeout", 0) for f in per_file.values())
    return {"command": "make mutants", "sample": f"mutants numbered *[{digits}]", "wall_s": round(wall, 1),
            "max_children": max_children,
            "mutants": total, "killed": killed, "kill_rate": round(killed / total, 3) if total else None,
            "per_file": per_file, "survivors": survivors}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-children", type=int, default=2)
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "mutants.json")
    ap.add_argument("--digits", default="0123456789",
                    help="run the mutants whose number ends in one of these digits (default: all; 147: a 30%% sample)")
    ap.add_argument("--files", nargs="*", help="only these of the targets (e.g. compare/rows.py)")
    args = ap.parse_args(argv)
    if args.files:
        for path in set(TARGETS) - set(args.files):
            del TARGETS[path]
    t0 = time.perf_counter()
    stage()
    mutmut = Path(sys.executable).with_name("mutmut")
    subprocess.run([str(mutmut), "run", "--max-children", str(args.max_children), *patterns(args.digits)], cwd=STAGE,
                   check=False)
    wall = time.perf_counter() - t0
    sys.path.insert(0, str(STAGE))
    import os
    os.chdir(STAGE)
    result = summarise(wall, args.max_children, args.digits)
    args.out.write_text(json.dumps(result, indent=1, ensure_ascii=False) + "\n")
    print(f"\n{result['sample']}: {result['killed']} of {result['mutants']} mutants killed "
          f"({result['kill_rate']:.1%}) in {result['wall_s']:.0f} s")
    for path, f in result["per_file"].items():
        print(f"  {path:26s} {f['mutants']:5d} mutants, kill rate {f['kill_rate']}")
    print(f"{len(result['survivors'])} survivors (bench/mutants.json has each one's line and change); "
          f"`cd build/mutants && mutmut show NAME` shows one's diff")
    for s in result["survivors"][:30]:
        change = re.sub(r"\s+", " ", s["change"])[:100]
        print(f"  {s['where']:30s} {change}")


if __name__ == "__main__":
    main()
