"""Every committed study regenerated from its committed tables by the command its README gives, its scorecard and
law rows against the committed metrics.json (compare.metrics.row_differences): the largest relative difference of
any number, the rows only one side has, the fields whose words differ.

    .venv/bin/python bench/regenerate.py [--studies NAME ...] [--scratch DIR]

Prints the table for bench/RESULTS.md ("Regeneration") and writes bench/regenerate.json (the studies not rerun keep
their last entries).
"""
from __future__ import annotations

import argparse
import json
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STUDIES = ("study-spheres", "study-disks", "study-oscillating-disks", "study-oscillating-spheres", "pair-style-spheres")


def readme_command(study: str) -> list[str]:
    """The ``granstokes compare --tables ...`` command of results/STUDY/README.md, its REPORT_DIR left out."""
    text = (ROOT / "results" / study / "README.md").read_text()
    # one command, its lines joined by backslashes (a README may show other compare commands before it)
    command = re.search(r"^\s+(granstokes compare --tables (?:\\\n|[^\n])*?--out REPORT_DIR)", text,
                        flags=re.M).group(1)
    words = shlex.split(command.replace("\\\n", " "))
    return words[1:words.index("--out")]


def regenerate(study: str, scratch: Path) -> dict:
    from granstokes.compare.metrics import row_differences

    out = scratch / study
    args = readme_command(study)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "granstokes.cli", *args, "--out", str(out)], cwd=ROOT, check=True,
                   capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    report = ROOT / Path(args[args.index("--tables") + 1]).parent  # the committed report beside its tables
    committed = json.loads((report / "metrics.json").read_text())
    return {"command": "granstokes " + " ".join(args) + " --out REPORT_DIR", "seconds": seconds,
            "differences": row_differences(committed, json.loads((out / "metrics.json").read_text()))}


def table(rows: dict) -> str:
    lines = ["| study | section | rows | only committed, only regenerated | largest relative difference | words "
             "differ | wall |", "|---|---|---|---|---|---|---|"]
    for study, r in rows.items():
        for section, d in r["differences"].items():
            lines.append(f"| {study} | {section} | {d['rows']} | {d['only_committed']}, {d['only_regenerated']} | "
                         f"{d['max_relative']:.2g} | {', '.join(d['words_differ']) or 'none'} | {r['seconds']:.0f} s |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--studies", nargs="*", choices=STUDIES, default=list(STUDIES))
    ap.add_argument("--scratch", type=Path, default=None, help="folder for the regenerated reports (default: temp)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="granstokes-regenerate-") as tmp:
        scratch = args.scratch or Path(tmp)
        rows = {}
        for study in args.studies:
            rows[study] = regenerate(study, scratch)
            print(f"{study}: {rows[study]['differences']}", flush=True)
    record = ROOT / "bench" / "regenerate.json"
    rows = {**(json.loads(record.read_text()) if record.exists() else {}), **rows}  # the studies not rerun kept
    record.write_text(json.dumps({k: rows[k] for k in STUDIES if k in rows}, indent=2))
    print(table({k: rows[k] for k in STUDIES if k in rows}))


if __name__ == "__main__":
    main()
