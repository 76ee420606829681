"""Coarse-graining rate on a DEM dump, against MDAnalysis's bare read rate of the same dump (same process).

    .venv/bin/python bench/cg_rate.py [DRIVE_DIR] [--width 0.5] [--append]

Without DRIVE_DIR, runs the smoke preset with atoms and contacts dumped every 0.05 into
/tmp/granstokes_cg_bench (reused if present).  Rates are grain-frames per second (atoms in the dump x
frames / CPU time, ``time.process_time``, minimum of 3 repeats):
* bare read: MDAnalysis LAMMPSDUMP reader iterating the frames and touching the positions;
* contacts read: pandas parse of every contact snapshot (``DriveFolder.contacts_at``);
* coarse-graining: ``DepthProfiles(...).run()`` end to end (atom read, contact read, all fields, tables).
The ratio of the rates says how much the coarse-graining adds to reading the dump (1: nothing).
``--append`` adds the markdown block to bench/RESULTS.md (## Coarse-graining).
"""
from __future__ import annotations

import argparse
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from granstokes.compare.profiles import CGSettings, DepthProfiles
from granstokes.compare.reader import find_drives

DEFAULT = Path("/tmp/granstokes_cg_bench")


def best(fn, repeats=3) -> float:
    times = []
    for _ in range(repeats):
        t = time.process_time()
        fn()
        times.append(time.process_time() - t)
    return min(times)


def bare_read(drive) -> None:
    u = drive.universe()
    acc = 0.0
    for ts in u.trajectory[:len(drive.atoms)]:
        acc += float(ts.positions[:, 1].sum())


def contacts_read(drive) -> None:
    for s in drive.atoms.steps:
        drive.contacts_at(int(s))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("drive", nargs="?", help="drive folder or run folder (default: a dense smoke run in /tmp)")
    ap.add_argument("--width", type=float, default=0.5)
    ap.add_argument("--append", action="store_true", help="append the result to bench/RESULTS.md")
    args = ap.parse_args(argv)
    if args.drive is None and not (DEFAULT / "run" / "run.json").exists():
        from granstokes.dem import config

        from granstokes.cli import main as granstokes_main

        DEFAULT.mkdir(parents=True, exist_ok=True)
        text = config.preset_text("smoke").replace("atoms = 1.0", "atoms = 0.05")
        (DEFAULT / "smoke.toml").write_text(text.replace("contacts = 1.0", "contacts = 0.05"))
        argv = ["dem", "run", str(DEFAULT / "smoke.toml"), "--out", str(DEFAULT / "run"), "--quiet"]
        assert granstokes_main(argv) == 0, "the DEM run failed"
    drive = find_drives(args.drive or DEFAULT / "run")[0]
    warnings.simplefilter("ignore")
    n_atoms, n_frames = int(drive.atoms.rows[0]), len(drive.atoms)
    n_contacts = int(drive.contacts.rows.mean())
    gf = n_atoms * n_frames
    t_read = best(lambda: bare_read(drive))
    t_contacts = best(lambda: contacts_read(drive))
    t_cg = best(lambda: DepthProfiles(drive, CGSettings("lucy", args.width)).run())
    prof = DepthProfiles(drive, CGSettings("lucy", args.width)).run()
    n_y = len(prof.results.y)
    core = max(t_cg - t_read - t_contacts, 0.0)
    cmd = "bench/cg_rate.py" + (f" {args.drive}" if args.drive else "")
    cmd += f" --width {args.width}" if args.width != 0.5 else ""
    lines = [
        "", "## Coarse-graining", "",
        f"Command: `.venv/bin/python {cmd}`; machine: 2 cores ({platform.machine()}), one process, CPU time "
        "(`time.process_time()`), minimum of 3 repeats.",
        "",
        f"Dump: {drive.path} ({drive.dimension}D, {n_atoms} atoms incl. base and plate, {n_frames} frames, "
        f"{n_contacts} contacts per frame on average); Lucy kernel w = {args.width} d, {n_y} grid points.",
        "",
        "| stage | CPU [s] | grain-frames/s |",
        "|---|---|---|",
        f"| MDAnalysis bare read (positions touched) | {t_read:.3f} | {gf / t_read:,.0f} |",
        f"| contact snapshots (pandas) | {t_contacts:.3f} | {gf / t_contacts:,.0f} |",
        f"| coarse-graining, end to end (`DepthProfiles.run`) | {t_cg:.3f} | {gf / t_cg:,.0f} |",
        f"| of which CG arithmetic (end to end - reads) | {core:.3f} | {gf / max(core, 1e-9):,.0f} |",
        "",
        f"Ratio of the coarse-graining rate to the bare read rate: {t_read / t_cg:.2f} (1 = the CG costs nothing "
        f"beyond MDAnalysis's read).  Shares of the end-to-end time: CG arithmetic {core / t_cg:.0%}, atom read "
        f"{t_read / t_cg:.0%}, contact read {t_contacts / t_cg:.0%}; "
        + ("the CG arithmetic costs more than reading the dump (per frame: "
           if core > t_read else "reading the dump costs more than the CG arithmetic (per frame: ")
        + f"{1e3 * core / n_frames:.2f} ms CG, {1e3 * t_read / n_frames:.2f} ms MDAnalysis read).",
        "",
    ]
    block = "\n".join(lines)
    print(block)
    if args.append:
        with open(Path(__file__).with_name("RESULTS.md"), "a") as fh:
            fh.write(block)
    return 0


if __name__ == "__main__":
    np.seterr(all="ignore")
    sys.exit(main())
